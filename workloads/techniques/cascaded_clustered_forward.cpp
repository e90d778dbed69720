// Cascaded clustered forward shading (Billeter 2015, "Custom Practical Clustered Forward"): a
// practical (dense, assigned up front) clustered forward renderer whose clusters are near-cubical
// with an NxN pixel footprint and a minimum size near the camera, so their number stays even along
// the frustum; with a PreZ pass ("With PreZ", his measurements). Nothing but color leaves the chip.
// Billeter's table (as practical clustered forward with PreZ): off-chip buffers = color; 2 geometry
// passes; overshading no; MSAA yes; blending yes.
//
// The cluster grid uses docs/kernels.md `slicing=cubical`: screen tiles of `tile_px` (N) pixels,
// slice k+1 starting at z_k (1 + 2 tan(fov_y/2) N / H) from `min_depth` (the first slice covers
// [near, min_depth]: the minimum cluster size), as many slices as reach the far plane (at most
// `slices`). Billeter's 12 cascades with a resolution each have no counterpart in the kernel
// contract: the cubical grid is their limit of one slice per cascade at the full N px resolution
// (docs/techniques.md).
// dispatch cluster_light_assign dense=yes slicing=cubical (dense=no: a stored depth pre-pass,
//   cluster_flag and assignment over the used clusters, as clustered_forward); barrier; pass `main`
//   (as practical_clustered_forward): PreZ, lit draws with light_source=cluster_list (20 + 6 ALU,
//   2 fetches, 8 varyings, 12 per light), BLEND geometry with the same lists.
#include "kernel/errors.hpp"
#include "techniques/technique.hpp"

namespace tbdr {

namespace {

Trace generate_cascaded_clustered_forward(const TraceSetup& setup, const TechniqueOptions& options) {
  using Kind = LightGridConfig::Kind;
  const LightGridConfig c{.technique = "cascaded_clustered_forward",
                          .kind = options.get_bool("dense") ? Kind::DenseClusters : Kind::SparseClusters,
                          .grid = light_grid_option(setup, options, GridOptions::CubicalClusters),
                          .prez = options.get_bool("prez")};
  if (c.kind == Kind::SparseClusters && !c.prez)
    throw InputError("option prez=no", "cascaded_clustered_forward with dense=no needs its stored depth pre-pass");
  return generate_light_grid_forward(setup, options, c);
}

}  // namespace

TechniqueInfo technique_cascaded_clustered_forward() {
  return {"cascaded_clustered_forward",
          "near-cubical NxN px clusters with a minimum size, assigned up front, PreZ + one forward pass "
          "(Billeter 2015, cascaded clustering)",
          {{"tile_px", "64",
            "cluster footprint N in pixels (Billeter: near-cubical clusters with an NxN px footprint; the talk "
            "gives no N: 64 as practical_clustered_forward's tiles)"},
           {"min_depth", "auto",
            "view distance where the first cubical slice starts, world units: the minimum cluster size "
            "(Billeter); auto = 10 x near (at most far/2)"},
           {"slices", "auto",
            "maximum number of cubical depth slices; auto = as many as reach the far plane (Billeter uses 12 "
            "cascades, each subdivided; the kernel's cubical slicing has one slice per cascade)"},
           {"max_lights_per_cluster", "all",
            "light index list capacity per cluster, sizes light_index (Billeter: 3.5 lights on average, worst "
            "20, at 192 lights); all = the light count"},
           {"index_bytes", "auto", "bytes per light index: 1, 2, 4 or auto (smallest that addresses every light)"},
           {"prez", "yes", "depth-only pre-pass in the same render pass, lit draws test equal (Billeter: 'With PreZ')"},
           {"dense", "yes",
            "assign every cluster up front (Billeter builds on Persson's dense grid); no: stored depth pre-pass, "
            "cluster_flag and assignment over the used clusters (Olsson)"}},
          &generate_cascaded_clustered_forward};
}

}  // namespace tbdr
