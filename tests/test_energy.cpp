// The energy model's scaling with hardware and process: leakage summed over the configured units
// and SRAM arrays (CACTI by size), Stillmaker & Baas node scaling of the 45 nm per-op figures, DRAM
// power-down by default, and the energy of a fixed frame period against race to idle.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "atrium_trace_setup.hpp"
#include "cli_run.hpp"
#include "file_text.hpp"
#include "db_query.hpp"
#include "scratch_dir.hpp"
#include "app/run_driver.hpp"
#include "models/dram_memspec.hpp"
#include "models/dram_microbench.hpp"
#include "models/energy.hpp"
#include "models/hw_config.hpp"
#include "models/sram_energy.hpp"
#include "models/sram_energy_table.hpp"
#include "stat_lookup.hpp"
#include "timed_run.hpp"

namespace tbdr {
namespace {

HwConfig config(const std::vector<std::string>& sets = {}) { return resolve_config({}, sets).hw; }

/// The shipped config file `name` (configs/<name>.ini in the source tree).
std::string config_file(const std::string& name) { return std::string(TBDRSIM_SOURCE_DIR) + "/configs/" + name + ".ini"; }

/// The CACTI point of `kind` at `node` nm and `size` bytes (the test fails when it is missing).
const SramPoint* cacti_point(SramArray kind, int node, double size) {
  for (const SramPoint& p : kCactiSramTable) {
    if (p.kind == kind && p.node_nm == node && p.size_bytes == size) return &p;
  }
  ADD_FAILURE() << "no CACTI point " << node << " nm " << size << " B";
  return nullptr;
}

TEST(SramEnergy, TablePointsAreReadBackAndInterpolatedInSizeAndNode) {
  // On a table point the lookup is the point: CACTI 32 nm 128 KiB cache, 51.3154 pJ per 64 B read
  // = 0.80180 pJ/B, leakage 1.42498 mW.
  const SramPoint* p = cacti_point(SramArray::Cache, 32, 131072);
  ASSERT_NE(p, nullptr);
  SramCost c = sram_cost(SramArray::Cache, 131072, 32, 0.9);
  EXPECT_NEAR(c.read_pj_per_byte, p->read_pj / 64.0, 1e-9);
  EXPECT_NEAR(c.write_pj_per_byte, p->write_pj / 64.0, 1e-9);
  EXPECT_NEAR(c.leakage_mw, p->leakage_mw, 1e-9);
  // Between sizes: log-log, so 181 KiB (the geometric mean of 128 and 256 KiB) gets the geometric mean.
  const SramPoint* q = cacti_point(SramArray::Cache, 32, 262144);
  ASSERT_NE(q, nullptr);
  c = sram_cost(SramArray::Cache, std::sqrt(131072.0 * 262144.0), 32, 0.9);
  EXPECT_NEAR(c.read_pj_per_byte, std::sqrt(p->read_pj * q->read_pj) / 64.0, 1e-9);
  EXPECT_NEAR(c.leakage_mw, std::sqrt(p->leakage_mw * q->leakage_mw), 1e-9);
  // Between nodes: linear, 28 nm = 22 + 0.6 x (32 - 22).
  const SramPoint* r = cacti_point(SramArray::Cache, 22, 131072);
  ASSERT_NE(r, nullptr);
  c = sram_cost(SramArray::Cache, 131072, 28, 0.9);
  EXPECT_NEAR(c.leakage_mw, r->leakage_mw + 0.6 * (p->leakage_mw - r->leakage_mw), 1e-9);
  EXPECT_NEAR(c.read_pj_per_byte, (r->read_pj + 0.6 * (p->read_pj - r->read_pj)) / 64.0, 1e-9);
}

TEST(SramEnergy, ABiggerSlcCostsMorePerByteAndLeaksMore) {
  // The SLC's figures follow its configured size (was 12.5 pJ/B and no leakage at any size).
  // 28 nm: 0.4 x CACTI 22 nm + 0.6 x 32 nm; 128 KiB ~0.6 pJ/B and ~2 mW, 8 MiB ~6 pJ/B and ~40 mW.
  const HwConfig small = config({"cache.slc.size_bytes=131072"});
  const HwConfig big = config({"cache.slc.size_bytes=8388608"});
  const double e_small = on_chip_pj_per_byte(small, OnChipArray::Slc);
  const double e_big = on_chip_pj_per_byte(big, OnChipArray::Slc);
  const double l_small = on_chip_leakage_mw(small, OnChipArray::Slc);
  const double l_big = on_chip_leakage_mw(big, OnChipArray::Slc);
  std::printf("[ figures  ] SLC 128 KiB: %.3f pJ/B, %.3f mW; 8 MiB: %.3f pJ/B, %.3f mW\n", e_small, l_small, e_big, l_big);
  EXPECT_GT(e_big / e_small, 4.0);
  EXPECT_GT(l_big / l_small, 10.0);
  // And the static power of the GPU grows by exactly the SLC's leakage difference.
  EXPECT_NEAR(static_power(big).total_mw() - static_power(small).total_mw(), l_big - l_small, 1e-9);
}

TEST(ProcessScaling, StillmakerBaasFactorsAgainstTheirEquation) {
  // Energy factor a V^2 + b V + c (Stillmaker & Baas 2017). At 45 nm, 0.9 V (Horowitz's point):
  // 1.103 x 0.81 - 0.362 x 0.9 + 0.2767 = 0.89343 - 0.3258 + 0.2767 = 0.84433.
  EXPECT_NEAR(stillmaker_energy_factor(45, 0.9), 0.84433, 1e-5);
  EXPECT_NEAR(process_energy_scale(45, 0.9), 1.0, 1e-12);
  // 32 nm at 0.9 V: 0.9559 x 0.81 - 0.7823 x 0.9 + 0.471 = 0.774279 - 0.70407 + 0.471 = 0.541209;
  // 20 nm: 0.373 x 0.81 - 0.1582 x 0.9 + 0.04104 = 0.30213 - 0.14238 + 0.04104 = 0.20079.
  // 28 nm lies 8/12 of the way from 20 to 32: 0.20079 + (8/12) x (0.541209 - 0.20079) = 0.427736,
  // over 0.84433 = 0.50660: the default node halves Horowitz's 45 nm per-op energies.
  EXPECT_NEAR(process_energy_scale(28, 0.9), 0.427736 / 0.84433, 1e-4);
  // The ALU and texel terms follow: 2.3 pJ x 0.5066 = 1.165 pJ of arithmetic per op at 28 nm.
  const HwConfig hw = config();
  EXPECT_NEAR(hw.energy.alu_op_pj_45nm * process_energy_scale(hw.energy.process_nm, hw.energy.vdd_v), 1.165, 0.001);
  // Halving the node from 45 to 22.5 nm at one voltage costs less energy per op; 65 nm more.
  EXPECT_LT(process_energy_scale(22, 0.9), process_energy_scale(28, 0.9));
  EXPECT_GT(process_energy_scale(65, 0.9), 1.0);
}

/// plain_forward on the atrium (detail 1) from the entrance at 320x180 with 64 lights: every pixel
/// lit by many lights, an ALU-bound frame (the same physics as 960x540 at a ninth of the pixels).
class EnergyFrame : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    scene_ = std::make_unique<Scene>(load_scene("atrium:1"));
    trace_ = std::make_unique<Trace>(
        generate_trace("plain_forward", testing_support::atrium_entrance_setup(*scene_, 64, 320, 180)));
  }
  static void TearDownTestSuite() {
    trace_.reset();
    scene_.reset();
  }
  static Timed timed(const std::vector<std::string>& sets) {
    const HwConfig hw = config(sets);
    Timed r;
    r.frame = simulate_frame(*trace_, "e.trace", *scene_, hw);
    time_frame(hw, r.frame, r.timing, r.energy);
    r.stats = run_rows(r.frame, r.timing, r.energy);
    return r;
  }
  static std::unique_ptr<Scene> scene_;
  static std::unique_ptr<Trace> trace_;
};
std::unique_ptr<Scene> EnergyFrame::scene_;
std::unique_ptr<Trace> EnergyFrame::trace_;

