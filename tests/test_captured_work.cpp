// How the work `tbdrsim import` carries from a real application responds to its own size: a
// transfer's bytes (kernel `transfer`), a captured compute shader's ALU count (`captured_compute`)
// and a captured vertex shader's cost (`shader ... vertex_alu_ops=`). Each figure must move the
// way the physics says and by a size that can be argued; these are responses of the model to its
// inputs (self-consistency), not a comparison with a real GPU.
#include <gtest/gtest.h>

#include <memory>
#include <string>

#include "scene/scene_library.hpp"
#include "stat_lookup.hpp"
#include "timed_run.hpp"
#include "trace_parse_errors.hpp"

namespace tbdr {
namespace {

class CapturedWork : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { scene_ = std::make_unique<Scene>(load_scene("atrium:1")); }
  static void TearDownTestSuite() { scene_.reset(); }
  static Timed run(const std::string& text) { return run_timed(testing_support::parse_text(text), *scene_, {}); }
  static std::unique_ptr<Scene> scene_;
};
std::unique_ptr<Scene> CapturedWork::scene_;

/// A 64x64 frame, one small pass, then `tail` (declarations and dispatches after the pass).
std::string frame_with(const std::string& decl, const std::string& tail) {
  return "tbdrsim-trace 5\nscene atrium detail=1\nframe width=64 height=64 samples=1\n"
         "camera eye=0,0,5 target=0,0,0 up=0,1,0 fov_y_deg=60 near=0.1 far=100\n"
         "shader s alu_ops=8 tex_fetches=0 varyings=0 light_alu_ops=0 light_source=none color_outputs=1\n" +
         decl +
         "pipeline p shader=s depth_test=no depth_write=no blend=off cull=none\n"
         "pass main\n"
         "  attachment color format=rgba8 samples=1 load=clear store=store usage=color\n"
         "  draw fullscreen pipeline=p lights=none\n"
         "end\n" +
         tail;
}

/// A transfer of `bytes` read and `bytes` written, one thread per 16 bytes in groups of 64. Its
/// source is of class `other`, which nothing in the frame produced: its reads get addresses of
/// their own. (A source of class `color` is read where the frame's last colour producer wrote: a
/// mip chain's blit reads the level the blit before it wrote.)
std::string transfer(std::uint64_t bytes) {
  const std::uint64_t groups = bytes / 16 / 64;
  return frame_with("buffer src bytes=" + std::to_string(bytes) + " traffic=other content=other upload=yes\n"
                    "buffer dst bytes=" + std::to_string(bytes) + " traffic=color content=other\n",
                    "dispatch transfer groups=" + std::to_string(groups) + ",1,1 group_size=64,1,1 reads=src writes=dst\n");
}

TEST_F(CapturedWork, ATransferTwiceAsLargeMovesTwiceTheBytesAndTakesLonger) {
  // 1 MiB and 2 MiB copies after the same pass. The bytes at DRAM grow by exactly the extra
  // 1 MiB read + 1 MiB written (the pass is the same). A copy has no ALU work: it is a stream of
  // memory reads and writes, so its time grows with its bytes; the frame (pass + copy) is not
  // twice as long, but the copy's extra 2 MiB at the peak of 12.8 GB/s take at least
  // 2,097,152 / 12.8e9 s = 164 us = 98,000 cycles at 600 MHz.
  const Timed one = run(transfer(1 << 20)), two = run(transfer(2 << 20));
  const double bytes_one = stat(one, "mem/dram", "read_bytes") + stat(one, "mem/dram", "write_bytes");
  const double bytes_two = stat(two, "mem/dram", "read_bytes") + stat(two, "mem/dram", "write_bytes");
  EXPECT_NEAR(bytes_two - bytes_one, 2.0 * (1 << 20), 0.02 * (1 << 20));
  EXPECT_EQ(stat(one, "frame/compute", "compute_alu_ops"), 0);
  EXPECT_GT(two.timing.frame_cycles - one.timing.frame_cycles, 98000.0)
      << one.timing.frame_cycles << " -> " << two.timing.frame_cycles;
}

/// A captured compute dispatch of 64 x 64 workgroups of 64 threads, `alu` ALU operations each.
std::string compute(int alu) {
  return frame_with("buffer out bytes=4096 traffic=other content=other\n",
                    "dispatch captured_compute groups=64,64,1 group_size=64,1,1 writes=out alu_ops=" + std::to_string(alu) + "\n");
}

TEST_F(CapturedWork, ACapturedComputeShaderWithTwiceTheAluWorkTakesAboutTwiceAsLong) {
  // 262,144 threads x 2000 or 4000 ALU operations: 524 M or 1,049 M operations against 4 KiB of
  // memory, an ALU-bound dispatch. The operations double exactly; the frame's cycles, dominated
  // by the dispatch, grow by 1.8x to 2.05x (the pass before it is the same).
  const Timed one = run(compute(2000)), two = run(compute(4000));
  EXPECT_EQ(stat(two, "frame/compute", "compute_alu_ops"), 2.0 * stat(one, "frame/compute", "compute_alu_ops"));
  EXPECT_EQ(stat(one, "frame/compute", "compute_alu_ops"), 262144.0 * 2000);
  const double ratio = two.timing.frame_cycles / one.timing.frame_cycles;
  EXPECT_GT(ratio, 1.8) << one.timing.frame_cycles << " -> " << two.timing.frame_cycles;
  EXPECT_LT(ratio, 2.05);
}

TEST_F(CapturedWork, ACapturedVertexShaderCostReplacesTheHardwareParameter) {
  // The full-screen triangle's 3 vertices at vertex_alu_ops=100 and 1000: 300 and 3000 vertex
  // ALU operations, whatever geometry.vertex_shader_alu_ops says (24 by default: 72 without the
  // key). The frame never gets cheaper for a costlier vertex shader.
  auto with_cost = [&](const std::string& key) {
    std::string text = frame_with("", "");
    const std::string from = "color_outputs=1\n";
    text.replace(text.find(from), from.size(), "color_outputs=1" + key + "\n");
    return run(text);
  };
  const Timed none = with_cost(""), cheap = with_cost(" vertex_alu_ops=100"), dear = with_cost(" vertex_alu_ops=1000");
  EXPECT_EQ(stat(none, "frame/geometry", "vertex_alu_ops"), 3 * 24);
  EXPECT_EQ(stat(cheap, "frame/geometry", "vertex_alu_ops"), 3 * 100);
  EXPECT_EQ(stat(dear, "frame/geometry", "vertex_alu_ops"), 3 * 1000);
  EXPECT_GE(dear.timing.frame_cycles, cheap.timing.frame_cycles);
}

}  // namespace
}  // namespace tbdr
