#include "analysis/results_db.hpp"

#include <sqlite3.h>
#include <unistd.h>

#include <chrono>
#include <ctime>
#include <map>
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
};
static_assert(sizeof(kMigrations) / sizeof(kMigrations[0]) == ResultsDb::kSchemaVersion);

/// A prepared statement that finalizes itself.
class Stmt {
 public:
  Stmt(sqlite3* db, const std::string& path, const char* sql) : db_(db), path_(path) {
    if (sqlite3_prepare_v2(db, sql, -1, &s_, nullptr) != SQLITE_OK) fail("prepare");
  }
  ~Stmt() { sqlite3_finalize(s_); }
  Stmt(const Stmt&) = delete;
  Stmt& operator=(const Stmt&) = delete;

  Stmt& bind(int i, const std::string& v) {
    sqlite3_bind_text(s_, i, v.c_str(), static_cast<int>(v.size()), SQLITE_TRANSIENT);
    return *this;
  }
  Stmt& bind(int i, std::int64_t v) {
    sqlite3_bind_int64(s_, i, v);
    return *this;
  }
  Stmt& bind(int i, double v) {
    sqlite3_bind_double(s_, i, v);
    return *this;
  }
  /// Steps once: true when a row is available.
  bool step() {
    const int rc = sqlite3_step(s_);
    if (rc == SQLITE_ROW) return true;
    if (rc == SQLITE_DONE) return false;
    fail("step");
    return false;
  }
  void run_and_reset() {
    step();
    sqlite3_reset(s_);
    sqlite3_clear_bindings(s_);
  }
  std::string text(int col) const {
    const auto* p = sqlite3_column_text(s_, col);
    return p ? reinterpret_cast<const char*>(p) : "";
  }
  std::int64_t int64(int col) const { return sqlite3_column_int64(s_, col); }
  double real(int col) const { return sqlite3_column_double(s_, col); }

 private:
  [[noreturn]] void fail(const char* what) {
    throw InputError(path_, std::string("SQLite ") + what + " failed: " + sqlite3_errmsg(db_));
  }
  sqlite3* db_;
  const std::string& path_;
  sqlite3_stmt* s_ = nullptr;
};

}  // namespace

ResultsDb::ResultsDb(const std::string& path, int target_version) : path_(path) {
  if (target_version < 1 || target_version > kSchemaVersion) {
    throw std::logic_error("ResultsDb: bad target schema version");
  }
  if (sqlite3_open_v2(path.c_str(), &db_, SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE, nullptr) != SQLITE_OK) {
    std::string msg = db_ ? sqlite3_errmsg(db_) : "out of memory";
    sqlite3_close(db_);
    db_ = nullptr;
    throw InputError(path, "cannot open results database: " + msg);
  }
  try {
    sqlite3_busy_timeout(db_, 60000);
    // Opening writers race on a new file (creating the schema, switching to WAL); SQLite reports
    // some of those races as SQLITE_BUSY without waiting, so the whole setup is retried.
    for (int attempt = 0;; ++attempt) {
      try {
        setup(target_version);
        break;
      } catch (const InputError&) {
        const int code = sqlite3_errcode(db_) & 0xff;
        if ((code != SQLITE_BUSY && code != SQLITE_LOCKED) || attempt >= 200) throw;
        sqlite3_exec(db_, "ROLLBACK", nullptr, nullptr, nullptr);
        usleep(static_cast<useconds_t>(2000 + 1000 * attempt));
      }
    }
  } catch (const InputError& e) {
    sqlite3_close(db_);
    db_ = nullptr;
    const std::string msg = e.what();
    // Messages from Stmt already start with the path.
    if (msg.rfind(path, 0) == 0) throw;
    throw InputError(path, msg);
  } catch (...) {
    sqlite3_close(db_);
    db_ = nullptr;
    throw;
  }
}

