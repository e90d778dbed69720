// `tbdrsim dram-bench`: a DRAM microbenchmark (models/dram_microbench.hpp) on the configured DRAM,
// its figures printed one per line, and optionally its request or command stream exported
// (--memory-trace) for DRAMsim3 or DRAMPower (bench/dram_vs_dramsim3.sh, bench/dram_vs_drampower.sh).
#include <cstdio>
#include <iostream>

#include <boost/program_options.hpp>

#include "app/cli.hpp"
#include "app/commands.hpp"
#include "app/memory_trace_options.hpp"
#include "kernel/errors.hpp"
#include "models/dram_microbench.hpp"

namespace tbdr {

namespace po = boost::program_options;

int cmd_dram_bench(const std::vector<std::string>& args, std::ostream& out, std::ostream&) {
  po::options_description desc("dram-bench options");
  add_config_options(desc);
  desc.add_options()("pattern", po::value<std::string>()->default_value("stream"),
                     "stream (consecutive 64 B lines from 0) or random (lines uniform over 1 GiB)")(
      "lines", po::value<std::uint64_t>()->default_value(65536), "64 B reads to issue")(
      "seed", po::value<std::uint64_t>()->default_value(1), "seed of the random pattern");
  add_memory_trace_options(desc);
  po::variables_map vm;
  if (!parse_command_options("dram-bench", args, desc, nullptr, vm, out)) return 0;
  const std::string pattern_name = vm["pattern"].as<std::string>();
  DramPattern pattern = DramPattern::Stream;
  if (pattern_name == "random") {
    pattern = DramPattern::Random;
  } else if (pattern_name != "stream") {
    throw InputError("--pattern " + pattern_name, "expected stream or random");
  }
  const std::uint64_t lines = vm["lines"].as<std::uint64_t>();
  if (lines == 0 || lines > (std::uint64_t{1} << 26)) {
    throw InputError("--lines " + std::to_string(lines), "expected 1..67108864 lines");
  }
  const ResolvedConfig config = config_from_options(vm);
  std::unique_ptr<DramTraceExport> trace = memory_trace_from_options(vm);  // checked before the run
  const DramBenchResult r = run_dram_microbench(config.hw, pattern, lines, vm["seed"].as<std::uint64_t>(), trace.get());
  if (trace) trace->write(vm["memory-trace"].as<std::string>());
  const DramStats& s = r.stats;
  const double t_rfc_ns = config.hw.dram.t_rfc_ns;
  char buf[160];
  const auto line = [&](const char* name, double v) {
    std::snprintf(buf, sizeof buf, "%s %.6g\n", name, v);
    out << buf;
  };
  line("elapsed_ns", r.ns);
  line("read_bytes", static_cast<double>(s.read_bytes.value()));
  line("achieved_bandwidth_gbps", s.achieved_bandwidth_gbps.value());
  line("avg_read_latency_ns", s.avg_read_latency_ns.value());
  line("row_hit_rate", s.row_hit_rate.value());
  // Per burst (one column command each), as a tool counting 32 B transactions sees it: 1 - activates / bursts.
  const double bursts = static_cast<double>(s.read_bytes.value() + s.write_bytes.value()) / config.hw.dram.burst_bytes;
  line("row_hit_rate_per_burst", bursts > 0 ? 1.0 - static_cast<double>(s.activates.value()) / bursts : 0.0);
  line("activates", static_cast<double>(s.activates.value()));
  line("precharges", static_cast<double>(s.precharges.value()));
  line("refreshes", static_cast<double>(s.refreshes.value()));
  // Share of channel time spent refreshing: refreshes x tRFC over channels x elapsed.
  line("refresh_share", r.ns > 0 ? static_cast<double>(s.refreshes.value()) * t_rfc_ns /
                                       (static_cast<double>(config.hw.dram.channels) * r.ns)
                                 : 0.0);
  line("energy_read_pj", s.energy_read_pj.value());
  line("energy_write_pj", s.energy_write_pj.value());
  line("energy_io_pj", s.energy_io_pj.value());
  line("energy_activate_pj", s.energy_activate_pj.value());
  line("energy_background_pj", s.energy_background_pj.value());
  line("energy_refresh_pj", s.energy_refresh_pj.value());
  line("energy_pj", s.energy_pj.value());
  return 0;
}

}  // namespace tbdr
