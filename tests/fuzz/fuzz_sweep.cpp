// libFuzzer harness: a sweep file (parse_sweep_file, then expand_sweep), through a file in a
// folder that also holds the trace and config files the seeds name (t.trace, a.ini). Bad input
// must end in an InputError.
#include <cstddef>
#include <cstdint>
#include <fstream>

#include "app/sweep_spec.hpp"
#include "fuzz_input.hpp"
#include "kernel/errors.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const bool files = [] {
    std::ofstream(tbdr::fuzz::scratch() / "t.trace") << "tbdrsim-trace 2\n";
    std::ofstream(tbdr::fuzz::scratch() / "u.trace") << "tbdrsim-trace 2\n";
    std::ofstream(tbdr::fuzz::scratch() / "a.ini") << "[isp]\ntag_buffers = 2\n";
    return true;
  }();
  (void)files;
  const std::string path = tbdr::fuzz::write_input("fuzz_sweep.ini", data, size);
  try {
    const tbdr::SweepSpec spec = tbdr::parse_sweep_file(path);
    (void)tbdr::slice_points(tbdr::expand_sweep(spec), {0, 2});
  } catch (const tbdr::InputError&) {
  }
  return 0;
}
