#pragma once
// Error types shared by every input reader (config, trace, glTF, database, command line).
// Each carries what a user needs to fix the input: the file (or argument), the line when there is
// one, and what was wrong. The command-line tool turns them into a message and exit code 2.
#include <stdexcept>
#include <string>

namespace tbdr {

/// Bad input from a user: a config, trace, scene, light file, database or command-line argument.
/// `where` is "file:line", "file", or "--set a.b=c"; what() is the full message "where: message".
class InputError : public std::runtime_error {
 public:
  InputError(std::string where, const std::string& message)
      : std::runtime_error(where.empty() ? message : where + ": " + message), where_(std::move(where)) {}
  /// Convenience: "file:line".
  InputError(const std::string& file, long line, const std::string& message)
      : InputError(file + ":" + std::to_string(line), message) {}
  const std::string& where() const { return where_; }

 private:
  std::string where_;
};

/// The command line itself is malformed (unknown command or option): print usage, exit 2.
class UsageError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// The simulation cannot make progress (a deadlock in the timing model); names the stuck units.
class StallError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace tbdr
