// The functional TBDR pipeline on small synthetic scenes whose counts can be worked out by hand:
// tag-buffer HSR, punch-through and translucent flushes, writeback, partial renders.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

#include "models/hw_config.hpp"
#include "models/command_processor.hpp"
#include "trace/trace.hpp"
#include "scene/lights.hpp"
#include "scene/scene_library.hpp"
#include "techniques/technique.hpp"
#include "synthetic_scene.hpp"
#include "stat_lookup.hpp"

namespace tbdr {
namespace {

using namespace synthetic;


FrameResult run(const Scene& s, const std::vector<DrawCmd>& draws, const std::vector<std::string>& sets = {}) {
  Trace t = base_trace();
  PassDesc p = base_pass();
  p.draws = draws;
  t.commands.push_back(p);
  const ResolvedConfig rc = resolve_config({}, sets);
  return simulate_frame(t, "synthetic.trace", s, rc.hw);
}

TEST(PipelineHsr, OpaqueShadingIsIndependentOfSubmissionOrder) {
  // Three overlapping opaque quads at depths 2, 3, 4 covering columns [0,40), [12,52), [24,64).
  Scene s = base_scene();
  add_quad(s, "near", 2, 0, 40, 0);
  add_quad(s, "mid", 3, 12, 52, 0);
  add_quad(s, "far", 4, 24, 64, 0);
  const FrameResult f2b = run(s, {draw_of("near"), draw_of("mid"), draw_of("far")});
  const FrameResult b2f = run(s, {draw_of("far"), draw_of("mid"), draw_of("near")});
  // Every pixel is covered by at least one quad: a TBDR shades each exactly once, whatever the order.
  const double covered = kSize * kSize;
  EXPECT_EQ(stat(f2b, "frame/tsp", "shaded_samples"), covered);
  EXPECT_EQ(stat(b2f, "frame/tsp", "shaded_samples"), covered);
  EXPECT_EQ(stat(f2b, "frame/tsp", "shader_invocations"), covered);
  EXPECT_EQ(stat(b2f, "frame/tsp", "shader_invocations"), covered);
  // Rasterised: 40+40+40 columns of 64 rows. Front to back the hidden ones fail the depth test;
  // back to front they pass it and overwrite pending tags (removed by HSR instead of shaded).
  const double rasterised = 3 * 40 * kSize;
  EXPECT_EQ(stat(f2b, "frame/isp", "samples_rasterised"), rasterised);
  EXPECT_EQ(stat(f2b, "frame/isp", "depth_test_failed_samples"), rasterised - covered);
  EXPECT_EQ(stat(f2b, "frame/isp", "hsr_removed_samples"), 0);
  EXPECT_EQ(stat(b2f, "frame/isp", "depth_test_failed_samples"), 0);
  EXPECT_EQ(stat(b2f, "frame/isp", "hsr_removed_samples"), rasterised - covered);
  // Identical images.
  EXPECT_EQ(f2b.images.attachments.at("color").color, b2f.images.attachments.at("color").color);
  // The same trace on a tbr GPU (early-Z only) overshades back to front.
  const FrameResult tbr = run(s, {draw_of("far"), draw_of("mid"), draw_of("near")}, {"gpu.mode=tbr"});
  EXPECT_EQ(stat(tbr, "frame/tsp", "shaded_samples"), rasterised);
}

TEST(PipelineHsr, PunchThroughFlushesTagsAndWritesDepthAfterTheAlphaTest) {
  // An opaque quad at depth 5 behind a punch-through quad at depth 3, both covering the frame.
  // The mask kills the punch-through quad's left half (32 of 64 columns).
  Scene s = base_scene();
  add_quad(s, "wall", 5, -32, 96, 0);
  add_quad(s, "leaves", 3, -32, 96, 1);  // uv 0.5 at column 32: columns < 32 transparent
  const double tile = 32 * 32, frame = kSize * kSize;
  {
    // Opaque first: each of the 4 tiles holds 1024 wall tags when the leaves arrive; they pass the
    // depth test everywhere, so the wall's tags are flushed and shaded (1024 per tile; with one tag
    // buffer the first leaf triangle in a tile flushes the whole tile: 4 flushes), then the leaves
    // are shaded (4096) and write depth only on the right half.
    const FrameResult f = run(s, {draw_of("wall"), draw_of("leaves")}, {"isp.tag_buffers=1"});
    EXPECT_EQ(stat(f, "frame/isp", "tag_flushes"), 4);
    EXPECT_EQ(stat(f, "frame/isp", "tag_flushed_samples"), 4 * tile);
    EXPECT_EQ(stat(f, "frame/isp", "punch_through_samples"), frame);
    EXPECT_EQ(stat(f, "frame/tsp", "shader_invocations"), 2 * frame);
    EXPECT_EQ(stat(f, "frame/tsp", "alpha_test_killed_samples"), frame / 2);
    EXPECT_EQ(stat(f, "frame/tsp", "shaded_samples"), frame + frame / 2);
  }
  {
    // Punch-through first: the leaves wait as unresolved layers; the wall behind them needs their
    // alpha test, so each tile is flushed once (4 flushes, the ISP waits): the leaves are shaded
    // (4096) and write depth on the right half, so the wall fails the depth test there (2048)
    // and only its left half is shaded.
    const FrameResult f = run(s, {draw_of("leaves"), draw_of("wall")});
    EXPECT_EQ(stat(f, "frame/isp", "tag_flushes"), 4);
    EXPECT_EQ(stat(f, "frame/isp", "resolve_flushes"), 4);
    EXPECT_EQ(stat(f, "frame/isp", "depth_test_failed_samples"), frame / 2);
    EXPECT_EQ(stat(f, "frame/tsp", "shader_invocations"), frame + frame / 2);
    // Both orders give the same picture.
    const FrameResult g = run(s, {draw_of("wall"), draw_of("leaves")});
    EXPECT_EQ(f.images.attachments.at("color").color, g.images.attachments.at("color").color);
  }
}

TEST(PipelineHsr, TranslucentWaitsAsALayerWithTwoTagBuffers) {
  // far opaque quad (depth 5, whole frame), then glass (depth 2, columns [0,16)), then a near
  // opaque quad (depth 3, columns [16,64)).
  Scene s = base_scene();
  add_quad(s, "far", 5, -32, 96, 0);
  add_quad(s, "glass", 2, -32, 16, 2);
  add_quad(s, "near", 3, 16, 96, 0);
  const std::vector<DrawCmd> draws = {draw_of("far"), draw_of("glass", "blend"), draw_of("near")};
  // One tag buffer: in the two left tiles the glass forces a flush of all 1024 far tags, then the
  // glass (16x32 = 512) is shaded, then the near quad's 512 samples are shaded at the end of the
  // tile: 2048 per left tile. Right tiles: the near quad overwrites all far tags: 1024 each.
  const FrameResult one = run(s, draws, {"isp.tag_buffers=1"});
  EXPECT_EQ(stat(one, "frame/isp", "tag_flushes"), 2);
  EXPECT_EQ(stat(one, "frame/isp", "tag_flushed_samples"), 2 * 1024);
  EXPECT_EQ(stat(one, "frame/isp", "translucent_samples"), 2 * 512);
  EXPECT_EQ(stat(one, "frame/tsp", "blended_samples"), 2 * 512);
  EXPECT_EQ(stat(one, "frame/tsp", "shader_invocations"), 2 * 2048 + 2 * 1024);
  // Two tag buffers: the glass is a second layer over the far tags (no flush); the near quad
  // then clears the far tags of columns [16,32) before they are shaded: 512 far + 512 glass +
  // 512 near = 1536 per left tile.
  const FrameResult two = run(s, draws, {"isp.tag_buffers=2"});
  EXPECT_EQ(stat(two, "frame/isp", "tag_flushes"), 0);
  EXPECT_EQ(stat(two, "frame/isp", "tag_flushed_samples"), 0);
  EXPECT_EQ(stat(two, "frame/tsp", "shader_invocations"), 2 * 1536 + 2 * 1024);
  EXPECT_EQ(one.images.attachments.at("color").color, two.images.attachments.at("color").color);
}

TEST(PipelineHsr, BlendedQuadsBehindTheStoredDepthFailEverySampleTheyCoverAndAreNeverShaded) {
  // Light volumes' case: a first pass stores the depth of a wall (depth 3, whole frame); a second
  // pass loads it and draws two blended quads with the depth test on and no depth write: one behind
  // the wall (depth 5, columns [0,40)) and one in front of it (depth 2, columns [24,64)). In every
  // tile the one behind lies wholly beyond the tile's stored depth, so the ISP counts its samples
  // as failed without testing them one by one; the counts are those of the per-sample test.
  Scene s = base_scene();
  add_quad(s, "wall", 3, -32, 96, 0);
  add_quad(s, "behind", 5, -32, 40, 2);
  add_quad(s, "front", 2, 24, 96, 2);
  for (const int samples : {1, 4}) {
    Trace t = base_trace();
    PassDesc first = base_pass();
    first.name = "first";
    first.attachments[1].transient = false;
    first.attachments[1].store = StoreOp::Store;
    first.draws = {draw_of("wall")};
    PassDesc second = base_pass();
    second.name = "second";
    second.attachments[1].transient = false;
    second.attachments[1].load = LoadOp::Load;
    second.draws = {draw_of("behind", "blend"), draw_of("front", "blend")};
    for (PassDesc* p : {&first, &second}) {
      for (Attachment& a : p->attachments) a.samples = static_cast<std::uint32_t>(samples);
    }
    t.frame.samples = samples;
    t.commands = {first, second};
    const FrameResult f = simulate_frame(t, "synthetic.trace", s, resolve_config({}, {}).hw);
    const double column = kSize * samples;  // samples in one pixel column
    EXPECT_EQ(stat(f, "pass1.second/isp", "samples_rasterised"), 2 * 40 * column) << samples << "x";
    EXPECT_EQ(stat(f, "pass1.second/isp", "depth_test_failed_samples"), 40 * column) << samples << "x";
    EXPECT_EQ(stat(f, "pass1.second/isp", "translucent_samples"), 40 * column) << samples << "x";
    EXPECT_EQ(stat(f, "pass1.second/tsp", "blended_samples"), 40 * column) << samples << "x";
  }
}

TEST(PipelineWriteback, PlainForwardWritesColorOnceAndDepthNeverLeavesTheChip) {
  const Scene atrium = load_scene("atrium:1");
  TraceSetup setup;
  setup.scene = &atrium;
  setup.scene_spec = "atrium:1";
  setup.camera = atrium_viewpoint("entrance", atrium);
  LightSetSpec spec;
  spec.count = 32;
  setup.lights = generate_lights(atrium, spec);
  setup.width = 320;
  setup.height = 180;
  const Trace t = generate_trace("plain_forward", setup);
  const FrameResult f = simulate_frame(t, "pf.trace", atrium, resolve_config({}, {}).hw);
  EXPECT_EQ(f.dram.writes(DramClass::Color), 320u * 180u * 4u);
  EXPECT_EQ(f.dram.reads(DramClass::Color), 0u);
  EXPECT_EQ(f.dram.reads(DramClass::DepthStencil), 0u);
  EXPECT_EQ(f.dram.writes(DramClass::DepthStencil), 0u);
  EXPECT_GT(f.dram.writes(DramClass::ParameterBuffer), 0u);
  EXPECT_GT(f.dram.reads(DramClass::ParameterBuffer), 0u);
  EXPECT_GT(stat(f, "frame/isp", "tag_flushes"), 0) << "the atrium's cut-out foliage forces flushes";
  EXPECT_GT(stat(f, "frame/tsp", "alpha_test_killed_samples"), 0);
  EXPECT_GT(stat(f, "frame/isp", "translucent_samples"), 0) << "the atrium's glass is blended";
  // Framebuffer compression scales the color writeback.
  const FrameResult c = simulate_frame(t, "pf.trace", atrium, resolve_config({}, {"writeback.compression_ratio=0.5"}).hw);
  EXPECT_EQ(c.dram.writes(DramClass::Color), 320u * 180u * 2u);
}

TEST(PipelinePartialRender, SmallParameterBufferForcesPartialRendersWithDepthTraffic) {
  // An 80x80 grid of small quads (12800 triangles, 6561 vertices of 10 + 8x4 bytes in the
  // parameter buffer: about 280 KB) in front of a full-frame quad.
  const Scene s = partial_render_grid_scene();
  const std::vector<DrawCmd> draws = {draw_of("back"), draw_of("grid")};
  const FrameResult big = run(s, draws);
  const FrameResult small = run(s, draws, {"tiling.pb_capacity_bytes=65536"});
  EXPECT_EQ(stat(big, "frame/tiler", "partial_renders"), 0);
  EXPECT_GE(stat(small, "frame/tiler", "partial_renders"), 1);
  EXPECT_EQ(big.dram.writes(DramClass::DepthStencil), 0u);
  // Every tile a partial render stores (depth 4 B/pixel) is reloaded once by the next render.
  EXPECT_GT(small.dram.writes(DramClass::DepthStencil), 0u);
  EXPECT_EQ(small.dram.writes(DramClass::DepthStencil), small.dram.reads(DramClass::DepthStencil));
  EXPECT_EQ(small.dram.writes(DramClass::DepthStencil) % (32 * 32 * 4), 0u);
  EXPECT_EQ(stat(small, "frame/tile_memory", "partial_render_store_bytes"),
            static_cast<double>(small.dram.writes(DramClass::DepthStencil) * 2));  // depth + rgba8 color
  // Same picture; HSR cannot work across a partial render, so shading can only grow.
  EXPECT_EQ(big.images.attachments.at("color").color, small.images.attachments.at("color").color);
  EXPECT_GE(stat(small, "frame/tsp", "shaded_samples"), stat(big, "frame/tsp", "shaded_samples"));
  EXPECT_LE(stat(small, "frame/tiler", "pb_peak_allocated_bytes"), 65536);
}

TEST(PipelinePartialRender, TheRestOfADrawAfterAPartialRenderIsTheNextRendersGeometry) {
  // The geometry unit delivers the grid's triangles one at a time and the tiler bins each as it
  // arrives, so when the 64 KiB parameter buffer fills in the middle of the grid draw, the
  // partial render holds what was binned so far and the grid's remaining triangles are the next
  // render's geometry work, as on the hardware: every render has primitives in of its own (when
  // the whole draw went through geometry before binning, the first render had all 12802 and the
  // others none), and they add up to the back quad's 2 + the grid's 12800 triangles.
  const Scene s = partial_render_grid_scene();
  const FrameResult small = run(s, {draw_of("back"), draw_of("grid")}, {"tiling.pb_capacity_bytes=65536"});
  const auto& renders = small.work.commands.at(0).renders;
  ASSERT_GE(renders.size(), 3u);
  std::uint64_t in = 0, binned = 0;
  for (const RenderWork& r : renders) {
    EXPECT_GT(r.binning.primitives_in, 0u);
    EXPECT_GE(r.binning.primitives_in, r.binning.primitives_binned);
    in += r.binning.primitives_in;
    binned += r.binning.primitives_binned;
  }
  EXPECT_EQ(in, 2u + 12800u);
  EXPECT_EQ(static_cast<double>(binned), stat(small, "frame/tiler", "primitives_binned"));
}

TEST(PipelineTileMemory, OverBudgetPassSplitsTilesOrSpills) {
  Scene s = base_scene();
  add_quad(s, "wall", 5, -32, 96, 0);
  Trace t = base_trace();
  PassDesc p = base_pass();
  // 3 rgba16f G-buffer-like targets = 24 B/pixel against the default 16 B/pixel (128 bits).
  for (const char* name : {"g0", "g1"}) {
    Attachment a;
    a.name = name;
    a.format = Format::Rgba16f;
    a.usage = AttachmentUsage::Gbuffer;
    a.store = StoreOp::DontCare;
    a.transient = true;
    p.attachments.push_back(a);
  }
  p.attachments[0].format = Format::Rgba16f;
  p.draws = {draw_of("wall")};
  t.commands.push_back(p);
  const FrameResult split = simulate_frame(t, "t", s, resolve_config({}, {"pls.over_budget=smaller_tiles"}).hw);
  EXPECT_EQ(stat(split, "frame/tile_memory", "onchip_need_bytes_per_pixel"), 24);
  EXPECT_EQ(stat(split, "frame/tile_memory", "tile_split_factor"), 2);
  EXPECT_EQ(stat(split, "frame/isp", "tiles_rendered"), 8);  // 4 tiles x 2 strips
  const FrameResult fits = simulate_frame(t, "t", s, resolve_config({}, {"pls.tile_buffer_bits_per_pixel=256"}).hw);
  EXPECT_EQ(stat(fits, "frame/isp", "tiles_rendered"), 4);
  EXPECT_LT(fits.dram.reads(DramClass::ParameterBuffer), split.dram.reads(DramClass::ParameterBuffer));
  EXPECT_EQ(fits.dram.writes(DramClass::Spill), 0u);
  // Spill (the default): a third of the 24 B/pixel is over the 16 B budget, so a third of the
  // shader's tile buffer writes (4096 pixels x 8 B of its one rgba16f output) go to DRAM and are
  // read back at the end of the tile: 4 tiles x round(8192 / 3) = 4 x 2731 bytes each way.
  const FrameResult spill = simulate_frame(t, "t", s, resolve_config({}, {}).hw);
  EXPECT_EQ(stat(spill, "frame/isp", "tiles_rendered"), 4);
  EXPECT_EQ(spill.dram.writes(DramClass::Spill), 4u * 2731u);
  EXPECT_EQ(spill.dram.reads(DramClass::Spill), 4u * 2731u);
}

}  // namespace
}  // namespace tbdr

