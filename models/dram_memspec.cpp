#include "models/dram_memspec.hpp"

#include <algorithm>

namespace tbdr {

namespace {

/// Bits in one 64 B line: the random pattern's access (the SLC line, as the memory system requests).
constexpr double kLineBits = 512.0;

}  // namespace

MemspecEnergy memspec_energy(const DramMemspec& m) {
  MemspecEnergy e;
  const double t_ras = m.ras * m.tck_ns, t_rp = m.rp * m.tck_ns, t_rfc = m.rfc * m.tck_ns;
  const double burst_ns = m.burst_length / 2.0 * m.tck_ns;  // BL / data rate x tCK
  const double burst_bits = static_cast<double>(m.burst_length) * m.width_bits;
  // mA x V x ns = pJ.
  for (const MemspecRail& r : m.core) {
    e.read_pj_per_bit += r.volts * (r.idd4r - r.idd3n) * burst_ns / burst_bits;
    e.write_pj_per_bit += r.volts * (r.idd4w - r.idd3n) * burst_ns / burst_bits;
    e.activate_precharge_nj += r.volts * (r.idd0 * (t_ras + t_rp) - r.idd3n * t_ras - r.idd2n * t_rp) * 1e-3;
    e.refresh_nj += r.volts * (r.idd5 - r.idd3n) * t_rfc * 1e-3;
    e.active_standby_mw += r.volts * r.idd3n;
    e.precharge_standby_mw += r.volts * r.idd2n;
    e.active_powerdown_mw += r.volts * r.idd3p;
    e.precharge_powerdown_mw += r.volts * r.idd2p;
  }
  if (m.has_vddq) {
    const MemspecRail& q = m.vddq;
    e.io_read_pj_per_bit = q.volts * (q.idd4r - q.idd3n) * burst_ns / burst_bits;
    e.io_write_pj_per_bit = q.volts * (q.idd4w - q.idd3n) * burst_ns / burst_bits;
    e.active_standby_mw += q.volts * q.idd3n;
    e.precharge_standby_mw += q.volts * q.idd2n;
    e.active_powerdown_mw += q.volts * q.idd3p;
    e.precharge_powerdown_mw += q.volts * q.idd2p;
  }
  return e;
}

MemspecPerBit memspec_per_bit(const DramMemspec& die, const MemspecChannel& c) {
  // The same currents at the preset's VDDQ (LPDDR4X runs the LPDDR4 die's I/O at 0.6 V).
  DramMemspec m = die;
  if (c.vddq_v > 0 && m.has_vddq) m.vddq.volts = c.vddq_v;
  const MemspecEnergy e = memspec_energy(m);
  const double dies = c.dies;
  const double peak_bits_per_ns = c.gbps * 8.0;
  const double t = m.tck_ns;
  const double refi_ns = m.refi * t;
  // Per bit whatever the pattern: the burst, its I/O, the standby of every die and its refreshes
  // over the bits that flow meanwhile.
  const double io = m.has_vddq ? e.io_read_pj_per_bit : c.io_pj_per_bit;
  const auto per_bit = [&](double bits_per_ns, double bits_per_activate) {
    return e.read_pj_per_bit + io + dies * e.activate_precharge_nj * 1000.0 / bits_per_activate +
           dies * e.active_standby_mw / bits_per_ns + dies * e.refresh_nj * 1000.0 / refi_ns / bits_per_ns;
  };
  MemspecPerBit r;
  // Streaming: a refresh idles the bus from the last data before it to the first data after it:
  // the open row's precharge, the refresh, the next row's activate and read latency.
  r.stream_efficiency = 1.0 - (m.rp + m.rfc + m.rcd + m.rl) * t / refi_ns;
  r.stream_pj = per_bit(peak_bits_per_ns * r.stream_efficiency, dies * m.row_bytes * 8.0);
  // Random lines: one activate per line at the rate tRRD, tFAW, tRC over the banks and the bus allow;
  // no activate during a refresh (tRP + tRFC of every tREFI).
  const double line_ns = std::max({m.rrd * t, m.faw * t / 4.0, (m.ras + m.rp) * t / m.banks, kLineBits / peak_bits_per_ns});
  r.random_efficiency = kLineBits / line_ns / peak_bits_per_ns * (1.0 - (m.rp + m.rfc) * t / refi_ns);
  r.random_pj = per_bit(peak_bits_per_ns * r.random_efficiency, kLineBits);
  return r;
}

const DramMemspec& memspec_lpddr3_1600() {
  static const DramMemspec m = [] {
    DramMemspec s;
    s.id = "MICRON_4Gb_LPDDR3-1600_32bit_A";
    s.source = "DRAMPower memspec (github.com/tukl-msd/DRAMPower, memspecs/MICRON_4Gb_LPDDR3-1600_32bit_A.xml at "
               "1ddc48a, the last commit before DRAMPower 5 dropped the XML memspecs)";
    // idd0/idd2n/idd3n/idd4r/idd4w/idd5/idd2p0/idd3p0 on vdd 1.8 V and idd02.. on vdd2 1.2 V.
    s.core = {{1.8, 15.0, 2.0, 2.0, 5.0, 10.0, 40.0, 0.6, 1.2}, {1.2, 80.0, 38.0, 45.0, 260.0, 284.0, 160.0, 0.87, 8.15}};
    s.tck_ns = 1.25;  // clkMhz 800
    s.width_bits = 32;
    s.burst_length = 8;
    s.banks = 8;
    s.row_bytes = 1024 * 32 / 8;  // nbrOfColumns x width
    s.ras = 36, s.rp = 15, s.rcd = 15, s.rl = 12, s.rrd = 8, s.faw = 40, s.rfc = 104, s.refi = 3120;
    return s;
  }();
  return m;
}

const DramMemspec& memspec_lpddr4_3200() {
  static const DramMemspec m = [] {
    DramMemspec s;
    s.id = "MICRON_6Gb_LPDDR4-3200_32bit_A";
    s.source = "DRAMSys memspec (github.com/tukl-msd/DRAMSys, configs/memspec/MICRON_6Gb_LPDDR4-3200_32bit_A.json at "
               "2107966; the same die as DRAMPower's memspecs/MICRON_6Gb_LPDDR4-3200_32bit_A.json)";
    // idd01.. on vdd1 1.8 V, idd02.. on vdd2 1.1 V; VDDQ 1.1 V: idd0ql/idd2nQ/idd3nQ 0.75, idd4rq 150,
    // idd4wq 55, idd5q/idd2pQ/idd3pQ 0.75 mA.
    s.core = {{1.8, 3.5, 2.0, 2.25, 2.25, 2.25, 10.0, 1.2, 1.2}, {1.1, 45.0, 27.0, 30.0, 275.0, 210.0, 90.0, 3.0, 9.0}};
    s.has_vddq = true;
    s.vddq = {1.1, 0.75, 0.75, 0.75, 150.0, 55.0, 0.75, 0.75, 0.75};
    s.tck_ns = 0.625;
    s.width_bits = 16;
    s.burst_length = 16;
    s.banks = 8;
    s.row_bytes = 1024 * 16 / 8;
    s.ras = 68, s.rp = 29, s.rcd = 29, s.rl = 28, s.rrd = 16, s.faw = 64, s.rfc = 448, s.refi = 6246;  // RPpb, RFCab
    return s;
  }();
  return m;
}

const std::vector<DramPresetMemspec>& dram_preset_memspecs() {
  static const std::vector<DramPresetMemspec> presets = {
      {"LPDDR3-1600 2x32", {"series6xt_gx6450"}, &memspec_lpddr3_1600(), 1,
       "the memspec has no I/O currents: I/O is the preset's pin-capacitance estimate (energy.dram_io_pj_per_bit)"},
      {"LPDDR4X-4266 2x32", {"mobile_16x16_lpddr4x"}, &memspec_lpddr4_3200(), 2,
       "LPDDR4-3200 x16 dies, two per modelled 32-bit channel, at 4266 MT/s; the memspec's VDDQ 1.1 V at LPDDR4X's "
       "0.6 V (JESD209-4-1)", 0.6},
      {"LPDDR5-6400 4x16 (8B mode)", {"mobile_16x16_lpddr4x", "dram_lpddr5_6400"}, &memspec_lpddr4_3200(), 1,
       "no public LPDDR5 memspec has currents: the LPDDR4 die's, at LPDDR5's bandwidth and VDDQ 0.5 V", 0.5},
      {"LPDDR5-6400 4x16 (BG mode)", {"mobile_16x16_lpddr4x", "dram_lpddr5_6400_bg"}, &memspec_lpddr4_3200(), 1,
       "LPDDR4 die's currents as above; bank-group timing from JESD209-5 (gem5 transcription)", 0.5},
  };
  return presets;
}

}  // namespace tbdr
