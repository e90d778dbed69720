// `tbdrsim import` (docs/capture-import.md): the committed vkcube capture intermediate
// (tests/data/capture/vkcube, exported from a RenderDoc capture) becomes a trace and a GLB whose
// _CLIP_POSITION geometry the simulator replays as it is; its image is compared with the pixel
// history RenderDoc recorded in the application's own frame. None of this needs RenderDoc; the one
// test of the .rdc route checks only that a bad capture is refused with nothing written.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <sstream>

#include <nlohmann/json.hpp>

#include "cli_run.hpp"
#include "app/cli.hpp"
#include "app/capture_convert.hpp"
#include "kernel/errors.hpp"
#include "models/command_processor.hpp"
#include "models/hw_config.hpp"
#include "scene/gltf_loader.hpp"
#include "scratch_dir.hpp"

namespace tbdr {
namespace {

namespace fs = std::filesystem;
using testing_scratch::scratch_dir;

const testing_scratch::ScratchCleanup cleanup{"import"};

const fs::path kFixture = fs::path(TBDRSIM_SOURCE_DIR) / "tests" / "data" / "capture" / "vkcube";

using testing_support::CliResult;
using testing_support::run_cli;

nlohmann::json fixture_json() {
  std::ifstream in(kFixture / "frame.json");
  return nlohmann::json::parse(in);
}

/// Imports the fixture into `dir` (trace, GLB) and returns the trace path.
fs::path import_fixture(const fs::path& dir) {
  const auto r = run_cli({"import", kFixture.string(), "--out", (dir / "vkcube.trace").string()});
  EXPECT_EQ(r.code, 0) << r.err;
  return dir / "vkcube.trace";
}

/// How the simulated frame agrees with the application's at the pixels RenderDoc's pixel history
/// sampled: coverage (both covered or both background) and triangle (a sampled pixel matches when
/// its captured triangle and its simulated primitive are each the other's most frequent partner:
/// a one-to-one matching, so one primitive everywhere cannot score).
struct Agreement {
  std::size_t samples = 0, coverage_match = 0, covered_both = 0, triangle_match = 0;
};

Agreement agreement(const nlohmann::json& frame, const std::vector<std::uint32_t>& triangle_id, int width) {
  Agreement a;
  std::map<std::pair<int, int>, std::map<std::uint32_t, int>> ref_to_sim;
  std::map<std::uint32_t, std::map<std::pair<int, int>, int>> sim_to_ref;
  const auto& samples = frame["pixel_history"]["samples"];
  for (const auto& s : samples) {
    const int x = s[0], y = s[1], ev = s[2], prim = s[3];
    const std::uint32_t id = triangle_id[static_cast<std::size_t>(y) * static_cast<std::size_t>(width) + static_cast<std::size_t>(x)];
    ++a.samples;
    const bool ref_covered = ev >= 0, sim_covered = id != 0;
    if (ref_covered == sim_covered) ++a.coverage_match;
    if (ref_covered && sim_covered) {
      ++a.covered_both;
      ++ref_to_sim[{ev, prim}][id];
      ++sim_to_ref[id][{ev, prim}];
    }
  }
  auto best = [](const auto& m) {
    return std::max_element(m.begin(), m.end(), [](const auto& p, const auto& q) { return p.second < q.second; })->first;
  };
  for (const auto& s : samples) {
    const int x = s[0], y = s[1], ev = s[2], prim = s[3];
    const std::uint32_t id = triangle_id[static_cast<std::size_t>(y) * static_cast<std::size_t>(width) + static_cast<std::size_t>(x)];
    if (ev < 0 || id == 0) continue;
    const std::pair<int, int> ref{ev, prim};
    if (best(ref_to_sim[ref]) == id && best(sim_to_ref[id]) == ref) ++a.triangle_match;
  }
  return a;
}

FrameResult simulate(const fs::path& trace_path, const Scene& scene, const std::string& mode) {
  const Trace t = read_trace(trace_path.string());
  const ResolvedConfig cfg = resolve_config({}, {"gpu.mode=" + mode});
  return simulate_frame(t, trace_path.string(), scene, cfg.hw);
}

TEST(Import, FixtureBecomesATraceAndAClipSpaceGlb) {
  const fs::path dir = scratch_dir("import", "fixture");
  const fs::path trace_path = import_fixture(dir);
  for (const char* f : {"vkcube.trace", "vkcube.glb", "vkcube.import.txt", "vkcube.reference.png"}) {
    EXPECT_TRUE(fs::is_regular_file(dir / f)) << f;
  }
  // Imported from the exported intermediate, as from an .rdc, the intermediate is kept beside the
  // trace as vkcube.capture/ (docs/capture-import.md's step 4 reads it), without the .rdc.
  EXPECT_TRUE(fs::is_regular_file(dir / "vkcube.capture" / "frame.json"));
  EXPECT_TRUE(fs::is_regular_file(dir / "vkcube.capture" / "reference.png"));
  EXPECT_FALSE(fs::exists(dir / "vkcube.capture" / "vkcube_frame272.rdc"));
  // The clear colour as the capture's floats read, not their double expansion (0.20000000298023224).
  std::ifstream summary_in(dir / "vkcube.import.txt");
  const std::string summary((std::istreambuf_iterator<char>(summary_in)), {});
  EXPECT_NE(summary.find("clears to colour [0.2, 0.2, 0.2, 0.2]"), std::string::npos) << summary;
  const Trace t = read_trace(trace_path.string());
  EXPECT_EQ(t.frame.width, 320);
  EXPECT_EQ(t.frame.height, 240);
  ASSERT_EQ(t.commands.size(), 1u);  // vkcube: one render pass with one draw of 36 vertices
  const auto& pass = std::get<PassDesc>(t.commands[0]);
  ASSERT_EQ(pass.draws.size(), 1u);
  EXPECT_EQ(pass.draws[0].submesh, "draw_11");
  ASSERT_EQ(pass.attachments.size(), 2u);
  // The render pass's load/store ops: colour cleared and stored, D16 depth cleared and dropped.
  EXPECT_EQ(pass.attachments[0].format, Format::Rgba8);
  EXPECT_EQ(pass.attachments[0].load, LoadOp::Clear);
  EXPECT_EQ(pass.attachments[0].store, StoreOp::Store);
  EXPECT_EQ(pass.attachments[1].format, Format::D16);
  EXPECT_EQ(pass.attachments[1].store, StoreOp::DontCare);
  const PipelineState* p = t.find_pipeline(pass.draws[0].pipeline);
  ASSERT_NE(p, nullptr);
  EXPECT_TRUE(p->depth_test);
  EXPECT_TRUE(p->depth_write);
  EXPECT_EQ(p->depth_compare, CompareOp::LessEqual);
  EXPECT_EQ(p->cull, CullMode::Back);
  EXPECT_EQ(p->blend, BlendMode::Off);
  // The fragment shader's static SPIR-V count, as the fixture records it (Import.SpirvCost derives
  // the 20 ALU operations), 1 sample, 7 varyings: texcoord 4 + frag_pos 3.
  const ShaderDesc* s = t.find_shader(p->shader);
  ASSERT_NE(s, nullptr);
  EXPECT_EQ(s->alu_ops, 20u);
  EXPECT_EQ(s->tex_fetches, 1u);
  EXPECT_EQ(s->varyings, 7u);

  // The GLB, read back through the validated loader: 12 triangles whose clip positions are the
  // captured ones in the simulator's convention. Vulkan (x, y, z, w) -> (x, -y, 2z - w, w).
  const Scene scene = load_gltf((dir / "vkcube.glb").string());
  ASSERT_EQ(scene.submeshes.size(), 1u);
  const SubMesh& sm = scene.submeshes[0];
  EXPECT_EQ(sm.triangle_count(), 12u);
  ASSERT_EQ(sm.clip_positions.size(), 36u);
  // The viewport [40, 0, 240, 240] of the 320x240 frame first: x' = (240/320) x + ((80 + 240)/320 - 1) w
  // = 0.75 x + 0 w; y' = (240/240) y + 0 w = y.
  const nlohmann::json captured = fixture_json();
  const auto& v0 = captured["passes"][0]["draws"][0]["clip_positions"][0];
  const float x = v0[0], y = v0[1], z = v0[2], w = v0[3];
  EXPECT_FLOAT_EQ(sm.clip_positions[0].x, 0.75f * x);
  EXPECT_FLOAT_EQ(sm.clip_positions[0].y, -y);
  EXPECT_FLOAT_EQ(sm.clip_positions[0].z, 2.0f * z - w);
  EXPECT_FLOAT_EQ(sm.clip_positions[0].w, w);
  // The material samples the captured texture (256x256, the LunarG logo) with the exported uvs.
  ASSERT_EQ(scene.textures.size(), 1u);
  EXPECT_EQ(scene.textures[0].width, 256);
  EXPECT_EQ(scene.textures[0].height, 256);
  EXPECT_EQ(t.scene.content_hash, scene.content_hash);
}

// docs/capture-import.md quotes the report of the vkcube frame on the three modes: the commands it
// shows, run here, print exactly its table (a change of the model's figures fails this test until
// the doc's table is replaced by what they print now).
TEST(Import, DocsReportTableIsCurrent) {
  const fs::path dir = scratch_dir("import", "docs_table");
  const fs::path trace_path = import_fixture(dir);
  const std::string db = (dir / "vkcube.db").string();
  for (const char* mode : {"tbdr", "tbr", "imr"}) {
    const auto r = run_cli({"run", "--trace", trace_path.string(), "--set", std::string("gpu.mode=") + mode, "--db", db,
                            "--quiet"});
    ASSERT_EQ(r.code, 0) << r.err;
  }
  const auto rep = run_cli({"report", "--db", db, "--by", "gpu.mode", "--format", "markdown", "--metric", "cycles",
                            "frame_time_ms", "requested_total_mb", "dram_total_mb", "energy_total_mj"});
  ASSERT_EQ(rep.code, 0) << rep.err;
  const std::string table = rep.out.substr(rep.out.find("| gpu.mode"));
  std::ifstream in(fs::path(TBDRSIM_SOURCE_DIR) / "docs" / "capture-import.md");
  const std::string doc((std::istreambuf_iterator<char>(in)), {});
  EXPECT_NE(doc.find(table), std::string::npos) << "docs/capture-import.md's table is stale; the commands now print:\n"
                                                << table;
}

TEST(Import, ReplayMatchesTheApplicationsFrameOnEveryMode) {
  const fs::path dir = scratch_dir("import", "replay");
  const fs::path trace_path = import_fixture(dir);
  const Scene scene = load_gltf((dir / "vkcube.glb").string());
  const nlohmann::json frame = fixture_json();
  for (const char* mode : {"tbdr", "tbr", "imr"}) {
    const FrameResult fr = simulate(trace_path, scene, mode);
    const Agreement a = agreement(frame, fr.images.counters.triangle_id, 320);
    // 1200 sampled pixels (every 8th in x and y, at pixel centres), 240 of them on the cube in
    // vkcube's frame. Measured: every sample agrees on coverage and every covered one on its
    // triangle (the whole frame's coverage agrees pixel for pixel: compare_frame.py). Before the
    // viewport mapping (vkcube draws into a 240x240 viewport at x = 40) 82 samples disagreed on
    // coverage; with the opposite winding 156 covered ones disagreed on their triangle.
    EXPECT_EQ(a.samples, 1200u) << mode;
    EXPECT_EQ(a.coverage_match, 1200u) << mode;
    EXPECT_EQ(a.covered_both, 240u) << mode;
    EXPECT_EQ(a.triangle_match, 240u) << mode;
  }
}

/// Imports the committed real-application intermediate tests/data/capture/NAME into a scratch
/// folder; its trace path.
fs::path import_example(const std::string& name) {
  const fs::path dir = scratch_dir("import", "example_" + name);
  const auto r = run_cli({"import", (kFixture.parent_path() / name).string(), "--out", (dir / (name + ".trace")).string()});
  EXPECT_EQ(r.code, 0) << r.err;
  return dir / (name + ".trace");
}

nlohmann::json example_json(const std::string& name) {
  std::ifstream in(kFixture.parent_path() / name / "frame.json");
  return nlohmann::json::parse(in);
}

TEST(Import, RealApplicationsReplayAsTheyRan) {
  // Two OpenGL frames of glmark2 captured through zink (docs/capture-import.md, "The OpenGL
  // route"): dynamic rendering, clip z from -w to w (depth clip control), a negative viewport
  // height. desktop: 11 passes, 4 of them 84x84 blur targets at their own render area, alpha-
  // blended windows over each other. ideas: 227 draws, 17 of them line strips. The 1200 sampled
  // pixels of the application's frame (the last draw that changed the pixel, read back from
  // RenderDoc's replay; its triangle from the exported clip positions, which agreed with
  // RenderDoc's PixelHistory at 300 of 300 samples of each frame) against the simulated frame on
  // every mode. Measured: every sample agrees on coverage and every covered one on its triangle
  // on all three modes; the issue asks for >= 99 % and >= 95 %.
  for (const std::string name : {"glmark2_desktop", "glmark2_ideas"}) {
    const fs::path trace_path = import_example(name);
    const Trace t = read_trace(trace_path.string());
    const Scene scene = load_gltf((trace_path.parent_path() / (name + ".glb")).string());
    const nlohmann::json frame = example_json(name);
    for (const char* mode : {"tbdr", "tbr", "imr"}) {
      const FrameResult fr = simulate(trace_path, scene, mode);
      const Agreement a = agreement(frame, fr.images.counters.triangle_id, t.frame.width);
      EXPECT_EQ(a.samples, 1200u) << name << " " << mode;
      EXPECT_GE(a.coverage_match, a.samples * 99 / 100) << name << " " << mode;
      EXPECT_GE(a.triangle_match, a.covered_both * 95 / 100) << name << " " << mode;
      EXPECT_GT(a.covered_both, 300u) << name << " " << mode;
    }
    if (name == "glmark2_desktop") {
      int small = 0;
      for (const auto& c : t.commands) {
        if (const auto* p = std::get_if<PassDesc>(&c); p && p->area) {
          EXPECT_EQ(*p->area, (ScissorRect{0, 0, 84, 84}));
          ++small;
        }
      }
      EXPECT_EQ(small, 4) << "the blur passes at their own 84x84";
    } else {
      std::ifstream in(trace_path.parent_path() / (name + ".import.txt"));
      const std::string summary((std::istreambuf_iterator<char>(in)), {});
      std::size_t lines = 0;
      for (auto at = summary.find("line segments as rectangles"); at != std::string::npos;
           at = summary.find("line segments as rectangles", at + 1)) {
        ++lines;
      }
      EXPECT_EQ(lines, 17u) << summary;
      EXPECT_NE(summary.find("227 draws"), std::string::npos) << summary;
    }
  }
}

TEST(Import, SeveralCapturesBecomeOneSequence) {
  // Two captured frames of the same size imported as one sequence (trace version 4): one GLB
  // holding both frames' geometry (names prefixed f0_, f1_), each frame its own passes and
  // declarations. Each frame replays as it did imported alone: the same samples rasterised.
  const fs::path dir = scratch_dir("import", "sequence");
  const fs::path data = kFixture.parent_path();
  const auto r = run_cli({"import", (data / "glmark2_desktop").string(), (data / "glmark2_ideas").string(), "--out",
                          (dir / "seq.trace").string()});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("2 frames"), std::string::npos) << r.out;
  const std::vector<Trace> frames = read_trace_frames((dir / "seq.trace").string());
  ASSERT_EQ(frames.size(), 2u);
  EXPECT_TRUE(fs::is_regular_file(dir / "seq.capture" / "frame0" / "frame.json"));
  EXPECT_TRUE(fs::is_regular_file(dir / "seq.capture" / "frame1" / "frame.json"));
  const Scene scene = load_gltf((dir / "seq.glb").string());
  const ResolvedConfig cfg = resolve_config({}, {"gpu.mode=tbdr"});
  for (std::size_t k = 0; k < 2; ++k) {
    const std::string name = k == 0 ? "glmark2_desktop" : "glmark2_ideas";
    const fs::path alone = import_example(name);
    const FrameResult one = simulate(alone, load_gltf((alone.parent_path() / (name + ".glb")).string()), "tbdr");
    const FrameResult in_seq = simulate_frame(frames[k], "seq.trace", scene, cfg.hw);
    EXPECT_EQ(in_seq.images.counters.shaded, one.images.counters.shaded) << name;
    std::size_t draws = 0;
    for (const auto& c : frames[k].commands) {
      if (const auto* p = std::get_if<PassDesc>(&c)) {
        for (const DrawCmd& d : p->draws) {
          EXPECT_EQ(d.submesh.rfind("f" + std::to_string(k) + "_draw_", 0), 0u) << d.submesh;
          ++draws;
        }
      }
    }
    EXPECT_EQ(draws, k == 0 ? 14u : 227u);
  }
  // Frames of different sizes are refused, naming the intermediate; nothing written.
  const fs::path small = scratch_dir("import", "sequence_small");
  nlohmann::json j = example_json("glmark2_ideas");
  j["width"] = 64;
  j["height"] = 64;
  for (auto& p : j["passes"]) {
    p["render_area"] = {0, 0, 64, 64};
  }
  std::ofstream(small / "frame.json") << j.dump();
  const fs::path out = scratch_dir("import", "sequence_out");
  const auto bad = run_cli({"import", (data / "glmark2_desktop").string(), (small / "frame.json").string(), "--out",
                            (out / "x.trace").string()});
  EXPECT_EQ(bad.code, 2);
  EXPECT_NE(bad.err.find("frame 1 is 64x64 at 1 samples, the first 320x240 at 1 samples"), std::string::npos) << bad.err;
  std::size_t files = 0;
  for ([[maybe_unused]] const auto& e : fs::directory_iterator(out)) ++files;
  EXPECT_EQ(files, 0u);
}

TEST(Import, ClipSpaceGeometryIgnoresCameraAndInstanceTransform) {
  const fs::path dir = scratch_dir("import", "clip");
  const fs::path trace_path = import_fixture(dir);
  Scene scene = load_gltf((dir / "vkcube.glb").string());
  const auto base = simulate(trace_path, scene, "tbdr").images.counters.triangle_id;
  // Moving the instance changes nothing: the clip positions are taken as they are.
  scene.instances[0].world[3] = glm::vec4(5.0f, -3.0f, 2.0f, 1.0f);
  EXPECT_EQ(simulate(trace_path, scene, "tbdr").images.counters.triangle_id, base);
  // Without them the same sub-mesh goes through the camera transform (POSITION is clip x, y, z)
  // and lands elsewhere: the control that shows the comparison above can fail.
  scene.submeshes[0].clip_positions.clear();
  EXPECT_NE(simulate(trace_path, scene, "tbdr").images.counters.triangle_id, base);
}

TEST(Import, SpirvCostCountsVkcubesFragmentShader) {
  // scripts/capture/spirv_cost.py on vkcube's fragment shader as RenderDoc gave it (fs_182.spv).
  // spirv-dis lists its arithmetic: OpDPdx v3, OpDPdy v3, Cross v3, Normalize v3, OpDot of two v3,
  // FMax float, OpVectorTimesScalar v4 -> 3 + 3 + 3 + 3 + 3 + 1 + 4 = 20 ALU operations; one
  // OpImageSampleImplicitLod; 8 OpLoad, 5 OpStore; no branch, loop or discard.
  if (!fs::exists("/usr/bin/python3")) GTEST_SKIP() << "no /usr/bin/python3 to run scripts/capture/spirv_cost.py";
  const fs::path dir = scratch_dir("import", "spirv");
  const std::string cmd = "/usr/bin/python3 '" + (fs::path(TBDRSIM_SOURCE_DIR) / "scripts" / "capture" / "spirv_cost.py").string() +
                          "' '" + (kFixture / "fs_182.spv").string() + "' > '" + (dir / "cost.txt").string() + "'";
  ASSERT_EQ(std::system(cmd.c_str()), 0);
  std::ifstream in(dir / "cost.txt");
  std::string line;
  std::getline(in, line);
  const auto j = nlohmann::json::parse(line.substr(line.find('{')));
  EXPECT_EQ(j["alu_ops"], 20);
  EXPECT_EQ(j["tex_fetches"], 1);
  EXPECT_EQ(j["loads"], 8);
  EXPECT_EQ(j["stores"], 5);
  EXPECT_EQ(j["branches"], 0);
  EXPECT_EQ(j["loops"], 0);
  EXPECT_EQ(j["discard"], false);
  // Truncated: refused with the word it stopped at.
  std::ifstream spv(kFixture / "fs_182.spv", std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(spv)), {});
  std::ofstream(dir / "cut.spv", std::ios::binary) << bytes.substr(0, 1000);
  const std::string cut = "/usr/bin/python3 '" + (fs::path(TBDRSIM_SOURCE_DIR) / "scripts" / "capture" / "spirv_cost.py").string() +
                          "' '" + (dir / "cut.spv").string() + "' > /dev/null 2>&1";
  EXPECT_NE(std::system(cut.c_str()), 0);
}

