#pragma once
// Simulated time: Tick (integer picoseconds, the event queue's clock), Cycles (a count of clock
// cycles of one domain) and ClockDomain (an exact, drift-free conversion between the two).
//
// Tick and Cycles are distinct strong types: adding a Tick to a Cycles, or passing one where the
// other is expected, does not compile. The only bridge is a ClockDomain, because the length of a
// cycle depends on whose clock it is (a 600 MHz core cycle is 1666.67 ps, an 1866 MHz DRAM cycle
// 535.91 ps). Frequencies are stored as integer Hz and conversions use 128-bit integer arithmetic,
// so cycle n of any domain lands on the same tick no matter how long the simulation has run.
// (Common clocks reduce to a small fraction, e.g. 600 MHz = 5000/3 ps per cycle, and convert with
// 64-bit arithmetic: when num x den < 2^62 (every clock of the configs) by an exact multiplication
// with a reciprocal instead of the divisions; 128-bit division is the fallback for awkward
// frequencies. tests/test_clock_fast_paths.cpp checks every path against 128-bit arithmetic.)
#include <compare>
#include <cstdint>
#include <numeric>
#include <stdexcept>
#include <string>
#include <utility>

namespace tbdr {

/// What Tick and Cycles share: a strong 64-bit count that compares, adds, subtracts and scales
/// only with its own kind `D` (a Tick plus a Cycles does not compile).
template <class D>
class StrongCount {
 public:
  friend constexpr auto operator<=>(StrongCount, StrongCount) = default;
  friend constexpr D operator+(D a, D b) { return D{a.n_ + b.n_}; }
  friend constexpr D operator-(D a, D b) { return D{a.n_ - b.n_}; }
  friend constexpr D operator*(D a, std::int64_t k) { return D{a.n_ * k}; }
  friend constexpr D operator*(std::int64_t k, D a) { return D{a.n_ * k}; }
  constexpr D& operator+=(D b) { n_ += b.n_; return static_cast<D&>(*this); }
  constexpr D& operator-=(D b) { n_ -= b.n_; return static_cast<D&>(*this); }

 protected:
  constexpr StrongCount() = default;
  constexpr explicit StrongCount(std::int64_t n) : n_(n) {}
  std::int64_t n_ = 0;
};

/// A point in (or span of) simulated time, in integer picoseconds; the event queue's time base.
class Tick : public StrongCount<Tick> {
 public:
  constexpr Tick() = default;
  constexpr explicit Tick(std::int64_t ps) : StrongCount(ps) {}

  static constexpr Tick zero() { return Tick{0}; }
  static constexpr Tick max() { return Tick{INT64_MAX}; }
  static constexpr Tick from_ns(std::int64_t ns) { return Tick{ns * 1000}; }
  static constexpr Tick from_us(std::int64_t us) { return Tick{us * 1'000'000}; }

  constexpr std::int64_t ps() const { return n_; }
  /// For reports only: the tick in seconds as a double.
  constexpr double seconds() const { return static_cast<double>(n_) * 1e-12; }
};

/// A count of clock cycles of some ClockDomain; converts to Tick only through that domain.
class Cycles : public StrongCount<Cycles> {
 public:
  constexpr Cycles() = default;
  constexpr explicit Cycles(std::int64_t n) : StrongCount(n) {}

  constexpr std::int64_t count() const { return n_; }

  constexpr Cycles& operator++() { ++n_; return *this; }
  constexpr Cycles operator++(int) { Cycles old = *this; ++n_; return old; }
};

/// A named clock (core, memory, ...) with an exact integer frequency; maps cycles <-> ticks.
///
/// Cycle n of the domain starts at real time n / f. Ticks are integer picoseconds, so the edge is
/// placed on the first tick at or after it: tick_of(n) = ceil(n * 1e12 / f). (Rounding up rather
/// than down is what makes the round trip exact: cycles_at(tick_of(n)) == n for every n, given
/// f <= 1 THz. With rounding down, cycle 1 of an 1866 MHz clock would start at 535 ps, where
/// only 0.998 cycles have elapsed.) All edges are computed from cycle 0, never by adding a
/// rounded period repeatedly, so there is no drift: 1866e6 DRAM cycles are exactly 1e12 ps.
class ClockDomain {
 public:
  static constexpr std::int64_t kPsPerSecond = 1'000'000'000'000;

