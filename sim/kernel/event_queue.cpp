#include "kernel/event_queue.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>

namespace tbdr {

const char* to_string(Priority p) {
  switch (p) {
    case Priority::DramResponse: return "DramResponse";
    case Priority::CacheResponse: return "CacheResponse";
    case Priority::Default: return "Default";
    case Priority::UnitOperate: return "UnitOperate";
    case Priority::Stats: return "Stats";
    case Priority::Watchdog: return "Watchdog";
  }
  return "Priority(?)";
}

EventId EventQueue::schedule(Tick when, Priority priority, EventCallback fn) {
  if (when < now_) {
    throw std::logic_error("EventQueue: event scheduled in the past (at " + std::to_string(when.ps()) +
                           " ps, now " + std::to_string(now_.ps()) + " ps)");
  }
  if (!fn) throw std::logic_error("EventQueue: empty event callable");
  std::uint32_t slot;
  if (!free_slots_.empty()) {
    slot = free_slots_.back();
    free_slots_.pop_back();
  } else {
    if (slots_.size() >= UINT32_MAX) throw std::length_error("EventQueue: too many pending events");
    slot = static_cast<std::uint32_t>(slots_.size());
    slots_.emplace_back();
  }
  if (next_seq_ > kSeqMask) throw std::length_error("EventQueue: event sequence numbers exhausted");
  const std::uint64_t seq = next_seq_++;
  slots_[slot].fn = std::move(fn);
  slots_[slot].seq = seq;
  heap_.push_back(Key{when.ps(), pack_order(priority, seq), slot});
  std::push_heap(heap_.begin(), heap_.end(), Later{});
  ++live_;
  return EventId{slot, seq};
}

EventId EventQueue::schedule_in(Tick delay, Priority priority, EventCallback fn) {
  if (delay < Tick::zero()) {
    throw std::logic_error("EventQueue: negative delay " + std::to_string(delay.ps()) + " ps");
  }
  if (delay > Tick::max() - now_) throw std::overflow_error("EventQueue: delay overflows the tick range");
  return schedule(now_ + delay, priority, std::move(fn));
}

void EventQueue::release_slot(std::uint32_t slot) {
  slots_[slot].seq = 0;
  free_slots_.push_back(slot);
}

bool EventQueue::cancel(EventId id) {
  if (!is_pending(id)) return false;
  Slot& s = slots_[id.slot];
  s.fn.reset();
  release_slot(id.slot);
  --live_;
  // Stale keys are normally skipped when they reach the top; rebuild if they dominate the heap so
  // cancel-heavy models (timeouts that rarely fire) don't grow it without bound.
  if (heap_.size() > 1024 && heap_.size() > 4 * live_) compact();
  return true;
}

void EventQueue::compact() {
  std::erase_if(heap_, [this](const Key& k) { return slots_[k.slot].seq != k.seq(); });
  std::make_heap(heap_.begin(), heap_.end(), Later{});
}

bool EventQueue::settle_top() {
  while (!heap_.empty()) {
    const Key& top = heap_.front();
    if (slots_[top.slot].seq == top.seq()) return true;
    std::pop_heap(heap_.begin(), heap_.end(), Later{});
    heap_.pop_back();
  }
  return false;
}

std::optional<Tick> EventQueue::next_tick() {
  if (!settle_top()) return std::nullopt;
  return Tick{heap_.front().tick_ps};
}

bool EventQueue::step() {
  if (!settle_top()) return false;
  const Key top = heap_.front();
  std::pop_heap(heap_.begin(), heap_.end(), Later{});
  heap_.pop_back();
  // Move the callable out and free its slot before running it: the event may schedule (growing
  // slots_) or try to cancel itself (a no-op now), and an exception leaves the queue consistent.
  EventCallback fn = std::move(slots_[top.slot].fn);
  release_slot(top.slot);
  --live_;
  now_ = Tick{top.tick_ps};
  ++executed_;
  fn();
  return true;
}

std::uint64_t EventQueue::run_until(Tick limit) {
  std::uint64_t ran = 0;
  while (settle_top() && heap_.front().tick_ps <= limit.ps()) {
    step();
    ++ran;
  }
  return ran;
}

}  // namespace tbdr
