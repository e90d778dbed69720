#pragma once
// DRAM memory specifications (memspecs) as DRAMPower and DRAMSys publish them: the currents per
// supply rail and the timings of one die, and DRAMPower's formulas that turn them into energies
// per event (activate + precharge, read and write bursts, refresh, standby). They are the
// independent side of the DRAM energy check: `tbdrsim validate`, tests/test_dram_presets.cpp and
// bench/dram.sh compare the model (which reads its unit costs from [dram] and [energy]) with the
// energy per bit these give for a streaming and a random read pattern.
#include <string>
#include <vector>

namespace tbdr {

/// Currents of one supply rail of one die, in mA, at `volts`.
struct MemspecRail {
  double volts = 0;
  double idd0 = 0;   ///< one bank activate-precharge
  double idd2n = 0;  ///< precharge standby
  double idd3n = 0;  ///< active standby
  double idd4r = 0;  ///< burst read
  double idd4w = 0;  ///< burst write
  double idd5 = 0;   ///< all-bank refresh
  double idd2p = 0;  ///< precharge power-down
  double idd3p = 0;  ///< active power-down
};

/// One die's memspec: rails (the core rails and, where the memspec gives one, VDDQ) and timings.
struct DramMemspec {
  std::string id;      ///< the memspec's memoryId
  std::string source;  ///< repository, path and commit it was read from
  std::vector<MemspecRail> core;  ///< VDD / VDD1, VDD2: what DRAMPower's core model charges
  bool has_vddq = false;          ///< VDDQ currents given (I/O: read drivers, write receivers)
  MemspecRail vddq;
  double tck_ns = 0;
  int width_bits = 0;   ///< DQ of the die
  int burst_length = 0;
  int banks = 0;
  int row_bytes = 0;    ///< page of one die: columns x width / 8
  // Timings in clock cycles, as the memspec gives them.
  int ras = 0, rp = 0, rcd = 0, rl = 0, rrd = 0, faw = 0, rfc = 0, refi = 0;
};

/// DRAMPower's energies per event of one die (DRAMPower 5, standards/lpddr4/core_calculation_LPDDR4.cpp:
/// E_act + E_pre = VDD (IDD0 (tRAS + tRP) - IDD3N tRAS - IDD2N tRP); E_RD = VDD (IDD4R - IDD3N) BL/2 tCK;
/// E_WR likewise with IDD4W; E_ref = VDD (IDD5 - IDD3N) tRFC; background VDD IDD3N with a row open,
/// VDD IDD2N all precharged), summed over the core rails. VDDQ is not in DRAMPower's core model; where
/// the memspec gives its currents they are the I/O terms: VDDQ (IDD4RQ - IDD3NQ) BL/2 tCK per read burst.
struct MemspecEnergy {
  double read_pj_per_bit = 0;
  double write_pj_per_bit = 0;
  double io_read_pj_per_bit = 0;   ///< 0 when the memspec has no VDDQ currents
  double io_write_pj_per_bit = 0;
  double activate_precharge_nj = 0;
  double refresh_nj = 0;
  double active_standby_mw = 0;     ///< core rails and VDDQ
  double precharge_standby_mw = 0;
  double active_powerdown_mw = 0;     ///< VDD IDD3P, core rails and VDDQ
  double precharge_powerdown_mw = 0;  ///< VDD IDD2P
};

/// The energies per event of `m`.
MemspecEnergy memspec_energy(const DramMemspec& m);

/// How a preset's channel is built from memspec dies, and the preset's own data rate.
struct MemspecChannel {
  int dies = 1;              ///< dies side by side on one modelled channel (each activates and bursts)
  double gbps = 0;           ///< peak bandwidth of one modelled channel
  double io_pj_per_bit = 0;  ///< I/O energy to use when the memspec gives no VDDQ currents (0: none)
  double vddq_v = 0;         ///< VDDQ the preset runs its dies at, when not the memspec's (0: the memspec's)
};

/// Energy per bit of reads, from the memspec alone, for two patterns on one channel:
/// - streaming: every row read whole (one activate per channel row of dies x row_bytes), the bus
///   busy but for refresh, which idles it tRP + tRFC + tRCD + RL per tREFI;
/// - random: every 64 B line in a new row, one line per max(tRRD, tFAW / 4, (tRAS + tRP) / banks,
///   line burst), the activate rate the memspec's timings allow.
/// Each is read + I/O + activate per bit + dies x active standby / bit rate + dies x refresh per
/// tREFI / bit rate.
struct MemspecPerBit {
  double stream_pj = 0;
  double random_pj = 0;
  double stream_efficiency = 0;  ///< streaming bit rate / peak
  double random_efficiency = 0;  ///< random bit rate / peak
};
MemspecPerBit memspec_per_bit(const DramMemspec& m, const MemspecChannel& c);

/// DRAMPower's memspec MICRON_4Gb_LPDDR3-1600_32bit_A (the default preset's die).
const DramMemspec& memspec_lpddr3_1600();
/// DRAMSys's memspec MICRON_6Gb_LPDDR4-3200_32bit_A (one x16 channel; the LPDDR4X and LPDDR5 presets' energies).
const DramMemspec& memspec_lpddr4_3200();

/// A shipped DRAM preset and the memspec die its energies come from.
struct DramPresetMemspec {
  std::string label;                 ///< the preset's dram.name
  std::vector<std::string> configs;  ///< config names in the checkout's configs/, loaded in order
  const DramMemspec* memspec = nullptr;
  int dies = 1;      ///< memspec dies on one modelled channel
  std::string note;  ///< how the preset departs from the memspec
  double vddq_v = 0; ///< the preset's VDDQ when not the memspec's (LPDDR4X 0.6 V, LPDDR5 0.5 V; 0: the memspec's)
};

/// Every shipped DRAM preset with its memspec (the default, LPDDR4X, LPDDR5 8-bank and bank-group modes).
const std::vector<DramPresetMemspec>& dram_preset_memspecs();

}  // namespace tbdr
