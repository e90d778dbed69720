// Statistics sets: declared once, combined as values (kernel/stats.hpp).
#include <gtest/gtest.h>

#include <memory>

#include "app/run_stats.hpp"
#include "kernel/stats.hpp"

namespace tbdr {
namespace {

#define TEST_UNIT_STATS(X)                                             \
  X(Counter, samples, "samples", Sum, "Samples seen")                  \
  X(Counter, peak_bytes, "bytes", Gauge, "Largest footprint")          \
  X(Accumulator, energy_pj, "pJ", Sum, "Energy")                       \
  X(Accumulator, hit_rate, "ratio", Derived, "Hits / accesses")
struct TestUnitStats {
  TBDR_STATS(TEST_UNIT_STATS)
};

TEST(Stats, DeclarationsCarryTheMemberNameUnitAndKind) {
  const auto defs = stat_defs<TestUnitStats>();
  ASSERT_EQ(defs.size(), 4u);
  EXPECT_STREQ(defs[0].name, "samples");
  EXPECT_STREQ(defs[1].unit, "bytes");
  EXPECT_EQ(defs[1].kind, StatKind::Gauge);
  EXPECT_EQ(defs[3].kind, StatKind::Derived);
}

TEST(Stats, SnapshotDifferenceIsTheWorkInBetween) {
  TestUnitStats s;
  s.samples += 100;
  s.peak_bytes.set(64);
  const TestUnitStats before = s;
  s.samples += 28;        // one tile's work
  s.peak_bytes.set(96);   // a level, not work: the difference keeps the current level
  s.energy_pj += 2.5;
  const TestUnitStats tile = s - before;
  EXPECT_EQ(tile.samples.value(), 28u);
  EXPECT_EQ(tile.peak_bytes.value(), 96u);
  EXPECT_DOUBLE_EQ(tile.energy_pj.value(), 2.5);
}

TEST(Stats, FrameTotalSumsCountsAndTakesTheLargestGauge) {
  TestUnitStats pass_a, pass_b, frame;
  pass_a.samples += 10;
  pass_a.peak_bytes.set(4096);
  pass_a.hit_rate.set(0.5);
  pass_b.samples += 32;
  pass_b.peak_bytes.set(1024);
  pass_b.hit_rate.set(0.9);
  frame += pass_a;
  frame += pass_b;
  EXPECT_EQ(frame.samples.value(), 42u);        // 10 + 32
  EXPECT_EQ(frame.peak_bytes.value(), 4096u);   // max(4096, 1024), not 5120
  EXPECT_DOUBLE_EQ(frame.hit_rate.value(), 0);  // derived: left for its owner to recompute
}

TEST(Stats, CollectWritesOneRowPerStatisticUnderTheScope) {
  TestUnitStats s;
  s.samples += 7;
  std::vector<StatRecord> rows;
  collect_stats(s, "pass0.main/isp", rows);
  ASSERT_EQ(rows.size(), 4u);
  EXPECT_EQ(rows[0].scope, "pass0.main/isp");
  EXPECT_EQ(rows[0].name, "samples");
  EXPECT_EQ(rows[0].value, 7);
  EXPECT_EQ(rows[2].unit, "pJ");
}

}  // namespace
}  // namespace tbdr

#include "kernel/ring_queue.hpp"
#include "kernel/slot_pool.hpp"

namespace tbdr {
namespace {

TEST(SlotPool, ReusesTheMostRecentlyReleasedSlot) {
  SlotPool<int> pool;
  const auto a = pool.acquire(), b = pool.acquire(), c = pool.acquire();
  EXPECT_EQ(a, 0u);
  EXPECT_EQ(b, 1u);
  EXPECT_EQ(c, 2u);
  pool[b] = 42;
  pool.release(a);
  pool.release(b);
  EXPECT_EQ(pool.live(), 1u);
  EXPECT_EQ(pool.acquire(), b);  // last released first
  EXPECT_EQ(pool[b], 42);        // contents left for the caller to overwrite
  EXPECT_EQ(pool.acquire(), a);
  EXPECT_EQ(pool.acquire(), 3u);  // no free slot: a new one
  EXPECT_EQ(pool.capacity(), 4u);
}

// stat_name gives the declared name of a member; members of one type are told apart by address.
TEST(StatName, IsTheDeclaredNameOfTheMember) {
  EXPECT_STREQ(stat_name(&FrameTimingStats::frame_cycles), "frame_cycles");
  EXPECT_STREQ(stat_name(&FrameTimingStats::frame_time_ms), "frame_time_ms");  // the same type as frame_cycles
  EXPECT_STREQ(stat_name(&CommandTimingStats::end_cycle), "end_cycle");
  EXPECT_STREQ(stat_name(&UnitTimeStats::utilization), "utilization");
}

// A set with derive() gets its derived rows computed when collected: busy 30 + stalled 20 cycles of
// a 100-cycle frame leave idle = 100 - 30 - 20 = 50 and utilization = 30 / 100 = 0.3; the set
// itself is left as it was (collect_stats derives on a copy).
TEST(DerivingStatSet, CollectComputesTheDerivedFiguresFromTheirInputs) {
  UnitTimeStats u;
  u.busy_cycles.set(30);
  u.stalled_cycles.set(20);
  u.frame_cycles = 100;
  std::vector<StatRecord> rows;
  collect_stats(u, "frame/unit.usc", rows);
  ASSERT_EQ(rows.size(), 4u);
  auto value = [&](const char* name) {
    for (const auto& r : rows) {
      if (r.name == name) return r.value;
    }
    ADD_FAILURE() << name;
    return -1.0;
  };
  EXPECT_DOUBLE_EQ(value("idle_cycles"), 50.0);
  EXPECT_DOUBLE_EQ(value("utilization"), 0.3);
  EXPECT_DOUBLE_EQ(u.idle_cycles.value(), 0.0);
  // A stalled share past the frame (more than 100 % busy + stalled) leaves no negative idle time.
  u.stalled_cycles.set(90);
  rows.clear();
  collect_stats(u, "frame/unit.usc", rows);
  EXPECT_DOUBLE_EQ(value("idle_cycles"), 0.0);
}

// Elements leave in the order they came, across the ring's wrap and its growth (8 slots, then 16).
TEST(RingQueue, KeepsOrderAcrossWrapAndGrowth) {
  RingQueue<std::unique_ptr<int>> q;  // (a move-only element)
  int next_in = 0, next_out = 0;
  auto push = [&] { q.push_back(std::make_unique<int>(next_in++)); };
  auto pop = [&] {
    ASSERT_FALSE(q.empty());
    EXPECT_EQ(*q.front(), next_out++);
    q.pop_front();
  };
  for (int i = 0; i < 6; ++i) push();
  for (int i = 0; i < 5; ++i) pop();  // head at slot 5 of 8
  for (int i = 0; i < 7; ++i) push();  // 8 held: wrapped around the end of the ring
  EXPECT_EQ(q.size(), 8u);
  push();  // full: grows to 16, elements moved in order
  push();
  EXPECT_EQ(q.size(), 10u);
  while (!q.empty()) pop();
  EXPECT_EQ(next_out, next_in);
  EXPECT_EQ(next_out, 15);
}

}  // namespace
}  // namespace tbdr
