// A render pass at its own size (trace version 5, `pass NAME area=x0,y0,x1,y1`): the reader's
// checks and round trip, and the models: a pass whose area is W x H inside a larger frame does
// the work of the same pass in a W x H frame (samples, shaded fragments, tiles, region headers,
// loads, clears and stores), and nothing outside its area.
#include <gtest/gtest.h>

#include <sstream>
#include <string>

#include "kernel/errors.hpp"
#include "scene/scene_library.hpp"
#include "stat_lookup.hpp"
#include "timed_run.hpp"
#include "trace/trace.hpp"
#include "trace_parse_errors.hpp"

namespace tbdr {
namespace {

Trace parse(const std::string& text) { return testing_support::parse_text(text); }

/// A one-pass trace: a `frame` of w x h, the pass line `pass_line` (line 7), a colour target
/// cleared and stored, and one full-screen draw whose shader does 8 ALU operations a fragment.
std::string one_pass(int version, int w, int h, const std::string& pass_line) {
  return "tbdrsim-trace " + std::to_string(version) + "\n" +                                   // 1
         "scene atrium detail=1\n"                                                             // 2
         "frame width=" + std::to_string(w) + " height=" + std::to_string(h) + " samples=1\n"  // 3
         "camera eye=0,0,5 target=0,0,0 up=0,1,0 fov_y_deg=60 near=0.1 far=100\n"              // 4
         "shader s alu_ops=8 tex_fetches=0 varyings=0 light_alu_ops=0 light_source=none color_outputs=1\n"
         "pipeline p shader=s depth_test=no depth_write=no blend=off cull=none\n"  // 6
         + pass_line + "\n"                                                       // 7
         "  attachment color format=rgba8 samples=1 load=clear store=store usage=color\n"
         "  draw fullscreen pipeline=p lights=none\n"
         "end\n";
}

void expect_error(const std::string& text, int line, const std::string& token) {
  testing_support::expect_trace_error(text, line, token);
}

TEST(TracePassArea, ReadWrittenAsVersion5AndRoundTrips) {
  const Trace t = parse(one_pass(5, 128, 96, "pass shadow area=0,0,64,48"));
  const auto& p = std::get<PassDesc>(t.commands.front());
  ASSERT_TRUE(p.area.has_value());
  EXPECT_EQ(*p.area, (ScissorRect{0, 0, 64, 48}));
  const std::string text = trace_text(t);
  EXPECT_EQ(text.rfind("tbdrsim-trace 5\n", 0), 0u) << text;
  EXPECT_NE(text.find("pass shadow area=0,0,64,48\n"), std::string::npos) << text;
  EXPECT_EQ(trace_text(parse(text)), text);
  // Without an area nothing needs version 5: a single frame is still written as version 3.
  const Trace plain = parse(one_pass(5, 128, 96, "pass main"));
  EXPECT_FALSE(std::get<PassDesc>(plain.commands.front()).area.has_value());
  EXPECT_EQ(trace_text(plain).rfind("tbdrsim-trace 3\n", 0), 0u);
}

TEST(TracePassArea, RefusedInOlderVersionsBeyondTheFrameOrEmpty) {
  expect_error(one_pass(4, 128, 96, "pass shadow area=0,0,64,48"), 7, "needs trace version 5");
  expect_error(one_pass(5, 128, 96, "pass shadow area=0,0,129,48"), 7, "reaches beyond the frame (128x96)");
  expect_error(one_pass(5, 128, 96, "pass shadow area=0,0,64,97"), 7, "reaches beyond the frame");
  expect_error(one_pass(5, 128, 96, "pass shadow area=10,0,10,48"), 7, "is empty");
  expect_error(one_pass(5, 128, 96, "pass shadow area=0,0,64"), 7, "malformed area");
  expect_error(one_pass(5, 128, 96, "pass shadow size=64"), 7, "size");
}

class PassAreaRun : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { scene_ = std::make_unique<Scene>(load_scene("atrium:1")); }
  static void TearDownTestSuite() { scene_.reset(); }
  static Timed run(int w, int h, const std::string& pass_line, const std::string& mode = "tbdr") {
    return run_timed(parse(one_pass(5, w, h, pass_line)), *scene_, {"gpu.mode=" + mode});
  }
  static std::unique_ptr<Scene> scene_;
};
std::unique_ptr<Scene> PassAreaRun::scene_;

TEST_F(PassAreaRun, APassAtItsOwnSizeDoesTheWorkOfThatSizeNotTheFrames) {
  // A 64x48 area in a 256x192 frame against the same pass in a 64x48 frame, and the whole
  // 256x192 frame. With the default 32x32 tiles the area has 2 x 2 = 4 tiles (the second row
  // 16 pixels high), the frame 8 x 6 = 48. The full-screen triangle covers every pixel:
  // 64 x 48 = 3072 samples shaded, 3072 x 4 = 12288 colour bytes cleared and stored.
  const Timed area = run(256, 192, "pass shadow area=0,0,64,48");
  const Timed small = run(64, 48, "pass shadow");
  const Timed whole = run(256, 192, "pass shadow");
  for (const char* name : {"samples_rasterised", "tiles_rendered"}) {
    EXPECT_EQ(stat(area, "frame/isp", name), stat(small, "frame/isp", name)) << name;
  }
  EXPECT_EQ(stat(area, "frame/isp", "samples_rasterised"), 64 * 48);
  EXPECT_EQ(stat(area, "frame/isp", "tiles_rendered"), 4);
  EXPECT_EQ(stat(whole, "frame/isp", "tiles_rendered"), 48);
  EXPECT_EQ(stat(area, "frame/tsp", "shader_invocations"), 64 * 48);
  for (const char* name : {"tile_clear_bytes", "tile_store_bytes"}) {
    EXPECT_EQ(stat(area, "frame/tile_memory", name), 64 * 48 * 4) << name;
    EXPECT_EQ(stat(whole, "frame/tile_memory", name), 256 * 192 * 4) << name;
  }
  // Region headers for the area's 4 tiles, not the frame's 48.
  EXPECT_EQ(stat(area, "frame/tiler", "pb_region_header_bytes"), stat(small, "frame/tiler", "pb_region_header_bytes"));
  EXPECT_EQ(stat(whole, "frame/tiler", "pb_region_header_bytes"), 12 * stat(area, "frame/tiler", "pb_region_header_bytes"));
  // Time: the area's frame costs what the small frame costs. The work is the same; only the
  // addresses differ (the image's rows are 256 pixels apart, not 64), so the DRAM timing may
  // differ a little: within 5 %. The whole frame has 16 times the pixels: far slower.
  const double area_cycles = area.timing.frame_cycles, small_cycles = small.timing.frame_cycles;
  EXPECT_NEAR(area_cycles / small_cycles, 1.0, 0.05) << area_cycles << " vs " << small_cycles;
  EXPECT_GT(whole.timing.frame_cycles, 8.0 * area_cycles);
  // Nothing outside the area was written: the frame's pixels beyond it were never shaded.
  const auto& shaded = area.frame.images.counters.shaded;
  for (int y = 0; y < 192; y += 7) {
    for (int x = 0; x < 256; x += 5) {
      EXPECT_EQ(shaded[static_cast<std::size_t>(y * 256 + x)] > 0, x < 64 && y < 48) << x << "," << y;
    }
  }
}

TEST_F(PassAreaRun, AnImmediateModeGpuAlsoTouchesOnlyTheArea) {
  // imr has no tiles: its framebuffer traffic goes through the ROP. The area's pass shades and
  // writes the area's 3072 pixels only, as in the 64x48 frame.
  const Timed area = run(256, 192, "pass shadow area=0,0,64,48", "imr");
  const Timed small = run(64, 48, "pass shadow", "imr");
  EXPECT_EQ(stat(area, "frame/tsp", "shader_invocations"), 64 * 48);
  EXPECT_EQ(stat(area, "frame/isp", "samples_rasterised"), stat(small, "frame/isp", "samples_rasterised"));
}

}  // namespace
}  // namespace tbdr
