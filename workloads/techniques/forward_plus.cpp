// Forward+ / tiled forward shading (Harada, McKee & Yang 2012; CMU 15-769 lecture "Forward+"):
// a depth pre-pass, a compute kernel that culls the lights per 16x16 screen tile against the tile's
// depth bounds into a light index list with a per-tile offset and count in memory, then a forward
// pass in which each fragment loops over its tile's list.
// Billeter's table (as "Clust. Fwd.", tiled variant): off-chip buffers = depth (the kernel reads it
// as a texture); 2 geometry passes; overshading no (PreZ; depth reloaded, equal test); MSAA yes*;
// blending yes* (translucent surfaces are not in the pre-pass depth, so they take per-object lists).
//
// Pass `prepass`: depth d24s8 (S samples; clear, store); depth-only opaque + masked (alpha test).
// barrier depth; dispatch tile_light_cull groups = ceil(W/16) x ceil(H/16), 16x16 threads,
//   reads depth + lights, writes tile_grid (8 B per tile) and light_index (tiles x
//   max_lights_per_tile x index_bytes); barrier.
// Pass `forward`: color rgba8 (MSAA: transient multisampled color resolved on chip), depth
//   (depth_reload=yes: load, equal test, no write; no: transient, cleared, less); opaque + masked
//   with `forward_lit` (light_source=tile_list; 20 + 3 tile lookup ALU, 2 fetches, 8 varyings,
//   12 per light), then BLEND geometry with per-object lists and alpha blending.
#include "techniques/technique.hpp"

namespace tbdr {

namespace {

Trace generate_forward_plus(const TraceSetup& setup, const TechniqueOptions& options) {
  return generate_light_grid_forward(setup, options,
                                     {.technique = "forward_plus",
                                      .kind = LightGridConfig::Kind::Tiles,
                                      .grid = light_grid_option(setup, options, GridOptions::Tiles),
                                      .depth_reload = options.get_bool("depth_reload")});
}

}  // namespace

TechniqueInfo technique_forward_plus() {
  return {"forward_plus",
          "depth pre-pass stored, per-tile light culling kernel, forward pass over the tile lists "
          "(Harada et al. 2012, Forward+)",
          {{"tile_px", "16", "screen tile edge in pixels (Harada 2012 and the 15-769 lecture: 16x16 tiles)"},
           {"max_lights_per_tile", "all",
            "light index list capacity per tile, sizes light_index and is the kernel's cap; all = the light "
            "count, so no list can overflow"},
           {"index_bytes", "4", "bytes per light index: 1, 2, 4 or auto (Harada's list stores 32-bit indices)"},
           {"depth_reload", "yes",
            "forward pass loads the pre-pass depth and shades with depth_compare=equal (Harada); no: a fresh "
            "transient depth tested less (a TBDR's HSR removes overshading without the reload)"}},
          &generate_forward_plus};
}

}  // namespace tbdr
