// Parameter effects: the DRAM data rate has one source (dram.clock_mhz x transfers_per_clock x
// bus_width_bits x channels, the peak bandwidth derived from it), every preset keeps its peak, the
// removed dram.bandwidth_gbps is refused with what replaced it, and the clock moves a DRAM-bound
// frame by the size the arithmetic gives. bench/param_effects.sh measures every parameter.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iostream>
#include <string>
#include <vector>

#include "cli_run.hpp"
#include "kernel/event_queue.hpp"
#include "models/dram.hpp"
#include "models/dram_microbench.hpp"
#include "models/hw_config.hpp"
#include "synthetic_scene.hpp"
#include "timed_run.hpp"

namespace tbdr {
namespace {

using namespace synthetic;
using testing_support::run_cli;

std::string preset(const std::string& name) { return std::string(TBDRSIM_SOURCE_DIR) + "/configs/" + name + ".ini"; }

TEST(DramDataRate, EveryPresetKeepsItsPeakBandwidth) {
  // Before, each preset set dram.bandwidth_gbps; now it is derived:
  //   defaults = series6xt_gx6450, series6xt_gx6250 (LPDDR3-1600 2x32): 800 MHz x 2 x 32 / 8 x 2 = 12.8 GB/s
  //   mobile_16x16_lpddr4x (LPDDR4X-4266 2x32): 2133 MHz x 2 x 32 / 8 x 2 = 34.128 GB/s (was set as 34.1, rounded)
  //   dram_lpddr5_6400(_bg) (4x16, WCK 4:1): 800 MHz x 8 x 16 / 8 x 4 = 51.2 GB/s
  struct Case {
    std::vector<std::string> files;
    double peak_gbps;
    double old_gbps;  // the removed dram.bandwidth_gbps of the preset
  };
  const std::vector<Case> cases = {
      {{}, 12.8, 12.8},
      {{preset("series6xt_gx6450")}, 12.8, 12.8},
      {{preset("series6xt_gx6250")}, 12.8, 12.8},
      {{preset("mobile_16x16_lpddr4x")}, 34.128, 34.1},
      {{preset("mobile_16x16_lpddr4x"), preset("dram_lpddr5_6400")}, 51.2, 51.2},
      {{preset("mobile_16x16_lpddr4x"), preset("dram_lpddr5_6400_bg")}, 51.2, 51.2},
  };
  for (const Case& c : cases) {
    const HwConfig hw = resolve_config(c.files, {}).hw;
    const std::string what = c.files.empty() ? "defaults" : c.files.back();
    EXPECT_NEAR(hw.dram.peak_bandwidth_gbps(), c.peak_gbps, 1e-9) << what;
    EXPECT_NEAR(hw.dram.peak_bandwidth_gbps() / c.old_gbps, 1.0, 1e-3) << what << ": within 0.1 % of the old figure";
    // The burst time, the model's only use of the rate: bit-identical to the old bandwidth_gbps
    // arithmetic where the figure was exact (LPDDR3: 32 B at 6.4 GB/s = 5000 ps; LPDDR5 8B mode:
    // 64 B at 12.8 GB/s = 5000 ps, BG mode 32 B = 2500 ps).
    EventQueue eq;
    const Dram dram(hw.dram, hw.energy, eq);
    const double old_burst_ps =
        static_cast<double>(hw.dram.burst_bytes) * 1000.0 / (c.old_gbps / static_cast<double>(hw.dram.channels));
    if (c.peak_gbps == c.old_gbps) {
      EXPECT_EQ(dram.timing().burst_ps, old_burst_ps) << what;
    } else {
      EXPECT_NEAR(dram.timing().burst_ps / old_burst_ps, 34.1 / 34.128, 1e-12) << what;  // 1876.8 -> 1875.3 ps
    }
    EXPECT_EQ(dram.stats().peak_bandwidth_gbps.value(), hw.dram.peak_bandwidth_gbps()) << what;
  }
}

TEST(DramDataRate, RemovedBandwidthKeyIsRefusedWithWhatReplacedIt) {
  const auto dir = std::filesystem::temp_directory_path() / "tbdrsim_test_param_effects";
  std::filesystem::create_directories(dir);
  const std::string cfg = (dir / "old.ini").string();
  std::ofstream(cfg) << "[dram]\nclock_mhz = 800\nbandwidth_gbps = 12.8\n";
  const auto r = run_cli({"params", "--config", cfg});
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find(cfg + ":3"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("'dram.bandwidth_gbps' was removed"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("dram.clock_mhz x dram.transfers_per_clock x dram.bus_width_bits / 8 x dram.channels"),
            std::string::npos)
      << r.err;
  const auto s = run_cli({"params", "--set", "dram.bandwidth_gbps=34"});
  EXPECT_EQ(s.code, 2);
  EXPECT_NE(s.err.find("--set dram.bandwidth_gbps=34"), std::string::npos) << s.err;
  EXPECT_NE(s.err.find("was removed"), std::string::npos) << s.err;
}

TEST(DramDataRate, ParamsPrintsTheDerivedPeak) {
  const auto d = run_cli({"params"});
  ASSERT_EQ(d.code, 0) << d.err;
  EXPECT_NE(d.out.find("dram peak bandwidth  12.8 GB/s"), std::string::npos) << d.out;
  EXPECT_NE(d.out.find("= 800 MHz x 2 x 32 / 8 x 2 (1600 MT/s per pin)"), std::string::npos) << d.out;
  const auto l5 = run_cli({"params", "--config", preset("dram_lpddr5_6400"), "--set", "dram.clock_mhz=400"});
  ASSERT_EQ(l5.code, 0) << l5.err;
  // 400 MHz x 8 x 16 / 8 x 4 = 25.6 GB/s: halving the clock halves the peak.
  EXPECT_NE(l5.out.find("dram peak bandwidth  25.6 GB/s"), std::string::npos) << l5.out;
}

TEST(DramDataRate, RunSummaryShowsThePeak) {
  const auto dir = std::filesystem::temp_directory_path() / "tbdrsim_test_param_effects";
  std::filesystem::create_directories(dir);
  const std::string trace = (dir / "pf.trace").string(), db = (dir / "pf.db").string();
  std::filesystem::remove(db);
  ASSERT_EQ(run_cli({"trace", "--technique", "plain_forward", "--scene", "atrium:1", "--lights", "8", "--resolution",
                     "64x36", "--out", trace})
                .code,
            0);
  const auto r = run_cli({"run", "--trace", trace, "--db", db, "--set", "dram.clock_mhz=400"});
  ASSERT_EQ(r.code, 0) << r.err;
  // 400 MHz x 2 x 32 / 8 x 2 = 6.4 GB/s.
  EXPECT_NE(r.out.find("GB/s achieved of 6.40 GB/s peak"), std::string::npos) << r.out;
}

TEST(DramDataRate, BurstMustBeWholeTransfers) {
  // 32 B bursts on a 96-bit bus would be 2.67 transfers.
  const HwConfig hw = resolve_config({}, {"dram.bus_width_bits=96"}).hw;
  EventQueue eq;
  EXPECT_THROW(Dram(hw.dram, hw.energy, eq), std::invalid_argument);
}

TEST(DramDataRate, ClockSetsTheStreamTime) {
  // 65536 streamed 64 B lines (4 MiB) on LPDDR3 2x32: at 800 MHz 4 MiB / 12.8 GB/s = 327.7 us over
  // refresh efficiency; at 400 MHz the bus moves half as much per ns (6.4 GB/s) and the refresh
  // losses stay in ns, so the stream takes about twice as long; at 1600 MHz about half.
  const auto stream_ns = [](const std::string& mhz) {
    return run_dram_microbench(resolve_config({}, {"dram.clock_mhz=" + mhz}).hw, DramPattern::Stream, 65536).ns;
  };
  const double at400 = stream_ns("400"), at800 = stream_ns("800"), at1600 = stream_ns("1600");
  std::cout << "[ figures  ] stream of 4 MiB: " << at400 << " / " << at800 << " / " << at1600 << " ns at 400 / 800 / 1600 MHz\n";
  EXPECT_NEAR(at400 / at800, 2.0, 0.1) << at400 << " vs " << at800 << " ns";
  EXPECT_NEAR(at800 / at1600, 2.0, 0.15) << at800 << " vs " << at1600 << " ns";
}

TEST(DramDataRate, TransfersPerClockAndBusWidthAreOneRate) {
  // At one command clock, twice the transfers per clock and twice the bus width give the same
  // burst time (32 B: 2500 ps on 2 x 12.8 GB/s instead of 5000 ps), hence the same stream to the
  // picosecond; both halve the default stream time up to the fixed ns costs (refresh, row opens).
  const auto stream_ns = [](const std::string& set, double burst_ps) {
    const HwConfig hw = resolve_config({}, {set}).hw;
    EventQueue eq;
    EXPECT_EQ(Dram(hw.dram, hw.energy, eq).timing().burst_ps, burst_ps) << set;
    return run_dram_microbench(hw, DramPattern::Stream, 65536).ns;
  };
  const double base = stream_ns("dram.transfers_per_clock=2", 5000.0);
  const double tpc = stream_ns("dram.transfers_per_clock=4", 2500.0), width = stream_ns("dram.bus_width_bits=64", 2500.0);
  EXPECT_EQ(tpc, width);
  EXPECT_NEAR(base / tpc, 2.0, 0.15) << base << " vs " << tpc << " ns";
}

TEST(DramDataRate, ClockMovesADramBoundFrame) {
  // One cheap full-frame quad at 256x256 writing 8 rgba32f targets that are all stored: 256 x 256 x
  // 128 B = 8 MiB. At 800 MHz (12.8 GB/s) the DRAM needs 8388608 / 12.8 GB/s = 655.4 us = 393 k
  // cycles at 600 MHz, over the ~95 % refresh leaves (tWR + tRP + tRFC + tRCD + RL of every tREFI):
  // ~414 k cycles; the pixel back end needs 262 k. At 400 MHz (6.4 GB/s) the DRAM time doubles:
  // ~829 k cycles, ratio ~2. At 1600 MHz (25.6 GB/s) the DRAM needs ~207 k cycles, under the back
  // end: the frame falls to ~262 k, 800 / 1600 ~ 1.58.
  Scene s = base_scene();
  Trace t = base_trace();
  t.frame.width = t.frame.height = 256;
  t.shaders[0].alu_ops = 1;
  t.shaders[0].tex_fetches = 0;
  add_quad(s, "wall", 3, -512, 1024, 0);
  PassDesc p = base_pass();
  p.draws = {draw_of("wall")};
  p.attachments[0].format = Format::Rgba32f;
  for (int i = 1; i < 8; ++i) {
    Attachment a = p.attachments[0];
    a.name = "mrt" + std::to_string(i);
    p.attachments.push_back(a);
  }
  t.shaders[0].color_outputs = 8;
  t.commands.push_back(p);
  const auto cycles = [&](const std::string& mhz) {
    const Timed r = run_timed(t, s, {"pls.tile_buffer_bits_per_pixel=2048", "dram.clock_mhz=" + mhz});
    EXPECT_EQ(r.frame.dram.writes(DramClass::Color), 256u * 256u * 128u);
    return r.timing.frame_cycles;
  };
  const double at400 = cycles("400"), at800 = cycles("800"), at1600 = cycles("1600");
  std::cout << "[ figures  ] store-bound frame: " << at400 << " / " << at800 << " / " << at1600
            << " cycles at 400 / 800 / 1600 MHz\n";
  const DramParams d = resolve_config({}, {}).hw.dram;
  const double refresh = 1.0 - (d.t_wr_ns + d.t_rp_ns + d.t_rfc_ns + d.t_rcd_ns + d.t_cl_ns) / d.t_refi_ns;
  const double bound800 = 256.0 * 256 * 128 / 12.8e9 * 600e6 / refresh;
  EXPECT_NEAR(at800, bound800, 0.05 * bound800);
  EXPECT_NEAR(at400 / at800, 2.0, 0.1) << at400 << " vs " << at800 << " cycles";
  EXPECT_GT(at800 / at1600, 1.3) << at800 << " vs " << at1600 << " cycles";
  EXPECT_LT(at800 / at1600, 2.0) << "the pixel back end bounds the frame at 1600 MHz";
}

}  // namespace
}  // namespace tbdr
