#include "kernel/run_loop.hpp"

#include <algorithm>
#include <stdexcept>

namespace tbdr {

namespace {

// Progress is sampled at most every this many events (and at least 8 times per window of
// simulated time), so the per-event cost of the watchdog is two integer comparisons.
constexpr std::uint64_t kCheckEveryEvents = 4096;

Tick saturating_add(Tick a, Tick b) { return a > Tick::max() - b ? Tick::max() : a + b; }

}  // namespace

RunLoop::RunLoop(EventQueue& queue, std::vector<Unit*> units, WatchdogConfig watchdog)
    : queue_(queue), units_(std::move(units)), watchdog_(watchdog), last_progress_(units_.size(), 0) {
  for (const Unit* u : units_) {
    if (u == nullptr) throw std::invalid_argument("RunLoop: null unit");
  }
  if (watchdog_.window <= Tick::zero()) throw std::invalid_argument("RunLoop: watchdog window must be > 0");
  if (watchdog_.max_events_without_progress == 0) {
    throw std::invalid_argument("RunLoop: max_events_without_progress must be > 0");
  }
}

bool RunLoop::sample_progress() {
  bool changed = false;
  for (std::size_t i = 0; i < units_.size(); ++i) {
    const std::uint64_t p = units_[i]->progress();
    if (p != last_progress_[i]) {
      last_progress_[i] = p;
      changed = true;
    }
  }
  return changed;
}

void RunLoop::throw_stall(const std::string& what, std::uint64_t events_run) const {
  std::string msg = "simulation stalled: " + what + "\n  at tick " + std::to_string(queue_.now().ps()) +
                    " ps after " + std::to_string(events_run) + " events (" +
                    std::to_string(queue_.events_executed()) + " since the queue was created)\n";
  std::size_t stuck = 0;
  for (const Unit* u : units_) {
    if (!u->has_pending_work()) continue;
    if (stuck++ == 0) msg += "  stuck units:\n";
    msg += "    ";
    msg += u->name();
    msg += ": ";
    msg += u->stall_reason();
    msg += " (progress " + std::to_string(u->progress()) + ")\n";
  }
  if (stuck == 0) msg += "  no unit reports pending work: some event keeps rescheduling itself\n";
  throw StallError(msg);
}

RunSummary RunLoop::run() {
  const std::uint64_t start_events = queue_.events_executed();
  const std::uint64_t check_every = std::min(kCheckEveryEvents, watchdog_.max_events_without_progress);
  const Tick check_interval = std::max(Tick{watchdog_.window.ps() / 8}, Tick{1});

  sample_progress();  // baseline
  Tick last_progress_tick = queue_.now();
  std::uint64_t events_at_last_progress = start_events;
  Tick next_check_tick = saturating_add(queue_.now(), check_interval);
  std::uint64_t next_check_events = start_events + check_every;

  while (queue_.step()) {
    const std::uint64_t executed = queue_.events_executed();
    const Tick now = queue_.now();
    if (executed < next_check_events && now < next_check_tick) continue;

    if (sample_progress()) {
      last_progress_tick = now;
      events_at_last_progress = executed;
    } else if (now - last_progress_tick > watchdog_.window) {
      throw_stall("livelock: no unit made progress for " + std::to_string((now - last_progress_tick).ps()) +
                      " ps (since tick " + std::to_string(last_progress_tick.ps()) +
                      " ps; watchdog window " + std::to_string(watchdog_.window.ps()) +
                      " ps) while events kept firing",
                  executed - start_events);
    } else if (executed - events_at_last_progress >= watchdog_.max_events_without_progress) {
      throw_stall("livelock: " + std::to_string(executed - events_at_last_progress) +
                      " events ran without any unit making progress (limit " +
                      std::to_string(watchdog_.max_events_without_progress) + ")",
                  executed - start_events);
    }
    next_check_tick = saturating_add(now, check_interval);
    next_check_events = executed + check_every;
  }

  const std::uint64_t ran = queue_.events_executed() - start_events;
  for (const Unit* u : units_) {
    if (u->has_pending_work()) {
      throw_stall("deadlock: the event queue is empty but units still have pending work", ran);
    }
  }
  return RunSummary{queue_.now(), ran};
}

}  // namespace tbdr
