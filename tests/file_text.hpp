#pragma once
// Tests' way to read a whole file as text (docs, logs, outputs); empty when it cannot be opened.
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace tbdr::testing_support {

/// The bytes of `path` as a string ("" when it cannot be read).
inline std::string read_text(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

}  // namespace tbdr::testing_support
