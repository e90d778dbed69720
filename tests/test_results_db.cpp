// Results database: schema creation and migration, round trip, atomicity, concurrent writers.
#include <gtest/gtest.h>
#include <signal.h>
#include <sqlite3.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <thread>

#include "kernel/errors.hpp"
#include "analysis/results_db.hpp"

namespace tbdr {
namespace {

std::string fresh_db(const std::string& name) {
  const auto dir = std::filesystem::temp_directory_path() / "tbdrsim_test_db";
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

int count(const std::string& path, const std::string& sql) {
  sqlite3* db = nullptr;
  sqlite3_open(path.c_str(), &db);
  sqlite3_stmt* s = nullptr;
  sqlite3_prepare_v2(db, sql.c_str(), -1, &s, nullptr);
  int v = -1;
  if (sqlite3_step(s) == SQLITE_ROW) v = sqlite3_column_int(s, 0);
  sqlite3_finalize(s);
  sqlite3_close(db);
  return v;
}

TEST(ResultsDb, CreatesCurrentSchemaInWalMode) {
  const auto path = fresh_db("create.db");
  ResultsDb db(path);
  EXPECT_EQ(db.schema_version(), ResultsDb::kSchemaVersion);
  EXPECT_EQ(count(path, "SELECT count(*) FROM sqlite_master WHERE name IN ('runs','run_params','stats','stat_defs','tile_stats')"), 5);
  sqlite3_stmt* s = nullptr;
  sqlite3_prepare_v2(db.handle(), "PRAGMA journal_mode", -1, &s, nullptr);
  ASSERT_EQ(sqlite3_step(s), SQLITE_ROW);
  EXPECT_STREQ(reinterpret_cast<const char*>(sqlite3_column_text(s, 0)), "wal");
  sqlite3_finalize(s);
}

TEST(ResultsDb, RoundTripIsEqual) {
  const auto path = fresh_db("roundtrip.db");
  ResultsDb db(path);
  const RunRecord w = make_run("a");
  const auto id = db.write_run(w);
  const auto r = db.read_run(id);
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
  EXPECT_EQ(db.find_ok_run(w.config_hash, w.trace_hash), id);
  EXPECT_FALSE(db.find_ok_run(w.config_hash, "other").has_value());
  EXPECT_FALSE(db.read_run(id + 100).has_value());
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
  ResultsDb now(path);
  EXPECT_EQ(now.schema_version(), ResultsDb::kSchemaVersion);
  EXPECT_EQ(count(path, "SELECT count(*) FROM sqlite_master WHERE name = 'tile_stats'"), 1);
  ASSERT_EQ(now.run_ids().size(), 1u);
  EXPECT_EQ(now.read_run(now.run_ids()[0])->config_hash, "hash-old");
  now.write_run(make_run("new"));
  EXPECT_EQ(now.run_ids().size(), 2u);
}

TEST(ResultsDb, RefusesNewerSchemaAndForeignFiles) {
  const auto path = fresh_db("newer.db");
  { ResultsDb db(path); db.exec("PRAGMA user_version = 99"); }
  try {
    ResultsDb db(path);
    FAIL() << "newer schema accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(path + ": results database schema version 99 is newer"), std::string::npos) << e.what();
  }
  const auto foreign = fresh_db("foreign.db");
  {
    sqlite3* db = nullptr;
    sqlite3_open(foreign.c_str(), &db);
    sqlite3_exec(db, "CREATE TABLE people(name TEXT)", nullptr, nullptr, nullptr);
    sqlite3_close(db);
  }
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
  // Let it write a few runs, then kill it without warning, most likely inside a transaction.
  for (int i = 0; i < 400 && count(path, "SELECT count(*) FROM runs") < 3; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(7));
  kill(child, SIGKILL);
  int status = 0;
  waitpid(child, &status, 0);
  ASSERT_TRUE(WIFSIGNALED(status));

  ResultsDb db(path);
  sqlite3_stmt* s = nullptr;
  sqlite3_prepare_v2(db.handle(), "PRAGMA integrity_check", -1, &s, nullptr);
  ASSERT_EQ(sqlite3_step(s), SQLITE_ROW);
  EXPECT_STREQ(reinterpret_cast<const char*>(sqlite3_column_text(s, 0)), "ok");
  sqlite3_finalize(s);
  const auto ids = db.run_ids();
  EXPECT_GE(ids.size(), 3u);
  for (auto id : ids) {
    const auto r = db.read_run(id);
    EXPECT_EQ(r->params.size(), 200u) << "run " << id << " is partial";
    EXPECT_EQ(r->stats.size(), 2000u) << "run " << id << " is partial";
  }
  EXPECT_EQ(count(path, "SELECT count(*) FROM stats WHERE run_id NOT IN (SELECT id FROM runs)"), 0);
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

}  // namespace
}  // namespace tbdr
