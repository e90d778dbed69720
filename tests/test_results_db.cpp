// Results database: schema creation and migration, round trip, atomicity, concurrent writers.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>
#include <thread>

#include "analysis/results_db.hpp"
#include "analysis/sql.hpp"
#include "app/cli.hpp"
#include "kernel/errors.hpp"
#include "scratch_dir.hpp"

namespace tbdr {
namespace {

/// Removes this process's database folder when the tests end.
const testing_scratch::ScratchCleanup cleanup{"db"};

/// A path for a new database `name` in this process's own folder (test processes that run at the
/// same time, from this build or another checkout, never share a file).
std::string fresh_db(const std::string& name) {
  const auto dir = testing_scratch::scratch_root("db");
  std::filesystem::create_directories(dir);
  const auto path = (dir / name).string();
  for (const char* suffix : {"", "-wal", "-shm", "-journal"}) std::filesystem::remove(path + suffix);
  return path;
}

/// A run with `n_params` parameters and `n_stats` statistics, all recognisable by `tag`.
RunRecord make_run(const std::string& tag, int n_params = 20, int n_stats = 50) {
  RunRecord r;
  r.started_at = "2026-11-22T10:00:00Z";
  r.finished_at = "2026-11-22T10:00:01Z";
  r.tool_version = "test";
  r.host = "host";
  r.command_line = "tbdrsim run --tag " + tag;
  r.config_name = "cfg";
  r.config_hash = "hash-" + tag;
  r.trace_path = "t.trace";
  r.trace_hash = "trace-" + tag;
  r.scene = "atrium:1";
  r.technique = "plain_forward";
  for (int i = 0; i < n_params; ++i) r.params.push_back({"sec.key" + std::to_string(i), std::to_string(i), "default"});
  for (int i = 0; i < n_stats; ++i) {
    r.stats.push_back({"unit" + std::to_string(i % 5), "stat" + std::to_string(i), i * 1.5, "bytes", "desc " + std::to_string(i)});
  }
  r.tiles.push_back({0, 1, 2, 100.0, 1024.0, 64.0});
  return r;
}

/// The first column of the first row of `sql` on its own connection (-1 when there is no row).
int count(const std::string& path, const std::string& sql) {
  SqlConnection db(path);
  SqlStatement s(db, sql);
  return s.step() ? static_cast<int>(s.int64(0)) : -1;
}

/// The first column of the first row of `sql` as text.
std::string text_of(const ResultsDb& db, const std::string& sql) {
  SqlStatement s(db.sql(), sql);
  return s.step() ? s.text(0) : std::string("(no row)");
}

/// Ids of all runs, ascending.
std::vector<std::int64_t> run_ids(const ResultsDb& db) {
  std::vector<std::int64_t> ids;
  SqlStatement s(db.sql(), "SELECT id FROM runs ORDER BY id");
  while (s.step()) ids.push_back(s.int64(0));
  return ids;
}

/// A run read back (params and stats in insertion order, tiles in raster order); nullopt when absent.
std::optional<RunRecord> read_run(const ResultsDb& db, std::int64_t id) {
  RunRecord r;
  {
    SqlStatement s(db.sql(),
                   "SELECT started_at, finished_at, tool_version, host, command_line, config_name, config_hash, "
                   "trace_path, trace_hash, scene, technique, status, error FROM runs WHERE id = ?");
    s.bind(1, id);
    if (!s.step()) return std::nullopt;
    std::string* fields[] = {&r.started_at,  &r.finished_at, &r.tool_version, &r.host,      &r.command_line,
                             &r.config_name, &r.config_hash, &r.trace_path,   &r.trace_hash, &r.scene,
                             &r.technique,   &r.status,      &r.error};
    for (int col = 0; col < 13; ++col) *fields[col] = s.text(col);
  }
  {
    SqlStatement s(db.sql(), "SELECT key, value, origin FROM run_params WHERE run_id = ? ORDER BY rowid");
    s.bind(1, id);
    while (s.step()) r.params.push_back({s.text(0), s.text(1), s.text(2)});
  }
  r.stats = db.run_stats(id);
  if (db.schema_version() >= 2) {
    SqlStatement s(db.sql(),
                   "SELECT pass, tile_x, tile_y, cycles, samples, dram_bytes FROM tile_stats WHERE run_id = ? "
                   "ORDER BY pass, tile_y, tile_x");
    s.bind(1, id);
    while (s.step()) r.tiles.push_back({s.int64(0), s.int64(1), s.int64(2), s.real(3), s.real(4), s.real(5)});
  }
  return r;
}

TEST(ResultsDb, CreatesCurrentSchemaInWalMode) {
  const auto path = fresh_db("create.db");
  ResultsDb db(path);
  EXPECT_EQ(db.schema_version(), ResultsDb::kSchemaVersion);
  EXPECT_EQ(count(path, "SELECT count(*) FROM sqlite_master WHERE name IN ('runs','run_params','stats','stat_defs','tile_stats')"), 5);
  EXPECT_EQ(text_of(db, "PRAGMA journal_mode"), "wal");
}

TEST(ResultsDb, RoundTripIsEqual) {
  const auto path = fresh_db("roundtrip.db");
  ResultsDb db(path);
  const RunRecord w = make_run("a");
  const auto id = db.write_run(w);
  const auto r = read_run(db, id);
  ASSERT_TRUE(r.has_value());
  EXPECT_EQ(r->config_hash, w.config_hash);
  EXPECT_EQ(r->command_line, w.command_line);
  EXPECT_EQ(r->status, "ok");
  EXPECT_EQ(r->params, w.params);
  ASSERT_EQ(r->stats.size(), w.stats.size());
  for (std::size_t i = 0; i < w.stats.size(); ++i) {
    EXPECT_EQ(r->stats[i].scope, w.stats[i].scope);
    EXPECT_EQ(r->stats[i].name, w.stats[i].name);
    EXPECT_DOUBLE_EQ(r->stats[i].value, w.stats[i].value);
    EXPECT_EQ(r->stats[i].unit, w.stats[i].unit);
    EXPECT_EQ(r->stats[i].description, w.stats[i].description);
  }
  EXPECT_EQ(r->tiles, w.tiles);
  EXPECT_FALSE(read_run(db, id + 100).has_value());
  // The resolved configuration is readable with a plain SELECT.
  EXPECT_EQ(count(path, "SELECT value FROM run_params WHERE run_id = 1 AND key = 'sec.key7'"), 7);
}

TEST(ResultsDb, MigratesAnOlderSchemaKeepingRuns) {
  const auto path = fresh_db("migrate.db");
  {
    ResultsDb v1(path, 1);
    EXPECT_EQ(v1.schema_version(), 1);
    RunRecord r = make_run("old");
    r.tiles.clear();  // v1 has no tile table
    v1.write_run(r);
    EXPECT_EQ(count(path, "SELECT count(*) FROM sqlite_master WHERE name = 'tile_stats'"), 0);
  }
  {  // A version-3 database (before the index of parameters by key) reads as it is, unchanged.
    ResultsDb v3(path, 3);
    ResultsDb ro(path, ResultsDb::QueryOnly{});
    EXPECT_EQ(ro.schema_version(), 3);
    EXPECT_EQ(count(path, "SELECT count(*) FROM v_param WHERE key = 'sec.key7'"), 1);
  }
  ResultsDb now(path);
  EXPECT_EQ(now.schema_version(), ResultsDb::kSchemaVersion);
  EXPECT_EQ(count(path, "SELECT count(*) FROM sqlite_master WHERE name = 'tile_stats'"), 1);
  EXPECT_EQ(count(path, "SELECT count(*) FROM sqlite_master WHERE name = 'run_params_by_key'"), 1);
  ASSERT_EQ(run_ids(now).size(), 1u);
  EXPECT_EQ(read_run(now, run_ids(now)[0])->config_hash, "hash-old");
  // The run written at v1 keeps its descriptions (by name, as they were written).
  const RunRecord old = make_run("old");
  const std::vector<StatRecord> old_stats = now.run_stats(run_ids(now)[0]);
  ASSERT_EQ(old_stats.size(), old.stats.size());
  for (std::size_t i = 0; i < old_stats.size(); ++i) EXPECT_EQ(old_stats[i].description, old.stats[i].description);
  now.write_run(make_run("new"));
  EXPECT_EQ(run_ids(now).size(), 2u);
}

// One name can mean different things in different units (a cache's fill_bytes, the ROP's): each
// is described as its own unit declares it, per scope kind, and a pass's statistics share their
// descriptions with every other pass's.
TEST(ResultsDb, DescribesAStatisticByItsScopeKindAndName) {
  EXPECT_EQ(stat_scope_kind("pass3.lighting/rop"), "pass/rop");
  EXPECT_EQ(stat_scope_kind("pass12.final/dram.color"), "pass/dram.color");
  EXPECT_EQ(stat_scope_kind("dispatch2.cull/compute"), "dispatch/compute");
  EXPECT_EQ(stat_scope_kind("frame/rop"), "frame/rop");
  EXPECT_EQ(stat_scope_kind("mem/cache.slc.class.color"), "mem/cache.slc.class.color");
  EXPECT_EQ(stat_scope_kind("mem"), "mem");
  const auto path = fresh_db("kinds.db");
  ResultsDb db(path);
  RunRecord r = make_run("kinds", 1, 0);
  r.stats = {{"pass0.a/rop", "fill_bytes", 1, "bytes", "ROP fills"},
             {"mem/cache.slc", "fill_bytes", 2, "bytes", "SLC fills"},
             {"frame/dram", "read_bytes", 3, "bytes", "requested"},
             {"mem/dram", "read_bytes", 4, "bytes", "served"},
             {"pass1.b/rop", "fill_bytes", 5, "bytes", "ROP fills"}};
  const auto id = db.write_run(r);
  const std::vector<StatRecord> back = db.run_stats(id);
  ASSERT_EQ(back.size(), r.stats.size());
  for (std::size_t i = 0; i < back.size(); ++i) {
    EXPECT_EQ(back[i].scope, r.stats[i].scope);
    EXPECT_EQ(back[i].description, r.stats[i].description) << r.stats[i].scope << "/" << r.stats[i].name;
  }
  // Four descriptions: the two passes' ROP share one.
  EXPECT_EQ(count(path, "SELECT count(*) FROM stat_defs"), 4);
}

TEST(ResultsDb, RefusesNewerSchemaAndForeignFiles) {
  const auto path = fresh_db("newer.db");
  { ResultsDb db(path); db.sql().exec("PRAGMA user_version = 99"); }
  try {
    ResultsDb db(path);
    FAIL() << "newer schema accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(path + ": results database schema version 99 is newer"), std::string::npos) << e.what();
  }
  const auto foreign = fresh_db("foreign.db");
  SqlConnection(foreign).exec("CREATE TABLE people(name TEXT)");
  EXPECT_THROW(ResultsDb db(foreign), InputError);
  const auto text = fresh_db("text.db");
  std::ofstream(text) << "this is not a database, just text that is long enough to fill a header page....\n";
  try {
    ResultsDb db(text);
    FAIL() << "text file accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(text), std::string::npos);
  }
}

TEST(ResultsDb, KilledWriterLeavesOnlyWholeRuns) {
  const auto path = fresh_db("atomic.db");
  { ResultsDb db(path); }
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    try {
      ResultsDb db(path);
      for (int i = 0;; ++i) db.write_run(make_run("k" + std::to_string(i), 200, 2000));
    } catch (...) {
    }
    _exit(0);
  }
  // Let it write a few runs (however long that takes: it writes until killed), then kill it without
  // warning, most likely inside a transaction (it writes all the time). Wherever the kill lands,
  // only whole runs may be left.
  int status = 0;
  while (count(path, "SELECT count(*) FROM runs") < 3) {
    ASSERT_EQ(waitpid(child, &status, WNOHANG), 0) << "the writer ended by itself";
    std::this_thread::yield();
  }
  kill(child, SIGKILL);
  waitpid(child, &status, 0);
  ASSERT_TRUE(WIFSIGNALED(status));

