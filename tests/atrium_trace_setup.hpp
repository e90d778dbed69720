#pragma once
// Tests' generator setup for the atrium seen from its entrance, with seeded lights.
#include <array>
#include <memory>
#include <string>

#include <gtest/gtest.h>

#include "scene/lights.hpp"
#include "scene/scene_library.hpp"
#include "techniques/technique.hpp"

namespace tbdr::testing_support {

/// A TraceSetup for `scene` (the atrium at detail 1) from the entrance camera, `lights` generated
/// lights, `width` x `height` pixels. `scene` must outlive the setup.
inline TraceSetup atrium_entrance_setup(const Scene& scene, int lights, int width, int height) {
  TraceSetup setup;
  setup.scene = &scene;
  setup.scene_spec = "atrium:1";
  setup.camera_name = "entrance";
  setup.camera = atrium_viewpoint("entrance", scene);
  LightSetSpec spec;
  spec.count = lights;
  setup.lights = generate_lights(scene, spec);
  setup.width = width;
  setup.height = height;
  return setup;
}

/// A suite over technique names (the parameter) sharing one atrium:1 scene, loaded once per suite.
/// Instantiate it with every_technique() and technique_test_name.
class AtriumTechniqueSuite : public ::testing::TestWithParam<std::string> {
 protected:
  static void SetUpTestSuite() { scene_ = std::make_unique<Scene>(load_scene("atrium:1")); }
  static void TearDownTestSuite() { scene_.reset(); }
  /// `technique`'s trace at 200x120 with 48 lights: every kind of pass of the technique in a
  /// fraction of a second (7 x 4 = 28 tiles of 32x32 per render; forward_multipass with 8 lights
  /// per pass: 6 additive passes).
  static Trace small_trace(const std::string& technique) {
    TraceSetup setup = atrium_entrance_setup(*scene_, 48, 200, 120);
    if (technique == "forward_multipass") setup.options["lights_per_pass"] = "8";
    return generate_trace(technique, setup);
  }
  /// The techniques that run MSAA (G-buffer and PLS ones refuse it), one of each kind: forward,
  /// additive multi-pass, visibility buffer (its compute kernel resolves) and clustered forward.
  static constexpr std::array<const char*, 4> kMultisampledTechniques = {"plain_forward", "forward_multipass",
                                                                         "visibility_buffer", "clustered_forward"};
  /// `technique`'s trace at 160x96, 4x MSAA, 32 lights: per-sample coverage of the alpha-tested
  /// cloth, blending and resolves.
  static Trace msaa4_trace(const std::string& technique) {
    TraceSetup setup = atrium_entrance_setup(*scene_, 32, 160, 96);
    setup.samples = 4;
    return generate_trace(technique, setup);
  }
  inline static std::unique_ptr<Scene> scene_;
};

/// Every registered technique (techniques/technique.hpp), so a new one is tested without a list to edit.
inline auto every_technique() { return ::testing::ValuesIn(technique_names()); }
/// Names each instance after its technique (SpeedEquivalence/Techniques.Same/deferred).
inline std::string technique_test_name(const ::testing::TestParamInfo<std::string>& info) { return info.param; }

}  // namespace tbdr::testing_support