  /// frequency_hz must be in (0, 1e12]: a period of at least one tick.
  ClockDomain(std::string name, std::int64_t frequency_hz) : name_(std::move(name)), hz_(frequency_hz) {
    if (hz_ <= 0 || hz_ > kPsPerSecond) {
      throw std::invalid_argument("clock domain '" + name_ + "': frequency " + std::to_string(hz_) +
                                  " Hz is outside (0, 1 THz]");
    }
    const std::int64_t g = std::gcd(kPsPerSecond, hz_);
    num_ = static_cast<std::uint64_t>(kPsPerSecond / g);
    den_ = static_cast<std::uint64_t>(hz_ / g);
    fast_ = num_ <= UINT64_MAX / den_;
    // The reciprocal path needs every dividend below 2^63: r*num + den - 1 < num*den + den.
    magic_ = num_ < (std::uint64_t{1} << 62) / den_;
    if (magic_) {
      by_num_ = DivideBy(num_);
      by_den_ = DivideBy(den_);
    }
  }
  /// Convenience for configs that give MHz: rounds to the nearest integer Hz (1866 -> 1866000000).
  static ClockDomain from_mhz(std::string name, double mhz) {
    const double hz = mhz * 1e6;
    if (!(hz >= 0.5) || hz > static_cast<double>(kPsPerSecond)) {
      throw std::invalid_argument("clock domain '" + name + "': frequency " + std::to_string(mhz) +
                                  " MHz is outside (0, 1e6 MHz]");
    }
    return ClockDomain(std::move(name), static_cast<std::int64_t>(hz + 0.5));
  }

  const std::string& name() const { return name_; }
  std::int64_t frequency_hz() const { return hz_; }
  /// For reports only: the (generally non-integer) period in picoseconds.
  double period_ps() const { return static_cast<double>(kPsPerSecond) / static_cast<double>(hz_); }

  // The conversions are always inlined: the timing model converts at every cache and DRAM step,
  // and GCC left cycles_at and tick_of as calls there (1-2 % of the timing model's CPU).

  /// The tick at which cycle n starts: ceil(n * 1e12 / f). n must be >= 0.
  [[gnu::always_inline]] Tick tick_of(Cycles n) const {
    if (n.count() < 0) throw_negative("cycle index");
    const auto cycles = static_cast<std::uint64_t>(n.count());
    if (magic_) {
      // As below, with the divisions by den replaced by exact reciprocal multiplications
      // (cycles < 2^63 and r*num + den - 1 < 2^63).
      const std::uint64_t q = by_den_.quotient(cycles), r = cycles - q * den_;
      std::uint64_t ps;
      if (__builtin_mul_overflow(q, num_, &ps) || __builtin_add_overflow(ps, by_den_.quotient(r * num_ + den_ - 1), &ps) ||
          ps > static_cast<std::uint64_t>(INT64_MAX)) {
        throw_overflow(n);
      }
      return Tick{static_cast<std::int64_t>(ps)};
    }
    if (fast_) {
      // n = q*den + r: tick = q*num + ceil(r*num/den), with r*num < den*num < 2^64.
      const std::uint64_t q = cycles / den_, r = cycles % den_;
      std::uint64_t ps;
      if (__builtin_mul_overflow(q, num_, &ps) || __builtin_add_overflow(ps, (r * num_ + den_ - 1) / den_, &ps) ||
          ps > static_cast<std::uint64_t>(INT64_MAX)) {
        throw_overflow(n);
      }
      return Tick{static_cast<std::int64_t>(ps)};
    }
    const U128 ps = (static_cast<U128>(cycles) * num_ + den_ - 1) / den_;
    if (ps > static_cast<U128>(INT64_MAX)) throw_overflow(n);
    return Tick{static_cast<std::int64_t>(ps)};
  }

