// Lighting spent on surfaces that end up hidden (tsp.hidden_lit_samples and
// tsp.hidden_light_evaluations, LitSampleLedger in models/tsp.hpp), across the techniques on the
// atrium: Billeter's "overshading" column as a count. Techniques that light only the stored, final
// surface (G-buffer, visibility buffer, PLS) and those whose lit pass runs after a depth pre-pass
// with an equal test hide nothing; plain forward hides what early-Z in submission order lets
// through on an IMR, and on a TBDR only what punch-through and translucent flushes force.
#include <gtest/gtest.h>

#include <map>
#include <memory>
#include <string>
#include <vector>

#include "models/command_processor.hpp"
#include "models/hw_config.hpp"
#include "atrium_trace_setup.hpp"
#include "stat_lookup.hpp"

namespace tbdr {
namespace {

class Overshading : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { scene_ = std::make_unique<Scene>(load_scene("atrium:1")); }
  static void TearDownTestSuite() { scene_.reset(); }
  /// `technique` at 200x120, 48 lights, from the entrance, on the default GPU plus `sets`
  /// (without colours: the counts are the same, tests/test_speed_equivalence.cpp).
  static FrameResult run(const std::string& technique, const std::vector<std::string>& sets = {}) {
    const TraceSetup setup = testing_support::atrium_entrance_setup(*scene_, 48, 200, 120);
    const Trace t = generate_trace(technique, setup);
    return simulate_frame(t, "t.trace", *scene_, resolve_config({}, sets).hw, FrameOptions{.colour = false});
  }
  static double hidden(const FrameResult& f) { return stat(f, "frame/tsp", "hidden_lit_samples"); }
  static double hidden_lights(const FrameResult& f) { return stat(f, "frame/tsp", "hidden_light_evaluations"); }
  inline static std::unique_ptr<Scene> scene_;
};

TEST_F(Overshading, TechniquesThatLightOnlyTheFinalSurfaceHideNothing) {
  // deferred and its kin light the G-buffer's (final) surface with light volumes or kernels, and
  // their translucent forward pass only blends: nothing lit is ever replaced. forward_plus lights
  // after its depth pre-pass with an equal test: only the visible surface passes.
  for (const char* technique : {"deferred", "tiled_deferred", "clustered_deferred", "visibility_buffer", "light_prepass",
                                "deferred_tile_store", "forward_plus", "clustered_forward"}) {
    const FrameResult f = run(technique);
    EXPECT_EQ(hidden(f), 0.0) << technique;
    EXPECT_EQ(hidden_lights(f), 0.0) << technique;
  }
}

TEST_F(Overshading, DeferredHidesLessThanForwardPlusAndPlainForwardHidesMoreOnAnImr) {
  // On the TBDR both hide nothing (above); with the depth and stencil tests after the shader
  // (tbr, isp.early_z=0) forward+'s lit pass is shaded on every rasterised sample and its equal
  // test then fails on the hidden ones, while deferred lights no surface before its light
  // volumes: only its blended glass, where it fails the depth test, is lit in vain.
  const std::vector<std::string> late_z = {"gpu.mode=tbr", "isp.early_z=0"};
  const FrameResult deferred = run("deferred", late_z);
  const FrameResult forward_plus = run("forward_plus", late_z);
  EXPECT_GT(hidden(forward_plus), 0.0);
  EXPECT_LT(hidden(deferred), hidden(forward_plus));
  EXPECT_LT(hidden_lights(deferred), hidden_lights(forward_plus));
  // Without a depth pre-pass, an IMR lights every surface early-Z in submission order lets
  // through, and the nearer ones drawn later replace them; the TBDR's tag buffers remove them
  // before shading (what remains are the surfaces punch-through and translucent flushes made it
  // shade before a nearer one came). Measured: 2,891 samples against 916.
  const FrameResult imr = run("plain_forward", {"gpu.mode=imr"});
  const FrameResult tbdr = run("plain_forward");
  EXPECT_GT(hidden(tbdr), 0.0);
  EXPECT_GT(hidden(imr), 2 * hidden(tbdr));
  EXPECT_GT(hidden_lights(imr), 2 * hidden_lights(tbdr));
  // Every hidden sample's fragment evaluated the 48 lights (light_source=all, one sample per pixel).
  EXPECT_EQ(hidden_lights(imr), 48 * hidden(imr));
  // The pre-pass removes it on the IMR too.
  EXPECT_EQ(hidden(run("forward_plus", {"gpu.mode=imr"})), 0.0);
}

}  // namespace
}  // namespace tbdr
