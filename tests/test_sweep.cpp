// Sweeps: sweep file parsing (lists, ranges, zips, globs, errors naming file:line), point
// expansion and slicing, real parallel sweeps through the tbdrsim binary (resume after SIGKILL or
// SIGINT, failures recorded, two sweeps on one database), Slurm scripts and merging shards.
#include <gtest/gtest.h>

#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <optional>
#include <regex>
#include <set>
#include <sstream>
#include <thread>

#include "analysis/results_db.hpp"
#include "analysis/sql.hpp"
#include "app/cli.hpp"
#include "app/sweep.hpp"
#include "app/worker_pool.hpp"
#include "models/hw_config.hpp"
#include "kernel/errors.hpp"
#include "db_query.hpp"
#include "scratch_dir.hpp"

namespace tbdr {
namespace {

namespace fs = std::filesystem;

testing_scratch::ScratchCleanup scratch_cleanup{"sweep"};
fs::path scratch(const std::string& name) { return testing_scratch::scratch_dir("sweep", name); }

void write_file(const fs::path& p, const std::string& text) {
  fs::create_directories(p.parent_path());
  std::ofstream(p) << text;
}

/// Starts the tbdrsim binary in the background (output to `log`).
pid_t start_tool(const std::vector<std::string>& args, const fs::path& log) {
  std::vector<std::string> all = {TBDRSIM_BINARY};
  all.insert(all.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (auto& a : all) argv.push_back(a.data());
  argv.push_back(nullptr);
  const pid_t pid = fork();
  if (pid == 0) {
    const int fd = open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    dup2(fd, 1);
    dup2(fd, 2);
    execv(argv[0], argv.data());
    _exit(127);
  }
  return pid;
}

/// Runs the tbdrsim binary; returns its exit code, stdout+stderr in `output`.
int run_tool(const std::vector<std::string>& args, std::string* output = nullptr) {
  const fs::path log = fs::temp_directory_path() / ("tbdrsim_test_sweep_" + std::to_string(getpid()) + "_" +
                                                     std::to_string(std::rand()) + ".log");
  const pid_t pid = start_tool(args, log);
  int status = 0;
  waitpid(pid, &status, 0);
  std::ifstream in(log);
  std::stringstream ss;
  ss << in.rdbuf();
  if (output) *output = ss.str();
  fs::remove(log);
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

int wait_tool(pid_t pid) {
  int status = 0;
  waitpid(pid, &status, 0);
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

/// Runs two sweeps (files `a` and `b`, -j 2 each) on one database at the same time; both must exit 0.
void run_two_sweeps_together(const std::string& a, const std::string& b, const std::string& db, const fs::path& dir) {
  const pid_t pa = start_tool({"sweep", a, "--db", db, "-j", "2"}, dir / "a.log");
  const pid_t pb = start_tool({"sweep", b, "--db", db, "-j", "2"}, dir / "b.log");
  EXPECT_EQ(wait_tool(pa), 0);
  EXPECT_EQ(wait_tool(pb), 0);
}

std::int64_t scalar(const std::string& db_path, const std::string& sql) {
  return std::llround(testing_support::query_number(db_path, sql));
}

/// Rows of runs: ok count, distinct ok (config, trace) count, all rows.
struct RunCounts {
  std::int64_t ok = 0, distinct_ok = 0, all = 0;
};
RunCounts run_counts(const std::string& db) {
  return {scalar(db, "SELECT count(*) FROM runs WHERE status = 'ok'"),
          scalar(db, "SELECT count(DISTINCT config_hash || trace_hash) FROM runs WHERE status = 'ok'"),
          scalar(db, "SELECT count(*) FROM runs")};
}

/// Three tiny traces (160x90, atrium:1, 16 lights, three light seeds) shared by the real sweeps.
class SweepRun : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new fs::path(scratch("traces"));
    for (int seed = 1; seed <= 3; ++seed) {
      std::string out;
      const int code = run_tool({"trace", "--resolution", "160x90", "--scene", "atrium:1", "--lights", "16",
                                 "--light-seed", std::to_string(seed), "--out",
                                 (*dir_ / ("t" + std::to_string(seed) + ".trace")).string()},
                                &out);
      ASSERT_EQ(code, 0) << out;
    }
  }
  static void TearDownTestSuite() {
    fs::remove_all(dir_->parent_path());
    delete dir_;
  }
  /// A sweep file over the three traces with the given [vary] body.
  static std::string sweep_file(const fs::path& dir, const std::string& vary, int repetitions = 1) {
    const fs::path p = dir / "sweep.ini";
    write_file(p, "[sweep]\nname = test\ntrace = " + (*dir_ / "t*.trace").string() + "\nrepetitions = " +
                      std::to_string(repetitions) + "\n[vary]\n" + vary);
    return p.string();
  }
  static fs::path* dir_;
};
fs::path* SweepRun::dir_ = nullptr;

// ---------------------------------------------------------------------------------------------

TEST(SweepParse, ListsRangesZipsGlobsAndRepetitions) {
  const fs::path dir = scratch("parse");
  write_file(dir / "traces/b.trace", "x");
  write_file(dir / "traces/a.trace", "x");
  write_file(dir / "extra.trace", "x");
  write_file(dir / "cfg/base.ini", "[usc]\ncount = 6\n");
  write_file(dir / "cfg/alt.ini", "[usc]\ncount = 2\n");
  write_file(dir / "sweeps/s.ini",
             "# a sweep\n"
             "[sweep]\n"
             "name = my sweep\n"
             "config = ../cfg/base.ini\n"
             "trace = ../traces/*.trace\n"
             "trace = ../extra.trace\n"
             "repetitions = 2\n"
             "[set]\n"
             "gpu.name = a GPU, with a comma   # text is not split in [set]\n"
             "[vary]\n"
             "isp.tag_buffers = 1, 2, 4\n"
             "tiling.tile_width = 16..64 step 16\n"
             "[zip.budget]\n"
             "pls.tile_buffer_bits_per_pixel = 128, 256\n"
             "pls.max_pls_bytes_per_pixel = 16, 32\n");
  const SweepSpec s = parse_sweep_file((dir / "sweeps/s.ini").string());
  EXPECT_EQ(s.name, "my sweep");
  ASSERT_EQ(s.base_configs.size(), 1u);
  EXPECT_EQ(fs::path(s.base_configs[0]).filename(), "base.ini");
  EXPECT_TRUE(fs::exists(s.base_configs[0]));
  ASSERT_EQ(s.traces.size(), 3u);  // glob matches sorted, then the explicit one
  EXPECT_EQ(fs::path(s.traces[0]).filename(), "a.trace");
  EXPECT_EQ(fs::path(s.traces[1]).filename(), "b.trace");
  EXPECT_EQ(fs::path(s.traces[2]).filename(), "extra.trace");
  EXPECT_EQ(s.repetitions, 2);
  ASSERT_EQ(s.sets.size(), 1u);
  EXPECT_EQ(s.sets[0], "gpu.name=a GPU, with a comma");
  ASSERT_EQ(s.axes.size(), 3u);
  EXPECT_EQ(s.axes[1].values.size(), 4u);
  EXPECT_EQ(s.axes[1].values[3][0], "64");
  EXPECT_EQ(s.axes[2].keys, (std::vector<std::string>{"pls.tile_buffer_bits_per_pixel", "pls.max_pls_bytes_per_pixel"}));
  EXPECT_EQ(s.axes[2].values[1], (std::vector<std::string>{"256", "32"}));

  const auto points = expand_sweep(s);
  EXPECT_EQ(points.size(), 3u * 4u * 2u * 3u * 2u);  // tag buffers x widths x zip x traces x reps
  // Deterministic order: last axis fastest, then traces, then repetitions.
  EXPECT_EQ(points[0].sets, (std::vector<std::string>{"gpu.name=a GPU, with a comma", "isp.tag_buffers=1",
                                                      "tiling.tile_width=16", "pls.tile_buffer_bits_per_pixel=128",
                                                      "pls.max_pls_bytes_per_pixel=16"}));
  EXPECT_EQ(points[1].repetition, 1);
  EXPECT_EQ(points[0].group, points[1].group);
  EXPECT_EQ(fs::path(points[2].trace).filename(), "b.trace");
  EXPECT_EQ(points[6].sets.back(), "pls.max_pls_bytes_per_pixel=32");
  EXPECT_EQ(points.back().sets[1], "isp.tag_buffers=4");
  EXPECT_EQ(points[0].configs, s.base_configs);
  for (std::size_t i = 0; i < points.size(); ++i) EXPECT_EQ(points[i].index, i);

  // Slices partition the points and keep the repetitions of a point together.
  std::size_t total = 0;
  for (int i = 0; i < 5; ++i) {
    const auto part = slice_points(points, {i, 5});
    total += part.size();
    for (const auto& p : part) EXPECT_EQ(p.group % 5, static_cast<std::size_t>(i));
  }
  EXPECT_EQ(total, points.size());

  // A config file axis (zipped with a parameter) appends the file after the base configs.
  write_file(dir / "sweeps/c.ini",
             "[sweep]\ntrace = ../extra.trace\n[zip.preset]\nconfig = ../cfg/base.ini, ../cfg/alt.ini\n"
             "gpu.core_clock_mhz = 600, 450\n");
  const auto cp = expand_sweep(parse_sweep_file((dir / "sweeps/c.ini").string()));
  ASSERT_EQ(cp.size(), 2u);
  ASSERT_EQ(cp[1].configs.size(), 1u);
  EXPECT_EQ(fs::path(cp[1].configs[0]).filename(), "alt.ini");
  EXPECT_EQ(cp[1].sets, (std::vector<std::string>{"gpu.core_clock_mhz=450"}));
  EXPECT_NE(cp[1].label.find("config=alt.ini"), std::string::npos);
}

// The points are made from their index (nothing is kept per point): every slice's points equal
// those of the whole list that fall in it, and a configuration's hash, continued from the last
// one's, equals the hash of its parameters resolved from scratch (the runs' config_hash, which
// finds the points already in a database), in order, backwards and in a stride.
TEST(SweepParse, LazyPointsAndConfigHashesMatchAFullResolution) {
  const fs::path dir = scratch("lazy");
  write_file(dir / "a.trace", "x");
  write_file(dir / "b.trace", "x");
  write_file(dir / "base.ini", "[usc]\ncount = 6\n");
  write_file(dir / "alt.ini", "[usc]\ncount = 2\n[dram]\nt_rcd_ns = 20\n");
  write_file(dir / "s.ini",
             "[sweep]\nconfig = base.ini\ntrace = a.trace, b.trace\nrepetitions = 2\n"
             "[set]\nisp.tag_buffers = 3\n"
             "[vary]\ngpu.core_clock_mhz = 450.0, 600\ndram.t_rcd_ns = 10..14\n"
             "[zip.preset]\nconfig = base.ini, alt.ini\ngeometry.vertex_shader_alu_ops = 8, 24\n");
  const SweepSpec spec = parse_sweep_file((dir / "s.ini").string());
  const SweepPoints all(spec);
  ASSERT_EQ(all.size(), 2u * 5u * 2u * 2u * 2u);  // clock x t_rcd x zip x traces x repetitions
  EXPECT_EQ(all.total(), all.size());
  EXPECT_EQ(all.groups(), 2u * 5u * 2u * 2u);
  EXPECT_EQ(all.combinations(), 2u * 5u * 2u);
  const auto list = expand_sweep(spec);
  for (int count = 1; count <= 7; ++count) {
    for (int index = 0; index < count; ++index) {
      const SweepPoints slice(spec, {index, count});
      const auto expected = slice_points(list, {index, count});
      ASSERT_EQ(slice.size(), expected.size()) << index << "/" << count;
      for (std::size_t i = 0; i < slice.size(); ++i) {
        const SweepPoint p = slice[i];
        EXPECT_EQ(p.index, expected[i].index);
        EXPECT_EQ(p.group, expected[i].group);
        EXPECT_EQ(p.repetition, expected[i].repetition);
        EXPECT_EQ(p.sets, expected[i].sets);
        EXPECT_EQ(p.configs, expected[i].configs);
        EXPECT_EQ(p.trace, expected[i].trace);
        EXPECT_EQ(p.label, expected[i].label);
        EXPECT_EQ(slice.traces()[slice.trace(i)], p.trace);
        EXPECT_EQ(slice.index(i), p.index);
      }
    }
  }
  // The order: the last axis fastest, then traces, then repetitions.
  EXPECT_EQ(list[0].label, "gpu.core_clock_mhz=450.0 dram.t_rcd_ns=10 config=base.ini geometry.vertex_shader_alu_ops=8 | a.trace #1");
  EXPECT_EQ(list[1].label, "gpu.core_clock_mhz=450.0 dram.t_rcd_ns=10 config=base.ini geometry.vertex_shader_alu_ops=8 | a.trace #2");
  EXPECT_EQ(list[2].trace, (dir / "b.trace").lexically_normal().string());
  EXPECT_EQ(list[4].label, "gpu.core_clock_mhz=450.0 dram.t_rcd_ns=10 config=alt.ini geometry.vertex_shader_alu_ops=24 | a.trace #1");

  const ParamTable& table = hw_params().table();
  std::vector<std::string> full(all.combinations());
  for (std::size_t i = 0; i < all.size(); ++i) {
    const SweepPoint p = all[i];
    full[all.combination(i)] = table.hash(table.resolve(p.configs, p.sets));
  }
  std::set<std::string> distinct(full.begin(), full.end());
  EXPECT_EQ(distinct.size(), full.size()) << "every configuration differs";
  SweepConfigHashes forward(spec);
  for (std::size_t c = 0; c < full.size(); ++c) EXPECT_EQ(forward(c), full[c]) << "configuration " << c;
  SweepConfigHashes backward(spec);
  for (std::size_t c = full.size(); c-- > 0;) EXPECT_EQ(backward(c), full[c]) << "configuration " << c;
  SweepConfigHashes stride(spec);
  for (std::size_t k = 0; k < 3 * full.size(); ++k) {
    const std::size_t c = (k * 7) % full.size();
    EXPECT_EQ(stride(c), full[c]) << "configuration " << c;
  }
}

TEST(SweepParse, ValueListsAndRanges) {
  using V = std::vector<std::string>;
  EXPECT_EQ(expand_value_list("1, 2,4", "w"), (V{"1", "2", "4"}));
  EXPECT_EQ(expand_value_list("16..64 step 16", "w"), (V{"16", "32", "48", "64"}));
  EXPECT_EQ(expand_value_list("16..60 step 16", "w"), (V{"16", "32", "48"}));
  EXPECT_EQ(expand_value_list("1..4", "w"), (V{"1", "2", "3", "4"}));
  EXPECT_EQ(expand_value_list("1..8 x 2", "w"), (V{"1", "2", "4", "8"}));
  EXPECT_EQ(expand_value_list("16..256 *4", "w"), (V{"16", "64", "256"}));
  EXPECT_EQ(expand_value_list("0.1..0.3 step 0.1", "w"), (V{"0.1", "0.2", "0.3"}));
  EXPECT_EQ(expand_value_list("0.5..1 step 0.25, 2", "w"), (V{"0.5", "0.75", "1", "2"}));
  for (const char* bad : {"", "1,,2", "1..", "a..b", "4..1", "1..4 step 0", "1..4 step -1", "0..8 x 2",
                          "1..8 x 1", "1, 1", "1..3, 2"}) {
    try {
      expand_value_list(bad, "s.ini:7");
      ADD_FAILURE() << "no error for '" << bad << "'";
    } catch (const InputError& e) {
      EXPECT_EQ(e.where(), "s.ini:7") << bad;
    }
  }
}

TEST(SweepParse, ErrorsNameFileAndLine) {
  const fs::path dir = scratch("errors");
  write_file(dir / "t.trace", "x");
  const std::string head = "[sweep]\ntrace = t.trace\n";  // lines 1-2
  struct Case {
    std::string body;
    int line;
    std::string message;
  };
  const std::vector<Case> cases = {
      {head + "[sweeps]\n", 3, "unknown section [sweeps]"},
      {head + "[vary]\ntiling.tile_widht = 16, 32\n", 4, "did you mean 'tiling.tile_width'"},
      {head + "[vary]\ntiling.tile_width = 16, 1000\n", 4, "tiling.tile_width' = '1000'"},
      {head + "[vary]\nisp.tag_buffers = 1..4 step -1\n", 4, "step must be positive"},
      {head + "[zip.z]\nisp.tag_buffers = 1, 2\ntiling.tile_width = 16, 32, 64\n", 5, "equal length"},
      {"[sweep]\ntrace = nothing/*.trace\n", 2, "matches no file"},
      {"[sweep]\ntrace = missing.trace\n", 2, "not found"},
      {head + "repetitions = 0\n", 3, "repetitions"},
      {head + "colour = red\n", 3, "unknown key 'colour'"},
      {head + "[vary]\nisp.tag_buffers = 1\nisp.tag_buffers = 2\n", 5, "set twice"},
      {head + "[set]\nisp.tag_buffers = 1\n[vary]\nisp.tag_buffers = 2, 4\n", 6, "already set or swept at"},
      {head + "[vary]\nisp.tag_buffers\n", 4, "expected 'key = value'"},
      {"isp.tag_buffers = 1\n", 1, "outside any section"},
      {head + "config = nope.ini\n", 3, "config file"},
      {head + "[vary]\ngpu.mode = tbdr, warp\n", 4, "one of tbdr|tbr|imr"},
      {head + "[zip.empty]\n", 3, "is empty"},
  };
  for (const auto& c : cases) {
    const fs::path p = dir / "s.ini";
    write_file(p, c.body);
    try {
      parse_sweep_file(p.string());
      ADD_FAILURE() << "no error for:\n" << c.body;
    } catch (const InputError& e) {
      EXPECT_EQ(e.where(), p.string() + ":" + std::to_string(c.line)) << c.body << "\n" << e.what();
      EXPECT_NE(std::string(e.what()).find(c.message), std::string::npos) << e.what();
    }
  }
  write_file(dir / "notrace.ini", "[vary]\nisp.tag_buffers = 1, 2\n");
  EXPECT_THROW(parse_sweep_file((dir / "notrace.ini").string()), InputError);
  EXPECT_THROW(parse_sweep_file((dir / "absent.ini").string()), InputError);
  EXPECT_THROW(parse_slice("2/2"), InputError);
  EXPECT_THROW(parse_slice("x"), InputError);
  EXPECT_EQ(parse_slice("1/3").index, 1);
  // The command line turns them into exit code 2.
  std::string out;
  EXPECT_EQ(run_tool({"sweep", (dir / "s.ini").string(), "--db", (dir / "x.db").string()}, &out), 2);
  EXPECT_NE(out.find("s.ini:3"), std::string::npos) << out;
  EXPECT_FALSE(fs::exists(dir / "x.db"));
}

TEST_F(SweepRun, SmallSweepInParallelThenResumeSkipsEverything) {
  const fs::path dir = scratch("small");
  const std::string file =
      sweep_file(dir, "tiling.tile_width = 16..32 step 16\npls.tile_buffer_bits_per_pixel = 128, 192, 256\n");
  const std::string db = (dir / "r.db").string();
  std::string out;
  ASSERT_EQ(run_tool({"sweep", file, "--db", db, "-j", "2"}, &out), 0) << out;
  EXPECT_NE(out.find("18 point(s)"), std::string::npos) << out;
  EXPECT_NE(out.find("points/s"), std::string::npos) << out;
  auto c = run_counts(db);
  EXPECT_EQ(c.all, 18);
  EXPECT_EQ(c.distinct_ok, 18);
  EXPECT_EQ(scalar(db, "SELECT count(DISTINCT value) FROM run_params WHERE key = 'tiling.tile_width'"), 2);
  EXPECT_EQ(scalar(db, "SELECT count(*) FROM v_run_summary WHERE overshading > 0"), 18);
  // Rerun: everything is already there.
  ASSERT_EQ(run_tool({"sweep", file, "--db", db, "-j", "2"}, &out), 0) << out;
  EXPECT_NE(out.find("18 already in"), std::string::npos) << out;
  EXPECT_EQ(run_counts(db).all, 18);
  // A dry run lists the points.
  ASSERT_EQ(run_tool({"sweep", file, "--db", db, "--dry-run"}, &out), 0) << out;
  EXPECT_NE(out.find("done"), std::string::npos);
}

TEST_F(SweepRun, RepetitionsAreKeptAndResumed) {
  const fs::path dir = scratch("reps");
  const std::string file = sweep_file(dir, "isp.tag_buffers = 1, 2\n", 2);
  const std::string db = (dir / "r.db").string();
  SweepSpec spec = parse_sweep_file(file);
  SweepOptions opt;
  opt.db_path = db;
  opt.jobs = 2;
  opt.binary = TBDRSIM_BINARY;
  opt.progress = SweepProgress::None;
  opt.slice = {0, 2};  // half of the point groups, both repetitions of each
  std::ostringstream out;
  auto s = run_sweep(spec, opt, out);
  EXPECT_EQ(s.points, 6u);
  EXPECT_EQ(s.ok, 6u);
  opt.slice = {0, 1};
  s = run_sweep(spec, opt, out);
  EXPECT_EQ(s.skipped, 6u);
  EXPECT_EQ(s.ok, 6u);
  const auto c = run_counts(db);
  EXPECT_EQ(c.ok, 12);
  EXPECT_EQ(c.distinct_ok, 6);
}

/// Kills a sweep half-way (SIGKILL: workers die with it; SIGINT: running points finish), reruns it
/// and checks every point is there exactly once. No clock decides what "half-way" is: the test
/// takes the database's write lock (BEGIN IMMEDIATE) as soon as it holds 4 runs or more, so no
/// further run can be written (the workers wait on the lock, within SQLite's 60 s busy timeout)
/// until the signal has been sent; the sweep cannot have finished its 36 points by then.
void kill_and_resume(const fs::path& dir, const std::string& file, int sig) {
  const std::string db = (dir / "r.db").string();
  const std::int64_t n = 36;
  { ResultsDb create(db); }  // the schema exists, so the test can take the lock from the start
  const pid_t pid = start_tool({"sweep", file, "--db", db, "-j", "2"}, dir / "first.log");
  std::optional<SqlConnection> lock_holder;
  std::optional<SqlTransaction> lock;
  for (;;) {
    lock_holder.emplace(db);
    lock.emplace(*lock_holder);
    SqlStatement count(*lock_holder, "SELECT count(*) FROM runs");
    ASSERT_TRUE(count.step());
    if (count.int64(0) >= 4) break;
    lock.reset();  // rolled back: the sweep writes on
    lock_holder.reset();
    std::this_thread::yield();
  }
  kill(pid, sig);
  if (sig == SIGINT) {  // the running points finish: they need the lock
    lock.reset();
    lock_holder.reset();
  }
  const int code = wait_tool(pid);
  lock.reset();
  lock_holder.reset();
  std::ifstream log(dir / "first.log");
  std::stringstream first;
  first << log.rdbuf();
  if (sig == SIGINT) {
    EXPECT_EQ(code, 130) << first.str();
    EXPECT_NE(first.str().find("interrupted"), std::string::npos) << first.str();
  } else {
    EXPECT_EQ(code, 128 + SIGKILL);
  }
  const auto mid = run_counts(db);
  EXPECT_LT(mid.all, n) << "the sweep finished before it was killed";
  EXPECT_EQ(mid.ok, mid.distinct_ok);
  EXPECT_EQ(mid.all, mid.ok);  // no failed rows: an interrupted point is not a failure
  std::string out;
  ASSERT_EQ(run_tool({"sweep", file, "--db", db, "-j", "2"}, &out), 0) << out;
  const auto c = run_counts(db);
  EXPECT_EQ(c.all, n) << out;
  EXPECT_EQ(c.distinct_ok, n);
  EXPECT_EQ(scalar(db, "SELECT count(*) FROM runs r WHERE NOT EXISTS (SELECT 1 FROM stats s WHERE s.run_id = r.id)"), 0);
}

TEST_F(SweepRun, SigkillHalfWayThenRerunHasNoDuplicateAndNoMissingRow) {
  const fs::path dir = scratch("kill");
  kill_and_resume(dir, sweep_file(dir, "isp.tag_buffers = 1..4\ntiling.tile_width = 16, 32, 64\n"), SIGKILL);
}

TEST_F(SweepRun, SigintStopsCleanlyThenRerunCompletes) {
  const fs::path dir = scratch("int");
  kill_and_resume(dir, sweep_file(dir, "isp.tag_buffers = 1..4\ntiling.tile_width = 16, 32, 64\n"), SIGINT);
}

TEST_F(SweepRun, TwoSweepsOnOneDatabaseLoseNoRows) {
  const fs::path dir = scratch("two");
  const fs::path a = dir / "a", b = dir / "b";
  const std::string fa = sweep_file(a, "isp.tag_buffers = 1..4\n");
  const std::string fb = sweep_file(b, "gpu.core_clock_mhz = 400, 500, 700, 800\n");
  const std::string db = (dir / "shared.db").string();
  { ResultsDb create(db); }  // the schema exists; what is tested is concurrent writing of runs
  run_two_sweeps_together(fa, fb, db, dir);
  const auto c = run_counts(db);
  EXPECT_EQ(c.all, 24);
  EXPECT_EQ(c.distinct_ok, 24);
  EXPECT_EQ(scalar(db, "SELECT count(*) FROM stats") % 24, 0);
}

// Two identical sweeps started together on one (new) database: each point is claimed in the
// database by the sweep that runs it, so the 12 points (4 tag-buffer counts x 3 traces) are run
// once in all: 12 rows, 12 distinct. (Before the claims, each sweep ran nearly every point: the
// issue saw 103 rows for 52 points.)
TEST_F(SweepRun, TwoIdenticalSweepsOnOneDatabaseRunEachPointOnce) {
  const fs::path dir = scratch("same");
  const std::string file = sweep_file(dir, "isp.tag_buffers = 1..4\n");
  const std::string db = (dir / "shared.db").string();
  run_two_sweeps_together(file, file, db, dir);
  const auto c = run_counts(db);
  EXPECT_EQ(c.all, 12);
  EXPECT_EQ(c.distinct_ok, 12);
  EXPECT_EQ(scalar(db, "SELECT count(*) FROM sweep_claims"), 0);  // both released theirs
}

// Claims left in the database: one of a live process on this host (held: the point is left to
// it), one of a process that no longer exists and one whose lease lapsed on another host (both
// taken over). Of 6 points, 3 are removed and claimed that way: the rerun runs 2, leaves 1, skips 3.
TEST_F(SweepRun, DeadOrLapsedClaimsAreTakenOverLiveOnesAreLeft) {
  const fs::path dir = scratch("claims");
  const std::string db = (dir / "r.db").string();
  SweepSpec spec = parse_sweep_file(sweep_file(dir, "isp.tag_buffers = 1, 2\n"));
  SweepOptions opt;
  opt.db_path = db;
  opt.jobs = 2;
  opt.binary = TBDRSIM_BINARY;
  opt.progress = SweepProgress::None;
  std::ostringstream out;
  ASSERT_EQ(run_sweep(spec, opt, out).ok, 6u);
  const pid_t gone = fork();  // a process id that no longer exists once reaped
  if (gone == 0) _exit(0);
  waitpid(gone, nullptr, 0);
  const double now = static_cast<double>(std::time(nullptr));
  {
    ResultsDb rdb(db);
    struct Held {
      std::string host;
      std::int64_t pid;
      double lease_until;
    };
    const Held held[] = {{host_name(), getpid(), now + 600},  // live: left to it
                         {host_name(), gone, now + 600},      // its process is gone
                         {"elsewhere", getpid(), now - 1}};   // its lease lapsed
    std::vector<std::pair<std::string, std::string>> keys;
    {
      SqlStatement q(rdb.sql(), "SELECT config_hash, trace_hash FROM runs ORDER BY id LIMIT 3");
      while (q.step()) keys.emplace_back(q.text(0), q.text(1));
    }
    ASSERT_EQ(keys.size(), 3u);
    for (std::size_t k = 0; k < 3; ++k) {
      SqlStatement del(rdb.sql(), "DELETE FROM runs WHERE config_hash = ? AND trace_hash = ?");
      del.bind(1, keys[k].first).bind(2, keys[k].second);
      del.run();
      SqlStatement claim(rdb.sql(), "INSERT INTO sweep_claims VALUES(?, ?, 0, ?, ?, ?, ?)");
      claim.bind(1, keys[k].first).bind(2, keys[k].second).bind(3, "other-sweep-" + std::to_string(k));
      claim.bind(4, held[k].host).bind(5, held[k].pid).bind(6, held[k].lease_until);
      claim.run();
    }
  }
  const SweepSummary s = run_sweep(spec, opt, out);
  EXPECT_EQ(s.ok, 2u) << out.str();
  EXPECT_EQ(s.elsewhere, 1u) << out.str();
  EXPECT_EQ(s.skipped, 3u) << out.str();
  EXPECT_NE(out.str().find("1 being run by another sweep"), std::string::npos) << out.str();
  EXPECT_EQ(run_counts(db).all, 5);
  EXPECT_EQ(scalar(db, "SELECT count(*) FROM sweep_claims"), 1);  // the live one's, untouched
  EXPECT_EQ(scalar(db, "SELECT count(*) FROM sweep_claims WHERE owner = 'other-sweep-0'"), 1);
}

/// The names in a folder with their sizes, sorted (what a command left behind).
std::vector<std::pair<std::string, std::uintmax_t>> listing(const fs::path& dir) {
  std::vector<std::pair<std::string, std::uintmax_t>> files;
  for (const auto& e : fs::directory_iterator(dir)) {
    files.emplace_back(e.path().filename().string(), e.is_regular_file() ? e.file_size() : 0);
  }
  std::sort(files.begin(), files.end());
  return files;
}

// A dry run writes nothing: without a database it creates none (6 points, all to run); with one
// (4 of the 6 points run by a sliced sweep first) it reads it, listing 4 done, and leaves the
// folder as it was (no file created, none changed in size).
TEST_F(SweepRun, DryRunWritesNothing) {
  const fs::path dir = scratch("dry");
  const std::string file = sweep_file(dir, "isp.tag_buffers = 1, 2\n");
  const std::string db = (dir / "r.db").string();
  std::string out;
  auto before = listing(dir);
  ASSERT_EQ(run_tool({"sweep", file, "--db", db, "--dry-run"}, &out), 0) << out;
  EXPECT_NE(out.find("0 already in " + db + ", 6 to run"), std::string::npos) << out;
  EXPECT_EQ(listing(dir), before) << "the dry run created the database";

  ASSERT_EQ(run_tool({"sweep", file, "--db", db, "--slice", "0/3", "-j", "2"}, &out), 0) << out;
  ASSERT_EQ(run_tool({"sweep", file, "--db", db, "--slice", "1/3", "-j", "2"}, &out), 0) << out;
  before = listing(dir);
  ASSERT_EQ(run_tool({"sweep", file, "--db", db, "--dry-run"}, &out), 0) << out;
  EXPECT_NE(out.find("4 already in " + db + ", 2 to run"), std::string::npos) << out;
  EXPECT_EQ(listing(dir), before);
}

TEST_F(SweepRun, FailedPointIsRecordedAndOthersRun) {
  const fs::path dir = scratch("fail");
  // A glTF trace whose buffer file goes missing: the parent reads the trace fine, the worker fails.
  const float tri[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  fs::create_directories(dir / "box");
  std::ofstream(dir / "box/Box0.bin", std::ios::binary).write(reinterpret_cast<const char*>(tri), sizeof tri);
  write_file(dir / "box/Box.gltf",
             R"({"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[0]}],"nodes":[{"mesh":0}],)"
             R"("meshes":[{"primitives":[{"attributes":{"POSITION":0}}]}],)"
             R"("accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}],)"
             R"("bufferViews":[{"buffer":0,"byteLength":36}],"buffers":[{"uri":"Box0.bin","byteLength":36}]})");
  std::string out;
  ASSERT_EQ(run_tool({"trace", "--resolution", "160x90", "--scene", (dir / "box/Box.gltf").string(), "--lights", "4",
                      "--out", (dir / "box.trace").string()},
                     &out),
            0)
      << out;
  fs::remove(dir / "box/Box0.bin");
  const fs::path file = dir / "sweep.ini";
  write_file(file, "[sweep]\ntrace = box.trace\ntrace = " + (*dir_ / "t1.trace").string() +
                       "\n[vary]\nisp.tag_buffers = 1, 2\n");
  const std::string db = (dir / "r.db").string();
  EXPECT_EQ(run_tool({"sweep", file.string(), "--db", db, "-j", "2"}, &out), 1) << out;
  EXPECT_NE(out.find("FAILED"), std::string::npos) << out;
  testing_support::expect_numbers(
      db, {{"SELECT count(*) FROM runs WHERE status = 'ok'", 2},
           {"SELECT count(*) FROM runs WHERE status = 'failed' AND error LIKE '%Box0.bin%'", 2},
           {"SELECT count(*) FROM run_params p JOIN runs r ON r.id = p.run_id WHERE r.status = 'failed' "
            "AND p.key = 'isp.tag_buffers'",
            2},
           {"SELECT count(*) FROM stats s JOIN runs r ON r.id = s.run_id WHERE r.status = 'failed'", 0}});
}

