// The texture-bound roofline: texture.texels_per_clock counts bilinear-filtered texels (one per
// bilinear fetch) per clock per texture unit, and a frame whose shader is all texture fetches takes
// filtered texels / (texture.units x texture.texels_per_clock) cycles.
#include <gtest/gtest.h>

#include "models/hw_config.hpp"
#include "models/command_processor.hpp"
#include "app/run_driver.hpp"
#include "synthetic_scene.hpp"
#include "timed_run.hpp"

namespace tbdr {
namespace {

using namespace synthetic;


/// One opaque quad covering a `size` x `size` frame, shaded with `alu_ops` ALU ops and
/// `tex_fetches` bilinear fetches per fragment; its material has no texture, so every fetch reads
/// the 4x4 default texture (one cache line per fetch slot: no memory bound).
Timed textured_frame(int size, std::uint32_t alu_ops, std::uint32_t tex_fetches, const std::vector<std::string>& sets) {
  Scene s = base_scene();
  add_quad(s, "wall", 3, -8, kSize + 8, 0);
  Trace t = base_trace();
  t.frame.width = size;
  t.frame.height = size;
  t.shaders[0].alu_ops = alu_ops;
  t.shaders[0].tex_fetches = tex_fetches;
  PassDesc p = base_pass();
  p.draws = {draw_of("wall")};
  t.commands.push_back(p);
  return run_timed(t, s, sets);
}

std::uint64_t frame_texels(const Timed& r) {
  std::uint64_t texels = 0;
  for (const auto& c : r.frame.work.commands) {
    for (const auto& rw : c.renders) {
      for (const auto& tw : rw.tiles) texels += tw.texels;
    }
  }
  return texels;
}

// 256 x 256 pixels = 16384 quads, plus the 128 quads on the quad's diagonal that both of its
// triangles launch: 16512 quads x 4 lanes x 16 fetches = 1056768 bilinear fetches.
constexpr std::uint64_t kFetches = (16384 + 128) * 4 * 16;

TEST(TextureRoofline, BilinearFetchIsOneFilteredTexel) {
  // Each bilinear fetch is one filtered texel (texture.filtered_texels_per_fetch = 1), not the 4
  // texels it reads; a trilinear one (= 2) two.
  const Timed r = textured_frame(256, 1, 16, {});
  EXPECT_EQ(frame_texels(r), kFetches);
  const Timed tri = textured_frame(256, 1, 16, {"texture.filtered_texels_per_fetch=2"});
  EXPECT_EQ(frame_texels(tri), 2 * kFetches);
}

TEST(TextureRoofline, TextureBoundFrameTakesTexelsOverTheTextureRate) {
  // Bound: 1056768 filtered texels / (2 units x 4 per clock) = 132096 cycles. The other units are
  // far below it: ALU 66048 lanes / (4 USCs x 16 lanes x 2) = 516 cycles, ISP 65536 samples / 32 =
  // 2048 cycles, colour store 256 KiB / 12.8 GB/s x 600 MHz = 12288 cycles (overlapped with
  // shading). Within 3 %: what is left is the first tile's ISP work before the USCs start and the
  // last tile's store after they finish (a few hundred cycles).
  const Timed two = textured_frame(256, 1, 16, {});
  const double bound2 = static_cast<double>(kFetches) / (2 * 4);
  EXPECT_NEAR(two.timing.frame_cycles, bound2, 0.03 * bound2);
  // Twice the texture units: half the bound (66048 cycles), and the frame follows it.
  const Timed four = textured_frame(256, 1, 16, {"texture.units=4"});
  const double bound4 = static_cast<double>(kFetches) / (4 * 4);
  EXPECT_NEAR(four.timing.frame_cycles, bound4, 0.03 * bound4);
  EXPECT_NEAR(four.timing.frame_cycles / two.timing.frame_cycles, 0.5, 0.03);
  // Twice the rate per unit: the same as twice the units.
  const Timed fast = textured_frame(256, 1, 16, {"texture.texels_per_clock=8"});
  EXPECT_NEAR(fast.timing.frame_cycles, four.timing.frame_cycles, 0.01 * four.timing.frame_cycles);
}

TEST(TextureRoofline, AluBoundFrameIgnoresTheTextureUnits) {
  // Past the knee: 1024 ALU ops and 16 fetches per fragment. ALU 66048 lanes x 1024 / 128 =
  // 528384 cycles against 132096 for the texture units: more texture units change nothing
  // (within 1 %).
  const Timed two = textured_frame(256, 1024, 16, {});
  const Timed four = textured_frame(256, 1024, 16, {"texture.units=4"});
  const double alu_bound = (16384.0 + 128) * 4 * 1024 / 128;
  EXPECT_NEAR(two.timing.frame_cycles, alu_bound, 0.03 * alu_bound);
  EXPECT_NEAR(four.timing.frame_cycles, two.timing.frame_cycles, 0.01 * two.timing.frame_cycles);
}

}  // namespace
}  // namespace tbdr
