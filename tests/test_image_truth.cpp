// What the images say: triangle ids that do not depend on how the parameter buffer split the frame,
// and compute kernels' material fetches that read the texture lines fragment shading reads.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include "models/hw_config.hpp"
#include "models/command_processor.hpp"
#include "synthetic_scene.hpp"
#include "stat_lookup.hpp"

namespace tbdr {
namespace {

using namespace synthetic;



TEST(ImageTruth, TriangleIdsDoNotRestartAfterAPartialRender) {
  const Scene s = partial_render_grid_scene();
  Trace t = base_trace();
  PassDesc p = base_pass();
  p.draws = {draw_of("back"), draw_of("grid")};
  t.commands.push_back(p);
  const FrameResult big = simulate_frame(t, "ids.trace", s, resolve_config({}, {}).hw);
  const FrameResult small = simulate_frame(t, "ids.trace", s, resolve_config({}, {"tiling.pb_capacity_bytes=65536"}).hw);
  ASSERT_EQ(stat(big, "frame/tiler", "partial_renders"), 0);
  ASSERT_GE(stat(small, "frame/tiler", "partial_renders"), 1);
  // Same colour, and the same id at every pixel: the frame's primitive index, whichever render
  // drew it.
  EXPECT_EQ(big.images.attachments.at("color").color, small.images.attachments.at("color").color);
  EXPECT_EQ(big.images.counters.triangle_id, small.images.counters.triangle_id);
  // Ids are 1 + the frame's primitive index: the back quad's 2 triangles, then the grid's 12800.
  const auto [lo, hi] = std::minmax_element(small.images.counters.triangle_id.begin(), small.images.counters.triangle_id.end());
  EXPECT_GE(*lo, 1u);
  EXPECT_LE(*hi, 12802u);
  EXPECT_GT(*hi, 12000u) << "the last rows of the grid, drawn by the last render";
}

/// A quad covering the 64x64 frame with a 256x256 base colour texture (4 texels per pixel: mip
/// level 2, 64x64 texels).
Scene textured_wall() {
  Scene s = base_scene();
  TextureInfo tex;
  tex.name = "wall";
  tex.format = "procedural";
  tex.width = tex.height = 256;
  tex.channels = 4;
  s.textures.push_back(tex);
  s.materials[0].base_color_texture = 0;
  add_quad(s, "wall", 3, 0, kSize, 0);
  return s;
}

TEST(ImageTruth, TheAlbedoIsTheBaseColourTexelTheFetchIsChargedFor) {
  // A wall whose 2x1 base colour texture is red on the left half of its uv range and blue on the
  // right: the shaded colour follows the texel (glTF: base colour = factor x texel, the texel
  // sRGB-decoded), where the factor alone would give one colour everywhere.
  Scene s = textured_wall();
  ColorTexels texels;
  texels.width = 2;
  texels.height = 1;
  texels.rgba = {255, 0, 0, 255, 0, 0, 255, 255};
  s.base_color_texels.push_back(texels);
  s.materials[0].base_color = {1, 1, 1, 1};
  s.materials[0].base_color_texels = 0;
  Trace t = base_trace();
  PassDesc p = base_pass();
  p.draws = {draw_of("wall")};
  t.commands.push_back(p);
  const FrameResult f = simulate_frame(t, "texels.trace", s, resolve_config({}, {}).hw);
  const auto& c = f.images.attachments.at("color").color;
  const glm::vec4 left = c[32 * kSize + 8], right = c[32 * kSize + 56];
  std::printf("[ texels   ] left (%.3f %.3f %.3f), right (%.3f %.3f %.3f)\n", left.x, left.y, left.z, right.x, right.y, right.z);
  EXPECT_GT(left.x, 4 * left.z);
  EXPECT_GT(right.z, 4 * right.x);
  EXPECT_EQ(left.y, 0.0f);
  // The sRGB decode: code 200 is 0.578 linear ((200/255 + 0.055) / 1.055)^2.4.
  ColorTexels grey{1, 1, {200, 200, 200, 255}};
  EXPECT_NEAR(grey.sample_linear_rgb({0.5f, 0.5f}).x, std::pow((200.0 / 255.0 + 0.055) / 1.055, 2.4), 1e-6);
}

/// Every tile's (or workgroup tile's) texture line list of a command, sorted among themselves.
std::vector<std::vector<std::uint64_t>> tile_lists(const FrameResult& f) {
  std::vector<std::vector<std::uint64_t>> out;
  for (const auto& c : f.work.commands) {
    for (const auto& r : c.renders) {
      for (const auto& t : r.tiles) {
        if (!t.texture_lines.empty()) out.push_back(t.texture_lines);
      }
    }
  }
  std::sort(out.begin(), out.end());
  return out;
}

TEST(ImageTruth, VisibilityBufferKernelReadsTheTextureLinesFragmentShadingReads) {
  const Scene s = textured_wall();
  const HwConfig hw = resolve_config({}, {}).hw;
  // Forward: 2 material fetches per fragment (base colour and a companion), 32x32 tiles.
  Trace fwd = base_trace();
  fwd.shaders[0].tex_fetches = 2;
  PassDesc p = base_pass();
  p.draws = {draw_of("wall")};
  fwd.commands.push_back(p);
  const FrameResult f = simulate_frame(fwd, "fwd.trace", s, hw);

  // Visibility buffer: ids and depth, then vbuffer_shade over 32x32 pixel workgroup tiles with 3
  // fetches: one of the visibility image it reads, 2 of the material.
  Trace vb = base_trace();
  vb.shaders[0].tex_fetches = 0;
  ShaderDesc lit;
  lit.name = "vlit";
  lit.alu_ops = 10;
  lit.tex_fetches = 3;
  lit.light_source = LightSource::All;
  lit.color_outputs = 1;
  vb.shaders.push_back(lit);
  BufferDesc frame;
  frame.name = "frame";
  frame.bytes = kSize * kSize * 4;
  frame.traffic = DramClass::Color;
  frame.content = BufferContent::Image;
  vb.buffers.push_back(frame);
  PassDesc vis = base_pass();
  vis.name = "visibility";
  vis.attachments[0].name = "visibility";
  vis.attachments[0].format = Format::R32ui;
  vis.attachments[0].usage = AttachmentUsage::Visibility;
  vis.draws = {draw_of("wall")};
  vb.commands.push_back(vis);
  BarrierCmd barrier;
  barrier.resources = {"visibility"};
  vb.commands.push_back(barrier);
  DispatchCmd shade;
  shade.kernel = ComputeKernel::VbufferShade;
  shade.groups[0] = shade.groups[1] = 2;
  shade.group_size[0] = shade.group_size[1] = 32;
  shade.reads = {"visibility"};
  shade.writes = {"frame"};
  shade.params = {{"shader", "vlit"}, {"tile_px", "32"}};
  vb.commands.push_back(shade);
  const FrameResult v = simulate_frame(vb, "vb.trace", s, hw);

  ASSERT_EQ(v.work.commands.size(), 2u);
  const CommandWork& dispatch = v.work.commands[1];
  ASSERT_TRUE(dispatch.is_dispatch);
  // The same 4 tiles' footprints, 2 copies each. The texture is magnified 4x across (256 texels
  // over 64 pixels) and 2.67x down (the quad spans 96 pixel rows): level 2, 64x64 texels in 4x4
  // blocks (a 64 B line); a 32-pixel tile reads 32 + 1 texel columns (9 blocks) and 21.3 + 1 rows
  // (6 or 7 blocks).
  const auto fwd_tiles = tile_lists(f);
  ASSERT_EQ(fwd_tiles.size(), 4u);
  std::vector<std::vector<std::uint64_t>> kernel_tiles;
  std::size_t k = 0;
  for (const auto& t : fwd_tiles) {
    (void)t;
    // The dispatch's list is the workgroup tiles' lists one after another; split it where the
    // offsets stop increasing (each tile's list is sorted and starts low).
    std::vector<std::uint64_t> one;
    while (k < dispatch.texture_lines.size() && (one.empty() || dispatch.texture_lines[k] > one.back())) {
      one.push_back(dispatch.texture_lines[k++]);
    }
    kernel_tiles.push_back(one);
  }
  EXPECT_EQ(k, dispatch.texture_lines.size());
  std::sort(kernel_tiles.begin(), kernel_tiles.end());
  EXPECT_EQ(kernel_tiles, fwd_tiles);
  for (const auto& t : fwd_tiles) {
    EXPECT_GE(t.size(), 2u * 9u * 6u);
    EXPECT_LE(t.size(), 2u * 9u * 7u);
  }
  // Booked as texture reads (the texture unit's requests) as fragment shading books them, not in
  // the dispatch's plain read stream; line accesses counted the same way.
  EXPECT_EQ(v.dram.reads(DramClass::Textures), f.dram.reads(DramClass::Textures));
  EXPECT_EQ(dispatch.read_bytes[static_cast<std::size_t>(DramClass::Textures)], 0u);
  EXPECT_EQ(dispatch.texture_line_accesses, static_cast<std::uint64_t>(stat(f, "frame/tsp", "texture_line_accesses")));
}

TEST(ImageTruth, TheTexelTheShaderPrefetchesIsTheTexelItSamples) {
  // Tsp::shade finds a batch's base colour texels first (ColorTexels::texel_at) and decodes them
  // later (linear_rgb): the same value as sample_linear_rgb wherever texel_at names a texel, for
  // uvs inside, on the edges of and outside [0, 1) (repeat wrapping); none where the uv is not
  // finite (sampled black) or the texture holds no texels (sampled white).
  ColorTexels t;
  t.width = 5;
  t.height = 3;
  for (int i = 0; i < 15; ++i) t.rgba.insert(t.rgba.end(), {static_cast<std::uint8_t>(17 * i), static_cast<std::uint8_t>(255 - 9 * i), 77, 255});
  int named = 0;
  for (float u = -1.5f; u <= 2.5f; u += 0.0625f) {
    for (float v = -1.0f; v <= 2.0f; v += 0.1f) {
      const std::uint8_t* texel = t.texel_at({u, v});
      ASSERT_NE(texel, nullptr);
      EXPECT_EQ(ColorTexels::linear_rgb(texel), t.sample_linear_rgb({u, v})) << u << "," << v;
      ++named;
    }
  }
  EXPECT_GT(named, 1000);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  EXPECT_EQ(t.texel_at({nan, 0.5f}), nullptr);
  EXPECT_EQ(t.sample_linear_rgb({nan, 0.5f}), glm::vec3(0.0f));
  ColorTexels undecoded;
  undecoded.width = 4;
  undecoded.height = 4;
  EXPECT_EQ(undecoded.texel_at({0.5f, 0.5f}), nullptr);
  EXPECT_EQ(undecoded.sample_linear_rgb({0.5f, 0.5f}), glm::vec3(1.0f));
}

}  // namespace
}  // namespace tbdr
