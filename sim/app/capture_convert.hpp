#pragma once
// The capture intermediate of `tbdrsim import` as a trace: a frame of a real application,
// captured with RenderDoc (docs/capture-import.md). A RenderDoc capture (.rdc) is first exported
// by scripts/capture/rdc_export.py into the capture intermediate (frame.json beside the textures
// it names); convert_capture() turns that intermediate into a Trace and a GLB file holding each
// draw's post-vertex-shader clip positions (glTF attribute _CLIP_POSITION), which the trace names
// by its content hash and the simulator reads back through the validated glTF loader.
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "trace/trace.hpp"

namespace tbdr {

/// What one import produced: the trace, the GLB bytes it names, and the summary lines (counts and
/// every capture feature that was approximated or dropped, never silently).
struct CaptureImport {
  Trace trace;
  std::vector<std::uint8_t> glb;
  std::vector<std::string> summary;      ///< one line each: counts, shader cost source, ...
  std::vector<std::string> unsupported;  ///< one line each: what the trace does not carry, by event
  std::uint64_t draws = 0;
  std::uint64_t passes = 0;
  std::uint64_t triangles = 0;
  std::uint64_t transfers = 0;   ///< blits, copies, resolves, clears and fills, as transfer dispatches
  std::uint64_t dispatches = 0;  ///< the application's compute dispatches, as captured_compute
};

/// Converts a capture intermediate (frame.json; the textures it names are read from its folder)
/// into a trace whose scene line names `glb_name` (a path relative to the trace's folder). Throws
/// InputError naming the file and the event (draw, pass) at fault; writes nothing.
CaptureImport convert_capture(const std::string& frame_json_path, const std::string& glb_name);

/// A sequence of captured frames as one import: each frame's trace and summary, and the one GLB
/// every frame's scene line names (their geometry side by side, each frame's names prefixed f<k>_).
struct CaptureSequence {
  std::vector<CaptureImport> frames;
  std::vector<std::uint8_t> glb;
};

/// Converts the intermediates of consecutive frames, in order, into the frames of one sequence
/// (trace version 4): one scene, each frame's passes, transfers and dispatches. The frames must
/// share one size (InputError naming the intermediate otherwise).
CaptureSequence convert_captures(const std::vector<std::string>& frame_json_paths, const std::string& glb_name);

/// Refuses a file that is not a PNG by its 8-byte signature, before anything decodes it:
/// InputError naming the file, `what`, and its first bytes.
void check_png_file(const std::filesystem::path& p, const std::string& what);

}  // namespace tbdr
