// Sampled simulation of sequences (docs/sequences.md, "Sampled simulation"): frame signatures
// (models/frame_signature.hpp), the grouping and extrapolation (analysis/frame_sampling.hpp), the
// windows simulated (app/sampled_run.hpp) and `tbdrsim run --sample K` against simulating every frame.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "analysis/frame_sampling.hpp"
#include "app/run_driver.hpp"
#include "app/sampled_run.hpp"
#include "models/address_space.hpp"
#include "models/frame_signature.hpp"
#include "scene/scene_library.hpp"
#include "techniques/technique.hpp"
#include "trace/trace.hpp"
#include "atrium_trace_setup.hpp"
#include "cli_run.hpp"
#include "scratch_dir.hpp"
#include "stat_lookup.hpp"

namespace tbdr {
namespace {

testing_scratch::ScratchCleanup cleanup{"frame_sampling"};

/// A scene of one square [-1, 1]^2 at z = 0 facing +z, drawn S = kSignatureTriangleStride times
/// over (2 S triangles: its two halves S times each, in that order), so that the signature's sample
/// of every S-th triangle (triangles 0 and S) sees both halves once; `flip`: wound the other way.
Scene square_scene(bool flip, bool double_sided = false) {
  Scene s;
  s.name = "square";
  Material m;
  m.double_sided = double_sided;
  s.materials.push_back(m);
  SubMesh mesh;
  mesh.positions = {{-1, -1, 0}, {1, -1, 0}, {1, 1, 0}, {-1, 1, 0}};
  const std::array<std::uint32_t, 3> a = flip ? std::array<std::uint32_t, 3>{0, 2, 1} : std::array<std::uint32_t, 3>{0, 1, 2};
  const std::array<std::uint32_t, 3> b = flip ? std::array<std::uint32_t, 3>{0, 3, 2} : std::array<std::uint32_t, 3>{0, 2, 3};
  for (const auto& half : {a, b}) {
    for (std::uint32_t copy = 0; copy < kSignatureTriangleStride; ++copy) mesh.indices.insert(mesh.indices.end(), half.begin(), half.end());
  }
  s.submeshes.push_back(mesh);
  s.instances.push_back(Instance{.submesh = 0, .world = glm::mat4(1.0f), .node = "square"});
  return s;
}

/// A 100 x 100 frame looking at the origin from (0, 0, 5), 60 degrees vertically.
Trace square_frame() {
  Trace t;
  t.frame.width = 100;
  t.frame.height = 100;
  t.camera.eye = {0, 0, 5};
  t.camera.target = {0, 0, 0};
  return t;
}

TEST(FrameSignature, MeasuresTheSquaresAreaAndItsLights) {
  // The square's half-width in NDC is 1 / (5 tan 30 deg) = 0.34641; it covers 0.34641^2 of the
  // viewport: 1200 of its 10,000 pixels, drawn S times: 1200 S pixels of depth complexity x area.
  const double copies = kSignatureTriangleStride;
  Trace frame = square_frame();
  Light in_front;
  in_front.position = {0, 0, 0};
  in_front.radius = 0.5f;
  Light behind;  // behind the eye
  behind.position = {0, 0, 10};
  behind.radius = 0.5f;
  frame.lights = {in_front, behind};
  const FrameSignature s = frame_signature(frame, square_scene(false));
  EXPECT_EQ(s.triangles_in_view.value(), 2 * copies);
  EXPECT_NEAR(s.opaque_area_px.value(), 1200 * copies, 0.5);
  EXPECT_EQ(s.masked_area_px.value(), 0);
  EXPECT_EQ(s.blended_area_px.value(), 0);
  EXPECT_EQ(s.lights_in_view.value(), 1);
  // The light's rectangle: its sphere's box seen from 4.5..5.5 units, +1 pixel each side: about
  // (2 x 0.5 / (4.5 tan 30) x 50 + 2)^2 = (19.2 + 2)^2, 450 pixels.
  EXPECT_GT(s.light_area_px.value(), 350);
  EXPECT_LT(s.light_area_px.value(), 550);
}

TEST(FrameSignature, LeavesOutBackFacesUnlessDoubleSidedAndCutsToTheViewport) {
  const Trace frame = square_frame();
  const double copies = kSignatureTriangleStride;
  EXPECT_EQ(frame_signature(frame, square_scene(true)).opaque_area_px.value(), 0);
  EXPECT_EQ(frame_signature(frame, square_scene(true)).triangles_in_view.value(), 0);
  EXPECT_NEAR(frame_signature(frame, square_scene(true, true)).opaque_area_px.value(), 1200 * copies, 0.5);
  // From 0.5 units the square overfills the view: its area is cut to the viewport's 10,000 pixels
  // (x S copies), not the 1.2 million its projection spans.
  Trace close = frame;
  close.camera.eye = {0, 0, 0.5f};
  EXPECT_NEAR(frame_signature(close, square_scene(false)).opaque_area_px.value(), 10000 * copies, 0.5);
}

/// Signatures of `n` frames in three well-separated families (frame k in family k % 3), each
/// frame a little off its family's centre; frame 0 is like family 0.
std::vector<std::vector<double>> three_families(std::size_t n) {
  std::vector<std::vector<double>> s;
  for (std::size_t k = 0; k < n; ++k) {
    const double family = static_cast<double>(k % 3) * 100.0;
    s.push_back({family + static_cast<double>(k % 5) * 0.1, 1000.0 - family});
  }
  return s;
}

TEST(FrameSampling, GroupsFramesBySignatureWithTheColdAndLastFramesAlone) {
  const SamplingPlan plan = plan_sampling(three_families(30), 5);
  ASSERT_EQ(plan.groups(), 5u);
  // Frame 0 (cold) and frame 29 (the last) are groups of their own, the others three groups of
  // their family.
  for (std::size_t alone : {0u, 29u}) {
    EXPECT_EQ(plan.representative[plan.group_of[alone]], alone);
    EXPECT_EQ(plan.members[plan.group_of[alone]], 1u);
  }
  std::size_t total = 0;
  for (std::size_t g = 0; g < plan.groups(); ++g) total += plan.members[g];
  EXPECT_EQ(total, 30u);
  for (std::size_t k = 1; k < 29; ++k) {
    const std::size_t rep = plan.representative[plan.group_of[k]];
    EXPECT_EQ(rep % 3, k % 3) << k;  // the same family
    EXPECT_NE(rep, 0u);
    EXPECT_NE(rep, 29u);
  }
  // Family 1 keeps its 10 frames; families 0 and 2 have 9 (frames 0 and 29 are apart).
  for (std::size_t g = 0; g < plan.groups(); ++g) {
    const std::size_t rep = plan.representative[g];
    if (rep != 0 && rep != 29) {
      EXPECT_EQ(plan.members[g], rep % 3 == 1 ? 10u : 9u);
    }
  }
}

TEST(FrameSampling, AsManyRepresentativesAsFramesSimulatesEveryFrameExactly) {
  const SamplingPlan plan = plan_sampling(three_families(7), 7);
  ASSERT_EQ(plan.groups(), 7u);
  std::vector<double> measured;
  double sum = 0;
  for (std::size_t g = 0; g < 7; ++g) {
    EXPECT_EQ(plan.members[g], 1u);
    EXPECT_EQ(plan.feature_sd[g][0], 0);
    measured.push_back(10.0 + static_cast<double>(g));
    sum += measured.back();
  }
  const SampledTotal t = extrapolate(plan, three_families(7), measured);
  EXPECT_EQ(t.total, sum);
  EXPECT_EQ(t.error_pct, 0);
}

TEST(FrameSampling, ExtrapolationWeighsEachRepresentativeByItsGroup) {
  // Frame 0 (cold, measured 50), three groups of frames with one feature x, and frame 7 (the
  // last, measured 30):
  //   group 1: frames 1-3, x = 9, 10, 11 (sd sqrt(2/3)), representative frame 2 (x 10), measured 20
  //   group 2: frames 4-5, x = 20, 20 (sd 0), representative frame 4, measured 40
  //   group 3: frame 6, x = 30, measured 60
  // Total = 50 + 3 x 20 + 2 x 40 + 60 + 30 = 280. Over the three middle representatives (x 10,
  // 20, 30; y 20, 40, 60; the cold and last frames left out) the line fits exactly with slope 2:
  // group 1's frames spread by 2 sqrt(2/3) = 1.633; its term's variance had its frame been drawn
  // at random: 3^2 x 1.633^2 x (3 - 1) / 3 = 16; the others' 0. Two standard errors: 2 x 4 = 8,
  // 2.857 % of 280.
  SamplingPlan plan;
  plan.group_of = {0, 1, 1, 1, 2, 2, 3, 4};
  plan.representative = {0, 2, 4, 6, 7};
  plan.members = {1, 3, 2, 1, 1};
  plan.feature_mean = {{5.0}, {10.0}, {20.0}, {30.0}, {1.0}};
  plan.feature_sd = {{0.0}, {std::sqrt(2.0 / 3.0)}, {0.0}, {0.0}, {0.0}};
  const std::vector<std::vector<double>> x{{5}, {9}, {10}, {11}, {20}, {20}, {30}, {1}};
  const SampledTotal t = extrapolate(plan, x, {50.0, 20.0, 40.0, 60.0, 30.0});
  EXPECT_DOUBLE_EQ(t.total, 280.0);
  EXPECT_EQ(t.fitted_feature, 0);
  EXPECT_NEAR(t.error_pct, 800.0 / 280.0, 1e-9);
  // plan_sampling measures each group's spread of each feature (population standard deviation).
  const SamplingPlan measured = plan_sampling({{1.0}, {9.0}, {11.0}, {10.0}, {50.0}}, 3);
  ASSERT_EQ(measured.groups(), 3u);
  const std::size_t g = measured.group_of[1];
  EXPECT_EQ(measured.members[g], 3u);
  EXPECT_NEAR(measured.feature_mean[g][0], 10.0, 1e-12);
  EXPECT_NEAR(measured.feature_sd[g][0], std::sqrt(2.0 / 3.0), 1e-12);
  // With fewer than three representatives to fit, the figure spreads like the group's most spread
  // feature relative to its mean: sd sqrt(2/3) / 10 of 20 per frame: variance 9 x (0.1633)^2 x 2/3.
  SamplingPlan two = plan;
  two.group_of = {0, 1, 1, 1, 2};
  two.representative = {0, 2, 4};
  two.members = {1, 3, 1};
  two.feature_mean = {{5.0}, {10.0}, {1.0}};
  two.feature_sd = {{0.0}, {std::sqrt(2.0 / 3.0)}, {0.0}};
  const SampledTotal fallback = extrapolate(two, {{5}, {9}, {10}, {11}, {1}}, {50.0, 20.0, 0.0});
  EXPECT_EQ(fallback.fitted_feature, -1);
  const double sigma = std::sqrt(2.0 / 3.0) / 10.0 * 20.0;
  EXPECT_NEAR(fallback.error_pct, 200.0 * std::sqrt(9.0 * sigma * sigma * 2.0 / 3.0) / 110.0, 1e-9);
}

TEST(FrameSampling, WindowsHoldTheFrameBeforeAndAfterEachRepresentativeMerged) {
  SamplingPlan plan;
  plan.representative = {0, 20, 5, 6, 21};
  const std::vector<SampleWindow> w = sample_windows(plan, 22);
  ASSERT_EQ(w.size(), 3u);
  EXPECT_EQ(w[0].first, 0u);
  EXPECT_EQ(w[0].last, 1u);
  EXPECT_EQ(w[1].first, 4u);
  EXPECT_EQ(w[1].last, 7u);
  EXPECT_EQ(w[2].first, 19u);
  EXPECT_EQ(w[2].last, 21u);  // the last frame has no frame after it
}

TEST(SampledWindows, AdoptAnotherSpacesLayoutAndAllocateAfterIt) {
  // A sampled window starts with the regions the sequence's first frames made: the same names at
  // the same addresses, and new regions after them in each range.
  AddressSpace first;
  const std::uint64_t fb = first.allocate("framebuffer.pass0.main", 10000, DramClass::Color);
  const std::uint64_t high = first.allocate_high("buffers.pass0.main", 100, DramClass::Other);
  const std::uint64_t top = first.top();
  AddressSpace window;
  window.adopt(first.regions());
  EXPECT_EQ(window.base_of("framebuffer.pass0.main"), fb);
  EXPECT_EQ(window.reuse_or_allocate("framebuffer.pass0.main", 9000, DramClass::Color), fb);
  EXPECT_EQ(window.reuse_or_allocate("buffers.pass0.main", 64, DramClass::Other, true), high);
  EXPECT_EQ(window.reserved_bytes(), first.reserved_bytes());
  EXPECT_EQ(window.allocate("vertices.pass0.main.render0", 4096, DramClass::Vertices), top);
  EXPECT_EQ(window.allocate_high("buffers.pass1.forward", 64, DramClass::Other), high + 4096);
  EXPECT_THROW(window.adopt(first.regions()), std::logic_error);  // only into an empty space
}

const Scene& atrium1() {
  static const Scene scene = load_scene("atrium:1");
  return scene;
}

/// Writes `frames` of forward_plus (atrium:1 entrance, 160x90, 32 lights, camera and lights
/// orbiting) to a scratch trace and returns its path.
std::string orbit_trace(int frames, const std::string& name) {
  const TraceSetup setup = testing_support::atrium_entrance_setup(atrium1(), 32, 160, 90);
  const std::vector<Trace> seq = generate_sequence("forward_plus", setup, SequenceMotion{frames, CameraPath::Orbit, LightMotion::Orbit, {}});
  const auto dir = testing_scratch::scratch_dir("frame_sampling", name);
  const std::string path = (dir / "t.trace").string();
  std::ofstream out(path);
  write_trace_frames(seq, out);
  return path;
}

RunOutcome run_trace(const std::string& path, std::size_t sample, const std::string& db) {
  RunRequest req;
  req.config = resolve_config({}, {});
  req.trace_path = path;
  req.db_path = db;
  req.sample_frames = sample;
  return run_one(req);
}

double device_bytes(const RunOutcome& o) { return static_cast<double>(o.timing.dram.total_read() + o.timing.dram.total_written()); }

TEST(SampledRun, SamplingEveryFrameIsTheFullRun) {
  // With as many representatives as frames every frame is a group of its own; the windows merge
  // into the whole sequence, simulated once: the estimate is the full run's, to the cycle and byte.
  const std::string path = orbit_trace(5, "every");
  const std::string db = (std::filesystem::path(path).parent_path() / "r.db").string();
  const RunOutcome full = run_trace(path, 0, db);
  const RunOutcome sampled = run_trace(path, 5, db);
  ASSERT_TRUE(sampled.sampled.has_value());
  const SamplingSummaryStats& e = sampled.sampled->estimate;
  EXPECT_EQ(e.groups.value(), 5u);
  EXPECT_EQ(e.frames_simulated.value(), 5u);
  EXPECT_EQ(e.windows.value(), 1u);
  EXPECT_NEAR(e.total_cycles.value(), full.timing.frame_cycles, 1e-9 * full.timing.frame_cycles);
  EXPECT_EQ(e.dram_bytes.value(), device_bytes(full));
  EXPECT_NEAR(e.energy_mj.value(), full.energy.total_pj * 1e-9, 1e-9 * e.energy_mj.value());
  EXPECT_EQ(e.total_cycles_error_pct.value(), 0);
  // Its sequence summary is the full run's.
  EXPECT_NEAR(stat(sampled, SequenceSummaryStats::kScope, "steady_interval_ms"), stat(full, SequenceSummaryStats::kScope, "steady_interval_ms"), 1e-12);
  EXPECT_NEAR(stat(sampled, SequenceSummaryStats::kScope, "p95_interval_ms"), stat(full, SequenceSummaryStats::kScope, "p95_interval_ms"), 1e-12);
  // Every frame has its sampling row with its signature; no frame/ row is stored.
  for (int k = 0; k < 5; ++k) EXPECT_EQ(stat(sampled, "sampling/frame" + std::to_string(k), "representative"), 1);
  EXPECT_GT(stat(sampled, "sampling/frame2", "opaque_area_px"), 0);
  for (const StatRecord& r : sampled.stats) EXPECT_NE(r.scope.rfind("frame/", 0), 0u) << r.scope << " " << r.name;
}

TEST(SampledRun, FewerRepresentativesSimulateFewerFramesAndStayWithinOneAndAHalfPercent) {
  // 16 orbiting frames, 4 representatives (frame 0, frame 15 and 2 groups): windows [0, 1], two of
  // 3 frames and [14, 15], at most 10 frames. The estimate is within 1.5 % of the full run on
  // cycles, DRAM bytes and energy (measured: about +0.35 % on each); its +- here is the fallback
  // (only two middle groups to fit), far wider, and is checked only to be positive.
  const std::string path = orbit_trace(16, "fewer");
  const std::string db = (std::filesystem::path(path).parent_path() / "r.db").string();
  const RunOutcome full = run_trace(path, 0, db);
  const RunOutcome sampled = run_trace(path, 4, db);
  ASSERT_TRUE(sampled.sampled.has_value());
  const SamplingSummaryStats& e = sampled.sampled->estimate;
  EXPECT_EQ(e.groups.value(), 4u);
  EXPECT_LE(e.frames_simulated.value(), 10u);
  EXPECT_NEAR(e.total_cycles.value() / full.timing.frame_cycles, 1.0, 0.015);
  EXPECT_NEAR(e.dram_bytes.value() / device_bytes(full), 1.0, 0.015);
  EXPECT_NEAR(e.energy_mj.value() / (full.energy.total_pj * 1e-9), 1.0, 0.015);
  EXPECT_GT(e.total_cycles_error_pct.value(), 0);
  // Each representative's measured frame is stored as sequence/frame<k>; the others are not.
  std::size_t measured = 0;
  for (int k = 0; k < 16; ++k) {
    const bool rep = stat(sampled, "sampling/frame" + std::to_string(k), "representative") == 1;
    bool has_row = false;
    for (const StatRecord& r : sampled.stats) has_row = has_row || r.scope == SequenceFrameStats::kScopePrefix + std::to_string(k);
    EXPECT_EQ(rep, has_row) << k;
    measured += rep ? 1 : 0;
  }
  EXPECT_EQ(measured, 4u);
}

TEST(SampledRun, WithEnoughWarmUpEachRepresentativeIsItsFrameOfTheFullRun) {
  // A frame's figures depend on the state the frames before it leave: caches, the DRAM's rows and
  // queues, how far the pipeline's overlap has run ahead, and where the data lives (the addresses
  // the sequence's first frames gave it: later windows take the first window's layout). With
  // three frames before it (--sample-warmup 3) each representative's window reproduces its frame
  // of the full run to the cycle and byte here (on forward_plus at 1080p over 300 frames too:
  // docs/sequences.md); the frame after it is cut to its first pass, which is all that can run
  // before the representative ends.
  const std::string path = orbit_trace(12, "warm");
  const std::string db = (std::filesystem::path(path).parent_path() / "r.db").string();
  const RunOutcome full = run_trace(path, 0, db);
  RunRequest req;
  req.config = resolve_config({}, {});
  req.trace_path = path;
  req.db_path = db;
  req.sample_frames = 4;
  req.sample_warmup_frames = 3;
  const RunOutcome sampled = run_one(req);
  ASSERT_TRUE(sampled.sampled.has_value());
  int reps = 0;
  for (int k = 0; k < 12; ++k) {
    const std::string scope = "sampling/frame" + std::to_string(k);
    if (stat(sampled, scope, "representative") != 1) continue;
    ++reps;
    const std::string frame = SequenceFrameStats::kScopePrefix + std::to_string(k);
    EXPECT_NEAR(stat(sampled, frame, "interval_cycles"), stat(full, frame, "interval_cycles"), 1e-6) << k;
    EXPECT_EQ(stat(sampled, frame, "dram_interval_bytes"), stat(full, frame, "dram_interval_bytes")) << k;
    EXPECT_NEAR(stat(sampled, frame, "energy_mj"), stat(full, frame, "energy_mj"), 1e-9 * stat(full, frame, "energy_mj")) << k;
  }
  EXPECT_EQ(reps, 4);
}

TEST(SampledRun, EveryRowIsTheSameAtOneAndTwoThreads) {
  const std::string path = orbit_trace(8, "threads");
  const std::string db = (std::filesystem::path(path).parent_path() / "r.db").string();
  RunRequest req;
  req.config = resolve_config({}, {});
  req.trace_path = path;
  req.db_path = db;
  req.sample_frames = 4;
  const RunOutcome one = run_one(req);
  req.threads = 2;
  const RunOutcome two = run_one(req);
  expect_same_rows(one.stats, two.stats);
}

TEST(SampledRun, BadRequestsExit2AndWriteNothing) {
  using testing_support::run_cli;
  const std::string path = orbit_trace(3, "bad");
  const auto dir = std::filesystem::path(path).parent_path();
  const std::string db = (dir / "bad.db").string();
  const auto one = run_cli({"run", "--trace", path, "--db", db, "--sample", "1"});
  EXPECT_EQ(one.code, 2);
  EXPECT_NE(one.err.find("--sample"), std::string::npos) << one.err;
  const auto images = run_cli({"run", "--trace", path, "--db", db, "--sample", "2", "--images", (dir / "img").string()});
  EXPECT_EQ(images.code, 2);
  EXPECT_NE(images.err.find("--images"), std::string::npos) << images.err;
  // One frame is no sequence.
  const TraceSetup setup = testing_support::atrium_entrance_setup(atrium1(), 8, 64, 64);
  const std::string single = (dir / "one.trace").string();
  {
    std::ofstream out(single);
    write_trace(generate_trace("forward_plus", setup), out);
  }
  const auto alone = run_cli({"run", "--trace", single, "--db", db, "--sample", "2"});
  EXPECT_EQ(alone.code, 2);
  EXPECT_NE(alone.err.find("one.trace"), std::string::npos) << alone.err;
  EXPECT_FALSE(std::filesystem::exists(db));
  EXPECT_FALSE(std::filesystem::exists(dir / "img"));
}

}  // namespace
}  // namespace tbdr
