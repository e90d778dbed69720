#include "app/stat_rows.hpp"

#include <algorithm>
#include <cmath>
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

namespace {
/// Milliseconds per core cycle of the run (from the timing model's own two figures).
double ms_per_cycle(const TimingResult& timing) { return timing.frame_time_ps * 1e-9 / timing.frame_cycles; }

}  // namespace

SequenceFrameStats sequence_frame_stats(const TimingResult& timing, const SequenceFrames& sequence, std::size_t k) {
  const FrameTime& f = timing.frames[k];
  const double end_before = k > 0 ? timing.frames[k - 1].end_cycle : 0.0;
  const std::uint64_t bytes_before = k > 0 ? timing.frames[k - 1].dram_bytes_at_end : 0;
  SequenceFrameStats s;
  s.start_cycle.set(f.start_cycle);
  s.end_cycle.set(f.end_cycle);
  s.interval_cycles.set(f.end_cycle - end_before);
  s.interval_ms.set(s.interval_cycles.value() * ms_per_cycle(timing));
  s.latency_cycles.set(f.end_cycle - f.start_cycle);
  s.dram_interval_bytes.set(f.dram_bytes_at_end - bytes_before);
  if (k < sequence.energy.size()) {
    s.energy_mj.set(sequence.energy[k].total_pj * 1e-9);
    s.at_period_energy_mj.set(sequence.energy[k].at_period_total_pj() * 1e-9);
  }
  if (k < sequence.totals.size()) {
    const PassStats& r = sequence.totals[k].render;
    s.primitives_out.set(r.geometry.primitives_out.value());
    s.shader_invocations.set(r.tsp.shader_invocations.value());
    s.light_evaluations.set(r.tsp.light_evaluations.value() + sequence.totals[k].compute.compute_light_evaluations.value());
  }
  return s;
}

namespace {
/// Whether frame k of n is a steady frame: after the warm-up, before the drain (when frames remain
/// between them).
bool steady_frame(std::size_t k, std::size_t n) {
  if (k < kSequenceWarmupFrames) return false;
  return n <= kSequenceWarmupFrames + kSequenceDrainFrames || k + kSequenceDrainFrames < n;
}
}  // namespace

SequenceSummaryStats summarize_frames(const std::vector<SequenceFrameStats>& frames, double total_ms, double energy_pj) {
  SequenceSummaryStats summary;
  const std::size_t n = frames.size();
  if (n < 2) return summary;
  summary.frames.set(n);
  summary.warmup_frames.set(kSequenceWarmupFrames);
  summary.drain_frames.set(n > kSequenceWarmupFrames + kSequenceDrainFrames ? kSequenceDrainFrames : 0);
  std::vector<double> steady_ms;
  double steady_bytes = 0, steady_mj = 0, steady_period_mj = 0;
  for (std::size_t k = 0; k < n; ++k) {
    if (!steady_frame(k, n)) continue;
    const SequenceFrameStats& s = frames[k];
    steady_ms.push_back(s.interval_ms.value());
    steady_bytes += s.dram_interval_bytes.as_double();
    steady_mj += s.energy_mj.value();
    steady_period_mj += s.at_period_energy_mj.value();
  }
  summary.mean_interval_ms.set(total_ms / static_cast<double>(n));
  double sum = 0;
  for (double v : steady_ms) sum += v;
  const double mean = sum / static_cast<double>(steady_ms.size());
  summary.steady_interval_ms.set(mean);
  std::sort(steady_ms.begin(), steady_ms.end());
  // Nearest rank: the smallest value with at least p % of the values at or below it.
  auto percentile = [&](double p) {
    const auto rank = static_cast<std::size_t>(std::ceil(p / 100.0 * static_cast<double>(steady_ms.size())));
    return steady_ms[std::max<std::size_t>(rank, 1) - 1];
  };
  summary.p50_interval_ms.set(percentile(50));
  summary.p95_interval_ms.set(percentile(95));
  summary.max_interval_ms.set(steady_ms.back());
  summary.steady_fps.set(mean > 0 ? 1000.0 / mean : 0.0);
  summary.steady_dram_mb_per_frame.set(steady_bytes / static_cast<double>(steady_ms.size()) * 1e-6);
  summary.energy_per_frame_mj.set(energy_pj * 1e-9 / static_cast<double>(n));
  summary.steady_energy_per_frame_mj.set(steady_mj / static_cast<double>(steady_ms.size()));
  summary.steady_at_period_energy_per_frame_mj.set(steady_period_mj / static_cast<double>(steady_ms.size()));
  return summary;
}

SequenceSummaryStats summarize_sequence(const TimingResult& timing, double energy_pj, const SequenceFrames& sequence) {
  const std::size_t n = timing.frames.size();
  if (n < 2 || timing.frame_cycles <= 0) return {};
  std::vector<SequenceFrameStats> frames;
  for (std::size_t k = 0; k < n; ++k) frames.push_back(sequence_frame_stats(timing, sequence, k));
  return summarize_frames(frames, timing.frames.back().end_cycle * ms_per_cycle(timing), energy_pj);
}

void append_sequence_rows(const TimingResult& timing, double energy_pj, const SequenceFrames& sequence,
                          std::vector<StatRecord>& out) {
  if (timing.frames.size() < 2 || timing.frame_cycles <= 0) return;
  for (std::size_t k = 0; k < timing.frames.size(); ++k) {
    collect_stats(sequence_frame_stats(timing, sequence, k), SequenceFrameStats::kScopePrefix + std::to_string(k), out);
  }
  collect_stats(summarize_sequence(timing, energy_pj, sequence), SequenceSummaryStats::kScope, out);
}

std::vector<StatRecord> run_rows(const FrameResult& frame, const TimingResult& timing, const EnergyBreakdown& energy,
                                 const SequenceFrames& sequence) {
  std::vector<StatRecord> out = frame_rows(frame);
  append_timing_rows(timing, out);
  append_energy_rows(energy, out);
  append_sequence_rows(timing, energy.total_pj, sequence, out);
  return out;
}

std::vector<StatRecord> sampled_rows(const SampledSequence& s, const SamplingSummaryStats& estimate, const SequenceSummaryStats& summary) {
  std::vector<StatRecord> out;
  const std::vector<SequenceFrameStats> frames = sampled_frame_figures(s);
  for (std::size_t k = 0; k < frames.size(); ++k) {
    const std::size_t g = s.plan.group_of[k];
    SampledFrameStats f;
    f.group.set(g);
    f.representative.set(s.plan.representative[g] == k ? 1 : 0);
    copy_frame_interval(frames[k], f);
    const std::string scope = SampledFrameStats::kScopePrefix + std::to_string(k);
    collect_stats(f, scope, out);
    collect_stats(s.signatures[k], scope, out);
  }
  collect_stats(estimate, SamplingSummaryStats::kScope, out);
  for (std::size_t g = 0; g < s.plan.groups(); ++g) {
    collect_stats(s.measured[g], SequenceFrameStats::kScopePrefix + std::to_string(s.plan.representative[g]), out);
  }
  collect_stats(summary, SequenceSummaryStats::kScope, out);
  return out;
}

}  // namespace tbdr
