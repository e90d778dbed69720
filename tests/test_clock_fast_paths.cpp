// ClockDomain's conversions (sim/kernel/time.hpp) take one of three paths: reciprocal
// multiplication when num*den < 2^62 (600 MHz = 5000/3 ps, 1866 MHz = 500000/933 ps), 64-bit
// division when num*den fits 64 bits, 128-bit division otherwise. Every path must give exactly
// the textbook values, over the whole tick range, since the timing model's results depend on
// every edge; these tests compare all of them with 128-bit reference arithmetic.
#include <gtest/gtest.h>

#include <cstdint>
#include <random>
#include <vector>

#include "kernel/time.hpp"

namespace tbdr {
namespace {

__extension__ typedef unsigned __int128 U128;
constexpr U128 kPs = 1'000'000'000'000;

// Reference: tick_of(n) = ceil(n * 1e12 / f), cycles_at(t) = floor(t * f / 1e12).
std::int64_t ref_tick(std::int64_t hz, std::int64_t n) {
  return static_cast<std::int64_t>((static_cast<U128>(n) * kPs + static_cast<U128>(hz) - 1) / static_cast<U128>(hz));
}
std::int64_t ref_cycles(std::int64_t hz, std::int64_t t) {
  return static_cast<std::int64_t>(static_cast<U128>(t) * static_cast<U128>(hz) / kPs);
}
// The first edge at or after t, by search from the floor (edges compared in 128 bits: the edge
// of the cycle after the last representable one lies beyond INT64_MAX).
std::int64_t ref_edge_index(std::int64_t hz, std::int64_t t) {
  std::int64_t n = ref_cycles(hz, t);
  const auto edge = [hz](std::int64_t c) {
    return (static_cast<U128>(c) * kPs + static_cast<U128>(hz) - 1) / static_cast<U128>(hz);
  };
  while (edge(n) < static_cast<U128>(t)) ++n;
  return n;
}

// Frequencies on each path: reciprocal (the configs' clocks, a power of two, 1 THz), 64-bit
// division (333,333,333 Hz: num*den ~ 3e20) and 128-bit division (num*den > 2^64).
const std::vector<std::int64_t> kFreqs = {600'000'000,   1'866'000'000, 450'000'000, 850'000'000, 3'200'000'000,
                                          1 << 30,       1'000'000'000'000, 1, 7,    333'333'333,
                                          999'999'999'989};

// The last cycle whose edge is a representable tick.
std::int64_t n_max(std::int64_t hz) { return ref_cycles(hz, INT64_MAX); }

void check(const ClockDomain& d, std::int64_t hz, std::int64_t t, std::int64_t n) {
  ASSERT_EQ(d.tick_of(Cycles{n}).ps(), ref_tick(hz, n)) << hz << " Hz, cycle " << n;
  ASSERT_EQ(d.cycles_at(Tick{t}).count(), ref_cycles(hz, t)) << hz << " Hz, tick " << t;
  const std::int64_t e = ref_edge_index(hz, t);
  ASSERT_EQ(d.edge_index(Tick{t}).count(), e) << hz << " Hz, tick " << t;
  if (e <= n_max(hz) - 3) {
    ASSERT_EQ(d.next_edge(Tick{t}).ps(), ref_tick(hz, e)) << hz << " Hz, tick " << t;
    ASSERT_EQ(d.after(Tick{t}, Cycles{3}).ps(), ref_tick(hz, e + 3)) << hz << " Hz, tick " << t;
  }
}

TEST(ClockFastPathsTest, SmallTicksAndCyclesExhaustively) {
  for (std::int64_t hz : kFreqs) {
    const ClockDomain d("d", hz);
    for (std::int64_t x = 0; x < 20'000; ++x) check(d, hz, x, x);
  }
}

TEST(ClockFastPathsTest, RandomTicksUpToTheRangeLimit) {
  std::mt19937_64 rng(7);
  for (std::int64_t hz : kFreqs) {
    const ClockDomain d("d", hz);
    // The largest cycle whose edge is representable, and a tick range up to INT64_MAX.
    const std::int64_t max_cycle = ref_cycles(hz, INT64_MAX);
    std::uniform_int_distribution<std::int64_t> tick(0, INT64_MAX), cycle(0, max_cycle);
    for (int i = 0; i < 20'000; ++i) {
      // Half uniform, half near a power of two (where reciprocal rounding would first go wrong).
      std::int64_t t = tick(rng), n = cycle(rng);
      if (i % 2) {
        const int b = static_cast<int>(rng() % 63);
        t = std::min<std::int64_t>(INT64_MAX, (std::int64_t{1} << b) + static_cast<std::int64_t>(rng() % 5) - 2);
        n = std::min<std::int64_t>(max_cycle, std::max<std::int64_t>(0, (std::int64_t{1} << b) - static_cast<std::int64_t>(rng() % 3)));
      }
      t = std::max<std::int64_t>(t, 0);
      check(d, hz, t, n);
    }
    // The extremes.
    check(d, hz, INT64_MAX, max_cycle);
    if (max_cycle < INT64_MAX) {
      EXPECT_THROW(d.tick_of(Cycles{max_cycle + 1}), std::overflow_error) << hz << " Hz";
    }
  }
}

TEST(ClockFastPathsTest, EdgeIndexRejectsNegativeTicks) {
  const ClockDomain d("core", 600'000'000);
  EXPECT_THROW(d.edge_index(Tick{-1}), std::domain_error);
  EXPECT_THROW(d.next_edge(Tick{-5}), std::domain_error);
}

}  // namespace
}  // namespace tbdr
