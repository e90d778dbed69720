// The TSP on its own: shading batches handed over directly (or by the ISP for one triangle), with
// quads, helper lanes, ALU ops, texture fetches and tile buffer bytes derived by hand.
#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <tuple>
#include <vector>

#include "kernel/random.hpp"
#include "unit_fixture.hpp"

namespace tbdr {
namespace {

using namespace unit;

/// Pixels (x0..x1) x (y0..y1) inclusive, sorted by row then column (what the ISP hands over).
std::vector<ShadePixel> block(int x0, int y0, int x1, int y1) {
  std::vector<ShadePixel> out;
  for (int y = y0; y <= y1; ++y) {
    for (int x = x0; x <= x1; ++x) out.push_back({x, y, 1u});
  }
  return out;
}

/// The pixels of the upper-left half of tile 0 under the top-left rule: x + y <= 30 (496).
std::vector<ShadePixel> upper_left_pixels() {
  std::vector<ShadePixel> out;
  for (int y = 0; y < 32; ++y) {
    for (int x = 0; x < 32; ++x) {
      if (x + y <= 30) out.push_back({x, y, 1u});
    }
  }
  return out;
}

const ScreenTri kUpperLeft{{0, 0}, {32, 0}, {0, 32}};

TEST(UnitTsp, OnePixelLaunchesAQuadWithThreeHelperLanes) {
  RenderRig rig;
  rig.add_draw(make_shader(10, 0, LightSource::None, 1, 2));
  const std::uint32_t p = rig.add_triangle(kUpperLeft);
  rig.shade(p, {{5, 7, 1u}});
  EXPECT_EQ(rig.tsp_stats.shader_invocations.value(), 1u);
  EXPECT_EQ(rig.tsp_stats.shaded_quads.value(), 1u);
  EXPECT_EQ(rig.tsp_stats.helper_lanes.value(), 3u);
  // Every lane runs: 4 x 10 ALU ops; 4 lanes x 2 fetches = 8 bilinear fetches, one filtered
  // texel each (texture.texels_per_clock's unit), whatever the 4 texels each reads.
  EXPECT_EQ(rig.tsp_stats.fragment_alu_ops.value(), 40u);
  EXPECT_EQ(rig.tsp_stats.texture_fetches.value(), 8u);
  EXPECT_EQ(rig.tsp_stats.texels_filtered.value(), 8u);
  // One rgba8 sample written: 4 B of tile buffer.
  EXPECT_EQ(rig.tsp_stats.shaded_samples.value(), 1u);
  EXPECT_EQ(rig.tsp_stats.tile_buffer_write_bytes.value(), 4u);
}

TEST(UnitTsp, QuadsOfABatchWithNothingToRunAreIdle) {
  // One quad (2x2 at (4,4)) per draw. A depth-only shader (0 ALU ops, no fetch, no colour output,
  // no PLS) has nothing to run: its quad is idle (a task that retires at once, the timing model's
  // task slots). 1 ALU op (4 on the quad's lanes), one colour output (4 samples x 4 B of tile
  // buffer) or one fetch (4 texels) is work: those quads are not idle. 4 quads, 1 idle.
  RenderRig rig;
  const std::uint32_t depth_only = rig.add_draw(make_shader(0, 0, LightSource::None, 0, 0));
  const std::uint32_t alu = rig.add_draw(make_shader(1, 0, LightSource::None, 0, 0));
  const std::uint32_t output = rig.add_draw(make_shader(0, 0, LightSource::None, 1, 0));
  const std::uint32_t fetch = rig.add_draw(make_shader(0, 0, LightSource::None, 0, 1));
  for (const std::uint32_t d : {depth_only, alu, output, fetch}) {
    ScreenTri t = kUpperLeft;
    t.draw = d;
    rig.shade(rig.add_triangle(t), block(4, 4, 5, 5));
  }
  EXPECT_EQ(rig.tsp_stats.shaded_quads.value(), 4u);
  EXPECT_EQ(rig.tsp_stats.idle_quads.value(), 1u);
  EXPECT_EQ(rig.tsp_stats.fragment_alu_ops.value(), 4u);
  EXPECT_EQ(rig.tsp_stats.tile_buffer_write_bytes.value(), 16u);
  EXPECT_EQ(rig.tsp_stats.texels_filtered.value(), 4u);
}

TEST(UnitTsp, QuadsAreAlignedToEvenPixels) {
  // 2x2 pixels at (4,4): one quad, no helper. The same 2x2 at (5,5) straddles 4 quads: 16 lanes,
  // 12 helpers. 3x3 at (1,1)..(3,3): quads x 0..1, y 0..1 = 4 quads, 16 - 9 = 7 helpers.
  RenderRig rig;
  rig.add_draw(make_shader(1));
  const std::uint32_t p = rig.add_triangle(kUpperLeft);
  rig.shade(p, block(4, 4, 5, 5));
  EXPECT_EQ(rig.tsp_stats.shaded_quads.value(), 1u);
  EXPECT_EQ(rig.tsp_stats.helper_lanes.value(), 0u);
  rig.shade(p, block(5, 5, 6, 6));
  EXPECT_EQ(rig.tsp_stats.shaded_quads.value(), 1u + 4u);
  EXPECT_EQ(rig.tsp_stats.helper_lanes.value(), 12u);
  rig.shade(p, block(1, 1, 3, 3));
  EXPECT_EQ(rig.tsp_stats.shaded_quads.value(), 1u + 4u + 4u);
  EXPECT_EQ(rig.tsp_stats.helper_lanes.value(), 12u + 7u);
  EXPECT_EQ(rig.tsp_stats.shader_invocations.value(), 4u + 4u + 9u);
}

// launched_quads marks a bitmap of quads (batches within 64 x 64 quads, any pixel order) or merges
// the two pixel rows of each quad row in one pass (wider batches, the pixels' order; a sort when
// unordered) and must give what sorting every pixel's quad and dropping repeats gives, in the
// same order, on every path; launched_quad_count (the count alone, from the bitmap's rows) the
// same number.
TEST(UnitTsp, LaunchedQuadsEqualSortedUniqueQuadsOfThePixels) {
  const auto by_sort = [](const std::vector<ShadePixel>& px) {
    std::vector<std::uint64_t> q;
    for (const ShadePixel& p : px) q.push_back((std::uint64_t{static_cast<std::uint32_t>(p.y >> 1)} << 32) | static_cast<std::uint32_t>(p.x >> 1));
    std::sort(q.begin(), q.end());
    q.erase(std::unique(q.begin(), q.end()), q.end());
    return q;
  };
  std::vector<std::uint64_t> got, scratch;
  // Hand-counted: a 3x3 block at (1,1) touches quads x 0..1, y 0..1 = 4 quads.
  EXPECT_EQ(launched_quads(block(1, 1, 3, 3), got), 4u);
  EXPECT_EQ(launched_quad_count(block(1, 1, 3, 3), scratch), 4u);
  EXPECT_EQ(got, by_sort(block(1, 1, 3, 3)));
  // The upper-left half of a tile (rows of falling length; odd and even first rows) and random
  // sparse pixel sets in raster order, then the same sets shuffled (the sorting fallback).
  EXPECT_EQ(launched_quads(upper_left_pixels(), got), by_sort(upper_left_pixels()).size());
  EXPECT_EQ(launched_quad_count(upper_left_pixels(), scratch), by_sort(upper_left_pixels()).size());
  EXPECT_EQ(got, by_sort(upper_left_pixels()));
  std::uint32_t state = 12345u;
  const auto next = [&] { return state = state * 1664525u + 1013904223u; };
  for (int trial = 0; trial < 200; ++trial) {
    std::vector<ShadePixel> px;
    const int y0 = static_cast<int>(next() % 5);
    for (int y = y0; y < y0 + 9; ++y) {
      for (int x = 0; x < 12; ++x) {
        if (next() % 3 == 0) px.push_back({x, y, 1u});
      }
    }
    EXPECT_EQ(launched_quads(px, got), by_sort(px).size());
    EXPECT_EQ(launched_quad_count(px, scratch), by_sort(px).size());
    EXPECT_EQ(got, by_sort(px));
    std::reverse(px.begin(), px.end());
    EXPECT_EQ(launched_quads(px, got), by_sort(px).size());
    EXPECT_EQ(launched_quad_count(px, scratch), by_sort(px).size());
    EXPECT_EQ(got, by_sort(px));
    // Wider than 64 quads (the merge, then reversed: the sort), and exactly 64 quads wide and
    // tall (the bitmap's last bit and row).
    for (const int span : {129, 128}) {
      std::vector<ShadePixel> wide;
      for (int y = y0; y < y0 + span; y += 7) {
        for (int x = 0; x < span; ++x) {
          if (next() % 5 == 0 || x == span - 1 || y == y0) wide.push_back({x, y, 1u});
        }
      }
      wide.push_back({span - 1, y0 + span - 1, 1u});
      EXPECT_EQ(launched_quads(wide, got), by_sort(wide).size());
      EXPECT_EQ(launched_quad_count(wide, scratch), by_sort(wide).size());
      EXPECT_EQ(got, by_sort(wide));
      std::reverse(wide.begin(), wide.end());
      EXPECT_EQ(launched_quads(wide, got), by_sort(wide).size());
      EXPECT_EQ(launched_quad_count(wide, scratch), by_sort(wide).size());
      EXPECT_EQ(got, by_sort(wide));
    }
  }
}

TEST(UnitTsp, QuadsAndHelperLanesOfATriangleWhoseEdgeCutsQuads) {
  // The ISP hands over UL (x + y <= 30, 496 pixels) in one batch. Quad (qx, qy) holds pixels with
  // x + y from 2(qx + qy) to 2(qx + qy) + 2: quads with qx + qy <= 14 are full (sum over s = 0..14
  // of (s + 1) = 120 quads, 480 pixels); the 16 quads with qx + qy = 15 hold one covered pixel
  // (x + y = 30) and 3 helpers. 136 quads, 544 lanes, 48 helpers.
  RenderRig rig;
  rig.render_one_draw({kUpperLeft});
  EXPECT_EQ(rig.tsp_stats.shader_invocations.value(), 496u);
  EXPECT_EQ(rig.tsp_stats.shaded_quads.value(), 136u);
  EXPECT_EQ(rig.tsp_stats.helper_lanes.value(), 48u);
}

TEST(UnitTsp, AluOpsAreBaseAndPerLightOpsTimesLanes) {
  // 10 ALU ops + 5 per light, every light of the draw's selection (3 of the 3 lights): per lane
  // 10 + 5 x 3 = 25; UL's 544 lanes (496 + 48 helpers): 13600 ops. Light evaluations count
  // covered fragments only: 3 x 496 = 1488.
  RenderSpec spec;
  spec.lights.resize(3);
  RenderRig rig(spec);
  rig.add_draw(make_shader(10, 5, LightSource::All), {}, {0, 1, 2});
  rig.add_triangle(kUpperLeft);
  rig.shade(0, upper_left_pixels());
  EXPECT_EQ(rig.tsp_stats.shaded_quads.value(), 136u);
  EXPECT_EQ(rig.tsp_stats.fragment_alu_ops.value(), 25u * 544u);
  EXPECT_EQ(rig.tsp_stats.light_evaluations.value(), 3u * 496u);
}

TEST(UnitTsp, FewerSelectedLightsCostFewerOps) {
  // The same triangle with 2 of the 3 lights selected: (10 + 5 x 2) x 544 = 10880; with a shader
  // that evaluates no light: 10 x 544 = 5440.
  RenderSpec spec;
  spec.lights.resize(3);
  RenderRig rig(spec);
  rig.add_draw(make_shader(10, 5, LightSource::All), {}, {0, 2});
  rig.add_draw(make_shader(10, 5, LightSource::None), {}, {0, 1, 2});
  ScreenTri t = kUpperLeft;
  rig.add_triangle(t);
  t.draw = 1;
  rig.add_triangle(t);
  rig.shade(0, upper_left_pixels());
  EXPECT_EQ(rig.tsp_stats.fragment_alu_ops.value(), 20u * 544u);
  rig.shade(1, upper_left_pixels());
  EXPECT_EQ(rig.tsp_stats.fragment_alu_ops.value(), 20u * 544u + 10u * 544u);
  EXPECT_EQ(rig.tsp_stats.light_evaluations.value(), 2u * 496u);
}

TEST(UnitTsp, TileBufferBytesFollowTheOutputFormats) {
  // Two color outputs, rgba8 (4 B) and rgba16f (8 B): 12 B per written sample. Additive blending
  // reads them too. 496 pixels: 5952 B written, 5952 B read, 496 blended samples.
  RenderSpec spec;
  spec.attachments = {make_attachment("color", Format::Rgba8), make_attachment("hdr", Format::Rgba16f),
                      make_attachment("depth", Format::D24s8, LoadOp::Clear, StoreOp::DontCare, true)};
  RenderRig rig(spec);
  PipelineState add;
  add.blend = BlendMode::Add;
  rig.add_draw(make_shader(1, 0, LightSource::None, 2), add);
  rig.add_triangle(kUpperLeft);
  rig.shade(0, upper_left_pixels());
  EXPECT_EQ(rig.tsp_stats.shaded_samples.value(), 496u);
  EXPECT_EQ(rig.tsp_stats.tile_buffer_write_bytes.value(), 496u * 12u);
  EXPECT_EQ(rig.tsp_stats.tile_buffer_read_bytes.value(), 496u * 12u);
  EXPECT_EQ(rig.tsp_stats.blended_samples.value(), 496u);
}

TEST(UnitTsp, StoredImagesSampledPerPixelAreReadPerInvocation) {
  // A shader reading an 8 B G-buffer texel at its own pixel: one read per covered fragment
  // (helpers excluded): 9 pixels -> 72 B of class gbuffer.
  RenderRig rig;
  rig.add_draw(make_shader(1), {}, {}, {{DramClass::Gbuffer, 8u}});
  rig.add_triangle(kUpperLeft);
  rig.shade(0, block(1, 1, 3, 3));
  EXPECT_EQ(rig.dram.reads(DramClass::Gbuffer), 9u * 8u);
  EXPECT_EQ(rig.dram.total_read(), 9u * 8u);
}

TEST(UnitTsp, PixelLocalStorageIsAccessedWholePerFragment) {
  // PLS of rgba8 + r32ui = 8 B per pixel. A shader reading it (no color output) accesses 8 B per
  // fragment; one reading and writing it 16 B. 4x4 pixels: 128 B, then 256 B more.
  RenderSpec spec;
  spec.pls = {PlsVariable{"albedo", Format::Rgba8, 0}, PlsVariable{"count", Format::R32ui, 0}};
  RenderRig rig(spec);
  ShaderDesc reader = make_shader(1, 0, LightSource::None, 0);
  reader.pls = PlsAccess::Read;
  ShaderDesc rw = reader;
  rw.pls = PlsAccess::ReadWrite;
  rig.add_draw(reader);
  rig.add_draw(rw);
  ScreenTri t = kUpperLeft;
  rig.add_triangle(t);
  t.draw = 1;
  rig.add_triangle(t);
  rig.shade(0, block(0, 0, 3, 3));
  EXPECT_EQ(rig.tsp_stats.pls_bytes_accessed.value(), 16u * 8u);
  rig.shade(1, block(0, 0, 3, 3));
  EXPECT_EQ(rig.tsp_stats.pls_bytes_accessed.value(), 16u * 8u + 16u * 16u);
  EXPECT_EQ(rig.tsp_stats.shaded_samples.value(), 0u);  // no color output
}

TEST(UnitTsp, AlphaTestKillsTheMaskedSamples) {
  // UL with the masked material, uv (0,0), (1,0), (0,1): u = (x + 0.5) / 32 at pixel centres; the
  // mask is transparent for u < 0.5 (x <= 15). Killed: sum over x = 0..15 of (31 - x) = 376;
  // alive 120. Killed fragments still ran (ALU ops of all 544 lanes) but write no color.
  RenderRig rig;
  rig.add_draw(make_shader(1));
  ScreenTri leaves = kUpperLeft;
  leaves.hsr = HsrClass::PunchThrough;
  leaves.material = 1;
  leaves.uv = {glm::vec2{0, 0}, glm::vec2{1, 0}, glm::vec2{0, 1}};
  rig.add_triangle(leaves);
  const std::vector<ShadePixel> pixels = upper_left_pixels();
  std::vector<std::uint32_t> alive;
  rig.shade(0, pixels, &alive);
  EXPECT_EQ(rig.tsp_stats.alpha_test_killed_samples.value(), 376u);
  EXPECT_EQ(rig.tsp_stats.shaded_samples.value(), 120u);
  EXPECT_EQ(rig.tsp_stats.fragment_alu_ops.value(), 544u);
  ASSERT_EQ(alive.size(), pixels.size());
  for (std::size_t i = 0; i < pixels.size(); ++i) {
    EXPECT_EQ(alive[i], pixels[i].x <= 15 ? 0u : 1u) << "pixel " << pixels[i].x << "," << pixels[i].y;
  }
}

TEST(UnitTsp, ColorWritesKeepTheTargetFormatsPrecision) {
  // No lights: the colour is the ambient term, 0.03 x albedo 1 = 0.03. rgba8 keeps
  // round(0.03 x 255) / 255 = 8/255; rgba32f keeps 0.03 exactly; the alpha (1) survives both.
  RenderSpec spec;
  spec.attachments = {make_attachment("c8", Format::Rgba8), make_attachment("c32", Format::Rgba32f),
                      make_attachment("depth", Format::D24s8)};
  spec.attachments[2].usage = AttachmentUsage::Depth;
  RenderRig rig(spec);
  rig.add_draw(make_shader(1, 0, LightSource::None, 2));
  ScreenTri t = kUpperLeft;
  t.material = 0;  // a scene triangle: it has a surface
  const std::uint32_t p = rig.add_triangle(t);
  rig.shade(p, {{5, 7, 1u}});
  const std::size_t px = 7 * kViewportPx + 5;
  EXPECT_EQ(rig.images.attachments.at("c8").color[px], glm::vec4(8.0f / 255.0f, 8.0f / 255.0f, 8.0f / 255.0f, 1.0f));
  EXPECT_EQ(rig.images.attachments.at("c32").color[px], glm::vec4(0.03f, 0.03f, 0.03f, 1.0f));
}

TEST(UnitTsp, AdditiveBlendingAccumulatesInTheTargetsPrecision) {
  // 0.001 added 100 times: rgba8 rounds every sum back to 0 (0.001 < 0.5/255); rgba16f keeps the
  // sum within its 10-bit mantissa (about 0.1, error under 100 x 2^-11 x 0.1); rgba32f within 1e-5.
  for (const auto& [format, want, tolerance] : {std::tuple{Format::Rgba8, 0.0f, 0.0f}, std::tuple{Format::Rgba16f, 0.1f, 0.005f},
                                                std::tuple{Format::Rgba32f, 0.1f, 1e-5f}}) {
    glm::vec4 acc(0.0f);
    for (int i = 0; i < 100; ++i) acc = FormatPrecision::color(format, acc + glm::vec4(0.001f, 0.0f, 0.0f, 0.0f));
    EXPECT_NEAR(acc.x, want, tolerance) << bytes_per_sample(format);
  }
}

// The fp16 and r11g11b10f channels round through the exponent field (models/shading.cpp,
// small_float); this is the formula they replace, with the library's frexp, ldexp and nearbyint.
// Compared on every 61st float bit pattern (70 M values: every exponent, both signs, zeros,
// denormals, infinities and NaNs) for the three channel widths: bit for bit the same.
float small_float_by_library(float x, int mantissa, bool is_signed) {
  if (std::isnan(x)) return 0.0f;
  if (!is_signed && x < 0.0f) return 0.0f;
  const float a = std::fabs(x);
  if (a == 0.0f) return x;
  int e = 0;
  std::frexp(a, &e);
  const int lead = std::max(e - 1, -14);
  const float step = std::ldexp(1.0f, lead - mantissa);
  const float largest = std::ldexp(2.0f - std::ldexp(1.0f, -mantissa), 15);
  return std::copysign(std::min(std::nearbyint(a / step) * step, largest), x);
}

TEST(UnitTsp, SmallFloatRoundingMatchesTheLibraryFormulaEverywhere) {
  std::uint64_t differing = 0, compared = 0;
  for (std::uint64_t bits = 0; bits <= 0xffffffffu; bits += 61) {
    const float x = std::bit_cast<float>(static_cast<std::uint32_t>(bits));
    const glm::vec4 v(x);
    const glm::vec4 half = FormatPrecision::color(Format::Rgba16f, v);  // (four lanes: each compared)
    const glm::vec4 small = FormatPrecision::color(Format::R11g11b10f, v);
    const glm::vec4 byte = FormatPrecision::color(Format::Rgba8, v);
    const float want_half = small_float_by_library(x, 10, true);
    // unorm8 by the library: clamp, nearbyint(x * 255) / 255.
    const float want_byte = x > 0.0f ? (x >= 1.0f ? 1.0f : std::nearbyint(x * 255.0f) / 255.0f) : 0.0f;
    const float want_small6 = small_float_by_library(x, 6, false);
    const float want[12] = {want_half,   want_half, want_half, want_half, want_small6, want_small6, small_float_by_library(x, 5, false),
                            1.0f,        want_byte, want_byte, want_byte, want_byte};
    const float got[12] = {half.x, half.y, half.z, half.w, small.x, small.y, small.z, small.w, byte.x, byte.y, byte.z, byte.w};
    for (int k = 0; k < 12; ++k) {
      differing += std::bit_cast<std::uint32_t>(got[k]) != std::bit_cast<std::uint32_t>(want[k]) ? 1 : 0;
      ++compared;
    }
  }
  EXPECT_EQ(differing, 0u) << "of " << compared;
  // One value by hand: 1/3 in fp16 is 0x3555 = 1365/4096 (10 mantissa bits, lead -2: step 2^-12).
  EXPECT_EQ(FormatPrecision::color(Format::Rgba16f, glm::vec4(1.0f / 3.0f)).x, 1365.0f / 4096.0f);
}

TEST(UnitTsp, FormatPrecisionOfEachFormat) {
  const glm::vec4 v(0.5f, 1.0f / 3.0f, -0.25f, 0.4f);
  // unorm8: 0.5 -> 128/255 (127.5 rounds to even), 1/3 -> 85/255, negatives clamp to 0.
  EXPECT_EQ(FormatPrecision::color(Format::Rgba8, v), glm::vec4(128.0f / 255, 85.0f / 255, 0.0f, 102.0f / 255));
  // rgb10a2: 0.5 x 1023 = 511.5 -> 512; 1/3 -> 341; alpha in 2 bits: 0.4 x 3 = 1.2 -> 1/3.
  EXPECT_EQ(FormatPrecision::color(Format::Rgb10a2, v), glm::vec4(512.0f / 1023, 341.0f / 1023, 0.0f, 1.0f / 3));
  // fp16: 1/3 -> 0x3555 = 1365/4096; saturates at 65504.
  EXPECT_EQ(FormatPrecision::color(Format::Rgba16f, v), glm::vec4(0.5f, 1365.0f / 4096, -0.25f, 0.39990234375f));
  EXPECT_EQ(FormatPrecision::color(Format::R16f, glm::vec4(1e6f)).x, 65504.0f);
  // r11g11b10f: 1/3 with 6 mantissa bits = 85/256, blue (5 bits) -> 0 for a negative, no alpha (1).
  EXPECT_EQ(FormatPrecision::color(Format::R11g11b10f, v), glm::vec4(0.5f, 85.0f / 256, 0.0f, 1.0f));
  // Channels the format lacks read back 0, alpha 1.
  EXPECT_EQ(FormatPrecision::color(Format::R8, v), glm::vec4(128.0f / 255, 0.0f, 0.0f, 1.0f));
  EXPECT_EQ(FormatPrecision::color(Format::Rgba32f, v), v);
}

// Tsp::shade leaves an additive target alone where a fragment adds exactly 0, for the formats
// FormatPrecision::keeps_every_channel names: sound only if every value such a target holds (its
// clear, 0, and whatever color() wrote) is a fixed point of color(). Checked on every 61st float
// bit pattern in each lane (zeros, denormals, NaN, infinities) for those formats; a format lacking
// a channel is refused, as its cleared 0 reads back as alpha 1.
TEST(UnitTsp, AddingZeroKeepsWhatAFourChannelTargetHolds) {
  const Format kept[] = {Format::Rgba8, Format::Rgb10a2, Format::Rgba16f, Format::Rgba32f};
  std::uint64_t moved = 0;
  for (const Format f : kept) {
    ASSERT_TRUE(FormatPrecision::keeps_every_channel(f));
    EXPECT_EQ(FormatPrecision::color(f, glm::vec4(0.0f)), glm::vec4(0.0f));  // the clear
    for (std::uint64_t bits = 0; bits <= 0xffffffffu; bits += 61 * 7) {
      const float x = std::bit_cast<float>(static_cast<std::uint32_t>(bits));
      const glm::vec4 held = FormatPrecision::color(f, glm::vec4(x, -x, x * 0.5f, x * 3.0f));
      const glm::vec4 again = FormatPrecision::color(f, held + glm::vec4(0.0f));
      for (int c = 0; c < 4; ++c) {
        if (std::isnan(held[c]) && std::isnan(again[c])) continue;  // (rgba32f keeps a NaN)
        // (-0 + 0 is +0: an fp16 target that held -0 would read +0 had the 0 been added; equal
        // values, the same in every image. Every other value bit for bit.)
        const bool same = held[c] == 0.0f ? again[c] == 0.0f : std::bit_cast<std::uint32_t>(held[c]) == std::bit_cast<std::uint32_t>(again[c]);
        moved += same ? 0 : 1;
      }
    }
  }
  EXPECT_EQ(moved, 0u);
  for (const Format f : {Format::R11g11b10f, Format::R8, Format::Rg16f, Format::R32f}) {
    EXPECT_FALSE(FormatPrecision::keeps_every_channel(f));
    EXPECT_NE(FormatPrecision::color(f, glm::vec4(0.0f)), glm::vec4(0.0f));  // why: alpha reads 1
  }
}

// An additive pass's fragment out of its light's reach adds exactly 0: the TSP leaves the target
// as it is instead of writing dst + 0 back (host speed), but the hardware still blends it, so
// every count is the one of a fragment its light reaches. Pixel (5, 7) of UL lies at world
// (5.5, -7.5, -1), normal +z. Light 0 sits 1 unit in front of it (radius 3: it reaches and faces
// it); light 1 is 150 units away with radius 1. The target holds 128/255 before (an rgba8 value).
// Per pass: 1 shaded and blended sample, 4 B written and 4 B read (rgba8), 1 light evaluated.
TEST(UnitTsp, AnAdditiveFragmentOutOfReachCountsAsOneInReachAndKeepsItsPixel) {
  RenderSpec spec;
  spec.attachments = {make_attachment("color", Format::Rgba8), make_attachment("depth", Format::D24s8)};
  spec.attachments[1].usage = AttachmentUsage::Depth;
  spec.lights.resize(2);
  spec.lights[0].position = glm::vec3(5.5f, -7.5f, 0.0f);
  spec.lights[0].radius = 3.0f;
  spec.lights[1].position = glm::vec3(100.0f, 100.0f, 50.0f);
  spec.lights[1].radius = 1.0f;
  RenderRig rig(spec);
  PipelineState add;
  add.blend = BlendMode::Add;
  rig.add_draw(make_shader(1, 1, LightSource::All), add, {1});  // the far light's pass
  rig.add_draw(make_shader(1, 1, LightSource::All), add, {0});  // the near light's pass
  ScreenTri t = kUpperLeft;
  t.material = 0;
  const std::uint32_t far = rig.add_triangle(t);
  t.draw = 1;
  const std::uint32_t near = rig.add_triangle(t);
  const std::size_t px = 7 * kViewportPx + 5;
  glm::vec4& dst = rig.images.attachments.at("color").color[px];
  const glm::vec4 before(128.0f / 255.0f, 64.0f / 255.0f, 0.0f, 1.0f);
  dst = before;
  rig.shade(far, {{5, 7, 1u}});
  EXPECT_EQ(dst, before);  // bit for bit: nothing added
  EXPECT_EQ(rig.tsp_stats.blended_samples.value(), 1u);
  EXPECT_EQ(rig.tsp_stats.shaded_samples.value(), 1u);
  EXPECT_EQ(rig.tsp_stats.tile_buffer_write_bytes.value(), 4u);
  EXPECT_EQ(rig.tsp_stats.tile_buffer_read_bytes.value(), 4u);
  EXPECT_EQ(rig.tsp_stats.light_evaluations.value(), 1u);
  rig.shade(near, {{5, 7, 1u}});
  EXPECT_GT(dst.x, before.x);  // the near light adds (n.l = 1, attenuation (1 - 1/9)^2)
  EXPECT_EQ(rig.tsp_stats.blended_samples.value(), 2u);
  EXPECT_EQ(rig.tsp_stats.shaded_samples.value(), 2u);
  EXPECT_EQ(rig.tsp_stats.tile_buffer_write_bytes.value(), 8u);
  EXPECT_EQ(rig.tsp_stats.tile_buffer_read_bytes.value(), 8u);
  EXPECT_EQ(rig.tsp_stats.light_evaluations.value(), 2u);
}

TEST(UnitTsp, ATriangleIsOutOfALightsReachOnlyWhenItsBoxIsBeyondTheRadius) {
  Primitive p;
  p.world = {glm::vec3(0.0f, 0.0f, 0.0f), glm::vec3(4.0f, 0.0f, 0.0f), glm::vec3(0.0f, 2.0f, 1.0f)};
  std::vector<Light> lights(1);
  const std::uint32_t one[1] = {0};
  lights[0].radius = 1.0f;
  const auto at = [&](glm::vec3 position) {
    lights[0].position = position;
    return may_reach_triangle(p, one, lights);
  };
  EXPECT_TRUE(at(glm::vec3(1.0f, 0.5f, 0.25f)));   // inside the triangle's box
  EXPECT_TRUE(at(glm::vec3(4.9f, 0.0f, 0.0f)));    // 0.9 beyond the box's x face: within the radius
  EXPECT_FALSE(at(glm::vec3(5.1f, 0.0f, 0.0f)));   // 1.1 beyond it
  EXPECT_FALSE(at(glm::vec3(4.8f, 2.8f, 0.0f)));   // 0.8 beyond two faces: sqrt(1.28) > 1
  EXPECT_TRUE(at(glm::vec3(4.6f, 2.6f, 0.0f)));    // 0.6 beyond two faces: sqrt(0.72) < 1
  // The box, not the triangle: a light off the hypotenuse but inside the box may reach.
  EXPECT_TRUE(at(glm::vec3(3.5f, 1.9f, 0.9f)));
  // Several lights: any one that may reach.
  lights.push_back(lights[0]);
  lights[0].position = glm::vec3(100.0f);
  lights[1].position = glm::vec3(1.0f);
  const std::uint32_t both[2] = {0, 1};
  EXPECT_TRUE(may_reach_triangle(p, both, lights));
  lights[1].position = glm::vec3(-100.0f);
  EXPECT_FALSE(may_reach_triangle(p, both, lights));
}

TEST(UnitTsp, NoPointATriangleInterpolatesIsReachedWhenItsBoxIsOutOfReach) {
  // The safety of the TSP's shortcut: wherever a light reaches a point the TSP may interpolate
  // (float barycentrics in [0, 1] from double ones, weighted as Tsp::shade's position_at), the
  // triangle may be reached. The hard case: a triangle in an axis-aligned plane (a wall; its box
  // is flat there), whose interpolated points step off the plane by a rounding (weights summing
  // to 1 + 2^-23), lit by a light on the plane's normal at r (1 +- 1e-4) from the point. With the
  // box not widened and no margin (the box test alone) this fails at trial 5223.
  Pcg32 rng(20261206, 7);
  std::vector<Light> lights(1);
  const std::uint32_t one[1] = {0};
  int reached = 0;
  for (int trial = 0; trial < 20000; ++trial) {
    Primitive p;
    const float scale = std::ldexp(1.0f, static_cast<int>(rng.next() % 12) - 4);  // 1/16 .. 128
    const auto axis = static_cast<int>(rng.next() % 3);
    const float plane = rng.range(-1, 1) * scale;
    for (glm::vec3& v : p.world) {
      v = glm::vec3(rng.range(-1, 1), rng.range(-1, 1), rng.range(-1, 1)) * scale;
      v[axis] = plane;
    }
    glm::dvec3 wd(rng.uniform_double(), rng.uniform_double(), rng.uniform_double());
    wd /= wd.x + wd.y + wd.z;
    const glm::vec3 b(wd);
    const glm::vec3 position = p.world[0] * b.x + p.world[1] * b.y + p.world[2] * b.z;
    const float r = scale * rng.range(0.001f, 1.0f);
    glm::vec3 normal(0.0f);
    normal[axis] = position[axis] >= plane ? 1.0f : -1.0f;  // away from the plane, on the point's side
    lights[0].radius = r;
    lights[0].position = position + normal * (r * static_cast<float>(1.0 + (rng.uniform_double() - 0.5) * 2e-4));
    if (!ShadingModel::reaches(lights[0], position)) continue;
    ++reached;
    ASSERT_TRUE(may_reach_triangle(p, one, lights)) << "trial " << trial;
  }
  EXPECT_GT(reached, 5000);  // about half the lights reach their point
}

TEST(UnitTsp, GbufferTargetsKeepTheSurfaceAtTheirPrecision) {
  // G-buffer targets albedo rgba8 and normal rgb10a2: the stored surface's albedo 0.3 becomes
  // round(76.5) = 76 (even) / 255; the normal (0, 0, 1) stored as n/2 + 1/2 = (0.5, 0.5, 1) in
  // 10 bits reads back (1/1023, 1/1023, 1) renormalised: off by about 1.4e-3 rad; the lighting the
  // deferred pass computes is what that precision gives.
  RenderSpec spec;
  spec.attachments = {make_attachment("albedo", Format::Rgba8), make_attachment("normal", Format::Rgb10a2),
                      make_attachment("depth", Format::D24s8)};
  spec.attachments[0].usage = AttachmentUsage::Gbuffer;
  spec.attachments[1].usage = AttachmentUsage::Gbuffer;
  spec.attachments[2].usage = AttachmentUsage::Depth;
  RenderRig rig(spec);
  rig.scene.materials[0].base_color = glm::vec4(0.3f, 0.3f, 0.3f, 1.0f);
  rig.add_draw(make_shader(1, 0, LightSource::None, 2));
  ScreenTri t = kUpperLeft;
  t.material = 0;
  const std::uint32_t p = rig.add_triangle(t);
  rig.shade(p, {{5, 7, 1u}});
  const AttachmentImage& g = rig.images.attachments.at("albedo");
  ASSERT_FALSE(g.surface.empty());
  const SurfacePoint& s = g.surface[7 * kViewportPx + 5];
  EXPECT_EQ(s.albedo, glm::vec3(76.0f / 255));
  const glm::vec3 n = s.normal;
  EXPECT_NEAR(glm::length(n), 1.0f, 1e-6f);
  const float off = std::acos(std::min(1.0f, std::fabs(n.z)));
  EXPECT_GT(off, 1e-3f);
  EXPECT_LT(off, 2e-3f);
}

}  // namespace
}  // namespace tbdr

