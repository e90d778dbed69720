// The command line: usage errors, exit codes, strict arguments (stray positionals, unknown --by and
// --metric with suggestions), config names looked up in the checkout, the params command, and bad
// results databases refused before any work (run, merge).
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "cli_run.hpp"
#include "analysis/results_db.hpp"
#include "analysis/sql.hpp"
#include "app/cli.hpp"
#include "app/commands.hpp"
#include "db_query.hpp"
#include "scratch_dir.hpp"

namespace tbdr {
namespace {

using testing_support::CliResult;
using testing_support::run_cli;

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
  for (const char* key : {"isp.samples_per_clock", "tiling.tile_width", "dram.transfers_per_clock",
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

// A merge that fails after its checks (a shard whose tables are broken: it passes the identity and
// version checks, then its copy fails) leaves no output file, not even a temporary one.
TEST(Cli, FailedMergeLeavesNoOutputFile) {
  const auto dir = testing_scratch::scratch_dir("cli", "merge_fails_late");
  const std::string trace = tiny_trace(dir);
  const std::string good = (dir / "good.db").string();
  const std::string broken = (dir / "broken.db").string();
  ASSERT_EQ(run_cli({"run", "--trace", trace, "--db", good, "--quiet"}).code, 0);
  ASSERT_EQ(run_cli({"run", "--trace", trace, "--db", broken, "--quiet"}).code, 0);
  { ResultsDb b(broken); b.sql().exec("DROP TABLE tile_stats"); }
  const auto before = listing(dir);
  const std::string out = (dir / "all.db").string();
  const auto r = run_cli({"merge", out, good, broken});
  EXPECT_NE(r.code, 0) << r.out;
  EXPECT_NE(r.err.find("tile_stats"), std::string::npos) << r.err;
  EXPECT_EQ(listing(dir), before) << "a failed merge left files behind";
  // The same merge without the broken shard writes the output whole: 1 run (good.db holds 1), and
  // nothing else beside it.
  ASSERT_EQ(run_cli({"merge", out, good}).code, 0);
  EXPECT_EQ(testing_support::query_number(out, "SELECT count(*) FROM runs"), 1.0);
  auto after = listing(dir);
  std::erase_if(after, [](const std::string& n) { return n.find(".merging-") != std::string::npos; });
  EXPECT_EQ(after.size(), before.size() + 1);
}

// Every command refuses an argument it does not take, naming it, exit 2, before doing any work.
TEST(Cli, StrayPositionalArgumentsAreRefusedByName) {
  const auto dir = testing_scratch::scratch_dir("cli", "stray");
  const std::string db = (dir / "r.db").string();
  const std::vector<std::vector<std::string>> lines = {
      {"params", "--set", "isp.tag_buffers=4", "tile", "stray"},  // (params takes one PATTERN)
      {"run", "--trace", (dir / "none.trace").string(), "--db", db, "stray"},
      {"report", "--db", db, "--format", "csv", "stray"},
      {"trace", "--out", (dir / "t.trace").string(), "stray"},
      {"scene", "info", "atrium:1", "stray"},
      {"study", "--out", (dir / "study").string(), "stray"},
      {"sweep", "tile_size", "stray", "--dry-run", "--db", db},
      {"validate", "stray"},
  };
  for (const auto& args : lines) {
    const auto r = run_cli(args);
    EXPECT_EQ(r.code, 2) << args.front();
    EXPECT_NE(r.err.find("unexpected argument 'stray'"), std::string::npos) << args.front() << ": " << r.err;
    EXPECT_NE(r.err.find("tbdrsim " + args.front() + " --help"), std::string::npos) << r.err;
  }
  const auto scene = run_cli({"scene", "info", "atrium:1", "stray"});
  EXPECT_NE(scene.err.find("takes 2 argument(s)"), std::string::npos) << scene.err;
  EXPECT_EQ(listing(dir), std::vector<std::string>{}) << "a refused command wrote something";
}

// --by and --metric take several values (space- or comma-separated, or repeated); an unknown one
// is refused with the closest names the database has.
TEST(Cli, ReportByTakesSeveralKeysAndSuggestsUnknownOnes) {
  const auto dir = testing_scratch::scratch_dir("cli", "report_by");
  const std::string trace = tiny_trace(dir);
  const std::string db = (dir / "r.db").string();
  ASSERT_EQ(run_cli({"run", "--trace", trace, "--db", db, "--quiet"}).code, 0);
  ASSERT_EQ(run_cli({"run", "--trace", trace, "--db", db, "--quiet", "--set", "tiling.tile_width=16",
                     "--set", "tiling.tile_height=16"}).code, 0);
  // Two runs, tile widths 32 (the default) and 16: grouped by technique alone they are 1 row, by
  // technique and tile width 2 rows, whichever way the two keys are written.
  const auto one = run_cli({"report", "--db", db, "--by", "technique", "--metric", "cycles", "--format", "csv"});
  ASSERT_EQ(one.code, 0) << one.err;
  EXPECT_EQ(one.out.rfind("technique,", 0), 0u) << one.out;
  EXPECT_EQ(one.out.find("tiling.tile_width"), std::string::npos) << one.out;
  EXPECT_NE(one.out.find("\nplain_forward,2,"), std::string::npos) << "one group of 2 runs: " << one.out;
  for (const auto& by : std::vector<std::vector<std::string>>{{"--by", "technique", "tiling.tile_width"},
                                                             {"--by", "technique,tiling.tile_width"},
                                                             {"--by", "technique", "--by", "tiling.tile_width"}}) {
    std::vector<std::string> args = {"report", "--db", db, "--metric", "cycles", "--format", "csv"};
    args.insert(args.end(), by.begin(), by.end());
    const auto r = run_cli(args);
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_EQ(r.out.rfind("technique,tiling.tile_width,", 0), 0u) << r.out;
    EXPECT_NE(r.out.find("\nplain_forward,16,1,"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("\nplain_forward,32,1,"), std::string::npos) << r.out;
  }
  const auto typo = run_cli({"report", "--db", db, "--by", "technique", "tiling.tile_widht"});
  EXPECT_EQ(typo.code, 2);
  EXPECT_NE(typo.err.find("--by tiling.tile_widht"), std::string::npos) << typo.err;
  EXPECT_NE(typo.err.find("did you mean 'tiling.tile_width'"), std::string::npos) << typo.err;
  const auto tail = run_cli({"report", "--db", db, "--by", "tile_width"});
  EXPECT_EQ(tail.code, 2);
  EXPECT_NE(tail.err.find("'tiling.tile_width'"), std::string::npos) << tail.err;
  const auto metric = run_cli({"report", "--db", db, "--metric", "frame_time_sm"});
  EXPECT_EQ(metric.code, 2);
  EXPECT_NE(metric.err.find("did you mean 'frame_time_ms'"), std::string::npos) << metric.err;
  const auto far = run_cli({"report", "--db", db, "--by", "zzzzzzzz"});
  EXPECT_EQ(far.code, 2);
  EXPECT_EQ(far.err.find("did you mean"), std::string::npos) << "nothing is close to zzzzzzzz: " << far.err;
  const auto empty = run_cli({"report", "--db", db, "--by", "technique,"});
  EXPECT_EQ(empty.code, 2);
  EXPECT_NE(empty.err.find("empty name"), std::string::npos) << empty.err;
}

TEST(Cli, DidYouMeanPicksTheClosestNames) {
  const std::vector<std::string> names = {"technique", "scene", "config", "lights", "tiling.tile_width",
                                          "tiling.tile_height"};
  EXPECT_EQ(did_you_mean("tecnique", names), "did you mean 'technique'?");
  EXPECT_EQ(did_you_mean("tile_width", names), "did you mean 'tiling.tile_width'?");
  // "tiling.tile_hieght" is 1 edit (a swap) from _height and 4 from _width: closest first.
  EXPECT_EQ(did_you_mean("tiling.tile_hieght", names), "did you mean 'tiling.tile_height' or 'tiling.tile_width'?");
  EXPECT_EQ(did_you_mean("series6xt_gx6540", {"series6xt_gx6250", "series6xt_gx6450"}),
            "did you mean 'series6xt_gx6450' or 'series6xt_gx6250'?");
  EXPECT_EQ(did_you_mean("frobnicate", names), "");
  EXPECT_EQ(did_you_mean("scene", names), "") << "an exact name is not a suggestion";
}

/// Runs `body` with the working folder set to `dir`, restoring it afterwards.
template <typename F>
void in_folder(const std::filesystem::path& dir, F body) {
  const auto before = std::filesystem::current_path();
  std::filesystem::current_path(dir);
  body();
  std::filesystem::current_path(before);
}

// A config named on the command line is found from any folder: as given, else the same relative
// path in the checkout, else a bare preset name in the checkout's configs/; a name found nowhere is
// an error listing where it looked, with a suggestion.
TEST(Cli, ConfigNamesAreFoundFromAnyFolder) {
  const auto dir = testing_scratch::scratch_dir("cli", "elsewhere");
  std::filesystem::create_directories(dir / "configs");
  std::ofstream(dir / "configs" / "mobile_16x16_lpddr4x.ini") << "[usc]\ncount = 3\n";
  const std::string checkout(TBDRSIM_SOURCE_DIR);
  in_folder(dir, [&] {
    // A bare preset name, with or without .ini: the checkout's configs/ (the working folder has no
    // file of that name).
    for (const char* name : {"series6xt_gx6250", "series6xt_gx6250.ini"}) {
      const auto r = run_cli({"params", "--config", name});
      ASSERT_EQ(r.code, 0) << r.err;
      EXPECT_NE(r.out.find(checkout + "/configs/series6xt_gx6250.ini:"), std::string::npos) << r.out;
    }
    // The working folder's own configs/mobile_16x16_lpddr4x.ini wins over the checkout's.
    const auto local = run_cli({"params", "--config", "configs/mobile_16x16_lpddr4x.ini"});
    ASSERT_EQ(local.code, 0) << local.err;
    EXPECT_NE(local.out.find("configs/mobile_16x16_lpddr4x.ini:2"), std::string::npos) << local.out;
    EXPECT_EQ(local.out.find(checkout + "/configs"), std::string::npos) << local.out;
    // A relative path that is not in the working folder: the same path in the checkout.
    const auto inside = run_cli({"params", "--config", "configs/dram_lpddr5_6400.ini"});
    ASSERT_EQ(inside.code, 0) << inside.err;
    EXPECT_NE(inside.out.find(checkout + "/configs/dram_lpddr5_6400.ini:"), std::string::npos) << inside.out;
    const auto typo = run_cli({"params", "--config", "series6xt_gx6540"});
    EXPECT_EQ(typo.code, 2);
    EXPECT_NE(typo.err.find("no such config"), std::string::npos) << typo.err;
    EXPECT_NE(typo.err.find("did you mean 'series6xt_gx6450'"), std::string::npos) << typo.err;
    const auto sweep = run_cli({"sweep", "tile_sise", "--dry-run", "--db", "x.db"});
    EXPECT_EQ(sweep.code, 2);
    EXPECT_NE(sweep.err.find("did you mean 'tile_size'"), std::string::npos) << sweep.err;
  });
  const auto help = run_cli({"--help"});
  EXPECT_NE(help.out.find("a bare name in the checkout's configs/"), std::string::npos) << help.out;
  const auto where = run_cli({"--checkout"});
  EXPECT_EQ(where.code, 0);
  EXPECT_EQ(where.out, checkout + "\n");
}

}  // namespace
}  // namespace tbdr

// The version a run records names the commit the binary was built from: `git describe` is taken
// at every build (scripts/version_source.cmake), not only when CMake configured the build folder,
// so rebuilding after a commit changes it. (Run the tests after building, as .ci/run does.)
TEST(Cli, VersionNamesTheCommitBuilt) {
  const std::string cmd = std::string("git -C '") + TBDRSIM_SOURCE_DIR + "' describe --always --tags 2>/dev/null";
  FILE* p = popen(cmd.c_str(), "r");
  ASSERT_NE(p, nullptr);
  char buf[256] = {};
  const bool read = std::fgets(buf, sizeof buf, p) != nullptr;
  const int status = pclose(p);
  if (!read || status != 0) GTEST_SKIP() << "not a git checkout";
  std::string describe(buf);
  while (!describe.empty() && (describe.back() == '\n' || describe.back() == '\r')) describe.pop_back();
  std::ostringstream out, err;
  ASSERT_EQ(tbdr::cli_main({"--version"}, out, err), 0);
  EXPECT_NE(out.str().find("(" + describe), std::string::npos)
      << out.str() << " vs git describe " << describe << " (a build older than the checkout: run cmake --build first)";
}