double term_pj(const EnergyBreakdown& b, const std::string& component) {
  for (const auto& t : b.terms) {
    if (t.component == component) return t.pj;
  }
  ADD_FAILURE() << "no energy term " << component;
  return 0;
}

TEST_F(EnergyFrame, EightUscsLeakMoreThanFourAtTheSameFrameTime) {
  // Static energy = leakage x frame time. At the 4-USC frame's time, 8 USCs add 4 x (10 mW of
  // logic + 16 lane slices of 5 KiB register file from CACTI) and 2 texture units (2 x 5 mW).
  const Timed four = timed({"usc.count=4", "texture.units=2"});
  const HwConfig hw4 = config({"usc.count=4", "texture.units=2"});
  const HwConfig hw8 = config({"usc.count=8", "texture.units=4"});
  const double t = four.timing.frame_time_ps;
  const EnergyBreakdown e4 = compute_energy(hw4, four.frame.totals, four.timing.memory, t);
  const EnergyBreakdown e8 = compute_energy(hw8, four.frame.totals, four.timing.memory, t);
  const double rf_usc = on_chip_leakage_mw(hw8, OnChipArray::RegisterFile) / 8.0;  // one USC's register file
  const double extra_mw = 4 * (hw8.energy.usc_leakage_mw + rf_usc) + 2 * hw8.energy.texture_unit_leakage_mw;
  std::printf("[ figures  ] frame %.3f ms; static 4 USCs %.4f mJ (%.1f mW), 8 USCs %.4f mJ (%.1f mW)\n", t * 1e-9,
              term_pj(e4, "static") * 1e-9, e4.leakage.total_mw(), term_pj(e8, "static") * 1e-9, e8.leakage.total_mw());
  EXPECT_GT(term_pj(e8, "static"), term_pj(e4, "static"));
  EXPECT_NEAR(e8.leakage.total_mw() - e4.leakage.total_mw(), extra_mw, 1e-9);
  // mW x ps x 1e-3 = pJ.
  EXPECT_NEAR(term_pj(e8, "static") - term_pj(e4, "static"), extra_mw * t * 1e-3, 1e-6 * extra_mw * t * 1e-3);
  EXPECT_GT(extra_mw, 4 * 10.0 + 2 * 5.0);
  // The frame's own run with 8 USCs is shorter (ALU-bound), yet its static energy is the product too.
  const Timed eight = timed({"usc.count=8", "texture.units=4"});
  EXPECT_LT(eight.timing.frame_time_ps, t);
  EXPECT_NEAR(term_pj(eight.energy, "static"), e8.leakage.total_mw() * eight.timing.frame_time_ps * 1e-3, 1e-3);
}