  /// Whole cycles elapsed at tick t (the index of the cycle in progress): floor(t * f / 1e12).
  [[gnu::always_inline]] Cycles cycles_at(Tick t) const {
    if (t.ps() < 0) throw_negative("tick");
    const auto ps = static_cast<std::uint64_t>(t.ps());
    if (magic_) {  // as below, dividing by reciprocal multiplication (ps < 2^63, r*den < 2^62)
      const std::uint64_t q = by_num_.quotient(ps), r = ps - q * num_;
      return Cycles{static_cast<std::int64_t>(q * den_ + by_num_.quotient(r * den_))};
    }
    if (fast_) {
      // t = q*num + r: cycles = q*den + floor(r*den/num), with r*den < den*num < 2^64.
      const std::uint64_t q = ps / num_, r = ps % num_;
      return Cycles{static_cast<std::int64_t>(q * den_ + r * den_ / num_)};  // <= t, so it fits
    }
    return Cycles{static_cast<std::int64_t>(static_cast<U128>(ps) * den_ / num_)};
  }

  /// The index of the first cycle boundary at or after t: cycles_at(next_edge(t)), computed with
  /// one conversion. tick_of is strictly increasing, so it is the least n with tick_of(n) >= t,
  /// i.e. with n*num/den > t - 1: floor((t - 1)*den/num) + 1 = cycles_at(t - 1) + 1 (0 for t = 0).
  [[gnu::always_inline]] Cycles edge_index(Tick t) const {
    if (t.ps() < 0) throw_negative("tick");
    return t.ps() == 0 ? Cycles{0} : cycles_at(Tick{t.ps() - 1}) + Cycles{1};
  }

  /// The first cycle boundary at or after t (t itself when t is an edge).
  [[gnu::always_inline]] Tick next_edge(Tick t) const { return tick_of(edge_index(t)); }

  /// The first cycle boundary strictly after t.
  [[gnu::always_inline]] Tick edge_after(Tick t) const { return tick_of(cycles_at(t) + Cycles{1}); }

  /// The edge n cycles after the current-or-next edge of t: when a unit acting at `now` is done
  /// after a latency of n cycles. after(now, Cycles{0}) == next_edge(now).
  [[gnu::always_inline]] Tick after(Tick now, Cycles n) const { return tick_of(edge_index(now) + n); }

 private:
  __extension__ typedef unsigned __int128 U128;

  /// Exact unsigned division by a constant d of dividends below 2^63 as a multiplication by a
  /// rounded-up reciprocal (Granlund & Montgomery, "Division by invariant integers using
  /// multiplication", PLDI 1994): with s = floor(log2 d) and m = ceil(2^(64+s) / d) < 2^64 (d
  /// not a power of two), n*m / 2^(64+s) = n/d + n*e / (d*2^(64+s)) where e = m*d - 2^(64+s) < d;
  /// the error term is below 1/d when n*e < 2^63 * 2^(s+1), so the floor is exactly n/d.
  /// Powers of two shift.
  struct DivideBy {
    DivideBy() = default;
    explicit DivideBy(std::uint64_t d) {
      shift = 63u - static_cast<unsigned>(__builtin_clzll(d));
      pow2 = (d & (d - 1)) == 0;
      if (!pow2) mul = static_cast<std::uint64_t>(((static_cast<U128>(1) << (64 + shift)) - 1) / d + 1);
    }
    std::uint64_t quotient(std::uint64_t n) const {  // n < 2^63
      if (pow2) return n >> shift;
      return static_cast<std::uint64_t>((static_cast<U128>(n) * mul) >> 64) >> shift;
    }
    std::uint64_t mul = 0;
    unsigned shift = 0;
    bool pow2 = true;
  };

  // The error paths live out of line so that the conversions stay small enough to inline.
  [[noreturn, gnu::cold, gnu::noinline]] void throw_negative(const char* what) const {
    throw std::domain_error("clock domain '" + name_ + "': negative " + what);
  }
  [[noreturn, gnu::cold, gnu::noinline]] void throw_overflow(Cycles n) const {
    throw std::overflow_error("clock domain '" + name_ + "': cycle " + std::to_string(n.count()) +
                              " is beyond the representable tick range");
  }

  std::string name_;
  std::int64_t hz_;
  // One cycle is exactly num_/den_ ps (1e12/f reduced: 600 MHz -> 5000/3, 1866 MHz -> 500000/933).
  std::uint64_t num_ = 1;
  std::uint64_t den_ = 1;
  bool fast_ = true;  // num_ * den_ fits 64 bits: conversions need no 128-bit division
  bool magic_ = true;  // num_ * den_ < 2^62: conversions divide by reciprocal multiplication
  DivideBy by_num_, by_den_;
};

}  // namespace tbdr
