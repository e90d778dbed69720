#include "scene/number_file.hpp"

#include <charconv>
#include <cmath>
#include <utility>

#include "kernel/errors.hpp"

namespace tbdr {

std::vector<std::string> split_words(const std::string& line) {
  std::vector<std::string> out;
  std::size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && (line[i] == ' ' || line[i] == '\t' || line[i] == '\r')) ++i;
    if (i < line.size() && line[i] == '#') break;  // a word starting with # comments out the rest
    const std::size_t start = i;
    while (i < line.size() && line[i] != ' ' && line[i] != '\t' && line[i] != '\r') ++i;
    if (i > start) out.push_back(line.substr(start, i - start));
  }
  return out;
}

NumberFile::NumberFile(std::string path, std::string magic, int version, std::string what)
    : path_(std::move(path)), magic_(std::move(magic)), what_(std::move(what)), version_(version), in_(path_) {
  if (!in_) throw InputError(path_, "cannot open " + what_);
}

bool NumberFile::next(std::vector<std::string>& words) {
  std::string text;
  while (std::getline(in_, text)) {
    ++line_;
    words = split_words(text);
    if (words.empty()) continue;
    if (header_) return true;
    const std::string header = magic_ + " " + std::to_string(version_);
    if (words[0] != magic_) fail("expected the header '" + header + "', got '" + words[0] + "'");
    if (words.size() != 2 || words[1] != std::to_string(version_)) {
      fail("unsupported " + what_ + " version '" + (words.size() > 1 ? words[1] : std::string()) + "' (this build reads version " +
           std::to_string(version_) + ")");
    }
    header_ = true;
  }
  if (!header_) {
    ++line_;
    fail("empty " + what_ + ": missing the header '" + magic_ + " " + std::to_string(version_) + "'");
  }
  return false;
}

float NumberFile::number(const std::string& word, const std::string& name) const {
  float f = 0.0f;
  const auto [ptr, ec] = std::from_chars(word.data(), word.data() + word.size(), f);
  if (ec != std::errc() || ptr != word.data() + word.size() || !std::isfinite(f)) {
    fail("expected a finite number for " + name + ", got '" + word + "'");
  }
  return f;
}

void NumberFile::fail(const std::string& message) const { throw InputError(path_, line_, message); }

}  // namespace tbdr
