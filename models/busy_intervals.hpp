#pragma once
// When a unit was busy: the timing model's reservations of a unit during one command, merged into
// a bounded list of intervals (in core cycles) for the run's timeline (`tbdrsim run --timeline`).
#include <algorithm>
#include <cstddef>
#include <tuple>
#include <vector>

namespace tbdr {

/// One stretch of time a unit was busy: [start_cycle, end_cycle], holding busy_cycles of work
/// (less than the span when merging closed gaps between reservations).
struct BusyInterval {
  double start_cycle = 0;
  double end_cycle = 0;
  double busy_cycles = 0;
};

/// The most busy intervals one unit keeps over the frame: in the timing model each command's unit
/// gets a share, kFrameBusyIntervals / commands, clamped to [kMinCommandBusyIntervals,
/// kMaxCommandBusyIntervals]; a DRAM channel's data bus keeps kFrameBusyIntervals. A timeline
/// file of a few megabytes even for forward_multipass's hundreds of passes.
inline constexpr std::size_t kFrameBusyIntervals = 1024;
/// At least the first and the last stretch of a unit's work in a command.
inline constexpr std::size_t kMinCommandBusyIntervals = 2;
/// At most this many per command and unit: finer than a timeline viewer shows a pass.
inline constexpr std::size_t kMaxCommandBusyIntervals = 64;

/// A unit's busy intervals in the order they start, at most `cap` of them, in the time unit of
/// its caller (core cycles in the timing model, picoseconds in the DRAM). Reservations that follow
/// each other within `adjacent` are one interval. When the list passes its cap, it is
/// merged down to half the cap by closing its smallest gaps (ties: every other one, so evenly
/// spaced work coarsens evenly); each interval's busy_cycles stays the exact sum of what it covers.
class BusyIntervals {
 public:
  /// The timing model reserves a unit for whole cycles (a reservation of 2.5 cycles holds it for
  /// 3), so back-to-back reservations leave less than a cycle between one's work and the next's.
  static constexpr double kAdjacentCycles = 1.0;

  explicit BusyIntervals(std::size_t cap = kMaxCommandBusyIntervals, double adjacent = kAdjacentCycles)
      : cap_(cap < 2 ? 2 : cap), adjacent_(adjacent) {}

  /// Books `busy` cycles of work from `start` to `end` (start no earlier than the previous start).
  void add(double start, double end, double busy) {
    if (!(end > start) && !(busy > 0)) return;
    if (!list_.empty() && start - list_.back().end_cycle <= adjacent_) {
      BusyInterval& b = list_.back();
      if (end > b.end_cycle) b.end_cycle = end;
      b.busy_cycles += busy;
    } else {
      list_.push_back({start, end, busy});
    }
    if (list_.size() > cap_) coarsen(cap_ / 2);
  }

  const std::vector<BusyInterval>& intervals() const { return list_; }

 private:
  /// Closes the smallest gaps until `target` intervals are left.
  void coarsen(std::size_t target) {
    const std::size_t n = list_.size();
    std::vector<std::size_t> gaps(n - 1);  // gap g lies between interval g and g + 1
    for (std::size_t g = 0; g + 1 < n; ++g) gaps[g] = g;
    auto gap = [&](std::size_t g) { return list_[g + 1].start_cycle - list_[g].end_cycle; };
    std::sort(gaps.begin(), gaps.end(), [&](std::size_t a, std::size_t b) {
      return std::make_tuple(gap(a), a % 2, a) < std::make_tuple(gap(b), b % 2, b);
    });
    std::vector<bool> close(n - 1, false);
    for (std::size_t k = 0; k < n - target; ++k) close[gaps[k]] = true;
    std::vector<BusyInterval> merged = {list_[0]};
    for (std::size_t i = 1; i < n; ++i) {
      if (close[i - 1]) {
        merged.back().end_cycle = std::max(merged.back().end_cycle, list_[i].end_cycle);
        merged.back().busy_cycles += list_[i].busy_cycles;
      } else {
        merged.push_back(list_[i]);
      }
    }
    list_ = std::move(merged);
  }

  std::size_t cap_;
  double adjacent_;
  std::vector<BusyInterval> list_;
};

}  // namespace tbdr
