// The DRAM presets against their memspecs (models/dram_memspec), bank groups (LPDDR5 BG mode), and
// the microbenchmarks bench/dram.sh prints (models/dram_microbench). Every expected figure is
// worked out in the comment beside it; lines starting "[ figures  ]" are what the bench shows.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <iostream>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "models/dram.hpp"
#include "models/dram_memspec.hpp"
#include "models/dram_microbench.hpp"
#include "models/hw_config.hpp"
#include "kernel/errors.hpp"
#include "kernel/event_queue.hpp"

namespace tbdr {
namespace {

HwConfig preset(const DramPresetMemspec& p) {
  std::vector<std::string> files;
  for (const auto& c : p.configs) files.push_back(std::string(TBDRSIM_SOURCE_DIR) + "/configs/" + c + ".ini");
  return resolve_config(files, {}).hw;
}

TEST(DramMemspec, Lpddr3DieIsDramPowersArithmetic) {
  // MICRON_4Gb_LPDDR3-1600_32bit_A, tCK 1.25 ns, BL8 on 32 bits: a burst is 256 bits in 4 tCK = 5 ns.
  //   read   (5 - 2) mA x 1.8 V x 5 ns + (260 - 45) mA x 1.2 V x 5 ns = 27 + 1290 = 1317 pJ / 256 = 5.1445 pJ/bit
  //   write  (10 - 2) x 1.8 x 5 + (284 - 45) x 1.2 x 5 = 72 + 1434 = 1506 pJ / 256 = 5.8828 pJ/bit
  //   act + pre, tRAS 36 tCK = 45 ns, tRP 15 tCK = 18.75 ns:
  //     1.8 V x (15 x 63.75 - 2 x 45 - 2 x 18.75) + 1.2 V x (80 x 63.75 - 45 x 45 - 38 x 18.75)
  //     = 1491.75 + 2835 = 4326.75 pJ
  //   refresh, tRFC 104 tCK = 130 ns: 1.8 x 38 x 130 + 1.2 x 115 x 130 = 8892 + 17940 = 26832 pJ
  //   standby: active 1.8 x 2 + 1.2 x 45 = 57.6 mW, precharge 1.8 x 2 + 1.2 x 38 = 49.2 mW
  const MemspecEnergy e = memspec_energy(memspec_lpddr3_1600());
  EXPECT_NEAR(e.read_pj_per_bit, 1317.0 / 256.0, 1e-9);
  EXPECT_NEAR(e.write_pj_per_bit, 1506.0 / 256.0, 1e-9);
  EXPECT_NEAR(e.activate_precharge_nj, 4.32675, 1e-9);
  EXPECT_NEAR(e.refresh_nj, 26.832, 1e-9);
  EXPECT_NEAR(e.active_standby_mw, 57.6, 1e-9);
  EXPECT_NEAR(e.precharge_standby_mw, 49.2, 1e-9);
  EXPECT_EQ(e.io_read_pj_per_bit, 0.0) << "the LPDDR3 memspec gives no VDDQ currents";
  // The default [dram] / [energy] parameters are these figures (rounded within 1 %).
  const HwConfig hw = resolve_config({}, {}).hw;
  EXPECT_NEAR(hw.energy.dram_read_pj_per_bit / e.read_pj_per_bit, 1.0, 0.01);
  EXPECT_NEAR(hw.energy.dram_write_pj_per_bit / e.write_pj_per_bit, 1.0, 0.01);
  EXPECT_NEAR(hw.energy.dram_activate_precharge_nj / e.activate_precharge_nj, 1.0, 0.01);
  EXPECT_NEAR(hw.dram.refresh_nj / e.refresh_nj, 1.0, 0.01);
  EXPECT_NEAR(hw.dram.active_standby_mw / e.active_standby_mw, 1.0, 0.01);
  EXPECT_NEAR(hw.dram.precharge_standby_mw / e.precharge_standby_mw, 1.0, 0.01);
  // Power-down: active 1.8 x 1.2 + 1.2 x 8.15 = 11.94 mW, precharge 1.8 x 0.6 + 1.2 x 0.87 = 2.124 mW.
  EXPECT_NEAR(e.active_powerdown_mw, 11.94, 1e-9);
  EXPECT_NEAR(e.precharge_powerdown_mw, 2.124, 1e-9);
  EXPECT_NEAR(hw.dram.active_powerdown_mw / e.active_powerdown_mw, 1.0, 0.01);
  EXPECT_NEAR(hw.dram.precharge_powerdown_mw / e.precharge_powerdown_mw, 1.0, 0.02);
}

TEST(DramMemspec, Lpddr4DieAndTheLpddr4xPresetBuiltOfTwo) {
  // MICRON_6Gb_LPDDR4-3200_32bit_A, one x16 channel, tCK 0.625 ns, BL16: 256 bits in 8 tCK = 5 ns.
  //   read   VDD2 (275 - 30) mA x 1.1 V x 5 ns = 1347.5 pJ / 256 = 5.2637 pJ/bit (VDD1: 2.25 - 2.25 = 0)
  //   I/O    VDDQ (150 - 0.75) x 1.1 x 5 = 820.875 pJ / 256 = 3.2065 pJ/bit
  //   write  (210 - 30) x 1.1 x 5 = 990 pJ / 256 = 3.8672 pJ/bit
  //   act + pre, tRAS 68 tCK = 42.5 ns, tRPpb 29 tCK = 18.125 ns:
  //     1.8 x (3.5 x 60.625 - 2.25 x 42.5 - 2 x 18.125) + 1.1 x (45 x 60.625 - 30 x 42.5 - 27 x 18.125)
  //     = 144.5625 + 1060.125 = 1204.6875 pJ
  //   refresh, tRFCab 448 tCK = 280 ns: 1.8 x 7.75 x 280 + 1.1 x 60 x 280 = 3906 + 18480 = 22386 pJ
  //   active standby 1.8 x 2.25 + 1.1 x 30 + 1.1 x 0.75 = 37.875 mW
  const MemspecEnergy e = memspec_energy(memspec_lpddr4_3200());
  EXPECT_NEAR(e.read_pj_per_bit, 1347.5 / 256.0, 1e-9);
  EXPECT_NEAR(e.io_read_pj_per_bit, 820.875 / 256.0, 1e-9);
  EXPECT_NEAR(e.write_pj_per_bit, 990.0 / 256.0, 1e-9);
  EXPECT_NEAR(e.activate_precharge_nj, 1.2046875, 1e-9);
  EXPECT_NEAR(e.refresh_nj, 22.386, 1e-9);
  EXPECT_NEAR(e.active_standby_mw, 37.875, 1e-9);
  // The LPDDR4X preset's 32-bit channel is two such dies: an activate opens both (2 x 1204.7 pJ),
  // a refresh refreshes both (2 x 22.386 nJ), both stand by (2 x 37.875 mW at VDDQ 1.1 V; the
  // preset takes LPDDR4X's VDDQ 0.6 V: 2 x (37.875 - 0.75 x 0.5) = 75.0 mW).
  const HwConfig hw = preset(dram_preset_memspecs()[1]);
  EXPECT_NEAR(hw.energy.dram_read_pj_per_bit / e.read_pj_per_bit, 1.0, 0.01);
  // I/O at LPDDR4X's VDDQ 0.6 V, as the standby figures: (150 - 0.75) mA x 0.6 V x 5 ns / 256 bits
  // = 1.749 pJ/bit, the memspec's 3.2065 at 1.1 V x 0.6 / 1.1.
  EXPECT_NEAR(hw.energy.dram_io_pj_per_bit / (e.io_read_pj_per_bit * 0.6 / 1.1), 1.0, 0.01);
  EXPECT_NEAR(hw.energy.dram_activate_precharge_nj / (2 * e.activate_precharge_nj), 1.0, 0.01);
  EXPECT_NEAR(hw.dram.refresh_nj / (2 * e.refresh_nj), 1.0, 0.01);
  EXPECT_NEAR(hw.dram.active_standby_mw, 2 * (e.active_standby_mw - 0.75 * 0.5), 0.01);
  // Power-down likewise: 2 x (1.8 x 1.2 + 1.1 x 9 + 0.6 x 0.75) = 25.02 mW active,
  // 2 x (1.8 x 1.2 + 1.1 x 3 + 0.6 x 0.75) = 11.82 mW precharged (the memspec's at 1.1 V: 12.885 and 6.285 per die).
  EXPECT_NEAR(e.active_powerdown_mw, 12.885, 1e-9);
  EXPECT_NEAR(e.precharge_powerdown_mw, 6.285, 1e-9);
  EXPECT_NEAR(hw.dram.active_powerdown_mw, 2 * (e.active_powerdown_mw - 0.75 * 0.5), 0.03);
  EXPECT_NEAR(hw.dram.precharge_powerdown_mw, 2 * (e.precharge_powerdown_mw - 0.75 * 0.5), 0.03);
}

TEST(DramPresets, EnergyPerBitAndEfficiencyAgainstTheMemspecAndTheTimings) {
  // Each preset reads 4 MiB as a stream and 16384 random 64 B lines (one in-order stream per
  // channel, refresh on). The memspec's figures (memspec_per_bit: see its header for the
  // arithmetic) are the range the model must reproduce: streaming within 3 % (the model's
  // timings are the preset's, the memspec's its own die's), random within 15 % (the model's
  // FR-FCFS controller reaches the activate rate tFAW allows only when its queues hold requests to
  // enough banks). LPDDR3-1600 streaming: 5.14 core + 3.8 I/O + 0.13 activate + 57.6 mW / (51.2
  // Gbit/s x 95.3 %) = 1.18 standby + 0.14 refresh = 10.4 pJ/bit; random: one line per
  // max(tRRD 10, tFAW/4 12.5, tRC/8 8.0, bus 10) = 12.5 ns, 76.9 % of the bus with refresh:
  // 5.14 + 3.8 + 4327 pJ / 512 = 8.45 + 57.6 / 39.4 = 1.46 + 0.17 = 19.0 pJ/bit.
  for (const DramPresetMemspec& p : dram_preset_memspecs()) {
    const HwConfig hw = preset(p);
    ASSERT_EQ(hw.dram.name, p.label);
    const MemspecPerBit m = preset_memspec_per_bit(p, hw);
    const DramBenchResult s = run_dram_microbench(hw, DramPattern::Stream, 65536);
    const DramBenchResult r = run_dram_microbench(hw, DramPattern::Random, 16384);
    // The preset's own arithmetic for the stream: a refresh idles the bus tRP + tRFC + tRCD + RL of
    // every tREFI. With bank groups (LPDDR5 BG: burst 2.5 ns, tCCD_L 5 ns, a 64 B line is k = 2
    // bursts of one bank, tCCD_L apart) the stream reaches between
    //   burst / tCCD_L = 2.5 / 5 = 50 %                 (consecutive lines of one row: one group)
    //   k burst / ((k - 1) tCCD_L + burst) = 5 / 7.5 = 66.7 %  (lines alternating between groups)
    // of the bus before refresh; the per-channel queue holds lines of the next row, in another group.
    const auto& d = hw.dram;
    const double refresh = 1.0 - (d.t_rp_ns + d.t_rfc_ns + d.t_rcd_ns + d.t_cl_ns) / d.t_refi_ns;
    const double burst_ns = static_cast<double>(d.burst_bytes) / d.channel_peak_bandwidth_gbps();
    const bool bg = d.bank_groups > 1 && d.t_ccd_l_ns > burst_ns;
    const double k = 64.0 / static_cast<double>(d.burst_bytes);
    const double low = bg ? refresh * burst_ns / d.t_ccd_l_ns : refresh;
    const double high = bg ? refresh * k * burst_ns / ((k - 1.0) * d.t_ccd_l_ns + burst_ns) : refresh;
    std::cout << "[ figures  ] " << p.label << ": stream " << 100.0 * s.efficiency << " % of peak (timing arithmetic "
              << 100.0 * low << (bg ? " .. " + std::to_string(100.0 * high) : std::string()) << " %), " << s.pj_per_bit
              << " pJ/bit (memspec " << m.stream_pj << "); random " << 100.0 * r.efficiency << " % (memspec timing bound "
              << 100.0 * m.random_efficiency << " %), " << r.pj_per_bit << " pJ/bit (memspec " << m.random_pj << ")\n";
    EXPECT_GE(s.efficiency, 0.99 * low) << p.label;
    EXPECT_LE(s.efficiency, 1.01 * high) << p.label;
    if (!bg) {
      EXPECT_LT(r.efficiency, s.efficiency) << p.label << ": an activate per line costs bandwidth";
      // Background per bit is a share of the stream's energy: a stream at half the bus pays twice.
      EXPECT_NEAR(s.pj_per_bit / m.stream_pj, 1.0, 0.03) << p.label;
    } else {
      EXPECT_GT(s.pj_per_bit, m.stream_pj) << p.label << ": the tCCD_L-bound stream stands by longer per bit";
    }
    EXPECT_NEAR(r.pj_per_bit / m.random_pj, 1.0, 0.15) << p.label;
    EXPECT_GT(r.pj_per_bit, s.pj_per_bit) << p.label << ": an activate per line";
  }
}

/// One channel, 16 banks in 4 groups, 32 B bursts of 2.5 ns (12.8 GB/s: a synthetic 32-bit bus at 3.2
/// transfers per clock), 1 GHz command clock,
/// tCCD_L 5 ns, tCCD_S 2.5 ns, refresh off.
HwConfig bank_group_config(const std::vector<std::string>& sets = {}) {
  std::vector<std::string> all = {"dram.clock_mhz=1000", "dram.channels=1", "dram.banks=16", "dram.bank_groups=4",
                                  "dram.row_bytes=2048", "dram.burst_bytes=32", "dram.transfers_per_clock=3.2", "dram.bus_width_bits=32",
                                  "dram.t_rcd_ns=18", "dram.t_rp_ns=18", "dram.t_cl_ns=20", "dram.t_ras_ns=42",
                                  "dram.t_rrd_ns=5", "dram.t_faw_ns=20", "dram.t_ccd_l_ns=5", "dram.t_ccd_s_ns=2.5",
                                  "dram.t_refi_ns=0", "dram.controller_latency_ns=10",
                                  "dram.read_queue_entries=64", "dram.address_mapping=row_bank_channel_column"};
  all.insert(all.end(), sets.begin(), sets.end());
  return resolve_config({}, all).hw;
}

/// Completion ticks of 64 reads of 32 B alternating between row 0 of `bank_a` and of `bank_b`
/// (consecutive columns in each), all queued at t = 0.
std::vector<std::int64_t> alternating_reads(const HwConfig& hw, std::uint32_t bank_a, std::uint32_t bank_b, Dram** stats_of = nullptr,
                                            EventQueue* eq_out = nullptr) {
  EventQueue local;
  EventQueue& eq = eq_out ? *eq_out : local;
  auto* d = new Dram(hw.dram, hw.energy, eq);
  std::vector<std::int64_t> done(64, -1);
  for (int i = 0; i < 64; ++i) {
    const std::uint64_t bank = i % 2 == 0 ? bank_a : bank_b;
    const std::uint64_t addr = bank * 2048 + static_cast<std::uint64_t>(i / 2) * 32;  // row 0 | bank | column
    EXPECT_TRUE(d->enqueue(DramRequest{addr, 32, false, DramClass::Other, [&done, &eq, i] { done[static_cast<std::size_t>(i)] = eq.now().ps(); }}));
  }
  eq.run();
  if (stats_of) {
    *stats_of = d;
  } else {
    delete d;
  }
  return done;
}

TEST(DramBankGroups, SameGroupColumnsAreTccdLApartOtherGroupsTccdS) {
  // Banks 0 and 4 are in group 0 (bank mod 4); banks 0 and 1 in groups 0 and 1. Once both rows are
  // open, reads alternate between the two banks:
  //   same group:   each burst waits tCCD_L = 5 ns after the previous one (the bus would take 2.5)
  //   other groups: tCCD_S = 2.5 ns = the burst: back to back on the bus
  // so the last 32 reads complete 31 x 5 = 155 ns, or 31 x 2.5 = 77.5 ns, after the 33rd.
  EventQueue eq_same, eq_other;
  Dram* same = nullptr;
  Dram* other = nullptr;
  const auto t_same = alternating_reads(bank_group_config(), 0, 4, &same, &eq_same);
  const auto t_other = alternating_reads(bank_group_config(), 0, 1, &other, &eq_other);
  std::unique_ptr<Dram> keep_same(same), keep_other(other);
  for (int i = 33; i < 64; ++i) {
    EXPECT_EQ(t_same[static_cast<std::size_t>(i)] - t_same[static_cast<std::size_t>(i - 1)], 5000) << i;
    EXPECT_EQ(t_other[static_cast<std::size_t>(i)] - t_other[static_cast<std::size_t>(i - 1)], 2500) << i;
  }
  EXPECT_GT(same->stats().bursts_delayed_ccd.value(), 32u);
  EXPECT_EQ(other->stats().bursts_delayed_ccd.value(), 0u) << "tCCD_S equals the burst: never beyond the bus";
  // Without bank groups (one group, tCCD_L 0) banks 0 and 4 stream back to back as well.
  const auto t_plain = alternating_reads(bank_group_config({"dram.bank_groups=1", "dram.t_ccd_l_ns=0", "dram.t_ccd_s_ns=0"}), 0, 4);
  for (int i = 33; i < 64; ++i) EXPECT_EQ(t_plain[static_cast<std::size_t>(i)] - t_plain[static_cast<std::size_t>(i - 1)], 2500) << i;
}

TEST(DramBankGroups, AGroupCountThatDoesNotDivideTheBanksIsRefused) {
  // Refused where the configuration is resolved (models/config_checks: InputError naming both
  // parameters, exit 2), and by the model itself when given such a struct directly.
  EXPECT_THROW(bank_group_config({"dram.bank_groups=3"}), InputError);
  HwConfig hw = bank_group_config({});
  hw.dram.bank_groups = 3;
  EventQueue eq;
  EXPECT_THROW(Dram(hw.dram, hw.energy, eq), std::invalid_argument);
}

TEST(DramPowerDown, AnIdleChannelPowersDownAndItsNextRequestPaysTxp) {
  // 1 GHz DRAM, 2 channels of 6.4 GB/s (1.6 transfers per clock x 32 bits; a 64 B line: 10 ns of bus), controller 30 ns each way,
  // tRCD 18, RL 15, refresh off; power-down after 100 ns idle, tXP 10 ns.
  //   t = 0:      a read to channel 0 (empty bank): ACT 30, data 63..73, back at 103 ns.
  //   t = 10 us:  a read of the same row: a row hit, 30 + 15 + 10 + 30 = 85 ns when awake; channel
  //               0 powered down at 173 ns, so its first command waits tXP after arrival (10030 +
  //               10): data 10055..10065, back at 10095 ns (95 ns).
  //   t = 20 us:  statistics. Channel 0 in active power-down (its row stays open) 173..10000 and
  //               10165..20000: 9827 + 9835 = 19662 ns; channel 1 never used: precharge power-down
  //               100..20000 = 19900 ns.
  //   background = ch0: 12 mW x 19662 + 57.6 mW x (19970 - 19662) active standby + 49.2 mW x 30
  //                (before the activate) + ch1: 2 mW x 19900 + 49.2 mW x 100   [mW x ns = pJ]
  const auto cfg = [](double after) {
    return resolve_config({}, {"dram.clock_mhz=1000", "dram.channels=2", "dram.banks=8", "dram.row_bytes=4096",
                               "dram.burst_bytes=32", "dram.transfers_per_clock=1.6", "dram.bus_width_bits=32", "dram.t_rcd_ns=18", "dram.t_rp_ns=18",
                               "dram.t_cl_ns=15", "dram.t_refi_ns=0", "dram.controller_latency_ns=30",
                               "dram.active_standby_mw=57.6", "dram.precharge_standby_mw=49.2",
                               "dram.active_powerdown_mw=12", "dram.precharge_powerdown_mw=2", "dram.t_xp_ns=10",
                               "dram.powerdown_after_ns=" + std::to_string(after),
                               "dram.address_mapping=row_bank_channel_column"})
        .hw;
  };
  for (const double after : {100.0, 0.0}) {
    const HwConfig hw = cfg(after);
    EventQueue eq;
    Dram d(hw.dram, hw.energy, eq);
    std::int64_t first = -1, second = -1;
    ASSERT_TRUE(d.enqueue(DramRequest{0, 64, false, DramClass::Other, [&] { first = eq.now().ps(); }}));
    eq.schedule(Tick{10'000'000}, [&] {
      ASSERT_TRUE(d.enqueue(DramRequest{64, 64, false, DramClass::Other, [&] { second = eq.now().ps() - 10'000'000; }}));
    });
    eq.schedule(Tick{20'000'000}, [] {});
    eq.run();
    d.update_derived_stats();
    EXPECT_EQ(first, 103'000);
    if (after > 0) {
      EXPECT_EQ(second, 95'000) << "a row hit after power-down pays tXP";
      EXPECT_EQ(d.stats().powerdown_exits.value(), 1u);
      EXPECT_EQ(d.channel_stats(0).powerdown_ps.value(), 19'662'000u);
      EXPECT_EQ(d.channel_stats(1).powerdown_ps.value(), 19'900'000u);
      const double expected = 12.0 * 19662 + 57.6 * (19970 - 19662) + 49.2 * 30 + 2.0 * 19900 + 49.2 * 100;
      EXPECT_NEAR(d.stats().energy_background_pj.value(), expected, 1e-6 * expected);
    } else {
      EXPECT_EQ(second, 85'000) << "awake: a plain row hit";
      EXPECT_EQ(d.stats().powerdown_exits.value(), 0u);
      // Standby all along: ch0 active 19970 ns, precharged 30; ch1 precharged 20000.
      const double expected = 57.6 * 19970 + 49.2 * 30 + 49.2 * 20000;
      EXPECT_NEAR(d.stats().energy_background_pj.value(), expected, 1e-6 * expected);
    }
  }
}

}  // namespace
}  // namespace tbdr