  ResultsDb db(path);
  EXPECT_EQ(text_of(db, "PRAGMA integrity_check"), "ok");
  const auto ids = run_ids(db);
  EXPECT_GE(ids.size(), 3u);
  for (auto id : ids) {
    const auto r = read_run(db, id);
    EXPECT_EQ(r->params.size(), 200u) << "run " << id << " is partial";
    EXPECT_EQ(r->stats.size(), 2000u) << "run " << id << " is partial";
  }
  EXPECT_EQ(count(path, "SELECT count(*) FROM stats WHERE run_id NOT IN (SELECT id FROM runs)"), 0);
}

/// Forks `n` processes that each open `path` as a results database, and returns how many of them
/// failed (each failure's reason is on stderr).
int failed_openers(const std::string& path, int n) {
  std::vector<pid_t> kids;
  for (int w = 0; w < n; ++w) {
    const pid_t pid = fork();
    if (pid == 0) {
      int rc = 0;
      try {
        ResultsDb db(path);
      } catch (const std::exception& e) {
        std::fprintf(stderr, "opener %d: %s\n", w, e.what());
        rc = 1;
      }
      _exit(rc);
    }
    if (pid > 0) kids.push_back(pid);
  }
  int failed = n - static_cast<int>(kids.size());
  for (pid_t k : kids) {
    int status = 0;
    waitpid(k, &status, 0);
    if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) ++failed;
  }
  return failed;
}

