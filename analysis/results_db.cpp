#include "analysis/results_db.hpp"

#include <sqlite3.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include <chrono>
#include <ctime>
#include <filesystem>
#include <map>
#include <optional>
#include <set>
#include <stdexcept>

#include "analysis/report.hpp"
#include "kernel/errors.hpp"

namespace tbdr {

namespace {

/// The forward migrations: entry i takes the schema from version i to version i+1.
const char* const kMigrations[] = {
    // v1: runs, their resolved parameters, statistic declarations and values.
    R"sql(
CREATE TABLE runs(
  id INTEGER PRIMARY KEY AUTOINCREMENT,
  started_at TEXT NOT NULL,
  finished_at TEXT,
  tool_version TEXT NOT NULL,
  host TEXT NOT NULL,
  command_line TEXT NOT NULL,
  config_name TEXT NOT NULL,
  config_hash TEXT NOT NULL,
  trace_path TEXT NOT NULL,
  trace_hash TEXT NOT NULL,
  scene TEXT NOT NULL,
  technique TEXT NOT NULL,
  status TEXT NOT NULL CHECK(status IN ('ok', 'failed', 'running')),
  error TEXT NOT NULL DEFAULT ''
);
CREATE TABLE run_params(
  run_id INTEGER NOT NULL REFERENCES runs(id) ON DELETE CASCADE,
  key TEXT NOT NULL,
  value TEXT NOT NULL,
  origin TEXT NOT NULL,
  UNIQUE(run_id, key)
);
CREATE TABLE stat_defs(
  name TEXT PRIMARY KEY,
  unit TEXT NOT NULL,
  description TEXT NOT NULL
);
CREATE TABLE stats(
  run_id INTEGER NOT NULL REFERENCES runs(id) ON DELETE CASCADE,
  scope TEXT NOT NULL,
  name TEXT NOT NULL,
  value REAL NOT NULL,
  unit TEXT NOT NULL,
  UNIQUE(run_id, scope, name)
);
)sql",
    // v2: optional per-tile rows for heat maps; lookup of finished runs by inputs (sweep resume).
    R"sql(
CREATE TABLE tile_stats(
  run_id INTEGER NOT NULL REFERENCES runs(id) ON DELETE CASCADE,
  pass INTEGER NOT NULL,
  tile_x INTEGER NOT NULL,
  tile_y INTEGER NOT NULL,
  cycles REAL NOT NULL,
  samples REAL NOT NULL,
  dram_bytes REAL NOT NULL,
  PRIMARY KEY(run_id, pass, tile_x, tile_y)
);
CREATE INDEX runs_by_inputs ON runs(config_hash, trace_hash, status);
)sql",
    // v3: claims of the sweep points being run, so that sweeps sharing a database run each point
    // once (app/sweep.cpp): the point (its inputs and repetition), the sweep that runs it (owner
    // token, host, process id) and when its claim lapses unless renewed (Unix seconds).
    R"sql(
CREATE TABLE sweep_claims(
  config_hash TEXT NOT NULL,
  trace_hash TEXT NOT NULL,
  repetition INTEGER NOT NULL,
  owner TEXT NOT NULL,
  host TEXT NOT NULL,
  pid INTEGER NOT NULL,
  lease_until REAL NOT NULL,
  PRIMARY KEY(config_hash, trace_hash, repetition)
);
)sql",
    // v4: the trace's technique options and viewpoint are stored as run parameters
    // (technique.<option>, trace.camera; app/run_driver.cpp) and grouped on by key: an index by key
    // so that `report --by KEY` and v_param lookups by key do not scan every run's parameters.
    R"sql(
CREATE INDEX run_params_by_key ON run_params(key, run_id);
)sql",
    // v5: a statistic is described per scope kind and name (stat_scope_kind): one name means
    // different things in different units (a cache's fill_bytes, the ROP's; the DRAM's read_bytes
    // as requested and as served), and v1-v4 kept one description per name, the first unit's. Their
    // rows stay under the empty kind, the description of last resort for the runs written then.
    R"sql(
CREATE TABLE stat_defs_by_kind(
  scope_kind TEXT NOT NULL,
  name TEXT NOT NULL,
  unit TEXT NOT NULL,
  description TEXT NOT NULL,
  PRIMARY KEY(scope_kind, name)
);
INSERT INTO stat_defs_by_kind(scope_kind, name, unit, description) SELECT '', name, unit, description FROM stat_defs;
DROP TABLE stat_defs;
ALTER TABLE stat_defs_by_kind RENAME TO stat_defs;
)sql",
};
static_assert(sizeof(kMigrations) / sizeof(kMigrations[0]) == ResultsDb::kSchemaVersion);

