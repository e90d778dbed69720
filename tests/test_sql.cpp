// The SQL helper: bound parameters, one statement per SqlStatement, errors naming the database
// with SQLite's code, transactions that roll back unless committed, and the busy-retry policy.
#include <gtest/gtest.h>

#include <sqlite3.h>

#include <filesystem>
#include <string>

#include "analysis/sql.hpp"
#include "kernel/errors.hpp"
#include "scratch_dir.hpp"

namespace tbdr {
namespace {

namespace fs = std::filesystem;

testing_scratch::ScratchCleanup scratch_cleanup{"sql"};

std::string fresh(const std::string& name) { return (testing_scratch::scratch_dir("sql", name) / "t.db").string(); }

std::int64_t count_rows(const SqlConnection& db) {
  SqlStatement s(db, "SELECT count(*) FROM t");
  EXPECT_TRUE(s.step());
  return s.int64(0);
}

TEST(Sql, BoundValuesTravelAsDataNotAsSql) {
  SqlConnection db(fresh("bind"));
  db.exec("CREATE TABLE t(name TEXT UNIQUE, n INTEGER, x REAL)");
  const std::string nasty = "O'Brien'); DROP TABLE t; --";
  SqlStatement insert(db, "INSERT INTO t(name, n, x) VALUES(?, ?, ?)");
  insert.bind(1, nasty).bind(2, std::int64_t{42}).bind(3, 0.5);
  insert.run();
  EXPECT_EQ(db.last_insert_rowid(), 1);
  insert.bind(1, std::string("second")).bind(2, std::int64_t{7});  // x left unbound: NULL
  insert.run();
  SqlStatement q(db, "SELECT n, x FROM t WHERE name = ?");
  q.bind(1, nasty);
  ASSERT_TRUE(q.step());
  EXPECT_EQ(q.int64(0), 42);
  EXPECT_DOUBLE_EQ(q.real(1), 0.5);
  EXPECT_FALSE(q.step());
  q.reset();
  q.bind(1, std::string("second"));
  ASSERT_TRUE(q.step());
  EXPECT_TRUE(q.is_null(1));
  EXPECT_EQ(count_rows(db), 2);
}

TEST(Sql, ErrorsNameTheDatabaseAndCarrySqliteCodes) {
  const std::string path = fresh("errors");
  SqlConnection db(path);
  db.exec("CREATE TABLE t(name TEXT UNIQUE)");
  try {
    SqlStatement q(db, "SELECT no_such_column FROM t");
    ADD_FAILURE() << "prepared";
  } catch (const SqlError& e) {
    EXPECT_EQ(e.where(), path);
    EXPECT_NE(std::string(e.what()).find("cannot prepare 'SELECT no_such_column FROM t'"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("no such column"), std::string::npos) << e.what();
    EXPECT_EQ(e.code(), SQLITE_ERROR);
    EXPECT_FALSE(e.busy());
  }
  // One statement only: text spliced into a statement cannot add another.
  EXPECT_THROW(SqlStatement(db, "SELECT 1; DROP TABLE t"), SqlError);
  EXPECT_NO_THROW(SqlStatement(db, "SELECT 1;  "));
  SqlStatement insert(db, "INSERT INTO t(name) VALUES(?)");
  insert.bind(1, std::string("a"));
  insert.run();
  insert.bind(1, std::string("a"));
  try {
    insert.run();
    ADD_FAILURE() << "duplicate inserted";
  } catch (const SqlError& e) {
    EXPECT_EQ(e.code(), SQLITE_CONSTRAINT) << e.what();
  }
  try {
    db.exec("CREATE TABLE t(x)");
    ADD_FAILURE() << "table created twice";
  } catch (const SqlError& e) {
    EXPECT_NE(std::string(e.what()).find("cannot run 'CREATE TABLE t(x)'"), std::string::npos) << e.what();
  }
  // An SqlError is an InputError: the command line reports it with exit code 2.
  EXPECT_THROW(db.exec("nonsense"), InputError);
  EXPECT_TRUE(SqlError("p", "m", SQLITE_BUSY).busy());
  EXPECT_TRUE(SqlError("p", "m", SQLITE_LOCKED).busy());
}

TEST(Sql, TransactionRollsBackUnlessCommitted) {
  SqlConnection db(fresh("tx"));
  db.exec("CREATE TABLE t(n INTEGER)");
  {
    SqlTransaction tx(db);
    db.exec("INSERT INTO t VALUES(1)");
  }
  EXPECT_EQ(count_rows(db), 0);
  try {
    SqlTransaction tx(db);
    db.exec("INSERT INTO t VALUES(1)");
    throw std::runtime_error("leaving early");
  } catch (const std::runtime_error&) {
  }
  EXPECT_EQ(count_rows(db), 0);
  {
    SqlTransaction tx(db);
    db.exec("INSERT INTO t VALUES(1)");
    tx.commit();
  }
  EXPECT_EQ(count_rows(db), 1);
}

TEST(Sql, BusyErrorsAreRetriedOthersAreNot) {
  int calls = 0;
  retry_while_busy([&] {
    if (++calls < 4) throw SqlError("db", "busy", SQLITE_BUSY);
  });
  EXPECT_EQ(calls, 4);
  calls = 0;
  EXPECT_THROW(retry_while_busy([&] {
                 ++calls;
                 throw SqlError("db", "broken", SQLITE_CORRUPT);
               }),
               SqlError);
  EXPECT_EQ(calls, 1);
  calls = 0;
  EXPECT_THROW(retry_while_busy([&] {
                 ++calls;
                 throw InputError("db", "not SQLite's");
               }),
               InputError);
  EXPECT_EQ(calls, 1);
}

TEST(Sql, OpeningAFolderFailsNamingIt) {
  const fs::path dir = testing_scratch::scratch_dir("sql", "folder");
  try {
    SqlConnection db(dir.string());
    db.exec("CREATE TABLE t(x)");
    ADD_FAILURE() << "a folder opened as a database";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), dir.string()) << e.what();
  }
}

}  // namespace
}  // namespace tbdr
