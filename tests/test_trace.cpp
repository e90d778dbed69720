// Tests of the command trace: data model helpers, strict reader errors (file:line + token),
// canonical writer round trips, hashing, the technique registry and the plain forward generator.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "kernel/errors.hpp"
#include "trace/trace.hpp"
#include "trace_parse_errors.hpp"
#include "techniques/technique.hpp"

namespace tbdr {
namespace {

// A complete hand-written trace using every command and most keys.
const char* const kComplete = R"(tbdrsim-trace 1
# A complete hand-written trace: every command.
technique hand_written note="two passes" level=3
scene gltf path="scenes/my scene.gltf" hash=0123456789abcdef
frame width=640 height=360 samples=1
camera eye=0,1.5,5 target=0,1,0 up=0,1,0 fov_y_deg=60 near=0.1 far=100 name=entrance

light point position=1,2,3 radius=2.5 color=1,0.5,0.25 intensity=2
light spot position=-1,3,0 radius=4 color=1,1,1 intensity=1 direction=0,-1,0 cos_inner=0.9 cos_outer=0.8
light point position=0,0.5,-2 radius=1e-3 color=0.1,0.2,0.3 intensity=0.5   # trailing comment

buffer lights bytes=144 traffic=light_data content=lights upload=yes
buffer tile_grid bytes=7200 traffic=light_lists content=tile_grid
buffer light_index bytes=65536 traffic=light_lists content=light_index_list
shader gbuffer alu_ops=10 tex_fetches=2 varyings=8 light_alu_ops=0 light_source=none color_outputs=3 pls=none discard=no
shader gbuffer_masked alu_ops=11 tex_fetches=2 varyings=8 light_alu_ops=0 light_source=none color_outputs=3 discard=yes
shader tiled_resolve alu_ops=8 tex_fetches=3 varyings=2 light_alu_ops=14 light_source=tile_list color_outputs=1
shader proxy_accum alu_ops=6 tex_fetches=0 varyings=4 light_alu_ops=12 light_source=proxy color_outputs=0 pls=read_write
pipeline gbuffer shader=gbuffer depth_test=yes depth_write=yes blend=off cull=back
pipeline gbuffer_masked shader=gbuffer_masked depth_test=yes depth_write=yes depth_compare=less_equal blend=off cull=none alpha=punch_through
pipeline resolve shader=tiled_resolve depth_test=no depth_write=no blend=off cull=none
pipeline volumes shader=proxy_accum depth_test=yes depth_write=no depth_compare=greater_equal stencil_test=yes stencil_compare=equal stencil_fail_op=keep stencil_depth_fail_op=incr_wrap stencil_pass_op=keep stencil_ref=1 blend=add cull=front

pass gbuffer
  attachment albedo format=rgba8 samples=1 load=clear store=store usage=gbuffer
  attachment normal format=rgb10a2 samples=1 load=clear store=store usage=gbuffer
  attachment depth format=d24s8 samples=1 load=clear store=store usage=depth
  attachment ids format=rg32ui samples=1 load=dont_care store=dont_care usage=visibility transient=yes
  draw scene pipeline=gbuffer subset=opaque
  draw scene pipeline=gbuffer_masked material="leaf #2"
  draw scene pipeline=gbuffer submesh=floor
end
barrier resources=depth
dispatch tile_light_cull groups=40,23,1 group_size=16,16,1 reads=depth,lights writes=tile_grid,light_index tile_px=16 max_lights_per_tile=256
barrier resources=all
pass lighting
  attachment color format=r11g11b10f samples=1 load=dont_care store=store usage=color
  attachment depth format=d24s8 samples=1 load=load store=dont_care usage=depth
  pls accum format=r11g11b10f
  pls spare format=r32ui
  draw fullscreen pipeline=resolve reads=albedo,normal,tile_grid,light_index,lights fetch=depth
  draw light_spheres pipeline=volumes subdivisions=2 lights=2,0 fetch=depth
  draw light_quads pipeline=volumes lights=none
end
)";

/// The reader on `text` (tests/trace_parse_errors.hpp).
Trace parse(const std::string& text, const std::string& name = "t.trace") { return testing_support::parse_text(text, name); }

std::string write(const Trace& t) { return trace_text(t); }

// Expects parsing `text` to throw an InputError at `line` whose message contains `token`.
void expect_error(const std::string& text, int line, const std::string& token) {
  testing_support::expect_trace_error(text, line, token);
}

// A valid prefix of 12 lines (declarations + an open pass) to append error cases to.
std::string base(const std::vector<std::pair<int, std::string>>& replacements = {}) {
  std::vector<std::string> lines = {
      "tbdrsim-trace 1",
      "scene atrium detail=1",
      "frame width=64 height=64 samples=1",
      "camera eye=0,0,5 target=0,0,0 up=0,1,0 fov_y_deg=60 near=0.1 far=100",
      "light point position=0,0,0 radius=1 color=1,1,1 intensity=1",
      "buffer lights bytes=48 traffic=light_data content=lights upload=yes",
      "buffer grid bytes=64 traffic=light_lists content=tile_grid",
      "shader s alu_ops=1 tex_fetches=0 varyings=0 light_alu_ops=1 light_source=all color_outputs=1",
      "pipeline p shader=s depth_test=yes depth_write=yes blend=off cull=back",
      "pass main",
      "  attachment color format=rgba8 samples=1 load=clear store=store usage=color",
      "  attachment depth format=d24s8 samples=1 load=clear store=dont_care usage=depth transient=yes",
  };
  for (const auto& [at, text] : replacements) lines.at(static_cast<std::size_t>(at - 1)) = text;
  std::string out;
  for (const auto& l : lines) out += l + "\n";
  return out;
}

// ---- data model ------------------------------------------------------------------------------------

TEST(TraceModel, EnumsRoundTripThroughTheirSpelling) {
  for (int i = 0; i <= static_cast<int>(Format::D32fs8); ++i) {
    const auto f = static_cast<Format>(i);
    ASSERT_EQ(parse_format(to_string(f)), f) << to_string(f);
  }
  for (int i = 0; i <= static_cast<int>(LightSource::PlsStack); ++i)
    EXPECT_EQ(parse_light_source(to_string(static_cast<LightSource>(i))), static_cast<LightSource>(i));
  for (int i = 0; i <= static_cast<int>(StencilOp::DecrWrap); ++i)
    EXPECT_EQ(parse_stencil_op(to_string(static_cast<StencilOp>(i))), static_cast<StencilOp>(i));
  for (int i = 0; i <= static_cast<int>(BufferContent::Other); ++i)
    EXPECT_EQ(parse_buffer_content(to_string(static_cast<BufferContent>(i))), static_cast<BufferContent>(i));
  EXPECT_EQ(parse_compare_op("greater_equal"), CompareOp::GreaterEqual);
  EXPECT_EQ(parse_load_op("dont_care"), LoadOp::DontCare);
  EXPECT_EQ(parse_blend_mode("alpha"), BlendMode::Alpha);
  EXPECT_FALSE(parse_format("rgba9").has_value());
  EXPECT_FALSE(parse_cull_mode("Back").has_value());  // case-sensitive
}

TEST(TraceModel, BytesPerSample) {
  EXPECT_EQ(bytes_per_sample(Format::Rgba8), 4u);
  EXPECT_EQ(bytes_per_sample(Format::Rgb10a2), 4u);
  EXPECT_EQ(bytes_per_sample(Format::R11g11b10f), 4u);
  EXPECT_EQ(bytes_per_sample(Format::Rgba16f), 8u);
  EXPECT_EQ(bytes_per_sample(Format::R32ui), 4u);
  EXPECT_EQ(bytes_per_sample(Format::Rg32ui), 8u);
  EXPECT_EQ(bytes_per_sample(Format::D24s8), 4u);
  EXPECT_EQ(bytes_per_sample(Format::D32f), 4u);
  EXPECT_TRUE(is_depth_format(Format::D32f));
  EXPECT_FALSE(is_depth_format(Format::R32f));
  EXPECT_TRUE(has_stencil(Format::D24s8));
  EXPECT_FALSE(has_stencil(Format::D32f));
}

TEST(TraceModel, LightSelectionCounts) {
  LightSelection s;
  EXPECT_EQ(s.count(10), 10u);
  s.all = false;
  EXPECT_TRUE(s.empty());
  s.ranges = {{0, 2}, {5, 5}, {8, 20}};
  EXPECT_EQ(s.count(10), 3u + 1u + 2u);
  EXPECT_TRUE(s.contains(5));
  EXPECT_FALSE(s.contains(4));
}

// ---- reader and writer round trips ------------------------------------------------------------------

TEST(TraceRoundTrip, HandWrittenCompleteTrace) {
  const Trace t = parse(kComplete);
  EXPECT_EQ(t.version, 1);
  EXPECT_EQ(t.technique, "hand_written");
  EXPECT_EQ(t.options.at("note"), "two passes");
  EXPECT_EQ(t.scene.kind, SceneKind::Gltf);
  EXPECT_EQ(t.scene.path, "scenes/my scene.gltf");
  EXPECT_EQ(t.scene.content_hash, "0123456789abcdef");
  EXPECT_EQ(t.frame.width, 640);
  EXPECT_EQ(t.camera.eye, glm::vec3(0.0f, 1.5f, 5.0f));
  EXPECT_EQ(t.camera.near_plane, 0.1f);
  EXPECT_EQ(t.camera_name, "entrance");
  ASSERT_EQ(t.lights.size(), 3u);
  EXPECT_EQ(t.lights[1].type, Light::Type::Spot);
  EXPECT_EQ(t.lights[1].cos_outer, 0.8f);
  EXPECT_EQ(t.lights[2].radius, 1e-3f);
  EXPECT_EQ(t.light_lines, (std::vector<int>{8, 9, 10}));
  ASSERT_EQ(t.commands.size(), 5u);

  const auto& gbuffer = std::get<PassDesc>(t.commands[0]);
  EXPECT_EQ(gbuffer.line, 24);
  EXPECT_EQ(gbuffer.end_line, 32);
  ASSERT_EQ(gbuffer.attachments.size(), 4u);
  EXPECT_TRUE(gbuffer.attachments[3].transient);
  EXPECT_EQ(gbuffer.color_targets().size(), 3u);
  ASSERT_EQ(gbuffer.draws.size(), 3u);
  EXPECT_EQ(gbuffer.draws[1].material, "leaf #2");
  EXPECT_EQ(gbuffer.draws[1].line, 30);
  EXPECT_EQ(gbuffer.draws[2].submesh, "floor");

  const auto& barrier = std::get<BarrierCmd>(t.commands[1]);
  EXPECT_FALSE(barrier.all);
  EXPECT_EQ(barrier.resources, std::vector<std::string>{"depth"});
  const auto& dispatch = std::get<DispatchCmd>(t.commands[2]);
  EXPECT_EQ(dispatch.kernel, ComputeKernel::TileLightCull);
  EXPECT_EQ(dispatch.line, 34);
  EXPECT_EQ(dispatch.group_count(), 40u * 23u);
  EXPECT_EQ(dispatch.params.at("tile_px"), "16");
  EXPECT_EQ(dispatch.params.size(), 2u);
  EXPECT_TRUE(std::get<BarrierCmd>(t.commands[3]).all);

  const auto& lighting = std::get<PassDesc>(t.commands[4]);
  EXPECT_EQ(lighting.pls_bytes_per_pixel(), 8u);
  ASSERT_EQ(lighting.draws.size(), 3u);
  EXPECT_EQ(lighting.draws[0].fetch, std::vector<std::string>{"depth"});
  EXPECT_EQ(lighting.draws[1].geometry, GeometryKind::LightSpheres);
  EXPECT_EQ(lighting.draws[1].subdivisions, 2u);
  EXPECT_EQ(lighting.draws[1].lights.count(3), 2u);  // "2,0" sorted to 0,2
  EXPECT_TRUE(lighting.draws[2].lights.empty());
  const auto* volumes = t.find_pipeline("volumes");
  ASSERT_NE(volumes, nullptr);
  EXPECT_EQ(volumes->stencil_depth_fail_op, StencilOp::IncrWrap);
  EXPECT_EQ(volumes->cull, CullMode::Front);

  // write -> read -> write gives identical bytes.
  const std::string once = write(t);
  const std::string twice = write(parse(once));
  EXPECT_EQ(once, twice);
  EXPECT_NE(once.find("lights=0,2"), std::string::npos);
  EXPECT_NE(once.find("path=\"scenes/my scene.gltf\""), std::string::npos);
}

TEST(TraceRoundTrip, FloatsRoundTripExactly) {
  const float values[] = {0.1f, 1.0f / 3.0f, 1e-7f, 123456.789f, -0.0f, 3.40282e38f, 1.17549e-38f, 7.0f};
  Trace t = parse(base() + "end\n");
  for (float v : values) {  // one light per value, the value in several fields
    Light l;
    // Positions are bounded (kMaxWorldCoordinate); color and intensity take the whole float range.
    if (std::abs(v) <= kMaxWorldCoordinate) l.position = glm::vec3(v, -v, v * 0.5f);
    l.color = glm::vec3(std::abs(v), std::abs(v) * 0.5f, 0.0f);
    l.intensity = std::abs(v);
    t.lights.push_back(l);
  }
  for (auto& b : t.buffers)  // the light buffer grows with the lights (the reader checks 48 bytes each)
    if (b.content == BufferContent::Lights) b.bytes = kLightBufferBytesPerLight * t.lights.size();
  const Trace back = parse(write(t));
  ASSERT_EQ(back.lights.size(), t.lights.size());
  for (std::size_t i = 0; i < t.lights.size(); ++i) {
    EXPECT_EQ(back.lights[i].position, t.lights[i].position);
    EXPECT_EQ(back.lights[i].color, t.lights[i].color);
    EXPECT_EQ(back.lights[i].intensity, t.lights[i].intensity);
  }
  EXPECT_EQ(write(back), write(t));
}

TEST(TraceRoundTrip, FileReadWrite) {
  const Trace t = parse(kComplete);
  const std::string path = ::testing::TempDir() + "trace_roundtrip.trace";
  write_trace_file(t, path);
  const Trace back = read_trace(path);
  EXPECT_EQ(write(back), write(t));
  std::remove(path.c_str());
  try {
    read_trace(path);
    ADD_FAILURE() << "reading a missing file did not throw";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), path);
  }
}

