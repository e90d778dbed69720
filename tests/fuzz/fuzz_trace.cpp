// libFuzzer harness: the trace reader (parse_trace) on arbitrary bytes. Bad input must end in an
// InputError; anything else (a crash, a sanitizer report, another exception) is a finding.
#include <cstddef>
#include <cstdint>
#include <sstream>
#include <string>

#include "kernel/errors.hpp"
#include "trace/trace.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::istringstream in(std::string(reinterpret_cast<const char*>(data), size));
  try {
    const tbdr::Trace t = tbdr::parse_trace(in, "fuzz.trace");
    // A trace the reader accepts must write and read back to the same text.
    const std::string text = tbdr::trace_text(t);
    std::istringstream again(text);
    if (tbdr::trace_text(tbdr::parse_trace(again, "rewritten.trace")) != text) __builtin_trap();
  } catch (const tbdr::InputError&) {
  }
  return 0;
}