void ResultsDb::setup(int target_version) {
  exec("PRAGMA foreign_keys = ON");
  // Check what the file is before changing anything in it.
  int app_id = 0;
  int object_count = 0;
  {
    Stmt s(db_, path_, "PRAGMA application_id");
    if (s.step()) app_id = static_cast<int>(s.int64(0));
  }
  {
    Stmt s(db_, path_, "SELECT count(*) FROM sqlite_master");
    if (s.step()) object_count = static_cast<int>(s.int64(0));
  }
  if (app_id != kApplicationId && (app_id != 0 || object_count != 0)) {
    throw InputError(path_, "not a tbdrsim results database (SQLite application_id " +
                               std::to_string(app_id) + ", " + std::to_string(object_count) + " schema objects)");
  }
  exec("PRAGMA journal_mode = WAL");
  migrate(target_version);
  create_views(db_, path_);  // the analysis views (analysis/views.sql)
}

ResultsDb::~ResultsDb() { sqlite3_close(db_); }

void ResultsDb::exec(const std::string& sql) const {
  char* err = nullptr;
  if (sqlite3_exec(db_, sql.c_str(), nullptr, nullptr, &err) != SQLITE_OK) {
    std::string msg = err ? err : sqlite3_errmsg(db_);
    sqlite3_free(err);
    throw InputError(path_, "SQLite: " + msg);
  }
}

int ResultsDb::schema_version() const {
  Stmt s(db_, path_, "PRAGMA user_version");
  return s.step() ? static_cast<int>(s.int64(0)) : 0;
}

void ResultsDb::migrate(int target_version) {
  exec("BEGIN IMMEDIATE");
  try {
    const int current = schema_version();
    if (current > kSchemaVersion) {
      throw InputError(path_, "results database schema version " + std::to_string(current) +
                                  " is newer than this tbdrsim supports (" + std::to_string(kSchemaVersion) +
                                  "); use a newer tbdrsim");
    }
    for (int v = current; v < target_version; ++v) exec(kMigrations[v]);
    if (current < target_version) {
      exec("PRAGMA application_id = " + std::to_string(kApplicationId));
      exec("PRAGMA user_version = " + std::to_string(target_version));
    }
    exec("COMMIT");
  } catch (...) {
    sqlite3_exec(db_, "ROLLBACK", nullptr, nullptr, nullptr);
    throw;
  }
}

std::int64_t ResultsDb::write_run(const RunRecord& run) {
  // BEGIN IMMEDIATE waits through the busy timeout; a busy error that SQLite reports at once (a
  // writer racing a checkpoint) is retried.
  for (int attempt = 0;; ++attempt) {
    if (sqlite3_exec(db_, "BEGIN IMMEDIATE", nullptr, nullptr, nullptr) == SQLITE_OK) break;
    const int code = sqlite3_errcode(db_) & 0xff;
    if ((code != SQLITE_BUSY && code != SQLITE_LOCKED) || attempt >= 200) {
      throw InputError(path_, std::string("SQLite: cannot begin a transaction: ") + sqlite3_errmsg(db_));
    }
    usleep(static_cast<useconds_t>(2000 + 1000 * attempt));
  }
  try {
    {
      Stmt s(db_, path_,
             "INSERT INTO runs(started_at, finished_at, tool_version, host, command_line, config_name, "
             "config_hash, trace_path, trace_hash, scene, technique, status, error) "
             "VALUES(?,?,?,?,?,?,?,?,?,?,?,?,?)");
      s.bind(1, run.started_at).bind(2, run.finished_at).bind(3, run.tool_version).bind(4, run.host);
      s.bind(5, run.command_line).bind(6, run.config_name).bind(7, run.config_hash).bind(8, run.trace_path);
      s.bind(9, run.trace_hash).bind(10, run.scene).bind(11, run.technique).bind(12, run.status);
      s.bind(13, run.error);
      s.step();
    }
    const std::int64_t id = sqlite3_last_insert_rowid(db_);
    {
      Stmt s(db_, path_, "INSERT INTO run_params(run_id, key, value, origin) VALUES(?,?,?,?)");
      for (const auto& p : run.params) {
        s.bind(1, id).bind(2, p.key).bind(3, p.value).bind(4, p.origin);
        s.run_and_reset();
      }
    }
    {
      Stmt def(db_, path_,
               "INSERT INTO stat_defs(name, unit, description) VALUES(?,?,?) "
               "ON CONFLICT(name) DO UPDATE SET unit = excluded.unit, description = excluded.description");
      Stmt s(db_, path_, "INSERT INTO stats(run_id, scope, name, value, unit) VALUES(?,?,?,?,?)");
      std::map<std::string, bool> defined;
      for (const auto& st : run.stats) {
        if (!defined[st.name]) {
          def.bind(1, st.name).bind(2, st.unit).bind(3, st.description);
          def.run_and_reset();
          defined[st.name] = true;
        }
        s.bind(1, id).bind(2, st.scope).bind(3, st.name).bind(4, st.value).bind(5, st.unit);
        s.run_and_reset();
      }
    }
    if (!run.tiles.empty()) {
      Stmt s(db_, path_,
             "INSERT INTO tile_stats(run_id, pass, tile_x, tile_y, cycles, samples, dram_bytes) "
             "VALUES(?,?,?,?,?,?,?)");
      for (const auto& t : run.tiles) {
        s.bind(1, id).bind(2, t.pass).bind(3, t.tile_x).bind(4, t.tile_y).bind(5, t.cycles);
        s.bind(6, t.samples).bind(7, t.dram_bytes);
        s.run_and_reset();
      }
    }
    exec("COMMIT");
    return id;
  } catch (...) {
    sqlite3_exec(db_, "ROLLBACK", nullptr, nullptr, nullptr);
    throw;
  }
}

