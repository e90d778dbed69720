#pragma once
// Where a pipelined run's two critical threads run. With the timing model beside the functional
// run (`--threads N`, N > 1) there are N + 1 busy threads on N cores: the caller's thread (geometry
// delivery, binning, the serial steps, its share of the tiles), the timing model's, and N - 1 tile
// helpers at a lower priority that take what those two leave idle. When the kernel puts the caller
// and the timing model on one core, each gets half of it while a helper has a core to itself, and
// Linux's load balancer may leave them so for the rest of the frame (a per-thread timeline from
// `perf record` showed the two at half a core each through the whole tile phase, the helper at a
// full one). Measured at 1080p, 1024 lights, 2 threads on 2 cores: plain_forward ran so in 3 of 15
// runs, ending 0.08 s later. CriticalThreadPlacement keeps the two
// on different CPUs while the frame runs, the helpers free; when this process does not have the
// machine's CPUs to itself (fewer threads than CPUs it may use: a sweep's workers share them) it
// leaves every thread where the kernel puts it. Measured against leaving them to the kernel
// (2 threads, interleaved, wall s, median): on an otherwise idle host the same medians, the slowest
// of 11 plain_forward 0.263 -> 0.236 and light_prepass 0.881 -> 0.850; beside one busy process of
// another user plain_forward 0.345 -> 0.308, deferred 0.828 -> 0.716, light_prepass 1.076 ->
// 1.011, visibility_buffer 0.635 -> 0.578; beside two (both cores taken) within 3 % either way
// (plain_forward 0.557 -> 0.576, deferred 1.221 -> 1.250, light_prepass 1.785 -> 1.759); two runs
// at once about the same (plain_forward pairs 0.395 -> 0.404 s, deferred 1.022 -> 1.035).
#include <mutex>
#include <vector>

namespace tbdr {

/// CPU numbers (the kernel's CPU ids).
using CpuList = std::vector<int>;

/// The CPUs the calling thread may run on, in increasing order (empty where not known: not Linux).
CpuList allowed_cpus();

/// The CPUs for the timing model's thread: every CPU of `allowed` but `caller_cpu`. Empty (leave
/// both where the kernel puts them) unless `allowed` has at least two CPUs, `caller_cpu` is one of
/// them and the run's `threads` are at least as many as `allowed` (the run has them to itself).
CpuList cpus_apart_from(const CpuList& allowed, int caller_cpu, unsigned threads);

/// Keeps the caller's thread and the timing model's on different CPUs while a pipelined frame runs.
class CriticalThreadPlacement {
 public:
  /// On the caller's thread, before the timing thread starts: notes the caller's thread, the CPU it
  /// runs on and the CPUs it may use, for a run of `threads` threads.
  explicit CriticalThreadPlacement(unsigned threads);
  CriticalThreadPlacement(const CriticalThreadPlacement&) = delete;
  CriticalThreadPlacement& operator=(const CriticalThreadPlacement&) = delete;
  ~CriticalThreadPlacement() { restore(); }

  /// On the timing model's thread, once the frame has begun (its tile helpers exist: threads
  /// inherit their creator's CPUs, and they keep all of them): pins the caller's thread to the CPU
  /// it ran on and this thread to the others. Nothing when the placement does not apply, or once
  /// restore() ran. A refusal (a sandbox) changes no result: ignored.
  void keep_apart();
  /// On the caller's thread: gives it back every CPU it had (once; keep_apart does nothing after).
  void restore();
  /// Whether keep_apart pinned the two threads (and restore() has not run yet).
  bool pinned() const;

 private:
  mutable std::mutex mutex_;
  CpuList allowed_;       ///< the caller's CPUs when constructed
  CpuList timing_cpus_;   ///< cpus_apart_from: empty when the placement does not apply
  int caller_cpu_ = -1;
  long caller_tid_ = 0;
  bool pinned_ = false;
  bool restored_ = false;
};

}  // namespace tbdr
