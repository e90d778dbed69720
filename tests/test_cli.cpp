// The command line: usage errors, exit codes, the params command, and bad results databases
// refused before any work (run, merge).
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "app/cli.hpp"
#include "db_query.hpp"
#include "scratch_dir.hpp"

namespace tbdr {
namespace {

struct CliResult {
  int code;
  std::string out;
  std::string err;
};

CliResult run_cli(const std::vector<std::string>& args) {
  std::ostringstream out, err;
  const int code = cli_main(args, out, err);
  return {code, out.str(), err.str()};
}

TEST(Cli, HelpAndUnknownCommandOrOption) {
  const auto help = run_cli({"--help"});
  EXPECT_EQ(help.code, 0);
  EXPECT_NE(help.out.find("usage: tbdrsim <command>"), std::string::npos);
  EXPECT_NE(help.out.find("params"), std::string::npos);
  const auto none = run_cli({});
  EXPECT_EQ(none.code, 2);
  const auto bad = run_cli({"frobnicate"});
  EXPECT_EQ(bad.code, 2);
  EXPECT_NE(bad.err.find("unknown command 'frobnicate'"), std::string::npos);
  EXPECT_NE(bad.err.find("usage:"), std::string::npos);
  const auto opt = run_cli({"params", "--colour"});
  EXPECT_EQ(opt.code, 2);
  EXPECT_NE(opt.err.find("colour"), std::string::npos);
  EXPECT_NE(opt.err.find("usage: tbdrsim params"), std::string::npos);
  EXPECT_EQ(run_cli({"params", "--help"}).code, 0);
}

TEST(Cli, ParamsListsEveryParameterWithDocAndRange) {
  const auto r = run_cli({"params"});
  ASSERT_EQ(r.code, 0) << r.err;
  for (const char* key : {"isp.samples_per_clock", "tiling.tile_width", "dram.bandwidth_gbps",
                          "energy.dram_activate_precharge_nj", "cache.slc.size_bytes", "pls.tile_buffer_bits_per_pixel"}) {
    EXPECT_NE(r.out.find(key), std::string::npos) << key;
  }
  EXPECT_NE(r.out.find("[1, 1024]"), std::string::npos);
  const auto md = run_cli({"params", "--format", "markdown"});
  EXPECT_EQ(md.code, 0);
  EXPECT_EQ(md.out.rfind("| parameter | default | unit | range | description | source |", 0), 0u);
}

TEST(Cli, ParamsResolvedShowsOrigins) {
  const auto dir = std::filesystem::temp_directory_path() / "tbdrsim_test_cli";
  std::filesystem::create_directories(dir);
  const auto cfg = (dir / "mine.ini").string();
  std::ofstream(cfg) << "[usc]\ncount = 6\n";
  const auto r = run_cli({"params", "--config", cfg, "--set", "isp.tag_buffers=4"});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find(cfg + ":2"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("--set isp.tag_buffers=4"), std::string::npos);
  EXPECT_NE(r.out.find("configuration 'mine'"), std::string::npos);
}

TEST(Cli, BadConfigExitsTwoWithFileLine) {
  const auto dir = std::filesystem::temp_directory_path() / "tbdrsim_test_cli";
  std::filesystem::create_directories(dir);
  const auto cfg = (dir / "typo.ini").string();
  std::ofstream(cfg) << "[tiling]\ntile_widht = 16\n";
  const auto r = run_cli({"params", "--config", cfg});
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find(cfg + ":2"), std::string::npos) << r.err;
  const auto s = run_cli({"params", "--set", "isp.samples_per_clock=-3"});
  EXPECT_EQ(s.code, 2);
  EXPECT_NE(s.err.find("[1, 1024]"), std::string::npos) << s.err;
}

const testing_scratch::ScratchCleanup cli_scratch_cleanup{"cli"};

/// A tiny trace (160x90, atrium:1, 16 lights) in `dir`, made by `tbdrsim trace`.
std::string tiny_trace(const std::filesystem::path& dir) {
  const std::string path = (dir / "tiny.trace").string();
  const auto r = run_cli({"trace", "--resolution", "160x90", "--scene", "atrium:1", "--lights", "16", "--out", path});
  EXPECT_EQ(r.code, 0) << r.err;
  return path;
}

/// The names in a folder, sorted (what a command left behind).
std::vector<std::string> listing(const std::filesystem::path& dir) {
  std::vector<std::string> names;
  for (const auto& e : std::filesystem::directory_iterator(dir)) names.push_back(e.path().filename().string());
  std::sort(names.begin(), names.end());
  return names;
}

// `run` checks --db before reading the trace and simulating: a database in a folder that does not
// exist, a file that is not a database, a folder. Each exits 2 naming the file, and the images
// folder (made before the simulation, written after it) is never created.
TEST(Cli, RunRefusesABadDatabaseBeforeSimulating) {
  const auto dir = testing_scratch::scratch_dir("cli", "run_bad_db");
  const std::string trace = tiny_trace(dir);
  std::ofstream(dir / "notes.txt") << "not a database, just text that is long enough to have a header\n";
  std::filesystem::create_directories(dir / "a_folder.db");
  const std::string bad[] = {(dir / "missing" / "r.db").string(), (dir / "notes.txt").string(),
                             (dir / "a_folder.db").string()};
  for (const auto& db : bad) {
    const auto images = dir / "images";
    const auto r = run_cli({"run", "--trace", trace, "--db", db, "--images", images.string(), "--quiet"});
    EXPECT_EQ(r.code, 2) << db;
    EXPECT_NE(r.err.find(db), std::string::npos) << r.err;
    EXPECT_FALSE(std::filesystem::exists(images)) << db << ": the run went ahead before the database was checked";
  }
  EXPECT_FALSE(std::filesystem::exists(dir / "missing"));
}

// `merge` checks every shard before writing: with a shard that is not a database, or one that is
// missing, it exits 2 naming that shard, and a new output is not created, an existing one keeps
// its runs (1, from one earlier merge of the good shard, which holds 1 run).
TEST(Cli, MergeValidatesEveryShardBeforeWriting) {
  const auto dir = testing_scratch::scratch_dir("cli", "merge_bad_shard");
  const std::string trace = tiny_trace(dir);
  const std::string good = (dir / "good.db").string();
  ASSERT_EQ(run_cli({"run", "--trace", trace, "--db", good, "--quiet"}).code, 0);
  const std::string junk = (dir / "junk.db").string();
  std::ofstream(junk) << "not a database, just text that is long enough to have a header\n";
  const std::string missing = (dir / "missing.db").string();

  const std::string fresh = (dir / "fresh_out.db").string();
  for (const auto& bad : {junk, missing}) {
    const auto before = listing(dir);
    const auto r = run_cli({"merge", fresh, good, bad});
    EXPECT_EQ(r.code, 2) << r.out;
    EXPECT_NE(r.err.find(bad), std::string::npos) << r.err;
    EXPECT_EQ(listing(dir), before) << "merge wrote something before failing on " << bad;
  }

  const std::string kept = (dir / "kept_out.db").string();
  ASSERT_EQ(run_cli({"merge", kept, good}).code, 0);
  for (const auto& bad : {junk, missing}) {
    const auto r = run_cli({"merge", kept, good, bad});
    EXPECT_EQ(r.code, 2);
    EXPECT_EQ(r.out.find("copied"), std::string::npos) << "nothing may be reported copied: " << r.out;
    EXPECT_EQ(testing_support::query_number(kept, "SELECT count(*) FROM runs"), 1.0);
  }
}

}  // namespace
}  // namespace tbdr
