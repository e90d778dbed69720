#include "analysis/sql.hpp"

#include <cstring>

#include <sqlite3.h>
#include <unistd.h>

#include <algorithm>

namespace tbdr {

namespace {

/// The first words of some SQL for an error message: 60 characters, on one line.
std::string sql_head(const std::string& sql) {
  const auto b = std::min(sql.size(), sql.find_first_not_of(" \t\r\n"));
  std::string head = sql.substr(b, 60);
  std::replace(head.begin(), head.end(), '\n', ' ');
  return "'" + head + (sql.size() - b > 60 ? "...'" : "'");
}

}  // namespace

bool SqlError::busy() const { return code_ == SQLITE_BUSY || code_ == SQLITE_LOCKED; }

// ---------------------------------------------------------------------------------------------
// SqlConnection

SqlConnection::SqlConnection(const std::string& path, SqlOpen mode) : path_(path) {
  const int flags = SQLITE_OPEN_READWRITE | (mode == SqlOpen::CreateReadWrite ? SQLITE_OPEN_CREATE : 0);
  if (sqlite3_open_v2(path.c_str(), &db_, flags, nullptr) != SQLITE_OK) {
    const std::string msg = db_ ? sqlite3_errmsg(db_) : "out of memory";
    sqlite3_close(db_);
    db_ = nullptr;
    throw InputError(path, "cannot open results database: " + msg);
  }
  sqlite3_busy_timeout(db_, 60000);
  if (mode == SqlOpen::ExistingQueryOnly) {
    try {
      exec("PRAGMA query_only = ON");
    } catch (...) {
      sqlite3_close(db_);
      throw;
    }
  }
}

SqlConnection::~SqlConnection() { sqlite3_close(db_); }

namespace {

/// SQLite's message for result code `rc` of `db`, with the operating system's reason when the
/// file system failed it (a full disk, a file size limit, a permission): "disk I/O error (File too large)".
std::string sqlite_reason(sqlite3* db, int rc, const std::string& message) {
  const int primary = rc & 0xff;
  const int os = sqlite3_system_errno(db);
  if (os != 0 && (primary == SQLITE_IOERR || primary == SQLITE_FULL || primary == SQLITE_CANTOPEN ||
                  primary == SQLITE_READONLY || primary == SQLITE_PERM)) {
    return message + " (" + std::strerror(os) + ")";
  }
  // SQLite keeps the last system error, which a rollback after the failed write may have reset.
  if (primary == SQLITE_IOERR) return message + " (a read or write of the file failed: a full disk or a file size limit?)";
  return message;
}

}  // namespace

void SqlConnection::fail(const std::string& what) const {
  const int rc = sqlite3_extended_errcode(db_);
  throw SqlError(path_, "SQLite: " + what + ": " + sqlite_reason(db_, rc, sqlite3_errmsg(db_)), rc & 0xff);
}

void SqlConnection::exec(const std::string& script) const {
  char* err = nullptr;
  const int rc = sqlite3_exec(db_, script.c_str(), nullptr, nullptr, &err);
  if (rc != SQLITE_OK) {
    const std::string msg = sqlite_reason(db_, rc, err ? err : sqlite3_errmsg(db_));
    sqlite3_free(err);
    throw SqlError(path_, "SQLite: cannot run " + sql_head(script) + ": " + msg, rc & 0xff);
  }
}

std::int64_t SqlConnection::last_insert_rowid() const { return sqlite3_last_insert_rowid(db_); }

// ---------------------------------------------------------------------------------------------
// SqlStatement

SqlStatement::SqlStatement(const SqlConnection& db, const std::string& sql) : db_(db) {
  const char* tail = nullptr;
  if (sqlite3_prepare_v2(db.db_, sql.c_str(), static_cast<int>(sql.size()), &s_, &tail) != SQLITE_OK) {
    db.fail("cannot prepare " + sql_head(sql));
  }
  if (tail && std::string(tail).find_first_not_of(" \t\r\n;") != std::string::npos) {
    sqlite3_finalize(s_);
    s_ = nullptr;
    throw SqlError(db.path(),
                   "SQL: only one statement allowed, found more after '" +
                       sql.substr(0, static_cast<std::size_t>(tail - sql.c_str())) + "'",
                   SQLITE_ERROR);
  }
}

SqlStatement::~SqlStatement() { sqlite3_finalize(s_); }

SqlStatement& SqlStatement::bind(int i, const std::string& v) {
  sqlite3_bind_text(s_, i, v.c_str(), static_cast<int>(v.size()), SQLITE_TRANSIENT);
  return *this;
}
SqlStatement& SqlStatement::bind(int i, std::int64_t v) {
  sqlite3_bind_int64(s_, i, v);
  return *this;
}
SqlStatement& SqlStatement::bind(int i, double v) {
  sqlite3_bind_double(s_, i, v);
  return *this;
}

bool SqlStatement::step() {
  const int rc = sqlite3_step(s_);
  if (rc == SQLITE_ROW) return true;
  if (rc == SQLITE_DONE) return false;
  db_.fail("step failed");
}

void SqlStatement::run() {
  while (step()) {
  }
  reset();
}

void SqlStatement::reset() {
  sqlite3_reset(s_);
  sqlite3_clear_bindings(s_);
}

bool SqlStatement::is_null(int col) const { return sqlite3_column_type(s_, col) == SQLITE_NULL; }
std::string SqlStatement::text(int col) const {
  const auto* p = sqlite3_column_text(s_, col);
  return p ? reinterpret_cast<const char*>(p) : "";
}
std::int64_t SqlStatement::int64(int col) const { return sqlite3_column_int64(s_, col); }
double SqlStatement::real(int col) const { return sqlite3_column_double(s_, col); }

// ---------------------------------------------------------------------------------------------
// SqlTransaction

SqlTransaction::SqlTransaction(const SqlConnection& db) : db_(db) { db.exec("BEGIN IMMEDIATE"); }

SqlTransaction::~SqlTransaction() {
  if (open_) sqlite3_exec(db_.db_, "ROLLBACK", nullptr, nullptr, nullptr);
}

void SqlTransaction::commit() {
  db_.exec("COMMIT");
  open_ = false;
}

// ---------------------------------------------------------------------------------------------
// The busy-retry policy

void retry_while_busy(const std::function<void()>& attempt) {
  constexpr int kMaxRetries = 200;
  for (int retry = 0;; ++retry) {
    try {
      attempt();
      return;
    } catch (const SqlError& e) {
      if (!e.busy() || retry >= kMaxRetries) throw;
    }
    usleep(static_cast<useconds_t>(2000 + 1000 * retry));
  }
}

}  // namespace tbdr