TEST_F(EnergyFrame, AnEightMiBSlcHasMoreStaticEnergyThanA128KiBOne) {
  const Timed small = timed({"cache.slc.size_bytes=131072"});
  const Timed big = timed({"cache.slc.size_bytes=8388608"});
  const double s_small = term_pj(small.energy, "static"), s_big = term_pj(big.energy, "static");
  std::printf("[ figures  ] SLC 128 KiB: static %.4f mJ over %.3f ms; 8 MiB: %.4f mJ over %.3f ms\n", s_small * 1e-9,
              small.timing.frame_time_ps * 1e-9, s_big * 1e-9, big.timing.frame_time_ps * 1e-9);
  EXPECT_GT(s_big, s_small);
  // At the same frame time the difference is the SLC's leakage difference alone.
  const HwConfig hs = config({"cache.slc.size_bytes=131072"}), hb = config({"cache.slc.size_bytes=8388608"});
  const double diff_mw = on_chip_leakage_mw(hb, OnChipArray::Slc) - on_chip_leakage_mw(hs, OnChipArray::Slc);
  const EnergyBreakdown at_small_time = compute_energy(hb, small.frame.totals, small.timing.memory, small.timing.frame_time_ps);
  EXPECT_NEAR(term_pj(at_small_time, "static") - s_small, diff_mw * small.timing.frame_time_ps * 1e-3, 1e-3);
}