TEST(TraceRoundTrip, HashIdentifiesCanonicalText) {
  const Trace a = parse(kComplete);
  Trace b = parse(write(a));
  EXPECT_EQ(trace_hash(a), trace_hash(b));
  EXPECT_EQ(trace_hash(a).size(), 16u);
  b.frame.width = 641;
  EXPECT_NE(trace_hash(a), trace_hash(b));
}

// ---- a pass over the image a dispatch wrote (version 2) ----------------------------------------------

// A G-buffer pass and a shading dispatch writing the image buffer `frame` (64 x 64 x 4 B): lines 1-16.
const std::string kImageHead =
    "scene atrium detail=1\n"
    "frame width=64 height=64 samples=1\n"
    "camera eye=0,0,5 target=0,0,0 up=0,1,0 fov_y_deg=60 near=0.1 far=100\n"
    "light point position=0,0,0 radius=1 color=1,1,1 intensity=1\n"
    "buffer lights bytes=48 traffic=light_data content=lights upload=yes\n"
    "buffer frame bytes=16384 traffic=color content=image\n"
    "shader s alu_ops=1 tex_fetches=0 varyings=0 light_alu_ops=0 light_source=none color_outputs=1\n"
    "pipeline p shader=s depth_test=yes depth_write=no blend=alpha cull=none\n"
    "pass gbuffer\n"
    "  attachment albedo format=rgba8 samples=1 load=clear store=store usage=gbuffer\n"
    "  attachment depth format=d24s8 samples=1 load=clear store=store usage=depth\n"
    "  draw fullscreen pipeline=p\n"
    "end\n"
    "barrier resources=albedo,depth\n"
    "dispatch deferred_shade groups=4,4,1 group_size=16,16,1 reads=albedo,depth,lights writes=frame shader=s\n";
