#include "app/sampled_run.hpp"

#include <algorithm>
#include <string>
#include <variant>

#include "app/stat_rows.hpp"

namespace tbdr {

std::vector<SampleWindow> sample_windows(const SamplingPlan& plan, std::size_t frames, std::size_t warmup) {
  std::vector<std::size_t> reps = plan.representative;
  std::sort(reps.begin(), reps.end());
  std::vector<SampleWindow> out;
  for (std::size_t r : reps) {
    const SampleWindow w{r > warmup ? r - warmup : 0, std::min(r + 1, frames - 1)};
    if (!out.empty() && w.first <= out.back().last + 1) {
      out.back().last = std::max(out.back().last, w.last);
    } else {
      out.push_back(w);
    }
  }
  return out;
}

std::vector<SequenceFrameStats> sampled_frame_figures(const SampledSequence& s) {
  std::vector<SequenceFrameStats> frames;
  for (std::size_t k = 0; k < s.plan.group_of.size(); ++k) {
    const SequenceFrameStats& m = s.measured[s.plan.group_of[k]];
    SequenceFrameStats f;
    copy_frame_interval(m, f);
    frames.push_back(f);
  }
  return frames;
}

Trace frame_after_representative(const Trace& frame) {
  Trace out = frame;
  const auto first_pass = std::find_if(out.commands.begin(), out.commands.end(),
                                       [](const TraceCommand& c) { return std::holds_alternative<PassDesc>(c); });
  if (first_pass != out.commands.end()) out.commands.erase(first_pass + 1, out.commands.end());
  return out;
}

namespace {

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
  std::vector<std::vector<double>> signatures;
  for (const FrameSignature& f : s.signatures) signatures.push_back(f.values());
  const SampledTotal cycles = extrapolate(s.plan, signatures, per_group(s, [](const SequenceFrameStats& m) { return m.interval_cycles.value(); }));
  out.total_cycles.set(cycles.total);
  out.total_cycles_error_pct.set(cycles.error_pct);
  out.total_ms.set(cycles.total * s.ms_per_cycle);
  const SampledTotal bytes = extrapolate(s.plan, signatures, per_group(s, [](const SequenceFrameStats& m) { return m.dram_interval_bytes.as_double(); }));
  out.dram_bytes.set(bytes.total);
  out.dram_bytes_error_pct.set(bytes.error_pct);
  const SampledTotal energy = extrapolate(s.plan, signatures, per_group(s, [](const SequenceFrameStats& m) { return m.energy_mj.value(); }));
  out.energy_mj.set(energy.total);
  out.energy_error_pct.set(energy.error_pct);
  return out;
}

SequenceSummaryStats summarize_sampled_sequence(const SampledSequence& s, const SamplingSummaryStats& estimate) {
  return summarize_frames(sampled_frame_figures(s), estimate.total_ms.value(), estimate.energy_mj.value() * 1e9);
}

}  // namespace tbdr
