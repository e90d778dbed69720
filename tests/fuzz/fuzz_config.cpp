// libFuzzer harness: a hardware config file (INI, read_ini_file + every parameter's parser),
// through a file as a user's config goes, then the constraints between parameters and the models
// a configuration builds (caches, DRAM, the memory system: each refuses a geometry it cannot
// model with std::invalid_argument). Bad input must end in an InputError before any model is
// built; a model refusing a configuration the checks passed is a finding.
#include <cstddef>
#include <cstdint>

#include "fuzz_input.hpp"
#include "kernel/errors.hpp"
#include "kernel/event_queue.hpp"
#include "models/config_checks.hpp"
#include "models/hw_config.hpp"
#include "models/memory_system.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string path = tbdr::fuzz::write_input("fuzz.ini", data, size);
  const tbdr::ParamTable& table = tbdr::hw_params().table();
  tbdr::HwConfig hw;
  try {
    tbdr::ResolvedParams p = table.defaults();
    table.apply_config_file(p, path);
    hw = tbdr::hw_params().build(p);
    tbdr::check_config_constraints(hw, p);
  } catch (const tbdr::InputError&) {
    return 0;
  }
  // Accepted: the models must take it (an uncaught std::invalid_argument here is a finding).
  tbdr::EventQueue eq;
  const tbdr::MemorySystem mem(hw, eq, "fuzz");
  (void)mem;
  return 0;
}
