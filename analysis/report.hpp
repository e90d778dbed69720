#pragma once
// The analysis layer over a results database: the SQL views every database carries
// (analysis/views.sql, compiled in by analysis/views.cpp) and the comparison tables of
// `tbdrsim report`.
#include <cstdint>
#include <iosfwd>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace tbdr {

/// The names of the v_metric figures (analysis/views.sql, v_metric_def) that C++ code names: the
/// report's default columns and the study's ranks. Declared here once; tests/test_stat_names.cpp
/// checks each is in v_metric_def. frame_time_ms is also the name of the statistic it passes
/// through (frame/timing, sim/app/run_stats.hpp).
namespace metric {
inline constexpr const char* kFrameTimeMs = "frame_time_ms";
inline constexpr const char* kCycles = "cycles";
inline constexpr const char* kDramTotalMb = "dram_total_mb";
inline constexpr const char* kDramReadMb = "dram_read_mb";
inline constexpr const char* kDramWriteMb = "dram_write_mb";
inline constexpr const char* kRequestedTotalMb = "requested_total_mb";
inline constexpr const char* kEnergyTotalMj = "energy_total_mj";
inline constexpr const char* kShadedFragmentsPerPixel = "shaded_fragments_per_pixel";
inline constexpr const char* kOvershading = "overshading";
inline constexpr const char* kLightsPerPixel = "lights_per_pixel";
/// Every name above, for the check against the views.
inline constexpr const char* kAll[] = {kFrameTimeMs,   kCycles,        kDramTotalMb,           kDramReadMb,
                                       kDramWriteMb,   kRequestedTotalMb, kEnergyTotalMj, kShadedFragmentsPerPixel,
                                       kOvershading,   kLightsPerPixel};
}  // namespace metric

class ResultsDb;
class SqlConnection;

/// The SQL of the analysis views, exactly as in analysis/views.sql.
std::string_view views_sql();
/// Hash of views_sql(); a database whose views carry another hash gets them re-created.
std::string views_sql_hash();
/// Creates the views in an open database, or re-creates them when they are missing or were made
/// by a different views.sql (one write transaction; nothing is written when they are current).
void create_views(const SqlConnection& db);

/// How `tbdrsim report` prints a table.
enum class ReportFormat { Table, Csv, Markdown };
/// Parses "table" | "csv" | "markdown" (InputError otherwise).
ReportFormat parse_report_format(const std::string& text);

/// The names `--by` accepts in this database (shorthands and every v_param key), for suggestions.
std::vector<std::string> report_group_key_names(const ResultsDb& db);
/// The metric names some run in this database has (v_metric), for suggestions.
std::vector<std::string> report_metric_names(const ResultsDb& db);

/// What to compare: group keys, metrics, a row filter.
struct ReportOptions {
  /// Group keys, in order: "technique", "scene", "config" (its label), "lights", "camera",
  /// "resolution", "trace" or any v_param key ("tiling.tile_width", "technique.pls_bytes", ...).
  /// Empty: technique.
  std::vector<std::string> by;
  /// v_metric names; empty: the default set, keeping only figures some run recorded.
  std::vector<std::string> metrics;
  /// SQL condition on v_run_summary's columns and on any v_param key written as a column
  /// ("lights = 256 AND technique.pls_bytes = 16 AND gpu.mode = 'tbdr'").
  std::string where;
  /// "KEY=VALUE": each group is compared with the group that differs from it only in KEY, where
  /// KEY has VALUE (KEY is added to the group keys when absent). Empty: no comparison.
  std::string baseline;
  bool transpose = false;  ///< metrics as rows, groups as columns
  /// A metric to rank the rows by, least first ("energy_dram_mj"), or largest first with ":max"
  /// ("tsp.shaded_samples:max"): rows are ranked among the rows that share every group key but the
  /// last (with one key, among all rows), sorted by those keys and the rank. Added to the metrics
  /// when absent. Empty: no rank.
  std::string rank;
  bool best = false;  ///< with `rank`: only the rows ranked first (ties kept)
};

/// A computed comparison: one row per group (finished runs only, repetitions averaged).
struct ReportTable {
  std::vector<std::string> group_keys;  ///< column titles of the group keys
  std::vector<std::string> metrics;     ///< metric names, in column order
  std::vector<std::string> units;       ///< one per metric
  /// One row per group: the group key values, then one averaged value per metric (nullopt: absent).
  struct Row {
    std::vector<std::string> keys;
    std::vector<std::optional<double>> values;
    std::int64_t runs = 0;
  };
  std::vector<Row> rows;
  /// With a baseline: which group key it varies, its value, and per row the baseline group's
  /// values (nullopt where that group has no value or does not exist).
  std::optional<std::size_t> baseline_key;
  std::string baseline_value;
  std::vector<std::vector<std::optional<double>>> baseline_values;
  std::int64_t rows_without_baseline = 0;  ///< rows whose baseline group is absent
  /// With a rank: the metric ranked (index into `metrics`), whether larger is better, and per row
  /// its rank (1 = best; 0 = the row has no value for the metric).
  std::optional<std::size_t> rank_metric;
  bool rank_largest_first = false;
  std::vector<int> ranks;
  /// How the table/markdown formats split the metrics into titled tables with short headers (the
  /// default report: frame figures, DRAM per class, energy per component); CSV prints them flat.
  struct Section {
    std::string title;
    std::vector<std::size_t> metrics;  ///< indices into `metrics`
    std::vector<std::string> headers;  ///< one per metric
  };
  std::vector<Section> sections;
  std::int64_t runs_used = 0;     ///< finished runs that passed the filter
  std::int64_t runs_failed = 0;   ///< failed runs left out (matching the filter)
  /// Why they failed: each distinct reason (the runs' error without the trace's file:line prefix)
  /// and how many runs it left out, most first.
  std::vector<std::pair<std::string, std::int64_t>> failed_reasons;
  /// Groups holding runs of different configurations or traces (averaged together), if any.
  std::int64_t mixed_groups = 0;
};

/// The v_param key a group key shorthand stands for ("technique" -> "trace.technique", "config"
/// -> "config.label", "lights" -> "trace.lights", ...); other keys are returned unchanged.
std::string canonical_group_key(const std::string& key);

/// The derived figures of one run, read from v_run_summary (their one definition: views.sql);
/// nullopt where the run did not record what a figure needs.
struct DerivedFigures {
  std::optional<double> frame_time_ms, cycles, dram_total_mb, requested_total_mb, energy_total_mj;
  std::optional<double> shaded_fragments_per_pixel, overshading, lights_per_pixel, lights_per_fragment;
  std::string config_label;
};
/// Reads them; InputError when the database has no such run.
DerivedFigures read_derived_figures(const ResultsDb& db, std::int64_t run_id);

/// Builds the comparison. InputError for an unknown group key or metric, bad SQL in `where`, or a
/// malformed or absent baseline.
ReportTable build_report(const ResultsDb& db, const ReportOptions& options);
/// Prints it: aligned columns (table), CSV, or a Markdown table.
void print_report(const ReportTable& table, ReportFormat format, bool transpose, std::ostream& out);

}  // namespace tbdr