// A pass whose color attachment is that image (first line given).
std::string image_pass(const std::string& attachment) {
  return "pass translucent\n" + attachment + "\n" +
         "  attachment depth format=d24s8 samples=1 load=load store=dont_care usage=depth\n"
         "  draw fullscreen pipeline=p\n"
         "end\n";
}
const std::string kImageAttachment = "  attachment frame format=rgba8 samples=1 load=load store=store usage=color";

TEST(TraceImageAttachments, APassLoadsTheImageADispatchWrote) {
  const std::string text = "tbdrsim-trace 2\n" + kImageHead + "barrier resources=frame\n" + image_pass(kImageAttachment);
  const Trace t = parse(text);
  EXPECT_EQ(t.version, 2);
  const auto& pass = std::get<PassDesc>(t.commands.back());
  EXPECT_EQ(pass.attachments[0].name, "frame");
  EXPECT_EQ(t.find_buffer("frame")->content, BufferContent::Image);
  EXPECT_EQ(write(parse(write(t))), write(t));
  // An earlier pass may already have used the image (not storing it): the dispatch's write counts.
  std::string earlier = kImageHead;
  const std::string albedo = "  attachment albedo format=rgba8 samples=1 load=clear store=store usage=gbuffer\n";
  earlier.replace(earlier.find(albedo), albedo.size(),
                  albedo + "  attachment frame format=rgba8 samples=1 load=clear store=dont_care usage=color\n");
  EXPECT_NO_THROW(parse("tbdrsim-trace 2\n" + earlier + "barrier resources=frame\n" + image_pass(kImageAttachment)));
}

