#include "models/dram_trace_export.hpp"

#include <algorithm>
#include <array>
#include <cerrno>
#include <cinttypes>
#include <cmath>
#include <cstdio>
#include <memory>
#include <stdexcept>

#include "kernel/errors.hpp"
#include "kernel/output_file.hpp"

namespace tbdr {

namespace {

// DRAMPower 5's command names (src/DRAMPower/DRAMPower/command/CmdType.h, CmdTypeUtil::from_string).
enum : std::uint8_t { kAct, kPre, kPrea, kRd, kWr, kRefa, kEnd };
constexpr std::array<const char*, 7> kCmdNames{"ACT", "PRE", "PREA", "RD", "WR", "REFA", "END"};

struct FileCloser {
  void operator()(std::FILE* f) const { std::fclose(f); }
};
using File = std::unique_ptr<std::FILE, FileCloser>;

/// Opens the temporary file of a pending output (InputError naming the output when it cannot).
File open_out(const PendingOutput& out) {
  errno = 0;
  File f(std::fopen(out.temp_path().c_str(), "w"));
  if (!f) throw InputError(out.path(), write_failure("the memory trace", errno));
  return f;
}

/// Closes the temporary file (InputError naming the output when a write failed; the pending output
/// then removes it).
void close_checked(File f, const PendingOutput& out) {
  const bool failed = std::ferror(f.get()) != 0;
  const int err = errno;
  if (failed) throw InputError(out.path(), write_failure("the memory trace", err));
  errno = 0;
  if (std::fclose(f.release()) != 0) throw InputError(out.path(), write_failure("the memory trace", errno));
}

}  // namespace

DramTraceFormat parse_dram_trace_format(const std::string& name) {
  if (name == "dramsim3") return DramTraceFormat::Dramsim3;
  if (name == "drampower") return DramTraceFormat::Drampower;
  throw std::invalid_argument("unknown memory trace format '" + name + "' (expected: dramsim3, drampower)");
}

void DramTraceExport::attach(const Dram& dram) {
  dram_ = &dram;
  burst_bytes_ = dram.burst_bytes();
  bank_groups_ = dram.timing().bank_groups;
  open_row_.assign(dram.channels(), std::vector<std::int64_t>(dram.banks(), -1));
}

void DramTraceExport::request(Tick now, std::uint64_t addr, std::uint32_t bytes, bool is_write) {
  const std::int64_t cycle = dram_->clock().cycles_at(now).count();
  for (std::uint32_t off = 0; off < bytes; off += dram_->burst_bytes()) {
    ++counts_.request_lines;
    if (format_ == DramTraceFormat::Dramsim3) reqs_.push_back(Req{cycle, addr + off, is_write});
  }
}

void DramTraceExport::push(std::int64_t cycle, std::uint8_t type, std::uint32_t channel, std::uint32_t bank,
                           std::uint64_t row, std::uint32_t column) {
  if (format_ == DramTraceFormat::Drampower) {
    cmds_.push_back(Cmd{cycle, seq_++, row, column, static_cast<std::uint16_t>(channel), static_cast<std::uint8_t>(bank), type});
  }
}

void DramTraceExport::activate(std::uint32_t channel, std::uint32_t bank, std::uint64_t row, std::int64_t pre_cycle,
                               std::int64_t act_cycle) {
  if (pre_cycle >= 0) {
    push(pre_cycle, kPre, channel, bank, 0, 0);
    ++counts_.pre;
  }
  push(act_cycle, kAct, channel, bank, row, 0);
  ++counts_.act;
  open_row_[channel][bank] = static_cast<std::int64_t>(row);
}

void DramTraceExport::column(std::uint32_t channel, std::uint32_t bank, std::uint64_t row, std::uint32_t column_bytes,
                             bool is_write, std::int64_t cmd_cycle, std::uint32_t bursts, std::uint32_t lines,
                             Tick enqueued, Tick data_start, Tick data_end, Tick done_after) {
  // One column command per burst, spaced as the bursts are on the data bus (at least a cycle).
  const double period = dram_->clock().period_ps();
  const auto spacing = std::max<std::int64_t>(
      1, static_cast<std::int64_t>(static_cast<double>((data_end - data_start).ps()) / bursts / period + 0.5));
  for (std::uint32_t k = 0; k < bursts; ++k) {
    push(cmd_cycle + spacing * k, is_write ? kWr : kRd, channel, bank, row, column_bytes / dram_->burst_bytes() + k);
  }
  (is_write ? counts_.wr : counts_.rd) += bursts;
  if (is_write) return;
  // Line i of L is back done_after after (i + 1) / L of the transfer (as Dram::commit counts it).
  const std::int64_t first = (data_start + done_after - enqueued).ps();
  const std::int64_t duration = (data_end - data_start).ps();
  for (std::uint32_t i = 0; i < lines; ++i) read_latency_ps_.push_back(first + duration * (i + 1) / lines);
}

void DramTraceExport::close_banks(std::uint32_t channel, std::int64_t refresh_cycle) {
  bool any = false;
  for (auto& r : open_row_[channel]) {
    any = any || r >= 0;
    r = -1;
  }
  if (!any) return;
  // Dram::refresh_until starts a refresh tRP after every open bank may precharge.
  push(refresh_cycle - dram_->timing().t_rp_cycles, kPrea, channel, 0, 0, 0);
  ++counts_.prea;
}

void DramTraceExport::refresh(std::uint32_t channel, std::int64_t start_cycle, std::int64_t count,
                              std::int64_t interval_cycles) {
  close_banks(channel, start_cycle);
  for (std::int64_t i = 0; i < count; ++i) push(start_cycle + i * interval_cycles, kRefa, channel, 0, 0, 0);
  counts_.refa += static_cast<std::uint64_t>(count);
}

void DramTraceExport::write(const std::string& path) {
  // Both files whole or neither (kernel/output_file.hpp): each goes in beside its name first.
  PendingOutput trace_out(path);
  PendingOutput summary_out(path + ".summary");
  File f = open_out(trace_out);
  if (format_ == DramTraceFormat::Dramsim3) {
    for (const Req& r : reqs_) {
      std::fprintf(f.get(), "0x%" PRIx64 " %s %" PRId64 "\n", r.addr, r.is_write ? "WRITE" : "READ", r.cycle);
    }
  } else {
    std::stable_sort(cmds_.begin(), cmds_.end(), [](const Cmd& a, const Cmd& b) {
      return a.cycle != b.cycle ? a.cycle < b.cycle : a.seq < b.seq;
    });
    const std::string data(2 * static_cast<std::size_t>(burst_bytes_), '0');
    const std::uint32_t groups = std::max<std::uint32_t>(1, bank_groups_);
    std::int64_t last = 0;
    for (const Cmd& c : cmds_) {
      std::fprintf(f.get(), "%" PRId64 ",%s,%u,%u,%u,%" PRIu64 ",%u", c.cycle, kCmdNames[c.type], c.channel,
                   c.bank % groups, c.bank, c.row, c.column);
      if (c.type == kRd || c.type == kWr) std::fprintf(f.get(), ",%s", data.c_str());
      std::fputc('\n', f.get());
      last = c.cycle;
    }
    std::fprintf(f.get(), "%" PRId64 ",%s,0,0,0,0,0\n", last + 1, kCmdNames[kEnd]);
  }
  close_checked(std::move(f), trace_out);

  File s = open_out(summary_out);
  std::vector<std::int64_t> lat = read_latency_ps_;
  std::sort(lat.begin(), lat.end());
  double mean = 0;
  for (std::int64_t v : lat) mean += static_cast<double>(v);
  mean = lat.empty() ? 0.0 : mean / static_cast<double>(lat.size());
  // Nearest-rank percentile: the smallest value with at least p of the lines at or below it.
  const auto pct = [&](double p) {
    if (lat.empty()) return 0.0;
    const auto rank = static_cast<std::size_t>(std::max(1.0, std::ceil(p * static_cast<double>(lat.size()))));
    return static_cast<double>(lat[std::min(rank, lat.size()) - 1]) * 1e-3;
  };
  std::fprintf(s.get(), "request_lines %" PRIu64 "\nrd %" PRIu64 "\nwr %" PRIu64 "\nact %" PRIu64 "\npre %" PRIu64
                        "\nprea %" PRIu64 "\nrefa %" PRIu64 "\nread_lines %zu\nread_latency_mean_ns %.3f\n"
                        "read_latency_p50_ns %.3f\nread_latency_p99_ns %.3f\n",
               counts_.request_lines, counts_.rd, counts_.wr, counts_.act, counts_.pre, counts_.prea, counts_.refa,
               lat.size(), mean * 1e-3, pct(0.5), pct(0.99));
  close_checked(std::move(s), summary_out);
  trace_out.commit();
  summary_out.commit();
}

}  // namespace tbdr
