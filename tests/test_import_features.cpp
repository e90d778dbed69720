// `tbdrsim import` of what real applications record beyond vkcube's one triangle draw (capture
// intermediate format 2, docs/capture-import.md): depth clip control (zink draws OpenGL with clip z
// from -w to w), passes at their own render areas, lines and points, instanced draws, scissors,
// MSAA resolves. Each case is a small hand-made intermediate whose pixels can be counted by hand;
// the import is replayed and the simulator's counts are checked against that arithmetic.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "cli_run.hpp"
#include "models/command_processor.hpp"
#include "models/hw_config.hpp"
#include "scene/gltf_loader.hpp"
#include "scratch_dir.hpp"
#include "stat_lookup.hpp"
#include "trace/trace.hpp"

namespace tbdr {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;
using testing_scratch::scratch_dir;
using testing_support::run_cli;

const testing_scratch::ScratchCleanup cleanup{"import_features"};

/// Vulkan clip position of framebuffer pixel coordinates (px, py) in a viewport of w x h at depth
/// z (clip w = 1): x = 2 px / w - 1, y = 2 py / h - 1 (Vulkan's y runs down the framebuffer).
json at(double px, double py, double w, double h, double z = 0.5) { return {2.0 * px / w - 1.0, 2.0 * py / h - 1.0, z, 1.0}; }

/// A draw of `topology` over `clip` (Vulkan clip positions), no depth test, no culling, a shader
/// of 4 ALU operations writing one colour output.
json draw(int event, const std::string& topology, const json& clip) {
  return {{"event", event},
          {"name", "vkCmdDraw()"},
          {"topology", topology},
          {"clip_positions", clip},
          {"depth_test", false},
          {"depth_write", false},
          {"depth_compare", "always"},
          {"cull", "none"},
          {"front_face", "ccw"},
          {"blend", "off"},
          {"shader", {{"alu_ops", 4}, {"tex_fetches", 0}, {"varyings", 0}, {"color_outputs", 1}, {"discard", false}, {"source", "hand"}}},
          {"textures", json::array()}};
}

/// Two triangles covering the w x h viewport at depth z (Vulkan clip space, w = 1).
json quad(int event, double w, double h, double z = 0.5) {
  return draw(event, "triangles",
              json::array({at(0, 0, w, h, z), at(w, 0, w, h, z), at(w, h, w, h, z), at(0, 0, w, h, z), at(w, h, w, h, z),
                           at(0, h, w, h, z)}));
}

/// A pass with one RGBA8 colour target (image `image`) cleared and stored, render area w x h.
json pass(int event, int w, int h, int image, const json& draws) {
  return {{"event", event},
          {"render_area", {0, 0, w, h}},
          {"attachments", json::array({{{"index", 0}, {"vk_format", "VK_FORMAT_R8G8B8A8_UNORM"}, {"samples", 1}, {"load", "clear"},
                                        {"store", "store"}, {"image", image}, {"width", w}, {"height", h}}})},
          {"draws", draws}};
}

/// A format-2 intermediate of `passes`, its final target w x h.
json frame(int w, int h, const json& passes) {
  return {{"format", "tbdrsim-capture 2"}, {"source", {{"tool", "hand"}, {"api", "Vulkan"}, {"capture", "test"}}},
          {"clip_convention", "vulkan"}, {"width", w}, {"height", h}, {"passes", passes}, {"dispatches", json::array()},
          {"unsupported", json::array()}};
}

/// What an import gave: the command's result, the trace, and (on success) the replayed frame.
struct Imported {
  testing_support::CliResult cli;
  std::string trace_text;
  std::string summary;
  FrameResult result;
};

/// Imports `j` in a scratch folder named `name` and, when it imports, replays it on `mode`.
Imported import_and_run(const std::string& name, const json& j, const std::string& mode = "tbdr") {
  const fs::path dir = scratch_dir("import_features", name);
  std::ofstream(dir / "frame.json") << j.dump();
  Imported out;
  out.cli = run_cli({"import", (dir / "frame.json").string(), "--out", (dir / "f.trace").string()});
  if (out.cli.code != 0) return out;
  std::ifstream t(dir / "f.trace"), s(dir / "f.import.txt");
  out.trace_text.assign(std::istreambuf_iterator<char>(t), {});
  out.summary.assign(std::istreambuf_iterator<char>(s), {});
  const Trace trace = read_trace((dir / "f.trace").string());
  const Scene scene = load_gltf((dir / "f.glb").string());
  out.result = simulate_frame(trace, (dir / "f.trace").string(), scene, resolve_config({}, {"gpu.mode=" + mode}).hw);
  return out;
}

double samples(const Imported& i) { return stat(i.result, "frame/isp", "samples_rasterised"); }

TEST(ImportDepthClip, NegativeOneToOneKeepsWhatZeroToOneClipsAway) {
  // zink draws OpenGL with VK_EXT_depth_clip_control: clip z from -w to w. A quad over the 64x64
  // frame at z = -0.5 w is inside that volume (depth (z/w + 1)/2 = 0.25): all 4096 pixels. Read as
  // Vulkan's default (0 <= z <= w) it lies in front of the near plane and is clipped away: 0. The
  // issue's glmark2 frame lost a band of 7,366 pixels this way without a word.
  json j = frame(64, 64, json::array({pass(1, 64, 64, 7, json::array({quad(2, 64, 64, -0.5)}))}));
  j["passes"][0]["draws"][0]["depth_clip"] = "negative_one_to_one";
  const Imported gl = import_and_run("clip_gl", j);
  ASSERT_EQ(gl.cli.code, 0) << gl.cli.err;
  EXPECT_EQ(samples(gl), 64 * 64);
  j["passes"][0]["draws"][0].erase("depth_clip");
  const Imported vk = import_and_run("clip_vk", j);
  ASSERT_EQ(vk.cli.code, 0) << vk.cli.err;
  EXPECT_EQ(samples(vk), 0);
}

TEST(ImportDepthClip, StateThatChangesDepthMeaningIsRefusedByName) {
  json j = frame(64, 64, json::array({pass(1, 64, 64, 7, json::array({quad(2, 64, 64)}))}));
  j["passes"][0]["draws"][0]["depth_clamp"] = true;
  Imported r = import_and_run("clamp", j);
  EXPECT_EQ(r.cli.code, 2);
  EXPECT_NE(r.cli.err.find("draw at event 2 (vkCmdDraw()): depth clamp enabled"), std::string::npos) << r.cli.err;
  j["passes"][0]["draws"][0].erase("depth_clamp");
  j["passes"][0]["draws"][0]["depth_clip"] = "one_to_two";
  r = import_and_run("clip_unknown", j);
  EXPECT_EQ(r.cli.code, 2);
  EXPECT_NE(r.cli.err.find("depth_clip 'one_to_two' is not known"), std::string::npos) << r.cli.err;
  j["passes"][0]["draws"][0].erase("depth_clip");
  j["passes"][0]["draws"][0]["refused"] = "viewport swizzle (VK_NV_viewport_swizzle)";
  r = import_and_run("refused", j);
  EXPECT_EQ(r.cli.code, 2);
  EXPECT_NE(r.cli.err.find("refused by the exporter: viewport swizzle"), std::string::npos) << r.cli.err;
  // A depth bias is imported and listed.
  j["passes"][0]["draws"][0].erase("refused");
  j["passes"][0]["draws"][0]["depth_bias"] = true;
  r = import_and_run("bias", j);
  ASSERT_EQ(r.cli.code, 0) << r.cli.err;
  EXPECT_NE(r.summary.find("depth bias enabled; imported without it"), std::string::npos) << r.summary;
}

TEST(ImportPassSizes, EachPassRunsAtItsOwnRenderArea) {
  // A 128x96 shadow-map pass and the application's 64x48 frame: the trace's grid is 128x96 and
  // the second pass has area=0,0,64,48. Full-viewport quads in each: 128 x 96 + 64 x 48 = 15360
  // samples; 32x32 tiles: 4 x 3 = 12 for the first pass, 2 x 2 = 4 for the second.
  const json j = frame(64, 48, json::array({pass(1, 128, 96, 7, json::array({quad(2, 128, 96)})),
                                            pass(3, 64, 48, 8, json::array({quad(4, 64, 48)}))}));
  const Imported r = import_and_run("sizes", j);
  ASSERT_EQ(r.cli.code, 0) << r.cli.err;
  EXPECT_NE(r.trace_text.find("frame width=128 height=96"), std::string::npos) << r.trace_text;
  EXPECT_NE(r.trace_text.find("pass pass_3 area=0,0,64,48\n"), std::string::npos) << r.trace_text;
  EXPECT_NE(r.trace_text.find("pass pass_1\n"), std::string::npos) << r.trace_text;
  EXPECT_EQ(samples(r), 128 * 96 + 64 * 48);
  EXPECT_EQ(stat(r.result, "frame/isp", "tiles_rendered"), 12 + 4);
  EXPECT_EQ(stat(r.result, "frame/tile_memory", "tile_store_bytes"), (128 * 96 + 64 * 48) * 4);
}

TEST(ImportLinesAndPoints, DrawnAsTheRectanglesAndSquaresTheyCover) {
  // A line strip of 3 vertices, (8, 20) -> (24, 20) -> (40, 20), 2 pixels wide: two segments,
  // rectangles over rows 19 and 20 (centres 19.5 and 20.5 inside y 19..21) and columns 8 to 39:
  // 2 x 32 = 64 samples. A line list of one vertical segment (50, 4) -> (50, 12), 1 pixel wide:
  // x 49.5..50.5 holds the centre 49.5 or 50.5 on its edge; the top-left rule keeps one column:
  // 8 samples.
  const double W = 64, H = 64;
  json strip = draw(2, "line_strip", json::array({at(8, 20, W, H), at(24, 20, W, H), at(40, 20, W, H)}));
  strip["line_width"] = 2.0;
  json list = draw(3, "lines", json::array({at(50, 4, W, H), at(50, 12, W, H)}));
  list["line_width"] = 1.0;
  // Three points of size 4 at (10, 10), (30, 30), (50, 50): squares [x-2, x+2) hold 4 x 4 pixel
  // centres each: 48 samples.
  json points = draw(4, "points", json::array({at(10, 10, W, H), at(30, 30, W, H), at(50, 50, W, H)}));
  points["point_sizes"] = {4.0, 4.0, 4.0};
  const Imported lines = import_and_run("lines", frame(64, 64, json::array({pass(1, 64, 64, 7, json::array({strip, list}))})));
  ASSERT_EQ(lines.cli.code, 0) << lines.cli.err;
  EXPECT_EQ(samples(lines), 64 + 8);
  EXPECT_NE(lines.summary.find("2 line segments as rectangles 2 pixels wide"), std::string::npos) << lines.summary;
  const Imported pts = import_and_run("points", frame(64, 64, json::array({pass(1, 64, 64, 7, json::array({points}))})));
  ASSERT_EQ(pts.cli.code, 0) << pts.cli.err;
  EXPECT_EQ(samples(pts), 3 * 16);
  EXPECT_NE(pts.summary.find("3 points as squares of their size"), std::string::npos) << pts.summary;
  // Adjacency topologies are refused by name.
  json adj = draw(5, "line_list_with_adjacency", json::array({at(8, 20, W, H), at(24, 20, W, H)}));
  const Imported refused = import_and_run("adjacency", frame(64, 64, json::array({pass(1, 64, 64, 7, json::array({adj}))})));
  EXPECT_EQ(refused.cli.code, 2);
  EXPECT_NE(refused.cli.err.find("topology 'line_list_with_adjacency' is not imported"), std::string::npos) << refused.cli.err;
}

TEST(ImportInstances, EveryInstanceIsDrawn) {
  // Three instances of an 8x8 square (two triangles, 6 vertices an instance) at x = 0, 16, 32:
  // 3 x 64 = 192 samples, 6 triangles. Before format 2 only instance 0 was imported: 64.
  const double W = 64, H = 64;
  json clip = json::array();
  for (int i = 0; i < 3; ++i) {
    const double x = 16.0 * i;
    for (const auto& p : {std::pair{x, 0.0}, {x + 8, 0.0}, {x + 8, 8.0}, {x, 0.0}, {x + 8, 8.0}, {x, 8.0}}) {
      clip.push_back(at(p.first, p.second, W, H));
    }
  }
  json d = draw(2, "triangles", clip);
  d["instances"] = 3;
  d["vertices_per_instance"] = 6;
  const Imported r = import_and_run("instances", frame(64, 64, json::array({pass(1, 64, 64, 7, json::array({d}))})));
  ASSERT_EQ(r.cli.code, 0) << r.cli.err;
  EXPECT_EQ(samples(r), 3 * 64);
  EXPECT_EQ(stat(r.result, "frame/geometry", "primitives_in"), 6);
  EXPECT_NE(r.summary.find("6 triangles (3 instances)"), std::string::npos) << r.summary;
  d["vertices_per_instance"] = 5;
  const Imported bad = import_and_run("instances_bad", frame(64, 64, json::array({pass(1, 64, 64, 7, json::array({d}))})));
  EXPECT_EQ(bad.cli.code, 2);
  EXPECT_NE(bad.cli.err.find("3 instances of 5 vertices need 15 clip positions, it has 18"), std::string::npos) << bad.cli.err;
}

TEST(ImportScissor, TheDrawsScissorIsApplied) {
  // A quad over the 64x64 frame with scissor [8, 24) x [8, 24): 16 x 16 = 256 samples.
  json d = quad(2, 64, 64);
  d["scissor"] = {8, 8, 16, 16};
  const Imported r = import_and_run("scissor", frame(64, 64, json::array({pass(1, 64, 64, 7, json::array({d}))})));
  ASSERT_EQ(r.cli.code, 0) << r.cli.err;
  EXPECT_EQ(samples(r), 256);
  EXPECT_NE(r.trace_text.find("scissor=8,8,24,24"), std::string::npos) << r.trace_text;
}

TEST(ImportMsaa, AResolveAttachmentBecomesTheTracesResolve) {
  // A 4-sample colour target resolved into a 1-sample one: the quad rasterises 64 x 64 x 4 =
  // 16384 samples and the tile memory resolves them into the target (resolved_samples).
  json p = pass(1, 64, 64, 7, json::array({quad(2, 64, 64)}));
  p["attachments"][0]["samples"] = 4;
  p["attachments"][0]["store"] = "dont_care";
  p["attachments"].push_back({{"index", 1}, {"vk_format", "VK_FORMAT_R8G8B8A8_UNORM"}, {"samples", 1}, {"load", "dont_care"},
                              {"store", "store"}, {"image", 9}, {"resolve_of", 0}});
  const Imported r = import_and_run("msaa", frame(64, 64, json::array({p})));
  ASSERT_EQ(r.cli.code, 0) << r.cli.err;
  EXPECT_NE(r.trace_text.find("resolve=img_9"), std::string::npos) << r.trace_text;
  EXPECT_EQ(samples(r), 64 * 64 * 4);
  EXPECT_EQ(stat(r.result, "frame/tile_memory", "resolved_samples"), 64 * 64 * 4);
}

TEST(ImportTransfers, BlitsAndCopiesAreMemoryTrafficInSubmissionOrder) {
  // A pass at event 1, a blit at event 2 (a 64x64 RGBA8 level into its 32x32 half: 16384 bytes
  // read, 4096 written) and a buffer copy at event 3 (1000 bytes each way): two transfer
  // dispatches after the pass, booking exactly those bytes. Threads: one per 16 bytes, in groups
  // of 64: the blit 16384 / 16 = 1024 threads = 16 groups, the copy 63 threads = 1 group.
  json j = frame(64, 64, json::array({pass(1, 64, 64, 7, json::array({quad(4, 64, 64)}))}));
  j["passes"][0]["event"] = 1;
  j["transfers"] = json::array(
      {{{"event", 2}, {"name", "vkCmdBlitImage()"}, {"kind", "blit"}, {"read_bytes", 16384}, {"write_bytes", 4096},
        {"src_image", 7}, {"dst_image", 7}, {"src_format", "VK_FORMAT_R8G8B8A8_UNORM"}, {"dst_format", "VK_FORMAT_R8G8B8A8_UNORM"}},
       {{"event", 3}, {"name", "vkCmdCopyBuffer()"}, {"kind", "copy_buffer"}, {"read_bytes", 1000}, {"write_bytes", 1000},
        {"src_image", nullptr}, {"dst_image", nullptr}}});
  const Imported r = import_and_run("transfers", j);
  ASSERT_EQ(r.cli.code, 0) << r.cli.err;
  const auto pass_at = r.trace_text.find("pass pass_1"), blit_at = r.trace_text.find("dispatch transfer groups=16,1,1 group_size=64,1,1 reads=xfer_2_src writes=xfer_2_dst");
  ASSERT_NE(blit_at, std::string::npos) << r.trace_text;
  EXPECT_LT(pass_at, blit_at);
  EXPECT_NE(r.trace_text.find("buffer xfer_2_src bytes=16384 traffic=color content=other upload=yes"), std::string::npos) << r.trace_text;
  EXPECT_NE(r.trace_text.find("dispatch transfer groups=1,1,1 group_size=64,1,1 reads=xfer_3_src writes=xfer_3_dst"), std::string::npos);
  EXPECT_EQ(stat(r.result, "frame/compute", "dispatches"), 2);
  EXPECT_EQ(stat(r.result, "frame/compute", "threads"), 16 * 64 + 64);
  EXPECT_EQ(stat(r.result, "frame/compute", "compute_alu_ops"), 0);
  EXPECT_NE(r.summary.find("transfer at event 2 (vkCmdBlitImage()): blit, 16384 bytes read, 4096 written"), std::string::npos)
      << r.summary;
  j["transfers"][0]["kind"] = "teleport";
  const Imported bad = import_and_run("transfers_bad", j);
  EXPECT_EQ(bad.cli.code, 2);
  EXPECT_NE(bad.cli.err.find("transfer at event 2 (vkCmdBlitImage()): transfer kind 'teleport' is not known"), std::string::npos)
      << bad.cli.err;
}

TEST(ImportDispatches, TheApplicationsComputeRunsByItsCapturedCost) {
  // A dispatch of 4 x 2 x 1 workgroups of 8 x 8 x 1: 512 threads of a 30-ALU shader = 15360 ALU
  // operations, after the pass that precedes it by event.
  json j = frame(64, 64, json::array({pass(1, 64, 64, 7, json::array({quad(2, 64, 64)}))}));
  j["dispatches"] = json::array({{{"event", 5}, {"name", "vkCmdDispatch(4, 2, 1)"}, {"groups", {4, 2, 1}}, {"local_size", {8, 8, 1}},
                                  {"shader", {{"alu_ops", 30}, {"tex_fetches", 1}, {"source", "spirv static count"}}},
                                  {"reads_bytes", 4096}, {"writes_bytes", 2048}}});
  const Imported r = import_and_run("dispatch", j);
  ASSERT_EQ(r.cli.code, 0) << r.cli.err;
  EXPECT_NE(r.trace_text.find("dispatch captured_compute groups=4,2,1 group_size=8,8,1 reads=disp_5_in writes=disp_5_out "
                              "alu_ops=30 tex_fetches=1"),
            std::string::npos)
      << r.trace_text;
  EXPECT_EQ(stat(r.result, "frame/compute", "compute_alu_ops"), 4 * 2 * 64 * 30);
  EXPECT_EQ(stat(r.result, "frame/compute", "threads"), 512);
}

}  // namespace
}  // namespace tbdr
