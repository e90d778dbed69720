#pragma once
// The sweep file: a sweep file (INI) names base configs, parameters with lists, ranges or zipped
// groups, traces and repetitions; it expands into a deterministic list of points (the cartesian
// product), and slices of that list feed Slurm job arrays. Syntax: docs/sweeps.md.
#include <cstddef>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace tbdr {

/// One swept axis: a single parameter, or a zip group of parameters that vary together.
/// values[i][k] is the i-th setting of keys[k]. The key "config" varies the config file.
struct SweepAxis {
  std::vector<std::string> keys;
  std::vector<std::vector<std::string>> values;
  std::vector<std::string> where;                ///< "file:line" of each key
};

/// One trace a sweep generates from its [generate] section: the options of `tbdrsim trace` for one
/// combination of the section's lists (docs/sweeps.md).
struct TraceRequest {
  std::string technique;
  std::vector<std::string> args;   ///< `tbdrsim trace` arguments without --out: --technique T --lights N -o k=v ...
  std::vector<std::string> arg_where;  ///< "file:line" of the [generate] key each option of args came from
  std::string label;               ///< the technique and the settings that vary: "forward_light_stack pls_bytes=16"
  std::string id;                  ///< 16 hex digits: hash of args, the tool version and the files they name
  std::string where;               ///< "file:line" of the [generate] header
};

/// What a [generate] section is checked and expanded against, given by the caller (app/sweep.hpp's
/// trace_generators(): the registered techniques) so that the sweep file reader does not depend on
/// the trace generators (tests/fuzz builds it alone).
struct TraceGenerators {
  /// Each technique, in registry order, with the option keys it reads.
  std::vector<std::pair<std::string, std::vector<std::string>>> techniques;
  /// Folded into every generated trace's hash (the tool version: a new tbdrsim generates anew).
  std::string version;
};

/// A parsed sweep file; every path is already relative to the working directory.
struct SweepSpec {
  std::string path;                        ///< the sweep file
  std::string name;                        ///< [sweep] name, or the file's stem
  std::vector<std::string> base_configs;   ///< applied in order to every point
  std::vector<std::string> sets;           ///< fixed "key=value" overrides for every point
  std::vector<SweepAxis> axes;             ///< in file order; the last one varies fastest
  std::vector<std::string> traces;         ///< globs expanded, in file order (glob matches sorted)
  std::vector<TraceRequest> generate;      ///< the [generate] traces, replayed after `traces`
  std::string generated_dir;               ///< where generated traces live (set_generated_dir)
  int repetitions = 1;
};

/// The folder of a sweep's generated traces for a results database: `<db stem>.traces/` beside it.
std::string generated_trace_dir(const std::string& db_path);

/// Where a generated trace is: `<spec.generated_dir>/<technique>-<id>.trace` (the id is the
/// request's hash, so a resumed sweep finds the traces it generated before).
std::string generated_trace_path(const SweepSpec& spec, const TraceRequest& request);

/// One simulation of a sweep: configuration, trace and repetition.
struct SweepPoint {
  std::size_t index = 0;   ///< position in the deterministic order
  std::size_t group = 0;   ///< index of its (configuration, trace) pair; repetitions share it
  int repetition = 0;
  std::vector<std::string> configs;  ///< config files, in order
  std::vector<std::string> sets;     ///< "key=value" overrides: fixed ones, then the axes'
  std::string trace;
  std::string label;                 ///< "tiling.tile_width=16 isp.tag_buffers=2 | a.trace"
};

/// A slice of a sweep for a job array: point groups g with g % count == index.
struct SweepSlice {
  int index = 0;
  int count = 1;
};

/// The most points one sweep may expand to. Each point is a simulation of at least a fraction of a
/// second and a row set in the database, so a million points is days of machine time; more is a
/// typing error (a range with a tiny step) that would otherwise allocate the list and fail with
/// std::bad_alloc. docs/limits.md lists it.
inline constexpr std::uint64_t kMaxSweepPoints = 1'000'000;

/// Refuses a sweep of more than kMaxSweepPoints points (InputError naming the file and the
/// product of its axes), computed without overflow and before any point is made.
void check_sweep_size(const SweepSpec& spec);

/// How a sweep file's config value that is not a file beside it is looked up as a preset name
/// (`config = series6xt_gx6450`), as --config finds it: the path found, or InputError saying why
/// not. The command sets it (find_data_file); unset, a config value is a file path only.
using ConfigNameLookup = std::string (*)(const std::string& name);
void set_sweep_config_lookup(ConfigNameLookup lookup);

