// libFuzzer harness: the trace reader (parse_trace_frames: one frame or a sequence) on arbitrary
// bytes. Bad input must end in an InputError; anything else (a crash, a sanitizer report, another
// exception) is a finding.
#include <cstddef>
#include <cstdint>
#include <sstream>
#include <string>
#include <vector>

#include "kernel/errors.hpp"
#include "trace/trace.hpp"

namespace {
std::string text_of(const std::vector<tbdr::Trace>& frames) {
  std::ostringstream out;
  tbdr::write_trace_frames(frames, out);
  return out.str();
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::istringstream in(std::string(reinterpret_cast<const char*>(data), size));
  try {
    const std::vector<tbdr::Trace> frames = tbdr::parse_trace_frames(in, "fuzz.trace");
    // A trace the reader accepts must write and read back to the same text.
    const std::string text = text_of(frames);
    std::istringstream again(text);
    if (text_of(tbdr::parse_trace_frames(again, "rewritten.trace")) != text) __builtin_trap();
  } catch (const tbdr::InputError&) {
  }
  return 0;
}
