#pragma once
// The discrete-event kernel: one queue of callables, each due at a Tick, executed in the
// deterministic order (tick, priority, insertion sequence) as in gem5. Events are lambdas; they
// may schedule and cancel other events (including at the current tick) while they run.
//
// Hot path: the heap holds 24-byte keys; the callables live out of line in a slot table (reused
// through a free list) and are moved out of their slot before being invoked. Small callables are
// stored inline in the slot (no allocation); large ones are boxed in a unique_ptr. Cancellation is
// lazy: the slot is freed at once and its stale heap key is skipped when it surfaces.
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <memory>
#include <new>
#include <optional>
#include <type_traits>
#include <utility>
#include <vector>

#include "kernel/time.hpp"

namespace tbdr {

/// Named ordering of events due at the same tick: lower values run first.
enum class Priority : std::int8_t {
  /// DRAM read data / write acknowledgements: delivered first so that every unit acting at this
  /// tick sees the memory system's state as of this tick.
  DramResponse = -30,
  /// Cache hits and fills returned to requesters (after DRAM responses have filled the caches).
  CacheResponse = -20,
  /// Everything without a reason to be elsewhere: queue hand-offs, command processor actions.
  Default = 0,
  /// A unit's per-cycle operate(): runs once all responses and hand-offs of the tick have landed.
  UnitOperate = 20,
  /// Statistics sampling: observes the state after all units operated at this tick.
  Stats = 40,
  /// Progress and deadlock checks: last, so they see the tick's completed work.
  Watchdog = 60,
};

/// Human-readable name of a priority level ("DramResponse", ...).
const char* to_string(Priority p);

/// A move-only type-erased `void()` callable with small-buffer storage; the event payload.
class EventCallback {
 public:
  static constexpr std::size_t kInlineBytes = 48;

  EventCallback() = default;

  template <class F>
    requires(!std::is_same_v<std::decay_t<F>, EventCallback> && std::is_invocable_r_v<void, std::decay_t<F>&>)
  EventCallback(F&& f) {  // NOLINT(google-explicit-constructor): lambdas convert implicitly
    using Fn = std::decay_t<F>;
    if constexpr (sizeof(Fn) <= kInlineBytes && alignof(Fn) <= alignof(std::max_align_t) &&
                  std::is_trivially_copyable_v<Fn> && std::is_trivially_destructible_v<Fn>) {
      // The common case ([&, i] captures): relocated by copying the whole buffer, which is
      // zeroed first so that no indeterminate byte is ever copied.
      std::memset(buf_, 0, kInlineBytes);
      ::new (static_cast<void*>(buf_)) Fn(std::forward<F>(f));
      ops_ = &kTrivialOps<Fn>;
    } else if constexpr (sizeof(Fn) <= kInlineBytes && alignof(Fn) <= alignof(std::max_align_t) &&
                         std::is_nothrow_move_constructible_v<Fn>) {
      ::new (static_cast<void*>(buf_)) Fn(std::forward<F>(f));
      ops_ = &kOps<Fn>;
    } else {
      using Box = std::unique_ptr<Fn>;
      ::new (static_cast<void*>(buf_)) Box(std::make_unique<Fn>(std::forward<F>(f)));
      ops_ = &kBoxOps<Fn>;
    }
  }

  EventCallback(EventCallback&& o) noexcept : ops_(o.ops_) {
    if (ops_) relocate_from(o);
  }
  EventCallback& operator=(EventCallback&& o) noexcept {
    if (this != &o) {
      reset();
      if (o.ops_) {
        ops_ = o.ops_;
        relocate_from(o);
      }
    }
    return *this;
  }
  EventCallback(const EventCallback&) = delete;
  EventCallback& operator=(const EventCallback&) = delete;
  ~EventCallback() { reset(); }

  explicit operator bool() const { return ops_ != nullptr; }
  void operator()() { ops_->invoke(buf_); }
  void reset() noexcept {
    if (ops_) {
      if (ops_->destroy) ops_->destroy(buf_);
      ops_ = nullptr;
    }
  }

 private:
  struct Ops {
    void (*invoke)(void*);
    void (*relocate)(void* dst, void* src) noexcept;  // move-construct dst from src, destroy src;
                                                      // null: trivially copyable, memcpy the buffer
    void (*destroy)(void*) noexcept;                  // null: trivially destructible
  };
  // Precondition: ops_ == o.ops_ != nullptr.
  void relocate_from(EventCallback& o) noexcept {
    if (ops_->relocate) {
      ops_->relocate(buf_, o.buf_);
    } else {
      std::memcpy(buf_, o.buf_, kInlineBytes);
    }
    o.ops_ = nullptr;
  }
  template <class Fn>
  static constexpr Ops kTrivialOps{[](void* p) { (*static_cast<Fn*>(p))(); }, nullptr, nullptr};
  template <class Fn>
  static constexpr Ops kOps{
      [](void* p) { (*static_cast<Fn*>(p))(); },
      [](void* dst, void* src) noexcept {
        ::new (dst) Fn(std::move(*static_cast<Fn*>(src)));
        static_cast<Fn*>(src)->~Fn();
      },
      [](void* p) noexcept { static_cast<Fn*>(p)->~Fn(); },
  };
  template <class Fn>
  static constexpr Ops kBoxOps{
      [](void* p) { (**static_cast<std::unique_ptr<Fn>*>(p))(); },
      [](void* dst, void* src) noexcept {
        using Box = std::unique_ptr<Fn>;
        ::new (dst) Box(std::move(*static_cast<Box*>(src)));
        static_cast<Box*>(src)->~Box();
      },
      [](void* p) noexcept {
        using Box = std::unique_ptr<Fn>;
        static_cast<Box*>(p)->~Box();
      },
  };