namespace tbdr {
namespace {

TEST(PipelineAlphaModes, AlphaBlendModeTestFlushesAndKillsAsItsMaterialsSay) {
  const std::string path = std::string(TBDRSIM_SCENES_DIR) + "/AlphaBlendModeTest/glTF/AlphaBlendModeTest.gltf";
  if (!std::filesystem::exists(path)) GTEST_SKIP() << "no " << path << " (../shared/scenes absent)";
  const Scene scene = load_scene(path);
  TraceSetup setup;
  setup.scene = &scene;
  setup.scene_spec = path;
  setup.camera = framing_camera(scene);
  setup.width = 320;
  setup.height = 180;
  const HwConfig hw = resolve_config({}, {"isp.tag_buffers=1"}).hw;
  // Plain forward draws the opaque bed and labels, then the three MASK quads, then the BLEND quad.
  // Every masked or blended fragment lands on the bed behind it, so it forces a flush of the tags
  // there (one tag buffer: the whole tile) before it is shaded; MASK samples below their cutoff are
  // killed; BLEND samples are shaded with blending and never write depth.
  const Trace pf = generate_trace("plain_forward", setup);
  const FrameResult f = simulate_frame(pf, path, scene, hw);
  EXPECT_GT(stat(f, "frame/isp", "tag_flushes"), 0);
  EXPECT_GT(stat(f, "frame/isp", "punch_through_samples"), 0);
  EXPECT_GT(stat(f, "frame/tsp", "alpha_test_killed_samples"), 0);
  EXPECT_GT(stat(f, "frame/isp", "translucent_samples"), 0);
  EXPECT_EQ(stat(f, "frame/tsp", "blended_samples"), stat(f, "frame/isp", "translucent_samples"));
  // The three MASK materials share one gradient mask with cutoffs 0.25, 0.5 and 0.75: drawn alone
  // over the bed, a higher cutoff must discard a larger share of the quad's samples.
  std::vector<double> killed_share;
  for (const char* material : {"MatCutoff25", "MatCutoffDefault", "MatCutoff75"}) {
    Trace t = pf;
    auto& pass = std::get<PassDesc>(t.commands[0]);
    std::vector<DrawCmd> draws;
    for (auto d : pass.draws) {
      if (d.subset == SceneSubset::Opaque) draws.push_back(d);
      if (d.subset == SceneSubset::Masked) {
        d.subset = SceneSubset::All;
        d.material = material;
        draws.push_back(d);
      }
    }
    pass.draws = draws;
    const FrameResult r = simulate_frame(t, path, scene, hw);
    const double pt = stat(r, "frame/isp", "punch_through_samples");
    ASSERT_GT(pt, 0) << material;
    killed_share.push_back(stat(r, "frame/tsp", "alpha_test_killed_samples") / pt);
  }
  EXPECT_LT(killed_share[0], killed_share[1]);
  EXPECT_LT(killed_share[1], killed_share[2]);
}

}  // namespace
}  // namespace tbdr
