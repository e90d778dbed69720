#pragma once
// Running a sweep: its points (app/sweep_spec.hpp) run in parallel worker processes
// (app/worker_pool.hpp), `tbdrsim run` per point; points already in the database are skipped,
// points that another sweep on the same database is running are left to it (claims in the
// database, app/sweep.cpp), failures are recorded as failed runs, and Ctrl-C stops cleanly. Slurm job arrays
// (app/sweep_slurm.hpp) run slices of a sweep into shard databases that app/sweep_merge.hpp joins.
// Syntax: docs/sweeps.md.
#include <cstddef>
#include <cstdint>
#include <iosfwd>
#include <string>
#include <vector>

#include "kernel/hash.hpp"

#include "app/sweep_progress.hpp"
#include "app/sweep_spec.hpp"

namespace tbdr {

/// How to run a sweep.
struct SweepOptions {
  std::string db_path;
  int jobs = 1;
  int threads = 1;             ///< threads inside each point's run (`tbdrsim run --threads`)
  SweepSlice slice;
  std::string binary;          ///< the tbdrsim executable the workers run (default: this one)
  SweepProgress progress = SweepProgress::Lines;
  bool dry_run = false;        ///< list the points and whether each is done; run nothing
};

/// What a sweep did.
struct SweepSummary {
  std::size_t points = 0;      ///< in this slice
  std::size_t skipped = 0;     ///< already in the database
  std::size_t elsewhere = 0;   ///< claimed by another sweep running on the same database
  std::size_t ok = 0;
  std::size_t failed = 0;
  std::size_t not_run = 0;     ///< left when interrupted
  bool interrupted = false;
  double seconds = 0;
};

/// The hash of each configuration of a sweep (ParamTable::hash of the parameters its config
/// files and overrides resolve to: the runs' config_hash), from the configuration's number
/// (SweepPoints::combination). Each config file list is resolved once and every axis value
/// formatted once; a configuration's hash continues the hash of the canonical text from the first
/// parameter whose value differs from the configuration asked for before, so a sweep's points in
/// order cost a fraction of a full resolution each, and nothing is kept per configuration.
class SweepConfigHashes {
 public:
  /// Resolves every config file list of the sweep (InputError naming the sweep file and the point
  /// when one is bad).
  explicit SweepConfigHashes(const SweepSpec& spec);
  /// The hash of configuration c (16 hex digits).
  const std::string& operator()(std::size_t c);

 private:
  /// A parameter an axis sets: its declaration's position, axis and key within the axis.
  struct Varying {
    std::size_t decl, axis, key;
  };
  /// The canonical text ("key=value\n" lines) of one config file list with the fixed overrides,
  /// cut at the varying parameters: segments[0] precedes the first, segments[k + 1] follows the k-th.
  struct Base {
    std::vector<std::string> segments;
  };
  const SweepSpec& spec_;
  std::vector<Varying> varying_;                            ///< by declaration order
  std::vector<std::vector<std::vector<std::string>>> lines_;  ///< [axis][value][key]: "key=value\n"
  std::vector<Base> bases_;                                 ///< by value of the config axis (one without)
  std::size_t config_axis_ = SIZE_MAX;                      ///< the axis that varies config files, if any
  std::size_t config_key_ = 0;                              ///< "config"'s key within that axis
  std::vector<std::size_t> digits_;
  // The last configuration hashed: its base, each varying parameter's axis value, the hash state
  // before each varying parameter, and its hash.
  std::size_t base_ = SIZE_MAX;
  std::vector<std::size_t> value_at_;
  std::vector<Fnv1a64> before_;
  std::size_t last_ = SIZE_MAX;
  std::string hash_;
};

/// The registered techniques with their options and this tool's version: what a sweep file's
/// [generate] section is parsed against (parse_sweep_file).
TraceGenerators trace_generators();

/// Prints a "slow:" line for each trace of the sweep that draws the scene many times (such as
/// forward_multipass, one pass per light batch), with its points and its cost relative to the
/// sweep's lightest trace. run_sweep prints it too, before anything runs.
void print_slow_points(const SweepSpec& spec, std::ostream& out);

/// Runs a sweep (see the file comment). Installs SIGINT/SIGTERM handlers while it runs: the first
/// SIGINT stops launching points and waits for the running ones, a second SIGINT or a SIGTERM
/// kills them (a killed run leaves no rows). InputError for bad inputs, before anything runs.
SweepSummary run_sweep(const SweepSpec& spec, const SweepOptions& options, std::ostream& out);

}  // namespace tbdr
