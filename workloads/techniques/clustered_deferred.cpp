// Clustered deferred shading (Olsson, Billeter & Assarsson 2012), as the thesis chapter in
// reference/ implements it: a G-buffer pass, then three compute dispatches: clustering (flag the
// clusters that hold a visible sample, compacted into a list of used clusters), light assignment
// (every light against every used cluster) and shading (one pixel per invocation, looping over its
// cluster's list).
// Billeter's table: off-chip buffers = G-buffers; 1 geometry pass; overshading no; MSAA no;
// blending no (here: a forward pass over the lit frame, as engines do).
//
// Pass `gbuffer`: option `gbuffer` targets (albedo rgba8 + normal rgb10a2) + depth d24s8, stored.
// barrier; dispatch cluster_flag (tiles_x x tiles_y groups, one per tile as in the thesis; reads
//   depth, writes used_clusters); barrier; dispatch cluster_light_assign (one group per cluster of
//   the grid, 64 threads over the lights; reads lights + used_clusters, writes cluster_grid +
//   light_index); barrier; dispatch deferred_shade (16x16 pixel groups, one pixel per thread; reads
//   the G-buffer, depth, lights and the lists; writes buffer `color`, the lit frame).
// Buffers: used_clusters 4 + 4 B x clusters; cluster_grid 8 B (offset, count) x clusters;
//   light_index clusters x max_lights_per_cluster x index_bytes; clusters = ceil(W/tile_px) x
//   ceil(H/tile_px) x slices.
// Shader `clustered_deferred_lit` (the per-pixel cost of deferred_shade): decode 4 (+1 per extra
//   target) + position reconstruction 8 + cluster lookup 6 + ambient 3 + output 5 ALU, one fetch per
//   G-buffer target + 1 for depth, light_source=cluster_list, 12 ALU per light.
// translucent=forward (default): barrier on `color`, then pass `translucent` drawing the BLEND
//   geometry over the lit frame and the G-buffer depth (as tiled_deferred.cpp).
#include "techniques/technique.hpp"

namespace tbdr {

namespace {

Trace generate_clustered_deferred(const TraceSetup& setup, const TechniqueOptions& options) {
  ComputeDeferred c = begin_compute_deferred(setup, "clustered_deferred", options);
  const LightGrid grid = light_grid_option(setup, options, GridOptions::LogClusters);

  const std::string used = add_used_clusters_buffer(c.trace, grid);
  add_light_grid_buffers(c.trace, grid);
  const ShadedGbuffer g = add_compute_gbuffer(c.trace, setup, c.layout, "clustered_deferred_lit", kClusterLookupAluOps,
                                              LightSource::ClusterList);
  add_sparse_cluster_assignment(c.trace, grid, c.lights, used);
  c.trace.commands.emplace_back(make_barrier({grid.grid_buffer(), kLightIndexBuffer}));
  return finish_compute_deferred(c, g, setup, options, ComputeKernel::DeferredShade, "clustered_deferred_lit",
                                 kKernelGroupEdge, {grid.grid_buffer(), kLightIndexBuffer});
}

}  // namespace

TechniqueInfo technique_clustered_deferred() {
  return {"clustered_deferred",
          "G-buffer, then cluster flagging, light assignment over used clusters and a shading dispatch "
          "(Olsson et al. 2012; the reference thesis chapter)",
          {{"gbuffer", "rgba8,rgb10a2",
            "G-buffer color targets: albedo, normal, extras (the thesis: depth, normal and albedo buffers)"},
           {"tile_px", "128", "cluster screen tile edge in pixels (the thesis chapter: 128 px tiles)"},
           {"slices", "16", "exponential depth slices between near and far (the thesis chapter: 16)"},
           {"max_lights_per_cluster", "all",
            "light index list capacity per cluster, sizes light_index (the thesis: 64 lights per partition, "
            "1 KB per cluster); all = the light count, so no list can overflow"},
           {"index_bytes", "auto",
            "bytes per light index: 1, 2, 4 or auto (smallest that addresses every light; the thesis uses 8-bit "
            "indices)"},
           translucent_pass_declaration()},
          &generate_clustered_deferred};
}

}  // namespace tbdr
