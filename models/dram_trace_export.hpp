#pragma once
// Exports what reaches the DRAM model, for checking it against tools the project did not write
// (docs/dram-cross-check.md, bench/dram_vs_dramsim3.sh, bench/dram_vs_drampower.sh):
//  - dramsim3: the request stream in DRAMsim3's trace format, one line per burst,
//    "0xADDRESS READ|WRITE CYCLE" (DRAMsim3 src/cpu.cc TraceBasedCPU; the cycle in DRAM clock
//    cycles, the request's enqueue time);
//  - drampower: the command stream in the DRAMPower 5 command-line tool's CSV format,
//    "cycle,CMD,rank,bank_group,bank,row,column[,data]" (DRAMPower src/cli/main.cpp), the channel
//    as the rank, one RD/WR per burst (the data: burst_bytes zero bytes), PREA before a refresh
//    that closes open rows, REFA, and END one cycle after the last command.
// Both are collected in memory while the run goes and written, sorted by time, by write().
// A summary beside the trace (FILE.summary) gives the model's own latency distribution over the
// same requests, which its statistics do not keep (mean, 50th and 99th percentile).
#include <cstdint>
#include <string>
#include <vector>

#include "models/dram.hpp"
#include "models/dram_observer.hpp"

namespace tbdr {

/// The trace formats `--memory-trace-format` accepts.
enum class DramTraceFormat : std::uint8_t { Dramsim3, Drampower };
/// "dramsim3" or "drampower"; std::invalid_argument naming the accepted values otherwise.
DramTraceFormat parse_dram_trace_format(const std::string& name);

/// Counts of what an export holds (for tests and the summary).
struct DramTraceCounts {
  std::uint64_t request_lines = 0;  ///< dramsim3 lines (one per burst of an accepted request)
  std::uint64_t rd = 0, wr = 0;     ///< RD / WR commands (one per burst)
  std::uint64_t act = 0, pre = 0, prea = 0, refa = 0;
};

/// Collects a Dram's requests and commands (set it with Dram::set_observer) and writes them.
class DramTraceExport final : public DramObserver {
 public:
  explicit DramTraceExport(DramTraceFormat format) : format_(format) {}

  void attach(const Dram& dram) override;
  void request(Tick now, std::uint64_t addr, std::uint32_t bytes, bool is_write) override;
  void activate(std::uint32_t channel, std::uint32_t bank, std::uint64_t row, std::int64_t pre_cycle,
                std::int64_t act_cycle) override;
  void column(std::uint32_t channel, std::uint32_t bank, std::uint64_t row, std::uint32_t column_bytes, bool is_write,
              std::int64_t cmd_cycle, std::uint32_t bursts, std::uint32_t lines, Tick enqueued, Tick data_start,
              Tick data_end, Tick done_after) override;
  void refresh(std::uint32_t channel, std::int64_t start_cycle, std::int64_t count, std::int64_t interval_cycles) override;

  /// After the run (the DRAM may be gone): writes the trace to `path` and the summary to `path` + ".summary" (std::runtime_error naming
  /// the file when it cannot be written).
  void write(const std::string& path);
  const DramTraceCounts& counts() const { return counts_; }
  /// Read latencies per line (ps, enqueue to data back), in the order the lines were served.
  const std::vector<std::int64_t>& read_latencies_ps() const { return read_latency_ps_; }

 private:
  // One DRAMPower command; `seq` keeps the decision order among commands of one cycle.
  struct Cmd {
    std::int64_t cycle;
    std::uint64_t seq;
    std::uint64_t row;
    std::uint32_t column;
    std::uint16_t channel;
    std::uint8_t bank;
    std::uint8_t type;  // index into kCmdNames
  };
  void push(std::int64_t cycle, std::uint8_t type, std::uint32_t channel, std::uint32_t bank, std::uint64_t row,
            std::uint32_t column);
  void close_banks(std::uint32_t channel, std::int64_t refresh_cycle);

  DramTraceFormat format_;
  const Dram* dram_ = nullptr;  // during the run only (write() may come after it is gone)
  std::uint32_t burst_bytes_ = 0;  // what write() needs, copied at attach()
  std::uint32_t bank_groups_ = 1;
  // One dramsim3 line per burst: written at the request's cycle, in acceptance order (time order).
  struct Req {
    std::int64_t cycle;
    std::uint64_t addr;
    bool is_write;
  };
  std::vector<Cmd> cmds_;
  std::vector<Req> reqs_;
  std::vector<std::vector<std::int64_t>> open_row_;  // per channel and bank: -1 precharged (the export's own view)
  std::vector<std::int64_t> read_latency_ps_;
  std::uint64_t seq_ = 0;
  DramTraceCounts counts_;
};

}  // namespace tbdr