TEST_F(EnergyFrame, DefaultPowerDownKeepsAnAluBoundFramesDramEnergyPerBitInTheMemspecRange) {
  // With power-down on by default (dram.powerdown_after_ns = 7.5 ns) the idle channels of an
  // ALU-bound frame draw IDD2P/IDD3P instead of IDD2N/IDD3N between requests.
  const Timed on = timed({});
  const Timed off = timed({"dram.powerdown_after_ns=0"});
  const auto& st = on.stats;
  const double bits = (stat(st, "mem/dram", "read_bytes") + stat(st, "mem/dram", "write_bytes")) * 8.0;
  const double per_bit_on = stat(st, "mem/dram", "energy_pj") / bits;
  const double per_bit_off = stat(off.stats, "mem/dram", "energy_pj") /
                             ((stat(off.stats, "mem/dram", "read_bytes") + stat(off.stats, "mem/dram", "write_bytes")) * 8.0);
  const double usc_util = stat(st, "frame/unit.usc", "utilization");
  // The range: DRAMPower memspec MICRON_4Gb_LPDDR3-1600_32bit_A through memspec_per_bit (see
  // tests/test_dram_presets.cpp): a streaming read 10.4 pJ/bit (5.14 core + 3.8 I/O + activates +
  // standby and refresh at 95 % of the bus) to random lines 19.0 pJ/bit (an activate per 64 B line).
  const MemspecPerBit m = preset_memspec_per_bit(dram_preset_memspecs()[0], config());
  std::printf("[ figures  ] ALU-bound frame (USC utilisation %.2f): DRAM %.2f pJ/bit with power-down, %.2f without; "
              "memspec range %.2f .. %.2f\n",
              usc_util, per_bit_on, per_bit_off, m.stream_pj, m.random_pj);
  EXPECT_GT(usc_util, 0.5) << "the frame must be ALU-bound";
  EXPECT_GE(per_bit_on, m.stream_pj);
  EXPECT_LE(per_bit_on, m.random_pj);
  // Without power-down the idle bus stands by at IDD2N/IDD3N: measured 19.1 against 12.3 pJ/bit.
  EXPECT_GT(per_bit_off, 1.3 * per_bit_on) << "without power-down standby dominates an idle bus";
  EXPECT_GT(stat(st, "mem/dram", "powerdown_exits"), 0.0);
}

