#pragma once
// Slurm job arrays: a sweep emitted as a batch script whose array task i runs slice i/K of the
// sweep into its own shard database (merged afterwards by `tbdrsim merge`).
#include <string>
#include <vector>

namespace tbdr {

struct SweepSpec;

/// What the job array asks Slurm for, and what its tasks pass on to `tbdrsim sweep`.
struct SlurmJobOptions {
  int slices = 1;                   ///< array tasks
  int jobs = 1;                     ///< worker processes per task (--cpus-per-task)
  std::string binary;               ///< the tbdrsim the tasks run (default: this one)
  std::string time;                 ///< #SBATCH --time, Slurm's format (empty: the partition's default)
  std::string partition;            ///< #SBATCH --partition (empty: the cluster's default)
  std::string mem;                  ///< #SBATCH --mem, per node, e.g. 4G (empty: the cluster's default)
  std::vector<std::string> traces;  ///< `sweep --trace` patterns the tasks pass on (made absolute)
};

/// Checks a --time, --partition or --mem value against Slurm's syntax (sbatch(1)); InputError
/// naming the option otherwise, so a typo fails here and not in the queue.
void check_slurm_option(const std::string& option, const std::string& value);

/// Writes a Slurm job-array script (array task i runs slice i/slices into dir/shard_i.db) and a
/// README telling how to merge; returns the script's path.
std::string write_slurm_job(const SweepSpec& spec, const std::string& dir, const SlurmJobOptions& options);

}  // namespace tbdr