TEST(TraceImageAttachments, TheImageIsAnRgba8FrameWrittenBeforeABarrierInVersion2) {
  const std::string v2 = "tbdrsim-trace 2\n" + kImageHead;
  // Line 17 is the barrier (or the pass), the attachment follows the pass line.
  expect_error(v2 + image_pass(kImageAttachment), 18, "no barrier in between");
  expect_error("tbdrsim-trace 1\n" + kImageHead + "barrier resources=frame\n" + image_pass(kImageAttachment), 19,
               "needs trace version 2");
  expect_error(v2 + "barrier resources=frame\n" +
                   image_pass("  attachment frame format=rgba16f samples=1 load=load store=store usage=color"),
               19, "must be format=rgba8 samples=1 usage=color");
  expect_error(v2 + "barrier resources=frame\n" +
                   image_pass("  attachment frame format=rgba8 samples=1 load=load store=store usage=gbuffer"),
               19, "must be format=rgba8 samples=1 usage=color");
  expect_error("tbdrsim-trace 2\n" + kImageHead.substr(0, kImageHead.find("buffer frame")) +
                   "buffer frame bytes=4096 traffic=color content=image\n" +
                   kImageHead.substr(kImageHead.find("shader s")) + "barrier resources=frame\n" + image_pass(kImageAttachment),
               19, "16384 bytes");
  // Any other buffer's name stays taken.
  expect_error(v2 + "barrier resources=frame\n" +
                   image_pass("  attachment lights format=rgba8 samples=1 load=clear store=store usage=color"),
               19, "already a buffer");
}

// ---- reader errors: file:line and the offending token ------------------------------------------------

TEST(TraceErrors, UnknownVersionIsRefused) {
  try {
    parse("tbdrsim-trace 7\n");
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()).rfind("t.trace:1: trace version 7 is newer than this reader (5)", 0), 0u)
        << e.what();
  }
  expect_error("tbdrsim-trace 0\n", 1, "'0'");
  expect_error("tbdrsim-trace one\n", 1, "'one'");
  expect_error("# comment first\ntbdrsim-trace 1\n", 1, "tbdrsim-trace");
  expect_error("", 1, "empty file");
  expect_error("tbdrsim-trace 1\ntbdrsim-trace 1\n", 2, "'tbdrsim-trace'");
}