/// `path` when it is an existing file (what a query-only open needs), else an InputError.
const std::string& checked_existing(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) throw InputError(path, "no such results database");
  if (!std::filesystem::is_regular_file(path, ec)) throw InputError(path, "not a results database file (a folder or a device)");
  return path;
}

}  // namespace

void check_results_db_target(const std::string& path) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (path.empty()) throw InputError("--db", "empty results database path");
  if (fs::exists(path, ec)) {
    // Refused before it is opened: opening a WAL database creates its -wal and -shm files, which a
    // connection that cannot write leaves behind.
    const fs::path folder = fs::path(path).has_parent_path() ? fs::path(path).parent_path() : fs::path(".");
    if (access(path.c_str(), W_OK) != 0) throw InputError(path, "results database is not writable");
    if (access(folder.c_str(), W_OK | X_OK) != 0) {
      throw InputError(path, "results database's folder '" + folder.string() +
                                 "' is not writable (SQLite writes its -wal and -shm files beside the database)");
    }
    { ResultsDb check(path, ResultsDb::QueryOnly{}); }
    return;
  }
  const fs::path folder = fs::path(path).has_parent_path() ? fs::path(path).parent_path() : fs::path(".");
  if (!fs::is_directory(folder, ec)) {
    throw InputError(path, "cannot create the results database: folder '" + folder.string() + "' does not exist");
  }
  if (access(folder.c_str(), W_OK | X_OK) != 0) {
    throw InputError(path, "cannot create the results database: folder '" + folder.string() + "' is not writable");
  }
}

namespace {

/// `path`, after create_whole made it when it was absent.
const std::string& created_if_absent(const std::string& path, int target_version) {
  std::error_code ec;
  const bool special = path.empty() || path == ":memory:" || path.rfind("file:", 0) == 0;  // SQLite's own names
  if (!special && !std::filesystem::exists(path, ec) && !ec) ResultsDb::create_whole(path, target_version);
  return path;
}

/// Removes a database file and the files SQLite keeps beside it, unless released.
class DatabaseFilesGuard {
 public:
  explicit DatabaseFilesGuard(std::string path) : path_(std::move(path)) {}
  ~DatabaseFilesGuard() {
    if (path_.empty()) return;
    std::error_code ec;
    for (const char* suffix : {"", "-wal", "-shm", "-journal"}) std::filesystem::remove(path_ + suffix, ec);
  }
  DatabaseFilesGuard(const DatabaseFilesGuard&) = delete;
  DatabaseFilesGuard& operator=(const DatabaseFilesGuard&) = delete;

 private:
  std::string path_;
};

}  // namespace

bool ResultsDb::create_whole(const std::string& path, int target_version) {
  const std::string temp = path + ".new-" + std::to_string(getpid());
  DatabaseFilesGuard guard(temp);  // whatever happens, the temporary goes
  try {
    ResultsDb made(temp, target_version, InPlace{});
  } catch (const InputError& e) {
    std::string why = e.what();
    if (why.rfind(temp + ": ", 0) == 0) why = why.substr(temp.size() + 2);
    throw InputError(path, "cannot create the results database: " + why + "; nothing written");
  }
  return link_into_place(temp, path);
}

bool ResultsDb::link_into_place(const std::string& made, const std::string& path) {
  std::error_code ec;
  // The connection's close folds the write-ahead log into the file and removes it; a close that
  // could not (a full disk) leaves it, and the file alone would miss its last commits.
  if (std::filesystem::exists(made + "-wal", ec)) {
    throw InputError(path, "cannot create the results database: its write-ahead log could not be folded in "
                           "(a full disk?); nothing written");
  }
  if (link(made.c_str(), path.c_str()) != 0) {
    const int err = errno;
    if (err == EEXIST) return false;
    throw InputError(path, "cannot create the results database: " + std::string(std::strerror(err)) + "; nothing written");
  }
  std::filesystem::remove(made, ec);
  return true;
}

ResultsDb::ResultsDb(const std::string& path, int target_version) : conn_(created_if_absent(path, target_version)) {
  if (target_version < 1 || target_version > kSchemaVersion) {
    throw std::logic_error("ResultsDb: bad target schema version");
  }
  // Opening writers race on a new file (creating the schema, switching to WAL); SQLite reports
  // some of those races as busy without waiting, so the whole setup is retried.
  retry_while_busy([&] { setup(target_version); });
}

ResultsDb::ResultsDb(const std::string& path, int target_version, InPlace) : conn_(path) {
  if (target_version < 1 || target_version > kSchemaVersion) {
    throw std::logic_error("ResultsDb: bad target schema version");
  }
  retry_while_busy([&] { setup(target_version); });
}

