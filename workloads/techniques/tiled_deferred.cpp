// Tiled deferred shading (Andersson 2011, "DirectX 11 rendering in Battlefield 3"; CMU 15-769
// lecture "tile-based deferred shading"): a G-buffer pass stores the surface to DRAM, then ONE
// compute dispatch per 16x16 tile computes the tile's depth bounds, culls the lights into a list in
// group-shared memory and shades every pixel of the tile once, writing the lit frame. The G-buffer
// is read once and the frame written once; light lists never leave the chip.
// Billeter's table (as clustered deferred): off-chip buffers = G-buffers; 1 geometry pass;
// overshading no; MSAA no; blending no (here: a forward pass over the lit frame, as engines do).
//
// Pass `gbuffer`: option `gbuffer` targets (default Andersson's 4 x rgba8) + depth d24s8, stored.
// barrier; dispatch tiled_deferred_shade groups = ceil(W/16) x ceil(H/16), 16x16 threads, reads the
//   G-buffer, depth and lights, writes buffer `color` (the lit frame, content=image, W x H x 4 B).
// Shader `tiled_deferred_lit` (the per-pixel cost the kernel charges): decode 4 (+1 per extra
//   target) + position reconstruction 8 + ambient 3 + output 5 ALU, one fetch per G-buffer target
//   + 1 for depth, light_source=tile_list (the group-shared list), 12 ALU per light. The tile is
//   the workgroup's: no lookup cost.
// translucent=forward (default): barrier on `color`; pass `translucent` loads the lit frame `color`
//   as its rgba8 color attachment (and stores it) over the G-buffer pass's depth (loaded, test less,
//   no write) and draws the BLEND geometry alpha-blended, lit from per-object light lists.
#include "techniques/technique.hpp"

namespace tbdr {

namespace {

Trace generate_tiled_deferred(const TraceSetup& setup, const TechniqueOptions& options) {
  ComputeDeferred c = begin_compute_deferred(setup, "tiled_deferred", options);
  const auto tile_px = static_cast<std::uint32_t>(options.get_int("tile_px", 4, 256));
  const std::uint32_t cap = list_cap_option(options, "max_lights_per_tile", c.trace.lights.size());

  const ShadedGbuffer g = add_compute_gbuffer(c.trace, setup, c.layout, "tiled_deferred_lit", 0, LightSource::TileList);
  return finish_compute_deferred(c, g, setup, options, ComputeKernel::TiledDeferredShade, "tiled_deferred_lit", tile_px,
                                 {}, {{"max_lights_per_tile", std::to_string(cap)}});
}

}  // namespace

TechniqueInfo technique_tiled_deferred() {
  return {"tiled_deferred",
          "G-buffer to DRAM, then one compute dispatch per 16x16 tile: depth bounds, light culling in group "
          "memory, shading (Andersson 2011, Battlefield 3)",
          {{"gbuffer", "rgba8,rgba8,rgba8,rgba8",
            "G-buffer color targets: albedo, normal, extras; default Andersson's 4 x RGBA8 (+ D24S8 = 20 B/px, "
            "per CMU 15-769 and Andersson 2011, Battlefield 3)"},
           {"tile_px", "16", "screen tile edge in pixels of one workgroup (Andersson: 16x16 tiles)"},
           {"max_lights_per_tile", "all",
            "capacity of the group-shared light list (Andersson's MAX_LIGHTS); all = the light count, so no "
            "tile can overflow and the image stays exact"},
           translucent_pass_declaration()},
          &generate_tiled_deferred};
}

}  // namespace tbdr