TEST(TraceErrors, UnknownCommandAndKey) {
  expect_error(base() + "  drow scene pipeline=p\nend\n", 13, "'drow'");
  expect_error(base() + "  draw scene pipeline=p colour=red\nend\n", 13, "'colour'");
  expect_error(base({{3, "frame width=64 height=64 samples=1 depth=2"}}), 3, "'depth'");
  expect_error(base() + "  draw scene pipeline=p pipeline=p\nend\n", 13, "duplicate key 'pipeline'");
  expect_error(base() + "  draw scene pipeline=p subset=opaque extra\nend\n", 13, "'extra'");
  expect_error(base() + "  draw scene pipeline=\nend\n", 13, "empty value for key 'pipeline'");
  expect_error(base() + "  draw teapot pipeline=p\nend\n", 13, "'teapot'");
  expect_error(base() + "  draw scene pipeline=p subset=translucent\nend\n", 13, "'translucent'");
  expect_error(base({{11, "  attachment color format=rgba9 samples=1 load=clear store=store usage=color"}}), 11, "'rgba9'");
}

TEST(TraceErrors, MalformedNumbers) {
  expect_error(base({{3, "frame width=1.5x height=64 samples=1"}}), 3, "'1.5x'");
  expect_error(base({{3, "frame width=64 height=-64 samples=1"}}), 3, "'-64'");
  expect_error(base({{3, "frame width=64 height=64 samples=3"}}), 3, "'3'");
  expect_error(base({{5, "light point position=0,0,0 radius=nan color=1,1,1 intensity=1"}}), 5, "'nan'");
  expect_error(base({{5, "light point position=0,0,0 radius=inf color=1,1,1 intensity=1"}}), 5, "'inf'");
  expect_error(base({{5, "light point position=0,0,0 radius=1.0f color=1,1,1 intensity=1"}}), 5, "'1.0f'");
  expect_error(base({{5, "light point position=0,0 radius=1 color=1,1,1 intensity=1"}}), 5, "'0,0'");
  expect_error(base({{5, "light point position=0,0,0,0 radius=1 color=1,1,1 intensity=1"}}), 5, "'0,0,0,0'");
}

TEST(TraceErrors, MissingRequiredKey) {
  expect_error(base({{11, "  attachment color samples=1 load=clear store=store usage=color"}}), 11, "'format'");
  expect_error(base({{8, "shader s alu_ops=1 tex_fetches=0 varyings=0 light_source=all color_outputs=1"}}), 8,
               "'light_alu_ops'");
  expect_error(base({{2, "scene gltf path=x.gltf"}}), 2, "'hash'");
  expect_error(base() + "end\ndispatch depth_bounds groups=1,1,1\n", 14, "'group_size'");
}

TEST(TraceErrors, DuplicateNames) {
  expect_error(base({{9, "shader s alu_ops=2 tex_fetches=0 varyings=0 light_alu_ops=0 light_source=none color_outputs=0"}}) +
                   "end\n",
               9, "'s'");
  expect_error(base() + "  attachment color format=rgba8 samples=1 load=clear store=store usage=color\nend\n", 13,
               "'color'");
  expect_error(base() + "end\npass main\n", 14, "'main'");
  expect_error(base({{7, "buffer lights bytes=64 traffic=light_lists content=tile_grid"}}), 7, "'lights'");
  expect_error(base() + "  pls a format=r32ui\n  pls a format=r32ui\nend\n", 14, "'a'");
}

TEST(TraceErrors, UndeclaredReferences) {
  expect_error(base({{9, "pipeline p shader=nope depth_test=yes depth_write=yes blend=off cull=back"}}), 9, "'nope'");
  expect_error(base() + "  draw scene pipeline=q\nend\n", 13, "'q'");
  expect_error(base() + "  draw scene pipeline=p reads=nobuf\nend\n", 13, "'nobuf'");
  expect_error(base() + "  draw scene pipeline=p fetch=albedo\nend\n", 13, "'albedo'");
  expect_error(base() + "end\ndispatch depth_bounds groups=1,1,1 group_size=8,8,1 writes=nowhere\n", 14, "'nowhere'");
  expect_error(base() + "end\nbarrier resources=ghost\n", 14, "'ghost'");
}

TEST(TraceErrors, AttachmentUsedOutsideItsPass) {
  const std::string second_pass =
      "pass post\n"
      "  attachment out format=rgba8 samples=1 load=dont_care store=store usage=color\n";
  // depth of pass main is transient: nothing may read it later
  expect_error(base() + "end\n" + second_pass + "  draw fullscreen pipeline=p reads=depth\nend\n", 16, "'depth'");
  // fetch= reads only attachments of the current pass
  expect_error(base() + "end\n" + second_pass + "  draw fullscreen pipeline=p fetch=color\nend\n", 16,
               "used outside its pass");
  // a stored attachment read as a texture inside its own pass is a feedback loop
  expect_error(base() + "  draw scene pipeline=p reads=color\nend\n", 13, "own pass");
  // attachment declared outside any pass
  expect_error(base() + "end\nattachment x format=rgba8 samples=1 load=clear store=store usage=color\n", 14,
               "outside a pass");
  // load=load of something never stored
  expect_error(base() + "end\npass again\n  attachment depth format=d24s8 samples=1 load=load store=dont_care usage=depth\nend\n",
               15, "'depth'");
  // redeclared with a different format
  expect_error(base() + "end\npass again\n  attachment color format=rgba16f samples=1 load=load store=store usage=color\nend\n",
               15, "'color'");
}

