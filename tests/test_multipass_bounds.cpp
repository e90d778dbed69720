// Draws bounded as a multi-pass renderer bounds them (issue 15): a draw's scissor rectangle and its
// object-culling box in the trace (version 3: reader checks, round trip, older versions refused),
// in the models (the geometry unit submits only the instances the box touches; the scissor cuts
// every primitive's pixel box at setup, so rasterisation and binning stay inside it), and in
// forward_multipass, whose additive passes draw only what their lights reach: the same image with
// fewer vertices and fragments.
#include <gtest/gtest.h>

#include <algorithm>
#include <memory>
#include <sstream>
#include <string>

#include "kernel/errors.hpp"
#include "models/command_processor.hpp"
#include "models/hw_config.hpp"
#include "models/rasterizer.hpp"
#include "scene/scene_library.hpp"
#include "stat_lookup.hpp"
#include "synthetic_scene.hpp"
#include "techniques/technique.hpp"
#include "trace/trace.hpp"
#include "trace_parse_errors.hpp"
#include "atrium_trace_setup.hpp"

namespace tbdr {
namespace {

// ---- trace: keys, checks, round trip, version ------------------------------------------------------

Trace parse(const std::string& text) { return testing_support::parse_text(text); }

/// A version-`version` trace of 12 lines whose line 12 is `draw` (a 64x64 frame, one light).
std::string with_draw(const std::string& draw, int version = kTraceVersion) {
  return "tbdrsim-trace " + std::to_string(version) + "\n" +              // 1
         "scene atrium detail=1\n"                                        // 2
         "frame width=64 height=64 samples=1\n"                           // 3
         "camera eye=0,0,5 target=0,0,0 up=0,1,0 fov_y_deg=60 near=0.1 far=100\n"
         "light point position=0,0,0 radius=1 color=1,1,1 intensity=1\n"  // 5
         "buffer lights bytes=48 traffic=light_data content=lights upload=yes\n"
         "shader s alu_ops=1 tex_fetches=0 varyings=0 light_alu_ops=1 light_source=all color_outputs=1\n"
         "pipeline p shader=s depth_test=yes depth_write=yes blend=off cull=back\n"  // 8
         "pass main\n"
         "  attachment color format=rgba8 samples=1 load=clear store=store usage=color\n"  // 10
         "  attachment depth format=d24s8 samples=1 load=clear store=dont_care usage=depth transient=yes\n"
         "  " + draw + "\n"  // 12
         "end\n";
}

void expect_error(const std::string& text, int line, const std::string& token) {
  testing_support::expect_trace_error(text, line, token);
}

const DrawCmd& only_draw(const Trace& t) { return std::get<PassDesc>(t.commands.front()).draws.front(); }

TEST(TraceDrawBounds, ScissorAndCullBoxReadAndRoundTrip) {
  const Trace t = parse(with_draw("draw scene pipeline=p subset=opaque scissor=3,4,60,33 cull_min=-1,-2.5,-3 cull_max=1,2,0.5", 3));
  EXPECT_EQ(t.version, 3);
  const DrawCmd& d = only_draw(t);
  ASSERT_TRUE(d.scissor && d.cull);
  EXPECT_EQ(*d.scissor, (ScissorRect{3, 4, 60, 33}));
  EXPECT_EQ(d.cull->min, glm::vec3(-1, -2.5f, -3));
  EXPECT_EQ(d.cull->max, glm::vec3(1, 2, 0.5f));
  const std::string text = trace_text(t);
  EXPECT_NE(text.find(" scissor=3,4,60,33 cull_min=-1,-2.5,-3 cull_max=1,2,0.5"), std::string::npos) << text;
  EXPECT_EQ(text.rfind("tbdrsim-trace 3\n", 0), 0u);
  const Trace again = parse(text);
  EXPECT_EQ(*only_draw(again).scissor, *d.scissor);
  EXPECT_EQ(*only_draw(again).cull, *d.cull);
  EXPECT_EQ(trace_text(again), text);
  // Without the keys a draw has neither, and the writer writes neither.
  const Trace plain = parse(with_draw("draw scene pipeline=p"));
  EXPECT_FALSE(only_draw(plain).scissor || only_draw(plain).cull);
  EXPECT_EQ(trace_text(plain).find("scissor"), std::string::npos);
  // A scissor on generated geometry; a scissor past the frame is kept as written (the simulator clamps).
  EXPECT_EQ(*only_draw(parse(with_draw("draw fullscreen pipeline=p scissor=0,0,16384,70"))).scissor,
            (ScissorRect{0, 0, 16384, 70}));
}

TEST(TraceDrawBounds, OlderVersionsReadButRefuseTheKeys) {
  EXPECT_EQ(parse(with_draw("draw scene pipeline=p", 1)).version, 1);
  EXPECT_EQ(parse(with_draw("draw scene pipeline=p", 2)).version, 2);
  expect_error(with_draw("draw scene pipeline=p scissor=0,0,8,8", 2), 12, "'scissor' needs trace version 3 (this trace is version 2)");
  expect_error(with_draw("draw scene pipeline=p cull_min=0,0,0 cull_max=1,1,1", 1), 12, "'cull_min' needs trace version 3");
  expect_error("tbdrsim-trace 6\n", 1, "trace version 6 is newer than this reader (5)");
}

TEST(TraceDrawBounds, MalformedBoundsAreRefusedAtTheirLine) {
  expect_error(with_draw("draw scene pipeline=p scissor=0,0,8"), 12, "malformed scissor '0,0,8'");
  expect_error(with_draw("draw scene pipeline=p scissor=0,0,8,8,8"), 12, "malformed scissor");
  expect_error(with_draw("draw scene pipeline=p scissor=0,0,8.5,8"), 12, "malformed number '8.5'");
  expect_error(with_draw("draw scene pipeline=p scissor=-1,0,8,8"), 12, "malformed number '-1'");
  expect_error(with_draw("draw scene pipeline=p scissor=0,0,16385,8"), 12, "out of range (0..16384)");
  expect_error(with_draw("draw scene pipeline=p scissor=8,0,8,8"), 12, "scissor '8,0,8,8' is empty");
  expect_error(with_draw("draw scene pipeline=p scissor=0,9,8,8"), 12, "is empty");
  expect_error(with_draw("draw scene pipeline=p cull_min=0,0,0"), 12, "cull_min without cull_max");
  expect_error(with_draw("draw scene pipeline=p cull_max=0,0,0"), 12, "cull_max without cull_min");
  expect_error(with_draw("draw scene pipeline=p cull_min=0,2,0 cull_max=1,1,1"), 12, "is above cull_max=1,1,1 in y");
  expect_error(with_draw("draw scene pipeline=p cull_min=0,0 cull_max=1,1,1"), 12, "malformed vector '0,0'");
  expect_error(with_draw("draw scene pipeline=p cull_min=-2e9,0,0 cull_max=1,1,1"), 12, "beyond +-1e+09");
  // The culling box selects scene instances: generated geometry has none.
  expect_error(with_draw("draw fullscreen pipeline=p cull_min=0,0,0 cull_max=1,1,1"), 12, "unknown key 'cull_min'");
}

// ---- models: the geometry unit's culling, the scissor at setup ---------------------------------------

using namespace synthetic;

FrameResult run_synthetic(const Scene& s, const std::vector<DrawCmd>& draws) {
  Trace t = base_trace();
  PassDesc p = base_pass();
  p.draws = draws;
  t.commands.push_back(p);
  return simulate_frame(t, "synthetic.trace", s, resolve_config({}, {}).hw);
}

DrawCmd all_of_scene() {
  DrawCmd d;
  d.pipeline = "opaque";
  return d;
}

TEST(GeometryCullBox, OnlyInstancesTouchingTheBoxAreSubmitted) {
  // Two quads at depth 3: "left" over columns [0, 16), "right" over [48, 64); 4 vertices and 2
  // triangles each (indices 0,1,2,0,2,3 through the post-transform cache: 4 shaded).
  Scene s = base_scene();
  add_quad(s, "left", 3, 0, 16, 0);
  add_quad(s, "right", 3, 48, 64, 0);
  DrawCmd whole = all_of_scene();
  const FrameResult both = run_synthetic(s, {whole});
  EXPECT_EQ(stat(both, "frame/geometry", "vertices_shaded"), 8);
  EXPECT_EQ(stat(both, "frame/geometry", "primitives_in"), 4);

  // A box around the left quad only (x from world_x(0) to world_x(16) at depth 3, z = -3).
  DrawCmd left = all_of_scene();
  left.cull = CullBox{{world_x(0, 3) - 0.01f, -10, -3.5f}, {world_x(16, 3) + 0.01f, 10, -2.5f}};
  const FrameResult one = run_synthetic(s, {left});
  EXPECT_EQ(stat(one, "frame/geometry", "draws"), 1);
  EXPECT_EQ(stat(one, "frame/geometry", "vertices_shaded"), 4);
  EXPECT_EQ(stat(one, "frame/geometry", "primitives_in"), 2);
  EXPECT_EQ(stat(one, "frame/geometry", "vertex_fetch_bytes"), 4 * 32);  // 4 vertices x 32-byte stride
  EXPECT_EQ(stat(one, "frame/geometry", "index_fetch_bytes"), 6 * 2);    // 6 indices x 2 bytes
  // 16 columns x 64 rows shaded, against 2 x 16 x 64 with both quads.
  EXPECT_EQ(stat(one, "frame/tsp", "shader_invocations"), 16 * 64);
  EXPECT_EQ(stat(both, "frame/tsp", "shader_invocations"), 2 * 16 * 64);

  // A box that touches the quads' plane only between them (columns 20..40 at depth 3): nothing.
  DrawCmd between = all_of_scene();
  between.cull = CullBox{{world_x(20, 3), -10, -3.5f}, {world_x(40, 3), 10, -2.5f}};
  const FrameResult none = run_synthetic(s, {between});
  EXPECT_EQ(stat(none, "frame/geometry", "draws"), 1);
  EXPECT_EQ(stat(none, "frame/geometry", "vertices_shaded"), 0);
  EXPECT_EQ(stat(none, "frame/geometry", "primitives_in"), 0);
  EXPECT_EQ(stat(none, "frame/tiler", "primitives_binned"), 0);
  // A box touching a quad's bounds at one face (closed boxes) keeps it: x up to exactly world_x(0).
  DrawCmd touching = all_of_scene();
  const float left_edge = s.submeshes[0].positions[0].x;  // world_x(0, 3): the left quad's smallest x
  touching.cull = CullBox{{left_edge - 1, -10, -3.5f}, {left_edge, 10, -2.5f}};
  EXPECT_EQ(stat(run_synthetic(s, {touching}), "frame/geometry", "vertices_shaded"), 4);
}

TEST(RasterizerScissor, SetupCutsThePixelBoxAndEverythingStaysInside) {
  const Viewport vp{64, 64, 8};
  // A triangle over the whole viewport (vertices far outside it).
  ScreenTriangle big;
  big.x_fixed = {-64 * 256, 192 * 256, -64 * 256};
  big.y_fixed = {-64 * 256, -64 * 256, 192 * 256};
  const SamplePattern one = standard_sample_pattern(1, 8);
  const TriangleSetup full = setup_triangle(big, vp);
  EXPECT_EQ(full.bbox, (PixelRect{0, 0, 64, 64}));
  const TriangleSetup cut = setup_triangle(big, vp, PixelRect{8, 4, 40, 20});
  ASSERT_FALSE(cut.empty);
  EXPECT_EQ(cut.bbox, (PixelRect{8, 4, 40, 20}));
  int visited = 0;
  rasterize_in_rect(cut, PixelRect{0, 0, 64, 64}, one, [&](int x, int y, std::uint32_t, const float*) {
    EXPECT_TRUE(x >= 8 && x < 40 && y >= 4 && y < 20) << x << "," << y;
    ++visited;
  });
  EXPECT_EQ(visited, 32 * 16);  // the whole rectangle is covered
  // 32x32 tiles: the rectangle touches tiles (0,0) and (1,0) only; without it, all 4.
  EXPECT_EQ(count_overlapped_tiles(cut, 32, 32, TileTest::Exact, one), 2);
  EXPECT_EQ(count_overlapped_tiles(full, 32, 32, TileTest::Exact, one), 4);
  EXPECT_FALSE(covers_any_sample(cut, PixelRect{40, 0, 64, 64}, one));
  // A scissor past the viewport is clamped to it; one outside it, or off the triangle, leaves nothing.
  EXPECT_EQ(setup_triangle(big, vp, PixelRect{32, 32, 1000, 1000}).bbox, (PixelRect{32, 32, 64, 64}));
  EXPECT_TRUE(setup_triangle(big, vp, PixelRect{64, 0, 100, 64}).empty);
  ScreenTriangle small;  // pixels [0, 8) x [0, 8)
  small.x_fixed = {0, 8 * 256, 0};
  small.y_fixed = {0, 0, 8 * 256};
  EXPECT_TRUE(setup_triangle(small, vp, PixelRect{16, 16, 32, 32}).empty);
}

TEST(RasterizerScissor, ADrawsScissorBoundsItsFragmentsAndBinning) {
  // A quad over the whole 64x64 frame (4 tiles of 32x32) drawn with scissor [8, 40) x [4, 20):
  // 32 x 16 = 512 samples rasterised and shaded instead of 4096, binned into the 2 top tiles.
  Scene s = base_scene();
  add_quad(s, "back", 6, -32, 96, 0);
  const FrameResult full = run_synthetic(s, {draw_of("back")});
  DrawCmd cut = draw_of("back");
  cut.scissor = ScissorRect{8, 4, 40, 20};
  const FrameResult scissored = run_synthetic(s, {cut});
  EXPECT_EQ(stat(full, "frame/isp", "samples_rasterised"), 64 * 64);
  EXPECT_EQ(stat(scissored, "frame/isp", "samples_rasterised"), 32 * 16);
  EXPECT_EQ(stat(scissored, "frame/tsp", "shader_invocations"), 32 * 16);
  // The vertices are submitted either way (the scissor works after the vertex shader).
  EXPECT_EQ(stat(scissored, "frame/geometry", "vertices_shaded"), stat(full, "frame/geometry", "vertices_shaded"));
  // The quad's corners are pixels (-32, 80) and (96, -16); its diagonal runs through row
  // 80 - 0.75 (x + 32): rows 50 to 26 over columns 8 to 40, below the rectangle's rows 4 to 20. So
  // only the upper-left triangle reaches the rectangle: 1 primitive binned, into the 2 top tiles.
  // Without the scissor both are binned, each into 3 or 4 tiles (exact binning): at least 6.
  EXPECT_EQ(stat(scissored, "frame/tiler", "primitives_binned"), 1);
  EXPECT_EQ(stat(scissored, "frame/tiler", "tile_references"), 2);
  EXPECT_EQ(stat(full, "frame/tiler", "primitives_binned"), 2);
  EXPECT_GE(stat(full, "frame/tiler", "tile_references"), 6);
  // Only pixels inside the rectangle were written: the colour outside keeps the clear value.
  const auto& color = scissored.images.attachments.at("color").color;
  for (int y = 0; y < kSize; ++y) {
    for (int x = 0; x < kSize; ++x) {
      const bool inside = x >= 8 && x < 40 && y >= 4 && y < 20;
      const glm::vec4 c = color[static_cast<std::size_t>(y * kSize + x)];
      EXPECT_EQ(inside, c != glm::vec4(0.0f)) << x << "," << y;
    }
  }
}

TEST(RasterizerScissor, TrianglesTheScissorRemovesAtSetupAreCounted) {
  // The 80x80 grid's 12800 small triangles drawn with scissor [0, 16) x [0, 16): every screen
  // triangle is either set up (primitives_out) or removed at setup because its pixel box misses
  // the rectangle (primitives_culled_scissor), so the two add up to the unscissored draw's
  // primitives_out, and the rectangle's 1/16 of the 64x64 frame leaves most of them removed.
  const Scene s = partial_render_grid_scene();
  const FrameResult full = run_synthetic(s, {draw_of("grid")});
  DrawCmd cut = draw_of("grid");
  cut.scissor = ScissorRect{0, 0, 16, 16};
  const FrameResult scissored = run_synthetic(s, {cut});
  EXPECT_EQ(stat(full, "frame/geometry", "primitives_culled_scissor"), 0);
  EXPECT_EQ(stat(scissored, "frame/geometry", "primitives_out") + stat(scissored, "frame/geometry", "primitives_culled_scissor"),
            stat(full, "frame/geometry", "primitives_out"));
  EXPECT_GT(stat(scissored, "frame/geometry", "primitives_culled_scissor"), stat(full, "frame/geometry", "primitives_out") / 2);
}

// ---- forward_multipass: bounded additive passes, the same image -----------------------------------

/// The atrium at detail 1, loaded once for the suite.
class MultipassBounds : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { scene_ = std::make_unique<Scene>(load_scene("atrium:1")); }
  static void TearDownTestSuite() { scene_.reset(); }
  static TraceSetup setup(int samples, const std::string& light_bounds, int lights_per_pass) {
    TraceSetup s = testing_support::atrium_entrance_setup(*scene_, kLights, 160, 96);
    s.samples = samples;
    s.options["light_bounds"] = light_bounds;
    s.options["lights_per_pass"] = std::to_string(lights_per_pass);
    return s;
  }
  static void expect_same_image_less_work(int samples, int per_pass);
  static constexpr int kLights = 24;
  inline static std::unique_ptr<Scene> scene_;
};

TEST_F(MultipassBounds, TheTraceBoundsEveryAdditivePassByItsLight) {
  const TraceSetup s = setup(1, "yes", 1);
  const Trace t = generate_trace("forward_multipass", s);
  EXPECT_EQ(t.options.at("light_bounds"), "yes");
  const PassDesc& pass = std::get<PassDesc>(t.commands.front());
  int additive = 0, visible = 0;
  for (std::uint32_t l = 1; l < kLights; ++l) visible += light_reach(t.lights[l], t.camera, 160, 96).visible ? 1 : 0;
  for (const DrawCmd& d : pass.draws) {
    if (d.pipeline != "additive") {
      EXPECT_FALSE(d.scissor || d.cull) << d.pipeline;  // the pre-pass, pass 0 and the glass: the whole frame
      continue;
    }
    ++additive;
    ASSERT_TRUE(d.cull);
    ASSERT_EQ(d.lights.ranges.size(), 1u);
    const std::uint32_t l = d.lights.ranges.front().first;
    const LightReach r = light_reach(t.lights[l], t.camera, 160, 96);
    EXPECT_TRUE(r.visible);
    EXPECT_EQ(*d.cull, r.box);
    EXPECT_EQ(d.scissor.has_value(), !r.full_frame);
    if (d.scissor) {
      EXPECT_EQ(*d.scissor, r.rect);
    }
    // The box holds the sphere with its margin: radius r + r/1024 + (max |c| + r) / 2^20 around c.
    const Light& light = t.lights[l];
    EXPECT_LT(d.cull->min.x, light.position.x - light.radius);
    EXPECT_GT(d.cull->max.y, light.position.y + light.radius);
    EXPECT_LT(d.cull->max.z - light.position.z, light.radius * 1.002f);
  }
  // One opaque and one masked draw per light (1..23) that reaches a visible pixel.
  EXPECT_EQ(additive, 2 * visible);
  // Both cases occur: lights in view, and lights behind the camera or beside the frame (not drawn).
  EXPECT_GT(visible, 0);
  EXPECT_LT(visible, kLights - 1);
  // The old form draws every light's pass over everything.
  const Trace old = generate_trace("forward_multipass", setup(1, "no", 1));
  const auto& old_draws = std::get<PassDesc>(old.commands.front()).draws;
  EXPECT_EQ(std::count_if(old_draws.begin(), old_draws.end(), [](const DrawCmd& d) { return d.pipeline == "additive"; }),
            2 * (kLights - 1));
  for (const DrawCmd& d : old_draws) EXPECT_FALSE(d.scissor || d.cull);
}

TEST(LightReach, RectangleAndBoxOfASphere) {
  // Camera at the origin looking down -z, 90 degree field of view, 100 x 100 pixels: a point
  // (x, y, -d) lands at pixel ((x/d + 1) * 50, (1 - y/d) * 50).
  Camera cam;
  cam.eye = {0, 0, 0};
  cam.target = {0, 0, -1};
  cam.fov_y_deg = 90;
  cam.near_plane = 0.5f;
  cam.far_plane = 100;
  Light l;
  l.position = {0, 0, -10};
  l.radius = 1;
  const LightReach r = light_reach(l, cam, 100, 100);
  ASSERT_TRUE(r.visible);
  EXPECT_FALSE(r.full_frame);
  // The view box's nearest face (z = -9) spans x, y in [-1, 1]: pixels 50 -+ 50/9 = 44.44 .. 55.56;
  // floor/ceil and one pixel of margin: [43, 57).
  EXPECT_EQ(r.rect, (ScissorRect{43, 43, 57, 57}));
  EXPECT_EQ(r.box.min.x, -r.box.max.x);
  EXPECT_GT(r.box.max.x, 1.0f);
  EXPECT_LT(r.box.max.x, 1.0f + 2.0f / 1024.0f);
  // Crossing the near plane (or holding the eye): the whole frame.
  l.position = {0, 0, -1};
  EXPECT_TRUE(light_reach(l, cam, 100, 100).full_frame);
  EXPECT_EQ(light_reach(l, cam, 100, 100).rect, (ScissorRect{0, 0, 100, 100}));
  // Wholly behind the near plane, or beside the frame: reaches no pixel.
  l.position = {0, 0, 2};
  EXPECT_FALSE(light_reach(l, cam, 100, 100).visible);
  l.position = {30, 0, -10};  // x/d from 29/11 to 31/9: right of the frame (x/d <= 1)
  EXPECT_FALSE(light_reach(l, cam, 100, 100).visible);
}

/// A frame's colour: its final target's samples (rgba8 values as the simulator holds them).
std::vector<glm::vec4> final_color(const FrameResult& f) { return f.images.attachments.at(f.final_color).color; }

/// forward_multipass with and without light bounds at `samples` and `per_pass` lights per pass:
/// the same colour, bit for bit, with fewer vertices, fragments and light evaluations, bounded by
/// what the lights reach (the arithmetic in the comments).
void MultipassBounds::expect_same_image_less_work(int samples, int per_pass) {
  const HwConfig hw = resolve_config({}, {}).hw;
  const Trace yes_trace = generate_trace("forward_multipass", setup(samples, "yes", per_pass));
  const FrameResult yes = simulate_frame(yes_trace, "yes", *scene_, hw);
  const FrameResult no = simulate_frame(generate_trace("forward_multipass", setup(samples, "no", per_pass)), "no", *scene_, hw);
  const FrameResult one = simulate_frame(generate_trace("forward_multipass", setup(samples, "no", kLights)), "one", *scene_, hw);
  // Bit for bit the same colour: the passes' parts left out would have added exactly 0.
  const auto a = final_color(yes), b = final_color(no);
  ASSERT_EQ(a.size(), b.size());
  std::size_t differing = 0;
  for (std::size_t i = 0; i < a.size(); ++i) differing += a[i] != b[i] ? 1 : 0;
  EXPECT_EQ(differing, 0u);

  // Vertices: the unbounded form shades the whole scene, V, per draw pair: the pre-pass, B passes,
  // and the glass Vt once: (1 + B) V + Vt; with one batch 2 V + Vt. The bounded form: 2 V + Vt
  // and at most V for each of its `visible` additive passes (the instances their box touches).
  const int batches = (kLights + per_pass - 1) / per_pass;
  const double v_no = stat(no, "frame/geometry", "vertices_shaded");
  const double v_one = stat(one, "frame/geometry", "vertices_shaded");
  const double v_scene = (v_no - v_one) / (batches - 1);
  const double v_glass = v_one - 2 * v_scene;
  const auto& draws = std::get<PassDesc>(yes_trace.commands.front()).draws;
  const auto visible = static_cast<double>(
      std::count_if(draws.begin(), draws.end(), [](const DrawCmd& d) { return d.pipeline == "additive"; }) / 2);
  const double v_yes = stat(yes, "frame/geometry", "vertices_shaded");
  std::printf("[ bounds   ] %dx, %d per pass: vertices %.0f bounded, %.0f unbounded (scene %.0f, glass %.0f; %.0f of %d "
              "additive passes drawn)\n",
              samples, per_pass, v_yes, v_no, v_scene, v_glass, visible, batches - 1);
  EXPECT_LE(v_yes, (2 + visible) * v_scene + v_glass);
  EXPECT_GE(v_yes, 2 * v_scene + v_glass);
  EXPECT_LT(v_yes, v_no);

  // Fragments: the additive passes' invocations (the frame's less the one-batch frame's, whose
  // pre-pass, pass 0 and glass shade the same samples) stay inside their rectangles: at most the
  // sum of their areas in samples (the equal test passes one surface per sample, but for the
  // scene's few coplanar faces, shaded twice in both forms: 1 % allowed).
  double rect_samples = 0;
  for (const DrawCmd& d : draws) {
    if (d.pipeline != "additive" || d.subset != SceneSubset::Opaque) continue;
    const ScissorRect r = d.scissor.value_or(ScissorRect{0, 0, static_cast<std::uint32_t>(yes_trace.frame.width),
                                                         static_cast<std::uint32_t>(yes_trace.frame.height)});
    rect_samples += static_cast<double>((r.x1 - r.x0) * (r.y1 - r.y0)) * samples;
  }
  const double f_one = stat(one, "frame/tsp", "shader_invocations");
  const double f_yes = stat(yes, "frame/tsp", "shader_invocations") - f_one;
  const double f_no = stat(no, "frame/tsp", "shader_invocations") - f_one;
  std::printf("[ bounds   ] additive fragments %.0f bounded (rectangles: %.0f samples), %.0f unbounded\n", f_yes,
              rect_samples, f_no);
  EXPECT_LE(f_yes, rect_samples * 1.01);
  EXPECT_LT(f_yes, f_no);
  EXPECT_LT(stat(yes, "frame/tsp", "light_evaluations"), stat(no, "frame/tsp", "light_evaluations"));
  EXPECT_LT(stat(yes, "frame/tiler", "primitives_binned"), stat(no, "frame/tiler", "primitives_binned"));
}

TEST_F(MultipassBounds, OneLightPerPassSameImageLessWork) { expect_same_image_less_work(1, 1); }
TEST_F(MultipassBounds, BatchesOfLightsSameImageLessWork) { expect_same_image_less_work(1, 5); }
TEST_F(MultipassBounds, MsaaSameImageLessWork) { expect_same_image_less_work(4, 1); }

}  // namespace
}  // namespace tbdr
