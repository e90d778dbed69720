// Clustered forward shading (Olsson, Billeter & Assarsson 2012; Billeter 2015 "Clustered Forward"):
// a depth-only pre-pass stored to DRAM, a clustering kernel that flags the clusters holding visible
// samples into a compact used list, light assignment against the used clusters, and a forward pass
// in which each fragment finds its cluster and loops over its list.
// Billeter's table: off-chip buffers = depth; 2 geometry passes; overshading PreZ (no: depth
// reloaded, equal test); MSAA yes*; blending yes* (translucent surfaces are not in the pre-pass
// depth, so their clusters may be unflagged: they take per-object light lists).
//
// Pass `prepass`: depth d24s8 (S samples; clear, store); depth-only opaque + masked.
// barrier; dispatch cluster_flag (one group per tile; reads depth, writes used_clusters); barrier;
//   dispatch cluster_light_assign dense=no (one group per cluster, 64 threads over the lights;
//   reads lights + used_clusters, writes cluster_grid + light_index); barrier.
// Pass `forward`: color rgba8 (MSAA resolved on chip), depth (reload: load, equal); opaque + masked
//   with `forward_lit` (light_source=cluster_list; 20 + 6 cluster lookup ALU, 2 fetches, 8 varyings,
//   12 per light); BLEND geometry with per-object lists.
// Buffers: used_clusters 4 + 4 B x clusters, cluster_grid 8 B x clusters, light_index clusters x
//   max_lights_per_cluster x index_bytes; clusters = ceil(W/tile_px) x ceil(H/tile_px) x slices.
#include "techniques/technique.hpp"

namespace tbdr {

namespace {

Trace generate_clustered_forward(const TraceSetup& setup, const TechniqueOptions& options) {
  return generate_light_grid_forward(setup, options,
                                     {.technique = "clustered_forward",
                                      .kind = LightGridConfig::Kind::SparseClusters,
                                      .grid = light_grid_option(setup, options, GridOptions::LogClusters),
                                      .depth_reload = options.get_bool("depth_reload")});
}

}  // namespace

TechniqueInfo technique_clustered_forward() {
  return {"clustered_forward",
          "depth pre-pass stored, cluster flagging, light assignment over used clusters, forward pass over "
          "the cluster lists (Olsson et al. 2012)",
          {{"tile_px", "128", "cluster screen tile edge in pixels (the reference thesis chapter: 128 px tiles)"},
           {"slices", "16", "exponential depth slices between near and far (the thesis chapter: 16)"},
           {"max_lights_per_cluster", "all",
            "light index list capacity per cluster, sizes light_index (the thesis: 64 per partition); all = the "
            "light count, so no list can overflow"},
           {"index_bytes", "auto",
            "bytes per light index: 1, 2, 4 or auto (smallest that addresses every light; the thesis uses 8-bit "
            "indices)"},
           {"depth_reload", "yes",
            "forward pass loads the pre-pass depth and tests equal (Billeter: reuse PreZ to avoid overshading, at "
            "the cost of copying depth back on chip); no: fresh transient depth, less"}},
          &generate_clustered_forward};
}

}  // namespace tbdr