/// Parses a sweep file (generated traces go into generated_trace_dir(db_path); empty: a
/// placeholder folder, for sweeps that only list or count points; a [generate] section is checked
/// against `generators`, and names no known technique without them). InputError naming file:line for anything malformed or unknown (sections,
/// keys, values out of range, bad ranges, zip lists of unequal length, globs matching nothing).
/// Non-empty `traces` (files or globs from the working folder, `sweep --trace`) replace the file's
/// [sweep] trace lines, which are then not read.
SweepSpec parse_sweep_file(const std::string& path, const std::vector<std::string>& traces = {},
                           const std::string& db_path = {}, const TraceGenerators& generators = {});

/// Expands one value list: "1, 2, 4", "16..64 step 16", "1..8 x 2" (also "*2"), "0.5..1 step 0.25".
/// InputError naming `where` when malformed.
std::vector<std::string> expand_value_list(const std::string& text, const std::string& where);

/// The points of a sweep, or of one slice of it, in their deterministic order: axes (last
/// fastest), then traces (the [sweep] traces, then the generated ones in [generate] order), then
/// repetitions. A point is made from its index when asked (a mixed-radix decode of the axes'
/// values), so a sweep of a million points keeps nothing per point (docs/limits.md).
class SweepPoints {
 public:
  /// The points of `spec` (kept by reference: it must outlive this) in `slice`: the point groups
  /// g with g % count == index. InputError when the sweep has more than kMaxSweepPoints points.
  explicit SweepPoints(const SweepSpec& spec, SweepSlice slice = {});

  std::size_t size() const { return size_; }            ///< points in the slice
  std::size_t total() const { return groups_ * reps_; }  ///< points in the whole sweep
  std::size_t groups() const { return groups_; }         ///< (configuration, trace) pairs of the whole sweep
  std::size_t combinations() const { return combos_; }   ///< configurations: the product of the axes' lengths
  /// Every trace path, in point order (a point's trace() indexes it).
  const std::vector<std::string>& traces() const { return trace_paths_; }

  /// Point i of the slice (0 <= i < size()).
  SweepPoint operator[](std::size_t i) const;
  /// Position of point i of the slice in the whole sweep.
  std::size_t index(std::size_t i) const { return group(i) * reps_ + i % reps_; }
  /// Its (configuration, trace) pair's number in the whole sweep.
  std::size_t group(std::size_t i) const { return slice_first_ + (i / reps_) * slice_step_; }
  /// Its configuration's number (the axes' values as digits, the last axis fastest).
  std::size_t combination(std::size_t i) const { return group(i) / trace_paths_.size(); }
  /// Its trace's position in traces().
  std::size_t trace(std::size_t i) const { return group(i) % trace_paths_.size(); }
  /// Its repetition (0-based).
  int repetition(std::size_t i) const { return static_cast<int>(i % reps_); }

  /// The value index of every axis of configuration c (the mixed-radix digits), into `digits`.
  void digits(std::size_t c, std::vector<std::size_t>& digits) const;
  /// The distinct configurations and traces of the slice's points (print_plan's counts).
  std::size_t configurations_in_slice() const;
  std::size_t traces_in_slice() const;
  /// Whether a point of the slice replays traces()[t].
  std::vector<bool> traces_used() const;

 private:
  const SweepSpec* spec_;
  std::vector<std::string> trace_paths_;
  std::vector<std::string> trace_labels_;  ///< the trace part of a point's label
  std::size_t combos_ = 1;
  std::size_t groups_ = 0;
  std::size_t reps_ = 1;
  std::size_t slice_first_ = 0;  ///< the slice's first group
  std::size_t slice_step_ = 1;   ///< groups between two of the slice's
  std::size_t size_ = 0;
};

/// All points in their deterministic order, as a list (SweepPoints without the laziness: for the
/// tests and the fuzz harness; a sweep runs over SweepPoints).
std::vector<SweepPoint> expand_sweep(const SweepSpec& spec);

/// Parses "i/K" (0 <= i < K). InputError naming the argument otherwise.
SweepSlice parse_slice(const std::string& text);

/// The points of one slice (their index and group are kept).
std::vector<SweepPoint> slice_points(const std::vector<SweepPoint>& points, SweepSlice slice);


}  // namespace tbdr