TEST(TraceErrors, PassStructure) {
  expect_error(base() + "  draw scene pipeline=p\n", 10, "'main'");                       // not closed
  expect_error(base() + "end\nend\n", 14, "'end' without an open pass");
  expect_error(base() + "end\ndraw scene pipeline=p\n", 14, "outside a pass");
  expect_error(base() + "pass inner\n", 13, "'inner'");
  expect_error(base() + "  dispatch depth_bounds groups=1,1,1 group_size=1,1,1\nend\n", 13, "'dispatch' inside pass");
  expect_error(base() + "  draw scene pipeline=p\n  attachment x format=rgba8 samples=1 load=clear store=store usage=color\nend\n",
               14, "after the first draw");
  expect_error(base() + "end\nlight point position=0,0,0 radius=1 color=1,1,1 intensity=1\n", 14, "'light'");
  expect_error(base() + "  shader t alu_ops=1 tex_fetches=0 varyings=0 light_alu_ops=0 light_source=none color_outputs=0\nend\n",
               13, "inside pass");
  expect_error("tbdrsim-trace 1\nscene atrium detail=1\nframe width=8 height=8 samples=1\n", 3, "'camera'");
}

TEST(TraceErrors, SemanticChecks) {
  // transient attachments never reach DRAM
  expect_error(base({{12, "  attachment depth format=d24s8 samples=1 load=clear store=store usage=depth transient=yes"}}), 12,
               "transient");
  // depth usage needs a depth format
  expect_error(base({{12, "  attachment depth format=rgba8 samples=1 load=clear store=dont_care usage=depth"}}), 12, "'rgba8'");
  // pixel local storage is not usable with MSAA
  expect_error(base({{11, "  attachment color format=rgba8 samples=4 load=clear store=store usage=color"},
                     {12, "  attachment depth format=d24s8 samples=4 load=clear store=dont_care usage=depth"}}) +
                   "  pls a format=r32ui\n  draw scene pipeline=p\nend\n",
               13, "MSAA");
  // mixed sample counts
  expect_error(base({{11, "  attachment color format=rgba8 samples=4 load=clear store=store usage=color"}}) +
                   "  draw scene pipeline=p\nend\n",
               12, "samples");
  // shader writes more color outputs than the pass has
  expect_error(base({{8, "shader s alu_ops=1 tex_fetches=0 varyings=0 light_alu_ops=1 light_source=all color_outputs=2"}}) +
                   "  draw scene pipeline=p\nend\n",
               13, "'s'");
  // light index out of range (one light)
  expect_error(base() + "  draw scene pipeline=p lights=0-3\nend\n", 13, "'0-3'");
  // proxy light source needs light geometry
  expect_error(base({{8, "shader s alu_ops=1 tex_fetches=0 varyings=0 light_alu_ops=1 light_source=proxy color_outputs=1"}}) +
                   "  draw fullscreen pipeline=p\nend\n",
               13, "proxy");
  // buffer read before anything wrote it
  expect_error(base() + "end\ndispatch depth_bounds groups=1,1,1 group_size=1,1,1 reads=grid\n", 14, "'grid'");
  // a dispatch's output read without a barrier
  expect_error(base() + "end\ndispatch depth_bounds groups=1,1,1 group_size=1,1,1 writes=grid\n"
                        "dispatch tile_light_cull groups=1,1,1 group_size=1,1,1 reads=grid\n",
               15, "barrier");
  // a pass's stored attachment read by a dispatch without a barrier
  expect_error(base() + "end\ndispatch depth_bounds groups=1,1,1 group_size=1,1,1 reads=color\n", 14, "barrier");
  // quoting mistakes
  expect_error(base({{4, "camera eye=0,0,5 target=0,0,0 up=0,1,0 fov_y_deg=60 near=0.1 far=100 name=\"open"}}), 4, "unterminated");
  expect_error(base({{4, "camera eye=0,0,5 target=0,0,0 up=0,1,0 fov_y_deg=60 near=0.1 far=100 name=a\"b\""}}), 4, "quote");
}

TEST(TraceErrors, UnknownKernelNamesLineAndKnownKernels) {
  expect_error(base() + "end\ndispatch cluster_assign groups=1,1,1 group_size=1,1,1\n", 14, "unknown kernel 'cluster_assign'");
  expect_error(base() + "end\ndispatch cluster_assign groups=1,1,1 group_size=1,1,1\n", 14, "cluster_light_assign");
  for (std::size_t k = 0; k < kComputeKernelCount; ++k) {
    const auto kernel = static_cast<ComputeKernel>(k);
    EXPECT_EQ(parse_compute_kernel(to_string(kernel)), kernel) << to_string(kernel);
  }
  EXPECT_FALSE(parse_compute_kernel("k").has_value());
}

