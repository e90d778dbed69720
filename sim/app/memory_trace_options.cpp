#include "app/memory_trace_options.hpp"

#include <stdexcept>
#include <string>

#include "app/stats_export.hpp"
#include "kernel/errors.hpp"

namespace tbdr {

namespace po = boost::program_options;

void add_memory_trace_options(po::options_description& desc) {
  desc.add_options()("memory-trace", po::value<std::string>(),
                     "write what reaches the DRAM to FILE (and its latency summary to FILE.summary)")(
      "memory-trace-format", po::value<std::string>(),
      "dramsim3: the request stream, DRAMsim3 trace lines; drampower: the command stream, DRAMPower 5 CSV");
}

std::unique_ptr<DramTraceExport> memory_trace_from_options(const po::variables_map& vm) {
  const bool file = vm.count("memory-trace") != 0, format = vm.count("memory-trace-format") != 0;
  if (!file && !format) return nullptr;
  if (!format) throw InputError("--memory-trace", "needs --memory-trace-format dramsim3 or drampower");
  const std::string name = vm["memory-trace-format"].as<std::string>();
  if (!file) throw InputError("--memory-trace-format " + name, "needs --memory-trace FILE");
  DramTraceFormat f{};
  try {
    f = parse_dram_trace_format(name);
  } catch (const std::invalid_argument& e) {
    throw InputError("--memory-trace-format " + name, e.what());
  }
  const std::string path = vm["memory-trace"].as<std::string>();
  check_output_file("--memory-trace", path);
  return std::make_unique<DramTraceExport>(f);
}

}  // namespace tbdr
