#pragma once
// `--memory-trace FILE --memory-trace-format dramsim3|drampower`: the DRAM request or command
// stream of a run, for other DRAM tools (models/dram_trace_export.hpp, docs/dram-cross-check.md).
#include <memory>

#include <boost/program_options.hpp>

#include "models/dram_trace_export.hpp"

namespace tbdr {

/// Declares --memory-trace and --memory-trace-format.
void add_memory_trace_options(boost::program_options::options_description& desc);
/// The export the options ask for (nullptr: none). Checks them before anything runs: InputError
/// (exit 2, nothing written) for an unknown format, a format without a file or a file without a
/// format, or a file that cannot be written.
std::unique_ptr<DramTraceExport> memory_trace_from_options(const boost::program_options::variables_map& vm);

}  // namespace tbdr
