// Tests for the discrete-event kernel: Tick/Cycles/ClockDomain (sim/time.hpp), EventQueue
// (sim/event_queue.hpp) and RunLoop with its watchdog (sim/run_loop.hpp).
#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <deque>
#include <functional>
#include <initializer_list>
#include <memory>
#include <ostream>
#include <random>
#include <stdexcept>
#include <string>
#include <tuple>
#include <vector>

#include "kernel/bits.hpp"
#include "kernel/errors.hpp"
#include "kernel/event_queue.hpp"
#include "kernel/run_loop.hpp"
#include "kernel/time.hpp"

namespace tbdr {

// GoogleTest printers, so failures show "1234 ps" rather than raw bytes.
void PrintTo(Tick t, std::ostream* os) { *os << t.ps() << " ps"; }
void PrintTo(Cycles c, std::ostream* os) { *os << c.count() << " cycles"; }

namespace {

// ---------------------------------------------------------------------------------------------
// Tick, Cycles, ClockDomain

template <class A, class B>
concept Addable = requires(A a, B b) { a + b; };
template <class A, class B>
concept Comparable = requires(A a, B b) { a < b; };

static_assert(!std::is_convertible_v<Cycles, Tick>);
static_assert(!std::is_convertible_v<Tick, Cycles>);
static_assert(!std::is_convertible_v<std::int64_t, Tick>);
static_assert(!Addable<Tick, Cycles>);
static_assert(!Addable<Cycles, Tick>);
static_assert(!Comparable<Tick, Cycles>);
static_assert(Addable<Tick, Tick> && Addable<Cycles, Cycles>);
static_assert(sizeof(Tick) == 8 && sizeof(Cycles) == 8);

TEST(ClockDomainTest, TickArithmetic) {
  EXPECT_EQ((Tick{5} + Tick{7}).ps(), 12);
  EXPECT_EQ((Tick{5} - Tick{7}).ps(), -2);
  EXPECT_EQ((Tick{5} * 3).ps(), 15);
  EXPECT_LT(Tick{1}, Tick{2});
  EXPECT_EQ(Tick::from_ns(3), Tick{3000});
  EXPECT_EQ(Tick::from_us(2), Tick{2'000'000});
  EXPECT_EQ((Cycles{4} + Cycles{6}).count(), 10);
}

TEST(ClockDomainTest, OneSecondIsExact) {
  const ClockDomain core("core", 600'000'000);
  const ClockDomain dram = ClockDomain::from_mhz("dram", 1866);
  EXPECT_EQ(dram.frequency_hz(), 1'866'000'000);
  const Tick one_second = dram.tick_of(Cycles{1'866'000'000});
  EXPECT_EQ(one_second.ps(), 1'000'000'000'000);
  EXPECT_EQ(core.cycles_at(one_second), Cycles{600'000'000});
  EXPECT_EQ(core.tick_of(Cycles{600'000'000}), one_second);
  EXPECT_EQ(dram.cycles_at(one_second), Cycles{1'866'000'000});
  // And one tick earlier, neither clock has completed its last cycle.
  EXPECT_EQ(core.cycles_at(one_second - Tick{1}), Cycles{599'999'999});
  EXPECT_EQ(dram.cycles_at(one_second - Tick{1}), Cycles{1'865'999'999});
  // Many seconds in: still exact (no accumulated rounding of the 535.9 ps period).
  EXPECT_EQ(dram.tick_of(Cycles{1'866'000'000LL * 3600}).ps(), 3600LL * 1'000'000'000'000);
  EXPECT_NEAR(dram.period_ps(), 535.9056806, 1e-6);
  EXPECT_NEAR(core.period_ps(), 1666.6666667, 1e-6);
}

TEST(ClockDomainTest, FirstEdgesRoundUp) {
  const ClockDomain dram("dram", 1'866'000'000);
  EXPECT_EQ(dram.tick_of(Cycles{0}), Tick{0});
  EXPECT_EQ(dram.tick_of(Cycles{1}), Tick{536});  // 535.9 ps, rounded up
  EXPECT_EQ(dram.tick_of(Cycles{2}), Tick{1072});  // 1071.8 ps
  EXPECT_EQ(dram.cycles_at(Tick{535}), Cycles{0});
  EXPECT_EQ(dram.cycles_at(Tick{536}), Cycles{1});
  const ClockDomain ps_clock("1THz", 1'000'000'000'000);
  EXPECT_EQ(ps_clock.tick_of(Cycles{12345}), Tick{12345});
  EXPECT_EQ(ps_clock.cycles_at(Tick{12345}), Cycles{12345});
}

TEST(ClockDomainTest, RoundTripIsExact) {
  const std::vector<std::int64_t> freqs_hz = {600'000'000, 1'866'000'000, 450'000'000, 850'000'000,
                                              1'000'000'000'000, 333'333'333, 7, 999'999'999'989};
  std::mt19937_64 rng(42);
  for (std::int64_t hz : freqs_hz) {
    const ClockDomain d("d", hz);
    for (std::int64_t n = 0; n < 5000; ++n) {
      ASSERT_EQ(d.cycles_at(d.tick_of(Cycles{n})), Cycles{n}) << hz << " Hz, cycle " << n;
    }
    std::uniform_int_distribution<std::int64_t> big(0, 1'000'000'000'000'000);  // up to ~1e6 s
    for (int i = 0; i < 5000; ++i) {
      const Cycles n{std::min<std::int64_t>(big(rng), hz * 1'000'000)};
      ASSERT_EQ(d.cycles_at(d.tick_of(n)), n) << hz << " Hz, cycle " << n.count();
      // Both fast (reduced-fraction, 64-bit) and slow paths agree with the textbook formulas.
      __extension__ typedef unsigned __int128 U128;
      const U128 f = static_cast<U128>(hz), s = 1'000'000'000'000;
      ASSERT_EQ(static_cast<U128>(d.tick_of(n).ps()), (static_cast<U128>(n.count()) * s + f - 1) / f);
      const std::int64_t t = std::min<std::int64_t>(big(rng), INT64_MAX / 2);
      ASSERT_EQ(static_cast<U128>(d.cycles_at(Tick{t}).count()), static_cast<U128>(t) * f / s);
      // The edge is the first tick at which cycle n has begun.
      if (d.tick_of(n) > Tick{0}) {
        ASSERT_LT(d.cycles_at(d.tick_of(n) - Tick{1}), n);
      }
    }
  }
}

TEST(ClockDomainTest, NextEdgeIsMonotoneAndAligned) {
  for (std::int64_t hz : {600'000'000LL, 1'866'000'000LL}) {
    const ClockDomain d("d", hz);
    Tick prev{0};
    for (std::int64_t t = 0; t < 20'000; ++t) {
      const Tick e = d.next_edge(Tick{t});
      ASSERT_GE(e, Tick{t});
      ASSERT_GE(e, prev);
      // Aligned: e is exactly the start tick of some cycle ...
      ASSERT_EQ(d.tick_of(d.cycles_at(e)), e);
      // ... and the first one at or after t.
      const Cycles c = d.cycles_at(e);
      if (c > Cycles{0}) {
        ASSERT_LT(d.tick_of(c - Cycles{1}), Tick{t});
      }
      ASSERT_GT(d.edge_after(Tick{t}), Tick{t});
      ASSERT_EQ(d.tick_of(d.cycles_at(d.edge_after(Tick{t}))), d.edge_after(Tick{t}));
      prev = e;
    }
  }
  const ClockDomain core("core", 600'000'000);
  EXPECT_EQ(core.after(Tick{0}, Cycles{3}), Tick{5000});
  EXPECT_EQ(core.after(Tick{1}, Cycles{0}), core.tick_of(Cycles{1}));
  EXPECT_EQ(core.after(Tick{1}, Cycles{2}), core.tick_of(Cycles{3}));
}

TEST(ClockDomainTest, RejectsBadInput) {
  EXPECT_THROW(ClockDomain("x", 0), std::invalid_argument);
  EXPECT_THROW(ClockDomain("x", 2'000'000'000'000), std::invalid_argument);
  EXPECT_THROW(ClockDomain::from_mhz("x", -5.0), std::invalid_argument);
  const ClockDomain d("d", 600'000'000);
  EXPECT_THROW(d.tick_of(Cycles{-1}), std::domain_error);
  EXPECT_THROW(d.tick_of(Cycles{INT64_MAX}), std::overflow_error);
}

// ---------------------------------------------------------------------------------------------
// EventQueue

TEST(EventQueueTest, OrdersByTickThenPriorityThenInsertion) {
  EventQueue q;
  std::vector<std::string> trace;
  auto rec = [&trace](std::string s) { return [&trace, s] { trace.push_back(s); }; };
  q.schedule(Tick{200}, Priority::Default, rec("t200"));
  q.schedule(Tick{100}, Priority::Stats, rec("t100-stats"));
  q.schedule(Tick{100}, Priority::UnitOperate, rec("t100-op-a"));
  q.schedule(Tick{100}, Priority::DramResponse, rec("t100-dram"));
  q.schedule(Tick{100}, Priority::UnitOperate, rec("t100-op-b"));
  q.schedule(Tick{100}, Priority::CacheResponse, rec("t100-cache"));
  q.schedule(Tick{100}, Priority::Watchdog, rec("t100-watchdog"));
  q.schedule(Tick{100}, Priority::Default, rec("t100-default"));
  q.schedule(Tick{100}, Priority::UnitOperate, rec("t100-op-c"));
  q.schedule(Tick{50}, Priority::Watchdog, rec("t50"));
  EXPECT_EQ(q.size(), 10u);
  EXPECT_EQ(q.next_tick(), Tick{50});
  EXPECT_EQ(q.run(), 10u);
  const std::vector<std::string> expected = {"t50",        "t100-dram",   "t100-cache", "t100-default",
                                             "t100-op-a",  "t100-op-b",   "t100-op-c",  "t100-stats",
                                             "t100-watchdog", "t200"};
  EXPECT_EQ(trace, expected);
  EXPECT_EQ(q.now(), Tick{200});
  EXPECT_EQ(q.events_executed(), 10u);
  EXPECT_TRUE(q.empty());
  EXPECT_STREQ(to_string(Priority::DramResponse), "DramResponse");
}

TEST(EventQueueTest, EventsScheduledAtTheCurrentTickRunInOrder) {
  EventQueue q;
  std::vector<std::string> trace;
  q.schedule(Tick{10}, Priority::UnitOperate, [&] {
    trace.push_back("op");
    // Same tick, lower priority value than the running event: still runs (now), after it.
    q.schedule(q.now(), Priority::DramResponse, [&] { trace.push_back("late-dram"); });
    q.schedule_in(Tick{0}, Priority::Stats, [&] { trace.push_back("stats"); });
  });
  q.schedule(Tick{10}, Priority::UnitOperate, [&] { trace.push_back("op2"); });
  q.run();
  const std::vector<std::string> expected = {"op", "late-dram", "op2", "stats"};
  EXPECT_EQ(trace, expected);
}

TEST(EventQueueTest, StepAndRunUntil) {
  EventQueue q;
  int ran = 0;
  for (int t = 1; t <= 10; ++t) q.schedule(Tick{t * 100}, [&] { ++ran; });
  EXPECT_TRUE(q.step());
  EXPECT_EQ(q.now(), Tick{100});
  EXPECT_EQ(q.run_until(Tick{500}), 4u);
  EXPECT_EQ(q.now(), Tick{500});
  EXPECT_EQ(q.run_until(Tick{549}), 0u);
  EXPECT_EQ(q.now(), Tick{500});
  EXPECT_EQ(q.size(), 5u);
  EXPECT_EQ(q.run(), 5u);
  EXPECT_FALSE(q.step());
  EXPECT_EQ(ran, 10);
}

TEST(EventQueueTest, ScheduleInThePastThrows) {
  EventQueue q;
  q.schedule(Tick{100}, [] {});
  q.run();
  EXPECT_THROW(q.schedule(Tick{99}, [] {}), std::logic_error);
  EXPECT_THROW(q.schedule_in(Tick{-1}, [] {}), std::logic_error);
  EXPECT_NO_THROW(q.schedule(Tick{100}, [] {}));
  EXPECT_EQ(q.schedule_in(Tick{5}, [] {}).seq, 3u);
  q.run();
  EXPECT_EQ(q.now(), Tick{105});
}

TEST(EventQueueTest, Cancellation) {
  EventQueue q;
  std::vector<int> trace;
  const EventId a = q.schedule(Tick{10}, [&] { trace.push_back(1); });
  const EventId b = q.schedule(Tick{20}, [&] { trace.push_back(2); });
  const EventId c = q.schedule(Tick{30}, [&] { trace.push_back(3); });
  EXPECT_TRUE(q.is_pending(b));
  EXPECT_TRUE(q.cancel(b));
  EXPECT_FALSE(q.is_pending(b));
  EXPECT_FALSE(q.cancel(b));  // twice
  EXPECT_EQ(q.size(), 2u);
  q.run_until(Tick{10});
  EXPECT_FALSE(q.cancel(a));  // already ran
  // b's slot is reused by d; the stale id must not cancel d.
  const EventId d = q.schedule(Tick{25}, [&] { trace.push_back(4); });
  EXPECT_FALSE(q.cancel(b));
  EXPECT_TRUE(q.is_pending(d));
  EXPECT_FALSE(q.cancel(EventId{}));
  EXPECT_FALSE(q.cancel(EventId{12345, 7}));
  q.run();
  EXPECT_EQ(trace, (std::vector<int>{1, 4, 3}));
  EXPECT_FALSE(q.cancel(c));
  EXPECT_EQ(q.events_executed(), 3u);

  // An event cancelling a later one at the same tick, and cancelling everything empties the queue.
  EventQueue q2;
  bool ran_victim = false;
  EventId victim;
  q2.schedule(Tick{5}, [&] { EXPECT_TRUE(q2.cancel(victim)); });
  victim = q2.schedule(Tick{5}, [&] { ran_victim = true; });
  q2.run();
  EXPECT_FALSE(ran_victim);
  std::vector<EventId> ids;
  for (int i = 0; i < 5000; ++i) ids.push_back(q2.schedule(Tick{100 + i}, [] { FAIL(); }));
  for (EventId id : ids) EXPECT_TRUE(q2.cancel(id));
  EXPECT_TRUE(q2.empty());
  EXPECT_FALSE(q2.next_tick().has_value());
  EXPECT_EQ(q2.run(), 0u);
}

TEST(EventQueueTest, MoveOnlyAndLargeCallables) {
  EventQueue q;
  int sum = 0;
  auto p = std::make_unique<int>(7);
  q.schedule(Tick{1}, [&sum, p = std::move(p)] { sum += *p; });
  std::array<std::int64_t, 32> big{};  // too large for the inline buffer: boxed
  big[31] = 100;
  q.schedule(Tick{2}, [&sum, big] { sum += static_cast<int>(big[31]); });
  // Many pending events force the slot table to grow (moving callables) before they run.
  for (int i = 0; i < 1000; ++i) {
    q.schedule(Tick{3 + i}, [&sum, big, u = std::make_unique<int>(1)] { sum += *u + static_cast<int>(big[0]); });
  }
  q.run();
  EXPECT_EQ(sum, 1107);
}

TEST(EventQueueTest, ExceptionFromEventLeavesQueueUsable) {
  EventQueue q;
  int ran = 0;
  q.schedule(Tick{1}, [] { throw std::runtime_error("boom"); });
  q.schedule(Tick{2}, [&] { ++ran; });
  EXPECT_THROW(q.run(), std::runtime_error);
  EXPECT_EQ(q.size(), 1u);
  EXPECT_EQ(q.run(), 1u);
  EXPECT_EQ(ran, 1);
}

// A random but seeded scenario: events spawn children at random delays and priorities, and
// sometimes cancel a pending one. Returns the trace of (tick, priority, event label).
std::vector<std::tuple<std::int64_t, int, int>> random_scenario(std::uint64_t seed) {
  EventQueue q;
  std::mt19937_64 rng(seed);
  std::vector<std::tuple<std::int64_t, int, int>> trace;
  std::vector<EventId> pending;
  int next_label = 0;
  const Priority prios[] = {Priority::DramResponse, Priority::CacheResponse, Priority::Default,
                            Priority::UnitOperate,  Priority::Stats,         Priority::Watchdog};
  std::function<void(int, Priority)> spawn;
  auto make = [&](int label, Priority pr) {
    return [&, label, pr] {
      trace.emplace_back(q.now().ps(), static_cast<int>(pr), label);
      if (next_label < 20000) {
        const int children = static_cast<int>(rng() % 3);
        for (int i = 0; i < children; ++i) spawn(next_label++, prios[rng() % 6]);
      }
      if (!pending.empty() && rng() % 5 == 0) q.cancel(pending[rng() % pending.size()]);
    };
  };
  spawn = [&](int label, Priority pr) {
    const Tick delay{static_cast<std::int64_t>(rng() % 4) * 250};  // many same-tick ties
    pending.push_back(q.schedule_in(delay, pr, make(label, pr)));
  };
  for (int i = 0; i < 8; ++i) spawn(next_label++, prios[rng() % 6]);
  q.run();
  return trace;
}

TEST(EventQueueTest, SeededRandomScenarioIsDeterministic) {
  const auto a = random_scenario(1234);
  const auto b = random_scenario(1234);
  ASSERT_GT(a.size(), 1000u);
  EXPECT_EQ(a, b);
  EXPECT_NE(a, random_scenario(4321));
  // And the trace never goes back in time.
  for (std::size_t i = 1; i < a.size(); ++i) ASSERT_LE(std::get<0>(a[i - 1]), std::get<0>(a[i]));
}

// Two clock domains at a non-integer ratio: a producer on the 600 MHz core clock pushes one item
// per cycle; a consumer on the 1866 MHz DRAM clock pops at most one per cycle. Every count is exact.
TEST(ClockDomainTest, ProducerAndConsumerOnTwoClocks) {
  const ClockDomain core("core", 600'000'000);
  const ClockDomain dram("dram", 1'866'000'000);
  EventQueue q;
  const Tick end = Tick::from_us(10);  // 6000 core cycles, 18660 DRAM cycles
  std::deque<Tick> fifo;               // production tick of each queued item
  std::int64_t core_cycles = 0, dram_cycles = 0, produced = 0, consumed = 0;
  bool all_on_next_edge = true;

  std::function<void()> core_tick = [&] {
    EXPECT_EQ(q.now(), core.tick_of(Cycles{core_cycles}));
    ++core_cycles;
    fifo.push_back(q.now());
    ++produced;
    const Tick next = core.tick_of(Cycles{core_cycles});
    if (next < end) q.schedule(next, Priority::Default, [&] { core_tick(); });
  };
  std::function<void()> dram_tick = [&] {
    EXPECT_EQ(q.now(), dram.tick_of(Cycles{dram_cycles}));
    ++dram_cycles;
    if (!fifo.empty()) {
      // DRAM is faster, so every item is taken at the first DRAM edge at or after its production.
      if (dram.next_edge(fifo.front()) != q.now()) all_on_next_edge = false;
      fifo.pop_front();
      ++consumed;
    }
    const Tick next = dram.tick_of(Cycles{dram_cycles});
    if (next < end) q.schedule(next, Priority::UnitOperate, [&] { dram_tick(); });
  };
  q.schedule(Tick{0}, Priority::Default, [&] { core_tick(); });
  q.schedule(Tick{0}, Priority::UnitOperate, [&] { dram_tick(); });
  q.run();

  EXPECT_EQ(core_cycles, 6000);
  EXPECT_EQ(dram_cycles, 18660);
  EXPECT_EQ(core.cycles_at(end), Cycles{core_cycles});
  EXPECT_EQ(dram.cycles_at(end), Cycles{dram_cycles});
  EXPECT_EQ(produced, 6000);
  EXPECT_EQ(consumed, 6000);
  EXPECT_TRUE(all_on_next_edge);
  EXPECT_TRUE(fifo.empty());
  EXPECT_EQ(q.events_executed(), 6000u + 18660u);
  EXPECT_EQ(q.now(), dram.tick_of(Cycles{18659}));
}

// ---------------------------------------------------------------------------------------------
// RunLoop

// A test unit: has `target` items of work; `done` counts completions.
class FakeUnit : public Unit {
 public:
  FakeUnit(std::string name, std::string reason) : name_(std::move(name)), reason_(std::move(reason)) {}
  std::string_view name() const override { return name_; }
  bool has_pending_work() const override { return done < target; }
  std::uint64_t progress() const override { return done; }
  std::string stall_reason() const override { return reason_; }

  std::uint64_t target = 0;
  std::uint64_t done = 0;

 private:
  std::string name_;
  std::string reason_;
};

// Runs a loop that must stop with a StallError; returns its message ("" and a failure otherwise).
std::string stall_message(RunLoop& loop) {
  try {
    loop.run();
  } catch (const StallError& e) {
    return e.what();
  }
  ADD_FAILURE() << "expected StallError";
  return "";
}

// Expects every one of `parts` in `msg`.
void expect_contains(const std::string& msg, std::initializer_list<const char*> parts) {
  for (const char* part : parts) EXPECT_NE(msg.find(part), std::string::npos) << part << " not in: " << msg;
}

TEST(RunLoopTest, NormalCompletionReturnsSummary) {
  const ClockDomain core("core", 600'000'000);
  EventQueue q;
  FakeUnit worker("worker", "idle");
  worker.target = 100;
  std::function<void()> operate = [&] {
    ++worker.done;
    if (worker.has_pending_work()) q.schedule(core.after(q.now(), Cycles{1}), Priority::UnitOperate, [&] { operate(); });
  };
  q.schedule(Tick{0}, Priority::UnitOperate, [&] { operate(); });
  RunLoop loop(q, {&worker});
  const RunSummary s = loop.run();
  EXPECT_EQ(s.events_executed, 100u);
  EXPECT_EQ(s.final_tick, core.tick_of(Cycles{99}));
  EXPECT_FALSE(worker.has_pending_work());
}

TEST(RunLoopTest, SlowSteadyProgressIsNotAStall) {
  EventQueue q;
  FakeUnit slow("slow", "working");
  slow.target = 2000;
  std::function<void()> operate = [&] {
    ++slow.done;
    if (slow.has_pending_work()) q.schedule_in(Tick{500}, Priority::UnitOperate, [&] { operate(); });
  };
  q.schedule(Tick{0}, [&] { operate(); });
  // Runs for 1 us of simulated time with a 10 ns window: progress every 500 ps keeps it alive.
  RunLoop loop(q, {&slow}, WatchdogConfig{Tick{10'000}, 1000});
  EXPECT_NO_THROW(loop.run());
  EXPECT_EQ(q.now(), Tick{500 * 1999});
}

TEST(RunLoopTest, DeadlockNamesTheStuckUnitAndItsReason) {
  EventQueue q;
  FakeUnit consumer("tsp0", "waiting for input queue 'tiles' (empty)");
  consumer.target = 4;
  FakeUnit idle("isp0", "nothing to do");
  FakeUnit producer("tiler", "output queue 'tiles' full");
  producer.target = 3;
  // The producer makes some progress, then stops without ever filling the consumer's queue.
  std::function<void()> produce = [&] {
    ++producer.done;
    if (producer.done < 2) q.schedule_in(Tick{1000}, [&] { produce(); });
  };
  q.schedule(Tick{0}, [&] { produce(); });
  RunLoop loop(q, {&idle, &producer, &consumer});
  const std::string msg = stall_message(loop);
  expect_contains(msg, {"deadlock", "tsp0: waiting for input queue 'tiles' (empty)", "tiler: output queue 'tiles' full",
                        "tick 1000 ps", "after 2 events"});
  EXPECT_EQ(msg.find("isp0"), std::string::npos) << msg;
}

TEST(RunLoopTest, LivelockOverTimeWindowThrows) {
  EventQueue q;
  FakeUnit dram("dram", "waiting for a refresh that never ends");
  dram.target = 1;
  // A self-rescheduling event that never makes progress (e.g. a retry loop that always fails).
  std::function<void()> retry = [&] { q.schedule_in(Tick{1000}, [&] { retry(); }); };
  q.schedule(Tick{0}, [&] { retry(); });
  RunLoop loop(q, {&dram}, WatchdogConfig{Tick::from_us(1), 1'000'000});
  expect_contains(stall_message(loop), {"livelock", "dram: waiting for a refresh that never ends"});
  // Detected within a window and a bit (the check runs 8 times per window).
  EXPECT_GT(q.now(), Tick::from_us(1));
  EXPECT_LE(q.now(), Tick::from_ns(1200));
}

TEST(RunLoopTest, ZeroTimeLivelockThrows) {
  EventQueue q;
  std::function<void()> spin = [&] { q.schedule(q.now(), [&] { spin(); }); };
  q.schedule(Tick{42}, [&] { spin(); });
  RunLoop loop(q, {}, WatchdogConfig{Tick::from_us(1), 10'000});
  expect_contains(stall_message(loop), {"livelock", "no unit reports pending work", "tick 42 ps"});
  EXPECT_LE(q.events_executed(), 20'000u);
}

TEST(Bits, BitCountSumsTheSetBits) {
  static_assert(bit_count(0) == 0);
  EXPECT_EQ(bit_count(0xF0F0u), 8u);                  // two nibbles of 4
  EXPECT_EQ(bit_count(0x8000000000000001ull), 2u);    // the two ends of the word
  EXPECT_EQ(bit_count(0x5555555555555555ull), 32u);   // every other bit of 64
  EXPECT_EQ(bit_count(~std::uint64_t{0}), 64u);       // every byte sums to 8, 8 x 8
  EXPECT_EQ(bit_count(0xffffu), 16u);                 // a full 16x coverage mask
}

}  // namespace
}  // namespace tbdr
