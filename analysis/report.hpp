#pragma once
// The analysis layer over a results database: the SQL views every database carries
// (analysis/views.sql, compiled in by analysis/views.cpp) and the comparison tables of
// `tbdrsim report`.
#include <cstdint>
#include <iosfwd>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace tbdr {

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
  /// Group keys, in order: "technique", "scene", "config" or any v_param key
  /// ("tiling.tile_width", "trace.lights", ...). Empty: technique.
  std::vector<std::string> by;
  /// v_metric names; empty: the default set, keeping only figures some run recorded.
  std::vector<std::string> metrics;
  /// SQL condition on v_run_summary's columns ("lights = 256 AND config_name = 'x'").
  std::string where;
  bool transpose = false;  ///< metrics as rows, groups as columns
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
  /// Groups holding runs of different configurations or traces (averaged together), if any.
  std::int64_t mixed_groups = 0;
};

/// Builds the comparison. InputError for an unknown group key or metric, or bad SQL in `where`.
ReportTable build_report(const ResultsDb& db, const ReportOptions& options);
/// Prints it: aligned columns (table), CSV, or a Markdown table.
void print_report(const ReportTable& table, ReportFormat format, bool transpose, std::ostream& out);

}  // namespace tbdr
