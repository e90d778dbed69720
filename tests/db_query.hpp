#pragma once
// Reading numbers back from a results database in a test.
#include <gtest/gtest.h>

#include <cmath>
#include <initializer_list>
#include <string>

#include "analysis/results_db.hpp"
#include "analysis/sql.hpp"

namespace tbdr::testing_support {

/// The first column of the first row of `sql` as a number; a test failure (and NaN) when the query
/// returns no row or NULL.
inline double query_number(const ResultsDb& db, const std::string& sql) {
  SqlStatement q(db.sql(), sql);
  if (!q.step()) {
    ADD_FAILURE() << "no row: " << sql;
    return std::nan("");
  }
  EXPECT_FALSE(q.is_null(0)) << sql;
  return q.real(0);
}
/// The same on the database at `path`.
inline double query_number(const std::string& path, const std::string& sql) { return query_number(ResultsDb(path), sql); }

/// A query and the number it must return (expect_numbers).
struct NumberIs {
  std::string sql;
  double value;
};
/// Expects every query of `expected` to return its number; `db` is a ResultsDb or a database path.
template <class Db>
void expect_numbers(const Db& db, std::initializer_list<NumberIs> expected) {
  for (const NumberIs& e : expected) EXPECT_DOUBLE_EQ(query_number(db, e.sql), e.value) << e.sql;
}

}  // namespace tbdr::testing_support
