#pragma once
// The analysis layer over a results database: the SQL views every database carries
// (analysis/views.sql, compiled in by analysis/views.cpp), a small prepared-statement helper, and
// the comparison tables of `tbdrsim report`.
#include <cstdint>
#include <iosfwd>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

struct sqlite3;
struct sqlite3_stmt;

namespace tbdr {

class ResultsDb;

/// The SQL of the analysis views, exactly as in analysis/views.sql.
std::string_view views_sql();
/// Hash of views_sql(); a database whose views carry another hash gets them re-created.
std::string views_sql_hash();
/// Creates the views in an open database, or re-creates them when they are missing or were made
/// by a different views.sql (one write transaction; nothing is written when they are current).
/// `path` names the database in errors (InputError).
void create_views(sqlite3* db, const std::string& path);

/// A prepared SQL statement on an open database that finalizes itself; errors are InputErrors
/// naming the database (and the SQL's first words when it cannot be prepared).
class SqlQuery {
 public:
  SqlQuery(sqlite3* db, const std::string& path, const std::string& sql);
  ~SqlQuery();
  SqlQuery(const SqlQuery&) = delete;
  SqlQuery& operator=(const SqlQuery&) = delete;

  SqlQuery& bind(int i, const std::string& v);
  SqlQuery& bind(int i, std::int64_t v);
  SqlQuery& bind(int i, double v);
  /// Steps once: true when a row is available.
  bool step();
  /// Resets for another execution with new bindings.
  void reset();
  int columns() const;
  std::string column_name(int col) const;
  bool is_null(int col) const;
  std::string text(int col) const;
  std::int64_t int64(int col) const;
  double real(int col) const;

 private:
  [[noreturn]] void fail(const std::string& what) const;
  sqlite3* db_;
  std::string path_;
  sqlite3_stmt* s_ = nullptr;
};

/// How `tbdrsim report` prints a table.
enum class ReportFormat { Table, Csv, Markdown };
/// Parses "table" | "csv" | "markdown" (InputError otherwise).
ReportFormat parse_report_format(const std::string& text);

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

/// The default metrics, in column order (figures absent from every run are dropped later).
std::vector<std::string> default_report_metrics(sqlite3* db, const std::string& path);
/// Builds the comparison. InputError for an unknown group key or metric, or bad SQL in `where`.
ReportTable build_report(const ResultsDb& db, const ReportOptions& options);
/// Prints it: aligned columns (table), CSV, or a Markdown table.
void print_report(const ReportTable& table, ReportFormat format, bool transpose, std::ostream& out);

}  // namespace tbdr
