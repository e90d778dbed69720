// Where a pipelined run's caller and timing model run (kernel/cpu_placement.hpp): on different CPUs
// while the frame runs, when the run has the CPUs to itself; the caller's CPUs given back after.
#include <gtest/gtest.h>

#include <algorithm>
#include <thread>

#include "kernel/cpu_placement.hpp"

namespace tbdr {
namespace {

TEST(CpuPlacement, TheTimingThreadGetsEveryCpuButTheCallers) {
  EXPECT_EQ(cpus_apart_from({0, 1}, 0, 2), (CpuList{1}));
  EXPECT_EQ(cpus_apart_from({0, 1}, 1, 2), (CpuList{0}));
  EXPECT_EQ(cpus_apart_from({0, 1, 2, 3}, 2, 4), (CpuList{0, 1, 3}));
  EXPECT_EQ(cpus_apart_from({4, 9}, 9, 7), (CpuList{4}));  // more threads than CPUs: still alone
}

TEST(CpuPlacement, NothingIsPinnedWhenTheRunSharesTheCpusOrHasOne) {
  EXPECT_TRUE(cpus_apart_from({0, 1, 2, 3}, 0, 2).empty());  // a sweep's worker: fewer threads than CPUs
  EXPECT_TRUE(cpus_apart_from({0}, 0, 2).empty());           // one CPU: nothing to keep apart
  EXPECT_TRUE(cpus_apart_from({}, 0, 2).empty());            // not known
  EXPECT_TRUE(cpus_apart_from({0, 1}, 5, 2).empty());        // the caller on a CPU not in its set
  EXPECT_TRUE(cpus_apart_from({0, 1}, -1, 2).empty());       // sched_getcpu failed
}

TEST(CpuPlacement, KeepsTheTwoThreadsApartUntilRestored) {
  const CpuList before = allowed_cpus();
  if (before.size() < 2) GTEST_SKIP() << "needs two CPUs (this process may use " << before.size() << ")";
  CriticalThreadPlacement placement(static_cast<unsigned>(before.size()));
  CpuList timing_cpus;
  std::thread timing([&] {
    placement.keep_apart();
    timing_cpus = allowed_cpus();
  });
  timing.join();
  ASSERT_TRUE(placement.pinned());
  const CpuList caller = allowed_cpus();
  ASSERT_EQ(caller.size(), 1u);
  // The timing thread has every other CPU the caller had, and not the caller's.
  EXPECT_EQ(timing_cpus.size(), before.size() - 1);
  EXPECT_EQ(std::count(timing_cpus.begin(), timing_cpus.end(), caller[0]), 0);
  for (const int c : timing_cpus) EXPECT_EQ(std::count(before.begin(), before.end(), c), 1) << c;
  placement.restore();
  EXPECT_FALSE(placement.pinned());
  EXPECT_EQ(allowed_cpus(), before);
  // Once restored, a late keep_apart (a frame shorter than the timing thread's start) pins nothing.
  std::thread late([&] { placement.keep_apart(); });
  late.join();
  EXPECT_FALSE(placement.pinned());
  EXPECT_EQ(allowed_cpus(), before);
}

TEST(CpuPlacement, ARunWithFewerThreadsThanCpusPinsNothing) {
  const CpuList before = allowed_cpus();
  if (before.size() < 2) GTEST_SKIP() << "needs two CPUs (this process may use " << before.size() << ")";
  CriticalThreadPlacement placement(static_cast<unsigned>(before.size()) - 1);
  std::thread timing([&] { placement.keep_apart(); });
  timing.join();
  EXPECT_FALSE(placement.pinned());
  EXPECT_EQ(allowed_cpus(), before);
}

}  // namespace
}  // namespace tbdr
