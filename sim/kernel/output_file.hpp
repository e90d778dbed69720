#pragma once
// Output files written whole or not at all. An output is written to a temporary file beside it
// (the same folder, so the rename is atomic) that replaces it only when every byte is written; a
// failure (a full disk, a file size limit, a write error) removes the temporary and reports the
// output by name with the system's reason. No 0-byte or partial file is left, and a file already
// at the path is kept as it was.
#include <functional>
#include <iosfwd>
#include <string>
#include <string_view>

namespace tbdr {

/// A temporary file beside an output, renamed over the output by commit() and removed if
/// destroyed before. An output that exists and is not a regular file (a terminal, a pipe,
/// /dev/null) is written in place: temp_path() is the output itself. A symlink's target is
/// replaced, not the symlink.
class PendingOutput {
 public:
  explicit PendingOutput(const std::string& path);
  ~PendingOutput();
  PendingOutput(const PendingOutput&) = delete;
  PendingOutput& operator=(const PendingOutput&) = delete;

  const std::string& path() const { return path_; }
  /// Where to write.
  const std::string& temp_path() const { return temp_; }
  /// Moves the written temporary over the output (InputError naming the output on failure; the
  /// temporary is removed then too).
  void commit();

 private:
  std::string path_;    ///< the output, as named
  std::string target_;  ///< what the rename replaces (the symlink's target for a symlink)
  std::string temp_;
  bool committed_ = false;
};

/// Writes an output file with `write`, whole or not at all (PendingOutput). InputError naming
/// `path`: "cannot write <what>: <the system's reason>", e.g. "No space left on device" or "File
/// too large"; nothing is left at `path` then (an existing file is unchanged).
void write_output_file(const std::string& path, const std::string& what, const std::function<void(std::ostream&)>& write);

/// write_output_file of bytes already in memory.
void write_output_file(const std::string& path, const std::string& what, std::string_view bytes);

/// "cannot write <what>: <strerror(err)>" (or without the reason when err is 0), for a write
/// that failed with errno `err`.
std::string write_failure(const std::string& what, int err);

}  // namespace tbdr
