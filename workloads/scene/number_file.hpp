#pragma once
// Line-oriented text files of numbers with a versioned header, read one line at a time: light
// files (docs/lights.md) and camera path files (docs/sequences.md). The first non-blank,
// non-comment line is `<magic> <version>`; then one record per line, its words separated by spaces
// or tabs; a word starting with `#` comments out the rest of its line; blank lines are skipped.
// Every error is an InputError naming file:line and the offending token.
#include <fstream>
#include <string>
#include <vector>

namespace tbdr {

/// Reads a numbers file record by record.
class NumberFile {
 public:
  /// Opens `path` (`what` names the file in errors: "light file", "camera path file") whose
  /// header must be `magic` followed by `version`.
  NumberFile(std::string path, std::string magic, int version, std::string what);
  /// The next record's words (after the header), or false at the end of the file (an empty file
  /// or one without the header: InputError).
  bool next(std::vector<std::string>& words);
  /// The line of the record read last.
  long line() const { return line_; }
  /// `word` as a finite float; InputError "expected a finite number for <name>, got '<word>'".
  float number(const std::string& word, const std::string& name) const;
  /// An InputError naming the file and the record's line.
  [[noreturn]] void fail(const std::string& message) const;

 private:
  std::string path_, magic_, what_;
  int version_;
  std::ifstream in_;
  long line_ = 0;
  bool header_ = false;
};

/// `line`'s words: split on spaces, tabs and carriage returns, up to a word starting with `#`.
std::vector<std::string> split_words(const std::string& line);

}  // namespace tbdr
