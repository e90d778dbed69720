#pragma once
// Reading a trace from text in a test, and expecting the reader's error at a line (tests only).
#include <gtest/gtest.h>

#include <sstream>
#include <string>

#include "kernel/errors.hpp"
#include "trace/trace.hpp"

namespace tbdr::testing_support {

/// The trace `text` as the reader reads it, named `name` in its errors.
inline Trace parse_text(const std::string& text, const std::string& name = "t.trace") {
  std::istringstream in(text);
  return parse_trace(in, name);
}

/// Expects reading `text` to fail at `line` (as t.trace:LINE) with a message containing `token`.
inline void expect_trace_error(const std::string& text, int line, const std::string& token) {
  try {
    parse_text(text);
    ADD_FAILURE() << "no error; expected line " << line << " with " << token << "\n" << text;
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_EQ(e.where(), "t.trace:" + std::to_string(line)) << what;
    EXPECT_NE(what.find(token), std::string::npos) << "message lacks " << token << ": " << what;
  }
}

}  // namespace tbdr::testing_support
