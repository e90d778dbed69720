#include "models/energy.hpp"

namespace tbdr {

namespace {

double stat_of(const std::vector<StatRecord>& stats, const std::string& scope, const std::string& name) {
  double v = 0;
  for (const auto& r : stats) {
    if (r.scope == scope && r.name == name) v += r.value;
  }
  return v;
}

}  // namespace

EnergyBreakdown compute_energy(const HwConfig& hw, const std::vector<StatRecord>& stats, double frame_time_ps) {
  const auto& e = hw.energy;
  EnergyBreakdown b;
  auto term = [&](const char* component, const char* counter, double count, double pj_per_unit) {
    b.terms.push_back({component, counter, count, pj_per_unit, count * pj_per_unit});
    b.total_pj += count * pj_per_unit;
  };
  // The memory system computed its energies per access (DRAM read/write/IO bits, activates; cache
  // bytes by cache): charged here as one unit each so the sum stays exact.
  term("dram", "pJ (memory system)", stat_of(stats, "mem/dram", "energy_pj"), 1.0);
  term("caches", "pJ (memory system)", stat_of(stats, "mem", "cache_energy_pj"), 1.0);
  term("tile_buffer", "bytes",
       stat_of(stats, "frame/tsp", "tile_buffer_read_bytes") + stat_of(stats, "frame/tsp", "tile_buffer_write_bytes") +
           stat_of(stats, "frame/tile_memory", "tile_load_bytes") + stat_of(stats, "frame/tile_memory", "tile_store_bytes") +
           stat_of(stats, "frame/tile_memory", "tile_clear_bytes") + stat_of(stats, "frame/tsp", "pls_bytes_accessed"),
       e.tile_buffer_pj_per_byte);
  term("tag_and_depth_buffer", "bytes",
       stat_of(stats, "frame/isp", "tag_buffer_read_bytes") + stat_of(stats, "frame/isp", "tag_buffer_write_bytes") +
           stat_of(stats, "frame/isp", "depth_buffer_read_bytes") + stat_of(stats, "frame/isp", "depth_buffer_write_bytes"),
       e.tag_buffer_pj_per_byte);
  term("alu", "ops",
       stat_of(stats, "frame/tsp", "fragment_alu_ops") + stat_of(stats, "frame/geometry", "vertex_alu_ops") +
           stat_of(stats, "frame/compute", "compute_alu_ops"),
       e.alu_op_pj);
  term("texture", "texels",
       stat_of(stats, "frame/tsp", "texels_filtered") +
           stat_of(stats, "frame/compute", "compute_texture_fetches") * static_cast<double>(hw.texture.texels_per_fetch),
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
