#pragma once
// Compute dispatches on the USCs, functionally real: the named kernels of docs/kernels.md (depth
// bounds, tile light culling, cluster flagging and light assignment, deferred shading, visibility
// buffer work lists and shading) compute their outputs from the frame's images and the lights,
// and are charged like draws: ALU operations, texture/buffer reads and writes per DRAM class.
// A shading kernel's fetches beyond one per image it reads sample the surface's material textures:
// their lines are computed per 2x2 quad as the TSP computes a fragment quad's (SurfacePoint::quad_uv).
#include <cstdint>
#include <string>
#include <vector>

#include "models/hw_config.hpp"
#include "models/light_lists.hpp"
#include "models/render_state.hpp"
#include "models/texture_unit.hpp"
#include "trace/traffic.hpp"
#include "kernel/stats.hpp"
#include "kernel/thread_pool.hpp"
#include "trace/trace.hpp"

namespace tbdr {

// Declared once: X(type, member = stored name, unit, Sum | Gauge, description).
#define TBDR_COMPUTE_STATS(X) \
  X(Counter, dispatches, "dispatches", Sum, "Compute dispatches run") \
  X(Counter, workgroups, "workgroups", Sum, "Workgroups launched") \
  X(Counter, threads, "threads", Sum, "Threads launched") \
  X(Counter, compute_alu_ops, "ops", Sum, "ALU operations of compute kernels") \
  X(Counter, light_volume_tests, "tests", Sum, "Light sphere against tile/cluster volume tests") \
  X(Counter, light_list_entries, "entries", Sum, "Light indices written into tile or cluster lists") \
  X(Counter, clusters_used, "clusters", Sum, "Clusters flagged as holding visible samples") \
  X(Counter, light_list_overflows, "tiles", Sum, "Tiles whose list exceeded the format's cap") \
  X(Counter, compute_shaded_pixels, "pixels", Sum, "Pixels shaded by compute kernels") \
  X(Counter, compute_light_evaluations, "evaluations", Sum, "Lights evaluated by compute shading") \
  X(Counter, compute_texture_fetches, "fetches", Sum, "Texture fetches of compute shading") \
  X(Counter, compute_texture_line_accesses, "lines", Sum, "Texture cache line accesses of compute shading's material fetches: distinct lines per quad and fetch") \
  X(Counter, compute_texture_tile_lines, "lines", Sum, "Distinct texture lines each workgroup tile's material fetches touched (its footprint), summed over tiles") \
  X(Counter, work_list_entries, "entries", Sum, "Per-material tile work list entries") \
  X(Counter, refetched_vertices, "vertices", Sum, "Vertices re-fetched by visibility-buffer shading")
/// Statistics of compute dispatches.
struct ComputeStats {
  TBDR_STATS(TBDR_COMPUTE_STATS)
};

/// What a dispatch needs from the frame around it: the frame's inputs, the trace (for errors
/// naming its lines) and the frame's images, which kernels read and write.
struct ComputeContext : FrameInputs {
  const Trace* trace = nullptr;
  const std::string* trace_path = nullptr;
  FrameImages* images = nullptr;
  /// The frame's texture address space and where the material fetches' lines go (each
  /// workgroup tile's footprint, sorted and distinct, appended in dispatch order); either null:
  /// no addresses.
  const TextureLayout* textures = nullptr;
  std::vector<std::uint64_t>* texture_lines = nullptr;
  /// Threads the per-pixel shading kernels run their bands of rows on (null: the caller's
  /// thread); the figures are the same at any count (bands are merged in row order).
  ThreadPool* pool = nullptr;
};

/// Runs one dispatch; InputError (trace:line) for an unknown kernel, a bad parameter or a
/// missing input.
void run_dispatch(const ComputeContext& ctx, const DispatchCmd& cmd, ComputeStats& stats, DramTraffic& dram,
                  std::string& image_written);

}  // namespace tbdr
