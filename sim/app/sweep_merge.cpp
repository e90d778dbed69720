#include "app/sweep_merge.hpp"

#include <unistd.h>

#include <cstdint>
#include <filesystem>
#include <map>
#include <utility>

#include "analysis/results_db.hpp"
#include "analysis/sql.hpp"
#include "kernel/errors.hpp"

namespace tbdr {

namespace fs = std::filesystem;

namespace {

/// A shard attached to the output's connection as schema "shard" for the merge's lifetime.
class AttachedShard {
 public:
  AttachedShard(const SqlConnection& db, const std::string& shard) : db_(db) {
    SqlStatement attach(db, "ATTACH DATABASE ? AS shard");
    attach.bind(1, shard);
    attach.run();
  }
  ~AttachedShard() {
    if (attached_) {
      try {
        db_.exec("DETACH DATABASE shard");
      } catch (const SqlError&) {  // leaving by an exception already: keep that one
      }
    }
  }
  AttachedShard(const AttachedShard&) = delete;
  AttachedShard& operator=(const AttachedShard&) = delete;
  /// Detaches now (an error here is the merge's error).
  void detach() {
    attached_ = false;
    db_.exec("DETACH DATABASE shard");
  }

 private:
  const SqlConnection& db_;
  bool attached_ = true;
};

/// Copies the attached shard's runs (with their parameters, statistics and tiles) into the output
/// in the current transaction, leaving out duplicates.
MergeShardResult copy_shard_runs(const SqlConnection& db, const std::string& shard) {
  MergeShardResult res;
  res.shard = shard;
  // Finished runs already in the output, per (config_hash, trace_hash).
  std::map<std::pair<std::string, std::string>, std::int64_t> have_ok;
  {
    SqlStatement q(db, "SELECT config_hash, trace_hash, count(*) FROM main.runs WHERE status = 'ok' GROUP BY 1, 2");
    while (q.step()) have_ok[{q.text(0), q.text(1)}] = q.int64(2);
  }
  SqlStatement same(db,
                    "SELECT 1 FROM main.runs WHERE config_hash = ? AND trace_hash = ? AND status = ? AND "
                    "started_at = ? AND host = ? AND error = ? LIMIT 1");
  SqlStatement copy_run(db,
                        "INSERT INTO main.runs(started_at, finished_at, tool_version, host, command_line, "
                        "config_name, config_hash, trace_path, trace_hash, scene, technique, status, error) "
                        "SELECT started_at, finished_at, tool_version, host, command_line, config_name, config_hash, "
                        "trace_path, trace_hash, scene, technique, status, error FROM shard.runs WHERE id = ?");
  SqlStatement copy_params(db,
                           "INSERT INTO main.run_params(run_id, key, value, origin) SELECT ?, key, value, origin "
                           "FROM shard.run_params WHERE run_id = ? ORDER BY rowid");
  SqlStatement copy_stats(db,
                          "INSERT INTO main.stats(run_id, scope, name, value, unit) SELECT ?, scope, name, value, unit "
                          "FROM shard.stats WHERE run_id = ? ORDER BY rowid");
  SqlStatement copy_tiles(db,
                          "INSERT INTO main.tile_stats(run_id, pass, tile_x, tile_y, cycles, samples, dram_bytes) "
                          "SELECT ?, pass, tile_x, tile_y, cycles, samples, dram_bytes FROM shard.tile_stats "
                          "WHERE run_id = ? ORDER BY rowid");
  SqlStatement runs(db, "SELECT id, config_hash, trace_hash, status, started_at, host, error FROM shard.runs ORDER BY id");
  while (runs.step()) {
    const std::int64_t id = runs.int64(0);
    const std::pair<std::string, std::string> key{runs.text(1), runs.text(2)};
    const std::string status = runs.text(3);
    bool duplicate = false;
    if (status == "ok") {
      auto& n = have_ok[key];
      if (n > 0) {
        --n;
        duplicate = true;
      }
    } else {
      same.bind(1, key.first).bind(2, key.second).bind(3, status).bind(4, runs.text(4)).bind(5, runs.text(5));
      same.bind(6, runs.text(6));
      duplicate = same.step();
      same.reset();
    }
    if (duplicate) {
      ++res.duplicates;
      continue;
    }
    copy_run.bind(1, id);
    copy_run.run();
    const std::int64_t new_id = db.last_insert_rowid();
    for (SqlStatement* q : {&copy_params, &copy_stats, &copy_tiles}) {
      q->bind(1, new_id).bind(2, id);
      q->run();
    }
    ++res.copied;
  }
  db.exec(
      "INSERT INTO main.stat_defs(scope_kind, name, unit, description) SELECT scope_kind, name, unit, description "
      "FROM shard.stat_defs WHERE true ON CONFLICT(scope_kind, name) DO NOTHING");
  return res;
}

/// Removes a half-written database (and its -wal, -shm, -journal files) unless released.
class PartialFileGuard {
 public:
  explicit PartialFileGuard(std::string path) : path_(std::move(path)) {}
  ~PartialFileGuard() {
    if (path_.empty()) return;
    std::error_code ec;
    for (const char* suffix : {"", "-wal", "-shm", "-journal"}) fs::remove(path_ + suffix, ec);
  }
  PartialFileGuard(const PartialFileGuard&) = delete;
  PartialFileGuard& operator=(const PartialFileGuard&) = delete;
  void release() { path_.clear(); }

 private:
  std::string path_;
};

}  // namespace

std::vector<MergeShardResult> merge_databases(const std::string& out_path, const std::vector<std::string>& shards) {
  if (shards.empty()) throw InputError("merge", "no shard databases given");
  // Every input is checked before anything is written: a missing, foreign or too new shard, or an
  // output that cannot take runs, stops the merge with the output untouched (or not created).
  check_results_db_target(out_path);
  for (const auto& shard : shards) {
    std::error_code ec;
    if (!fs::is_regular_file(shard, ec)) throw InputError(shard, "no such shard database");
    if (fs::equivalent(shard, out_path, ec)) throw InputError(shard, "is the output database itself");
    { ResultsDb check(shard, ResultsDb::QueryOnly{}); }  // a tbdrsim database this version reads
  }
  // A new output is built beside its final name and renamed into place at the end, so a merge that
  // fails half-way (a shard unreadable after all, a full disk) leaves no output file at all. An
  // existing output takes each shard in one transaction (a shard is in it whole, or not at all;
  // merging again skips what is there).
  const bool fresh = !fs::exists(out_path);
  const std::string work_path = fresh ? out_path + ".merging-" + std::to_string(getpid()) : out_path;
  PartialFileGuard guard(fresh ? work_path : std::string());
  std::vector<MergeShardResult> results;
  {
    ResultsDb out(work_path);
    for (const auto& shard : shards) {
      { ResultsDb migrate(shard); }  // an older shard is migrated to this version's schema
      AttachedShard attached(out.sql(), shard);
      {
        SqlTransaction tx(out.sql());
        results.push_back(copy_shard_runs(out.sql(), shard));
        tx.commit();
      }
      attached.detach();
    }
    // Into one file before the rename: the write-ahead log is folded in and removed.
    if (fresh) out.sql().exec("PRAGMA journal_mode = DELETE");
  }
  if (fresh) {
    if (fs::exists(out_path)) throw InputError(out_path, "appeared while merging; the merge is left in " + work_path);
    fs::rename(work_path, out_path);
    guard.release();
  }
  return results;
}

}  // namespace tbdr