TEST_F(EnergyFrame, AFixedFramePeriodAddsIdlePowerTimesIdleTime) {
  const Timed race = timed({});
  const double frame_ps = race.timing.frame_time_ps;
  // A period 4 ms longer than the frame: idle_ps = 4e9 ps.
  const double period_us = frame_ps * 1e-6 + 4000.0;
  const Timed period = timed({"gpu.frame_period_us=" + std::to_string(period_us)});
  const HwConfig hw = config();
  ASSERT_EQ(period.timing.frame_time_ps, frame_ps);
  const EnergyBreakdown& e = period.energy;
  EXPECT_DOUBLE_EQ(e.total_pj, race.energy.total_pj) << "the frame itself is unchanged";
  EXPECT_NEAR(e.idle_ps, 4e9, 1e3);  // std::to_string keeps 6 decimals of a us
  EXPECT_GE(e.at_period_total_pj(), race.energy.at_period_total_pj());
  EXPECT_EQ(race.energy.idle_pj(), 0.0);
  EXPECT_DOUBLE_EQ(race.energy.at_period_total_pj(), race.energy.total_pj);
  // GPU: (logic + gated SRAM) x 0.1 + caches in full, over idle_ps (mW x ps x 1e-3 = pJ).
  const StaticPower s = static_power(hw);
  const double gpu_mw = (s.logic_mw + s.sram_gated_mw) * 0.1 + s.sram_retained_mw;
  // DRAM, per channel (2), in ns: 7.5 ns precharge standby 49.2 mW, then precharge power-down
  // 2.1 mW until the next refresh (3900 ns), then self-refresh 5.72 mW; refresh 26.8 nJ / 3900 ns
  // = 6.872 mW while not in self-refresh.
  const double t_ns = e.idle_ps * 1e-3;
  const double refresh_mw = 26.8 / 3900.0 * 1000.0;
  const double dram_pj = 2 * ((49.2 + refresh_mw) * 7.5 + (2.1 + refresh_mw) * 3900.0 + 5.72 * (t_ns - 7.5 - 3900.0));
  const double idle_pj = gpu_mw * e.idle_ps * 1e-3 + dram_pj;
  EXPECT_NEAR(e.idle_gpu_pj, gpu_mw * e.idle_ps * 1e-3, 1e-6 * idle_pj);
  EXPECT_NEAR(e.idle_dram_pj, dram_pj, 1e-6 * dram_pj);
  EXPECT_NEAR(e.at_period_total_pj() - race.energy.total_pj, idle_pj, 1e-6 * idle_pj);
  // The records: at_period_total_mj = total_mj + idle_mj; idle_power_mw = idle_mj / idle_time_ms.
  const auto& st = period.stats;
  EXPECT_NEAR(stat(st, "frame/energy", "at_period_total_mj"), stat(st, "frame/energy", "total_mj") + idle_pj * 1e-9, 1e-12);
  EXPECT_NEAR(stat(st, "frame/energy", "idle_power_mw"), idle_pj / (e.idle_ps * 1e-3), 1e-6);
  std::printf("[ figures  ] frame %.3f ms %.4f mJ; at a %.3f ms period %.4f mJ (idle %.1f mW: GPU %.1f, DRAM %.2f)\n",
              frame_ps * 1e-9, e.total_pj * 1e-9, period_us * 1e-3, e.at_period_total_pj() * 1e-9,
              idle_pj / (e.idle_ps * 1e-3), gpu_mw, dram_pj / (e.idle_ps * 1e-3));
  // Self-refresh off: power-down with refreshes for the whole idle time costs more.
  const HwConfig no_sr = config({"dram.self_refresh_mw=0"});
  EXPECT_GT(dram_idle_pj(no_sr.dram, e.idle_ps), e.idle_dram_pj);
  // A period shorter than the frame: no idle time, at_period = race to idle.
  const Timed short_period = timed({"gpu.frame_period_us=1"});
  EXPECT_EQ(short_period.energy.idle_ps, 0.0);
  EXPECT_DOUBLE_EQ(short_period.energy.at_period_total_pj(), short_period.energy.total_pj);
}

