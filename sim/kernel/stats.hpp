#pragma once
// Statistics: each one is declared once (name, unit, description) where its unit defines it, and
// lives in a plain member that the hot path increments directly. A StatGroup is a scope ("isp",
// "pass.0.gbuffer", "dram.class.color") that knows its statistics so a run can collect them all
// into the results database at the end; nothing is looked up by string while simulating.
#include <cstdint>
#include <string>
#include <vector>

namespace tbdr {

/// The declaration of a statistic: stored once per name in the database's stat_defs table.
/// The strings must have static storage (string literals).
struct StatDef {
  const char* name;
  const char* unit;
  const char* description;
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

class StatBase;

/// A named scope that owns the list of statistics registered in it. Not copyable or movable:
/// statistics register their own address.
class StatGroup {
 public:
  explicit StatGroup(std::string scope) : scope_(std::move(scope)) {}
  StatGroup(const StatGroup&) = delete;
  StatGroup& operator=(const StatGroup&) = delete;

  const std::string& scope() const { return scope_; }
  void set_scope(std::string s) { scope_ = std::move(s); }
  /// Appends every statistic of this group (in declaration order) to `out`.
  void collect(std::vector<StatRecord>& out) const;
  /// Resets every statistic to zero.
  void reset();

 private:
  friend class StatBase;
  std::string scope_;
  std::vector<StatBase*> stats_;
};

/// Common part of counters and accumulators: the declaration and the registration.
class StatBase {
 public:
  StatBase(StatGroup& group, const StatDef& def) : def_(def) { group.stats_.push_back(this); }
  StatBase(const StatBase&) = delete;
  StatBase& operator=(const StatBase&) = delete;
  virtual ~StatBase() = default;
  const StatDef& def() const { return def_; }
  virtual double as_double() const = 0;
  virtual void reset() = 0;

 private:
  const StatDef def_;  ///< copied: the strings are literals with static storage
};

/// An event count (samples, bytes, primitives): a plain 64-bit integer.
class Counter final : public StatBase {
 public:
  using StatBase::StatBase;
  Counter& operator+=(std::uint64_t n) { value_ += n; return *this; }
  Counter& operator++() { ++value_; return *this; }
  std::uint64_t value() const { return value_; }
  double as_double() const override { return static_cast<double>(value_); }
  void reset() override { value_ = 0; }

 private:
  std::uint64_t value_ = 0;
};

/// A real-valued total (energy in pJ, time in ps as a derived figure): a plain double.
class Accumulator final : public StatBase {
 public:
  using StatBase::StatBase;
  Accumulator& operator+=(double v) { value_ += v; return *this; }
  void set(double v) { value_ = v; }
  double value() const { return value_; }
  double as_double() const override { return value_; }
  void reset() override { value_ = 0; }

 private:
  double value_ = 0;
};

inline void StatGroup::collect(std::vector<StatRecord>& out) const {
  for (const StatBase* s : stats_) {
    out.push_back({scope_, s->def().name, s->as_double(), s->def().unit, s->def().description});
  }
}

inline void StatGroup::reset() {
  for (StatBase* s : stats_) s->reset();
}

}  // namespace tbdr
