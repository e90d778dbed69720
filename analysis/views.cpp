// The analysis views, compiled in from analysis/views.sql (the one copy of their SQL) and created
// in every database tbdrsim opens (ResultsDb's constructor calls create_views()).
#include <string>
#include <string_view>

#include "analysis/report.hpp"
#include "analysis/sql.hpp"
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

/// The hash stored in the database's v_views_version view, or "" when it has none.
std::string stored_views_hash(const SqlConnection& db) {
  SqlStatement exists(db, "SELECT count(*) FROM sqlite_master WHERE type = 'view' AND name = 'v_views_version'");
  if (!exists.step() || exists.int64(0) == 0) return {};
  SqlStatement s(db, "SELECT sql_hash FROM v_views_version");
  return s.step() ? s.text(0) : std::string();
}

/// The statement that records the hash: a view cannot hold a bound parameter, so SQLite's quote()
/// of the bound hash writes the literal into the view's SQL.
std::string views_version_sql(const SqlConnection& db, const std::string& hash) {
  SqlStatement s(db, "SELECT 'DROP VIEW IF EXISTS v_views_version; CREATE VIEW v_views_version AS SELECT ' || "
                     "quote(?) || ' AS sql_hash;'");
  s.bind(1, hash);
  s.step();
  return s.text(0);
}

}  // namespace

std::string_view views_sql() { return {kViewsSql.text, kViewsSql.size}; }

std::string views_sql_hash() { return fnv1a_hex(views_sql()); }

void create_views(const SqlConnection& db) {
  const std::string want = views_sql_hash();
  if (stored_views_hash(db) == want) return;
  SqlTransaction tx(db);
  if (stored_views_hash(db) != want) {
    db.exec(std::string(views_sql()));
    db.exec(views_version_sql(db, want));
  }
  tx.commit();
}

}  // namespace tbdr