TEST(DramRails, EveryPresetChargesIoStandbyAndSelfRefreshOnItsOwnVddq) {
  // The LPDDR4 die (DRAMSys memspec MICRON_6Gb_LPDDR4-3200_32bit_A): read I/O (idd4rq 150 - idd3nq
  // 0.75) mA over a 5 ns BL16 burst of 256 bits; self-refresh idd61 0.3 mA x 1.8 V + idd62 0.5 mA x
  // 1.1 V + idd6q 0.1 mA x VDDQ. LPDDR3 (DRAMPower MICRON_4Gb_LPDDR3-1600_32bit_A, no VDDQ currents):
  // idd6 1.0 mA x 1.8 V + idd62 3.27 mA x 1.2 V = 5.724 mW.
  const auto io = [](double vddq) { return 149.25 * vddq * 5.0 / 256.0; };
  const auto sr = [](double vddq) { return 0.3 * 1.8 + 0.5 * 1.1 + 0.1 * vddq; };
  const HwConfig lp3 = config();
  EXPECT_NEAR(lp3.dram.self_refresh_mw, 1.0 * 1.8 + 3.27 * 1.2, 0.01);
  // LPDDR4X: VDDQ 0.6 V (JESD209-4-1) for I/O as for standby; two x16 dies per modelled channel.
  const HwConfig lp4x = resolve_config({config_file("mobile_16x16_lpddr4x")}, {}).hw;
  EXPECT_NEAR(lp4x.energy.dram_io_pj_per_bit, io(0.6), 0.01);  // 1.749
  EXPECT_NEAR(lp4x.dram.self_refresh_mw, 2 * sr(0.6), 0.01);    // 2 x 1.15
  // Standby's VDDQ share is the same 0.6 V: 2 x (2.25 x 1.8 + 30 x 1.1 + 0.75 x 0.6) = 75.0 mW.
  EXPECT_NEAR(lp4x.dram.active_standby_mw, 2 * (2.25 * 1.8 + 30 * 1.1 + 0.75 * 0.6), 0.01);
  // LPDDR5 presets: the same die at LPDDR5's VDDQ 0.5 V, one per x16 channel.
  for (const char* cfg : {"dram_lpddr5_6400", "dram_lpddr5_6400_bg"}) {
    const HwConfig lp5 = resolve_config({config_file("mobile_16x16_lpddr4x"), config_file(cfg)}, {}).hw;
    EXPECT_NEAR(lp5.energy.dram_io_pj_per_bit, io(0.5), 0.01) << cfg;  // 1.458
    EXPECT_NEAR(lp5.dram.self_refresh_mw, sr(0.5), 0.01) << cfg;       // 1.14
    EXPECT_NEAR(lp5.dram.active_standby_mw, 2.25 * 1.8 + 30 * 1.1 + 0.75 * 0.5, 0.05) << cfg;
  }
}

TEST(EnergyParams, EveryEnergyConstantNamesASource) {
  // `tbdrsim params`: every [energy] key (and the new frame-period and self-refresh keys) states a
  // source or why the value was chosen.
  const auto& table = hw_params().table();
  int seen = 0;
  for (const auto& p : table.decls()) {
    const std::string& key = p.key;
    if (key.rfind("energy.", 0) != 0 && key != "gpu.frame_period_us" && key != "dram.self_refresh_mw" &&
        key != "dram.powerdown_after_ns")
      continue;
    ++seen;
    EXPECT_GT(p.source.size(), 10u) << key;
  }
  EXPECT_EQ(seen, 17);  // 14 [energy] keys + the three above
}

}  // namespace
}  // namespace tbdr

