// gpu.mode=imr: an immediate-mode GPU. Primitives are rasterised and shaded in submission order
// with early-Z, depth and colour go through the ROP caches (models/rop.hpp) to the framebuffer in
// memory, and geometry, rasterisation, shading and the ROP overlap as a pipeline. The counts here
// are worked out by hand from the framebuffer layout: 4x4-pixel blocks, 64-byte lines, so one line
// holds one block of a 32-bit image.
#include <gtest/gtest.h>

#include "models/hw_config.hpp"
#include "models/command_processor.hpp"
#include "synthetic_scene.hpp"
#include "timed_run.hpp"
#include "stat_lookup.hpp"

namespace tbdr {
namespace {

using namespace synthetic;

constexpr int kFrame = 256;
/// Bytes of a 256x256 image of 32-bit pixels (RGBA8 colour, D24S8 depth): 4096 lines of 64 B.
constexpr double kImageBytes = 256.0 * 256.0 * 4.0;
/// ROP caches larger than both images: nothing is evicted before the flush at the end of the pass.
const std::vector<std::string> kHugeRop = {"cache.rop_depth.size_bytes=1048576", "cache.rop_color.size_bytes=1048576"};

/// `layers` full-frame quads at 256x256, front to back (nearest first) or back to front, drawn with
/// `pipeline`, each with a shader of `alu_ops` ALU ops and no texture fetch.
struct Layers {
  Scene scene = base_scene();
  Trace trace;
};
Layers layers(int n, bool back_to_front, const std::string& pipeline = "opaque", std::uint32_t alu_ops = 1,
              std::uint32_t material = 0) {
  Layers l;
  l.trace = base_trace();
  l.trace.frame.width = l.trace.frame.height = kFrame;
  l.trace.shaders[0].alu_ops = alu_ops;
  l.trace.shaders[0].tex_fetches = 0;
  PassDesc p = base_pass();
  for (int i = 0; i < n; ++i) {
    const int k = back_to_front ? n - 1 - i : i;
    const std::string name = "layer" + std::to_string(k);
    add_quad(l.scene, name, 2.0f + 0.1f * static_cast<float>(k), -256, 512, material);
    p.draws.push_back(draw_of(name, pipeline));
  }
  l.trace.commands.push_back(p);
  return l;
}

std::vector<std::string> with(std::vector<std::string> a, const std::vector<std::string>& b) {
  a.insert(a.end(), b.begin(), b.end());
  return a;
}

double dram_of(const Timed& r, DramClass c, bool write) {
  return static_cast<double>(write ? r.frame.dram.writes(c) : r.frame.dram.reads(c));
}

TEST(ImmediateMode, OneQuadWritesEachLineOnceWithFastClearAndBigCaches) {
  // One opaque full-frame quad. Fast clear: the first touch of each cleared line fetches nothing;
  // with caches larger than the images nothing is evicted, so the flush at the end of the pass
  // writes every depth and colour line exactly once: 256 KiB each, and nothing is read.
  const Layers l = layers(1, false);
  const Timed r = run_timed(l.trace, l.scene, with({"gpu.mode=imr"}, kHugeRop));
  EXPECT_EQ(dram_of(r, DramClass::Color, true), kImageBytes);
  EXPECT_EQ(dram_of(r, DramClass::DepthStencil, true), kImageBytes);
  EXPECT_EQ(dram_of(r, DramClass::Color, false), 0.0);
  EXPECT_EQ(dram_of(r, DramClass::DepthStencil, false), 0.0);
  EXPECT_EQ(stat(r.stats, "frame/rop", "fast_cleared_fills"), 2.0 * kImageBytes / 64.0);
  EXPECT_EQ(stat(r.stats, "frame/rop", "clear_bytes"), 0.0);  // every cleared line was touched
  // The timing model moved the same bytes through the SLC to DRAM (nothing stayed dirty in the SLC
  // at the end: the lines were written past it or evicted; the requested bytes are what matters).
  EXPECT_EQ(static_cast<double>(r.timing.requested.writes(DramClass::Color)), kImageBytes);
  EXPECT_EQ(static_cast<double>(r.timing.requested.writes(DramClass::DepthStencil)), kImageBytes);
}

TEST(ImmediateMode, WrittenClearsCostTheImageAndItsReadBack) {
  // imr.clear=write: each clear writes its image (256 KiB colour + 256 KiB depth: the transient
  // depth is lowered to an ordinary image on an IMR); the first depth test of each line then misses
  // and reads it back (256 KiB), while colour writes allocate without a fetch. At the end each
  // line is written once more: writes 2 x 512 KiB, reads 256 KiB of depth.
  const Layers l = layers(1, false);
  const Timed r = run_timed(l.trace, l.scene, with({"gpu.mode=imr", "imr.clear=write"}, kHugeRop));
  EXPECT_EQ(dram_of(r, DramClass::Color, true), 2 * kImageBytes);
  EXPECT_EQ(dram_of(r, DramClass::DepthStencil, true), 2 * kImageBytes);
  EXPECT_EQ(dram_of(r, DramClass::DepthStencil, false), kImageBytes);
  EXPECT_EQ(dram_of(r, DramClass::Color, false), 0.0);
  EXPECT_EQ(stat(r.stats, "frame/rop", "clear_bytes"), 2 * kImageBytes);
}

TEST(ImmediateMode, OverdrawCostsAnImrDramAndATbdrNothing) {
  // 8 opaque layers back to front: each passes the depth test, so an IMR rasterises, shades and
  // writes every layer. With 16 KiB ROP caches (256 lines; a layer touches 4096 per image) every
  // layer evicts the one before: each layer after the first re-reads the depth lines (7 x 256 KiB,
  // plus the lines of the quad's diagonal, which its second triangle touches after they were
  // evicted), and every layer writes depth and colour back (8 x 512 KiB). A TBDR keeps depth on
  // chip and stores the colour once: 256 KiB, whatever the overdraw.
  const Layers l = layers(8, true);
  const Timed imr = run_timed(l.trace, l.scene, {"gpu.mode=imr"});
  const Timed tbdr = run_timed(l.trace, l.scene, {"gpu.mode=tbdr"});
  const double depth_reads = dram_of(imr, DramClass::DepthStencil, false);
  const double writes = dram_of(imr, DramClass::Color, true) + dram_of(imr, DramClass::DepthStencil, true);
  EXPECT_GE(depth_reads, 7 * kImageBytes);
  EXPECT_LE(depth_reads, 7 * kImageBytes * 1.1);  // the diagonals: 64 blocks of 4096 per layer, about 2 %
  EXPECT_GE(writes, 8 * 2 * kImageBytes);
  EXPECT_LE(writes, 8 * 2 * kImageBytes * 1.1);
  EXPECT_EQ(dram_of(tbdr, DramClass::Color, true), kImageBytes);
  EXPECT_EQ(dram_of(tbdr, DramClass::DepthStencil, true) + dram_of(tbdr, DramClass::DepthStencil, false), 0.0);
  // The same 8 layers front to back: early-Z rejects the 7 behind, so the IMR reads each depth
  // line again per layer but writes it, and the colour, once.
  const Layers f = layers(8, false);
  const Timed front = run_timed(f.trace, f.scene, {"gpu.mode=imr"});
  EXPECT_LT(dram_of(front, DramClass::Color, true), 1.1 * kImageBytes);
  EXPECT_GE(dram_of(front, DramClass::Color, true), kImageBytes);
}

TEST(ImmediateMode, BiggerRopCachesNeverMoveMoreBytes) {
  // The same 8 back-to-front layers with 4, 16, 64 KiB and 1 MiB ROP caches: DRAM framebuffer
  // bytes never grow with the cache; at 1 MiB both images fit and each line moves once (512 KiB).
  const Layers l = layers(8, true);
  double prev = 1e300;
  for (const int kib : {4, 16, 64, 1024}) {
    const std::string size = std::to_string(kib * 1024);
    const Timed r = run_timed(l.trace, l.scene, {"gpu.mode=imr", "cache.rop_depth.size_bytes=" + size, "cache.rop_color.size_bytes=" + size});
    const double bytes = dram_of(r, DramClass::Color, true) + dram_of(r, DramClass::DepthStencil, true) +
                         dram_of(r, DramClass::Color, false) + dram_of(r, DramClass::DepthStencil, false);
    EXPECT_LE(bytes, prev) << kib << " KiB";
    prev = bytes;
  }
  EXPECT_EQ(prev, 2 * kImageBytes);
}

TEST(ImmediateMode, ShadesWhatEarlyZInSubmissionOrderShades) {
  // IMR and TBR (no forward pixel kill) both test depth early, in submission order: the same
  // samples are rasterised and shaded. Back to front, all 8 layers are shaded (8 per pixel); the
  // TBDR's tag buffer shades the front one only.
  const Layers l = layers(8, true);
  const Timed imr = run_timed(l.trace, l.scene, {"gpu.mode=imr"});
  const Timed tbr = run_timed(l.trace, l.scene, {"gpu.mode=tbr"});
  const Timed tbdr = run_timed(l.trace, l.scene, {"gpu.mode=tbdr"});
  const double pixels = kFrame * kFrame;
  EXPECT_EQ(stat(imr.stats, "frame/tsp", "shaded_samples"), stat(tbr.stats, "frame/tsp", "shaded_samples"));
  EXPECT_EQ(stat(imr.stats, "frame/isp", "samples_rasterised"), stat(tbr.stats, "frame/isp", "samples_rasterised"));
  EXPECT_EQ(stat(imr.stats, "frame/tsp", "shaded_samples"), 8 * pixels);
  EXPECT_EQ(stat(tbdr.stats, "frame/tsp", "shaded_samples"), pixels);
}

TEST(ImmediateMode, BlendingReadsTheColourBuffer) {
  // 4 translucent (alpha-blended, no depth write) full-frame layers: each blended write reads its
  // line first. With 16 KiB caches every layer after the first fetches the colour lines the one
  // before wrote back (3 x 256 KiB, plus the diagonals); the first finds fast-cleared lines.
  // With caches that hold the image, nothing is fetched.
  const Layers l = layers(4, true, "blend", 1, 2);
  const Timed small = run_timed(l.trace, l.scene, {"gpu.mode=imr"});
  const Timed big = run_timed(l.trace, l.scene, with({"gpu.mode=imr"}, kHugeRop));
  const double fill = stat(small.stats, "frame/rop", "fill_bytes") - dram_of(small, DramClass::DepthStencil, false);
  EXPECT_GE(fill, 3 * kImageBytes);
  EXPECT_LE(fill, 3 * kImageBytes * 1.1);
  EXPECT_EQ(dram_of(big, DramClass::Color, false), 0.0);
  EXPECT_GT(stat(small.stats, "frame/rop", "color_read_misses"), 0.0);
}

TEST(ImmediateMode, UnitsOverlapAsAPipeline) {
  // 32 back-to-front layers at 256x256, 4 ALU ops per pixel. Per layer: the ISP needs
  // 65536 / 32 = 2048 cycles, the USCs 65536 x 4 / (4 x 16 x 2) = 2048, and the colour outputs
  // 65536 x 4 B / (4 USCs x 16 B/clock) = 4096 on the USCs' pixel data path (the busiest: 131072
  // cycles for the frame). One batch of every primitive serialises them: the ISP's 65536 cycles,
  // then shading's 131072. Batches of one layer (2 triangles) rasterise the next layers while the
  // USCs shade this one: the ISP's time hides under shading, about 65536 cycles saved.
  // ROP caches that hold both images keep DRAM out of it (with 16 KiB ones the 32 layers' depth
  // re-reads and write-backs, 24 MiB, make the frame memory-bound: OverdrawCosts... above); both
  // end with the same flush of the two images (512 KiB) to DRAM.
  const Layers l = layers(32, true, "opaque", 4);
  const Timed serial = run_timed(l.trace, l.scene, with({"gpu.mode=imr", "imr.primitives_per_batch=1048576"}, kHugeRop));
  const Timed piped = run_timed(l.trace, l.scene, with({"gpu.mode=imr", "imr.primitives_per_batch=2"}, kHugeRop));
  const double isp = 32 * 2048.0, data_path = 32 * 4096.0;
  EXPECT_GE(serial.timing.frame_cycles, isp + data_path);
  EXPECT_GE(piped.timing.frame_cycles, data_path);
  EXPECT_GE(serial.timing.frame_cycles - piped.timing.frame_cycles, 0.9 * isp)
      << "piped " << piped.timing.frame_cycles << " serial " << serial.timing.frame_cycles;
  // Same work either way: batching moves time, not counts.
  EXPECT_EQ(stat(serial.stats, "frame/tsp", "fragment_alu_ops"), stat(piped.stats, "frame/tsp", "fragment_alu_ops"));
  EXPECT_EQ(serial.frame.dram.total_written(), piped.frame.dram.total_written());
}

}  // namespace
}  // namespace tbdr

