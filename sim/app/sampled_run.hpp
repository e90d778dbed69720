#pragma once
// Sampled simulation of a sequence (tbdrsim run --sample K): which runs of frames the timing model
// runs for a sampling plan (analysis/frame_sampling.hpp), and the rows of the run that estimate
// the whole sequence from them. The run driver does the simulating (run_driver.cpp).
#include <cstddef>
#include <vector>

#include "analysis/frame_sampling.hpp"
#include "app/run_stats.hpp"
#include "kernel/stats.hpp"
#include "models/frame_signature.hpp"
#include "trace/trace.hpp"

namespace tbdr {

/// Consecutive frames [first, last] of a sequence simulated together, from cold.
struct SampleWindow {
  std::size_t first = 0;
  std::size_t last = 0;
  std::size_t frames() const { return last - first + 1; }
};

/// The windows the timing model runs for `plan` over a sequence of `frames` frames: each
/// representative with the frame before it (which warms the caches and whose tiles the
/// representative's binning overlaps) and the frame after it (whose first binning competes with
/// the representative's tiles: frame_after_representative), windows that overlap or touch merged
/// into one; in frame order.
/// `warmup`: the frames before each representative (1 by default: kSampledWarmupFrames).
std::vector<SampleWindow> sample_windows(const SamplingPlan& plan, std::size_t frames, std::size_t warmup = 1);

/// The frame after a representative as its window needs it: its commands up to and including its
/// first render pass. Only that pass's binning can run before the representative ends (the next
/// binning needs the parameter buffer of the representative's last pass, free when that pass's
/// tiles are done, and fragment work runs in frame order), so what the representative's figures
/// see of the frame after it is the same with or without the rest, which is not simulated.
Trace frame_after_representative(const Trace& frame);

/// A sampled run's inputs to its rows.
struct SampledSequence {
  SamplingPlan plan;
  std::vector<FrameSignature> signatures;        ///< per frame
  std::vector<SequenceFrameStats> measured;      ///< per group: its representative as its window ran it
  std::vector<SampleWindow> windows;
  double ms_per_cycle = 0;                       ///< of the GPU's clock
};

/// The sequence's estimate: totals over groups with their error estimates (analysis/extrapolate).
SamplingSummaryStats summarize_sampled(const SampledSequence& s);

/// The sequence's summary (sequence/summary) over every frame's figures, measured or its
/// representative's, with the estimated totals' time and energy (`estimate`: summarize_sampled's).
SequenceSummaryStats summarize_sampled_sequence(const SampledSequence& s, const SamplingSummaryStats& estimate);

/// Each frame's figures (interval, DRAM bytes, energy): its own where it was simulated for its
/// group, else its representative's.
std::vector<SequenceFrameStats> sampled_frame_figures(const SampledSequence& s);

}  // namespace tbdr
