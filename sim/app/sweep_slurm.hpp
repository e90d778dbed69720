#pragma once
// Slurm job arrays: a sweep emitted as a batch script whose array task i runs slice i/K of the
// sweep into its own shard database (merged afterwards by `tbdrsim merge`).
#include <string>

namespace tbdr {

struct SweepSpec;

/// Writes a Slurm job-array script (array task i runs slice i/slices into dir/shard_i.db) and a
/// README telling how to merge; returns the script's path.
std::string write_slurm_job(const SweepSpec& spec, const std::string& dir, int slices, int jobs,
                            const std::string& binary);

}  // namespace tbdr
