#pragma once
// The command processor and run driver of one frame: replays a trace's commands in order through
// the units in models/ (geometry -> tiler/parameter buffer -> per tile ISP, TSP, tile memory),
// handles partial renders, and collects every unit's statistics per pass and for the frame.
#include <cstdint>
#include <string>
#include <vector>

#include "models/frame_work.hpp"
#include "models/hw_config.hpp"
#include "models/render_state.hpp"
#include "models/traffic.hpp"
#include "kernel/stats.hpp"
#include "trace/trace.hpp"
#include "scene/scene.hpp"

namespace tbdr {

/// What one pass did, for summaries (the full figures are in FrameResult::stats).
struct PassSummary {
  std::string name;
  std::uint64_t primitives = 0;
  std::uint64_t shaded_samples = 0;
  std::uint64_t partial_renders = 0;
  DramTraffic dram;
};

/// The functional result of a frame: statistics, per-pixel counters, the attachment images.
struct FrameResult {
  std::vector<StatRecord> stats;   ///< scopes "pass<i>.<name>/<unit>" and "frame/<unit>"
  std::vector<PassSummary> passes;
  DramTraffic dram;                ///< whole frame, per class
  FrameImages images;
  std::string final_color;         ///< name of the last stored color attachment or image buffer ("" if none)
  FrameWork work;                  ///< what the timing model schedules
};

/// Replays `trace` on `scene` with the hardware `hw`. Input problems (an unsupported kernel or
/// light source, a load of an attachment nothing stored, inconsistent sample counts, a scene
/// that does not match the trace's hash) throw InputError naming trace_path:line.
FrameResult simulate_frame(const Trace& trace, const std::string& trace_path, const Scene& scene, const HwConfig& hw);

}  // namespace tbdr
