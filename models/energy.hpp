#pragma once
// The energy model: every component's energy is a counter of the run times its unit cost from
// the [energy] parameters (DRAM per bit and per activate+precharge from the memory system, SRAM
// per byte by structure, per ALU op, per texel) plus static power times frame time. The records
// it produces let a reader recompute every figure from the counters.
#include <string>
#include <vector>

#include "models/command_processor.hpp"
#include "models/hw_config.hpp"
#include "models/memory_system.hpp"
#include "kernel/stats.hpp"

namespace tbdr {

/// One energy component: the counter it is charged on, the count, the unit cost and the product.
struct EnergyTerm {
  std::string component;  ///< "dram", "tile_buffer", "alu", ...
  std::string counter;    ///< what is counted ("bytes", "ops", "ps x mW", ...)
  double count = 0;
  double pj_per_unit = 0;
  double pj = 0;
};

/// The energy of a frame by component.
struct EnergyBreakdown {
  std::vector<EnergyTerm> terms;
  double total_pj = 0;
  /// Statistic records: "frame/energy" <component>_pj and total_pj / total_mj.
  void collect(std::vector<StatRecord>& out) const;
};

/// Computes the breakdown from the frame's unit statistics, the memory system's energies and the
/// frame time.
EnergyBreakdown compute_energy(const HwConfig& hw, const FrameStats& frame, const MemorySystemStats& memory,
                               double frame_time_ps);

}  // namespace tbdr
