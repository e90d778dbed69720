#include "app/sampled_run.hpp"

#include <algorithm>
#include <string>

#include "app/stat_rows.hpp"

namespace tbdr {

std::vector<SampleWindow> sample_windows(const SamplingPlan& plan, std::size_t frames) {
  std::vector<std::size_t> reps = plan.representative;
  std::sort(reps.begin(), reps.end());
  std::vector<SampleWindow> out;
  for (std::size_t r : reps) {
    const SampleWindow w{r > 0 ? r - 1 : 0, std::min(r + 1, frames - 1)};
    if (!out.empty() && w.first <= out.back().last + 1) {
      out.back().last = std::max(out.back().last, w.last);
    } else {
      out.push_back(w);
    }
  }
  return out;
}

namespace {

/// Each frame's figures: its own where it was simulated for its group, else its representative's.
std::vector<SequenceFrameStats> frame_figures(const SampledSequence& s) {
  std::vector<SequenceFrameStats> frames;
  for (std::size_t k = 0; k < s.plan.group_of.size(); ++k) {
    const SequenceFrameStats& m = s.measured[s.plan.group_of[k]];
    SequenceFrameStats f;
    f.interval_cycles.set(m.interval_cycles.value());
    f.interval_ms.set(m.interval_ms.value());
    f.dram_interval_bytes.set(m.dram_interval_bytes.value());
    f.energy_mj.set(m.energy_mj.value());
    f.at_period_energy_mj.set(m.at_period_energy_mj.value());
    frames.push_back(f);
  }
  return frames;
}

/// One figure of each group's representative.
template <typename Get>
std::vector<double> per_group(const SampledSequence& s, Get get) {
  std::vector<double> v;
  for (const SequenceFrameStats& m : s.measured) v.push_back(get(m));
  return v;
}

}  // namespace

SamplingSummaryStats summarize_sampled(const SampledSequence& s) {
  SamplingSummaryStats out;
  out.frames.set(s.plan.group_of.size());
  out.groups.set(s.plan.groups());
  std::size_t simulated = 0;
  for (const SampleWindow& w : s.windows) simulated += w.frames();
  out.frames_simulated.set(simulated);
  out.windows.set(s.windows.size());
  out.signature_triangle_stride.set(kSignatureTriangleStride);
  const SampledTotal cycles = extrapolate(s.plan, per_group(s, [](const SequenceFrameStats& m) { return m.interval_cycles.value(); }));
  out.total_cycles.set(cycles.total);
  out.total_cycles_error_pct.set(cycles.error_pct);
  out.total_ms.set(cycles.total * s.ms_per_cycle);
  const SampledTotal bytes = extrapolate(s.plan, per_group(s, [](const SequenceFrameStats& m) { return m.dram_interval_bytes.as_double(); }));
  out.dram_bytes.set(bytes.total);
  out.dram_bytes_error_pct.set(bytes.error_pct);
  const SampledTotal energy = extrapolate(s.plan, per_group(s, [](const SequenceFrameStats& m) { return m.energy_mj.value(); }));
  out.energy_mj.set(energy.total);
  out.energy_error_pct.set(energy.error_pct);
  return out;
}

SequenceSummaryStats summarize_sampled_sequence(const SampledSequence& s) {
  const SamplingSummaryStats summary = summarize_sampled(s);
  return summarize_frames(frame_figures(s), summary.total_ms.value(), summary.energy_mj.value() * 1e9);
}

std::vector<StatRecord> sampled_rows(const SampledSequence& s) {
  std::vector<StatRecord> out;
  const std::vector<SequenceFrameStats> frames = frame_figures(s);
  for (std::size_t k = 0; k < frames.size(); ++k) {
    const std::size_t g = s.plan.group_of[k];
    SampledFrameStats f;
    f.group.set(g);
    f.representative.set(s.plan.representative[g] == k ? 1 : 0);
    f.interval_cycles.set(frames[k].interval_cycles.value());
    f.interval_ms.set(frames[k].interval_ms.value());
    f.dram_interval_bytes.set(frames[k].dram_interval_bytes.value());
    f.energy_mj.set(frames[k].energy_mj.value());
    f.at_period_energy_mj.set(frames[k].at_period_energy_mj.value());
    const std::string scope = SampledFrameStats::kScopePrefix + std::to_string(k);
    collect_stats(f, scope, out);
    const auto values = s.signatures[k].values();
    for (std::size_t i = 0; i < FrameSignature::kFeatures; ++i) {
      const FrameSignature::Feature& feature = FrameSignature::features()[i];
      out.push_back({scope, feature.name, values[i], feature.unit, feature.description});
    }
  }
  const SamplingSummaryStats summary = summarize_sampled(s);
  collect_stats(summary, SamplingSummaryStats::kScope, out);
  for (std::size_t g = 0; g < s.plan.groups(); ++g) {
    collect_stats(s.measured[g], SequenceFrameStats::kScopePrefix + std::to_string(s.plan.representative[g]), out);
  }
  collect_stats(summarize_sampled_sequence(s), SequenceSummaryStats::kScope, out);
  return out;
}

}  // namespace tbdr