/// Writes the fixture with one edit into `dir` (textures copied) and returns its frame.json.
fs::path edited_fixture(const fs::path& dir, const std::function<void(nlohmann::json&)>& edit) {
  nlohmann::json j = fixture_json();
  edit(j);
  fs::copy_file(kFixture / "tex_164.png", dir / "tex_164.png");
  std::ofstream(dir / "frame.json") << j.dump();
  return dir / "frame.json";
}

void expect_refused(const fs::path& input, const fs::path& out_dir, const std::string& message) {
  const auto r = run_cli({"import", input.string(), "--out", (out_dir / "x.trace").string()});
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.err.find(message), std::string::npos) << r.err;
  std::size_t files = 0;
  for ([[maybe_unused]] const auto& e : fs::directory_iterator(out_dir)) ++files;
  EXPECT_EQ(files, 0u) << "nothing is written on error";
}

TEST(Import, BadCapturesNameTheDrawAndWriteNothing) {
  const fs::path in = scratch_dir("import", "bad_in");
  const fs::path out = scratch_dir("import", "bad_out");
  {  // truncated intermediate
    std::ifstream src(kFixture / "frame.json");
    std::string text((std::istreambuf_iterator<char>(src)), {});
    std::ofstream(in / "frame.json") << text.substr(0, text.size() / 2);
    expect_refused(in / "frame.json", out, "not valid JSON (truncated export?)");
  }
  {
    const fs::path d = scratch_dir("import", "bad_vertex");
    expect_refused(edited_fixture(d, [](nlohmann::json& j) { j["passes"][0]["draws"][0]["clip_positions"][5] = {1, 2, 3}; }),
                   out, "draw at event 11 (vkCmdDraw()) vertex 5: clip position is not 4 numbers");
  }
  {
    const fs::path d = scratch_dir("import", "bad_topology");
    expect_refused(edited_fixture(d, [](nlohmann::json& j) { j["passes"][0]["draws"][0]["topology"] = "patch_list"; }), out,
                   "draw at event 11 (vkCmdDraw()): topology 'patch_list' is not imported");
  }
  {
    const fs::path d = scratch_dir("import", "bad_format");
    expect_refused(edited_fixture(d, [](nlohmann::json& j) { j["passes"][0]["attachments"][0]["vk_format"] = "VK_FORMAT_R4G4_UNORM_PACK8"; }),
                   out, "pass at event 6 attachment 0: format VK_FORMAT_R4G4_UNORM_PACK8 has no trace equivalent");
  }
  {
    const fs::path d = scratch_dir("import", "bad_texture");
    expect_refused(edited_fixture(d, [](nlohmann::json& j) { j["passes"][0]["draws"][0]["textures"][0]["file"] = "gone.png"; }),
                   out, "gone.png: draw at event 11 (vkCmdDraw()) texture: cannot open file");
  }
  // A .rdc that is not a capture: refused by RenderDoc when it is installed, by the exporter's
  // "not installed" message when not; either way exit 2 and nothing written.
  // Both the wrong magic (refused before RenderDoc starts) and the right magic over junk (refused
  // by RenderDoc, which is then shut down: the exporter used to hang at exit in 2 runs of 3).
  std::ofstream(in / "junk.rdc") << "not a capture";
  expect_refused(in / "junk.rdc", out, "nothing written");
  std::ofstream(in / "junk_magic.rdc") << "RDOCjunkjunkjunk";
  expect_refused(in / "junk_magic.rdc", out, "nothing written");
  expect_refused(in / "missing.rdc", out, "capture not found");
}

