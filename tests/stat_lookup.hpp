#pragma once
// Looking a statistic up by scope and name in a run's rows (tests only: the simulator itself never
// looks figures up by name). A missing row fails the test and reads as -1.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "app/stat_rows.hpp"
#include "kernel/stats.hpp"

namespace tbdr {

/// The value of the row (scope, name) of `st`.
inline double stat(const std::vector<StatRecord>& st, const std::string& scope, const std::string& name) {
  for (const auto& r : st) {
    if (r.scope == scope && r.name == name) return r.value;
  }
  ADD_FAILURE() << "no statistic " << scope << " " << name;
  return -1;
}

/// The value of the row (scope, name) of a frame's functional statistics (frame_rows).
inline double stat(const FrameResult& frame, const std::string& scope, const std::string& name) {
  return stat(frame_rows(frame), scope, name);
}

/// The value of the row (scope, name) of a result that holds its rows in `stats` (Timed, RunOutcome).
template <class Result>
  requires requires(const Result& r) { r.stats; }
double stat(const Result& result, const std::string& scope, const std::string& name) {
  return stat(result.stats, scope, name);
}

/// Expects two runs' rows to be the same, row by row: scope, name and value.
inline void expect_same_rows(const std::vector<StatRecord>& a, const std::vector<StatRecord>& b) {
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].scope, b[i].scope);
    EXPECT_EQ(a[i].name, b[i].name);
    EXPECT_EQ(a[i].value, b[i].value) << a[i].scope << " " << a[i].name;
  }
}

}  // namespace tbdr
