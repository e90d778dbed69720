// The open-loop replay of a DRAM request stream (`tbdrsim dram-bench --replay`, run_dram_replay in
// models/dram_microbench.hpp): the tool's side of the frame-latency comparison with DRAMsim3 on
// identical arrivals (docs/dram-cross-check.md, "Frames"). A stream the model exported replays
// to the same bytes and bandwidth; the write queue's depth moves a mixed stream's read latency the
// way the mechanism says; bad files are refused with their line.
#include <gtest/gtest.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "models/dram_microbench.hpp"
#include "models/hw_config.hpp"
#include "cli_run.hpp"
#include "scratch_dir.hpp"

namespace tbdr {
namespace {

using testing_support::run_cli;
namespace fs = std::filesystem;

const testing_scratch::ScratchCleanup scratch_cleanup{"dram_replay"};

std::map<std::string, double> figures(const std::string& out) {
  std::map<std::string, double> m;
  std::istringstream in(out);
  std::string k;
  double v = 0;
  while (in >> k >> v) m[k] = v;
  return m;
}

TEST(DramReplay, AnExportedStreamReplaysToItsOwnBytesAndBandwidth) {
  // The random benchmark's requests as the controller accepted them (4096 lines of 64 B, 8192
  // transactions of 32 B in the export), replayed at those times: the same 262,144 bytes, and the
  // same bandwidth to within 2 % (the replay offers a request when it arrives, the benchmark when
  // the queue reported room: the same tick, so only the order within a tick can differ).
  const auto dir = testing_scratch::scratch_dir("dram_replay", "export");
  const std::string file = (dir / "r.trace").string();
  const auto bench = run_cli({"dram-bench", "--pattern", "random", "--lines", "4096", "--memory-trace", file,
                              "--memory-trace-format", "dramsim3"});
  ASSERT_EQ(bench.code, 0) << bench.err;
  const auto replay = run_cli({"dram-bench", "--replay", file});
  ASSERT_EQ(replay.code, 0) << replay.err;
  const auto b = figures(bench.out), r = figures(replay.out);
  EXPECT_EQ(r.at("read_bytes"), 262144.0);
  EXPECT_EQ(r.at("write_bytes"), 0.0);
  EXPECT_NEAR(r.at("achieved_bandwidth_gbps") / b.at("achieved_bandwidth_gbps"), 1.0, 0.02);
  EXPECT_NEAR(r.at("activates") / b.at("activates"), 1.0, 0.02);
  // Offered no earlier than the benchmark's own acceptances, no read waits outside its queue long.
  EXPECT_LT(r.at("read_wait_outside_ns"), 0.05 * r.at("avg_read_latency_ns"));
}

// A stream of reads and writes at 80 % of the channels' peak, like a frame's G-buffer pass: every
// 10 DRAM cycles (12.5 ns at the default 800 MHz) a 64 B read of one stream and a 64 B write of
// another, 128 B / 12.5 ns = 10.24 GB/s against 12.8 GB/s peak (2 x 32 bit x 1600 MT/s). The
// default 32-line write queue reaches its 24-line watermark and drains to 8 while reads wait; a
// 256-line queue drains from 192 lines, so writes mostly go when no read is waiting.
constexpr std::int64_t kCyclesPerPair = 10;
std::vector<DramReplayRequest> mixed_stream(std::uint64_t pairs, std::int64_t period_ps) {
  std::vector<DramReplayRequest> v;
  for (std::uint64_t i = 0; i < pairs; ++i) {
    const Tick t{static_cast<std::int64_t>(i) * kCyclesPerPair * period_ps};
    v.push_back({t, i * 64, 64, 1, false});
    v.push_back({t, (std::uint64_t{1} << 28) + i * 64, 64, 1, true});
  }
  return v;
}

TEST(DramReplay, ADeeperWriteQueueLetsAMixedStreamsReadsGoFirst) {
  HwConfig hw = resolve_config({}, {}).hw;
  const auto period_ps = static_cast<std::int64_t>(1e6 / hw.dram.clock_mhz);
  const auto stream = mixed_stream(4096, period_ps);
  hw.dram.read_queue_entries = 256;
  hw.dram.write_queue_entries = 32;
  const DramReplayResult shallow = run_dram_replay(hw, stream);
  hw.dram.write_queue_entries = 256;
  const DramReplayResult deep = run_dram_replay(hw, stream);
  const double shallow_ns = shallow.bench.stats.avg_read_latency_ns.value() + shallow.read_wait_outside_ns;
  const double deep_ns = deep.bench.stats.avg_read_latency_ns.value() + deep.read_wait_outside_ns;
  // The same bytes either way (4096 lines each way).
  EXPECT_EQ(shallow.bench.stats.read_bytes.value(), 4096u * 64);
  EXPECT_EQ(deep.bench.stats.write_bytes.value(), 4096u * 64);
  // Reads first: read latency from arrival falls by more than half (measured 736 -> 169 ns).
  EXPECT_LT(deep_ns, 0.5 * shallow_ns) << "shallow " << shallow_ns << " ns, deep " << deep_ns << " ns";
  // Both move the same bytes in about the same time (measured 52.25 and 52.15 us): within 5 %
  // (the order changes, the work does not).
  EXPECT_NEAR(deep.bench.ns / shallow.bench.ns, 1.0, 0.05);
}

TEST(DramReplay, BadFilesAreRefusedWithTheirLine) {
  const auto dir = testing_scratch::scratch_dir("dram_replay", "bad");
  const auto write = [&](const std::string& name, const std::string& text) {
    const std::string p = (dir / name).string();
    std::ofstream(p) << text;
    return p;
  };
  const struct {
    std::string text, expect;
  } cases[] = {
      {"0x40 READ 0\n0x80 FETCH 1\n", ":2: expected READ or WRITE, got 'FETCH'"},
      {"0x40 READ 5\n0x80 READ 4\n", ":2: cycle 4 before the previous line's 5"},
      {"40 READ 0\n", ":1: expected a hexadecimal address 0x..., got '40'"},
      {"0x40 READ\n", ":1: expected '0xADDR READ|WRITE CYCLE'"},
      {"0x40 READ 1 extra\n", ":1: unexpected 'extra' after the cycle"},
      {"# only a comment\n", "no requests in the replay file"},
  };
  int i = 0;
  for (const auto& c : cases) {
    const std::string p = write("bad" + std::to_string(i++) + ".trace", c.text);
    const auto r = run_cli({"dram-bench", "--replay", p});
    EXPECT_EQ(r.code, 2) << c.text;
    EXPECT_NE(r.err.find(p), std::string::npos) << r.err;
    EXPECT_NE(r.err.find(c.expect), std::string::npos) << r.err;
    EXPECT_EQ(r.out, "") << c.text;
  }
  const auto missing = run_cli({"dram-bench", "--replay", (dir / "none.trace").string()});
  EXPECT_EQ(missing.code, 2);
  // One byte past 256 MiB (a sparse file: nothing is read): refused by its size.
  const std::string big = write("big.trace", "0x40 READ 0\n");
  fs::resize_file(big, (std::uintmax_t{1} << 28) + 1);
  const auto too_big = run_cli({"dram-bench", "--replay", big});
  EXPECT_EQ(too_big.code, 2);
  EXPECT_NE(too_big.err.find("268435457 bytes, more than the 268435456 (256 MiB) a replay file may have"), std::string::npos)
      << too_big.err;
}

}  // namespace
}  // namespace tbdr