TEST_F(SweepRun, SlurmScriptAndMergedShardsMatchOneDatabase) {
  const fs::path dir = scratch("slurm");
  const std::string file = sweep_file(dir, "isp.tag_buffers = 1, 2\ntiling.tile_width = 16, 32\n");
  std::string out;
  ASSERT_EQ(run_tool({"sweep", file, "--emit-slurm", (dir / "job").string(), "--slices", "2", "-j", "2"}, &out), 0)
      << out;
  const fs::path script = dir / "job/test.sbatch";
  ASSERT_TRUE(fs::exists(script)) << out;
  ASSERT_TRUE(fs::exists(dir / "job/README.md"));
  EXPECT_EQ(std::system(("bash -n '" + script.string() + "'").c_str()), 0);
  std::ifstream in(script);
  std::stringstream text;
  text << in.rdbuf();
  EXPECT_NE(text.str().find("#SBATCH --array=0-1\n"), std::string::npos) << text.str();
  EXPECT_NE(text.str().find("--slice \"${TASK}/2\""), std::string::npos) << text.str();
  EXPECT_NE(text.str().find("shard_"), std::string::npos);
  EXPECT_NE(text.str().find(" merge "), std::string::npos);

  // Run the two array tasks the way Slurm would (the script with SLURM_ARRAY_TASK_ID), merge the
  // shards, compare with one database of the same points.
  std::vector<std::string> shards;
  for (int i = 0; i < 2; ++i) {
    shards.push_back((dir / ("job/shard_" + std::to_string(i) + ".db")).string());
    const std::string cmd = "SLURM_ARRAY_TASK_ID=" + std::to_string(i) + " TBDRSIM=" + std::string(TBDRSIM_BINARY) +
                            " bash '" + script.string() + "' > '" + (dir / "task.log").string() + "' 2>&1";
    ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
    ASSERT_TRUE(fs::exists(shards.back()));
  }
  EXPECT_EQ(run_counts(shards[0]).all + run_counts(shards[1]).all, 12);
  const std::string merged = (dir / "merged.db").string();
  std::vector<std::string> args = {"merge", merged};
  args.insert(args.end(), shards.begin(), shards.end());
  ASSERT_EQ(run_tool(args, &out), 0) << out;
  EXPECT_NE(out.find("12 run(s) copied"), std::string::npos) << out;
  // Merging again adds nothing.
  ASSERT_EQ(run_tool(args, &out), 0) << out;
  EXPECT_NE(out.find("0 run(s) copied, 12 duplicate(s)"), std::string::npos) << out;

  const std::string single = (dir / "single.db").string();
  ASSERT_EQ(run_tool({"sweep", file, "--db", single, "-j", "2"}, &out), 0) << out;
  auto rows = [](const std::string& db) {
    std::multiset<std::string> r;
    ResultsDb d(db);
    SqlStatement q(d.sql(),
               "SELECT r.config_hash, r.trace_hash, s.scope, s.name, s.value FROM runs r JOIN stats s ON s.run_id = r.id "
               "WHERE s.scope NOT GLOB 'frame/host*'");
    while (q.step()) r.insert(q.text(0) + "|" + q.text(1) + "|" + q.text(2) + "|" + q.text(3) + "|" + q.text(4));
    SqlStatement p(d.sql(), "SELECT r.config_hash, p.key, p.value FROM runs r JOIN run_params p ON p.run_id = r.id");
    while (p.step()) r.insert(p.text(0) + "|" + p.text(1) + "|" + p.text(2));
    return r;
  };
  const auto a = rows(merged), b = rows(single);
  EXPECT_EQ(a.size(), b.size());
  EXPECT_TRUE(a == b);
  EXPECT_EQ(run_counts(merged).distinct_ok, 12);
  EXPECT_EQ(scalar(merged, "SELECT count(*) FROM stat_defs"), scalar(single, "SELECT count(*) FROM stat_defs"));
  // Bad shards are refused by name.
  EXPECT_EQ(run_tool({"merge", merged, (dir / "absent.db").string()}, &out), 2);
  EXPECT_NE(out.find("absent.db"), std::string::npos);
}

