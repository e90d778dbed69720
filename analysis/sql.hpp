#pragma once
// The one way tbdrsim runs SQL: an open connection (SqlConnection), prepared statements with bound
// parameters (SqlStatement), write transactions that roll back unless committed (SqlTransaction)
// and the one busy-retry policy (retry_while_busy). Every error is an SqlError (an InputError
// naming the database file). Values always travel as bound parameters, never inside the SQL text.
#include <cstdint>
#include <functional>
#include <string>

#include "kernel/errors.hpp"

struct sqlite3;
struct sqlite3_stmt;

namespace tbdr {

/// An SQLite failure: an InputError naming the database, with SQLite's primary result code.
class SqlError : public InputError {
 public:
  SqlError(const std::string& path, const std::string& message, int code) : InputError(path, message), code_(code) {}
  /// SQLite's primary result code (SQLITE_BUSY, SQLITE_ERROR, ...).
  int code() const { return code_; }
  /// True when another connection held the lock (SQLITE_BUSY or SQLITE_LOCKED).
  bool busy() const;

 private:
  int code_;
};

/// How a connection opens its file.
enum class SqlOpen {
  CreateReadWrite,    ///< read-write, the file created when absent
  ExistingQueryOnly,  ///< an existing file only, every write refused (PRAGMA query_only); the
                      ///< connection still opens read-write so that, when it closes, SQLite removes
                      ///< the -wal and -shm files it made, leaving the folder as it was
};

/// An open database file (60 s busy timeout) that closes itself.
class SqlConnection {
 public:
  /// Opens `path`; InputError "cannot open results database" naming it when SQLite cannot.
  explicit SqlConnection(const std::string& path, SqlOpen mode = SqlOpen::CreateReadWrite);
  ~SqlConnection();
  SqlConnection(const SqlConnection&) = delete;
  SqlConnection& operator=(const SqlConnection&) = delete;

  /// The database file, as errors name it.
  const std::string& path() const { return path_; }
  /// Runs a script of statements that take no parameters and return no rows (schema, views,
  /// BEGIN/COMMIT). SqlError naming the script's first words on failure.
  void exec(const std::string& script) const;
  /// Row id of the last INSERT on this connection.
  std::int64_t last_insert_rowid() const;

 private:
  friend class SqlStatement;
  friend class SqlTransaction;
  /// Throws the SqlError for the connection's last failure; `what` says what failed.
  [[noreturn]] void fail(const std::string& what) const;
  std::string path_;
  sqlite3* db_ = nullptr;
};

/// One prepared SQL statement with `?` parameters, finalized when destroyed. It must hold exactly
/// one statement (a second one is refused), so text spliced into it cannot add statements.
class SqlStatement {
 public:
  /// Prepares `sql` on `db`; SqlError naming its first words when SQLite refuses it.
  SqlStatement(const SqlConnection& db, const std::string& sql);
  /// Prepares `sql` and binds `params` to its parameters 1, 2, ... in order.
  template <class... Params>
    requires(sizeof...(Params) > 0)
  SqlStatement(const SqlConnection& db, const std::string& sql, const Params&... params) : SqlStatement(db, sql) {
    int i = 0;
    (bind(++i, params), ...);
  }
  ~SqlStatement();
  SqlStatement(const SqlStatement&) = delete;
  SqlStatement& operator=(const SqlStatement&) = delete;

  /// Binds parameter i (1-based).
  SqlStatement& bind(int i, const std::string& v);
  SqlStatement& bind(int i, std::int64_t v);
  SqlStatement& bind(int i, double v);
  /// Steps once: true when a row is available, false when done; SqlError on failure.
  bool step();
  /// Steps to the end (a statement that returns no rows), then resets it for the next bindings.
  void run();
  /// Resets for another execution and clears the bindings.
  void reset();
  /// The current row's column `col` (0-based): NULL or not, and its value as text, integer, real.
  bool is_null(int col) const;
  std::string text(int col) const;
  std::int64_t int64(int col) const;
  double real(int col) const;

 private:
  const SqlConnection& db_;
  sqlite3_stmt* s_ = nullptr;
};

/// A write transaction (BEGIN IMMEDIATE) that rolls back when destroyed without commit().
class SqlTransaction {
 public:
  /// Begins it (BEGIN IMMEDIATE: waits for the write lock through the busy timeout).
  explicit SqlTransaction(const SqlConnection& db);
  ~SqlTransaction();
  SqlTransaction(const SqlTransaction&) = delete;
  SqlTransaction& operator=(const SqlTransaction&) = delete;
  /// Commits (COMMIT); when that fails the destructor rolls back.
  void commit();

 private:
  const SqlConnection& db_;
  bool open_ = true;
};

/// The busy-retry policy: runs `attempt`, and while it fails with a busy SqlError that SQLite
/// reported without waiting through the busy timeout (writers racing on a new file, a writer
/// racing a checkpoint), runs it again, up to 200 more times, 2 ms + 1 ms per retry apart
/// (about 20 s in all). Any other error, or the last busy one, is rethrown.
void retry_while_busy(const std::function<void()>& attempt);

}  // namespace tbdr
