// What more tag buffers buy on a workload built for it: layers of blended geometry over an opaque
// background, then an opaque surface in front of them all (a near occluder an unsorted engine
// submits after its particles or glass). One tag buffer flushes the tile at every layer; more
// buffers keep the layers pending and the occluder removes them unshaded (models/isp.hpp,
// Imagination's US 8,446,409). Every count derived by hand; the cycles from the timing model on
// the measured tile work (no memory traffic: nothing but the units' throughput decides them).
#include <gtest/gtest.h>

#include <cstdio>
#include <string>
#include <vector>

#include "unit_fixture.hpp"

namespace tbdr {
namespace {

using namespace unit;

// FULL: (0,0), (128,0), (0,128) covers every sample of the 64x64 viewport (the farthest sample,
// (63.5, 63.5), has x + y = 127 < 128), so each of the 4 tiles sees each layer on all its 1024
// samples (1 sample per pixel).
const ScreenTri kFull{{0, 0}, {128, 0}, {0, 128}};
constexpr std::uint64_t kTileSamples = 32 * 32;
constexpr std::uint64_t kTiles = 4;
constexpr std::uint64_t kBlendedLayers = 3;      // K: translucent layers between background and occluder
constexpr std::uint32_t kShaderAluOps = 64;      // ALU ops per fragment of every draw
constexpr std::uint64_t kPrimitives = kBlendedLayers + 2;

struct LayersRun {
  IspStats isp;
  TspStats tsp;
  double frame_cycles = 0;
  double usc_busy_cycles = 0;
};

/// Background B (z 0.9), K blended layers (z 0.8, 0.7, 0.6; no depth write), occluder O (z 0.1),
/// rendered on the 4 tiles with `buffers` tag buffers; then the 4 tiles' work through the timing
/// model.
LayersRun run_layers(int buffers) {
  const std::vector<std::string> sets = {"isp.tag_buffers=" + std::to_string(buffers)};
  RenderRig rig(RenderSpec{.sets = sets});
  rig.add_draw(make_shader(kShaderAluOps));
  PipelineState blend;
  blend.depth_write = false;
  blend.blend = BlendMode::Alpha;
  rig.add_draw(make_shader(kShaderAluOps), blend);
  ScreenTri t = kFull;
  t.z = 0.9f;
  rig.add_triangle(t);
  for (std::uint64_t k = 0; k < kBlendedLayers; ++k) {
    t.z = 0.8f - 0.1f * static_cast<float>(k);
    t.draw = 1;
    t.hsr = HsrClass::Translucent;
    rig.add_triangle(t);
  }
  t.z = 0.1f;
  t.draw = 0;
  t.hsr = HsrClass::Opaque;
  rig.add_triangle(t);
  std::vector<TileWork> tiles;
  for (int ty = 0; ty < 2; ++ty) {
    for (int tx = 0; tx < 2; ++tx) {
      const IspStats isp0 = rig.isp_stats;
      const TspStats tsp0 = rig.tsp_stats;
      rig.render_tile(RenderRig::tile_rect(tx, ty));
      TileWork w = tile_work(tx, ty, rig.isp_stats.primitives_fetched.value() - isp0.primitives_fetched.value(),
                             rig.isp_stats.samples_rasterised.value() - isp0.samples_rasterised.value(),
                             rig.tsp_stats.fragment_alu_ops.value() - tsp0.fragment_alu_ops.value());
      w.invocations = rig.tsp_stats.shader_invocations.value() - tsp0.shader_invocations.value();
      w.quads = rig.tsp_stats.shaded_quads.value() - tsp0.shaded_quads.value();
      w.isp_wait_alu_ops = rig.isp_stats.resolve_wait_alu_ops.value() - isp0.resolve_wait_alu_ops.value();
      tiles.push_back(std::move(w));
    }
  }
  const TimingResult r = run_schedule(frame_work({pass_work("layers", {render_work(tiles, binning_work(kPrimitives))})}), sets);
  return {rig.isp_stats, rig.tsp_stats, r.frame_cycles, r.unit(TimedUnit::Usc).busy_cycles};
}

TEST(TagBufferBenefit, LayersOverABackgroundAreBatchedAndTheOccluderRemovesThemUnshaded) {
  // Per tile, the K + 1 = 4 layers B, T1, T2, T3 are pushed before O; a push into a full stack
  // (L layers) flushes the tile, so the flushes are ceil((K + 1) / L) - 1 and the layers O finds
  // pending (and removes unshaded) are (K + 1) - L x flushes:
  //   L = 1: 3 flushes (B, T1, T2 shaded mid-tile), T3 removed: 3 layers + O shaded = 4 x 1024
  //   L = 2: 1 flush (B, T1), T2 and T3 removed:                 2 layers + O       = 3 x 1024
  //   L = 4: no flush, B..T3 removed:                                         O only = 1 x 1024
  //   L = 8: as 4 (the stack never fills).
  // Each shaded layer is the full tile: 256 quads, no helper lanes, 1024 x 64 ALU ops.
  struct Expect {
    int buffers;
    std::uint64_t flushes_per_tile, shaded_layers, removed_layers;
  };
  const Expect expected[] = {{1, 3, 4, 1}, {2, 1, 3, 2}, {4, 0, 1, 4}, {8, 0, 1, 4}};
  double previous_cycles = 0;
  double one_buffer_cycles = 0, one_buffer_usc = 0;
  for (const Expect& e : expected) {
    SCOPED_TRACE("isp.tag_buffers=" + std::to_string(e.buffers));
    const LayersRun run = run_layers(e.buffers);
    EXPECT_EQ(run.isp.tag_flushes.value(), kTiles * e.flushes_per_tile);
    EXPECT_EQ(run.isp.tag_flushed_samples.value(), kTiles * kTileSamples * (kBlendedLayers + 1 - e.removed_layers));
    EXPECT_EQ(run.isp.hsr_removed_samples.value(), kTiles * kTileSamples * e.removed_layers);
    EXPECT_EQ(run.isp.resolve_flushes.value(), 0u);  // nothing punch-through: the ISP never waits
    EXPECT_EQ(run.tsp.shader_invocations.value(), kTiles * kTileSamples * e.shaded_layers);
    EXPECT_EQ(run.tsp.fragment_alu_ops.value(), kTiles * kTileSamples * e.shaded_layers * kShaderAluOps);
    // The USCs' time is the ALU work over their rate (4 USCs x 16 lanes x 2 ops per clock = 128
    // ops per clock): 4 tiles x 1024 x 64 / 128 = 2048 cycles per shaded layer.
    EXPECT_DOUBLE_EQ(run.usc_busy_cycles, 2048.0 * static_cast<double>(e.shaded_layers));
    std::printf("[ layers   ] %d tag buffers: %llu flushes, %llu invocations, USC %.0f cycles, frame %.0f cycles\n", e.buffers,
                static_cast<unsigned long long>(run.isp.tag_flushes.value()),
                static_cast<unsigned long long>(run.tsp.shader_invocations.value()), run.usc_busy_cycles, run.frame_cycles);
    if (e.buffers == 1) {
      one_buffer_cycles = run.frame_cycles;
      one_buffer_usc = run.usc_busy_cycles;
    } else {
      // Never slower than with fewer buffers; 8 the same as 4 (nothing left to batch).
      EXPECT_LE(run.frame_cycles, previous_cycles);
      if (e.buffers == 8) {
        EXPECT_EQ(run.frame_cycles, previous_cycles);
      } else {
        EXPECT_LT(run.frame_cycles, previous_cycles);
      }
      // The frame is USC-bound here: it saves at least 90 % of the USC cycles saved
      // (2048 with 2 buffers, 6144 with 4 of 8192).
      EXPECT_GE(one_buffer_cycles - run.frame_cycles, 0.9 * (one_buffer_usc - run.usc_busy_cycles));
    }
    previous_cycles = run.frame_cycles;
  }
}

}  // namespace
}  // namespace tbdr
