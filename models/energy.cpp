#include "models/energy.hpp"

#include <algorithm>

#include "models/sram_energy.hpp"

namespace tbdr {

namespace {

/// Fixed-function units besides the ISP's raster pipes: geometry, tiler, pixel back end.
constexpr double kFixedFunctionUnitsBesidesRasterPipes = 3.0;

/// Share of an ALU op's operand bytes that are reads: an FMA reads three sources and writes one result.
constexpr double kOperandReadShare = 0.75;

/// mW x ps = 1e-3 W x 1e-12 s = 1e-15 J = 1e-3 pJ; mW x ns = 1 pJ.
constexpr double kPjPerMwPs = 1e-3;

}  // namespace

StaticPower static_power(const HwConfig& hw) {
  const EnergyParams& e = hw.energy;
  StaticPower s;
  s.logic_mw = static_cast<double>(hw.usc.count) * e.usc_leakage_mw +
               static_cast<double>(hw.texture.units) * e.texture_unit_leakage_mw +
               (kFixedFunctionUnitsBesidesRasterPipes + static_cast<double>(hw.isp.raster_pipes)) * e.fixed_function_leakage_mw;
  for (int i = 0; i < kOnChipArrays; ++i) {
    const auto a = static_cast<OnChipArray>(i);
    const double mw = on_chip_leakage_mw(hw, a);
    (on_chip_array(hw, a).retains_data ? s.sram_retained_mw : s.sram_gated_mw) += mw;
  }
  return s;
}

double dram_idle_pj(const DramParams& d, double idle_ps) {
  const double t_ns = std::max(0.0, idle_ps) * 1e-3;
  const bool refresh = d.t_refi_ns > 0 && d.t_rfc_ns > 0;
  // Refresh power on top of the background: refresh_nj every t_refi_ns; nJ / ns = W, x 1000 = mW.
  const double refresh_mw = refresh ? d.refresh_nj / d.t_refi_ns * 1000.0 : 0.0;
  double mw_ns = 0;  // per channel
  if (d.powerdown_after_ns <= 0) {
    mw_ns = (d.precharge_standby_mw + refresh_mw) * t_ns;
  } else {
    const double standby_ns = std::min(t_ns, d.powerdown_after_ns);
    const double after_ns = t_ns - standby_ns;
    const bool self_refresh = d.self_refresh_mw > 0 && refresh;
    const double powerdown_ns = self_refresh ? std::min(after_ns, d.t_refi_ns) : after_ns;
    mw_ns = (d.precharge_standby_mw + refresh_mw) * standby_ns + (d.precharge_powerdown_mw + refresh_mw) * powerdown_ns +
            (self_refresh ? d.self_refresh_mw * (after_ns - powerdown_ns) : 0.0);
  }
  return mw_ns * static_cast<double>(d.channels);  // mW x ns = pJ
}

EnergyBreakdown compute_energy(const HwConfig& hw, const FrameStats& frame, const MemorySystemStats& memory,
                               double frame_time_ps, int frames) {
  const auto& e = hw.energy;
  const TspStats& tsp = frame.render.tsp;
  const TileMemoryStats& tm = frame.render.tile_memory;
  const IspStats& isp = frame.render.isp;
  const auto d = [](const auto& stat) { return stat.as_double(); };
  EnergyBreakdown b;
  auto term = [&](const char* component, const char* counter, double count, double pj_per_unit) {
    b.terms.push_back({component, counter, count, pj_per_unit, count * pj_per_unit});
    b.total_pj += count * pj_per_unit;
  };
  // A term whose bytes are partly reads and partly writes (of possibly different arrays): charged
  // as bytes x their mean cost, so count x unit cost stays the product.
  auto bytes_term = [&](const char* component, double bytes, double pj) {
    term(component, "bytes", bytes, bytes > 0 ? pj / bytes : 0.0);
  };
  const auto pjb = [&](OnChipArray a, bool write) { return on_chip_pj_per_byte(hw, a, write); };
  // The memory system computed its energies per access (DRAM read/write/IO bits, activates; cache
  // bytes by cache): charged here as one unit each so the sum stays exact.
  term("dram", "pJ (memory system)", memory.dram_energy_pj.value(), 1.0);
  term("caches", "pJ (memory system)", memory.cache_energy_pj.value(), 1.0);
  // imr has no tile buffer and no on-chip depth buffer: the shaders' colour and the ISP's depth
  // accesses are the ROP caches' (their fills and write-backs are SRAM accesses too).
  const bool imr = hw.gpu.mode == GpuMode::Imr;
  const RopStats& rop = frame.render.rop;
  {
    // Reads: the shaders' reads and PLS accesses, the tile stores (the buffer read out); writes: the
    // shaders' writes, tile loads and clears.
    const double rd = imr ? 0.0 : d(tsp.tile_buffer_read_bytes) + d(tm.tile_store_bytes) + d(tsp.pls_bytes_accessed);
    const double wr = imr ? 0.0 : d(tsp.tile_buffer_write_bytes) + d(tm.tile_load_bytes) + d(tm.tile_clear_bytes);
    bytes_term("tile_buffer", rd + wr, rd * pjb(OnChipArray::TileBuffer, false) + wr * pjb(OnChipArray::TileBuffer, true));
  }
  {
    const double tag_rd = imr ? 0.0 : d(isp.tag_buffer_read_bytes), tag_wr = imr ? 0.0 : d(isp.tag_buffer_write_bytes);
    const double z_rd = imr ? 0.0 : d(isp.depth_buffer_read_bytes), z_wr = imr ? 0.0 : d(isp.depth_buffer_write_bytes);
    bytes_term("tag_and_depth_buffer", tag_rd + tag_wr + z_rd + z_wr,
               tag_rd * pjb(OnChipArray::TagBuffer, false) + tag_wr * pjb(OnChipArray::TagBuffer, true) +
                   z_rd * pjb(OnChipArray::DepthBuffer, false) + z_wr * pjb(OnChipArray::DepthBuffer, true));
  }
  {
    // The ROP's depth and colour caches are counted together: their mean read energy per byte.
    const double rop_bytes = d(rop.accessed_bytes) + d(rop.fill_bytes) + d(rop.writeback_bytes);
    const double rop_pjb = 0.5 * (pjb(OnChipArray::RopDepthCache, false) + pjb(OnChipArray::RopColorCache, false));
    term("rop_caches", "bytes", rop_bytes, rop_pjb);
  }
  const double scale = process_energy_scale(e.process_nm, e.vdd_v);
  {
    // An op's arithmetic at the node plus its operands: register_file_bytes_per_op bytes, 3 read for
    // 1 written (an FMA's three sources and one result).
    const double operand_pjb = kOperandReadShare * pjb(OnChipArray::RegisterFile, false) +
                               (1.0 - kOperandReadShare) * pjb(OnChipArray::RegisterFile, true);
    term("alu", "ops", d(tsp.fragment_alu_ops) + d(frame.render.geometry.vertex_alu_ops) + d(frame.compute.compute_alu_ops),
         e.alu_op_pj_45nm * scale + e.register_file_bytes_per_op * operand_pjb);
  }
  term("texture", "filtered texels",
       d(tsp.texels_filtered) + d(frame.compute.compute_texture_fetches) * static_cast<double>(hw.texture.filtered_texels_per_fetch),
       e.texel_pj_45nm * scale);
  b.leakage = static_power(hw);
  term("static", "mW x ps", b.leakage.total_mw() * frame_time_ps, kPjPerMwPs);
  // The idle time of a fixed frame period.
  const double period_ps = hw.gpu.frame_period_us * 1e6 * std::max(1, frames);
  b.idle_ps = period_ps > frame_time_ps ? period_ps - frame_time_ps : 0.0;
  b.idle_gpu_pj = b.leakage.idle_mw(e.gated_leakage_fraction) * b.idle_ps * kPjPerMwPs;
  b.idle_dram_pj = dram_idle_pj(hw.dram, b.idle_ps);
  return b;
}

}  // namespace tbdr
