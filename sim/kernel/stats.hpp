#pragma once
// Statistics: each one is declared once, in its unit's statistics set, with its name (the
// member's), unit, description and kind (summed or a gauge). A set is a plain value: the hot
// path increments members directly, sets subtract (the work of one tile = after - before) and add
// (a frame = the sum of its passes; gauges take the largest value) as values, and turn into rows
// (StatRecord) only where a run is written to the results database. Nothing is looked up by name.
#include <algorithm>
#include <concepts>
#include <cstdint>
#include <string>
#include <type_traits>
#include <vector>

namespace tbdr {

/// How a statistic combines across passes, tiles or runs.
enum class StatKind : std::uint8_t {
  Sum,    ///< a count or total: the frame's value is the sum of its parts
  Gauge,  ///< a level (bytes per pixel, a peak, a factor): the frame's value is the largest part
  Derived,  ///< a ratio or mean its owner computes from the set's sums; never combined
};

/// The declaration of a statistic: stored once per name in the database's stat_defs table.
/// The strings have static storage (string literals).
struct StatDef {
  const char* name;
  const char* unit;
  const char* description;
  StatKind kind = StatKind::Sum;
};

/// One collected value: what the results database stores per run.
struct StatRecord {
  std::string scope;
  std::string name;
  double value = 0;
  std::string unit;
  std::string description;
};

/// One per-tile row (optional, for heat maps): which pass, which tile, what it cost.
struct TileRecord {
  std::int64_t pass = 0;
  std::int64_t tile_x = 0;
  std::int64_t tile_y = 0;
  double cycles = 0;
  double samples = 0;
  double dram_bytes = 0;
  bool operator==(const TileRecord&) const = default;
};

/// An event count (samples, bytes, primitives): a 64-bit integer.
class Counter {
 public:
  Counter& operator+=(std::uint64_t n) { value_ += n; return *this; }
  Counter& operator-=(std::uint64_t n) { value_ -= n; return *this; }
  Counter& operator++() { ++value_; return *this; }
  Counter& operator+=(const Counter& o) { value_ += o.value_; return *this; }
  Counter& operator-=(const Counter& o) { value_ -= o.value_; return *this; }
  void set(std::uint64_t v) { value_ = v; }
  std::uint64_t value() const { return value_; }
  double as_double() const { return static_cast<double>(value_); }
  auto operator<=>(const Counter&) const = default;

 private:
  std::uint64_t value_ = 0;
};

/// A real-valued total (energy in pJ, time in ps as a derived figure).
class Accumulator {
 public:
  Accumulator& operator+=(double v) { value_ += v; return *this; }
  Accumulator& operator+=(const Accumulator& o) { value_ += o.value_; return *this; }
  Accumulator& operator-=(const Accumulator& o) { value_ -= o.value_; return *this; }
  void set(double v) { value_ = v; }
  double value() const { return value_; }
  double as_double() const { return value_; }
  auto operator<=>(const Accumulator&) const = default;

 private:
  double value_ = 0;
};

// Declares a statistics set inside a struct from an X-macro list of
//   X(Counter|Accumulator, member, "unit", Sum|Gauge, "description")
// It defines one member per entry and `zip(a, b, f)`, which calls f(a.member, b.member, def) for
// every entry in declaration order; the free functions below are written once on top of it.
#define TBDR_STAT_MEMBER(type, member, unit, kind, desc) ::tbdr::type member;
#define TBDR_STAT_ZIP(type, member, unit, kind, desc) \
  f(a.member, b.member, ::tbdr::StatDef{#member, unit, desc, ::tbdr::StatKind::kind});
#define TBDR_STATS(LIST)                              \
  LIST(TBDR_STAT_MEMBER)                              \
  template <class A, class B, class F>                \
  static void zip(A& a, B& b, F&& f) {                \
    LIST(TBDR_STAT_ZIP)                               \
  }

/// A struct declared with TBDR_STATS.
template <class S>
concept StatSet = requires(S& s, const S& c) {
  S::zip(s, c, [](auto&, const auto&, const StatDef&) {});
};

/// The part of `a` not in `b` (b an earlier snapshot of a): sums subtract; gauges and derived
/// figures keep a's value.
template <StatSet S>
S operator-(S a, const S& b) {
  S::zip(a, b, [](auto& x, const auto& y, const StatDef& d) {
    if (d.kind == StatKind::Sum) x -= y;
  });
  return a;
}

/// Adds `b` into `a`: sums add; gauges take the larger level; derived figures keep a's value
/// (their owner recomputes them from the sums).
template <StatSet S>
S& operator+=(S& a, const S& b) {
  S::zip(a, b, [](auto& x, const auto& y, const StatDef& d) {
    if (d.kind == StatKind::Sum) {
      x += y;
    } else if (d.kind == StatKind::Gauge && y.value() > x.value()) {
      x = y;
    }
  });
  return a;
}

/// A set with derived figures: its `derive()` computes each `Derived` member from the set's other
/// members (the formula beside the figures it combines, as gem5's Formula statistics).
template <class S>
concept DerivingStatSet = StatSet<S> && requires(S& s) { s.derive(); };

/// Appends every statistic of `s` to `out` under `scope`, in declaration order; a set's derived
/// figures are computed first (DerivingStatSet).
template <StatSet S>
void collect_stats(const S& s, const std::string& scope, std::vector<StatRecord>& out) {
  const auto append = [&](const S& set) {
    S::zip(set, set, [&](const auto& x, const auto&, const StatDef& d) {
      out.push_back({scope, d.name, x.as_double(), d.unit, d.description});
    });
  };
  if constexpr (DerivingStatSet<S>) {
    S derived = s;
    derived.derive();
    append(derived);
  } else {
    append(s);
  }
}

/// The stored name of a set's member, from its declaration: `stat_name(&FrameTimingStats::frame_cycles)`
/// is "frame_cycles". Code that reads a statistic back (from rows or the database) names it so,
/// never by a string literal of its own.
template <StatSet S, class M>
const char* stat_name(M S::*member) {
  static const S probe{};
  const char* name = nullptr;
  S::zip(probe, probe, [&](const auto& x, const auto&, const StatDef& d) {
    if constexpr (std::is_same_v<std::remove_cvref_t<decltype(x)>, M>) {
      if (&x == &(probe.*member)) name = d.name;
    }
  });
  return name;
}

/// Every declaration of a set, in order (for tools that print what a unit counts).
template <StatSet S>
std::vector<StatDef> stat_defs() {
  std::vector<StatDef> defs;
  S s{};
  S::zip(s, s, [&](const auto&, const auto&, const StatDef& d) { defs.push_back(d); });
  return defs;
}

}  // namespace tbdr
