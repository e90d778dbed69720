// A run that writes no image skips the colour arithmetic (FrameOptions::colour = false, what
// `tbdrsim run` does without --images) and must count exactly the same work: every statistic row
// and every tile row of the run (what the results database stores) is compared, value for value,
// with the run that computes the colours, for techniques that shade forward, store G-buffers,
// keep pixel local storage (light accumulation and light stacks), blend (forward_multipass's
// additive passes, the atrium's translucent glass), shade in compute kernels, and draw the
// atrium's punch-through cloth and foliage (whose alpha test decides coverage and must run for real).
#include <gtest/gtest.h>

#include <cstddef>
#include <map>
#include <string>
#include <variant>
#include <vector>

#include "app/stat_rows.hpp"
#include "app/run_driver.hpp"
#include "models/command_processor.hpp"
#include "models/hw_config.hpp"
#include "scene/scene_library.hpp"
#include "techniques/technique.hpp"
#include "atrium_trace_setup.hpp"

namespace tbdr {
namespace {

/// A frame simulated and timed as `tbdrsim run` does, with or without colours.
struct ColourRun {
  FrameResult frame;
  TimingResult timing;
  std::vector<StatRecord> stats;  ///< every row the run stores but the host's
};

/// With colours the ISP runs its general loop (FrameOptions::reference_loops) unless `lean`:
/// the runs without colours, which take the lean loop where it applies, are compared with it.
ColourRun run(const Trace& t, const Scene& s, const HwConfig& hw, bool colour, bool lean = false) {
  ColourRun r;
  r.frame = simulate_frame(t, "t.trace", s, hw, FrameOptions{.colour = colour, .reference_loops = colour && !lean});
  EnergyBreakdown energy;
  time_frame(hw, r.frame, r.timing, energy);
  r.stats = run_rows(r.frame, r.timing, energy);
  return r;
}

/// Sum of the final colour image's channels: > 0 when colours were computed.
double colour_sum(const FrameResult& f) {
  double sum = 0;
  const std::vector<glm::vec4>* img = nullptr;
  if (auto it = f.images.attachments.find(f.final_color); it != f.images.attachments.end()) img = &it->second.color;
  if (auto ib = f.images.image_buffers.find(f.final_color); ib != f.images.image_buffers.end()) img = &ib->second.color;
  if (img == nullptr) return -1;
  for (const glm::vec4& c : *img) sum += static_cast<double>(c.x + c.y + c.z);
  return sum;
}

/// Expects the two runs' statistic rows (scope, name, value) and tile rows to be identical.
void expect_same_rows(const ColourRun& with, const ColourRun& without, const std::string& what) {
  ASSERT_EQ(with.stats.size(), without.stats.size()) << what;
  std::size_t differing = 0;
  for (std::size_t i = 0; i < with.stats.size(); ++i) {
    const StatRecord& a = with.stats[i];
    const StatRecord& b = without.stats[i];
    EXPECT_EQ(a.scope, b.scope) << what << " row " << i;
    EXPECT_EQ(a.name, b.name) << what << " row " << i;
    if (a.value != b.value) {
      ++differing;
      ADD_FAILURE() << what << ": " << a.scope << "/" << a.name << " is " << a.value << " with colours, " << b.value
                    << " without";
    }
  }
  EXPECT_EQ(differing, 0u) << what;
  EXPECT_TRUE(with.timing.tiles == without.timing.tiles) << what << ": tile rows differ";
  EXPECT_EQ(with.timing.frame_cycles, without.timing.frame_cycles) << what;
}

/// The atrium:1 scene as `tbdrsim run` loads it without --images: no colour texels.
const Scene& scene_without_texels() {
  static const Scene bare = load_scene("atrium:1", SceneLoadOptions{.colour_texels = false});
  return bare;
}

class SpeedEquivalence : public testing_support::AtriumTechniqueSuite {};

// Without colour texels the textures keep their sizes (the texture traffic's address space) and
// hash; colours asked of such a scene are refused rather than drawn untextured.
TEST(SpeedEquivalenceScene, TheSceneWithoutColourTexelsKeepsItsTexturesAndRefusesColours) {
  const Scene full = load_scene("atrium:1");
  const Scene& bare = scene_without_texels();
  EXPECT_EQ(bare.content_hash, full.content_hash);
  ASSERT_EQ(bare.textures.size(), full.textures.size());
  ASSERT_EQ(bare.base_color_texels.size(), full.base_color_texels.size());
  for (std::size_t i = 0; i < full.textures.size(); ++i) {
    EXPECT_EQ(bare.textures[i].gpu_bytes(), full.textures[i].gpu_bytes());
    EXPECT_EQ(bare.base_color_texels[i].width, full.base_color_texels[i].width);
    EXPECT_TRUE(bare.base_color_texels[i].rgba.empty());
    EXPECT_FALSE(full.base_color_texels[i].rgba.empty());
  }
  EXPECT_EQ(bare.alpha_masks.size(), full.alpha_masks.size());  // the alpha tests' masks stay
  TraceSetup setup = testing_support::atrium_entrance_setup(full, 8, 64, 32);
  const Trace t = generate_trace("plain_forward", setup);
  EXPECT_THROW(simulate_frame(t, "t.trace", bare, resolve_config({}, {}).hw, FrameOptions{.colour = true}), std::logic_error);
}

TEST_P(SpeedEquivalence, EveryStatisticAndTileRowIsTheSameWithoutColours) {
  const std::string technique = GetParam();
  const Trace t = small_trace(technique);
  const HwConfig hw = resolve_config({}, {}).hw;
  const ColourRun with = run(t, *scene_, hw, true);
  const ColourRun without = run(t, scene_without_texels(), hw, false);
  expect_same_rows(with, without, technique);
  // The flag did something: the image has colour with it and none without (the cleared black).
  EXPECT_GT(colour_sum(with.frame), 0.0) << technique;
  EXPECT_EQ(colour_sum(without.frame), 0.0) << technique;
}

// With colours the ISP's lean loop (Isp::render_tile) counts the overdraw image as well: the
// same rows, colour images and per-pixel counters as the general loop. A lean loop that missed
// the overdraw count, or counted a pixel once instead of per covered sample (MSAA 4x below),
// fails here.
void expect_lean_loop_matches_general(const Trace& t, const Scene& scene, const std::string& what) {
  const HwConfig hw = resolve_config({}, {}).hw;
  const ColourRun general = run(t, scene, hw, true);
  const ColourRun lean = run(t, scene, hw, true, true);
  expect_same_rows(general, lean, what + " lean loop");
  const PixelCounters& a = general.frame.images.counters;
  const PixelCounters& b = lean.frame.images.counters;
  EXPECT_TRUE(a.rasterised_samples == b.rasterised_samples) << what << ": overdraw counters differ";
  EXPECT_TRUE(a.shaded == b.shaded && a.lights_evaluated == b.lights_evaluated && a.triangle_id == b.triangle_id) << what;
  std::uint64_t overdraw = 0;
  for (const std::uint32_t v : b.rasterised_samples) overdraw += v;
  EXPECT_EQ(overdraw, static_cast<std::uint64_t>(lean.frame.totals.render.isp.samples_rasterised.value())) << what;
  ASSERT_EQ(general.frame.images.attachments.size(), lean.frame.images.attachments.size()) << what;
  for (const auto& [name, img] : general.frame.images.attachments) {
    const AttachmentImage& other = lean.frame.images.attachments.at(name);
    EXPECT_TRUE(img.color == other.color) << what << " " << name;
    EXPECT_TRUE(img.depth == other.depth) << what << " " << name;
  }
  EXPECT_EQ(colour_sum(general.frame), colour_sum(lean.frame)) << what;
}

TEST_P(SpeedEquivalence, TheLeanLoopGivesTheGeneralLoopsImagesAndCounters) {
  expect_lean_loop_matches_general(small_trace(GetParam()), *scene_, GetParam());
}

INSTANTIATE_TEST_SUITE_P(Techniques, SpeedEquivalence, testing_support::every_technique(),
                         testing_support::technique_test_name);

// Without colours a G-buffer keeps its stored surfaces only when a command reads them
// (stored_surface_readers): deferred's and light_prepass's G-buffers, read only by light volumes
// that count without them, keep just their written marks (52 bytes a sample saved: 108 MB at
// 1080p); tiled_deferred's, read by its shading kernel, and visibility_buffer's ids, read by its
// material passes, keep theirs. With colours every one is kept. The rows are the same either way
// (EveryStatisticAndTileRowIsTheSameWithoutColours).
TEST_F(SpeedEquivalence, GbufferSurfacesAreStoredOnlyWhereSomethingReadsThem) {
  const HwConfig hw = resolve_config({}, {}).hw;
  struct Case { const char* technique; bool kept_without_colours; };
  for (const Case c : {Case{"deferred", false}, Case{"light_prepass", false}, Case{"tiled_deferred", true},
                       Case{"clustered_deferred", true}, Case{"visibility_buffer", true}}) {
    const Trace t = small_trace(c.technique);
    for (const bool colour : {true, false}) {
      const FrameResult f = simulate_frame(t, "t.trace", colour ? *scene_ : scene_without_texels(), hw, FrameOptions{.colour = colour});
      std::size_t written = 0, stored = 0;
      for (const auto& [name, img] : f.images.attachments) {
        if (img.surface_valid.empty()) continue;
        ++written;
        if (!img.surface.empty()) ++stored;
        EXPECT_EQ(img.keeps_surface, colour || c.kept_without_colours) << c.technique << " " << name;
      }
      EXPECT_GE(written, 1u) << c.technique << ": no attachment holds the G-buffer's written marks";
      EXPECT_EQ(stored, colour || c.kept_without_colours ? written : 0u) << c.technique << (colour ? " with" : " without") << " colours";
    }
  }
}

// The lighting pass of deferred is set up and binned before the G-buffer pass's tiles render
// (bin-ahead, models/command_processor.cpp): it finds the G-buffer's surface store allocated then.
// When no G-buffer tile writes a surface (every depth test fails), the store is released after
// those tiles, and the lighting pass is refused as it is when it is set up after them.
TEST_F(SpeedEquivalence, ALightingPassBinnedAheadOfAGbufferNoShaderWroteIsRefused) {
  Trace t = small_trace("deferred");
  const PassDesc* gbuffer = nullptr;
  for (const auto& cmd : t.commands) {
    if (const auto* p = std::get_if<PassDesc>(&cmd); p && gbuffer == nullptr) gbuffer = p;
  }
  ASSERT_NE(gbuffer, nullptr);
  for (const DrawCmd& d : gbuffer->draws) {
    for (PipelineState& pl : t.pipelines) {
      if (pl.name == d.pipeline) pl.depth_compare = CompareOp::Never;
    }
  }
  const HwConfig hw = resolve_config({}, {}).hw;
  for (const unsigned threads : {1u, 2u}) {
    try {
      simulate_frame(t, "t.trace", *scene_, hw, FrameOptions{.threads = threads});
      ADD_FAILURE() << "a lighting pass reading a G-buffer no shader wrote ran at " << threads << " threads";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("no shader wrote it"), std::string::npos) << e.what();
    }
  }
}

// MSAA 4x (the techniques that support it; G-buffer and PLS ones refuse it): per-sample coverage
// of the alpha-tested cloth, blending and resolves, with and without colours.
TEST_F(SpeedEquivalence, MultisampledRunsCountTheSameWithoutColours) {
  for (const char* technique : kMultisampledTechniques) {
    const Trace t = msaa4_trace(technique);
    const HwConfig hw = resolve_config({}, {}).hw;
    expect_same_rows(run(t, *scene_, hw, true), run(t, scene_without_texels(), hw, false), std::string(technique) + " 4x");
    expect_lean_loop_matches_general(t, *scene_, std::string(technique) + " 4x");
  }
}

// The other GPU modes (tile-based without deferred shading; immediate mode through the ROP
// caches) count the same without colours as well.
TEST_F(SpeedEquivalence, TbrAndImrModesCountTheSameWithoutColours) {
  for (const char* mode : {"gpu.mode=tbr", "gpu.mode=imr"}) {
    for (const char* technique : {"plain_forward", "forward_multipass", "tiled_deferred"}) {
      TraceSetup setup = testing_support::atrium_entrance_setup(*scene_, 32, 160, 96);
      if (std::string(technique) == "forward_multipass") setup.options["lights_per_pass"] = "8";
      const Trace t = generate_trace(technique, setup);
      const HwConfig hw = resolve_config({}, {mode}).hw;
      expect_same_rows(run(t, *scene_, hw, true), run(t, *scene_, hw, false), std::string(technique) + " " + mode);
    }
  }
}

// The punch-through alpha test runs for real without colours: it kills samples (the count is not
// zero), and the same ones either way (compared above). An alpha test that were skipped without
// colours would keep every sample and change the coverage.
TEST_F(SpeedEquivalence, AlphaTestStillKillsSamplesWithoutColours) {
  TraceSetup setup = testing_support::atrium_entrance_setup(*scene_, 16, 200, 120);
  const Trace t = generate_trace("plain_forward", setup);
  const FrameResult f = simulate_frame(t, "t.trace", *scene_, resolve_config({}, {}).hw, FrameOptions{.colour = false});
  EXPECT_GT(f.totals.render.tsp.alpha_test_killed_samples.value(), 0u);
}

}  // namespace
}  // namespace tbdr