std::optional<RunRecord> ResultsDb::read_run(std::int64_t id) const {
  RunRecord r;
  {
    Stmt s(db_, path_,
           "SELECT id, started_at, finished_at, tool_version, host, command_line, config_name, config_hash, "
           "trace_path, trace_hash, scene, technique, status, error FROM runs WHERE id = ?");
    s.bind(1, id);
    if (!s.step()) return std::nullopt;
    r.id = s.int64(0);
    r.started_at = s.text(1);
    r.finished_at = s.text(2);
    r.tool_version = s.text(3);
    r.host = s.text(4);
    r.command_line = s.text(5);
    r.config_name = s.text(6);
    r.config_hash = s.text(7);
    r.trace_path = s.text(8);
    r.trace_hash = s.text(9);
    r.scene = s.text(10);
    r.technique = s.text(11);
    r.status = s.text(12);
    r.error = s.text(13);
  }
  {
    Stmt s(db_, path_, "SELECT key, value, origin FROM run_params WHERE run_id = ? ORDER BY rowid");
    s.bind(1, id);
    while (s.step()) r.params.push_back({s.text(0), s.text(1), s.text(2)});
  }
  {
    Stmt s(db_, path_,
           "SELECT s.scope, s.name, s.value, s.unit, coalesce(d.description, '') FROM stats s "
           "LEFT JOIN stat_defs d ON d.name = s.name WHERE s.run_id = ? ORDER BY s.rowid");
    s.bind(1, id);
    while (s.step()) r.stats.push_back({s.text(0), s.text(1), s.real(2), s.text(3), s.text(4)});
  }
  if (schema_version() >= 2) {
    Stmt s(db_, path_,
           "SELECT pass, tile_x, tile_y, cycles, samples, dram_bytes FROM tile_stats WHERE run_id = ? "
           "ORDER BY pass, tile_y, tile_x");
    s.bind(1, id);
    while (s.step()) r.tiles.push_back({s.int64(0), s.int64(1), s.int64(2), s.real(3), s.real(4), s.real(5)});
  }
  return r;
}

std::vector<std::int64_t> ResultsDb::run_ids() const {
  std::vector<std::int64_t> ids;
  Stmt s(db_, path_, "SELECT id FROM runs ORDER BY id");
  while (s.step()) ids.push_back(s.int64(0));
  return ids;
}

std::optional<std::int64_t> ResultsDb::find_ok_run(const std::string& config_hash,
                                                   const std::string& trace_hash) const {
  Stmt s(db_, path_,
         "SELECT id FROM runs WHERE config_hash = ? AND trace_hash = ? AND status = 'ok' ORDER BY id LIMIT 1");
  s.bind(1, config_hash).bind(2, trace_hash);
  if (s.step()) return s.int64(0);
  return std::nullopt;
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