// --emit-slurm passes --time, --partition and --mem into #SBATCH lines (checked against Slurm's
// syntax first), writes paths without doubled separators whatever the folder's spelling, and hands
// the tasks the --trace patterns that replaced the sweep file's trace lines.
TEST_F(SweepRun, SlurmResourcesCleanPathsAndTraceOverride) {
  const fs::path dir = scratch("slurm_options");
  const fs::path file = dir / "s.ini";
  write_file(file, "[sweep]\nname = opts\ntrace = not_here/*.trace\n[vary]\nisp.tag_buffers = 1, 2\n");
  const std::vector<std::string> traces = {"--trace", (*dir_ / "t1.trace").string(), "--trace",
                                           (*dir_ / "t2.trace").string()};
  std::string out;
  // Without --trace the file's own line is read, and its glob matches nothing.
  EXPECT_EQ(run_tool({"sweep", file.string(), "--db", (dir / "x.db").string(), "--dry-run"}, &out), 2);
  EXPECT_NE(out.find("not_here"), std::string::npos) << out;
  std::vector<std::string> args = {"sweep", file.string(), "--emit-slurm", (dir / "job").string() + "/",
                                   "--slices", "2", "-j", "1", "--time", "1:30:00", "--partition", "short",
                                   "--mem", "2G"};
  args.insert(args.end(), traces.begin(), traces.end());
  std::vector<std::string> dry = args;
  dry.push_back("--dry-run");
  ASSERT_EQ(run_tool(dry, &out), 0) << out;
  EXPECT_NE(out.find("wrote nothing"), std::string::npos) << out;
  EXPECT_FALSE(fs::exists(dir / "job")) << "a dry run wrote the Slurm job";
  ASSERT_EQ(run_tool(args, &out), 0) << out;
  std::ifstream in(dir / "job/opts.sbatch");
  std::stringstream text;
  text << in.rdbuf();
  const std::string script = text.str();
  for (const char* line : {"#SBATCH --time=1:30:00\n", "#SBATCH --partition=short\n", "#SBATCH --mem=2G\n"}) {
    EXPECT_NE(script.find(line), std::string::npos) << line << script;
  }
  EXPECT_EQ(script.find("//"), std::string::npos) << script;
  EXPECT_NE(script.find("--trace " + shell_quote((*dir_ / "t1.trace").string())), std::string::npos) << script;
  std::ifstream readme_in(dir / "job/README.md");
  std::stringstream readme;
  readme << readme_in.rdbuf();
  EXPECT_EQ(readme.str().find("//"), std::string::npos) << readme.str();
  // The two tasks run as Slurm would start them: 2 traces x 2 tag-buffer counts = 4 runs.
  for (int i = 0; i < 2; ++i) {
    const std::string cmd = "SLURM_ARRAY_TASK_ID=" + std::to_string(i) + " TBDRSIM=" + std::string(TBDRSIM_BINARY) +
                            " bash '" + (dir / "job/opts.sbatch").string() + "' > '" + (dir / "task.log").string() +
                            "' 2>&1";
    ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
  }
  EXPECT_EQ(run_counts((dir / "job/shard_0.db").string()).ok + run_counts((dir / "job/shard_1.db").string()).ok, 4);

  // Bad requests are refused before anything is written, naming the option.
  const std::vector<std::pair<std::vector<std::string>, std::string>> bad = {
      {{"--time", "90 minutes"}, "--time 90 minutes"},
      {{"--mem", "2GB"}, "--mem 2GB"},
      {{"--partition", "a b"}, "--partition a b"},
  };
  for (const auto& [opt, named] : bad) {
    std::vector<std::string> a = {"sweep", file.string(), "--emit-slurm", (dir / "bad").string()};
    a.insert(a.end(), opt.begin(), opt.end());
    a.insert(a.end(), traces.begin(), traces.end());
    EXPECT_EQ(run_tool(a, &out), 2) << out;
    EXPECT_NE(out.find(named), std::string::npos) << out;
  }
  std::vector<std::string> no_slurm = {"sweep", file.string(), "--db", (dir / "y.db").string(), "--time", "1:00:00"};
  no_slurm.insert(no_slurm.end(), traces.begin(), traces.end());
  EXPECT_EQ(run_tool(no_slurm, &out), 2);
  EXPECT_NE(out.find("--time goes with --emit-slurm"), std::string::npos) << out;
  EXPECT_FALSE(fs::exists(dir / "bad"));
  EXPECT_FALSE(fs::exists(dir / "y.db"));
}

