// BusyIntervals (models/busy_intervals.hpp): the timeline's per-unit busy intervals merge
// back-to-back reservations, stay within their cap, and keep every busy cycle.
#include <gtest/gtest.h>

#include "models/busy_intervals.hpp"

namespace tbdr {
namespace {

TEST(BusyIntervals, AdjacentReservationsAreOneInterval) {
  BusyIntervals b(8);
  // 2.5 cycles from 0, then the next reservation at 3 (the first one held the unit for whole
  // cycles: ceil(2.5) = 3): a gap of 0.5 <= kAdjacentCycles, one interval of 2.5 + 4 = 6.5 busy cycles.
  b.add(0, 2.5, 2.5);
  b.add(3, 7, 4);
  // A gap of 3 cycles: a second interval.
  b.add(10, 12, 2);
  ASSERT_EQ(b.intervals().size(), 2u);
  EXPECT_DOUBLE_EQ(b.intervals()[0].start_cycle, 0);
  EXPECT_DOUBLE_EQ(b.intervals()[0].end_cycle, 7);
  EXPECT_DOUBLE_EQ(b.intervals()[0].busy_cycles, 6.5);
  EXPECT_DOUBLE_EQ(b.intervals()[1].busy_cycles, 2);
  b.add(12, 12, 0);  // nothing to book
  EXPECT_EQ(b.intervals().size(), 2u);
}

TEST(BusyIntervals, StayWithinTheCapAndKeepEveryBusyCycle) {
  // 1000 reservations of 1 cycle every 10 cycles (gaps of 9): without a cap, 1000 intervals.
  BusyIntervals b(16);
  for (int i = 0; i < 1000; ++i) b.add(10.0 * i, 10.0 * i + 1, 1);
  EXPECT_LE(b.intervals().size(), 16u);
  EXPECT_GE(b.intervals().size(), 2u);
  double busy = 0, last_end = -1;
  for (const auto& i : b.intervals()) {
    busy += i.busy_cycles;
    EXPECT_GT(i.start_cycle, last_end);  // in order, disjoint
    EXPECT_LE(i.busy_cycles, i.end_cycle - i.start_cycle);
    last_end = i.end_cycle;
  }
  EXPECT_DOUBLE_EQ(busy, 1000);  // 1000 x 1 cycle
  EXPECT_DOUBLE_EQ(b.intervals().front().start_cycle, 0);
  EXPECT_DOUBLE_EQ(b.intervals().back().end_cycle, 9991);  // the last reservation: 9990..9991
}

}  // namespace
}  // namespace tbdr
