#pragma once
// The command processor and run driver of one frame: replays a trace's commands in order through
// the units in models/ (geometry -> tiler/parameter buffer -> per tile ISP, TSP, tile memory),
// handles partial renders, and collects every unit's statistics per pass and for the frame.
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "models/compute_unit.hpp"
#include "models/pass_stats.hpp"
#include "models/frame_work.hpp"
#include "models/geometry_unit.hpp"
#include "models/hw_config.hpp"
#include "models/isp.hpp"
#include "models/render_state.hpp"
#include "models/tile_memory.hpp"
#include "models/rop.hpp"
#include "models/tiler.hpp"
#include "models/tsp.hpp"
#include "models/tile_signatures.hpp"
#include "models/work_feed.hpp"
#include "trace/traffic.hpp"
#include "kernel/stats.hpp"
#include "trace/trace.hpp"
#include "scene/scene.hpp"

namespace tbdr {

/// The frame's unit statistics: render passes and compute dispatches, each summed.
struct FrameStats {
  PassStats render;
  ComputeStats compute;
};

// The frame's shape and what was replayed (scope "frame/frame").
#define TBDR_FRAME_SHAPE_STATS(X)                                                           \
  X(Accumulator, width, "pixels", Gauge, "Frame width")                                      \
  X(Accumulator, height, "pixels", Gauge, "Frame height")                                    \
  X(Accumulator, samples_per_pixel, "samples", Gauge, "MSAA samples per pixel of the trace") \
  X(Accumulator, lights, "lights", Gauge, "Lights in the trace")                             \
  X(Counter, passes, "passes", Sum, "Render passes replayed")                                 \
  X(Counter, dispatches, "dispatches", Sum, "Compute dispatches replayed")                    \
  X(Counter, scene_triangles, "triangles", Gauge, "Triangles in the scene")                   \
  X(Counter, geometry_passes, "passes", Sum, "Submissions of the scene's opaque geometry")     \
  X(Counter, covered_pixels, "pixels", Gauge, "Pixels shaded at least once (the visible surface)")

/// The frame's size, its trace's lights and samples, and how many commands it replayed.
struct FrameShapeStats {
  TBDR_STATS(TBDR_FRAME_SHAPE_STATS)
  static constexpr const char* kScope = "frame/frame";
};

// Bytes of one traffic class, or of all (scopes "<command or frame>/dram.<class>" and ".../dram").
#define TBDR_TRAFFIC_STATS(X)                                    \
  X(Counter, read_bytes, "bytes", Sum, "Bytes the units requested to read (before the caches)") \
  X(Counter, write_bytes, "bytes", Sum, "Bytes the units requested to write (before the caches)")

/// Bytes the units requested to read and write for one traffic class (or all), before the caches.
struct TrafficStats {
  TBDR_STATS(TBDR_TRAFFIC_STATS)
  /// The scope of a command's or the frame's traffic: prefix + kScopeSuffix [+ "." + class].
  static constexpr const char* kScopeSuffix = "/dram";
};

/// The statistics of one pass or dispatch, typed (the app makes rows of them: sim/app/stat_rows.hpp).
struct CommandStats {
  std::string name;                    ///< its work's name: "pass0.gbuffer", "dispatch1.cull"
  std::optional<PassStats> pass;       ///< a pass: its units' statistics
  std::optional<ComputeStats> compute; ///< a dispatch: the compute unit's
  DramTraffic requested;               ///< the bytes it requested per class, before the caches
};

/// What one pass did, for summaries (the full figures are in FrameResult::commands).
struct PassSummary {
  std::string name;
  std::uint64_t primitives = 0;
  std::uint64_t shaded_samples = 0;
  std::uint64_t partial_renders = 0;
  DramTraffic dram;
};

/// The functional result of a frame: typed statistics, per-pixel counters, the attachment images.
struct FrameResult {
  std::vector<CommandStats> commands;  ///< each pass's and dispatch's statistics, in the order they completed
  FrameShapeStats shape;               ///< the frame's size and what was replayed
  std::vector<PassSummary> passes;
  DramTraffic dram;                ///< whole frame, per class
  FrameImages images;
  std::string final_color;         ///< name of the last stored color attachment or image buffer ("" if none)
  FrameWork work;                  ///< what the timing model schedules
  FrameStats totals;               ///< typed frame totals (the same figures as the "frame/<unit>" rows)
  /// Host wall seconds spent rendering tiles (on FrameOptions::threads threads); the rest of the
  /// functional simulation (trace replay, geometry, binning, dispatches) is serial.
  double host_tile_seconds = 0;
};

/// How a frame is simulated (host choices: none changes a statistic).
struct FrameOptions {
  /// Compute the colour images (FrameInputs::colour); false when no image is read. With it the
  /// scene must hold its colour texels (SceneLoadOptions::colour_texels).
  bool colour = true;
  /// FrameInputs::reference_loops: the ISP's general loop everywhere (tests compare it with the lean one).
  bool reference_loops = false;
  /// Threads the tiles of each render run on (models/pass_renderer.hpp); 0: the machine's
  /// (default_thread_count). Every figure and image is the same at any count.
  unsigned threads = 1;
  /// When set, the frame's work goes to this feed (models/work_feed.hpp), each command as soon as
  /// it is complete, for a timing model running meanwhile; FrameResult::work then holds only the
  /// frame's fields (WorkFeed::take gives the whole work back). The feed is closed when the
  /// simulation ends, also when it fails.
  WorkFeed* feed = nullptr;
  /// The frame's place in a sequence of frames that share one feed: the first frame begins it
  /// with `sequence_commands` commands (every frame's), the last one closes it, and each
  /// command's work carries its frame (CommandWork::frame). A single frame: 0 of 1.
  int sequence_frame = 0;
  int sequence_frames = 1;
  std::size_t sequence_commands = 0;
  /// writeback.transaction_elimination: the tile signatures of the sequence's frames so far (the
  /// frame starts a new frame of them; models/tile_signatures.hpp). Needs `colour`.
  TileSignatures* tile_signatures = nullptr;
};

/// How many commands the timing model gets from a trace: one per pass and dispatch (barriers make none).
std::size_t timed_command_count(const Trace& trace);

/// Replays `trace` on `scene` with the hardware `hw`. Input problems (an unsupported kernel or
/// light source, a load of an attachment nothing stored, inconsistent sample counts, a scene
/// that does not match the trace's hash) throw InputError naming trace_path:line.
FrameResult simulate_frame(const Trace& trace, const std::string& trace_path, const Scene& scene, const HwConfig& hw,
                           const FrameOptions& options = {});

}  // namespace tbdr
