#include "models/hardware_checks.hpp"

#include <stdexcept>
#include <variant>

#include "kernel/errors.hpp"
#include "models/rasterizer.hpp"
#include "models/tile_memory.hpp"

namespace tbdr {

namespace {

/// The rasterizer places `samples` standard positions on its sub-pixel grid, or the line is refused.
void check_sample_positions(int samples, const HwConfig& hw, const std::string& trace_path, int line,
                            const std::string& what) {
  try {
    (void)standard_sample_pattern(samples, static_cast<int>(hw.geometry.subpixel_bits));
  } catch (const std::invalid_argument& e) {
    throw InputError(trace_path, line, what + ": " + e.what() + " (geometry.subpixel_bits)");
  }
}

}  // namespace

void check_trace_on_hardware(const Trace& trace, const HwConfig& hw, const std::string& trace_path) {
  check_sample_positions(trace.frame.samples, hw, trace_path, trace.frame.line, "frame");
  for (const auto& cmd : trace.commands) {
    const auto* pass = std::get_if<PassDesc>(&cmd);
    if (!pass) continue;
    check_pls_layout(hw.pls, *pass, trace_path);
    if (hw.gpu.mode == GpuMode::Imr && !pass->pls.empty()) {
      // EXT_shader_pixel_local_storage keeps per-pixel data in tile memory for the life of a
      // pass: an immediate-mode GPU has none to offer, so the extension is not there.
      throw InputError(trace_path, pass->line,
                       "pass '" + pass->name + "' declares pixel local storage, which an immediate-mode GPU "
                       "(gpu.mode=imr) does not have: run it with gpu.mode=tbdr or tbr, or use a technique without PLS");
    }
    for (const Attachment& a : pass->attachments) {
      if (!pass->is_resolve_target(a)) {
        check_sample_positions(static_cast<int>(a.samples), hw, trace_path, a.line,
                               "pass '" + pass->name + "', attachment '" + a.name + "'");
      }
    }
  }
}

}  // namespace tbdr
