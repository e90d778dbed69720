#pragma once
// Sampled simulation of a frame sequence: which frames to simulate, and what the sequence's totals
// are estimated to be from them. The frames are grouped by their signatures (cheap figures of what
// each draws, models/frame_signature.hpp) with k-means, and the frame nearest each group's centre
// stands for the group, weighted by its size: the selection MEGsim makes (Anglada et al., "MEGsim:
// A Novel Methodology for Efficient Simulation of Graphics Workloads in GPUs", ISPASS 2022), as
// SimPoint does for program intervals (Sherwood et al., ASPLOS 2002). The first frame is a group
// of its own: it starts with cold caches and nothing to overlap, which no signature shows; so is
// the last, which nothing after it overlaps.
// Pure arithmetic: nothing here knows what a frame is.
#include <cstddef>
#include <vector>

namespace tbdr {

/// Frames at the start of a sequence that are always simulated and stand for themselves (the cold
/// first frame).
inline constexpr std::size_t kSampledColdFrames = 1;
/// Frames at the end of a sequence that are always simulated and stand for themselves (the last
/// frame: no later frame's binning competes with its tiles, so it ends sooner; on forward_plus at
/// 160x90 a quarter sooner than the frame before it).
inline constexpr std::size_t kSampledDrainFrames = 1;
/// Most rounds of k-means (Lloyd's iterations) before the grouping is taken as it is: it settles
/// within tens of rounds on hundreds of frames; the bound only keeps a pathological input finite.
inline constexpr int kSamplingMaxRounds = 200;

/// Which frame stands for which group.
struct SamplingPlan {
  std::vector<std::size_t> group_of;        ///< per frame: its group
  std::vector<std::size_t> representative;  ///< per group: the frame simulated for it
  std::vector<std::size_t> members;         ///< per group: how many frames it stands for
  /// Per group, per signature feature: the mean and the standard deviation over its frames (the
  /// deviation 0 for a group of one frame): how far its frames differ in what they draw.
  std::vector<std::vector<double>> feature_mean;
  std::vector<std::vector<double>> feature_sd;
  std::size_t groups() const { return representative.size(); }
};

/// Groups `signatures` (one vector of features per frame, all the same length) into at most
/// `representatives` groups, the first kSampledColdFrames and the last kSampledDrainFrames frames
/// each one of their own (when more frames remain), and picks
/// each group's representative. Features are compared after scaling each to unit standard
/// deviation over the frames (a constant feature is left out). Deterministic: the first centre
/// is the frame nearest the mean, each further one the frame farthest from the centres so far
/// (ties: the lower frame), then Lloyd's rounds. `representatives` >= the number of frames: every
/// frame stands for itself.
SamplingPlan plan_sampling(const std::vector<std::vector<double>>& signatures, std::size_t representatives);

/// A sequence's total of one figure estimated from its representatives' measured values.
struct SampledTotal {
  double total = 0;       ///< sum over groups of members x the representative's value
  /// Two standard errors of `total`, relative, in %: its standard error had each representative
  /// been drawn at random from its group (with the finite-population correction (n - 1) / n).
  /// A group's spread of the figure is predicted from its spread of one signature feature: the
  /// one whose least-squares line over the representatives (the cold frames left out) fits the
  /// figure best, times that line's slope. With fewer than 3 such representatives, or no feature
  /// that varies among them, the figure is taken to spread as much, relative to its value, as the
  /// group's most spread feature.
  double error_pct = 0;
  /// The feature the spread was predicted from (fitted_feature < 0: the fallback above).
  int fitted_feature = -1;
};

/// The total of one figure from `measured`, one value per group (its representative's), and its
/// error estimate from `signatures` (those plan_sampling grouped).
SampledTotal extrapolate(const SamplingPlan& plan, const std::vector<std::vector<double>>& signatures,
                         const std::vector<double>& measured);

}  // namespace tbdr
