#pragma once
// The run loop: drains the event queue and watches the hardware units for deadlock and livelock,
// in the spirit of ChampSim's progress-returning operate(). Units schedule their own events; the
// loop only needs to ask each one whether it still has work, how much it has done so far, and
// what it is waiting for, so that a stuck model ends in a StallError naming the culprits instead
// of a silent early finish or an endless run.
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "kernel/errors.hpp"
#include "kernel/event_queue.hpp"
#include "kernel/time.hpp"

namespace tbdr {

/// A named hardware unit (ISP, TSP, tiler, DRAM controller, ...) as seen by the run loop.
class Unit {
 public:
  virtual ~Unit() = default;
  /// Stable name used in stall reports ("isp0", "dram").
  virtual std::string_view name() const = 0;
  /// True while the unit has accepted work it has not finished (queued, in flight, waiting).
  virtual bool has_pending_work() const = 0;
  /// Monotone count of work done (requests served, tiles shaded, ...). It must increase at least
  /// once per watchdog window while the unit is working normally.
  virtual std::uint64_t progress() const = 0;
  /// What the unit is blocked on right now ("input queue 'tiles' empty", "waiting for DRAM read
  /// of 64 B at 0x1000", "output queue full"); only asked when it is reported as stuck.
  virtual std::string stall_reason() const = 0;
};

/// Watchdog limits of a RunLoop.
struct WatchdogConfig {
  /// Livelock: no unit's progress() changed for this much simulated time while events kept
  /// firing. Default 1 ms (600k cycles at 600 MHz), far beyond any legitimate memory latency.
  Tick window{1'000'000'000};
  /// Zero-time livelock: this many events ran without any unit's progress() changing (catches
  /// events that keep rescheduling themselves at the current tick, where time never advances).
  std::uint64_t max_events_without_progress = 100'000'000;
};

/// Outcome of a run that completed normally.
struct RunSummary {
  Tick final_tick;                   // tick of the last executed event
  std::uint64_t events_executed = 0; // events run by this call
};

/// Runs an EventQueue to completion while a watchdog checks the units for deadlock / livelock.
class RunLoop {
 public:
  RunLoop(EventQueue& queue, std::vector<Unit*> units, WatchdogConfig watchdog = {});

  /// Executes events until the queue is empty. Throws StallError if the queue drains while a unit
  /// still has pending work (deadlock), or if the watchdog limits are exceeded (livelock); the
  /// message names every unit with pending work and its stall_reason, the tick and event count.
  RunSummary run();

  const WatchdogConfig& watchdog() const { return watchdog_; }

 private:
  // Samples every unit's progress; true if any changed since the last sample.
  bool sample_progress();
  [[noreturn]] void throw_stall(const std::string& what, std::uint64_t events_run) const;

  EventQueue& queue_;
  std::vector<Unit*> units_;
  WatchdogConfig watchdog_;
  std::vector<std::uint64_t> last_progress_;
};

}  // namespace tbdr