ResultsDb::ResultsDb(const std::string& path, QueryOnly) : conn_(checked_existing(path), SqlOpen::ExistingQueryOnly) {
  retry_while_busy([&] {
    check_identity();
    check_not_newer();
  });
}

void ResultsDb::setup(int target_version) {
  conn_.exec("PRAGMA foreign_keys = ON");
  check_identity();
  // A commit in WAL mode syncs the log only at checkpoints (SQLite, "PRAGMA synchronous":
  // NORMAL is safe from corruption in WAL mode; a power loss may roll back the last commits, not
  // damage the file). FULL synced every commit: 2-3 ms of a 1080p run's serial end, creating a
  // new database and writing its run (0.9 -> 0.3 ms per commit, 2026-12-06). Set first: the switch
  // to WAL and the schema's creation commit under it too.
  conn_.exec("PRAGMA synchronous = NORMAL");
  conn_.exec("PRAGMA journal_mode = WAL");
  migrate(target_version);
  create_views(conn_);  // the analysis views (analysis/views.sql)
}

void ResultsDb::check_identity() {
  // Check what the file is before changing anything in it. Both figures come from one statement,
  // so from one read transaction: read apart, another writer could commit the schema and the id
  // (one transaction, migrate()) between the two reads, and a new tbdrsim database would look
  // like a foreign one (id 0 with schema objects).
  int app_id = 0;
  int object_count = 0;
  try {
    SqlStatement s(conn_, "SELECT (SELECT application_id FROM pragma_application_id), (SELECT count(*) FROM sqlite_master)");
    if (s.step()) {
      app_id = static_cast<int>(s.int64(0));
      object_count = static_cast<int>(s.int64(1));
    }
  } catch (const SqlError& e) {
    // A text file, an image, a trace given as --db: SQLite cannot read its header.
    if (e.code() != SQLITE_NOTADB) throw;
    throw InputError(path(), "not a results database: the file is not an SQLite database (a text or other file); "
                             "--db names the database a run, sweep or study wrote, or a new file to create");
  }
  if (app_id != kApplicationId && (app_id != 0 || object_count != 0)) {
    throw InputError(path(), "not a tbdrsim results database (SQLite application_id " +
                                 std::to_string(app_id) + ", " + std::to_string(object_count) + " schema objects)");
  }
}

void ResultsDb::check_not_newer() {
  const int current = schema_version();
  if (current > kSchemaVersion) {
    throw InputError(path(), "results database schema version " + std::to_string(current) +
                                 " is newer than this tbdrsim supports (" + std::to_string(kSchemaVersion) +
                                 "); use a newer tbdrsim");
  }
}

int ResultsDb::schema_version() const {
  SqlStatement s(conn_, "PRAGMA user_version");
  return s.step() ? static_cast<int>(s.int64(0)) : 0;
}

void ResultsDb::migrate(int target_version) {
  SqlTransaction tx(conn_);
  check_not_newer();
  const int current = schema_version();
  for (int v = current; v < target_version; ++v) conn_.exec(kMigrations[v]);
  if (current < target_version) {
    // A PRAGMA takes no bound parameters: its values are written here, and both are integers.
    conn_.exec("PRAGMA application_id = " + std::to_string(kApplicationId));
    conn_.exec("PRAGMA user_version = " + std::to_string(target_version));
  }
  tx.commit();
}