  alignas(std::max_align_t) unsigned char buf_[kInlineBytes];
  const Ops* ops_ = nullptr;
};

/// Handle to a scheduled event, used only to cancel it; stays safe to use after the event ran.
struct EventId {
  std::uint32_t slot = UINT32_MAX;
  std::uint64_t seq = 0;  // insertion sequence number; 0 never names an event
  friend constexpr bool operator==(EventId, EventId) = default;
};

/// The simulator's single event queue: owns pending events and the current simulated time.
class EventQueue {
 public:
  EventQueue() = default;
  EventQueue(const EventQueue&) = delete;
  EventQueue& operator=(const EventQueue&) = delete;

  /// Schedules `fn` to run at tick `when` (>= now(), else std::logic_error).
  EventId schedule(Tick when, Priority priority, EventCallback fn);
  EventId schedule(Tick when, EventCallback fn) { return schedule(when, Priority::Default, std::move(fn)); }
  /// Schedules `fn` to run `delay` (>= 0) after now().
  EventId schedule_in(Tick delay, Priority priority, EventCallback fn);
  EventId schedule_in(Tick delay, EventCallback fn) { return schedule_in(delay, Priority::Default, std::move(fn)); }

  /// Cancels a pending event; false if it already ran, was already cancelled, or never existed.
  bool cancel(EventId id);
  /// True while `id` names an event that has neither run nor been cancelled.
  bool is_pending(EventId id) const {
    return id.slot < slots_.size() && slots_[id.slot].seq == id.seq && id.seq != 0;
  }

  /// Current simulated time: the tick of the event being (or last) executed.
  Tick now() const { return now_; }
  /// No pending (uncancelled) events.
  bool empty() const { return live_ == 0; }
  /// Number of pending (uncancelled) events.
  std::size_t size() const { return live_; }
  /// Tick of the next pending event, if any.
  std::optional<Tick> next_tick();
  /// Events executed since construction.
  std::uint64_t events_executed() const { return executed_; }

  /// Executes the next pending event, advancing now() to its tick; false if there was none.
  bool step();
  /// Executes every event due at or before `limit` (including ones they schedule); returns how
  /// many ran. now() is left at the last executed event's tick (not advanced to `limit`).
  std::uint64_t run_until(Tick limit);
  /// Executes events until the queue is empty; returns how many ran.
  std::uint64_t run() { return run_until(Tick::max()); }

 private:
  // Heap key, ordered by (tick, priority, seq). Priority and seq are packed into one word
  // (priority biased to unsigned in the top 8 bits, seq in the low 56) so that the comparison is
  // two integer compares; seq is unique, so the order is total.
  static constexpr int kSeqBits = 56;
  static constexpr std::uint64_t kSeqMask = (std::uint64_t{1} << kSeqBits) - 1;
  static constexpr std::uint64_t pack_order(Priority p, std::uint64_t seq) {
    return (static_cast<std::uint64_t>(static_cast<std::int64_t>(p) + 128) << kSeqBits) | seq;
  }
  struct Key {
    std::int64_t tick_ps;
    std::uint64_t order;  // pack_order(priority, seq)
    std::uint32_t slot;
    std::uint64_t seq() const { return order & kSeqMask; }
  };
  // Min-heap comparator for std::push_heap / pop_heap (which build max-heaps): "a after b".
  struct Later {
    bool operator()(const Key& a, const Key& b) const {
      // Branch-free: event order is data-dependent, so branches here mispredict half the time.
      return (a.tick_ps > b.tick_ps) | ((a.tick_ps == b.tick_ps) & (a.order > b.order));
    }
  };
  struct Slot {
    EventCallback fn;
    std::uint64_t seq = 0;  // seq of the event occupying the slot; 0 when free
  };

  // Drops cancelled keys from the top of the heap; true if a live event is on top.
  bool settle_top();
  void release_slot(std::uint32_t slot);
  void compact();

  std::vector<Key> heap_;
  std::vector<Slot> slots_;
  std::vector<std::uint32_t> free_slots_;
  std::size_t live_ = 0;
  std::uint64_t next_seq_ = 1;
  std::uint64_t executed_ = 0;
  Tick now_{0};
};

}  // namespace tbdr