// A trace that draws the scene many times (forward_multipass: a pass per light batch) is announced
// before the sweep runs, with its point count; the single-pass traces are not.
TEST_F(SweepRun, SlowPointsAreAnnouncedBeforeRunning) {
  const fs::path dir = scratch("slow");
  std::string out;
  const std::string multi = (dir / "multi.trace").string();
  ASSERT_EQ(run_tool({"trace", "--technique", "forward_multipass", "--resolution", "160x90", "--scene", "atrium:1",
                      "--lights", "64", "--out", multi},
                     &out),
            0)
      << out;
  const fs::path file = dir / "s.ini";
  write_file(file, "[sweep]\nname = costs\ntrace = multi.trace\ntrace = " + (*dir_ / "t1.trace").string() +
                       "\n[vary]\nisp.tag_buffers = 1, 2\n");
  ASSERT_EQ(run_tool({"sweep", file.string(), "--db", (dir / "x.db").string(), "--dry-run"}, &out), 0) << out;
  // forward_multipass at 64 lights draws the scene well over 8 times (per light); the plain_forward
  // trace draws it 3 times (opaque, masked, blended).
  EXPECT_NE(out.find("slow: 2 point(s) replay " + multi + " (forward_multipass), which draws the scene "),
            std::string::npos)
      << out;
  EXPECT_NE(out.find(", 3 in this sweep's lightest trace"), std::string::npos) << out;
  EXPECT_EQ(out.find("slow:", out.find("slow:") + 1), std::string::npos) << "only one trace is slow: " << out;
  EXPECT_LT(out.find("slow:"), out.find("to run  ")) << "announced before the point list: " << out;
  EXPECT_FALSE(fs::exists(dir / "x.db")) << "a dry run writes nothing";
  const std::string plain = sweep_file(dir, "isp.tag_buffers = 1, 2\n");
  ASSERT_EQ(run_tool({"sweep", plain, "--db", (dir / "x.db").string(), "--dry-run"}, &out), 0) << out;
  EXPECT_EQ(out.find("slow:"), std::string::npos) << out;
}

}  // namespace
}  // namespace tbdr