// Processes that open a database which does not exist yet race on creating it: one commits the
// schema while the others check what the file is. Each round is a new file; 4 openers x 30
// rounds = 120 opens, each of which must succeed. (Before the identity check read the id and
// the schema in one transaction, a few opens per run saw "application_id 0, 11 schema objects"
// and refused the file as not a tbdrsim database.)
TEST(ResultsDb, ProcessesOpeningANewDatabaseTogetherAllSucceed) {
  constexpr int kOpeners = 4;
  constexpr int kRounds = 30;
  int failed = 0;
  for (int round = 0; round < kRounds; ++round) {
    const auto path = fresh_db("new_together.db");
    failed += failed_openers(path, kOpeners);
    EXPECT_EQ(count(path, "PRAGMA user_version"), ResultsDb::kSchemaVersion);
  }
  EXPECT_EQ(failed, 0) << "of " << kOpeners * kRounds << " opens";
}

TEST(ResultsDb, TwoConcurrentWritersLoseNothing) {
  const auto path = fresh_db("concurrent.db");
  constexpr int kRunsEach = 25;
  std::vector<pid_t> kids;
  for (int w = 0; w < 2; ++w) {
    const pid_t pid = fork();
    ASSERT_GE(pid, 0);
    if (pid == 0) {
      int rc = 0;
      try {
        ResultsDb db(path);
        for (int i = 0; i < kRunsEach; ++i) db.write_run(make_run("w" + std::to_string(w) + "-" + std::to_string(i)));
      } catch (const std::exception& e) {
        std::fprintf(stderr, "writer %d: %s\n", w, e.what());  // the reason, in the test's output
        rc = 1;
      } catch (...) {
        rc = 1;
      }
      _exit(rc);
    }
    kids.push_back(pid);
  }
  for (pid_t k : kids) {
    int status = 0;
    waitpid(k, &status, 0);
    EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0);
  }
  EXPECT_EQ(count(path, "SELECT count(*) FROM runs"), 2 * kRunsEach);
  EXPECT_EQ(count(path, "SELECT count(DISTINCT config_hash) FROM runs"), 2 * kRunsEach);
  EXPECT_EQ(count(path, "SELECT count(*) FROM stats"), 2 * kRunsEach * 50);
}

