// The visibility buffer (Burns & Hunt 2013, "The Visibility Buffer: A Cache-Friendly Approach to
// Deferred Shading"): a visibility pass stores only a 4-byte triangle + instance id per sample (8
// with tessellation or huge scenes) and depth; a kernel builds per-material work lists of the tiles
// that need shading; the shading kernel re-fetches each visible triangle's vertices, re-runs the
// vertex work, interpolates the surface and shades it with the tile's light list (Burns & Hunt use
// pre-culled per-tile light lists: here a `tile_light_cull` dispatch builds them).
// Billeter's table (not listed; by the same criteria): off-chip buffers = visibility ids + depth;
// 1 geometry pass; overshading no; MSAA yes (ids per sample, shading per unique id); blending no
// (Burns & Hunt do not handle it; here: a forward pass over the lit frame at 1 sample, as engines do).
//
// Pass `visibility`: visibility r32ui (id_bytes=8: rg32ui) and depth d24s8, S samples, cleared and
//   stored; opaque + masked with `visibility_id` (pack ids: 2 ALU, no fetch, no varying; masked:
//   +1 ALU alpha test, 1 fetch, 2 varyings (uv), discard).
// barrier; dispatch vbuffer_worklists (tiles of tile_px, reads visibility, writes work_lists);
//   dispatch tile_light_cull (reads depth + lights, writes tile_grid + light_index); barrier;
//   dispatch vbuffer_shade (reads visibility, work_lists, lights, tile_grid, light_index; writes
//   buffer `color`, the lit frame).
// Buffers: work_lists = tiles x materials x 12 B (8-byte tile/material pairs, then 4-byte tile ids
//   sorted by material) + 8 B per material (offset, count); tile_grid 8 B per tile; light_index
//   tiles x max_lights_per_tile x index_bytes.
// Shader `vbuffer_lit` (vbuffer_shade's per-sample cost): reconstruction 120 + surface 12 +
//   ambient 3 + output 5 ALU, 2 material fetches + 1 id fetch, light_source=tile_list, 12 per
//   light; the tile is the workgroup's: no lookup. The vertex re-fetch is DRAM traffic the kernel books.
// translucent=forward (default, 1 sample): barrier on `color`, then pass `translucent` drawing the
//   BLEND geometry over the lit frame and the visibility pass's depth (as tiled_deferred.cpp).
#include <algorithm>

#include "kernel/errors.hpp"
#include "techniques/technique.hpp"

namespace tbdr {

namespace {

Trace generate_visibility_buffer(const TraceSetup& setup, const TechniqueOptions& options) {
  Trace t = begin_trace(setup, "visibility_buffer", options, {.needs_lights = true});
  const std::string lights = add_light_buffer(t);
  const std::int64_t id_bytes = options.get_int("id_bytes", 4, 8);
  if (id_bytes != 4 && id_bytes != 8)
    throw InputError("option id_bytes=" + options.get("id_bytes"), "visibility ids are 4 (r32ui) or 8 (rg32ui) bytes");
  const LightGrid grid = light_grid_option(setup, options, GridOptions::Tiles);
  const auto samples = static_cast<std::uint32_t>(setup.samples);

  const std::uint64_t materials = std::max<std::size_t>(1, scene_material_count(setup));
  const std::string work = add_buffer(t, "work_lists", grid.cells() * materials * 12 + materials * 8,
                                      DramClass::WorkLists, BufferContent::WorkLists);
  add_light_grid_buffers(t, grid);
  const std::string frame = add_frame_buffer(t, setup);

  PassDesc pass;
  pass.name = "visibility";
  pass.attachments.push_back(make_attachment("visibility", id_bytes == 8 ? Format::Rg32ui : Format::R32ui, samples,
                                             LoadOp::Clear, StoreOp::Store, AttachmentUsage::Visibility));
  pass.attachments.push_back(depth_attachment(samples, LoadOp::Clear, StoreOp::Store));
  const ShaderDesc id = make_shader("visibility_id", kVisibilityIdAluOps, 0, 0, 0, LightSource::None, 1);
  add_scene_shading(t, pass, "visibility", id, masked_variant(id, 1, kUvVaryings));
  t.shaders.push_back(make_shader("vbuffer_lit",
                                  kVisibilityReconstructAluOps + kSurfaceAluOps + kAmbientAluOps + kOutputAluOps,
                                  kSurfaceTexFetches + 1, 0, kLightAluOps, LightSource::TileList, 1));

  const std::uint32_t edge = grid.group_edge();
  t.commands.emplace_back(std::move(pass));
  t.commands.emplace_back(make_barrier({"visibility", "depth"}));
  t.commands.emplace_back(make_dispatch(ComputeKernel::VbufferWorklists, grid.tiles_x(), grid.tiles_y(), 1, edge, edge, 1,
                                        {"visibility"}, {work}, {{"tile_px", std::to_string(grid.tile_px)}}));
  t.commands.emplace_back(tile_light_cull_dispatch(grid, lights));
  t.commands.emplace_back(make_barrier({work, grid.grid_buffer(), kLightIndexBuffer}));
  t.commands.emplace_back(shading_dispatch(ComputeKernel::VbufferShade, "vbuffer_lit", setup, grid.tile_px,
                                           {"visibility", work, lights, grid.grid_buffer(), kLightIndexBuffer}, frame));
  add_translucent_pass(t, setup, options, frame, lights);
  return t;
}

}  // namespace

TechniqueInfo technique_visibility_buffer() {
  return {"visibility_buffer",
          "visibility pass storing triangle+instance ids and depth, per-material tile work lists, tile light "
          "culling, a shading dispatch that rebuilds the surface (Burns & Hunt 2013)",
          {{"id_bytes", "4",
            "bytes of the triangle + instance id per sample: 4 (r32ui) or 8 (rg32ui, tessellation or huge "
            "scenes) (Burns & Hunt 2013)"},
           {"tile_px", "16",
            "work-list, light-culling and shading tile edge in pixels; Burns & Hunt use 16x8 tiles, the kernels "
            "take square tiles: 16"},
           {"max_lights_per_tile", "all",
            "light index list capacity per tile, sizes light_index and is the kernel's cap; all = the light "
            "count, so no list can overflow"},
           {"index_bytes", "4", "bytes per light index: 1, 2, 4 or auto (32-bit indices as forward_plus)"},
           translucent_pass_declaration()},
          &generate_visibility_buffer};
}

}  // namespace tbdr
