// A glTF scene's node animation played over a sequence (docs/sequences.md): `tbdrsim trace
// --animation` writes a `pose` line per frame and `tbdrsim run` replays each frame posed. (The
// loader's and pose_scene's own tests are in test_gltf.cpp, which the reader fuzz build also links
// without the command line.)
#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "trace/trace.hpp"
#include "cli_run.hpp"
#include "scratch_dir.hpp"

namespace tbdr {
namespace {

testing_scratch::ScratchCleanup cleanup{"animation_replay"};
using json = nlohmann::json;

/// Writes slide.gltf and slide.bin into `dir`: a unit quad whose node slides along x, LINEAR, from
/// x = 0 at 0 s to x = 10 at 1 s (animation 0). Returns the .gltf path.
std::string write_sliding_quad(const std::filesystem::path& dir) {
  const std::vector<float> positions{0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0};
  const std::vector<std::uint16_t> indices{0, 1, 2, 0, 2, 3};
  const std::vector<float> times{0.0f, 1.0f};
  const std::vector<float> moves{0, 0, 0, 10, 0, 0};
  std::string bin;
  auto append = [&bin](const void* data, std::size_t bytes) {
    const std::size_t at = bin.size();
    bin.append(static_cast<const char*>(data), bytes);
    while (bin.size() % 4) bin.push_back('\0');
    return at;
  };
  const std::size_t p = append(positions.data(), positions.size() * 4);
  const std::size_t i = append(indices.data(), indices.size() * 2);
  const std::size_t t = append(times.data(), times.size() * 4);
  const std::size_t m = append(moves.data(), moves.size() * 4);
  std::ofstream(dir / "slide.bin", std::ios::binary) << bin;
  auto view = [](std::size_t offset, std::size_t bytes) { return json{{"buffer", 0}, {"byteOffset", offset}, {"byteLength", bytes}}; };
  json doc = {
      {"asset", {{"version", "2.0"}}},
      {"buffers", json::array({json{{"uri", "slide.bin"}, {"byteLength", bin.size()}}})},
      {"bufferViews", json::array({view(p, 48), view(i, 12), view(t, 8), view(m, 24)})},
      {"accessors", json::array({json{{"bufferView", 0}, {"componentType", 5126}, {"count", 4}, {"type", "VEC3"},
                                      {"min", {0, 0, 0}}, {"max", {1, 1, 0}}},
                                 json{{"bufferView", 1}, {"componentType", 5123}, {"count", 6}, {"type", "SCALAR"}},
                                 json{{"bufferView", 2}, {"componentType", 5126}, {"count", 2}, {"type", "SCALAR"}},
                                 json{{"bufferView", 3}, {"componentType", 5126}, {"count", 2}, {"type", "VEC3"}}})},
      {"meshes", json::array({json{{"name", "Quad"}, {"primitives", json::array({json{{"attributes", {{"POSITION", 0}}}, {"indices", 1}}})}}})},
      {"nodes", json::array({json{{"name", "quad"}, {"mesh", 0}}})},
      {"scenes", json::array({json{{"nodes", {0}}}})},
      {"scene", 0},
      {"animations", json::array({json{{"channels", json::array({json{{"sampler", 0}, {"target", {{"node", 0}, {"path", "translation"}}}}})},
                                       {"samplers", json::array({json{{"input", 2}, {"output", 3}}})}}})}};
  std::ofstream(dir / "slide.gltf") << doc.dump(1);
  return (dir / "slide.gltf").string();
}

TEST(AnimationReplay, ASequencePlaysTheAnimationFrameByFrame) {
  // Three frames at 2 frames per second of the clock: the quad at x = 0, 5 and 10. The camera
  // frames the scene as it rests (the quad at the origin): by the last frame the quad has left the
  // view, so that frame draws fewer primitives than the first.
  const auto dir = testing_scratch::scratch_dir("animation_replay", "slide");
  const std::string scene = write_sliding_quad(dir);
  const std::string trace = (dir / "slide.trace").string();
  using testing_support::run_cli;
  const auto made = run_cli({"trace", "--technique", "plain_forward", "--scene", scene, "--lights", "4", "--resolution", "64x64",
                             "--frames", "3", "--animation", "0", "--animation-fps", "2", "--out", trace});
  ASSERT_EQ(made.code, 0) << made.err;
  std::ifstream in(trace);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("pose animation=0 time=0.5\n"), std::string::npos);
  const std::vector<Trace> frames = read_trace_frames(trace);
  ASSERT_EQ(frames.size(), 3u);
  ASSERT_TRUE(frames[2].pose.has_value());
  EXPECT_DOUBLE_EQ(frames[2].pose->time_s, 1.0);
  const std::string stats = (dir / "s.json").string();
  const auto ran = run_cli({"run", "--trace", trace, "--db", (dir / "r.db").string(), "--threads", "1", "--stats", stats});
  ASSERT_EQ(ran.code, 0) << ran.err;
  std::ifstream js(stats);
  const json rows = json::parse(js);
  auto frame_primitives = [&](int k) {
    return rows["stats"]["sequence/frame" + std::to_string(k)]["primitives_out"]["value"].get<double>();
  };
  EXPECT_GT(frame_primitives(0), frame_primitives(2));
  // A pose the scene has no animation for is refused, naming the line; nothing is written.
  std::string bad = text;
  bad.replace(bad.find("pose animation=0"), 16, "pose animation=3");
  std::ofstream((dir / "bad.trace").string()) << bad;
  const std::string bad_db = (dir / "bad.db").string();
  const auto refused = run_cli({"run", "--trace", (dir / "bad.trace").string(), "--db", bad_db});
  EXPECT_EQ(refused.code, 2);
  EXPECT_NE(refused.err.find("bad.trace:"), std::string::npos) << refused.err;
  EXPECT_NE(refused.err.find("has 1 animation(s)"), std::string::npos) << refused.err;
  EXPECT_FALSE(std::filesystem::exists(bad_db));
  // --animation on a scene without one is refused by `trace`.
  const auto none = run_cli({"trace", "--technique", "plain_forward", "--scene", "atrium:1", "--frames", "2", "--animation", "0",
                             "--out", (dir / "none.trace").string()});
  EXPECT_EQ(none.code, 2);
  EXPECT_NE(none.err.find("0 animation(s)"), std::string::npos) << none.err;
}

}  // namespace
}  // namespace tbdr