TEST(TraceErrors, BarrierResolvesHazard) {
  const Trace t = parse(base() + "end\ndispatch depth_bounds groups=1,1,1 group_size=1,1,1 writes=grid\n"
                                 "barrier resources=grid,color\n"
                                 "dispatch tile_light_cull groups=1,1,1 group_size=1,1,1 reads=grid,color\n");
  EXPECT_EQ(t.commands.size(), 4u);
}

// ---- techniques ------------------------------------------------------------------------------------------

// A tiny scene built by hand: one material, one sub-mesh of one triangle, one instance.
Scene tiny_scene() {
  Scene s;
  s.name = "tiny";
  s.source = "tiny.gltf";
  s.content_hash = "00112233445566aa";
  Material m;
  m.name = "mat";
  s.materials.push_back(m);
  SubMesh sm;
  sm.name = "tri";
  sm.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  sm.normals = {{0, 0, 1}, {0, 0, 1}, {0, 0, 1}};
  sm.uvs = {{0, 0}, {1, 0}, {0, 1}};
  sm.indices = {0, 1, 2};
  s.submeshes.push_back(sm);
  s.instances.push_back(Instance{});
  s.bounds.max = {1, 1, 0};
  return s;
}

TraceSetup tiny_setup(const Scene& scene, int samples) {
  TraceSetup setup;
  setup.scene = &scene;
  setup.scene_spec = "tiny.gltf";
  setup.camera.eye = {0.5f, 0.5f, 3.0f};
  setup.camera.target = {0.5f, 0.5f, 0.0f};
  setup.camera_name = "front";
  for (int i = 0; i < 3; ++i) {
    Light l;
    l.position = {0.1f * static_cast<float>(i), 0.5f, 1.0f};
    l.radius = 2.0f;
    setup.lights.lights.push_back(l);
  }
  setup.lights.lights[2].type = Light::Type::Spot;
  setup.lights.lights[2].cos_inner = 0.95f;
  setup.lights.lights[2].cos_outer = 0.7f;
  setup.width = 320;
  setup.height = 200;
  setup.samples = samples;
  return setup;
}

TEST(TraceTechnique, RegistryListsPlainForward) {
  const auto names = technique_names();
  ASSERT_FALSE(names.empty());
  EXPECT_EQ(names.front(), "plain_forward");
  try {
    generate_trace("no_such_technique", TraceSetup{});
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("plain_forward"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("no_such_technique"), std::string::npos) << e.what();
  }
}

TEST(TraceTechnique, UnknownOrMalformedOptionIsAnError) {
  const Scene scene = tiny_scene();
  TraceSetup setup = tiny_setup(scene, 1);
  setup.options["tile_px"] = "16";
  EXPECT_THROW(generate_trace("plain_forward", setup), InputError);
  setup.options.clear();
  setup.options["light_alu_ops"] = "12.5";
  EXPECT_THROW(generate_trace("plain_forward", setup), InputError);
  setup.options["light_alu_ops"] = "30";
  const Trace t = generate_trace("plain_forward", setup);
  EXPECT_EQ(t.options.at("light_alu_ops"), "30");
  EXPECT_EQ(t.options.at("alu_ops"), "20");  // defaults recorded too
  EXPECT_EQ(t.find_shader("forward_lit")->light_alu_ops, 30u);
}

TEST(TraceTechnique, PlainForwardStructure) {
  const Scene scene = tiny_scene();
  const Trace t = generate_trace("plain_forward", tiny_setup(scene, 1));
  EXPECT_EQ(t.technique, "plain_forward");
  EXPECT_EQ(t.scene.kind, SceneKind::Gltf);
  EXPECT_EQ(t.scene.path, "tiny.gltf");
  EXPECT_EQ(t.scene.content_hash, "00112233445566aa");
  EXPECT_EQ(t.frame.width, 320);
  EXPECT_EQ(t.camera_name, "front");
  ASSERT_EQ(t.lights.size(), 3u);
  EXPECT_EQ(t.lights[2].type, Light::Type::Spot);
  ASSERT_NE(t.find_buffer("lights"), nullptr);
  EXPECT_EQ(t.find_buffer("lights")->bytes, 3 * kLightBufferBytesPerLight);

  ASSERT_EQ(t.commands.size(), 1u);
  const auto& pass = std::get<PassDesc>(t.commands[0]);
  EXPECT_GT(pass.line, 0);  // line numbers of the canonical text
  ASSERT_EQ(pass.attachments.size(), 2u);
  const Attachment& color = pass.attachments[0];
  EXPECT_EQ(color.format, Format::Rgba8);
  EXPECT_EQ(color.load, LoadOp::Clear);
  EXPECT_EQ(color.store, StoreOp::Store);
  const Attachment* depth = pass.depth_attachment();
  ASSERT_NE(depth, nullptr);
  EXPECT_EQ(depth->format, Format::D24s8);
  EXPECT_EQ(depth->store, StoreOp::DontCare);
  EXPECT_TRUE(depth->transient);

  ASSERT_EQ(pass.draws.size(), 3u);
  const SceneSubset order[] = {SceneSubset::Opaque, SceneSubset::Masked, SceneSubset::Blended};
  for (int i = 0; i < 3; ++i) EXPECT_EQ(pass.draws[i].subset, order[i]);
  const PipelineState* opaque = t.find_pipeline(pass.draws[0].pipeline);
  const PipelineState* masked = t.find_pipeline(pass.draws[1].pipeline);
  const PipelineState* blended = t.find_pipeline(pass.draws[2].pipeline);
  EXPECT_TRUE(opaque->depth_test && opaque->depth_write);
  EXPECT_EQ(opaque->blend, BlendMode::Off);
  EXPECT_TRUE(masked->depth_test && masked->depth_write);
  EXPECT_TRUE(t.find_shader(masked->shader)->discard);
  EXPECT_TRUE(blended->depth_test);
  EXPECT_FALSE(blended->depth_write);
  EXPECT_EQ(blended->blend, BlendMode::Alpha);
  const ShaderDesc* lit = t.find_shader(opaque->shader);
  EXPECT_EQ(lit->light_source, LightSource::All);
  EXPECT_EQ(lit->alu_ops, 20u);
  EXPECT_EQ(lit->tex_fetches, 2u);
  EXPECT_EQ(lit->light_alu_ops, 12u);
}

