// The ISP on its own: one tile of a 64x64 viewport, triangles given in pixel coordinates, every
// count derived by hand (sample positions at pixel centres for 1x, the top-left fill rule).
#include <gtest/gtest.h>

#include <algorithm>
#include <string>
#include <vector>

#include "unit_fixture.hpp"

namespace tbdr {
namespace {

using namespace unit;

// Triangles of tile 0 ([0,32) x [0,32)), y down; samples at (x + 0.5, y + 0.5).
// UL: the upper-left half. Its hypotenuse x + y = 32 is a bottom-right edge (the setup orders
// the vertices clockwise on the y-down screen: (0,0) -> (32,0) is a top edge, (0,32) -> (0,0) a
// left edge, (32,0) -> (0,32) neither), so a pixel is covered iff x + 0.5 + y + 0.5 < 32, i.e.
// x + y <= 30: sum over s = x + y of (s + 1) for s = 0..30 = 31 * 32 / 2 = 496 samples. The 32
// samples exactly on the hypotenuse (x + y = 31) are left out.
const ScreenTri kUpperLeft{{0, 0}, {32, 0}, {0, 32}};
constexpr std::uint64_t kUpperLeftSamples = 496;
// LR: the lower-right half, sharing the hypotenuse, which is ITS left edge: x + y >= 31,
// 1024 - 496 = 528 samples (the 32 diagonal samples belong to it).
const ScreenTri kLowerRight{{32, 0}, {32, 32}, {0, 32}};
constexpr std::uint64_t kLowerRightSamples = 528;
// FULL: (0,0), (128,0), (0,128) covers every sample of the 64x64 viewport (the farthest sample,
// (63.5, 63.5), has x + y = 127 < 128).
const ScreenTri kFull{{0, 0}, {128, 0}, {0, 128}};
constexpr std::uint64_t kTileSamples = 32 * 32;  // 1024

constexpr std::uint64_t kDepthBytes = 4;  // isp.depth_stencil_bytes_per_sample (D24S8)
constexpr std::uint64_t kTagBytes = 4;    // isp.tag_bits = 32

ScreenTri at(ScreenTri t, float z, std::uint32_t draw = 0, HsrClass hsr = HsrClass::Opaque) {
  t.z = z;
  t.draw = draw;
  t.hsr = hsr;
  return t;
}

TEST(UnitIsp, RightTriangleRasterisesHalfATileUnderTheTopLeftRule) {
  RenderRig rig;
  rig.render_one_draw({kUpperLeft});
  EXPECT_EQ(rig.isp_stats.tiles_rendered.value(), 1u);
  EXPECT_EQ(rig.isp_stats.primitives_fetched.value(), 1u);
  EXPECT_EQ(rig.isp_stats.samples_rasterised.value(), kUpperLeftSamples);  // 496 (x + y <= 30)
  EXPECT_EQ(rig.isp_stats.depth_test_failed_samples.value(), 0u);
  EXPECT_EQ(rig.isp_stats.hsr_removed_samples.value(), 0u);
  // Every sample reads and writes depth once (4 B each): 496 x 4 = 1984 B; writes its tag
  // (32 bits): 1984 B; the end-of-tile flush reads every valid tag: 1984 B, and it is not a
  // mid-tile flush.
  EXPECT_EQ(rig.isp_stats.depth_buffer_read_bytes.value(), 496u * kDepthBytes);
  EXPECT_EQ(rig.isp_stats.depth_buffer_write_bytes.value(), 496u * kDepthBytes);
  EXPECT_EQ(rig.isp_stats.tag_buffer_write_bytes.value(), 496u * kTagBytes);
  EXPECT_EQ(rig.isp_stats.tag_buffer_read_bytes.value(), 496u * kTagBytes);
  EXPECT_EQ(rig.isp_stats.tag_flushes.value(), 0u);
  EXPECT_EQ(rig.tsp_stats.shader_invocations.value(), 496u);
  // The sample on the hypotenuse at pixel (15, 16) (x + y = 31) is outside; (15, 15) inside.
  EXPECT_EQ(rig.images.counters.rasterised_samples[16 * 64 + 15], 0u);
  EXPECT_EQ(rig.images.counters.rasterised_samples[15 * 64 + 15], 1u);
}

TEST(UnitIsp, TheTwoHalvesOfATileCoverEverySampleOnce) {
  {
    RenderRig rig;
    rig.render_one_draw({kLowerRight});
    EXPECT_EQ(rig.isp_stats.samples_rasterised.value(), kLowerRightSamples);  // 528 = 1024 - 496
  }
  RenderRig rig;
  rig.render_one_draw({at(kUpperLeft, 0.5f), at(kLowerRight, 0.5f)});
  // No crack, no double hit along the shared edge: 496 + 528 = 1024 samples, none hidden.
  EXPECT_EQ(rig.isp_stats.samples_rasterised.value(), kTileSamples);
  EXPECT_EQ(rig.isp_stats.hsr_removed_samples.value(), 0u);
  EXPECT_EQ(rig.tsp_stats.shader_invocations.value(), kTileSamples);
  // The neighbouring tile sees neither (primitives are still fetched: 2 more).
  rig.render_tile(RenderRig::tile_rect(1, 0));
  EXPECT_EQ(rig.isp_stats.primitives_fetched.value(), 4u);
  EXPECT_EQ(rig.isp_stats.samples_rasterised.value(), kTileSamples);
}

TEST(UnitIsp, FourSamplesPerPixelSplitTheDiagonalPixels) {
  // 4x MSAA at offsets (6,2), (14,6), (2,10), (10,14) / 16: x + y offsets 0.5, 1.25, 0.75, 1.5.
  // UL covers a sample iff x + y + offset < 32: pixels with x + y <= 30 keep all 4 (496 x 4 =
  // 1984); on the diagonal x + y = 31 only offsets 0.5 and 0.75 (2 x 32 = 64); exactly half of
  // the tile's 4096 samples: 2048. 528 pixels get an invocation (496 + 32), 2048 samples a color.
  RenderSpec spec;
  spec.attachments = default_attachments(4);
  RenderRig rig(spec);
  ASSERT_EQ(rig.samples_per_pixel(), 4);
  rig.render_one_draw({kUpperLeft});
  EXPECT_EQ(rig.isp_stats.samples_rasterised.value(), 2048u);
  EXPECT_EQ(rig.isp_stats.depth_buffer_write_bytes.value(), 2048u * kDepthBytes);
  EXPECT_EQ(rig.tsp_stats.shader_invocations.value(), 528u);
  EXPECT_EQ(rig.tsp_stats.shaded_samples.value(), 2048u);
}

TEST(UnitIsp, TriangleBehindTheFirstFailsTheDepthTest) {
  // Front (z 0.25) then back (z 0.75), both covering the tile: the back one's 1024 samples fail
  // the Less test against 0.25; only the front one is tagged and shaded.
  RenderRig rig;
  rig.render_one_draw({at(kFull, 0.25f), at(kFull, 0.75f)});
  EXPECT_EQ(rig.isp_stats.samples_rasterised.value(), 2 * kTileSamples);
  EXPECT_EQ(rig.isp_stats.depth_test_failed_samples.value(), kTileSamples);
  EXPECT_EQ(rig.isp_stats.hsr_removed_samples.value(), 0u);
  // Depth: 2048 reads, 1024 writes (4 B each); tags: 1024 written, 1024 read at the end.
  EXPECT_EQ(rig.isp_stats.depth_buffer_read_bytes.value(), 2048u * kDepthBytes);
  EXPECT_EQ(rig.isp_stats.depth_buffer_write_bytes.value(), 1024u * kDepthBytes);
  EXPECT_EQ(rig.isp_stats.tag_buffer_write_bytes.value(), 1024u * kTagBytes);
  EXPECT_EQ(rig.tsp_stats.shader_invocations.value(), kTileSamples);
  EXPECT_FLOAT_EQ(rig.depth_at(5, 5), 0.25f);
}

TEST(UnitIsp, EveryDepthComparisonPassesExactlyWhereItHolds) {
  // Draw 0 (Always, writes depth) lays 0.5 over the tile; draw 1 (no depth write) covers it at z
  // 0.25, 0.5 or 0.75 and tests against 0.5: all 1024 samples pass or all fail, per comparison
  // and per outcome (incoming less, equal or greater than the stored 0.5).
  struct Case {
    CompareOp op;
    bool less, equal, greater;  // passes when incoming < / == / > stored
  };
  const Case cases[] = {{CompareOp::Never, false, false, false},     {CompareOp::Less, true, false, false},
                        {CompareOp::Equal, false, true, false},      {CompareOp::LessEqual, true, true, false},
                        {CompareOp::Greater, false, false, true},    {CompareOp::NotEqual, true, false, true},
                        {CompareOp::GreaterEqual, false, true, true}, {CompareOp::Always, true, true, true}};
  for (const Case& c : cases) {
    for (const float z : {0.25f, 0.5f, 0.75f}) {
      RenderRig rig;
      PipelineState lay;
      lay.depth_compare = CompareOp::Always;
      PipelineState test;
      test.depth_compare = c.op;
      test.depth_write = false;
      rig.add_draw(make_shader(1), lay);
      rig.add_draw(make_shader(1), test);
      rig.add_triangle(at(kFull, 0.5f, 0));
      rig.add_triangle(at(kFull, z, 1));
      rig.render_tile(RenderRig::tile_rect(0, 0));
      const bool pass = z < 0.5f ? c.less : z == 0.5f ? c.equal : c.greater;
      EXPECT_EQ(rig.isp_stats.depth_test_failed_samples.value(), pass ? 0u : kTileSamples)
          << "compare " << static_cast<int>(c.op) << " at z " << z;
    }
  }
}

TEST(UnitIsp, OpaqueOverOpaqueRemovesTheHiddenSamplesBeforeShading) {
  // Back (z 0.75) then front (z 0.25): every back sample passes the depth test and is tagged,
  // then the front one overwrites all 1024 tags: the back triangle is never shaded.
  RenderRig rig;
  const std::vector<std::uint32_t> ids = rig.render_one_draw({at(kFull, 0.75f), at(kFull, 0.25f)});
  const std::uint32_t back = ids[0], front = ids[1];
  EXPECT_EQ(rig.isp_stats.depth_test_failed_samples.value(), 0u);
  EXPECT_EQ(rig.isp_stats.hsr_removed_samples.value(), kTileSamples);
  EXPECT_EQ(rig.isp_stats.depth_buffer_write_bytes.value(), 2048u * kDepthBytes);
  EXPECT_EQ(rig.isp_stats.tag_buffer_write_bytes.value(), 2048u * kTagBytes);
  EXPECT_EQ(rig.isp_stats.tag_buffer_read_bytes.value(), 1024u * kTagBytes);
  EXPECT_EQ(rig.tsp_stats.shader_invocations.value(), kTileSamples);
  // The last primitive shaded at a pixel is the front one (ids are index + 1).
  EXPECT_EQ(rig.images.counters.triangle_id[10 * 64 + 10], front + 1);
  EXPECT_NE(rig.images.counters.triangle_id[10 * 64 + 10], back + 1);
}

TEST(UnitIsp, PartlyHiddenTriangleIsShadedOnlyWhereVisible) {
  // Back FULL (z 0.75) then front UL (z 0.25): HSR removes the 496 back samples under UL; the
  // back triangle is shaded on LR's 528 samples and the front one on 496: 1024 invocations.
  RenderRig rig;
  rig.render_one_draw({at(kFull, 0.75f), at(kUpperLeft, 0.25f)});
  EXPECT_EQ(rig.isp_stats.samples_rasterised.value(), 1024u + 496u);
  EXPECT_EQ(rig.isp_stats.hsr_removed_samples.value(), 496u);
  EXPECT_EQ(rig.tsp_stats.shader_invocations.value(), 1024u);
}

TEST(UnitIsp, WithoutTagBufferEverySampleThatPassesEarlyDepthIsShaded) {
  // gpu.mode = tbr: back then front are both shaded at early-Z, 2 x 1024 invocations; no tags.
  RenderRig rig(RenderSpec{.sets = {"gpu.mode=tbr"}});
  rig.render_one_draw({at(kFull, 0.75f), at(kFull, 0.25f)});
  EXPECT_EQ(rig.isp_stats.hsr_removed_samples.value(), 0u);
  EXPECT_EQ(rig.isp_stats.tag_buffer_write_bytes.value(), 0u);
  EXPECT_EQ(rig.isp_stats.tag_buffer_read_bytes.value(), 0u);
  EXPECT_EQ(rig.tsp_stats.shader_invocations.value(), 2 * kTileSamples);
  EXPECT_EQ(rig.isp_stats.depth_buffer_write_bytes.value(), 2048u * kDepthBytes);
}

TEST(UnitIsp, StencilWrittenByOneDrawMasksTheNext) {
  // Draw 0 (no depth test or write; stencil always passes and replaces with 1) marks UL's 496
  // samples. Draw 1 (FULL, stencil Equal 1) passes there and fails on LR's 528 samples, which
  // therefore read no depth. Draw 0's 496 tags are then overwritten by draw 1 (HSR): only draw 1
  // is shaded, on 496 samples.
  RenderRig rig;
  PipelineState mark;
  mark.depth_test = false;
  mark.depth_write = false;
  mark.stencil_test = true;
  mark.stencil_compare = CompareOp::Always;
  mark.stencil_pass_op = StencilOp::Replace;
  mark.stencil_ref = 1;
  PipelineState masked;
  masked.stencil_test = true;
  masked.stencil_compare = CompareOp::Equal;
  masked.stencil_ref = 1;
  rig.add_draw(make_shader(1), mark);
  rig.add_draw(make_shader(1), masked);
  rig.add_triangle(at(kUpperLeft, 0.5f, 0));
  rig.add_triangle(at(kFull, 0.25f, 1));
  rig.render_tile(RenderRig::tile_rect(0, 0));
  EXPECT_EQ(rig.isp_stats.samples_rasterised.value(), 496u + 1024u);
  EXPECT_EQ(rig.isp_stats.stencil_test_failed_samples.value(), 528u);
  EXPECT_EQ(rig.isp_stats.depth_buffer_read_bytes.value(), 496u * kDepthBytes);  // draw 1 where it passed
  EXPECT_EQ(rig.isp_stats.depth_buffer_write_bytes.value(), 496u * kDepthBytes);
  EXPECT_EQ(rig.isp_stats.hsr_removed_samples.value(), 496u);
  EXPECT_EQ(rig.tsp_stats.shader_invocations.value(), 496u);
}

/// Opaque FULL behind a punch-through UL (no material: its alpha test keeps every sample).
void punch_through_over_opaque(RenderRig& rig) {
  rig.render_one_draw({at(kFull, 0.75f, 0, HsrClass::Opaque), at(kUpperLeft, 0.25f, 0, HsrClass::PunchThrough)});
}

TEST(UnitIsp, PunchThroughOverAPendingTagFlushesTheTileWithOneTagBuffer) {
  // One tag buffer: the punch-through samples need a second layer over the 1024 pending opaque
  // tags, so the tile is flushed (1 mid-tile flush of 1024 samples; no punch-through depth is
  // pending yet, so the ISP does not wait); the punch-through tags (496) are then the only layer
  // and are shaded at the end of the tile, writing depth where the alpha test kept them (all).
  RenderRig rig(RenderSpec{.sets = {"isp.tag_buffers=1"}});
  punch_through_over_opaque(rig);
  EXPECT_EQ(rig.isp_stats.tag_flushes.value(), 1u);
  EXPECT_EQ(rig.isp_stats.tag_flushed_samples.value(), 1024u);
  EXPECT_EQ(rig.isp_stats.resolve_flushes.value(), 0u);
  EXPECT_EQ(rig.isp_stats.resolve_wait_alu_ops.value(), 0u);
  EXPECT_EQ(rig.isp_stats.punch_through_samples.value(), 496u);
  EXPECT_EQ(rig.isp_stats.tag_buffer_read_bytes.value(), (1024u + 496u) * kTagBytes);
  EXPECT_EQ(rig.tsp_stats.shader_invocations.value(), 1024u + 496u);
  // Depth: 1024 opaque writes, then 496 punch-through writes after its (passing) alpha test;
  // reads: 1024 + 496, and the 496 punch-through samples again after the flush.
  EXPECT_EQ(rig.isp_stats.depth_buffer_write_bytes.value(), (1024u + 496u) * kDepthBytes);
  EXPECT_EQ(rig.isp_stats.depth_buffer_read_bytes.value(), (1024u + 496u + 496u) * kDepthBytes);
  EXPECT_FLOAT_EQ(rig.depth_at(3, 3), 0.25f);
}

TEST(UnitIsp, PunchThroughWaitsAsASecondLayerWithTwoTagBuffers) {
  // Two tag buffers: the punch-through tags go to the second layer, nothing is flushed mid-tile;
  // the end of the tile shades both layers in submission order: 1024 + 496 invocations, the same
  // as with one buffer (nothing hid them), and the same depth.
  RenderRig rig(RenderSpec{.sets = {"isp.tag_buffers=2"}});
  punch_through_over_opaque(rig);
  EXPECT_EQ(rig.isp_stats.tag_flushes.value(), 0u);
  EXPECT_EQ(rig.isp_stats.tag_buffer_read_bytes.value(), (1024u + 496u) * kTagBytes);
  EXPECT_EQ(rig.tsp_stats.shader_invocations.value(), 1024u + 496u);
  EXPECT_EQ(rig.isp_stats.depth_buffer_write_bytes.value(), (1024u + 496u) * kDepthBytes);
  EXPECT_FLOAT_EQ(rig.depth_at(3, 3), 0.25f);
  EXPECT_FLOAT_EQ(rig.depth_at(30, 30), 0.75f);
}

/// The interleaved workload: opaque A (FULL, z 0.75), punch-through P (UL, z 0.5), translucent T
/// (the corner (24,32),(32,24),(32,32), z 0.4, inside LR), then opaque B (FULL, z 0.25) in front
/// of everything: what an unsorted engine submits when a near object follows foliage and glass.
void interleaved(RenderRig& rig) {
  rig.add_draw(make_shader(1));
  PipelineState blend;
  blend.depth_write = false;
  blend.blend = BlendMode::Alpha;
  rig.add_draw(make_shader(1), blend);
  rig.add_triangle(at(kFull, 0.75f));
  rig.add_triangle(at(kUpperLeft, 0.5f, 0, HsrClass::PunchThrough));
  rig.add_triangle(at(ScreenTri{{24, 32}, {32, 24}, {32, 32}}, 0.4f, 1, HsrClass::Translucent));
  rig.add_triangle(at(kFull, 0.25f));
  rig.render_tile(RenderRig::tile_rect(0, 0));
}

TEST(UnitIsp, MoreTagBuffersNeverShadeMoreOnTheInterleavedWorkload) {
  // T covers x + y >= 55 inside [24,32)^2 (its hypotenuse is a left edge): sums 55..62 hold
  // 8, 7, ..., 1 pixels = 36 samples; P covers UL's 496. T and P do not overlap.
  // One tag buffer: P needs a second layer over A's 1024 tags: the tile is flushed (A shaded,
  //   1024). P's 496 and T's 36 then sit alone in the only layer; B (in front of P's unresolved
  //   depth: 0.25 < 0.5) clears them (496 + 36 removed) and is shaded at the end (1024):
  //   2048 invocations, 1 flush.
  // Two or more: P and T become second layers over A; B clears all three layers (1024 + 496 +
  //   36 = 1556 removed), only B is shaded: 1024 invocations, no flush.
  // So 2, 4 and 8 buffers shade 1024 / 2048 = half of what 1 does, and never more than fewer.
  const std::uint64_t shaded[] = {2048, 1024, 1024, 1024};
  const std::uint64_t flushes[] = {1, 0, 0, 0};
  const std::uint64_t removed[] = {496 + 36, 1024 + 496 + 36, 1024 + 496 + 36, 1024 + 496 + 36};
  std::uint64_t previous_alu = ~std::uint64_t{0}, one_buffer_alu = 0;
  int i = 0;
  for (int buffers : {1, 2, 4, 8}) {
    RenderRig rig(RenderSpec{.sets = {"isp.tag_buffers=" + std::to_string(buffers)}});
    interleaved(rig);
    SCOPED_TRACE("isp.tag_buffers=" + std::to_string(buffers));
    const int k = std::min(i, 3);
    EXPECT_EQ(rig.isp_stats.punch_through_samples.value(), 496u);
    EXPECT_EQ(rig.isp_stats.translucent_samples.value(), 36u);
    EXPECT_EQ(rig.isp_stats.tag_flushes.value(), flushes[k]);
    EXPECT_EQ(rig.isp_stats.hsr_removed_samples.value(), removed[k]);
    EXPECT_EQ(rig.tsp_stats.shader_invocations.value(), shaded[k]);
    EXPECT_EQ(rig.isp_stats.resolve_flushes.value(), 0u);
    // The picture is B everywhere whatever the buffers.
    EXPECT_FLOAT_EQ(rig.depth_at(3, 3), 0.25f);
    // Fragment ALU ops (helpers included): never more than with fewer buffers, and with 2 or more
    // strictly less than with one.
    const std::uint64_t alu = rig.tsp_stats.fragment_alu_ops.value();
    EXPECT_LE(alu, previous_alu);
    if (buffers == 1) one_buffer_alu = alu;
    if (buffers > 1) {
      EXPECT_LT(alu, one_buffer_alu);
    }
    previous_alu = alu;
    ++i;
  }
}

TEST(UnitIsp, DepthTestBehindAnUnresolvedPunchThroughMakesTheIspWaitForItsShader) {
  // A (FULL, z 0.75), punch-through P (UL, z 0.5), opaque C (FULL, z 0.6): behind P, in front of
  // A. C's depth test on UL depends on P's alpha test, so the layers are flushed (A, then P: P's
  // depth is written) and the ISP waits until P's shader has run (its 496 samples' quads, alone:
  // the same ALU ops as UL shaded on its own); C then fails on UL's 496 samples and is shaded on
  // LR's 528: 1024 + 496 + 528 = 2048 invocations, whatever the number of tag buffers (with one,
  // A was flushed when P arrived, without a wait).
  RenderRig ul_only;
  ul_only.render_one_draw({at(kUpperLeft, 0.5f)});
  const std::uint64_t ul_alu = ul_only.tsp_stats.fragment_alu_ops.value();
  for (int buffers : {1, 2, 4}) {
    RenderRig rig(RenderSpec{.sets = {"isp.tag_buffers=" + std::to_string(buffers)}});
    rig.render_one_draw({at(kFull, 0.75f), at(kUpperLeft, 0.5f, 0, HsrClass::PunchThrough), at(kFull, 0.6f)});
    SCOPED_TRACE("isp.tag_buffers=" + std::to_string(buffers));
    EXPECT_EQ(rig.isp_stats.resolve_flushes.value(), 1u);
    EXPECT_EQ(rig.tsp_stats.shader_invocations.value(), 2048u);
    EXPECT_EQ(rig.isp_stats.depth_test_failed_samples.value(), 496u);
    EXPECT_EQ(rig.isp_stats.resolve_wait_alu_ops.value(), ul_alu);
    EXPECT_GT(ul_alu, 0u);
    EXPECT_FLOAT_EQ(rig.depth_at(3, 3), 0.5f);
    EXPECT_FLOAT_EQ(rig.depth_at(30, 30), 0.6f);
  }
}

TEST(UnitIsp, PunchThroughWritesDepthOnlyWhereTheAlphaTestKeptTheSample) {
  // UL with the masked material (uv (0,0), (1,0), (0,1): u = (x + 0.5) / 32 at pixel centres;
  // the 2x1 mask is transparent for u < 0.5, i.e. x <= 15). Killed: sum over x = 0..15 of the
  // (31 - x) covered rows = 496 - 120 = 376; kept 120 (x = 16..30). The opaque FULL behind
  // (z 0.75) keeps its depth where the leaves were killed.
  RenderRig rig;
  rig.add_draw(make_shader(1));
  rig.add_triangle(at(kFull, 0.75f));
  ScreenTri leaves = at(kUpperLeft, 0.25f, 0, HsrClass::PunchThrough);
  leaves.material = 1;
  leaves.uv = {glm::vec2{0, 0}, glm::vec2{1, 0}, glm::vec2{0, 1}};
  rig.add_triangle(leaves);
  rig.render_tile(RenderRig::tile_rect(0, 0));
  EXPECT_EQ(rig.tsp_stats.alpha_test_killed_samples.value(), 376u);
  EXPECT_EQ(rig.isp_stats.punch_through_samples.value(), 496u);
  // Depth writes: 1024 opaque + 120 surviving leaves.
  EXPECT_EQ(rig.isp_stats.depth_buffer_write_bytes.value(), (1024u + 120u) * kDepthBytes);
  EXPECT_FLOAT_EQ(rig.depth_at(3, 3), 0.75f);   // killed leaf (x = 3)
  EXPECT_FLOAT_EQ(rig.depth_at(20, 5), 0.25f);  // kept leaf (x = 20, x + y = 25)
  // Colors written: 1024 opaque samples + 120 leaves.
  EXPECT_EQ(rig.tsp_stats.shaded_samples.value(), 1024u + 120u);
}

TEST(UnitIsp, TranslucentPrimitiveIsALayerAndHidesNothing) {
  // Blended UL (z 0.25, no depth write) over opaque FULL (z 0.75), two tag buffers: the 496
  // translucent tags are a second layer; the end of the tile shades the opaque 1024, then blends
  // the 496 translucent samples (496 read-modify-writes of 4 B). No mid-tile flush.
  RenderRig rig;
  rig.add_draw(make_shader(1));
  PipelineState blend;
  blend.depth_write = false;
  blend.blend = BlendMode::Alpha;
  rig.add_draw(make_shader(1), blend);
  rig.add_triangle(at(kFull, 0.75f, 0));
  rig.add_triangle(at(kUpperLeft, 0.25f, 1, HsrClass::Translucent));
  rig.render_tile(RenderRig::tile_rect(0, 0));
  EXPECT_EQ(rig.isp_stats.translucent_samples.value(), 496u);
  EXPECT_EQ(rig.isp_stats.tag_flushes.value(), 0u);
  EXPECT_EQ(rig.isp_stats.tag_flushed_samples.value(), 0u);
  EXPECT_EQ(rig.tsp_stats.blended_samples.value(), 496u);
  EXPECT_EQ(rig.tsp_stats.tile_buffer_read_bytes.value(), 496u * 4);
  EXPECT_EQ(rig.tsp_stats.tile_buffer_write_bytes.value(), (1024u + 496u) * 4);
  EXPECT_EQ(rig.isp_stats.depth_buffer_write_bytes.value(), 1024u * kDepthBytes);
  EXPECT_FLOAT_EQ(rig.depth_at(3, 3), 0.75f);
}

}  // namespace
}  // namespace tbdr
