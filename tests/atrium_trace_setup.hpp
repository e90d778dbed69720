#pragma once
// Tests' generator setup for the atrium seen from its entrance, with seeded lights.
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

}  // namespace tbdr::testing_support