namespace tbdr {
namespace {

namespace fs = std::filesystem;
const testing_scratch::ScratchCleanup energy_docs_scratch_cleanup{"energy"};

/// Whether `measured` rounds to the figure `quoted` (as docs print it: as many decimals as shown).
bool rounds_to(double measured, const std::string& quoted) {
  const auto dot = quoted.find('.');
  const int decimals = dot == std::string::npos ? 0 : static_cast<int>(quoted.size() - dot - 1);
  return std::fabs(measured - std::stod(quoted)) <= 0.5 * std::pow(10.0, -decimals) + 1e-12;
}

// docs/energy.md's measured table ("plain_forward, atrium:3, 256 lights, 960x540", usc.count 1, 4,
// 8) quotes what the model computes now: each "now" figure (total, static and its power, DRAM and
// its pJ per bit moved, ALU) and the frame times above it, to the decimals printed. A change that
// moves one of them fails here until the doc is measured again. (The "before" column is history.)
TEST(DocsEnergyTable, TheMeasuredUscTableIsCurrent) {
  const std::string doc = testing_support::read_text(std::string(TBDRSIM_SOURCE_DIR) + "/docs/energy.md");
  const std::regex row(R"(\| (\d+) \| [\d.]+ mJ \| ([\d.]+) mJ \| [\d.]+ -> ([\d.]+) mJ \(([\d.]+) mW\) \| ([\d.]+) mJ \(([\d.]+)(?:; ([\d.]+) mJ of it refresh)?\) \| ([\d.]+) mJ \|)");
  std::smatch times;
  ASSERT_TRUE(std::regex_search(doc, times, std::regex(R"(frame times ([\d.]+), ([\d.]+), ([\d.]+) ms)")));
  const fs::path dir = testing_scratch::scratch_dir("energy", "docs_table");
  const std::string trace = (dir / "pf.trace").string(), db = (dir / "e.db").string();
  ASSERT_EQ(testing_support::run_cli({"trace", "--technique", "plain_forward", "--scene", "atrium:3", "--lights", "256",
                                      "--resolution", "960x540", "--out", trace})
                .code,
            0);
  int rows = 0;
  for (auto it = std::sregex_iterator(doc.begin(), doc.end(), row); it != std::sregex_iterator(); ++it, ++rows) {
    const std::smatch& m = *it;
    const int uscs = std::stoi(m[1]);
    const int texture_units = uscs == 1 ? 1 : uscs / 2;  // the doc's "texture.units 1, 2, 4"
    ASSERT_EQ(testing_support::run_cli({"run", "--trace", trace, "--db", db, "--quiet", "--set", "usc.count=" + std::to_string(uscs),
                                        "--set", "texture.units=" + std::to_string(texture_units)})
                  .code,
              0);
    const std::string last = "(SELECT max(id) FROM runs)";
    const auto value = [&](const std::string& scope, const std::string& name) {
      return testing_support::query_number(db, "SELECT value FROM stats WHERE run_id = " + last + " AND scope = '" + scope +
                                                   "' AND name = '" + name + "'");
    };
    SCOPED_TRACE(std::to_string(uscs) + " USCs: docs/energy.md row " + m.str(0));
    const double bits = (value("mem/dram", "read_bytes") + value("mem/dram", "write_bytes")) * 8.0;
    EXPECT_TRUE(rounds_to(value("frame/energy", "total_mj"), m[2])) << value("frame/energy", "total_mj");
    EXPECT_TRUE(rounds_to(value("frame/energy", "static_pj") * 1e-9, m[3])) << value("frame/energy", "static_pj") * 1e-9;
    EXPECT_TRUE(rounds_to(value("frame/energy", "static_power_mw"), m[4])) << value("frame/energy", "static_power_mw");
    EXPECT_TRUE(rounds_to(value("frame/energy", "dram_pj") * 1e-9, m[5])) << value("frame/energy", "dram_pj") * 1e-9;
    EXPECT_TRUE(rounds_to(value("frame/energy", "dram_pj") / bits, m[6])) << value("frame/energy", "dram_pj") / bits;
    if (m[7].matched) {
      EXPECT_TRUE(rounds_to(value("mem/dram", "energy_refresh_pj") * 1e-9, m[7])) << value("mem/dram", "energy_refresh_pj") * 1e-9;
    }
    EXPECT_TRUE(rounds_to(value("frame/energy", "alu_pj") * 1e-9, m[8])) << value("frame/energy", "alu_pj") * 1e-9;
    EXPECT_TRUE(rounds_to(value("frame/timing", "frame_time_ms"), times[rows + 1])) << value("frame/timing", "frame_time_ms");
  }
  EXPECT_EQ(rows, 3) << "the table's rows for 1, 4 and 8 USCs";
}

}  // namespace
}  // namespace tbdr