TEST(TraceTechnique, PlainForwardMsaaResolvesOnChip) {
  const Scene scene = tiny_scene();
  const Trace t = generate_trace("plain_forward", tiny_setup(scene, 4));
  const auto& pass = std::get<PassDesc>(t.commands[0]);
  const Attachment* ms = pass.find_attachment("color_ms");
  const Attachment* color = pass.find_attachment("color");
  ASSERT_NE(ms, nullptr);
  ASSERT_NE(color, nullptr);
  EXPECT_EQ(ms->samples, 4u);
  EXPECT_TRUE(ms->transient);
  EXPECT_EQ(ms->resolve, "color");
  EXPECT_EQ(color->samples, 1u);
  EXPECT_EQ(color->store, StoreOp::Store);
  EXPECT_EQ(pass.depth_attachment()->samples, 4u);
  ASSERT_EQ(pass.color_targets().size(), 1u);
  EXPECT_EQ(pass.color_targets()[0]->name, "color_ms");
}

TEST(TraceTechnique, PlainForwardRoundTripsByteIdentically) {
  const Scene scene = tiny_scene();
  for (int samples : {1, 2, 4}) {
    const Trace t = generate_trace("plain_forward", tiny_setup(scene, samples));
    const std::string once = write(t);
    const std::string twice = write(parse(once));
    EXPECT_EQ(once, twice) << "samples=" << samples;
    EXPECT_EQ(trace_hash(t), trace_hash(parse(once)));
  }
}

TEST(TraceTechnique, PlainForwardWithoutLights) {
  const Scene scene = tiny_scene();
  TraceSetup setup = tiny_setup(scene, 1);
  setup.lights.lights.clear();
  const Trace t = generate_trace("plain_forward", setup);
  EXPECT_TRUE(t.buffers.empty());
  EXPECT_EQ(t.find_shader("forward_lit")->light_source, LightSource::None);
}

TEST(TraceTechnique, AtriumSceneLine) {
  const Scene scene = tiny_scene();
  TraceSetup setup = tiny_setup(scene, 1);
  setup.scene = nullptr;
  setup.scene_spec = "atrium:2";
  const TraceScene s = trace_scene_for(setup);
  EXPECT_EQ(s.kind, SceneKind::Atrium);
  EXPECT_EQ(s.detail, 2);
  EXPECT_TRUE(s.content_hash.empty());
  setup.scene_spec = "atrium";
  EXPECT_THROW(trace_scene_for(setup), InputError);  // detail unknown without a loaded scene
}

// ---- the examples of docs/trace-format.md parse and round-trip ------------------------------------------

TEST(TraceDocs, ExamplesAreValidTraces) {
  const std::string path = std::string(TBDRSIM_SOURCE_DIR) + "/docs/trace-format.md";
  std::ifstream in(path);
  ASSERT_TRUE(in) << path;
  std::string line, block;
  bool inside = false;
  int examples = 0, line_no = 0, block_start = 0;
  while (std::getline(in, line)) {
    ++line_no;
    if (!inside && line == "```trace") {
      inside = true;
      block.clear();
      block_start = line_no + 1;
      continue;
    }
    if (inside && line.rfind("```", 0) == 0) {
      inside = false;
      ++examples;
      try {
        const Trace t = parse(block, path + " example at line " + std::to_string(block_start));
        EXPECT_EQ(write(t), write(parse(write(t))));
      } catch (const InputError& e) {
        ADD_FAILURE() << e.what();
      }
      continue;
    }
    if (inside) block += line + "\n";
  }
  EXPECT_GE(examples, 2);
}

}  // namespace
}  // namespace tbdr
