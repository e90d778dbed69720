#pragma once
// Deterministic randomness for generated content (scenes, light sets): PCG32 (O'Neill 2014,
// pcg-random.org, pcg32_random_r) and the SplitMix64 mixer (Steele et al. 2014). No <random>
// distribution is used: their output differs between standard libraries, so the same seed would
// give different scenes on different machines.
#include <cstdint>

namespace tbdr {

/// SplitMix64's output function: a 64-bit bijective mixer that turns related seeds (0, 1, 2, ...)
/// into unrelated ones.
constexpr std::uint64_t splitmix64(std::uint64_t x) {
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

/// PCG32 (XSH RR): 32-bit outputs from a 64-bit state; the same sequence with every compiler and
/// standard library.
class Pcg32 {
 public:
  /// The generator of `seed` on stream `stream` (pcg32_srandom_r: streams are independent sequences).
  Pcg32(std::uint64_t seed, std::uint64_t stream) : inc_((stream << 1u) | 1u) {
    next();
    state_ += seed;
    next();
  }
  /// A generator whose seed and stream both come from one 64-bit value, mixed by splitmix64, so
  /// that nearby values (a base seed plus an index) give unrelated sequences.
  static Pcg32 from_seed(std::uint64_t seed) {
    return Pcg32(splitmix64(seed), splitmix64(seed ^ 0x5851f42d4c957f2dULL));
  }
  /// The next 32 random bits.
  std::uint32_t next() {
    const std::uint64_t old = state_;
    state_ = old * 6364136223846793005ULL + inc_;
    const auto xorshifted = static_cast<std::uint32_t>(((old >> 18u) ^ old) >> 27u);
    const auto rot = static_cast<std::uint32_t>(old >> 59u);
    return (xorshifted >> rot) | (xorshifted << ((32u - rot) & 31u));
  }
  /// Uniform in [0,1) with 24 random bits (exact in float).
  float uniform() { return static_cast<float>(next() >> 8) * (1.0f / 16777216.0f); }
  /// Uniform in [0,1) with 53 random bits (exact in double).
  double uniform_double() {
    const std::uint64_t hi = next() >> 5, lo = next() >> 6;
    return (static_cast<double>(hi) * 67108864.0 + static_cast<double>(lo)) * (1.0 / 9007199254740992.0);
  }
  /// Uniform in [lo, hi).
  float range(float lo, float hi) { return lo + (hi - lo) * uniform(); }

 private:
  std::uint64_t state_ = 0;
  std::uint64_t inc_;
};

}  // namespace tbdr
