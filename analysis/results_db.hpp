#pragma once
// The results database: one SQLite file (WAL mode, busy timeout), a versioned schema with forward
// migrations, and one transaction per run so a crash never leaves half a run behind. Queries go
// through its connection with the SQL helper (analysis/sql.hpp).
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "analysis/sql.hpp"
#include "kernel/stats.hpp"

namespace tbdr {

/// One resolved parameter of a run: key, canonical value text, and where the value came from.
struct RunParam {
  std::string key;
  std::string value;
  std::string origin;
  bool operator==(const RunParam&) const = default;
};

/// Everything stored about one run (write_run returns its id).
struct RunRecord {
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
  static constexpr int kSchemaVersion = 5;
  static constexpr int kApplicationId = 0x54424452;  ///< "TBDR"

  /// Opens (creating if absent) and migrates up to `target_version` (tests use older versions). A
  /// new database is made whole beside its name and linked in (create_whole): a failure (a full
  /// disk, a file size limit) leaves no file, not even its -wal or -shm.
  explicit ResultsDb(const std::string& path, int target_version = kSchemaVersion);
  /// Selects the constructor that opens a database only to read it.
  struct QueryOnly {};
  /// Opens an existing database to read it, changing nothing in it or beside it (no migration, no
  /// views, every write refused): InputError when it is absent, not a tbdrsim database, or newer.
  ResultsDb(const std::string& path, QueryOnly);
  ResultsDb(const ResultsDb&) = delete;
  ResultsDb& operator=(const ResultsDb&) = delete;

  /// Creates `path` (absent) with the schema of `target_version` and returns true, or returns
  /// false when another process created it meanwhile: the schema is written into a temporary
  /// database beside it whose connection is closed (folding its write-ahead log in) and which is
  /// then hard-linked to `path` (link fails rather than replace a file). InputError naming `path`
  /// and the system's reason when it cannot, with the temporary and its -wal and -shm removed.
  static bool create_whole(const std::string& path, int target_version = kSchemaVersion);
  /// Selects the constructor that opens or creates `path` in place, without create_whole's
  /// temporary: for a file only this process knows (create_whole's temporary, a run's working file).
  struct InPlace {};
  ResultsDb(const std::string& path, int target_version, InPlace);
  /// Moves a database this process made and closed (no -wal left) to `path` when nothing is there:
  /// true; false (and `made` left) when something is. InputError naming `path` when it cannot.
  static bool link_into_place(const std::string& made, const std::string& path);

  const std::string& path() const { return conn_.path(); }
  /// The open connection, for the queries of the analysis, sweep and study code.
  const SqlConnection& sql() const { return conn_; }
  int schema_version() const;

  /// Writes the whole run (runs, run_params, stat_defs, stats, tile_stats) in one transaction and
  /// returns its id.
  std::int64_t write_run(const RunRecord& run);
  /// A run's statistics in the order written, each with its unit and the description declared for
  /// its scope kind and name (stat_scope_kind; for runs written before schema v5, the one
  /// description its name had then).
  std::vector<StatRecord> run_stats(std::int64_t run_id) const;

 private:
  /// InputError unless the file is empty or a tbdrsim database (its application id).
  void check_identity();
  /// InputError when the schema is newer than this tbdrsim's.
  void check_not_newer();
  void setup(int target_version);
  void migrate(int target_version);
  SqlConnection conn_;
};

/// Checks, before any work, that `path` can take runs, without creating or changing anything: an
/// existing file must be a writable tbdrsim results database this version can open; for a new one,
/// its folder must exist and be writable. InputError naming the file otherwise.
void check_results_db_target(const std::string& path);

/// Checkpoints the database's write-ahead log into it and closes it, so that, when no other
/// connection has it open, SQLite removes the -wal and -shm files beside it (a user who copies the
/// .db file alone then copies every run). Commands call it after a reader that may not do this
/// (a read-only connection, such as the plot scripts', leaves them). Nothing when the file is absent.
void close_results_db_cleanly(const std::string& path);

/// What kind of scope a statistic is collected under, which with its name says what it means (the
/// results database describes statistics per kind and name): the scope with the index and name of
/// its command dropped ("pass3.lighting/rop" -> "pass/rop", "dispatch2.cull/compute" ->
/// "dispatch/compute"); the frame's and the memory system's scopes as they are ("frame/rop",
/// "mem/cache.slc"). One name can mean different things in different units: a cache's
/// fill_bytes and the ROP's, the DRAM's read_bytes as the units requested them ("frame/dram") and as
/// the devices served them ("mem/dram").
std::string stat_scope_kind(std::string_view scope);

/// Current UTC time as ISO 8601 ("2026-11-22T10:00:00Z").
std::string utc_now_iso8601();
/// This machine's host name.
std::string host_name();

}  // namespace tbdr
