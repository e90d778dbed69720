#pragma once
// The results database: one SQLite file (WAL mode, busy timeout), a versioned schema with forward
// migrations, and one transaction per run so a crash never leaves half a run behind.
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "kernel/stats.hpp"

struct sqlite3;

namespace tbdr {

/// One resolved parameter of a run: key, canonical value text, and where the value came from.
struct RunParam {
  std::string key;
  std::string value;
  std::string origin;
  bool operator==(const RunParam&) const = default;
};


/// Everything stored about one run. `id` is set by write_run / read back by read_run.
struct RunRecord {
  std::int64_t id = 0;
  std::string started_at;    ///< ISO 8601 UTC
  std::string finished_at;   ///< ISO 8601 UTC
  std::string tool_version;
  std::string host;
  std::string command_line;
  std::string config_name;
  std::string config_hash;
  std::string trace_path;
  std::string trace_hash;
  std::string scene;
  std::string technique;
  std::string status = "ok";  ///< ok | failed | running
  std::string error;          ///< message when status is failed
  std::vector<RunParam> params;
  std::vector<StatRecord> stats;
  std::vector<TileRecord> tiles;
};

/// The embedded results database. Opening creates or migrates the schema; a database written by a
/// newer tbdrsim (higher user_version) or a SQLite file that is not a tbdrsim database is refused
/// with an InputError naming the file.
class ResultsDb {
 public:
  static constexpr int kSchemaVersion = 2;
  static constexpr int kApplicationId = 0x54424452;  ///< "TBDR"

  /// Opens (creating if absent) and migrates up to `target_version` (tests use older versions).
  explicit ResultsDb(const std::string& path, int target_version = kSchemaVersion);
  ~ResultsDb();
  ResultsDb(const ResultsDb&) = delete;
  ResultsDb& operator=(const ResultsDb&) = delete;

  const std::string& path() const { return path_; }
  int schema_version() const;

  /// Writes the whole run (runs, run_params, stat_defs, stats, tile_stats) in one transaction and
  /// returns its id.
  std::int64_t write_run(const RunRecord& run);
  /// Reads a run back (params and stats in insertion order); nullopt when absent.
  std::optional<RunRecord> read_run(std::int64_t id) const;
  /// Ids of all runs, ascending.
  std::vector<std::int64_t> run_ids() const;
  /// Id of a finished (status ok) run with this resolved configuration and trace, if any.
  std::optional<std::int64_t> find_ok_run(const std::string& config_hash, const std::string& trace_hash) const;
  /// Runs arbitrary SQL with no result (views, maintenance); InputError on failure.
  void exec(const std::string& sql) const;

  /// The raw handle for analysis code that issues its own queries.
  sqlite3* handle() const { return db_; }

 private:
  void setup(int target_version);
  void migrate(int target_version);
  std::string path_;
  sqlite3* db_ = nullptr;
};

/// Current UTC time as ISO 8601 ("2026-11-22T10:00:00Z").
std::string utc_now_iso8601();
/// This machine's host name.
std::string host_name();

}  // namespace tbdr
