// `tbdrsim dram-bench`: a DRAM microbenchmark (models/dram_microbench.hpp) on the configured DRAM,
// or an open-loop replay of a request stream in DRAMsim3's trace format (--replay), its figures
// printed one per line, and optionally its request or command stream exported (--memory-trace)
// for DRAMsim3 or DRAMPower (bench/dram_vs_dramsim3.sh, bench/dram_vs_drampower.sh).
#include <cmath>
#include <filesystem>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <sstream>

#include <boost/program_options.hpp>

#include "app/cli.hpp"
#include "app/commands.hpp"
#include "app/memory_trace_options.hpp"
#include "kernel/errors.hpp"
#include "kernel/params.hpp"
#include "kernel/text_escape.hpp"
#include "models/dram_microbench.hpp"

namespace tbdr {

namespace po = boost::program_options;

namespace {

/// The line a replayed chain counts in the controller's queues (models/dram_microbench's 64 B).
constexpr std::uint32_t kReplayLineBytes = 64;
/// Longest accepted line of a replay file: "0x" + 16 hex digits, a kind, a cycle count.
constexpr std::size_t kMaxReplayLineBytes = 256;
/// Largest replay file: 256 MiB, about 11 million 32 B transactions (a 1080p deferred frame's
/// stream is 68 MB); each request read is 32 bytes of memory.
constexpr std::uintmax_t kMaxReplayFileBytes = std::uintmax_t{1} << 28;

/// Reads a DRAMsim3 trace ("0xADDR READ|WRITE CYCLE" per line, CYCLE in cycles of the configured
/// DRAM clock, non-decreasing): consecutive transactions of one kind and cycle that continue each
/// other inside one row are merged into one request, up to dram.max_chain_bytes (tbdrsim's burst
/// chains, which its export wrote as one transaction per burst).
std::vector<DramReplayRequest> read_replay(const std::string& path, const HwConfig& hw) {
  check_input_file(path, "replay file");
  std::error_code ec;
  const std::uintmax_t size = std::filesystem::file_size(path, ec);
  if (!ec && size > kMaxReplayFileBytes) {
    throw InputError(path, std::to_string(size) + " bytes, more than the 268435456 (256 MiB) a replay file may have");
  }
  std::ifstream in(path);
  if (!in) throw InputError(path, "cannot open the replay file");
  const double period_ps = 1e6 / hw.dram.clock_mhz;
  const auto row = static_cast<std::uint64_t>(hw.dram.row_bytes);
  const auto chain_max = static_cast<std::uint64_t>(std::max<std::int64_t>(hw.dram.max_chain_bytes, kReplayLineBytes));
  const auto burst = static_cast<std::uint32_t>(hw.dram.burst_bytes);
  std::vector<DramReplayRequest> out;
  std::string text;
  long n = 0;
  std::uint64_t last_cycle = 0;
  while (std::getline(in, text)) {
    ++n;
    if (text.size() > kMaxReplayLineBytes) throw InputError(path, n, "line longer than 256 bytes");
    if (text.empty() || text[0] == '#') continue;
    std::istringstream ls(text);
    std::string addr_s, kind;
    std::uint64_t cycle = 0;
    if (!(ls >> addr_s >> kind >> cycle)) throw InputError(path, n, "expected '0xADDR READ|WRITE CYCLE'");
    std::string rest;
    if (ls >> rest) throw InputError(path, n, "unexpected '" + escape_for_message(rest) + "' after the cycle");
    if (kind != "READ" && kind != "WRITE") throw InputError(path, n, "expected READ or WRITE, got '" + escape_for_message(kind) + "'");
    std::size_t used = 0;
    std::uint64_t addr = 0;
    try {
      addr = std::stoull(addr_s, &used, 16);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used != addr_s.size() || addr_s.rfind("0x", 0) != 0) throw InputError(path, n, "expected a hexadecimal address 0x..., got '" + escape_for_message(addr_s) + "'");
    if (cycle < last_cycle) throw InputError(path, n, "cycle " + std::to_string(cycle) + " before the previous line's " + std::to_string(last_cycle));
    if (cycle > (std::uint64_t{1} << 40)) throw InputError(path, n, "cycle " + std::to_string(cycle) + " past 2^40");
    last_cycle = cycle;
    const bool is_write = kind == "WRITE";
    const Tick at{std::llround(static_cast<double>(cycle) * period_ps)};
    if (!out.empty()) {
      DramReplayRequest& p = out.back();
      if (p.arrival == at && p.is_write == is_write && p.addr + p.bytes == addr && addr / row == p.addr / row &&
          p.bytes + burst <= chain_max) {
        p.bytes += burst;
        p.lines = (p.bytes + kReplayLineBytes - 1) / kReplayLineBytes;
        continue;
      }
    }
    out.push_back(DramReplayRequest{at, addr, burst, 1, is_write});
  }
  if (out.empty()) throw InputError(path, "no requests in the replay file");
  return out;
}

/// Prints the figures of a microbenchmark or replay, one "name value" per line.
void print_figures(std::ostream& out, const DramBenchResult& r, const HwConfig& hw) {
  const DramStats& s = r.stats;
  char buf[160];
  const auto line = [&](const char* name, double v) {
    std::snprintf(buf, sizeof buf, "%s %.6g\n", name, v);
    out << buf;
  };
  const auto stat = [&](auto DramStats::*member) { line(stat_name(member), (s.*member).as_double()); };
  line("elapsed_ns", r.ns);
  stat(&DramStats::read_bytes);
  stat(&DramStats::write_bytes);
  stat(&DramStats::achieved_bandwidth_gbps);
  stat(&DramStats::avg_read_latency_ns);
  stat(&DramStats::row_hit_rate);
  line("row_hit_rate_per_burst", row_hits_per_burst(s, hw.dram));
  stat(&DramStats::activates);
  stat(&DramStats::precharges);
  stat(&DramStats::refreshes);
  line("refresh_share", refresh_share(s, hw.dram, r.ns));
  stat(&DramStats::energy_read_pj);
  stat(&DramStats::energy_write_pj);
  stat(&DramStats::energy_io_pj);
  stat(&DramStats::energy_activate_pj);
  stat(&DramStats::energy_background_pj);
  stat(&DramStats::energy_refresh_pj);
  stat(&DramStats::energy_pj);
}

}  // namespace

int cmd_dram_bench(const std::vector<std::string>& args, std::ostream& out, std::ostream&) {
  po::options_description desc("dram-bench options");
  add_config_options(desc);
  desc.add_options()("pattern", po::value<std::string>()->default_value("stream"),
                     "stream (consecutive 64 B lines from 0) or random (lines uniform over 1 GiB)")(
      "lines", po::value<std::uint64_t>()->default_value(65536), "64 B reads to issue")(
      "seed", po::value<std::uint64_t>()->default_value(1), "seed of the random pattern")(
      "replay", po::value<std::string>(),
      "instead of a pattern: replay this request stream open loop (DRAMsim3 trace format, as "
      "`--memory-trace-format dramsim3` writes it; cycles of the configured DRAM clock)");
  add_memory_trace_options(desc);
  po::variables_map vm;
  if (!parse_command_options("dram-bench", args, desc, nullptr, vm, out)) return 0;
  if (vm.count("replay") != 0) {
    const ResolvedConfig config = config_from_options(vm);
    const std::vector<DramReplayRequest> requests = read_replay(vm["replay"].as<std::string>(), config.hw);
    std::unique_ptr<DramTraceExport> trace = memory_trace_from_options(vm);  // checked before the run
    const DramReplayResult r = run_dram_replay(config.hw, requests, trace.get());
    if (trace) trace->write(vm["memory-trace"].as<std::string>());
    print_figures(out, r.bench, config.hw);
    char buf[160];
    std::snprintf(buf, sizeof buf, "read_wait_outside_ns %.6g\nread_latency_from_arrival_ns %.6g\n", r.read_wait_outside_ns,
                  r.bench.stats.avg_read_latency_ns.value() + r.read_wait_outside_ns);
    out << buf;
    return 0;
  }
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
  print_figures(out, r, config.hw);
  return 0;
}

}  // namespace tbdr
