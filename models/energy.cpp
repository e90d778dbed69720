#include "models/energy.hpp"

namespace tbdr {

EnergyBreakdown compute_energy(const HwConfig& hw, const FrameStats& frame, const MemorySystemStats& memory,
                               double frame_time_ps) {
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
  // The memory system computed its energies per access (DRAM read/write/IO bits, activates; cache
  // bytes by cache): charged here as one unit each so the sum stays exact.
  term("dram", "pJ (memory system)", memory.dram_energy_pj.value(), 1.0);
  term("caches", "pJ (memory system)", memory.cache_energy_pj.value(), 1.0);
  // imr has no tile buffer and no on-chip depth buffer: the shaders' colour and the ISP's depth
  // accesses are the ROP caches' (their fills and write-backs are SRAM accesses too).
  const bool imr = hw.gpu.mode == GpuMode::Imr;
  const RopStats& rop = frame.render.rop;
  term("tile_buffer", "bytes",
       imr ? 0.0
           : d(tsp.tile_buffer_read_bytes) + d(tsp.tile_buffer_write_bytes) + d(tm.tile_load_bytes) + d(tm.tile_store_bytes) +
                 d(tm.tile_clear_bytes) + d(tsp.pls_bytes_accessed),
       e.tile_buffer_pj_per_byte);
  term("tag_and_depth_buffer", "bytes",
       imr ? 0.0
           : d(isp.tag_buffer_read_bytes) + d(isp.tag_buffer_write_bytes) + d(isp.depth_buffer_read_bytes) +
                 d(isp.depth_buffer_write_bytes),
       e.tag_buffer_pj_per_byte);
  term("rop_caches", "bytes", d(rop.accessed_bytes) + d(rop.fill_bytes) + d(rop.writeback_bytes), e.rop_cache_pj_per_byte);
  term("alu", "ops",
       d(tsp.fragment_alu_ops) + d(frame.render.geometry.vertex_alu_ops) + d(frame.compute.compute_alu_ops),
       e.alu_op_pj);
  term("texture", "filtered texels",
       d(tsp.texels_filtered) + d(frame.compute.compute_texture_fetches) * static_cast<double>(hw.texture.filtered_texels_per_fetch),
       e.texel_pj);
  // Static: mW x ps = 1e-3 W x 1e-12 s = 1e-15 J = 1e-3 pJ.
  term("static", "mW x ps", e.static_power_mw * frame_time_ps, 1e-3);
  return b;
}

void EnergyBreakdown::collect(std::vector<StatRecord>& out) const {
  for (const auto& t : terms) {
    // Names must be string literals with static storage only for StatDef; records own strings.
    out.push_back({"frame/energy", t.component + "_pj", t.pj, "pJ", "Energy of " + t.component + ": " + t.counter + " x unit cost"});
  }
  out.push_back({"frame/energy", "total_pj", total_pj, "pJ", "Energy of the frame, all components"});
  out.push_back({"frame/energy", "total_mj", total_pj * 1e-9, "mJ", "Energy of the frame, all components"});
}

}  // namespace tbdr