TEST(Import, PngThatIsPlainTextIsRefusedBeforeDecoding) {
  // The issue 55 reproducer: a texture named .png that is text was embedded as image/png without
  // a word. Refused by its signature, exit 2, naming the file and its first bytes; nothing written.
  const fs::path out = scratch_dir("import", "text_png_out");
  const fs::path d = scratch_dir("import", "text_png");
  const fs::path json = edited_fixture(d, [](nlohmann::json&) {});
  std::ofstream(d / "tex_164.png", std::ios::trunc) << "hello world\n";
  expect_refused(json, out,
                 (d / "tex_164.png").string() + ": draw at event 11 (vkCmdDraw()) texture: not a PNG file: it starts with "
                 "68 65 6c 6c 6f 20 77 6f ('hello wo'), where a PNG starts with 89 50 4e 47 0d 0a 1a 0a");
  std::ofstream(d / "tex_164.png", std::ios::trunc);  // empty
  expect_refused(json, out, "tex_164.png: draw at event 11 (vkCmdDraw()) texture: not a PNG file: it is empty");
  // The application's own frame, copied beside the trace, is checked the same way.
  fs::copy_file(kFixture / "tex_164.png", d / "tex_164.png", fs::copy_options::overwrite_existing);
  std::ofstream(d / "reference.png") << "P3\n2 2\n255\n";
  expect_refused(json, out, (d / "reference.png").string() + ": the application's frame (copied to x.reference.png): "
                            "not a PNG file: it starts with 50 33 0a 32 20 32 0a 32 ('P3\\x0a2 2\\x0a2')");
}

