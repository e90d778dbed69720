// libFuzzer harness: a hardware config file (INI, read_ini_file + every parameter's parser),
// through a file as a user's config goes. Bad input must end in an InputError.
#include <cstddef>
#include <cstdint>

#include "fuzz_input.hpp"
#include "kernel/errors.hpp"
#include "models/hw_config.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string path = tbdr::fuzz::write_input("fuzz.ini", data, size);
  const tbdr::ParamTable& table = tbdr::hw_params().table();
  try {
    tbdr::ResolvedParams p = table.defaults();
    table.apply_config_file(p, path);
    (void)tbdr::hw_params().build(p);
  } catch (const tbdr::InputError&) {
  }
  return 0;
}
