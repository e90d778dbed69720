// Texture addresses of fragment shading (models/texture_unit.hpp): the twiddled mip-chain layout,
// LOD selection, bilinear quad footprints with repeat wrapping, and per-tile footprints of a
// synthetic frame, all with hand-derived numbers (4 bytes per texel, 64-byte lines: one line holds
// a 4x4 Morton block of texels).
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <set>
#include <vector>

#include "models/hw_config.hpp"
#include "models/texture_unit.hpp"
#include "models/command_processor.hpp"
#include "synthetic_scene.hpp"
#include "stat_lookup.hpp"

namespace tbdr {
namespace {

using namespace synthetic;

/// A scene whose material 0 samples a w x h texture.
Scene textured_scene(int w, int h) {
  Scene s = base_scene();
  TextureInfo t;
  t.name = "tex";
  t.format = "procedural";
  t.width = w;
  t.height = h;
  t.channels = 4;
  s.textures.push_back(t);
  s.materials[0].base_color_texture = 0;
  return s;
}

/// Morton code of (x, y), x in the even bits, written as a plain bit loop.
std::uint64_t morton(std::uint32_t x, std::uint32_t y) {
  std::uint64_t m = 0;
  for (int b = 0; b < 16; ++b) {
    m |= static_cast<std::uint64_t>((x >> b) & 1u) << (2 * b);
    m |= static_cast<std::uint64_t>((y >> b) & 1u) << (2 * b + 1);
  }
  return m;
}

/// The uvs of a quad whose pixel (x, y) samples texel coordinate (x0 + dx*step + 0.25, y0 + dy*step + 0.25)
/// of an n x n texture (a quarter texel off the texel centres, so float rounding cannot move a footprint).
std::array<glm::vec2, 4> quad_uv(float x0, float y0, float step, float n) {
  std::array<glm::vec2, 4> uv;
  for (int lane = 0; lane < 4; ++lane) {
    const float dx = static_cast<float>(lane & 1), dy = static_cast<float>(lane >> 1);
    uv[static_cast<std::size_t>(lane)] = {(x0 + dx * step + 0.75f) / n, (y0 + dy * step + 0.75f) / n};
  }
  return uv;
}

std::vector<std::uint64_t> sorted(const QuadFootprint& fp) {
  std::vector<std::uint64_t> v(fp.lines.begin(), fp.lines.begin() + fp.count);
  std::sort(v.begin(), v.end());
  return v;
}

TEST(TextureLayout, MipChainOf256SquaredTextureIsLineAlignedAndDefaultTextureFollows) {
  const Scene s = textured_scene(256, 256);
  const TextureLayout layout(&s, 1, 4, 64);
  ASSERT_EQ(layout.storages().size(), 2u);  // the texture, then the default texture
  const TextureStorage& t = layout.of_material(0);
  EXPECT_EQ(t.scene_texture, 0);
  EXPECT_EQ(t.base, 0u);
  ASSERT_EQ(t.levels, 9u);  // 256 .. 1
  // Level bytes 262144, 65536, 16384, 4096, 1024, 256, 64, 16 (-> 64), 4 (-> 64).
  const std::array<std::uint64_t, 9> offsets{0, 262144, 327680, 344064, 348160, 349184, 349440, 349504, 349568};
  for (std::uint32_t l = 0; l < 9; ++l) {
    EXPECT_EQ(t.level[l].offset, offsets[l]) << "level " << l;
    EXPECT_EQ(t.level[l].width, 256u >> l);
    EXPECT_EQ(t.level[l].height, 256u >> l);
  }
  // 87381 texels x 4 bytes = 349524 (TextureInfo::gpu_bytes), plus 48 + 60 bytes of alignment.
  EXPECT_EQ(s.textures[0].gpu_bytes(), 349524u);
  EXPECT_EQ(t.slot_bytes, 349632u);
  // Default 4x4 texture: 64 + 16 (-> 64) + 4 (-> 64) bytes.
  const TextureStorage& d = layout.default_texture();
  EXPECT_EQ(d.scene_texture, -1);
  EXPECT_EQ(d.levels, 3u);
  EXPECT_EQ(d.base, 349632u);
  EXPECT_EQ(d.slot_bytes, 192u);
  EXPECT_EQ(layout.total_bytes(), 349632u + 192u);
  // Two fetch slots: each texture holds two copies, one after the other.
  const TextureLayout two(&s, 2, 4, 64);
  EXPECT_EQ(two.of_material(0).slot_base(1), 349632u);
  EXPECT_EQ(two.default_texture().base, 2u * 349632u);
  EXPECT_EQ(two.total_bytes(), 2u * (349632u + 192u));
}

TEST(TextureLayout, MaterialsWithoutUsableTextureShareTheDefaultTexture) {
  Scene s = textured_scene(64, 32);
  TextureInfo missing;
  missing.name = "gone";
  missing.width = 128;
  missing.height = 128;
  missing.missing = true;
  s.textures.push_back(missing);
  TextureInfo unused;  // referenced by no material: not stored
  unused.width = 16;
  unused.height = 16;
  s.textures.push_back(unused);
  s.materials[1].base_color_texture = 1;  // missing file
  // material 2 has no texture
  const TextureLayout layout(&s, 1, 4, 64);
  ASSERT_EQ(layout.storages().size(), 2u);
  EXPECT_EQ(layout.of_material(0).scene_texture, 0);
  EXPECT_EQ(&layout.of_material(1), &layout.default_texture());
  EXPECT_EQ(&layout.of_material(2), &layout.default_texture());
  EXPECT_EQ(&layout.of_material(kNoMaterial), &layout.default_texture());
  const TextureLayout none(nullptr, 1, 4, 64);
  EXPECT_EQ(none.storages().size(), 1u);
  EXPECT_EQ(none.total_bytes(), 192u);
}

TEST(TextureLayout, TexelsAreTwiddled) {
  const Scene s = textured_scene(16, 16);
  const TextureLayout layout(&s, 1, 4, 64);
  const TextureStorage& t = layout.of_material(0);
  EXPECT_EQ(t.twiddled_index(0, 0, 0), 0u);
  EXPECT_EQ(t.twiddled_index(0, 1, 0), 1u);  // byte offset 4
  EXPECT_EQ(t.twiddled_index(0, 0, 1), 2u);  // byte offset 8
  EXPECT_EQ(t.twiddled_index(0, 1, 1), 3u);
  EXPECT_EQ(t.twiddled_index(0, 2, 0), 4u);  // byte offset 16
  EXPECT_EQ(t.twiddled_index(0, 3, 3), 15u);
  EXPECT_EQ(t.twiddled_index(0, 4, 0), 16u);  // the next 4x4 block: the next 64-byte line
  EXPECT_EQ(t.twiddled_index(0, 15, 15), 255u);

  // Non-square: 8x2 is four 2x2 Morton blocks along x; 2x8 four blocks along y.
  const Scene wide_s = textured_scene(8, 2);
  const TextureLayout wide(&wide_s, 1, 4, 64);
  const TextureStorage& w = wide.of_material(0);
  EXPECT_EQ(w.levels, 4u);  // 8x2, 4x1, 2x1, 1x1
  EXPECT_EQ(w.twiddled_index(0, 2, 0), 4u);
  EXPECT_EQ(w.twiddled_index(0, 3, 1), 7u);
  EXPECT_EQ(w.twiddled_index(0, 7, 1), 15u);
  EXPECT_EQ(w.twiddled_index(1, 3, 0), 3u);  // 4x1: linear
  const Scene tall_s = textured_scene(2, 8);
  const TextureLayout tall(&tall_s, 1, 4, 64);
  EXPECT_EQ(tall.of_material(0).twiddled_index(0, 1, 3), 7u);
  EXPECT_EQ(tall.of_material(0).twiddled_index(0, 0, 6), 12u);
  // Non-power-of-two: 3x5 is padded to 4x8 (128 bytes); levels 3x5, 1x2, 1x1.
  const Scene npot_s = textured_scene(3, 5);
  const TextureLayout npot(&npot_s, 1, 4, 64);
  const TextureStorage& n = npot.of_material(0);
  EXPECT_EQ(n.levels, 3u);
  EXPECT_EQ(n.level[0].bytes, 128u);
  EXPECT_EQ(n.level[1].offset, 128u);
  EXPECT_EQ(n.level[1].width, 1u);
  EXPECT_EQ(n.level[1].height, 2u);
  EXPECT_EQ(n.level[2].offset, 192u);
  EXPECT_EQ(n.slot_bytes, 256u);
}

TEST(TextureFootprint, OneTexelPerPixelQuadTouchesTheBlocksItsBilinearFootprintCovers) {
  const Scene s = textured_scene(16, 16);
  const TextureLayout layout(&s, 2, 4, 64);
  const TextureStorage& t = layout.of_material(0);
  QuadFootprint fp;
  // Texels 0..1 sampled at +0.25: bilinear footprint texels 0..2 in x and y, inside block (0,0).
  layout.quad_footprint(t, quad_uv(0, 0, 1, 16), fp);
  EXPECT_EQ(fp.level, 0u);
  EXPECT_EQ(sorted(fp), (std::vector<std::uint64_t>{0}));
  // Texels 2..3: footprint 2..4 in x and y, the four blocks (0,0) (1,0) (0,1) (1,1).
  layout.quad_footprint(t, quad_uv(2, 2, 1, 16), fp);
  EXPECT_EQ(fp.level, 0u);
  EXPECT_EQ(sorted(fp), (std::vector<std::uint64_t>{0, 64, 128, 192}));
  // Texels 4..5 in x, 0..1 in y: block (1,0) only.
  layout.quad_footprint(t, quad_uv(4, 0, 1, 16), fp);
  EXPECT_EQ(sorted(fp), (std::vector<std::uint64_t>{64}));
  // Fetch slot 1 reads the companion copy: the same lines one copy further.
  std::vector<std::uint64_t> lines;
  EXPECT_EQ(layout.append_quad_lines(t, 1, quad_uv(2, 2, 1, 16), lines), 4u);
  std::sort(lines.begin(), lines.end());
  const std::uint64_t copy = t.slot_bytes;  // 1024 + 256 + 64 + 64 + 64
  EXPECT_EQ(copy, 1472u);
  EXPECT_EQ(lines, (std::vector<std::uint64_t>{copy, copy + 64, copy + 128, copy + 192}));
}

TEST(TextureFootprint, LevelFollowsTheQuadsTexelsPerPixel) {
  const Scene s = textured_scene(16, 16);
  const TextureLayout layout(&s, 1, 4, 64);
  const TextureStorage& t = layout.of_material(0);
  EXPECT_EQ(layout.quad_level(t, quad_uv(0, 0, 1, 16)), 0u);
  EXPECT_EQ(layout.quad_level(t, quad_uv(0, 0, 0.25f, 16)), 0u);  // magnified
  EXPECT_EQ(layout.quad_level(t, quad_uv(0, 0, 2, 16)), 1u);
  EXPECT_EQ(layout.quad_level(t, quad_uv(0, 0, 2.8f, 16)), 1u);  // log2 2.8 = 1.49
  EXPECT_EQ(layout.quad_level(t, quad_uv(0, 0, 3, 16)), 2u);     // log2 3 = 1.58
  EXPECT_EQ(layout.quad_level(t, quad_uv(0, 0, 1000, 16)), 4u);  // clamped to the 1x1 level
  // Minified by 4 along y only: rho takes the larger derivative.
  std::array<glm::vec2, 4> uv = quad_uv(0, 0, 1, 16);
  uv[2].y = uv[0].y + 4.0f / 16.0f;
  EXPECT_EQ(layout.quad_level(t, uv), 2u);
  // Minified by 4: level 2 (4x4 texels, one line at 1024 + 256).
  QuadFootprint fp;
  layout.quad_footprint(t, quad_uv(0, 0, 4, 16), fp);
  EXPECT_EQ(fp.level, 2u);
  EXPECT_EQ(sorted(fp), (std::vector<std::uint64_t>{1280}));
}

TEST(TextureFootprint, CoordinatesWrap) {
  const Scene s = textured_scene(16, 16);
  const TextureLayout layout(&s, 1, 4, 64);
  const TextureStorage& t = layout.of_material(0);
  // u = 0.01: x = 0.16 - 0.5 < 0, so the footprint is texels 15 and 0; v = 0.25: texels 3 and 4.
  // Blocks (3,0) (0,0) (3,1) (0,1): Morton 5, 0, 7, 2.
  const std::vector<std::uint64_t> expected{0, 128, 320, 448};
  QuadFootprint fp;
  for (float u : {0.01f, 1.01f, -0.99f, 3.01f}) {
    const std::array<glm::vec2, 4> uv{glm::vec2(u, 0.25f), glm::vec2(u, 0.25f), glm::vec2(u, 0.25f), glm::vec2(u, 0.25f)};
    layout.quad_footprint(t, uv, fp);
    EXPECT_EQ(fp.level, 0u) << u;
    EXPECT_EQ(sorted(fp), expected) << u;
  }
  // A shifted quad covers the same texels.
  layout.quad_footprint(t, quad_uv(2, 2, 1, 16), fp);
  const std::vector<std::uint64_t> base = sorted(fp);
  std::array<glm::vec2, 4> shifted = quad_uv(2, 2, 1, 16);
  for (auto& c : shifted) c += glm::vec2(1.0f, -2.0f);
  layout.quad_footprint(t, shifted, fp);
  EXPECT_EQ(sorted(fp), base);
  // Non-finite coordinates do not escape the texture.
  const float inf = std::numeric_limits<float>::infinity();
  const std::array<glm::vec2, 4> bad{glm::vec2(inf, 0.0f), glm::vec2(0.0f, std::nanf("")), glm::vec2(0.0f), glm::vec2(0.0f)};
  layout.quad_footprint(t, bad, fp);
  EXPECT_EQ(fp.level, 4u);
  EXPECT_EQ(sorted(fp), (std::vector<std::uint64_t>{t.level[4].offset}));
}

TEST(TextureFootprint, BlockCountingAgreesWithTexelByTexel) {
  // Random quads (positions over several repeats, 1/16 to 16 texels per pixel, rotated, sheared
  // and perspective-distorted) on square, wide, tall and tiny textures: counting line blocks gives
  // the lines of the texel-by-texel reference, except where a coordinate lies within 1/128 texel
  // of a texel boundary (the block path rounds texel coordinates to 1/256 texel first).
  Scene s = base_scene();
  const std::vector<std::pair<int, int>> sizes{{64, 64}, {256, 64}, {16, 128}, {4, 4}, {1, 8}, {2048, 2048}, {8, 2}};
  for (const auto& [w, h] : sizes) {
    TextureInfo t;
    t.width = w;
    t.height = h;
    s.textures.push_back(t);
    Material m;
    m.base_color_texture = static_cast<int>(s.textures.size() - 1);
    s.materials.push_back(m);
  }
  const TextureLayout layout(&s, 2, 4, 64);
  std::uint64_t state = 12345;
  auto rnd = [&]() {  // uniform in [0, 1)
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    return static_cast<float>(state >> 40) / static_cast<float>(1u << 24);
  };
  int compared = 0, skipped = 0, by_blocks = 0;
  for (std::size_t mi = 3; mi < s.materials.size(); ++mi) {
    const TextureStorage& t = layout.of_material(static_cast<std::uint32_t>(mi));
    for (int n = 0; n < 3000; ++n) {
      const float scale = std::exp2(rnd() * 8.0f - 4.0f);  // texels per pixel at level 0
      const float angle = rnd() * 6.2831853f, shear = rnd() - 0.5f;
      const glm::vec2 dx = glm::vec2(std::cos(angle), std::sin(angle)) * scale;
      const glm::vec2 dy = glm::vec2(-std::sin(angle) + shear * std::cos(angle), std::cos(angle)) * scale;
      const glm::vec2 size(static_cast<float>(t.width), static_cast<float>(t.height));
      const glm::vec2 o(rnd() * 6.0f - 3.0f, rnd() * 6.0f - 3.0f);
      const glm::vec2 warp = glm::vec2(rnd() - 0.5f, rnd() - 0.5f) * 0.3f * scale;
      const std::array<glm::vec2, 4> uv{o, o + dx / size, o + dy / size, o + (dx + dy + warp) / size};
      QuadFootprint fast, ref;
      layout.quad_footprint(t, uv, fast);
      layout.footprint_by_texel(t, uv, ref);
      ASSERT_EQ(fast.level, ref.level);
      by_blocks += fast.blocks ? 1 : 0;
      if (sorted(fast) == sorted(ref)) {
        ++compared;
        continue;
      }
      const TextureLevel& lv = t.level[ref.level];
      bool near = false;
      for (const glm::vec2& c : uv) {
        for (const float v : {c.x * static_cast<float>(lv.width) - 0.5f, c.y * static_cast<float>(lv.height) - 0.5f}) {
          near = near || std::fabs(v - std::round(v)) < 1.0f / 128.0f;
        }
      }
      EXPECT_TRUE(near) << t.width << "x" << t.height << " quad " << n << " level " << ref.level;
      ++skipped;
    }
  }
  EXPECT_GT(by_blocks, 15000);  // most quads take the block path
  EXPECT_LT(skipped, compared / 50);
}

/// A camera-facing triangle at depth 5 covering the whole 64x64 frame (NDC (-1,-1), (3,-1),
/// (-1,3)), with uv mapping pixel (x, y) to texel (x + 0.25, 63.25 - y) of a 64x64 texture.
void add_fullscreen_triangle(Scene& s, std::uint32_t material) {
  SubMesh m;
  m.name = "screen";
  m.material = material;
  const float d = 5.0f, k = d * kTan30;
  const float off = 0.25f / 64.0f;
  m.positions = {{-k, -k, -d}, {3 * k, -k, -d}, {-k, 3 * k, -d}};
  m.normals.assign(3, glm::vec3(0, 0, 1));
  m.uvs = {{off, off}, {2 + off, off}, {off, 2 + off}};
  m.indices = {0, 1, 2};
  m.index_bytes = 2;
  s.submeshes.push_back(m);
  s.instances.push_back({static_cast<std::uint32_t>(s.submeshes.size() - 1), glm::mat4(1.0f), "screen"});
}

FrameResult run_frame(const Scene& s, std::uint32_t tex_fetches, const std::vector<DrawCmd>& draws) {
  Trace t = base_trace();
  t.shaders[0].tex_fetches = tex_fetches;
  PassDesc p = base_pass();
  p.draws = draws;
  t.commands.push_back(p);
  return simulate_frame(t, "synthetic.trace", s, resolve_config({}, {}).hw);
}


TEST(TextureTileFootprint, FullScreenOneToOneTextureSplitsIntoTileFootprints) {
  Scene s = textured_scene(64, 64);
  add_fullscreen_triangle(s, 0);
  for (std::uint32_t fetches : {1u, 2u}) {
    const FrameResult f = run_frame(s, fetches, {draw_of("screen")});
    // 64x64 texture: 16384 + 4096 + 1024 + 256 + 64 + 64 + 64 bytes per copy; default texture 192.
    const std::uint64_t copy = 21952;
    EXPECT_EQ(f.work.texture_bytes, fetches * (copy + 192));
    ASSERT_EQ(f.work.commands.size(), 1u);
    ASSERT_EQ(f.work.commands[0].renders.size(), 1u);
    const auto& tiles = f.work.commands[0].renders[0].tiles;
    ASSERT_EQ(tiles.size(), 4u);
    std::set<std::uint64_t> all;
    std::uint64_t accesses = 0, footprint = 0;
    for (const TileWork& tw : tiles) {
      EXPECT_TRUE(std::is_sorted(tw.texture_lines.begin(), tw.texture_lines.end()));
      EXPECT_EQ(std::adjacent_find(tw.texture_lines.begin(), tw.texture_lines.end()), tw.texture_lines.end());
      // A 32x32 tile reads texels x0..x0+32 (the last one wraps for the right tiles); rows
      // 63 - y and 64 - y for its pixel rows y: 9 x 9 blocks of 4x4 texels per copy.
      std::set<std::uint32_t> bx, by;
      for (int x = tw.tile_x * 32; x <= tw.tile_x * 32 + 32; ++x) bx.insert(static_cast<std::uint32_t>(x % 64) / 4);
      for (int y = 32 - tw.tile_y * 32; y <= 64 - tw.tile_y * 32; ++y) by.insert(static_cast<std::uint32_t>(y % 64) / 4);
      std::vector<std::uint64_t> expected;
      for (std::uint32_t slot = 0; slot < fetches; ++slot) {
        for (auto x : bx) {
          for (auto y : by) expected.push_back(slot * copy + morton(x, y) * 64);
        }
      }
      std::sort(expected.begin(), expected.end());
      EXPECT_EQ(tw.texture_lines.size(), 81u * fetches);
      EXPECT_EQ(tw.texture_lines, expected) << "tile " << tw.tile_x << "," << tw.tile_y;
      // Per quad: 1 or 2 blocks in x (alternating) times 1 or 2 in y: (8*1 + 8*2)^2 per tile.
      EXPECT_EQ(tw.texture_line_accesses, 576u * fetches);
      all.insert(tw.texture_lines.begin(), tw.texture_lines.end());
      accesses += tw.texture_line_accesses;
      footprint += tw.texture_lines.size();
    }
    // Together the tiles read all of level 0 (64x64x4 bytes = 256 lines) of every copy.
    EXPECT_EQ(all.size(), 256u * fetches);
    EXPECT_EQ(*all.rbegin(), (fetches - 1) * copy + 16384 - 64);
    EXPECT_EQ(stat(f, "frame/tsp", "texture_line_accesses"), static_cast<double>(accesses));
    EXPECT_EQ(stat(f, "frame/tsp", "texture_line_accesses"), 2304.0 * fetches);
    EXPECT_EQ(stat(f, "frame/tsp", "texture_tile_lines"), static_cast<double>(footprint));
    EXPECT_EQ(stat(f, "frame/tsp", "helper_lanes"), 0);
  }
}

TEST(TextureTileFootprint, UntexturedMaterialReadsTheDefaultTextureAndScreenPassesReadNone) {
  Scene s = base_scene();  // material 0 has no texture
  add_fullscreen_triangle(s, 0);
  const FrameResult f = run_frame(s, 1, {draw_of("screen")});
  EXPECT_EQ(f.work.texture_bytes, 192u);
  for (const TileWork& tw : f.work.commands[0].renders[0].tiles) {
    // 16 texels per pixel along each axis: clamped to level 0, the whole 4x4 texture, one line.
    EXPECT_EQ(tw.texture_lines, (std::vector<std::uint64_t>{0}));
    EXPECT_EQ(tw.texture_line_accesses, 256u);  // 16x16 quads, one line each
  }
  // A full-screen pass (no scene triangle) reads no texture addresses, though its texels count.
  DrawCmd fs;
  fs.pipeline = "opaque";
  fs.geometry = GeometryKind::Fullscreen;
  const FrameResult g = run_frame(s, 1, {fs});
  EXPECT_GT(stat(g, "frame/tsp", "texels_filtered"), 0);
  EXPECT_EQ(stat(g, "frame/tsp", "texture_line_accesses"), 0);
  for (const TileWork& tw : g.work.commands[0].renders[0].tiles) {
    EXPECT_TRUE(tw.texture_lines.empty());
    EXPECT_EQ(tw.texture_line_accesses, 0u);
  }
}

}  // namespace
}  // namespace tbdr
