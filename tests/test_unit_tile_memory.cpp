// Tile memory on its own: the bytes a 32x32 tile (1024 pixels) loads, clears and stores for given
// attachment formats and load/store ops, transient attachments, MSAA resolve, partial renders, and
// what a pass over the on-chip budget costs (default budget: pls.tile_buffer_bits_per_pixel = 128,
// 16 B per pixel; depth lives in the ISP at isp.depth_stencil_bytes_per_sample = 4 B per sample).
#include <gtest/gtest.h>

#include <vector>

#include "unit_fixture.hpp"

namespace tbdr {
namespace {

using namespace unit;

constexpr std::uint64_t kPixels = 32 * 32;  // one tile

RenderSpec with_attachments(std::vector<Attachment> a, std::vector<std::string> sets = {}) {
  RenderSpec s;
  s.attachments = std::move(a);
  s.sets = std::move(sets);
  return s;
}

Attachment transient_depth(LoadOp load = LoadOp::Clear, std::uint32_t samples = 1) {
  return make_attachment("depth", Format::D24s8, load, StoreOp::DontCare, true, samples);
}

TEST(UnitTileMemory, ClearAndStoreOfTheDefaultPass) {
  // rgba8 color cleared and stored, d24s8 depth cleared, transient. On chip: 4 B per pixel (depth
  // is not in the tile buffer): fits the 16 B budget, one strip.
  RenderRig rig;
  EXPECT_EQ(rig.need_bytes_per_pixel(), 4u);
  EXPECT_EQ(rig.budget_bytes_per_pixel(), 16u);
  EXPECT_EQ(rig.tm_stats.tile_split_factor.value(), 1u);
  const PixelRect tile = RenderRig::tile_rect(1, 0);
  ASSERT_EQ(rig.strips(tile).size(), 1u);
  rig.begin_tile(tile);
  // Clears: color 1024 x 4 + depth 1024 x 4 = 8192 B; nothing read from DRAM.
  EXPECT_EQ(rig.tm_stats.tile_clear_bytes.value(), 8192u);
  EXPECT_EQ(rig.tm_stats.tile_load_bytes.value(), 0u);
  EXPECT_EQ(rig.dram.total_read(), 0u);
  rig.end_tile(tile);
  // Stores: color 4096 B; the transient depth never leaves the chip.
  EXPECT_EQ(rig.tm_stats.tile_store_bytes.value(), kPixels * 4);
  EXPECT_EQ(rig.tm_stats.writeback_dram_bytes.value(), kPixels * 4);
  EXPECT_EQ(rig.dram.writes(DramClass::Color), kPixels * 4);
  EXPECT_EQ(rig.dram.writes(DramClass::DepthStencil), 0u);
}

TEST(UnitTileMemory, LoadOpsReadWhatEarlierPassesStored) {
  // rgba16f color loaded and stored (8 B per pixel), d24s8 depth loaded and stored (non-transient).
  RenderRig rig(with_attachments({make_attachment("color", Format::Rgba16f, LoadOp::Load, StoreOp::Store),
                                  make_attachment("depth", Format::D24s8, LoadOp::Load, StoreOp::Store)}));
  const PixelRect tile = RenderRig::tile_rect(0, 1);
  rig.begin_tile(tile);
  rig.end_tile(tile);
  EXPECT_EQ(rig.tm_stats.tile_clear_bytes.value(), 0u);
  EXPECT_EQ(rig.tm_stats.tile_load_bytes.value(), kPixels * 8 + kPixels * 4);  // 12288
  EXPECT_EQ(rig.dram.reads(DramClass::Color), kPixels * 8);
  EXPECT_EQ(rig.dram.reads(DramClass::DepthStencil), kPixels * 4);
  EXPECT_EQ(rig.tm_stats.tile_store_bytes.value(), kPixels * 12);
  EXPECT_EQ(rig.dram.writes(DramClass::Color), kPixels * 8);
  EXPECT_EQ(rig.dram.writes(DramClass::DepthStencil), kPixels * 4);
}

TEST(UnitTileMemory, TransientAndDontCareAttachmentsMoveNothing) {
  // A transient G-buffer "loaded" (memoryless: nothing to load) and stored (never in DRAM), and a
  // don't-care color whose store is don't-care: no byte crosses the chip boundary; only clears
  // count, and don't-care is not a clear.
  RenderRig rig(with_attachments({make_attachment("gbuf", Format::Rgba8, LoadOp::Load, StoreOp::Store, true, 1,
                                                  AttachmentUsage::Gbuffer),
                                  make_attachment("color", Format::Rgba8, LoadOp::DontCare, StoreOp::DontCare),
                                  transient_depth(LoadOp::DontCare)}));
  const PixelRect tile = RenderRig::tile_rect(0, 0);
  rig.begin_tile(tile);
  rig.end_tile(tile);
  EXPECT_EQ(rig.tm_stats.tile_load_bytes.value(), 0u);
  EXPECT_EQ(rig.tm_stats.tile_clear_bytes.value(), 0u);
  EXPECT_EQ(rig.tm_stats.tile_store_bytes.value(), 0u);
  EXPECT_EQ(rig.dram.total_read(), 0u);
  EXPECT_EQ(rig.dram.total_written(), 0u);
}

TEST(UnitTileMemory, WritebackCompressionScalesTheDramBytes) {
  // writeback.compression_ratio 0.5: a loaded and stored rgba8 color tile reads and writes 2048 B
  // of DRAM for its 4096 B.
  RenderRig rig(with_attachments({make_attachment("color", Format::Rgba8, LoadOp::Load, StoreOp::Store), transient_depth()},
                                 {"writeback.compression_ratio=0.5"}));
  const PixelRect tile = RenderRig::tile_rect(1, 1);
  rig.begin_tile(tile);
  rig.end_tile(tile);
  EXPECT_EQ(rig.tm_stats.tile_load_bytes.value(), 4096u);
  EXPECT_EQ(rig.dram.reads(DramClass::Color), 2048u);
  EXPECT_EQ(rig.tm_stats.tile_store_bytes.value(), 4096u);
  EXPECT_EQ(rig.tm_stats.writeback_dram_bytes.value(), 2048u);
  EXPECT_EQ(rig.dram.writes(DramClass::Color), 2048u);
}

TEST(UnitTileMemory, MultisampledColorIsResolvedAndOnlyTheResolveStored) {
  // 4x rgba8 (16 B per pixel on chip, exactly the budget) resolved into a 1x rgba8 target; the
  // multisampled image is not stored. Clears: 4 x 4 x 1024 (msaa) + 4 x 1024 (resolve) +
  // 4 x 4 x 1024 (4x depth) = 36864 B. Resolve: 4096 samples averaged; store 4096 B.
  Attachment msaa = make_attachment("msaa", Format::Rgba8, LoadOp::Clear, StoreOp::DontCare, false, 4);
  msaa.resolve = "resolved";
  RenderRig rig(with_attachments({msaa, make_attachment("resolved", Format::Rgba8), transient_depth(LoadOp::Clear, 4)}));
  EXPECT_EQ(rig.need_bytes_per_pixel(), 16u);
  EXPECT_EQ(rig.tm_stats.tile_split_factor.value(), 1u);
  const PixelRect tile = RenderRig::tile_rect(0, 0);
  rig.begin_tile(tile);
  EXPECT_EQ(rig.tm_stats.tile_clear_bytes.value(), 36864u);
  // Samples of pixel (2, 3): 0, 0.2, 0.4, 0.6 in red: the resolved red is their mean, 0.3, as rgba8 keeps it.
  auto& src = rig.images.attachments.at("msaa").color;
  for (int s = 0; s < 4; ++s) src[(3 * 64 + 2) * 4 + static_cast<std::size_t>(s)] = glm::vec4(0.2f * static_cast<float>(s), 0, 0, 1);
  rig.end_tile(tile);
  EXPECT_EQ(rig.tm_stats.resolved_samples.value(), 4096u);
  EXPECT_EQ(rig.tm_stats.tile_store_bytes.value(), 4096u);
  EXPECT_EQ(rig.dram.writes(DramClass::Color), 4096u);
  // The rgba8 resolve target keeps the mean at its precision: 0.3 x 255 = 76.5, rounded to even: 76/255.
  EXPECT_EQ(rig.images.attachments.at("resolved").color[3 * 64 + 2].x, 76.0f / 255.0f);
}

TEST(UnitTileMemory, PartialRenderStoresEverythingAndReloadsIt) {
  // A partial render sends every attachment off chip, transient or not: color 4096 + depth 4096;
  // the next render of the tile reloads the same 8192 B instead of clearing.
  RenderRig rig;
  const PixelRect tile = RenderRig::tile_rect(0, 0);
  rig.begin_tile(tile);
  rig.end_tile(tile, true);
  EXPECT_EQ(rig.tm_stats.partial_render_store_bytes.value(), 8192u);
  EXPECT_EQ(rig.tm_stats.tile_store_bytes.value(), 0u);
  EXPECT_EQ(rig.dram.writes(DramClass::Color), 4096u);
  EXPECT_EQ(rig.dram.writes(DramClass::DepthStencil), 4096u);
  const std::uint64_t clears = rig.tm_stats.tile_clear_bytes.value();
  rig.begin_tile(tile, true);
  EXPECT_EQ(rig.tm_stats.partial_render_reload_bytes.value(), 8192u);
  EXPECT_EQ(rig.tm_stats.tile_clear_bytes.value(), clears);
  EXPECT_EQ(rig.dram.reads(DramClass::Color), 4096u);
  EXPECT_EQ(rig.dram.reads(DramClass::DepthStencil), 4096u);
}

TEST(UnitTileMemory, ImmediateModeKeepsAttachmentsInDram) {
  // gpu.mode = imr: the attachments live in DRAM behind the ROP caches (models/rop.hpp), which
  // clear them (test_timing's Imr tests count that traffic): tile memory moves nothing, neither
  // for the clear, nor for the load, nor at the end of the tile.
  RenderRig rig(with_attachments({make_attachment("color", Format::Rgba8), make_attachment("prev", Format::Rgba8, LoadOp::Load),
                                  transient_depth()},
                                 {"gpu.mode=imr"}));
  const PixelRect tile = RenderRig::tile_rect(0, 0);
  rig.begin_tile(tile);
  EXPECT_EQ(rig.dram.total_written(), 0u);
  EXPECT_EQ(rig.dram.total_read(), 0u);
  EXPECT_EQ(rig.tm_stats.tile_load_bytes.value(), 0u);
  EXPECT_EQ(rig.need_bytes_per_pixel(), 0u);  // no tile memory to fit
  rig.end_tile(tile);
  EXPECT_EQ(rig.tm_stats.tile_store_bytes.value(), 0u);
  EXPECT_EQ(rig.dram.total_written(), 0u);
}

/// `n` rgba16f color attachments (8 B per pixel each) plus a transient depth.
std::vector<Attachment> hdr_targets(int n) {
  std::vector<Attachment> a;
  for (int i = 0; i < n; ++i) a.push_back(make_attachment("c" + std::to_string(i), Format::Rgba16f));
  a.push_back(transient_depth());
  return a;
}

TEST(UnitTileMemory, SmallerTilesSplitAPassOverBudgetIntoStrips) {
  // 3 x 8 = 24 B per pixel > 16: ceil(24 / 16) = 2 strips of 32 x 16.
  {
    RenderRig rig(with_attachments(hdr_targets(3), {"pls.over_budget=smaller_tiles"}));
    EXPECT_EQ(rig.need_bytes_per_pixel(), 24u);
    EXPECT_EQ(rig.tm_stats.tile_split_factor.value(), 2u);
    EXPECT_EQ(rig.spill_fraction(), 0.0);
    const std::vector<PixelRect> s = rig.strips(RenderRig::tile_rect(1, 1));
    ASSERT_EQ(s.size(), 2u);
    EXPECT_EQ(s[0], (PixelRect{32, 32, 64, 48}));
    EXPECT_EQ(s[1], (PixelRect{32, 48, 64, 64}));
  }
  // 5 x 8 = 40 B: ceil(40 / 16) = 3 strips of ceil(32 / 3) = 11 rows: 11, 11, 10. Their clears
  // and stores add up to the whole tile's: 40 x 1024 color (+ 4 x 1024 depth cleared).
  RenderRig rig(with_attachments(hdr_targets(5), {"pls.over_budget=smaller_tiles"}));
  EXPECT_EQ(rig.tm_stats.tile_split_factor.value(), 3u);
  const std::vector<PixelRect> s = rig.strips(RenderRig::tile_rect(0, 0));
  ASSERT_EQ(s.size(), 3u);
  EXPECT_EQ(s[0].height(), 11);
  EXPECT_EQ(s[1].height(), 11);
  EXPECT_EQ(s[2].height(), 10);
  for (const PixelRect& r : s) {
    rig.begin_tile(r);
    rig.end_tile(r);
  }
  EXPECT_EQ(rig.tm_stats.tile_clear_bytes.value(), kPixels * 44);
  EXPECT_EQ(rig.tm_stats.tile_store_bytes.value(), kPixels * 40);
}

TEST(UnitTileMemory, ALargerTileBufferFitsThePass) {
  // pls.tile_buffer_bits_per_pixel = 256: 32 B per pixel hold the 24 B pass in one strip.
  RenderRig rig(with_attachments(hdr_targets(3), {"pls.over_budget=smaller_tiles", "pls.tile_buffer_bits_per_pixel=256"}));
  EXPECT_EQ(rig.budget_bytes_per_pixel(), 32u);
  EXPECT_EQ(rig.tm_stats.tile_split_factor.value(), 1u);
  EXPECT_EQ(rig.strips(RenderRig::tile_rect(0, 0)).size(), 1u);
}

TEST(UnitTileMemory, SpillSendsTheOverBudgetShareOfShaderAccessesToDram) {
  // spill (the default): 24 B needed, 16 on chip: a third of every tile buffer access goes to
  // DRAM. Shaders read 300 B and wrote 600 B: 200 B written out, 100 B read + the 200 B written
  // read back = 300 B; spill_bytes = 500.
  RenderRig rig(with_attachments(hdr_targets(3)));
  EXPECT_EQ(rig.tm_stats.tile_split_factor.value(), 1u);
  EXPECT_DOUBLE_EQ(rig.spill_fraction(), 8.0 / 24.0);
  rig.spill(300, 600);
  EXPECT_EQ(rig.dram.writes(DramClass::Spill), 200u);
  EXPECT_EQ(rig.dram.reads(DramClass::Spill), 300u);
  EXPECT_EQ(rig.tm_stats.spill_bytes.value(), 500u);
}

TEST(UnitTileMemory, PixelLocalStorageSharesTheColourStorageAndCountsAgainstTheBudget) {
  // PLS and colour share per-pixel storage (EXT_shader_pixel_local_storage): rgba8 colour (4 B)
  // beside PLS rgba16f + r32ui (8 + 4 B) needs max(4, 12) = 12 B, not 16. One more rgba8 PLS
  // variable makes 16 B of PLS: over a 96-bit (12 B) budget, a quarter spilled.
  RenderSpec fits;
  fits.pls = {PlsVariable{"light", Format::Rgba16f, 0}, PlsVariable{"count", Format::R32ui, 0}};
  RenderRig a(fits);
  EXPECT_EQ(a.need_bytes_per_pixel(), 12u);
  EXPECT_EQ(a.spill_fraction(), 0.0);
  RenderSpec over = fits;
  over.pls.push_back(PlsVariable{"albedo", Format::Rgba8, 0});
  over.sets = {"pls.tile_buffer_bits_per_pixel=96"};
  RenderRig b(over);
  EXPECT_EQ(b.need_bytes_per_pixel(), 16u);
  EXPECT_DOUBLE_EQ(b.spill_fraction(), 4.0 / 16.0);
}

}  // namespace
}  // namespace tbdr
