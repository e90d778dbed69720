// The compute unit on its own: kernels of docs/kernels.md on a 64x64 frame seen by a camera at the
// origin looking down -z (60 degree field of view), lights placed to project onto chosen pixels,
// with list entries, volume tests, ALU ops and buffer bytes derived by hand. Kernel constants:
// 24 ALU ops per light volume test, 2 per depth sample reduced, 8 B per grid entry, 4 B per light
// index.
#include <gtest/gtest.h>

#include <string>
#include <utility>
#include <vector>

#include "unit_fixture.hpp"

namespace tbdr {
namespace {

using namespace unit;

constexpr std::uint64_t kPixels = 64 * 64;

/// Four lights at view distance 10 (radius 0.5: about 2.8 pixels on screen):
///   0 centred on pixel (16, 16): inside tile (0, 0) of a 32 px grid only;
///   1 centred on pixel (32, 32): the corner the 4 tiles share, it reaches into each;
///   2 centred on pixel (48, 48): inside tile (1, 1) only;
///   3 behind the camera: no screen rectangle, in no list.
ComputeSpec four_lights() {
  ComputeSpec s;
  s.lights = {light_at(world_at_pixel(16, 16, 10), 0.5f), light_at(world_at_pixel(32, 32, 10), 0.5f),
              light_at(world_at_pixel(48, 48, 10), 0.5f), light_at({0, 0, 5}, 1.0f)};
  s.buffers = {make_buffer("grid", BufferContent::TileGrid, DramClass::LightLists),
               make_buffer("indices", BufferContent::LightIndexList, DramClass::LightLists),
               make_buffer("bounds", BufferContent::DepthBounds, DramClass::Other),
               make_buffer("lit", BufferContent::Image, DramClass::Color)};
  return s;
}

/// four_lights() and one shader `name` of 20 ALU ops + 7 per light, its lights from `source`,
/// no color output, `tex_fetches` texture fetches.
ComputeSpec four_lights_and_shader(const std::string& name, LightSource source, std::uint32_t tex_fetches) {
  ComputeSpec s = four_lights();
  ShaderDesc sh = make_shader(20, 7, source, 0, tex_fetches);
  sh.name = name;
  s.shaders = {sh};
  return s;
}

/// A G-buffer's valid flags with 100 surfaces: every 7th pixel from pixel 0 (pixels 0..693).
std::vector<std::uint8_t> hundred_surfaces() {
  std::vector<std::uint8_t> valid(kPixels, 0);
  for (std::size_t p = 0; p < 100; ++p) valid[p * 7] = 1;
  return valid;
}

TEST(UnitCompute, TileLightCullingListsTheLightsCoveringEachTile) {
  // 32 px tiles: 4 tiles. Lists: tile 0 {0, 1}, tile 1 {1}, tile 2 {1}, tile 3 {1, 2}: 6 entries.
  // Every tile tests every light: 4 x 4 = 16 tests of 24 ops = 384 ops. Writes: the grid
  // 4 x 8 = 32 B and the index list 6 x 4 = 24 B, both light lists.
  ComputeRig rig(four_lights());
  DispatchCmd d = make_dispatch("tile_light_cull", {}, {"grid", "indices"}, {{"tile_px", "32"}, {"bounds", "none"}});
  d.groups[0] = 2;
  d.groups[1] = 2;
  d.group_size[0] = 32;
  d.group_size[1] = 32;
  rig.dispatch(d);
  EXPECT_EQ(rig.stats.dispatches.value(), 1u);
  EXPECT_EQ(rig.stats.workgroups.value(), 4u);
  EXPECT_EQ(rig.stats.threads.value(), 4u * 1024u);
  EXPECT_EQ(rig.stats.light_volume_tests.value(), 16u);
  EXPECT_EQ(rig.stats.light_list_entries.value(), 6u);
  EXPECT_EQ(rig.stats.compute_alu_ops.value(), 16u * 24u);
  EXPECT_EQ(rig.dram.writes(DramClass::LightLists), 32u + 24u);
  EXPECT_EQ(rig.dram.total_read(), 0u);
  const TileLightGrid* g = rig.tile_grid("grid");
  ASSERT_NE(g, nullptr);
  ASSERT_EQ(g->lists.size(), 4u);
  EXPECT_EQ(g->lists[0], (std::vector<std::uint32_t>{0, 1}));
  EXPECT_EQ(g->lists[1], (std::vector<std::uint32_t>{1}));
  EXPECT_EQ(g->lists[2], (std::vector<std::uint32_t>{1}));
  EXPECT_EQ(g->lists[3], (std::vector<std::uint32_t>{1, 2}));
  EXPECT_EQ(rig.images.buffer_bytes_written.at("indices"), 24u);
}

TEST(UnitCompute, HalvingTheTileSizeQuadruplesTheTestsAndSplitsTheLights) {
  // 16 px tiles: 16 tiles x 4 lights = 64 tests. Lights 0, 1 and 2 now each sit on a corner four
  // tiles share ((16,16), (32,32), (48,48)): 4 entries each, 12 in all.
  ComputeRig rig(four_lights());
  rig.dispatch(make_dispatch("tile_light_cull", {}, {"grid", "indices"}, {{"tile_px", "16"}, {"bounds", "none"}}));
  EXPECT_EQ(rig.stats.light_volume_tests.value(), 64u);
  EXPECT_EQ(rig.stats.compute_alu_ops.value(), 64u * 24u);
  EXPECT_EQ(rig.stats.light_list_entries.value(), 12u);
  EXPECT_EQ(rig.dram.writes(DramClass::LightLists), 16u * 8u + 12u * 4u);
}

TEST(UnitCompute, ACapOnTheListCountsTheTilesOverIt) {
  // max_lights_per_tile 1: tiles 0 and 3 hold 2 lights each.
  ComputeRig rig(four_lights());
  rig.dispatch(make_dispatch("tile_light_cull", {}, {"grid", "indices"},
                             {{"tile_px", "32"}, {"bounds", "none"}, {"max_lights_per_tile", "1"}}));
  EXPECT_EQ(rig.stats.light_list_overflows.value(), 2u);
  EXPECT_EQ(rig.stats.light_list_entries.value(), 6u);  // lists are kept whole
}

/// Window depth (GL depth range) of view distance d with near 0.5 and far 50:
/// z_ndc = ((f + n) - 2 f n / d) / (f - n), window = z_ndc / 2 + 1/2.
float window_depth(float d) {
  const double n = 0.5, f = 50.0;
  return static_cast<float>(((f + n) - 2.0 * f * n / d) / (f - n) * 0.5 + 0.5);
}

/// A depth image at view distance 10 everywhere except tile (1, 1) of the 32 px grid (cleared).
std::vector<float> depth_without_tile_3() {
  std::vector<float> depth(kPixels, window_depth(10.0f));
  for (int y = 32; y < 64; ++y) {
    for (int x = 32; x < 64; ++x) depth[static_cast<std::size_t>(y) * 64 + static_cast<std::size_t>(x)] = 1.0f;
  }
  return depth;
}

TEST(UnitCompute, DepthBoundsEmptyTheListOfATileWithNothingVisible) {
  // Reading the depth image, the kernel reduces it first (4096 samples x 2 ops = 8192) and reads
  // it from DRAM (4096 x 4 B). Tile 3 holds no sample: its list is empty (light 1 and 2 dropped);
  // the others see surfaces at distance 10, which the lights (10 +- 0.5) reach: 2 + 1 + 1 = 4.
  ComputeRig rig(four_lights());
  rig.add_depth_image("depth", depth_without_tile_3());
  rig.dispatch(make_dispatch("tile_light_cull", {"depth"}, {"grid", "indices"}, {{"tile_px", "32"}}));
  EXPECT_EQ(rig.stats.light_list_entries.value(), 4u);
  EXPECT_TRUE(rig.tile_grid("grid")->lists[3].empty());
  EXPECT_EQ(rig.stats.compute_alu_ops.value(), 8192u + 16u * 24u);
  EXPECT_EQ(rig.dram.reads(DramClass::DepthStencil), kPixels * 4u);
}

TEST(UnitCompute, DepthBoundsKernelReducesEverySample) {
  // 16 px tiles (the default): 16 tiles of min/max (8 B each) = 128 B written; 8192 ALU ops.
  ComputeRig rig(four_lights());
  rig.add_depth_image("depth", depth_without_tile_3());
  rig.dispatch(make_dispatch("depth_bounds", {"depth"}, {"bounds"}));
  EXPECT_EQ(rig.stats.compute_alu_ops.value(), 8192u);
  EXPECT_EQ(rig.dram.writes(DramClass::Other), 128u);
  EXPECT_EQ(rig.images.buffer_bytes_written.at("bounds"), 128u);
}

TEST(UnitCompute, DeferredShadingChargesEveryLightPerStoredSurface) {
  // 100 pixels hold a surface; a shader of 20 ops + 7 per light, 2 texture fetches, evaluating
  // all 4 lights: 100 shaded pixels, 400 light evaluations, 100 x (20 + 28) = 4800 ops, 200
  // fetches. Reads the G-buffer (4096 x 4 B), writes the rgba8 image (4096 x 4 B).
  ComputeRig rig(four_lights_and_shader("resolve", LightSource::All, 2));
  rig.add_gbuffer("gbuf", hundred_surfaces());
  rig.dispatch(make_dispatch("deferred_shade", {"gbuf"}, {"lit"}, {{"shader", "resolve"}}));
  EXPECT_EQ(rig.stats.compute_shaded_pixels.value(), 100u);
  EXPECT_EQ(rig.stats.compute_light_evaluations.value(), 400u);
  EXPECT_EQ(rig.stats.compute_alu_ops.value(), 4800u);
  EXPECT_EQ(rig.stats.compute_texture_fetches.value(), 200u);
  EXPECT_EQ(rig.dram.reads(DramClass::Gbuffer), kPixels * 4u);
  EXPECT_EQ(rig.dram.writes(DramClass::Color), kPixels * 4u);
  EXPECT_EQ(rig.image_written, "lit");
}

TEST(UnitCompute, TiledShadingEvaluatesOnlyTheTilesLists) {
  // After culling with 32 px tiles (lists of 2, 1, 1, 2 lights), a tile-list shader on 10
  // surfaces in tile 0 (row 0, x 0..9) and 10 in tile 1 (row 0, x 40..49) evaluates
  // 10 x 2 + 10 x 1 = 30 lights: ALU 20 x 20 + 7 x 30 = 610.
  ComputeRig rig(four_lights_and_shader("tiled", LightSource::TileList, 0));
  rig.dispatch(make_dispatch("tile_light_cull", {}, {"grid", "indices"}, {{"tile_px", "32"}, {"bounds", "none"}}));
  const std::uint64_t cull_ops = rig.stats.compute_alu_ops.value();
  std::vector<std::uint8_t> valid(kPixels, 0);
  for (int x = 0; x < 10; ++x) valid[static_cast<std::size_t>(x)] = 1;
  for (int x = 40; x < 50; ++x) valid[static_cast<std::size_t>(x)] = 1;
  rig.add_gbuffer("gbuf", valid);
  rig.dispatch(make_dispatch("deferred_shade", {"gbuf", "grid", "indices"}, {"lit"}, {{"shader", "tiled"}}));
  EXPECT_EQ(rig.stats.compute_shaded_pixels.value(), 20u);
  EXPECT_EQ(rig.stats.compute_light_evaluations.value(), 30u);
  EXPECT_EQ(rig.stats.compute_alu_ops.value() - cull_ops, 20u * 20u + 7u * 30u);
  // The light lists are read at the size the culling wrote: 32 + 24 B.
  EXPECT_EQ(rig.dram.reads(DramClass::LightLists), 32u + 24u);
}

TEST(UnitCompute, ShadingKernelsMaterialFetchesAreTheFetchesBeyondTheImagesRead) {
  // deferred_shade reads one image (the G-buffer); a shader with 3 fetches spends 1 on it and 2 on
  // the material textures. 100 surfaces of the scene's material 0 (here the 4x4 default texture:
  // one 64 B line per copy), each its own triangle, in the first 11 rows: 4 workgroup tiles of
  // 16 px hold them, each reads line 0 of copies 0 and 1: 8 footprint lines, 512 B booked as
  // texture reads; 100 (quad, triangle) pairs x 1 line x 2 fetches = 200 line accesses.
  for (const auto& [fetches, lines] : {std::pair{1u, 0u}, std::pair{3u, 8u}}) {
    ComputeRig rig(four_lights_and_shader("resolve", LightSource::All, fetches));
    rig.add_gbuffer("gbuf", hundred_surfaces());
    SurfaceStore& surfaces = rig.images.attachments.at("gbuf").surface;
    for (std::size_t k = 0; k < surfaces.size(); ++k) {
      SurfacePoint s = surfaces[k];
      s.material = 0;
      surfaces.set(k, s);
    }
    const TextureLayout layout(&rig.scene, rig.hw, 3);
    std::vector<std::uint64_t> texture_lines;
    ComputeContext cc = rig.context();
    cc.textures = &layout;
    cc.texture_lines = &texture_lines;
    run_dispatch(cc, make_dispatch("deferred_shade", {"gbuf"}, {"lit"}, {{"shader", "resolve"}}), rig.stats, rig.dram,
                 rig.image_written);
    EXPECT_EQ(texture_lines.size(), lines) << fetches << " fetches";
    EXPECT_EQ(rig.stats.compute_texture_tile_lines.value(), lines);
    EXPECT_EQ(rig.stats.compute_texture_line_accesses.value(), lines == 0 ? 0u : 200u);
    EXPECT_EQ(rig.dram.reads(DramClass::Textures), lines * 64u);
    EXPECT_EQ(rig.stats.compute_texture_fetches.value(), 100u * fetches) << "every fetch is charged to the texture units";
  }
}

}  // namespace
}  // namespace tbdr