std::int64_t ResultsDb::write_run(const RunRecord& run) {
  // BEGIN IMMEDIATE waits through the busy timeout; a busy error that SQLite reports at once (a
  // writer racing a checkpoint) is retried.
  std::optional<SqlTransaction> tx;
  retry_while_busy([&] { tx.emplace(conn_); });
  {
    SqlStatement s(conn_,
                   "INSERT INTO runs(started_at, finished_at, tool_version, host, command_line, config_name, "
                   "config_hash, trace_path, trace_hash, scene, technique, status, error) "
                   "VALUES(?,?,?,?,?,?,?,?,?,?,?,?,?)");
    s.bind(1, run.started_at).bind(2, run.finished_at).bind(3, run.tool_version).bind(4, run.host);
    s.bind(5, run.command_line).bind(6, run.config_name).bind(7, run.config_hash).bind(8, run.trace_path);
    s.bind(9, run.trace_hash).bind(10, run.scene).bind(11, run.technique).bind(12, run.status);
    s.bind(13, run.error);
    s.run();
  }
  const std::int64_t id = conn_.last_insert_rowid();
  {
    SqlStatement s(conn_, "INSERT INTO run_params(run_id, key, value, origin) VALUES(?,?,?,?)");
    for (const auto& p : run.params) {
      s.bind(1, id).bind(2, p.key).bind(3, p.value).bind(4, p.origin);
      s.run();
    }
  }
  {
    // Before v5 (tests write older schemas) a statistic was described by its name alone.
    const bool by_kind = schema_version() >= 5;
    SqlStatement def(conn_, by_kind ? "INSERT INTO stat_defs(scope_kind, name, unit, description) VALUES(?,?,?,?) "
                                      "ON CONFLICT(scope_kind, name) DO UPDATE SET unit = excluded.unit, description = excluded.description"
                                    : "INSERT INTO stat_defs(name, unit, description) VALUES(?,?,?) "
                                      "ON CONFLICT(name) DO UPDATE SET unit = excluded.unit, description = excluded.description");
    SqlStatement s(conn_, "INSERT INTO stats(run_id, scope, name, value, unit) VALUES(?,?,?,?,?)");
    std::set<std::pair<std::string, std::string>> defined;
    for (const auto& st : run.stats) {
      std::string kind = by_kind ? stat_scope_kind(st.scope) : std::string();
      if (!defined.contains({kind, st.name})) {
        if (by_kind) {
          def.bind(1, kind).bind(2, st.name).bind(3, st.unit).bind(4, st.description);
        } else {
          def.bind(1, st.name).bind(2, st.unit).bind(3, st.description);
        }
        def.run();
        defined.insert({std::move(kind), st.name});
      }
      s.bind(1, id).bind(2, st.scope).bind(3, st.name).bind(4, st.value).bind(5, st.unit);
      s.run();
    }
  }
  if (!run.tiles.empty()) {
    SqlStatement s(conn_,
                   "INSERT INTO tile_stats(run_id, pass, tile_x, tile_y, cycles, samples, dram_bytes) "
                   "VALUES(?,?,?,?,?,?,?)");
    for (const auto& t : run.tiles) {
      s.bind(1, id).bind(2, t.pass).bind(3, t.tile_x).bind(4, t.tile_y).bind(5, t.cycles);
      s.bind(6, t.samples).bind(7, t.dram_bytes);
      s.run();
    }
  }
  tx->commit();
  return id;
}

std::vector<StatRecord> ResultsDb::run_stats(std::int64_t run_id) const {
  // Every description of the database, by (scope kind, name): a few thousand rows at most.
  std::map<std::pair<std::string, std::string>, std::string> described;
  {
    SqlStatement d(conn_, schema_version() >= 5 ? "SELECT scope_kind, name, description FROM stat_defs"
                                                : "SELECT '', name, description FROM stat_defs");
    while (d.step()) described.emplace(std::pair{d.text(0), d.text(1)}, d.text(2));
  }
  auto description = [&](const std::string& scope, const std::string& name) -> std::string {
    if (auto it = described.find({stat_scope_kind(scope), name}); it != described.end()) return it->second;
    if (auto it = described.find({std::string(), name}); it != described.end()) return it->second;  // written before v5
    return {};
  };
  std::vector<StatRecord> out;
  SqlStatement s(conn_, "SELECT scope, name, value, unit FROM stats WHERE run_id = ? ORDER BY rowid");
  s.bind(1, run_id);
  while (s.step()) {
    StatRecord r{s.text(0), s.text(1), s.real(2), s.text(3), {}};
    r.description = description(r.scope, r.name);
    out.push_back(std::move(r));
  }
  return out;
}

std::string stat_scope_kind(std::string_view scope) {
  const std::size_t slash = scope.find('/');
  const std::string_view head = scope.substr(0, slash);
  const std::size_t digit = head.find_first_of("0123456789");
  std::string kind(head.substr(0, digit));
  if (slash != std::string_view::npos) kind.append(scope.substr(slash));
  return kind;
}

void close_results_db_cleanly(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) return;
  SqlConnection c(path, SqlOpen::ExistingQueryOnly);
  // query_only refuses writes but not a checkpoint; the connection's close then removes the WAL
  // files when it is the last one (SQLite's default: it checkpoints and deletes the log).
  retry_while_busy([&] { c.exec("PRAGMA wal_checkpoint(TRUNCATE)"); });
}

std::string utc_now_iso8601() {
  const std::time_t t = std::chrono::system_clock::to_time_t(std::chrono::system_clock::now());
  std::tm tm{};
  gmtime_r(&t, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return buf;
}

std::string host_name() {
  char buf[256] = {};
  if (gethostname(buf, sizeof buf - 1) != 0) return "unknown";
  return buf;
}

}  // namespace tbdr
