#pragma once
// What the DRAM controller (models/dram.hpp) tells an observer, for exporting its request and
// command streams to other tools (models/dram_trace_export.hpp). Dram calls it only when one is
// set (Dram::set_observer): a null check otherwise. Timed requests only (not access_functional). Calls come in the order the scheduler decides,
// which is not time order across channels (activates are decided ahead of their cycle).
#include <cstdint>

#include "kernel/time.hpp"

namespace tbdr {

class Dram;

/// Receives every request the DRAM accepts and every command it decides (cycles of the DRAM clock).
class DramObserver {
 public:
  virtual ~DramObserver() = default;
  /// Called once by whoever installs the observer, before Dram::set_observer: the DRAM it watches
  /// (its clock, geometry and timing); it outlives the callbacks.
  virtual void attach(const Dram& dram) = 0;
  /// A request accepted at `now` (timed: enqueue; functional: access_functional), `bytes` whole bursts.
  virtual void request(Tick now, std::uint64_t addr, std::uint32_t bytes, bool is_write) = 0;
  /// A row opened: precharge at `pre_cycle` (-1: the bank was precharged), activate at `act_cycle`.
  virtual void activate(std::uint32_t channel, std::uint32_t bank, std::uint64_t row, std::int64_t pre_cycle,
                        std::int64_t act_cycle) = 0;
  /// A queue entry's column commands: the first at `cmd_cycle`, its `bursts` bursts on the data bus
  /// from `data_start` to `data_end`; `enqueued` is when the request entered the controller and
  /// `done_after` the latency from its last data to the requester (reads: the latency figures).
  virtual void column(std::uint32_t channel, std::uint32_t bank, std::uint64_t row, std::uint32_t column_bytes,
                      bool is_write, std::int64_t cmd_cycle, std::uint32_t bursts, std::uint32_t lines, Tick enqueued,
                      Tick data_start, Tick data_end, Tick done_after) = 0;
  /// `count` all-bank refreshes of `channel`, the first starting at `start_cycle`, then every
  /// `interval_cycles`; open banks are precharged tRP before the first.
  virtual void refresh(std::uint32_t channel, std::int64_t start_cycle, std::int64_t count,
                       std::int64_t interval_cycles) = 0;
};

}  // namespace tbdr
