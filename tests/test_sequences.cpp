// Frame sequences (docs/sequences.md): traces of several frames (version 4), the camera paths and
// light motions that generate them, and their replay: frames in flight (gpu.frames_in_flight),
// the display period (gpu.frame_period_us), caches and DRAM that keep their state from one frame
// to the next, and the per-frame and summary rows (sequence/frame<k>, sequence/summary).
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "app/run_driver.hpp"
#include "app/stat_rows.hpp"
#include "kernel/errors.hpp"
#include "models/address_space.hpp"
#include "models/hw_config.hpp"
#include "scene/scene_library.hpp"
#include "techniques/technique.hpp"
#include "trace/trace.hpp"
#include "atrium_trace_setup.hpp"
#include "cli_run.hpp"
#include "file_text.hpp"
#include "scratch_dir.hpp"
#include "stat_lookup.hpp"

namespace tbdr {
namespace {

testing_scratch::ScratchCleanup cleanup{"sequences"};

const Scene& atrium1() {
  static const Scene scene = load_scene("atrium:1");
  return scene;
}

/// `frames` frames of `technique` on atrium:1 from the entrance, `lights` lights, w x h.
std::vector<Trace> sequence(const std::string& technique, int frames, CameraPath camera, LightMotion lights, int n_lights = 256,
                            int w = 320, int h = 180) {
  const TraceSetup setup = testing_support::atrium_entrance_setup(atrium1(), n_lights, w, h);
  return generate_sequence(technique, setup, SequenceMotion{frames, camera, lights, {}});
}

std::string text_of(const std::vector<Trace>& frames) {
  std::ostringstream out;
  write_trace_frames(frames, out);
  return out.str();
}

std::size_t count(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (std::size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

/// Replays `frames` (written to a scratch trace) with the default hardware and `sets`; with
/// `images`, writing the images into the scratch folder's img/.
RunOutcome replay(const std::vector<Trace>& frames, const std::vector<std::string>& sets, const std::string& name,
                  bool images = false, unsigned threads = 1) {
  const auto dir = testing_scratch::scratch_dir("sequences", name);
  const std::string path = (dir / "t.trace").string();
  std::ofstream(path) << text_of(frames);
  RunRequest req;
  req.config = resolve_config({}, sets);
  req.trace_path = path;
  req.db_path = (dir / "r.db").string();
  if (images) req.images_dir = (dir / "img").string();
  req.threads = threads;
  return run_one(req);
}

std::string frame_scope(std::size_t k) { return SequenceFrameStats::kScopePrefix + std::to_string(k); }

/// `v` rounded to a whole number with thousands separators, as the docs print cycles: 51,718.
std::string with_commas(double v) {
  std::string digits = std::to_string(static_cast<long long>(std::llround(v)));
  for (int at = static_cast<int>(digits.size()) - 3; at > 0; at -= 3) digits.insert(static_cast<std::size_t>(at), ",");
  return digits;
}

double device_bytes(const RunOutcome& o) { return static_cast<double>(o.timing.dram.total_read() + o.timing.dram.total_written()); }

// ---- the trace ----------------------------------------------------------------------------------

TEST(SequenceTrace, FramesRoundTripWithTheirDeclarationsWrittenOnce) {
  const std::vector<Trace> frames = sequence("plain_forward", 3, CameraPath::Orbit, LightMotion::Orbit, 16, 64, 36);
  ASSERT_EQ(frames.size(), 3u);
  const std::string text = text_of(frames);
  EXPECT_EQ(text.rfind("tbdrsim-trace 4\n", 0), 0u);
  EXPECT_EQ(count(text, "\nframe "), 3u);
  EXPECT_EQ(count(text, "\ncamera "), 3u);
  EXPECT_EQ(count(text, "\nlight "), 3u * 16u);
  // Declarations once, for every frame.
  EXPECT_EQ(count(text, "\nshader "), frames[0].shaders.size());
  EXPECT_EQ(count(text, "\npipeline "), frames[0].pipelines.size());
  std::istringstream in(text);
  const std::vector<Trace> back = parse_trace_frames(in, "seq.trace");
  ASSERT_EQ(back.size(), 3u);
  EXPECT_EQ(text_of(back), text);
  for (const Trace& f : back) EXPECT_EQ(f.shaders.size(), frames[0].shaders.size());
  const Camera expected = camera_on_path(frames[0].camera, CameraPath::Orbit, 2);
  EXPECT_EQ(back[2].camera.eye, expected.eye);
  EXPECT_NE(back[2].camera.eye, back[0].camera.eye);
  EXPECT_NE(back[1].lights[0].position, back[0].lights[0].position);
}

TEST(SequenceTrace, OneFrameIsWrittenAsVersion3ThatOlderReadersRead) {
  const std::vector<Trace> frames = sequence("plain_forward", 1, CameraPath::Orbit, LightMotion::Static, 4, 64, 36);
  const std::string text = text_of(frames);
  EXPECT_EQ(text.rfind("tbdrsim-trace 3\n", 0), 0u);
  EXPECT_EQ(text, trace_text(frames[0]));
  EXPECT_EQ(trace_hash(frames), trace_hash(frames[0]));
}

/// The error text of reading `text` as a sequence ("" if it reads).
std::string sequence_error(const std::string& text) {
  std::istringstream in(text);
  try {
    parse_trace_frames(in, "seq.trace");
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(SequenceTrace, ABadSequenceIsRefusedAtItsLine) {
  const std::string text = text_of(sequence("plain_forward", 2, CameraPath::Static, LightMotion::Static, 4, 64, 36));
  const std::size_t second = text.find("\nframe ", text.find("\nframe ") + 1) + 1;
  const int second_line = static_cast<int>(count(text.substr(0, second), "\n")) + 1;
  // A version 3 trace holds one frame.
  std::string v3 = text;
  v3.replace(0, 16, "tbdrsim-trace 3\n");
  EXPECT_NE(sequence_error(v3).find("seq.trace:" + std::to_string(second_line) + ": duplicate 'frame' line"), std::string::npos)
      << sequence_error(v3);
  EXPECT_NE(sequence_error(v3).find("needs version 4"), std::string::npos);
  // The frames share one size.
  std::string resized = text;
  resized.replace(second, std::string("frame width=64").size(), "frame width=65");
  EXPECT_NE(sequence_error(resized).find("seq.trace:" + std::to_string(second_line) + ": frame 65x36"), std::string::npos)
      << sequence_error(resized);
  EXPECT_NE(sequence_error(resized).find("share one size"), std::string::npos);
  // A frame with no command before the next.
  const std::size_t first = text.find("\nframe ") + 1;
  const std::string frame_line = text.substr(first, text.find('\n', first) - first + 1);
  std::string empty = text;
  empty.insert(second, frame_line);
  EXPECT_NE(sequence_error(empty).find("has no pass, dispatch or barrier before the next 'frame' line"), std::string::npos)
      << sequence_error(empty);
  // A command that reads one frame says so, naming the second frame's line.
  std::istringstream in(text);
  try {
    parse_trace(in, "seq.trace");
    ADD_FAILURE() << "a sequence read as one frame";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("seq.trace:" + std::to_string(second_line) + ": the trace holds a sequence of 2 frames"),
              std::string::npos)
        << e.what();
  }
}

TEST(SequenceTrace, FramesAndTheDeclarationsTheyHoldAreBounded) {
  // Each frame holds every declaration made before it: frames x declarations is bounded
  // (kMaxSequenceDeclarations), and so are the frames (kMaxTraceFrames).
  const std::string head = "tbdrsim-trace 4\nscene atrium detail=1\n";
  const std::string frame = "frame width=8 height=8 samples=1\ncamera eye=0,0,5 target=0,0,0 up=0,1,0 fov_y_deg=60 near=0.1 far=100\n"
                            "barrier resources=all\n";
  std::string many = head;
  for (std::uint64_t k = 0; k <= kMaxTraceFrames; ++k) many += frame;
  // Line of frame k: 3 + 3k.
  EXPECT_NE(sequence_error(many).find("seq.trace:" + std::to_string(3 + 3 * kMaxTraceFrames) + ": more than 1000 frames"),
            std::string::npos)
      << sequence_error(many);
  std::string fewer = head;
  for (std::uint64_t k = 0; k < 3; ++k) fewer += frame;
  EXPECT_EQ(sequence_error(fewer), "");
  // 11,000 shaders before the first frame: the 96th frame (index 95) brings the frames' copies to
  // 96 x 11,000 = 1,056,000 > 2^20 = 1,048,576.
  std::string declared = head;
  for (int i = 0; i < 11000; ++i) {
    declared += "shader s" + std::to_string(i) + " alu_ops=1 tex_fetches=0 varyings=0 light_alu_ops=0 light_source=none color_outputs=0\n";
  }
  for (int k = 0; k < 100; ++k) declared += frame;
  EXPECT_NE(sequence_error(declared).find("frame 95 brings the declarations the sequence's frames hold to 1056000 (11000 per frame)"),
            std::string::npos)
      << sequence_error(declared);
}

// ---- camera paths and light motion ------------------------------------------------------------

TEST(SequenceMotion, TheOrbitTurnsOneDegreePerFrameAboutTheTarget) {
  const Camera first = atrium_viewpoint("entrance", atrium1());
  for (int k : {0, 1, 30, 90}) {
    const Camera c = camera_on_path(first, CameraPath::Orbit, k);
    const glm::vec3 a = first.eye - first.target, b = c.eye - c.target;
    EXPECT_EQ(c.target, first.target);
    EXPECT_NEAR(b.y, a.y, 1e-4);  // same height
    EXPECT_NEAR(glm::length(b), glm::length(a), 1e-3 * glm::length(a));
    const float cosine = glm::dot(glm::vec2(a.x, a.z), glm::vec2(b.x, b.z)) / glm::dot(glm::vec2(a.x, a.z), glm::vec2(a.x, a.z));
    EXPECT_NEAR(std::acos(std::min(1.0f, cosine)), glm::radians(kOrbitDegreesPerFrame * static_cast<float>(k)), 1e-3) << k;
  }
  // The flythrough walks 1 % of the eye-target distance per frame; after 100 frames the eye is
  // where the target was.
  const Camera walked = camera_on_path(first, CameraPath::Flythrough, 100);
  EXPECT_NEAR(glm::length(walked.eye - first.target), 0.0f, 1e-3f * glm::length(first.eye - first.target));
  EXPECT_EQ(camera_on_path(first, CameraPath::Static, 57).eye, first.eye);
}

TEST(SequenceMotion, LightsCircleTheirFirstPlaceAtHalfTheirRange) {
  LightSetSpec spec;
  spec.count = 8;
  const LightSet first = generate_lights(atrium1(), spec);
  const LightSet at0 = lights_in_motion(first, LightMotion::Orbit, 0);
  const LightSet at15 = lights_in_motion(first, LightMotion::Orbit, 15);
  for (std::size_t i = 0; i < first.lights.size(); ++i) {
    EXPECT_NEAR(glm::length(at0.lights[i].position - first.lights[i].position), 0.0f, 1e-4f);
    const float moved = glm::length(at15.lights[i].position - first.lights[i].position);
    // A chord of the circle of radius r = 0.5 x range for 15 x 6 = 90 degrees: r x sqrt(2).
    const float r = kLightOrbitRadiusFraction * first.lights[i].radius;
    EXPECT_NEAR(moved, r * std::sqrt(2.0f), 1e-3f * r) << i;
    EXPECT_EQ(at15.lights[i].position.y, first.lights[i].position.y);
    EXPECT_EQ(at15.lights[i].radius, first.lights[i].radius);
  }
  EXPECT_EQ(lights_in_motion(first, LightMotion::Static, 15).lights[3].position, first.lights[3].position);
}

TEST(SequenceMotion, ACameraPathFileGivesEachFrameItsCamera) {
  const auto dir = testing_scratch::scratch_dir("sequences", "camera_file");
  const std::string path = (dir / "walk.txt").string();
  std::ofstream(path) << "tbdrsim-camera-path 1\n# eye target [fov]\n0 1.6 9  0 1.5 0\n\n1 1.6 8.5  0 1.5 0  50\n";
  const Camera first = atrium_viewpoint("entrance", atrium1());
  const std::vector<Camera> cams = read_camera_path_file(path, first);
  ASSERT_EQ(cams.size(), 2u);
  EXPECT_EQ(cams[0].eye, glm::vec3(0, 1.6f, 9));
  EXPECT_EQ(cams[0].fov_y_deg, first.fov_y_deg);  // none given: the viewpoint's
  EXPECT_EQ(cams[1].fov_y_deg, 50.0f);
  EXPECT_EQ(cams[1].near_plane, first.near_plane);
  // Through the command line: two frames, each with its camera; a third is more than the file holds.
  const auto ok = testing_support::run_cli({"trace", "--technique", "plain_forward", "--scene", "atrium:1", "--lights", "4",
                                            "--resolution", "64x36", "--frames", "2", "--camera-path", path, "--out",
                                            (dir / "w.trace").string()});
  ASSERT_EQ(ok.code, 0) << ok.err;
  const std::vector<Trace> frames = read_trace_frames((dir / "w.trace").string());
  ASSERT_EQ(frames.size(), 2u);
  EXPECT_EQ(frames[1].camera.eye, glm::vec3(1, 1.6f, 8.5f));
  const auto more = testing_support::run_cli({"trace", "--technique", "plain_forward", "--scene", "atrium:1", "--frames", "3",
                                              "--camera-path", path, "--out", (dir / "x.trace").string()});
  EXPECT_EQ(more.code, 2);
  EXPECT_NE(more.err.find("holds 2 cameras, fewer than the frames asked for"), std::string::npos) << more.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "x.trace"));
  // Bad lines are refused at their line.
  auto error_of = [&](const std::string& text) {
    std::ofstream(path) << text;
    try {
      read_camera_path_file(path, first);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_NE(error_of("tbdrsim-camera-path 1\n0 1 2 0 1 2\n").find("walk.txt:2: the eye is on the target"), std::string::npos);
  EXPECT_NE(error_of("tbdrsim-camera-path 1\n0 1 2 0 1\n").find("walk.txt:2: a camera needs 6 numbers"), std::string::npos);
  EXPECT_NE(error_of("tbdrsim-camera-path 1\n0 x 2 0 1 0\n").find("walk.txt:2: expected a finite number for eye_y, got 'x'"),
            std::string::npos);
  EXPECT_NE(error_of("tbdrsim-camera-path 1\n0 5 0 0 1 0\n").find("along the camera's up vector"), std::string::npos);
  EXPECT_NE(error_of("tbdrsim-camera-path 1\n0 1 5 0 1 0 200\n").find("fov_y_deg '200' is outside"), std::string::npos);
  EXPECT_NE(error_of("tbdrsim-camera-path 2\n").find("walk.txt:1: unsupported camera path file version '2'"), std::string::npos);
  EXPECT_NE(error_of("tbdrsim-camera-path 1\n").find("no camera"), std::string::npos);
  const auto missing = testing_support::run_cli({"trace", "--frames", "2", "--camera-path", "orbti", "--out", (dir / "y.trace").string()});
  EXPECT_EQ(missing.code, 2);
  EXPECT_NE(missing.err.find("--camera-path orbti: neither a camera path (static, orbit, flythrough) nor a camera path file"),
            std::string::npos)
      << missing.err;
}

// ---- replay -----------------------------------------------------------------------------------

TEST(SequenceReplay, TheFirstFrameIsTheFrameAloneAndTheFramesAddUpToTheSequence) {
  const std::vector<Trace> frames = sequence("forward_plus", 3, CameraPath::Orbit, LightMotion::Orbit);
  const RunOutcome seq = replay(frames, {"gpu.frames_in_flight=1"}, "first_alone");
  ASSERT_EQ(seq.timing.frames.size(), 3u);
  double invocations = 0, covered = 0;
  for (std::size_t k = 0; k < frames.size(); ++k) {
    const RunOutcome alone = replay({frames[k]}, {"gpu.frames_in_flight=1"}, "alone" + std::to_string(k));
    invocations += alone.frame.totals.render.tsp.shader_invocations.as_double();
    covered += alone.frame.shape.covered_pixels.as_double();
    // Every frame's functional figures are the frame's alone: each is simulated on its own.
    EXPECT_EQ(stat(seq, frame_scope(k), "shader_invocations"), alone.frame.totals.render.tsp.shader_invocations.as_double()) << k;
    EXPECT_EQ(stat(seq, frame_scope(k), "primitives_out"), alone.frame.totals.render.geometry.primitives_out.as_double()) << k;
    EXPECT_EQ(stat(seq, frame_scope(k), "light_evaluations"),
              alone.frame.totals.render.tsp.light_evaluations.as_double() +
                  alone.frame.totals.compute.compute_light_evaluations.as_double())
        << k;
    if (k == 0) {
      // Nothing runs before the first frame with one frame in flight: its time and DRAM bytes are
      // the frame's alone, to the cycle and the byte.
      EXPECT_NEAR(stat(seq, frame_scope(0), "end_cycle"), alone.timing.frame_cycles, 1.0);
      // Its DRAM bytes are the frame's alone but the writes still queued at its end (posted: the
      // pixel back end is done when the DRAM accepts them), which DRAM moves in the next frame's
      // interval: at most a full write queue of lines per channel.
      const HwConfig hw = resolve_config({}, {}).hw;
      const double queued = device_bytes(alone) - stat(seq, frame_scope(0), "dram_interval_bytes");
      EXPECT_GE(queued, 0);
      EXPECT_LE(queued, static_cast<double>(hw.dram.channels * hw.dram.write_queue_entries * 64));
    }
  }
  // The functional figures of a sequence are its frames' sums (per-pixel ratios stay per frame).
  EXPECT_EQ(seq.frame.totals.render.tsp.shader_invocations.as_double(), invocations);
  EXPECT_EQ(seq.frame.shape.covered_pixels.as_double(), covered);
  ASSERT_TRUE(seq.derived.shaded_fragments_per_pixel.has_value());
  EXPECT_NEAR(*seq.derived.shaded_fragments_per_pixel, invocations / (320.0 * 180.0 * 3.0), 1e-9);  // per frame's pixel
  // The frames' intervals add up to the sequence's time, their DRAM bytes to what DRAM moved.
  double cycles = 0, bytes = 0;
  for (std::size_t k = 0; k < 3; ++k) {
    cycles += stat(seq, frame_scope(k), "interval_cycles");
    bytes += stat(seq, frame_scope(k), "dram_interval_bytes");
  }
  EXPECT_NEAR(cycles, seq.timing.frame_cycles, 1e-6 * cycles);
  EXPECT_EQ(bytes, device_bytes(seq));
  // Their energies (each frame's units, the memory's energy in its interval, leakage over it) add
  // up to the sequence's.
  double mj = 0;
  for (std::size_t k = 0; k < 3; ++k) {
    mj += stat(seq, frame_scope(k), "energy_mj");
    EXPECT_GT(seq.sequence.energy[k].total_pj, 0) << k;
  }
  EXPECT_NEAR(mj, seq.energy.total_pj * 1e-9, 1e-9 * mj);
  // Each frame's own counts (what changed from frame to frame), adding up to the sequence's.
  double frame_invocations = 0, frame_primitives = 0;
  for (std::size_t k = 0; k < 3; ++k) {
    frame_invocations += stat(seq, frame_scope(k), "shader_invocations");
    frame_primitives += stat(seq, frame_scope(k), "primitives_out");
  }
  EXPECT_EQ(frame_invocations, invocations);
  EXPECT_EQ(frame_primitives, seq.frame.totals.render.geometry.primitives_out.as_double());
  EXPECT_EQ(stat(seq, SequenceSummaryStats::kScope, "frames"), 3);
  // Steady frames: frame 1 (frame 0 is the warm-up, frame 2 the drain).
  EXPECT_NEAR(stat(seq, SequenceSummaryStats::kScope, "steady_interval_ms"), stat(seq, frame_scope(1), "interval_ms"), 1e-12);
}

TEST(SequenceReplay, ASecondFrameInFlightHidesMostOfTheNextFramesBinning) {
  // plain_forward, atrium:1 320x180, 64 lights, camera and lights orbiting, 4 frames; steady
  // frames 1 and 2. The frame is USC-bound (about 1.1 ms). With one frame in flight each frame
  // starts with its binning (about 51,700 cycles, nothing else running); with two it runs while
  // the frame before renders its tiles, so the frame's interval shrinks by the part of it that
  // overlap hides. It cannot shrink by more than the binning (the frame's other work is the same),
  // and the binning then shares the USCs (its vertex shading) and DRAM with those tiles, so it
  // hides less than all of it: measured 46,900 of 51,700 cycles (1.0943 -> 1.0163 ms per frame at
  // 600 MHz). (A DRAM-bound frame gains less or loses: docs/sequences.md.)
  const std::vector<Trace> frames = sequence("plain_forward", 4, CameraPath::Orbit, LightMotion::Orbit, 64);
  const RunOutcome one = replay(frames, {"gpu.frames_in_flight=1"}, "fif1");
  const RunOutcome two = replay(frames, {"gpu.frames_in_flight=2"}, "fif2");
  const double steady1 = stat(one, SequenceSummaryStats::kScope, "steady_interval_ms");
  const double steady2 = stat(two, SequenceSummaryStats::kScope, "steady_interval_ms");
  const double ms_per_cycle = one.timing.frame_time_ps * 1e-9 / one.timing.frame_cycles;
  // Frame 1's first binning with one frame in flight: from the frame's start to its pre-pass's binning end.
  double binning_cycles = -1;
  for (const CommandTime& c : one.timing.commands) {
    if (c.name == "frame1.pass0.main") binning_cycles = c.binning_end_cycle - c.start_cycle;
  }
  ASSERT_GT(binning_cycles, 0);
  EXPECT_EQ(stat(one, frame_scope(1), "start_cycle"), stat(one, frame_scope(0), "end_cycle"));
  EXPECT_LT(stat(two, frame_scope(1), "start_cycle"), stat(two, frame_scope(0), "end_cycle"));  // overlapped
  const double saved_cycles = (steady1 - steady2) / ms_per_cycle;
  // docs/sequences.md quotes these three figures.
  const std::string row = "| cycles | " + with_commas(binning_cycles) + " | " + with_commas(steady1 / ms_per_cycle) + " | " +
                          with_commas(steady2 / ms_per_cycle) + " |";
  EXPECT_NE(testing_support::read_text(std::filesystem::path(TBDRSIM_SOURCE_DIR) / "docs/sequences.md").find(row), std::string::npos)
      << "docs/sequences.md should have the row " << row;
  EXPECT_GT(saved_cycles, 0.5 * binning_cycles) << steady1 << " -> " << steady2 << " ms, binning " << binning_cycles;
  EXPECT_LE(saved_cycles, binning_cycles);
}

TEST(SequenceReplay, AStaticViewFindsTheCachesWarmAfterTheFirstFrame) {
  // The same frame three times, one frame in flight, forward_plus at 320x180 with 256 lights: the
  // frame moves about 3.2 MB through DRAM. With the default 128 KiB SLC nothing of it is left for
  // the next frame (each frame within 1 % of the first). With an 8 MiB SLC the whole frame's
  // data stays: the later frames find it at the same addresses (the same buffers, regions reused)
  // and DRAM moves little more than the colour stores (230,400 bytes a frame): measured 2,111,808
  // bytes for the first frame, 229,376 for the second, and 174,018 -> 115,095 cycles.
  const std::vector<Trace> frames = sequence("forward_plus", 3, CameraPath::Static, LightMotion::Static);
  const RunOutcome small = replay(frames, {"gpu.frames_in_flight=1"}, "warm_small");
  EXPECT_NEAR(stat(small, frame_scope(1), "dram_interval_bytes"), stat(small, frame_scope(0), "dram_interval_bytes"),
              0.01 * stat(small, frame_scope(0), "dram_interval_bytes"));
  const RunOutcome big = replay(frames, {"gpu.frames_in_flight=1", "cache.slc.size_bytes=8388608"}, "warm_big");
  const double first = stat(big, frame_scope(0), "dram_interval_bytes");
  const double second = stat(big, frame_scope(1), "dram_interval_bytes");
  EXPECT_LT(second, 0.2 * first);
  EXPECT_LT(stat(big, frame_scope(1), "interval_cycles"), 0.8 * stat(big, frame_scope(0), "interval_cycles"));
}

TEST(SequenceReplay, TheDisplayPeriodSpacesTheFrames) {
  // A 1,000 us period (longer than any of these 0.4 ms frames): frame k starts at k periods,
  // 600,000 cycles apart at 600 MHz, and the sequence lasts 2 periods plus the last frame.
  const std::vector<Trace> frames = sequence("forward_plus", 3, CameraPath::Orbit, LightMotion::Static);
  const RunOutcome o = replay(frames, {"gpu.frame_period_us=1000"}, "period");
  const double cycles_per_period = 1000.0 * o.timing.frame_cycles / (o.timing.frame_time_ps * 1e-6);
  EXPECT_NEAR(cycles_per_period, 600000, 1);
  for (std::size_t k = 1; k < 3; ++k) EXPECT_NEAR(stat(o, frame_scope(k), "start_cycle"), k * cycles_per_period, 1) << k;
  EXPECT_NEAR(o.timing.frame_cycles, 2 * cycles_per_period + stat(o, frame_scope(2), "latency_cycles"), 1);
  // The period figure covers the 3 periods: idle = 3 ms - the sequence's time.
  EXPECT_NEAR(o.energy.idle_ps, 3e9 - o.timing.frame_time_ps, 1e3);
}

TEST(TransactionElimination, AStaticViewSkipsEveryColourTileStoreFromTheSecondFrame) {
  // forward_plus, 3 frames of a static view at 320x180: its forward pass stores one rgba8 colour
  // attachment, 10 x 6 = 60 tiles of 32x32 (the last row 20 pixels tall), 320 x 180 x 4 = 230,400
  // bytes a frame. Frames 1 and 2 find every tile's signature equal to the frame before's:
  //   eliminated stores  2 x 60 = 120, eliminated bytes 2 x 230,400 = 460,800;
  //   signatures: frame 0 writes 60 x 8, frames 1 and 2 read and write 60 x 8 each:
  //   480 + 2 x 960 = 2,400 bytes;
  //   the colour bytes the units request: written 460,800 - 3 x 480 = 459,360 fewer, read 2 x 480 more.
  const std::vector<Trace> frames = sequence("forward_plus", 3, CameraPath::Static, LightMotion::Static, 64);
  const RunOutcome off = replay(frames, {"writeback.transaction_elimination=0"}, "te_off", true);
  const RunOutcome on = replay(frames, {"writeback.transaction_elimination=1"}, "te_on", true);
  const TileMemoryStats& tm = on.frame.totals.render.tile_memory;
  EXPECT_EQ(tm.eliminated_tile_stores.value(), 120u);
  EXPECT_EQ(tm.eliminated_store_bytes.value(), 460800u);
  EXPECT_EQ(tm.signature_bytes.value(), 2400u);
  EXPECT_EQ(off.frame.totals.render.tile_memory.eliminated_tile_stores.value(), 0u);
  const auto color = static_cast<std::size_t>(DramClass::Color);
  EXPECT_EQ(off.frame.dram.write_bytes[color] - on.frame.dram.write_bytes[color], 459360u);
  EXPECT_EQ(on.frame.dram.read_bytes[color] - off.frame.dram.read_bytes[color], 960u);
  EXPECT_EQ(on.frame.totals.render.tsp.shader_invocations.value(), off.frame.totals.render.tsp.shader_invocations.value());
  // What the skipped stores leave in memory is what they would have written: the images (the last
  // frame's attachments, read back as the next frame would) are the same files.
  for (const std::string& f : on.images_written) {
    const std::string name = std::filesystem::path(f).filename().string();
    if (name == "heat_tile_cycles.png") continue;  // the timing differs: that is the point
    const auto other = std::filesystem::path(off.images_written.front()).parent_path() / name;
    EXPECT_EQ(testing_support::read_text(f), testing_support::read_text(other)) << name;
  }
  // Fewer bytes reach DRAM from the second frame on.
  EXPECT_LT(stat(on, frame_scope(1), "dram_interval_bytes"), stat(off, frame_scope(1), "dram_interval_bytes"));
}

TEST(TransactionElimination, AMovingViewStoresTheTilesThatChanged) {
  // The orbit changes most tiles from frame to frame; a single frame has nothing to compare with.
  const std::vector<Trace> frames = sequence("forward_plus", 3, CameraPath::Orbit, LightMotion::Orbit, 64);
  const RunOutcome moving = replay(frames, {"writeback.transaction_elimination=1"}, "te_orbit");
  EXPECT_LT(moving.frame.totals.render.tile_memory.eliminated_tile_stores.value(), 60u);
  const RunOutcome single = replay({frames[0]}, {"writeback.transaction_elimination=1"}, "te_single");
  EXPECT_EQ(single.frame.totals.render.tile_memory.eliminated_tile_stores.value(), 0u);
  EXPECT_EQ(single.frame.totals.render.tile_memory.signature_bytes.value(), 480u);  // 60 written
}

/// Every technique replays a sequence: 3 frames of an orbit at 96x54, 16 lights, 2 in flight.
class SequenceEveryTechnique : public ::testing::TestWithParam<std::string> {};

TEST_P(SequenceEveryTechnique, ReplaysFrameAfterFrame) {
  const std::vector<Trace> frames = sequence(GetParam(), 3, CameraPath::Orbit, LightMotion::Orbit, 16, 96, 54);
  const RunOutcome o = replay(frames, {}, "every_" + GetParam());
  ASSERT_EQ(o.timing.frames.size(), 3u);
  for (std::size_t k = 0; k < 3; ++k) {
    EXPECT_GT(stat(o, frame_scope(k), "interval_cycles"), 0) << k;
    if (k > 0) {
      EXPECT_GE(stat(o, frame_scope(k), "start_cycle"), stat(o, frame_scope(k - 1), "start_cycle")) << k;
    }
  }
  EXPECT_GT(stat(o, SequenceSummaryStats::kScope, "steady_fps"), 0);
}

INSTANTIATE_TEST_SUITE_P(Techniques, SequenceEveryTechnique, ::testing::ValuesIn(technique_names()),
                         [](const ::testing::TestParamInfo<std::string>& i) { return i.param; });

TEST(SequenceStudy, PrintsTheColdFrameBesideTheSteadyState) {
  const auto dir = testing_scratch::scratch_dir("sequences", "study");
  const auto r = testing_support::run_cli({"study", "--technique", "forward_plus", "--technique", "plain_forward", "--lights", "16",
                                           "--resolution", "96x54", "--scene", "atrium:1", "--frames", "4", "--images", "none",
                                           "--jobs", "1", "--out", (dir / "s").string()});
  ASSERT_EQ(r.code, 0) << r.err << r.out;
  const auto at = r.out.find("\nSequences (4 frames, camera orbit, lights orbiting");
  ASSERT_NE(at, std::string::npos) << r.out;
  // Its rows: technique, lights, cold ms, steady ms, p95 ms, fps, DRAM MB/f, mJ/f, cold mJ.
  for (const std::string t : {"forward_plus", "plain_forward"}) {
    const auto row = r.out.find("\n" + t + " ", at);
    ASSERT_NE(row, std::string::npos) << t;
    std::istringstream line(r.out.substr(row + 1, r.out.find('\n', row + 1) - row - 1));
    std::string name;
    double lights = 0, cold = 0, steady = 0, p95 = 0, fps = 0, mb = 0, mj = 0, cold_mj = 0;
    line >> name >> lights >> cold >> steady >> p95 >> fps >> mb >> mj >> cold_mj;
    EXPECT_EQ(lights, 16);
    EXPECT_GT(cold, 0);
    EXPECT_GT(steady, 0);
    EXPECT_GE(p95, steady * 0.999);
    EXPECT_NEAR(fps, 1000.0 / steady, 0.01 * fps);  // (both printed rounded)
    EXPECT_GT(mb, 0);
    EXPECT_GT(mj, 0);
    EXPECT_GT(cold_mj, 0);
  }
  // The method table counts geometry passes per frame: forward_plus's depth pre-pass and forward pass.
  const auto method = r.out.find("\nforward_plus ", r.out.find("Method table"));
  ASSERT_NE(method, std::string::npos);
  EXPECT_NE(r.out.substr(method, 120).find("  2  "), std::string::npos) << r.out.substr(method, 120);
}

TEST(SequenceReplay, EveryRowIsTheSameAtOneAndTwoThreads) {
  // With two threads the timing model runs beside the functional run, fed frame after frame; with
  // one, after it: the same rows (transaction elimination on, so the tile signatures are compared
  // across frames on the tile threads too).
  const std::vector<Trace> frames = sequence("deferred", 3, CameraPath::Orbit, LightMotion::Orbit, 16, 160, 96);
  const RunOutcome one = replay(frames, {"writeback.transaction_elimination=1"}, "threads1", false, 1);
  const RunOutcome two = replay(frames, {"writeback.transaction_elimination=1"}, "threads2", false, 2);
  expect_same_rows(one.stats, two.stats);
}

TEST(SequenceAddresses, ALaterFrameUsesTheRegionsTheFrameBeforeAllocated) {
  AddressSpace space;
  const std::uint64_t a = space.allocate("framebuffer.pass0.main", 10000, DramClass::Color);
  EXPECT_EQ(space.reuse_or_allocate("framebuffer.pass0.main", 9000, DramClass::Color), a);
  EXPECT_EQ(space.reuse_or_allocate("framebuffer.pass0.main", 12288, DramClass::Color), a);  // 3 pages reserved
  const std::uint64_t bigger = space.reuse_or_allocate("framebuffer.pass0.main", 20000, DramClass::Color);
  EXPECT_NE(bigger, a);
  EXPECT_NE(space.find("framebuffer.pass0.main#2"), nullptr);
  EXPECT_EQ(space.reuse_or_allocate("framebuffer.pass0.main", 20000, DramClass::Color), bigger);
  EXPECT_NE(space.reuse_or_allocate("framebuffer.pass0.main", 100, DramClass::Gbuffer), a);  // another class
  const std::uint64_t high = space.reuse_or_allocate("buffers.pass1.forward", 64, DramClass::Other, true);
  EXPECT_GE(high, AddressSpace::kHighBase);
  EXPECT_EQ(space.reuse_or_allocate("buffers.pass1.forward", 64, DramClass::Other, true), high);
}

}  // namespace
}  // namespace tbdr