namespace tbdr {
namespace {

using namespace synthetic;

/// layers() with a lit shader: every fragment evaluates the trace's 3 lights (light_source=all).
Layers lit_layers(int n, bool back_to_front) {
  Layers l = layers(n, back_to_front);
  l.trace.shaders[0].light_source = LightSource::All;
  l.trace.shaders[0].light_alu_ops = 12;
  for (int i = 0; i < 3; ++i) {
    Light light;
    light.position = {static_cast<float>(i), 0.0f, -2.0f};
    light.radius = 5.0f;
    l.trace.lights.push_back(light);
  }
  return l;
}

TEST(ImmediateMode, BackToFrontLitLayersHideOneScreenOfSamplesWithEarlyZAndNoneOnATbdr) {
  // Two full-frame opaque lit quads, the far one first. IMR (early-Z in submission order): the
  // far quad passes and writes every sample, lit; the near one passes too and replaces each: one
  // screen of lit samples hidden, 256 x 256 = 65,536, each having evaluated 3 lights (196,608).
  // The TBDR's tag buffer removes the far quad before shading: nothing lit is hidden.
  const Layers l = lit_layers(2, true);
  const double screen = kFrame * kFrame;
  const Timed imr = run_timed(l.trace, l.scene, {"gpu.mode=imr"});
  const Timed tbr = run_timed(l.trace, l.scene, {"gpu.mode=tbr"});
  const Timed tbdr = run_timed(l.trace, l.scene, {"gpu.mode=tbdr"});
  EXPECT_EQ(stat(imr.stats, "frame/tsp", "lit_surface_invocations"), 2 * screen);
  EXPECT_EQ(stat(imr.stats, "frame/tsp", "hidden_lit_samples"), screen);
  EXPECT_EQ(stat(imr.stats, "frame/tsp", "hidden_light_evaluations"), 3 * screen);
  EXPECT_EQ(stat(tbr.stats, "frame/tsp", "hidden_lit_samples"), screen);  // tbr: the same order
  EXPECT_EQ(stat(tbdr.stats, "frame/tsp", "lit_surface_invocations"), screen);
  EXPECT_EQ(stat(tbdr.stats, "frame/tsp", "hidden_lit_samples"), 0.0);
  EXPECT_EQ(stat(tbdr.stats, "frame/tsp", "hidden_light_evaluations"), 0.0);
  // Front to back, early-Z rejects the far quad: nothing hidden. With the tests after the shader
  // (isp.early_z=0) the far quad is shaded everywhere and fails: one screen hidden again.
  const Layers f = lit_layers(2, false);
  EXPECT_EQ(stat(run_timed(f.trace, f.scene, {"gpu.mode=imr"}).stats, "frame/tsp", "hidden_lit_samples"), 0.0);
  const Timed late = run_timed(f.trace, f.scene, {"gpu.mode=imr", "isp.early_z=0"});
  EXPECT_EQ(stat(late.stats, "frame/tsp", "hidden_lit_samples"), screen);
  EXPECT_EQ(stat(late.stats, "frame/tsp", "hidden_light_evaluations"), 3 * screen);
  // 4 back-to-front layers on the IMR: each of the first 3 is replaced by the next: 3 screens.
  const Layers four = lit_layers(4, true);
  EXPECT_EQ(stat(run_timed(four.trace, four.scene, {"gpu.mode=imr"}).stats, "frame/tsp", "hidden_lit_samples"), 3 * screen);
}

}  // namespace
}  // namespace tbdr
