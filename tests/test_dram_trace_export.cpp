// The DRAM exports (`--memory-trace`, models/dram_trace_export.hpp) that bench/dram_vs_dramsim3.sh
// and bench/dram_vs_drampower.sh feed to DRAMsim3 and DRAMPower: well-formed, consistent with the
// model's own counts of the same run, identical at 1 and 2 threads, and refused cleanly when the
// options are wrong.
#include <gtest/gtest.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "kernel/event_queue.hpp"
#include "models/dram.hpp"
#include "models/dram_trace_export.hpp"
#include "models/hw_config.hpp"
#include "cli_run.hpp"
#include "db_query.hpp"
#include "scratch_dir.hpp"

namespace tbdr {
namespace {

using testing_support::query_number;
using testing_support::run_cli;
namespace fs = std::filesystem;

const testing_scratch::ScratchCleanup scratch_cleanup{"dram_export"};

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

std::vector<std::string> split(const std::string& line, char sep) {
  std::vector<std::string> f;
  std::stringstream ss(line);
  for (std::string x; std::getline(ss, x, sep);) f.push_back(x);
  return f;
}

std::map<std::string, double> read_summary(const fs::path& p) {
  std::map<std::string, double> m;
  std::ifstream in(p);
  for (std::string k; in >> k;) in >> m[k];
  return m;
}

double dram_stat(const std::string& db, const std::string& name) {
  return query_number(db, "select value from stats where scope = 'mem/dram' and name = '" + name + "'");
}

/// A tiny deferred frame (160x90, atrium:1, 16 lights).
std::string tiny_trace(const fs::path& dir) {
  const std::string path = (dir / "tiny.trace").string();
  const auto r = run_cli({"trace", "--technique", "deferred", "--resolution", "160x90", "--scene", "atrium:1",
                          "--lights", "16", "--out", path});
  EXPECT_EQ(r.code, 0) << r.err;
  return path;
}

struct Exported {
  std::string db, file;
};

Exported run_export(const fs::path& dir, const std::string& trace, const std::string& format, const std::string& threads) {
  Exported e{(dir / (format + threads + ".db")).string(), (dir / (format + threads + ".txt")).string()};
  const auto r = run_cli({"run", "--trace", trace, "--db", e.db, "--quiet", "--threads", threads, "--memory-trace",
                          e.file, "--memory-trace-format", format});
  EXPECT_EQ(r.code, 0) << r.err;
  return e;
}

// DRAMPower CSV: "cycle,CMD,rank,group,bank,row,column[,data]", sorted by cycle, ending with END.
// Replaying it on per-bank row state (ACT opens, PRE closes one bank, PREA all of a rank) every RD
// and WR finds its row open and every ACT a precharged bank; the command counts equal the model's
// statistics of the same run: RD x 32 B = read_bytes, WR x 32 B = write_bytes (the default LPDDR3
// preset's 32 B bursts), ACT = activates, PRE = precharges (row conflicts), REFA = refreshes.
TEST(DramTraceExport, DrampowerCommandsReplayAndMatchTheModelsCounts) {
  const auto dir = testing_scratch::scratch_dir("dram_export", "drampower");
  const std::string trace = tiny_trace(dir);
  const Exported e = run_export(dir, trace, "drampower", "1");
  std::ifstream in(e.file);
  std::map<std::string, std::uint64_t> n;
  std::map<std::pair<int, int>, std::int64_t> open;  // (rank, bank) -> row
  std::int64_t last = -1;
  bool ended = false;
  std::uint64_t lines = 0;
  for (std::string line; std::getline(in, line); ++lines) {
    ASSERT_FALSE(ended) << "a command after END: " << line;
    const auto f = split(line, ',');
    ASSERT_GE(f.size(), 7u) << line;
    const std::int64_t cycle = std::stoll(f[0]);
    ASSERT_GE(cycle, last) << "not sorted by time: " << line;
    last = cycle;
    const std::string& cmd = f[1];
    const int rank = std::stoi(f[2]), bank = std::stoi(f[4]);
    const std::int64_t row = std::stoll(f[5]);
    ++n[cmd];
    const auto key = std::make_pair(rank, bank);
    if (cmd == "ACT") {
      ASSERT_FALSE(open.count(key)) << "ACT to an open bank: " << line;
      open[key] = row;
    } else if (cmd == "PRE") {
      ASSERT_TRUE(open.count(key)) << "PRE of a precharged bank: " << line;
      open.erase(key);
    } else if (cmd == "PREA") {
      for (auto it = open.begin(); it != open.end();) it = it->first.first == rank ? open.erase(it) : std::next(it);
    } else if (cmd == "REFA") {
      for (const auto& [k, r] : open) ASSERT_NE(k.first, rank) << "REFA with an open bank: " << line;
    } else if (cmd == "RD" || cmd == "WR") {
      ASSERT_EQ(f.size(), 8u) << "RD/WR carry a data field: " << line;
      EXPECT_EQ(f[7].size(), 64u) << "32 B of data as hex: " << line;
      ASSERT_TRUE(open.count(key) && open[key] == row) << cmd << " to a row not open: " << line;
    } else if (cmd == "END") {
      ended = true;
    } else {
      FAIL() << "unknown command: " << line;
    }
  }
  EXPECT_TRUE(ended);
  EXPECT_GT(n["RD"], 0u);
  EXPECT_GT(n["REFA"], 0u);
  EXPECT_EQ(static_cast<double>(n["RD"] * 32), dram_stat(e.db, "read_bytes"));
  EXPECT_EQ(static_cast<double>(n["WR"] * 32), dram_stat(e.db, "write_bytes"));
  EXPECT_EQ(static_cast<double>(n["ACT"]), dram_stat(e.db, "activates"));
  EXPECT_EQ(static_cast<double>(n["PRE"]), dram_stat(e.db, "precharges"));
  EXPECT_EQ(static_cast<double>(n["REFA"]), dram_stat(e.db, "refreshes"));
  // The summary's latency over the same reads: its mean is the model's avg_read_latency_ns.
  const auto sum = read_summary(e.file + ".summary");
  EXPECT_EQ(sum.at("read_lines"), dram_stat(e.db, "reads"));
  EXPECT_NEAR(sum.at("read_latency_mean_ns"), dram_stat(e.db, "avg_read_latency_ns"), 1e-3);
  EXPECT_GE(sum.at("read_latency_p99_ns"), sum.at("read_latency_p50_ns"));
  EXPECT_GE(sum.at("read_latency_p99_ns"), sum.at("read_latency_mean_ns"));
}

// DRAMsim3 trace: "0xADDR READ|WRITE CYCLE", one line per 32 B burst, cycles non-decreasing (the
// requests' acceptance order); READ lines x 32 B = read_bytes, WRITE lines x 32 B = write_bytes.
// Both exports are byte-identical at 1 and 2 threads.
TEST(DramTraceExport, Dramsim3RequestsMatchTheModelAndThreadsDoNotMatter) {
  const auto dir = testing_scratch::scratch_dir("dram_export", "dramsim3");
  const std::string trace = tiny_trace(dir);
  const Exported e1 = run_export(dir, trace, "dramsim3", "1");
  const Exported e2 = run_export(dir, trace, "dramsim3", "2");
  const std::string text = slurp(e1.file);
  ASSERT_FALSE(text.empty());
  EXPECT_EQ(text, slurp(e2.file));
  EXPECT_EQ(slurp(e1.file + ".summary"), slurp(e2.file + ".summary"));
  std::istringstream in(text);
  std::uint64_t reads = 0, writes = 0;
  std::int64_t last = -1;
  for (std::string line; std::getline(in, line);) {
    const auto f = split(line, ' ');
    ASSERT_EQ(f.size(), 3u) << line;
    ASSERT_EQ(f[0].rfind("0x", 0), 0u) << line;
    EXPECT_EQ(std::stoull(f[0], nullptr, 16) % 32, 0u) << "bursts start 32 B aligned: " << line;
    ASSERT_TRUE(f[1] == "READ" || f[1] == "WRITE") << line;
    (f[1] == "READ" ? reads : writes) += 1;
    const std::int64_t cycle = std::stoll(f[2]);
    ASSERT_GE(cycle, last) << line;
    last = cycle;
  }
  EXPECT_EQ(static_cast<double>(reads * 32), dram_stat(e1.db, "read_bytes"));
  EXPECT_EQ(static_cast<double>(writes * 32), dram_stat(e1.db, "write_bytes"));

  const auto dir2 = testing_scratch::scratch_dir("dram_export", "drampower_threads");
  const Exported p1 = run_export(dir2, trace, "drampower", "1");
  const Exported p2 = run_export(dir2, trace, "drampower", "2");
  EXPECT_EQ(slurp(p1.file), slurp(p2.file));
}

// The streaming microbenchmark through `tbdrsim dram-bench`: 4096 reads of 64 B from address 0 on
// the default preset (2 channels, 8 banks, 4 KiB rows, row | bank | channel | column) fill 64 rows
// whole, each opened once (refresh off, which would close them): 64 ACT; the first row of each of
// the 2 x 8 banks finds its bank precharged, the other 48 close the bank's previous row (open-page
// policy): 48 PRE; 8192 RD of 32 B.
TEST(DramTraceExport, StreamBenchmarkOpensEachRowOnce) {
  const auto dir = testing_scratch::scratch_dir("dram_export", "bench");
  const std::string file = (dir / "s.csv").string();
  const auto r = run_cli({"dram-bench", "--pattern", "stream", "--lines", "4096", "--set", "dram.t_refi_ns=0", "--memory-trace", file,
                          "--memory-trace-format", "drampower"});
  ASSERT_EQ(r.code, 0) << r.err;
  const auto sum = read_summary(file + ".summary");
  EXPECT_EQ(sum.at("act"), 64.0);
  EXPECT_EQ(sum.at("pre"), 48.0);
  EXPECT_EQ(sum.at("rd"), 8192.0);
  EXPECT_EQ(sum.at("read_lines"), 4096.0);
  EXPECT_NE(r.out.find("activates 64\n"), std::string::npos) << r.out;
}

// Replays a DRAMPower CSV on per-bank row state: column commands to a row that is not open, and
// ones earlier than tRCD after their row's activate.
struct ReplayFaults {
  int not_open = 0, before_trcd = 0, columns = 0;
};
ReplayFaults replay(const std::string& path, std::int64_t t_rcd_cycles) {
  ReplayFaults r;
  std::map<std::pair<int, int>, std::pair<std::int64_t, std::int64_t>> open;  // (rank, bank) -> (row, ACT cycle)
  std::ifstream in(path);
  for (std::string line; std::getline(in, line);) {
    const auto f = split(line, ',');
    const std::int64_t cycle = std::stoll(f[0]);
    const auto key = std::make_pair(std::stoi(f[2]), std::stoi(f[4]));
    if (f[1] == "ACT") open[key] = {std::stoll(f[5]), cycle};
    if (f[1] == "PRE") open.erase(key);
    if (f[1] == "PREA") open.clear();  // one rank here
    if (f[1] == "RD" || f[1] == "WR") {
      ++r.columns;
      const auto it = open.find(key);
      if (it == open.end() || it->second.first != std::stoll(f[5])) {
        ++r.not_open;
      } else if (cycle < it->second.second + t_rcd_cycles) {
        ++r.before_trcd;
      }
    }
  }
  return r;
}

// The FR-FCFS starvation cap (Dram::kStarvationCap = 16): the oldest read (row 1 of bank 0) waits
// while 24 younger reads hit the open row 0 of the same bank; after 16 of them it may close row 0.
// It used to be prepared in the very cycle a row-0 hit took its column command: the precharge came
// before that hit's data, and the bank's column timer (set by the hit) let the next row-1 reads go
// before the activate. Now it waits a cycle: every column command finds its row open, tRCD after
// the activate (default preset: tRCD 18 ns = 15 cycles at 800 MHz), and row 1 is opened (one bank:
// every activate after the first closes the previous row, so precharges = activates - 1).
TEST(DramTraceExport, StarvationCapClosesARowOnlyAfterItsLastColumnCommand) {
  HwConfig hw = resolve_config({}, {"dram.t_refi_ns=0"}).hw;
  EventQueue eq;
  Dram dram(hw.dram, hw.energy, eq);
  dram.set_verify_scheduler(true);
  DramTraceExport ex(DramTraceFormat::Drampower);
  ex.attach(dram);
  dram.set_observer(&ex);
  // Row 0 of bank 0 open first; rows of bank 0 on channel 0 are 64 KiB apart (4 KiB x 2 ch x 8 banks).
  ASSERT_TRUE(dram.enqueue(DramRequest{0, 64, false, DramClass::Other, {}}));
  eq.run();
  ASSERT_TRUE(dram.enqueue(DramRequest{65536, 64, false, DramClass::Other, {}}));
  for (std::uint64_t i = 1; i <= 24; ++i) ASSERT_TRUE(dram.enqueue(DramRequest{i * 64, 64, false, DramClass::Other, {}}));
  ASSERT_TRUE(dram.enqueue(DramRequest{65536 + 64, 64, false, DramClass::Other, {}}));
  eq.run();
  const auto dir = testing_scratch::scratch_dir("dram_export", "starve");
  const std::string file = (dir / "c.csv").string();
  ex.write(file);
  const ReplayFaults r = replay(file, dram.timing().t_rcd_cycles);
  EXPECT_EQ(dram.timing().t_rcd_cycles, 15);
  EXPECT_EQ(r.columns, 2 * 27);  // 27 reads of 64 B, 2 bursts each
  EXPECT_EQ(r.not_open, 0);
  EXPECT_EQ(r.before_trcd, 0);
  EXPECT_GE(ex.counts().act, 2u);
  EXPECT_EQ(ex.counts().pre, ex.counts().act - 1);
  EXPECT_GE(dram.stats().row_conflicts.value(), 1u);
}

// Wrong options exit 2 naming what is wrong, before running, and write nothing.
TEST(DramTraceExport, BadOptionsExitTwoAndWriteNothing) {
  const auto dir = testing_scratch::scratch_dir("dram_export", "bad");
  const std::string file = (dir / "m.txt").string();
  const std::vector<std::vector<std::string>> bad = {
      {"--memory-trace", file, "--memory-trace-format", "ramulator"},
      {"--memory-trace", file},
      {"--memory-trace-format", "dramsim3"},
      {"--memory-trace", (dir / "missing" / "m.txt").string(), "--memory-trace-format", "dramsim3"},
  };
  for (const auto& extra : bad) {
    std::vector<std::string> args = {"dram-bench", "--lines", "16"};
    args.insert(args.end(), extra.begin(), extra.end());
    const auto r = run_cli(args);
    EXPECT_EQ(r.code, 2) << r.err;
    EXPECT_NE(r.err.find("--memory-trace"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(file));
    EXPECT_FALSE(fs::exists(file + ".summary"));
  }
  const auto r = run_cli({"run", "--trace", (dir / "none.trace").string(), "--db", (dir / "r.db").string(),
                          "--memory-trace", file, "--memory-trace-format", "bogus"});
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("bogus"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(file));
}

}  // namespace
}  // namespace tbdr
