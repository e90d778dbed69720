#pragma once
// A frame run through the functional pipeline and the timing model, as `tbdrsim run` does, for
// tests that read both (frame statistics, cycles, energy).
#include <string>
#include <vector>

#include "app/run_driver.hpp"
#include "app/stat_rows.hpp"
#include "models/command_processor.hpp"
#include "models/hw_config.hpp"

namespace tbdr {

/// What one timed run produced.
struct Timed {
  FrameResult frame;
  TimingResult timing;
  EnergyBreakdown energy;
  std::vector<StatRecord> stats;  ///< every row the run stores but the host's (run_rows)
};

/// Simulates and times trace `t` on scene `s` with the default hardware plus `sets`.
inline Timed run_timed(const Trace& t, const Scene& s, const std::vector<std::string>& sets) {
  const HwConfig hw = resolve_config({}, sets).hw;
  Timed r;
  r.frame = simulate_frame(t, "t.trace", s, hw);
  time_frame(hw, r.frame, r.timing, r.energy);
  r.stats = run_rows(r.frame, r.timing, r.energy);
  return r;
}

}  // namespace tbdr
