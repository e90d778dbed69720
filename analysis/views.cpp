// The analysis views, compiled in from analysis/views.sql (the one copy of their SQL) and created
// in every database tbdrsim opens (ResultsDb's constructor calls create_views()).
#include <sqlite3.h>

#include <string>
#include <string_view>

#include "analysis/report.hpp"
#include "kernel/errors.hpp"
#include "kernel/hash.hpp"

namespace tbdr {

namespace {

/// views.sql opens with the line `-- R"tbdr_views(` and closes with `-- )tbdr_views"_tbdr_sql`:
/// SQL comments to SQLite, but to C++ a `--` followed by a raw string literal with the suffix
/// below, so the #include yields `--SqlText{...}` and the file stays plain SQL for sqlite3.
struct SqlText {
  const char* text;
  std::size_t size;
  constexpr SqlText operator--() const { return *this; }
};
constexpr SqlText operator""_tbdr_sql(const char* text, std::size_t size) { return {text, size}; }

constexpr SqlText kViewsSql =
#include "analysis/views.sql"
    ;

std::string last_error(sqlite3* db) { return sqlite3_errmsg(db); }

void exec_sql(sqlite3* db, const std::string& path, const std::string& sql) {
  char* err = nullptr;
  if (sqlite3_exec(db, sql.c_str(), nullptr, nullptr, &err) != SQLITE_OK) {
    std::string msg = err ? err : last_error(db);
    sqlite3_free(err);
    throw InputError(path, "SQLite (analysis views): " + msg);
  }
}

/// The hash stored in the database's v_views_version view, or "" when there is none.
std::string stored_views_hash(sqlite3* db) {
  sqlite3_stmt* s = nullptr;
  std::string hash;
  if (sqlite3_prepare_v2(db, "SELECT sql_hash FROM v_views_version", -1, &s, nullptr) == SQLITE_OK &&
      sqlite3_step(s) == SQLITE_ROW) {
    if (const auto* p = sqlite3_column_text(s, 0)) hash = reinterpret_cast<const char*>(p);
  }
  sqlite3_finalize(s);
  return hash;
}

}  // namespace

std::string_view views_sql() { return {kViewsSql.text, kViewsSql.size}; }

std::string views_sql_hash() { return fnv1a_hex(views_sql()); }

void create_views(sqlite3* db, const std::string& path) {
  const std::string want = views_sql_hash();
  if (stored_views_hash(db) == want) return;
  exec_sql(db, path, "BEGIN IMMEDIATE");
  try {
    if (stored_views_hash(db) != want) {
      exec_sql(db, path, std::string(views_sql()));
      exec_sql(db, path,
               "DROP VIEW IF EXISTS v_views_version;\n"
               "CREATE VIEW v_views_version AS SELECT '" + want + "' AS sql_hash;");
    }
    exec_sql(db, path, "COMMIT");
  } catch (...) {
    sqlite3_exec(db, "ROLLBACK", nullptr, nullptr, nullptr);
    throw;
  }
}

}  // namespace tbdr