namespace tbdr {
namespace {

using namespace unit;

/// Two point lights near the upper-left tile (the counts do not depend on where they are).
std::vector<Light> two_lights() {
  Light a;
  a.position = {0.0f, 0.0f, 1.0f};
  a.radius = 10.0f;
  Light b = a;
  b.position = {1.0f, 0.0f, 1.0f};
  return {a, b};
}

TEST(UnitTsp, LitSamplesAnUnblendedWriteReplacesAreHidden) {
  // One sample per pixel, lit shaders evaluating both lights (light_source=all, 2 selected).
  RenderRig rig(RenderSpec{.lights = two_lights()});
  rig.keep_lit_sample_ledger();
  PipelineState blended;
  blended.blend = BlendMode::Alpha;
  const std::uint32_t lit = rig.add_draw(make_shader(1, 12, LightSource::All, 1), {}, {0, 1});
  const std::uint32_t lit_blended = rig.add_draw(make_shader(1, 12, LightSource::All, 1), blended, {0, 1});
  const std::uint32_t unlit = rig.add_draw(make_shader(1, 0, LightSource::None, 1));
  ScreenTri t = kUpperLeft;
  t.material = 0;  // a scene triangle (opaque material): a lit surface
  t.draw = lit;
  const std::uint32_t a = rig.add_triangle(t), b = rig.add_triangle(t);
  t.draw = lit_blended;
  const std::uint32_t glass = rig.add_triangle(t);
  t.draw = unlit;
  const std::uint32_t cover = rig.add_triangle(t);
  // a lights 4x4 pixels: they hold its writes, nothing is hidden yet.
  rig.shade(a, block(0, 0, 3, 3));
  EXPECT_EQ(rig.tsp_stats.hidden_lit_samples.value(), 0u);
  // b replaces columns 0..1 (8 pixels): a's 8 samples there are hidden, 8 x 2 lights.
  rig.shade(b, block(0, 0, 1, 3));
  EXPECT_EQ(rig.tsp_stats.hidden_lit_samples.value(), 8u);
  EXPECT_EQ(rig.tsp_stats.hidden_light_evaluations.value(), 16u);
  // Blended glass over columns 2..3 hides nothing: those samples now hold a's write and the glass's.
  rig.shade(glass, block(2, 0, 3, 3));
  EXPECT_EQ(rig.tsp_stats.hidden_lit_samples.value(), 8u);
  // An unlit unblended write over all 16 pixels hides what they hold: b's 8, and a's and the
  // glass's 2 x 8: 24 samples (48 evaluations) more, 32 (64) in all. It holds nothing lit itself.
  rig.shade(cover, block(0, 0, 3, 3));
  EXPECT_EQ(rig.tsp_stats.hidden_lit_samples.value(), 32u);
  EXPECT_EQ(rig.tsp_stats.hidden_light_evaluations.value(), 64u);
  rig.shade(cover, block(0, 0, 3, 3));
  EXPECT_EQ(rig.tsp_stats.hidden_lit_samples.value(), 32u);
  // A lit fragment shaded but not written (the depth test after the shader failed: isp.early_z=0)
  // is hidden at once: 1 sample, 2 evaluations.
  rig.shade(a, {{10, 10, 1u, 0u}});
  EXPECT_EQ(rig.tsp_stats.hidden_lit_samples.value(), 33u);
  EXPECT_EQ(rig.tsp_stats.hidden_light_evaluations.value(), 66u);
  // Every lit fragment counted its 2 lights once: 16 + 8 + 8 + 1 fragments.
  EXPECT_EQ(rig.tsp_stats.light_evaluations.value(), 2u * 33u);
}

TEST(UnitTsp, ASampleHoldsAnyNumberOfBlendedLitWrites) {
  // 300 blended lit writes at pixel (3,5) (more than a sample's 4-byte entry counts: it moves to
  // its block's wide entry), then an unlit unblended write: all 300 are hidden, 2 lights each;
  // then 2 more there (its entry narrow again) and a replacement of it and of its neighbour's
  // one write: 303.
  RenderRig rig(RenderSpec{.lights = two_lights()});
  rig.keep_lit_sample_ledger();
  PipelineState blended;
  blended.blend = BlendMode::Add;
  const std::uint32_t glass = rig.add_draw(make_shader(1, 12, LightSource::All, 1), blended, {0, 1});
  const std::uint32_t unlit = rig.add_draw(make_shader(1, 0, LightSource::None, 1));
  ScreenTri t = kUpperLeft;
  t.material = 0;
  t.draw = glass;
  const std::uint32_t g = rig.add_triangle(t);
  t.draw = unlit;
  const std::uint32_t cover = rig.add_triangle(t);
  for (int i = 0; i < 300; ++i) rig.shade(g, {{3, 5, 1u}});
  rig.shade(g, {{4, 5, 1u}});  // a neighbour in the same block stays narrow
  EXPECT_EQ(rig.tsp_stats.hidden_lit_samples.value(), 0u);
  rig.shade(cover, {{3, 5, 1u}});
  EXPECT_EQ(rig.tsp_stats.hidden_lit_samples.value(), 300u);
  EXPECT_EQ(rig.tsp_stats.hidden_light_evaluations.value(), 600u);
  rig.shade(g, {{3, 5, 1u}});
  rig.shade(g, {{3, 5, 1u}});
  rig.shade(cover, {{3, 5, 1u}, {4, 5, 1u}});
  EXPECT_EQ(rig.tsp_stats.hidden_lit_samples.value(), 303u);
  EXPECT_EQ(rig.tsp_stats.hidden_light_evaluations.value(), 606u);
}

TEST(UnitTsp, HiddenLitSamplesAreCountedPerSampleWithMsaa) {
  // 4 samples per pixel: a lit fragment writing all 4 samples of pixel (0,0), then an unlit one
  // writing samples 0 and 1 only: 2 of the lit fragment's samples are hidden, each counting the
  // fragment's 2 lights (4 evaluations: per hidden sample, not per fragment).
  RenderRig rig(RenderSpec{.attachments = default_attachments(4), .lights = two_lights()});
  ASSERT_EQ(rig.samples_per_pixel(), 4);
  rig.keep_lit_sample_ledger();
  const std::uint32_t lit = rig.add_draw(make_shader(1, 12, LightSource::All, 1), {}, {0, 1});
  const std::uint32_t unlit = rig.add_draw(make_shader(1, 0, LightSource::None, 1));
  ScreenTri t = kUpperLeft;
  t.material = 0;  // a scene triangle (opaque material): a lit surface
  t.draw = lit;
  const std::uint32_t a = rig.add_triangle(t);
  t.draw = unlit;
  const std::uint32_t b = rig.add_triangle(t);
  rig.shade(a, {{0, 0, 0xFu}});
  rig.shade(b, {{0, 0, 0x3u}});
  EXPECT_EQ(rig.tsp_stats.hidden_lit_samples.value(), 2u);
  EXPECT_EQ(rig.tsp_stats.hidden_light_evaluations.value(), 4u);
  // The other two follow when they are replaced.
  rig.shade(b, {{0, 0, 0xCu}});
  EXPECT_EQ(rig.tsp_stats.hidden_lit_samples.value(), 4u);
  EXPECT_EQ(rig.tsp_stats.hidden_light_evaluations.value(), 8u);
}

}  // namespace
}  // namespace tbdr