// Every command that writes a database leaves it alone on disk: the write-ahead log checkpointed
// into it and no -wal or -shm file beside it (a user who copies the .db file copies every run).
// The study also runs the plot scripts, whose read-only connections would leave both files.
TEST(ResultsDb, CommandsLeaveNoWalFilesBehind) {
  namespace fs = std::filesystem;
  const fs::path dir = testing_scratch::scratch_dir("db", "clean_close");
  auto alone = [](const fs::path& db) {
    EXPECT_TRUE(fs::exists(db)) << db;
    EXPECT_FALSE(fs::exists(db.string() + "-wal")) << db;
    EXPECT_FALSE(fs::exists(db.string() + "-shm")) << db;
  };
  std::ostringstream out, err;
  const std::string trace = (dir / "t.trace").string();
  ASSERT_EQ(cli_main({"trace", "--resolution", "64x36", "--scene", "atrium:1", "--lights", "4", "--out", trace}, out, err), 0)
      << err.str();
  ASSERT_EQ(cli_main({"run", "--trace", trace, "--db", (dir / "run.db").string(), "--quiet"}, out, err), 0) << err.str();
  alone(dir / "run.db");
  ASSERT_EQ(cli_main({"study", "--out", (dir / "study").string(), "--technique", "plain_forward", "--lights", "4",
                      "--resolution", "64x36", "--scene", "atrium:1", "--images", "none", "--jobs", "1"},
                     out, err),
            0)
      << err.str();
  alone(dir / "study" / "study.db");
  {
    std::ofstream f(dir / "s.ini");
    f << "[sweep]\ntrace = " << trace << "\n[vary]\ntiling.tile_width = 16, 64\n";  // not the run's 32
  }
  ASSERT_EQ(cli_main({"sweep", (dir / "s.ini").string(), "--db", (dir / "sweep.db").string(), "-j", "1", "--progress",
                      "none", "--tbdrsim", TBDRSIM_BINARY},
                     out, err),
            0)
      << err.str();
  alone(dir / "sweep.db");
  ASSERT_EQ(cli_main({"merge", (dir / "merged.db").string(), (dir / "run.db").string(), (dir / "sweep.db").string()}, out, err),
            0)
      << err.str();
  alone(dir / "merged.db");
  alone(dir / "run.db");
  alone(dir / "sweep.db");
  EXPECT_EQ(count((dir / "merged.db").string(), "SELECT count(*) FROM runs"), 3);  // 1 run + 2 sweep points
}

}  // namespace
}  // namespace tbdr
