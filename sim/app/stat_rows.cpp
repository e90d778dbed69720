#include "app/stat_rows.hpp"

#include <string>

namespace tbdr {

namespace {

/// A pass's (or the frame's) unit rows "<prefix>/<unit>".
void append_pass_rows(const PassStats& s, const std::string& prefix, std::vector<StatRecord>& out) {
  collect_stats(s.geometry, prefix + "/geometry", out);
  collect_stats(s.tiler, prefix + "/tiler", out);
  collect_stats(s.isp, prefix + "/isp", out);
  collect_stats(s.tsp, prefix + "/tsp", out);
  collect_stats(s.tile_memory, prefix + "/tile_memory", out);
  collect_stats(s.rop, prefix + "/rop", out);
}

/// The requested bytes of a command (or the frame) per class and in all: "<prefix>/dram[.<class>]".
void append_requested_rows(const DramTraffic& dram, const std::string& prefix, std::vector<StatRecord>& out) {
  TrafficStats all;
  for (std::size_t c = 0; c < kDramClassCount; ++c) {
    TrafficStats cls;
    cls.read_bytes.set(dram.read_bytes[c]);
    cls.write_bytes.set(dram.write_bytes[c]);
    collect_stats(cls, prefix + TrafficStats::kScopeSuffix + "." + to_string(static_cast<DramClass>(c)), out);
    all += cls;
  }
  collect_stats(all, prefix + TrafficStats::kScopeSuffix, out);
}

}  // namespace

std::vector<StatRecord> frame_rows(const FrameResult& frame) {
  std::vector<StatRecord> out;
  for (const CommandStats& c : frame.commands) {
    if (c.pass) append_pass_rows(*c.pass, c.name, out);
    if (c.compute) collect_stats(*c.compute, c.name + "/compute", out);
    append_requested_rows(c.requested, c.name, out);
  }
  // The frame's totals: every unit's statistics summed over the passes (gauges: the largest level).
  if (frame.shape.passes.value() > 0) append_pass_rows(frame.totals.render, "frame", out);
  if (frame.shape.dispatches.value() > 0) collect_stats(frame.totals.compute, "frame/compute", out);
  append_requested_rows(frame.dram, "frame", out);
  collect_stats(frame.shape, FrameShapeStats::kScope, out);
  return out;
}

void append_timing_rows(const TimingResult& timing, std::vector<StatRecord>& out) {
  FrameTimingStats f;
  f.frame_cycles.set(timing.frame_cycles);
  f.frame_time_ms.set(timing.frame_time_ps * 1e-9);
  f.timing_events.set(timing.events);
  collect_stats(f, FrameTimingStats::kScope, out);
  for (const auto& c : timing.commands) {
    CommandTimingStats span;
    span.start_cycle.set(c.start_cycle);
    span.binning_end_cycle.set(c.binning_end_cycle);
    span.end_cycle.set(c.end_cycle);
    collect_stats(span, c.name + CommandTimingStats::kScopeSuffix, out);
  }
  for (const auto& u : timing.units) {
    UnitTimeStats time;
    time.busy_cycles.set(u.busy_cycles);
    time.stalled_cycles.set(u.stalled_cycles);
    time.frame_cycles = timing.frame_cycles;
    collect_stats(time, UnitTimeStats::kScopePrefix + u.name, out);
  }
  TextureFetchStats texture;
  texture.line_accesses.set(timing.texture_line_accesses);
  texture.footprint_lines.set(timing.texture_footprint_lines);
  texture.cache_misses.set(timing.texture_cache_misses);
  collect_stats(texture, TextureFetchStats::kScope, out);
  append_memory_rows(timing.memory_units, out);
}

void append_memory_rows(const MemorySnapshot& memory, std::vector<StatRecord>& out) {
  collect_stats(memory.stats, memory.scope, out);
  for (std::size_t c = 0; c < kClientCount; ++c) {
    collect_stats(memory.clients[c], memory.scope + "/client." + to_string(static_cast<Client>(c)), out);
  }
  for (const CacheSnapshot& cache : memory.caches) append_cache_rows(cache, out);
  append_dram_rows(memory.dram, out);
}

void append_cache_rows(const CacheSnapshot& cache, std::vector<StatRecord>& out) {
  collect_stats(cache.stats, cache.scope, out);
  for (std::size_t c = 0; c < kDramClassCount; ++c) {
    collect_stats(cache.classes[c], cache.scope + ".class." + to_string(static_cast<DramClass>(c)), out);
  }
}

void append_dram_rows(const DramSnapshot& dram, std::vector<StatRecord>& out) {
  collect_stats(dram.stats, dram.scope, out);
  for (std::size_t c = 0; c < dram.channels.size(); ++c) collect_stats(dram.channels[c], dram.scope + ".ch" + std::to_string(c), out);
  for (std::size_t c = 0; c < kDramClassCount; ++c) {
    collect_stats(dram.classes[c], dram.scope + ".class." + to_string(static_cast<DramClass>(c)), out);
  }
}

void append_energy_rows(const EnergyBreakdown& energy, std::vector<StatRecord>& out) {
  // One row per component: its name is the component's (the energy model's terms), so it is made
  // here from the term rather than declared in a set.
  for (const auto& t : energy.terms) {
    out.push_back({EnergyFrameStats::kScope, t.component + "_pj", t.pj, "pJ", "Energy of " + t.component + ": " + t.counter + " x unit cost"});
  }
  EnergyFrameStats frame;
  frame.total_pj.set(energy.total_pj);
  frame.static_power_mw.set(energy.leakage.total_mw());
  frame.static_logic_mw.set(energy.leakage.logic_mw);
  frame.static_sram_mw.set(energy.leakage.sram_gated_mw + energy.leakage.sram_retained_mw);
  frame.idle_ps = energy.idle_ps;
  frame.idle_gpu_pj = energy.idle_gpu_pj;
  frame.idle_dram_pj = energy.idle_dram_pj;
  collect_stats(frame, EnergyFrameStats::kScope, out);
}

void append_host_rows(const HostRunStats& host, std::vector<StatRecord>& out) { collect_stats(host, HostRunStats::kScope, out); }

std::vector<StatRecord> run_rows(const FrameResult& frame, const TimingResult& timing, const EnergyBreakdown& energy) {
  std::vector<StatRecord> out = frame_rows(frame);
  append_timing_rows(timing, out);
  append_energy_rows(energy, out);
  return out;
}

}  // namespace tbdr