TEST(Import, RdcExportReproducesTheFixture) {
  // The .rdc route end to end, where RenderDoc is installed (scripts/install_capture_deps.sh): the
  // committed capture exported again gives the committed intermediate (pixel history aside, which
  // is skipped here to keep the test short) and so the same trace, GLB hash included.
  if (std::system("/usr/bin/python3 -c 'import renderdoc' > /dev/null 2>&1") != 0) {
    GTEST_SKIP() << "python3-renderdoc is not installed (scripts/install_capture_deps.sh); the .rdc route is not tested";
  }
  const fs::path dir = scratch_dir("import", "rdc");
  const auto r = run_cli({"import", (kFixture / "vkcube_frame272.rdc").string(), "--out", (dir / "vkcube.trace").string(),
                          "--history-samples", "0"});
  ASSERT_EQ(r.code, 0) << r.err;
  std::ifstream in(dir / "vkcube.capture" / "frame.json");
  nlohmann::json exported = nlohmann::json::parse(in);
  nlohmann::json committed = fixture_json();
  committed.erase("pixel_history");
  exported.erase("pixel_history");
  EXPECT_EQ(exported, committed);
  const fs::path fixture_dir = scratch_dir("import", "rdc_fixture");
  const Trace from_rdc = read_trace((dir / "vkcube.trace").string());
  const Trace from_fixture = read_trace(import_fixture(fixture_dir).string());
  EXPECT_EQ(trace_text(from_rdc), trace_text(from_fixture));
}

TEST(Import, UnsupportedFeaturesAreListedInTheSummary) {
  const fs::path d = scratch_dir("import", "unsupported");
  const fs::path out = scratch_dir("import", "unsupported_out");
  const fs::path json = edited_fixture(d, [](nlohmann::json& j) {
    j["passes"][0]["attachments"][1]["clear"]["depth"] = 0.0;  // reverse-Z clear
    j["passes"][0]["draws"][0]["shader"]["color_outputs"] = 3;  // more outputs than the pass's one target
  });
  const auto r = run_cli({"import", json.string(), "--out", (out / "f.trace").string()});
  ASSERT_EQ(r.code, 0) << r.err;
  std::ifstream in(out / "f.import.txt");
  const std::string summary((std::istreambuf_iterator<char>(in)), {});
  EXPECT_NE(summary.find("clears depth to 0.000000; the simulator clears depth to 1.0"), std::string::npos) << summary;
  EXPECT_NE(summary.find("shader writes 3 colour outputs, the pass has 1 colour targets; counted as 1"), std::string::npos)
      << summary;
}

}  // namespace
}  // namespace tbdr
