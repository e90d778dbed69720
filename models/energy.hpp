#pragma once
// The energy model: every component's energy is a counter of the run times its unit cost (DRAM per
// bit and per activate+precharge from the memory system; SRAM per byte by structure from the CACTI
// table at the structure's configured size and node; per ALU op and per texel from Horowitz's 45 nm
// figures scaled to the node) plus static power (leakage summed over the configured units and
// arrays) times frame time. At a fixed frame period (gpu.frame_period_us) the idle time after the
// frame adds idle power: gated units, caches, DRAM in power-down then self-refresh. The records it
// produces let a reader recompute every figure from the counters (docs/energy.md).
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

/// Leakage of the configured GPU, by kind, at its node.
struct StaticPower {
  double logic_mw = 0;          ///< USCs, texture units, fixed-function units
  double sram_gated_mw = 0;     ///< per-tile buffers and register files (gated when the GPU idles)
  double sram_retained_mw = 0;  ///< caches (keep their data: never gated)
  double total_mw() const { return logic_mw + sram_gated_mw + sram_retained_mw; }
  /// Leakage while the GPU idles: gated parts at energy.gated_leakage_fraction, caches in full.
  double idle_mw(double gated_fraction) const { return (logic_mw + sram_gated_mw) * gated_fraction + sram_retained_mw; }
};

/// The configured GPU's leakage (energy.*_leakage_mw per unit, CACTI per array).
StaticPower static_power(const HwConfig& hw);

/// Background energy of all DRAM channels idle for `idle_ps` after a frame: precharge standby until
/// dram.powerdown_after_ns, then precharge power-down (refreshing) until the next refresh is due
/// (one dram.t_refi_ns at most), then self-refresh (dram.self_refresh_mw; 0: power-down goes on).
double dram_idle_pj(const DramParams& d, double idle_ps);


// The frame's energy totals, leakage and frame-period figures (scope "frame/energy", beside the
// per-component "<component>_pj" rows of EnergyBreakdown::terms; none of these ends in _pj but the
// total).
#define TBDR_ENERGY_FRAME_STATS(X)                                                                         \
  X(Accumulator, total_pj, "pJ", Sum, "Energy of the frame, all components")                                \
  X(Accumulator, total_mj, "mJ", Derived, "Energy of the frame, all components: total_pj x 1e-9")            \
  X(Accumulator, static_power_mw, "mW", Gauge, "Leakage of the configured GPU: logic units + SRAM arrays (static_pj / frame time)") \
  X(Accumulator, static_logic_mw, "mW", Gauge, "Leakage of the USCs, texture and fixed-function units")     \
  X(Accumulator, static_sram_mw, "mW", Gauge, "Leakage of the on-chip SRAM arrays (CACTI, by configured size)") \
  X(Accumulator, idle_time_ms, "ms", Derived, "gpu.frame_period_us minus the frame time (0: race to idle)")  \
  X(Accumulator, idle_gpu_mj, "mJ", Derived, "GPU leakage over the idle time (gated units, caches)")          \
  X(Accumulator, idle_dram_mj, "mJ", Derived, "DRAM background over the idle time (standby, power-down, self-refresh)") \
  X(Accumulator, idle_mj, "mJ", Derived, "Energy of the idle time: idle_gpu_mj + idle_dram_mj")               \
  X(Accumulator, idle_power_mw, "mW", Derived, "Mean power over the idle time: idle_mj / idle_time_ms")        \
  X(Accumulator, at_period_total_mj, "mJ", Derived,                                                          \
    "Energy of one frame period: total_mj + idle_mj (= total_mj when racing to idle)")

/// The frame's energy totals and the figures of a fixed frame period, derived from the breakdown's
/// idle time and energies.
struct EnergyFrameStats {
  TBDR_STATS(TBDR_ENERGY_FRAME_STATS)
  static constexpr const char* kScope = "frame/energy";
  double idle_ps = 0;       ///< EnergyBreakdown::idle_ps
  double idle_gpu_pj = 0;   ///< EnergyBreakdown::idle_gpu_pj
  double idle_dram_pj = 0;  ///< EnergyBreakdown::idle_dram_pj
  void derive() {
    constexpr double kMjPerPj = 1e-9, kMsPerPs = 1e-9, kPjPerMwPs = 1e-3;
    const double idle_pj = idle_gpu_pj + idle_dram_pj;
    total_mj.set(total_pj.value() * kMjPerPj);
    idle_time_ms.set(idle_ps * kMsPerPs);
    idle_gpu_mj.set(idle_gpu_pj * kMjPerPj);
    idle_dram_mj.set(idle_dram_pj * kMjPerPj);
    idle_mj.set(idle_pj * kMjPerPj);
    idle_power_mw.set(idle_ps > 0 ? idle_pj / (idle_ps * kPjPerMwPs) : 0.0);
    at_period_total_mj.set((total_pj.value() + idle_pj) * kMjPerPj);
  }
};

/// The energy of a frame by component, and of one frame period.
struct EnergyBreakdown {
  std::vector<EnergyTerm> terms;
  double total_pj = 0;        ///< the frame at its own duration (race to idle)
  StaticPower leakage;        ///< what the static term charges over the frame time
  double idle_ps = 0;         ///< gpu.frame_period_us x frames - frame time (0 when no period or a longer frame)
  double idle_gpu_pj = 0;     ///< GPU leakage over idle_ps (gated units and caches)
  double idle_dram_pj = 0;    ///< DRAM background over idle_ps
  double idle_pj() const { return idle_gpu_pj + idle_dram_pj; }
  double at_period_total_pj() const { return total_pj + idle_pj(); }
};

/// Computes the breakdown from the frame's unit statistics, the memory system's energies and the
/// frame time; for a sequence of `frames` frames, from their sums and the sequence's time (its
/// fixed-period figure then covers `frames` periods).
EnergyBreakdown compute_energy(const HwConfig& hw, const FrameStats& frame, const MemorySystemStats& memory,
                               double frame_time_ps, int frames = 1);

}  // namespace tbdr
