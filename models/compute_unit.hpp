#pragma once
// Compute dispatches on the USCs, functionally real: the named kernels of docs/kernels.md (depth
// bounds, tile light culling, cluster flagging and light assignment, deferred shading, visibility
// buffer work lists and shading) compute their outputs from the frame's images and the lights,
// and are charged like draws: ALU operations, texture/buffer reads and writes per DRAM class.
#include <cstdint>
#include <string>
#include <vector>

#include "models/hw_config.hpp"
#include "models/light_lists.hpp"
#include "models/render_state.hpp"
#include "models/traffic.hpp"
#include "kernel/stats.hpp"
#include "trace/trace.hpp"

namespace tbdr {

/// Statistics of compute dispatches.
struct ComputeStats {
  StatGroup group;
  Counter dispatches{group, {"dispatches", "dispatches", "Compute dispatches run"}};
  Counter workgroups{group, {"workgroups", "workgroups", "Workgroups launched"}};
  Counter threads{group, {"threads", "threads", "Threads launched"}};
  Counter alu_ops{group, {"compute_alu_ops", "ops", "ALU operations of compute kernels"}};
  Counter light_volume_tests{group, {"light_volume_tests", "tests", "Light sphere against tile/cluster volume tests"}};
  Counter list_entries{group, {"light_list_entries", "entries", "Light indices written into tile or cluster lists"}};
  Counter clusters_used{group, {"clusters_used", "clusters", "Clusters flagged as holding visible samples"}};
  Counter list_overflows{group, {"light_list_overflows", "tiles", "Tiles whose list exceeded the format's cap"}};
  Counter shaded_pixels{group, {"compute_shaded_pixels", "pixels", "Pixels shaded by compute kernels"}};
  Counter light_evaluations{group, {"compute_light_evaluations", "evaluations", "Lights evaluated by compute shading"}};
  Counter texture_fetches{group, {"compute_texture_fetches", "fetches", "Texture fetches of compute shading"}};
  Counter work_list_entries{group, {"work_list_entries", "entries", "Per-material tile work list entries"}};
  Counter refetched_vertices{group, {"refetched_vertices", "vertices", "Vertices re-fetched by visibility-buffer shading"}};
  explicit ComputeStats(std::string scope) : group(std::move(scope)) {}
};

/// What a dispatch needs from the frame around it.
struct ComputeContext {
  const HwConfig* hw = nullptr;
  const Trace* trace = nullptr;
  const std::string* trace_path = nullptr;
  const Scene* scene = nullptr;
  FrameImages* images = nullptr;
  ViewFrustum frustum;
  CameraXform camera;
  Viewport viewport;
  int light_tile_px = 32;  ///< the screen-tile light candidates (exact acceleration of `all`)
  int light_tiles_x = 0;
  const std::vector<std::vector<std::uint32_t>>* light_tiles = nullptr;
};

/// Runs one dispatch; InputError (trace:line) for an unknown kernel, a bad parameter or a
/// missing input.
void run_dispatch(const ComputeContext& ctx, const DispatchCmd& cmd, ComputeStats& stats, DramTraffic& dram,
                  std::string& image_written);

/// The kernels the simulator implements, for error messages and docs.
const std::vector<std::string>& kernel_names();

}  // namespace tbdr
