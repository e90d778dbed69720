#pragma once
// The refusals of a trace that depend on the configuration it runs on, made once when the trace is
// bound to the configuration (the start of simulate_frame), before any command is simulated: a
// trace that a pass or dispatch late in the frame cannot run on this GPU is refused without the
// work of the commands before it (issue 16: every bad input refused before work starts).
#include <string>

#include "models/hw_config.hpp"
#include "trace/trace.hpp"

namespace tbdr {

/// Refuses (InputError at `trace_path`:line, naming the pass or attachment) a trace that this
/// configuration cannot run:
/// - a pass whose pixel local storage exceeds pls.max_pls_bytes_per_pixel (check_pls_layout);
/// - a pass with pixel local storage on an immediate-mode GPU (gpu.mode=imr has no tile memory);
/// - a frame or attachment sample count whose standard positions the rasterizer's sub-pixel grid
///   (geometry.subpixel_bits) cannot hold (standard_sample_pattern).
void check_trace_on_hardware(const Trace& trace, const HwConfig& hw, const std::string& trace_path);

}  // namespace tbdr
