// Practical clustered forward shading (Persson 2013/2015, "Practical Clustered Shading", Just
// Cause 3; Billeter 2015 "Practical Clustered Forward"): the lights are assigned up front into a
// dense cluster grid covering the whole view frustum, independent of the geometry, so one forward
// geometry pass (optionally after a PreZ pass in the same render pass) shades every surface,
// translucent ones included, from its cluster's list. Nothing but color leaves the chip.
// Billeter's table: off-chip buffers = color; 1 geometry pass (2 with PreZ); overshading yes
// (no with PreZ); MSAA yes; blending yes.
//
// Persson assigns on the CPU; docs/kernels.md requires a dispatch to compute the lists, so a
// `cluster_light_assign dense=yes` dispatch (reads lights, writes cluster_grid + light_index,
// marked upload=no) stands for that CPU job: its result is the lists an application would upload.
// barrier; pass `main`: color rgba8 (MSAA resolved on chip), depth d24s8 transient;
//   prez=yes: depth-only opaque + masked, then the lit draws test equal; opaque + masked with
//   `forward_lit` (light_source=cluster_list; 20 + 6 ALU, 2 fetches, 8 varyings, 12 per light);
//   BLEND geometry with the same shader and alpha blending (the dense grid covers it).
// Buffers: cluster_grid 8 B x clusters, light_index clusters x max_lights_per_cluster x
//   index_bytes; clusters = ceil(W/tile_px) x ceil(H/tile_px) x slices.
#include "techniques/technique.hpp"

namespace tbdr {

namespace {

Trace generate_practical_clustered_forward(const TraceSetup& setup, const TechniqueOptions& options) {
  return generate_light_grid_forward(setup, options,
                                     {.technique = "practical_clustered_forward",
                                      .kind = LightGridConfig::Kind::DenseClusters,
                                      .grid = light_grid_option(setup, options, GridOptions::LogClusters),
                                      .prez = options.get_bool("prez")});
}

}  // namespace

TechniqueInfo technique_practical_clustered_forward() {
  return {"practical_clustered_forward",
          "dense cluster grid assigned up front, one forward geometry pass (optional PreZ); color only leaves "
          "the chip (Persson 2013; Billeter 2015)",
          {{"tile_px", "64",
            "cluster screen tile edge in pixels (Persson's Just Cause 3 grid: 64x64 px; not in reference/)"},
           {"slices", "16", "exponential depth slices between near and far (Persson: 16)"},
           {"max_lights_per_cluster", "all",
            "light index list capacity per cluster, sizes light_index; all = the light count, so no list can "
            "overflow"},
           {"index_bytes", "auto", "bytes per light index: 1, 2, 4 or auto (smallest that addresses every light)"},
           {"prez", "no",
            "depth-only pre-pass in the same render pass, lit draws test equal (Billeter: 2 geometry passes, no "
            "overshading; Persson: no pre-pass needed)"}},
          &generate_practical_clustered_forward};
}

}  // namespace tbdr
