#pragma once
// Light sets: point and spot lights with a finite radius, deterministic seeded placement, and a
// text file format to read them from. Attenuation is exactly zero at and beyond the radius,
// so culling a light by its bounding sphere never changes the image.
#include <cstdint>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "scene/scene.hpp"

namespace tbdr {

/// A punctual light with a bounding sphere of `radius` world units.
struct Light {
  enum class Type : std::uint8_t { Point, Spot };
  Type type = Type::Point;
  glm::vec3 position{0.0f};
  float radius = 1.0f;                 ///< world units; contribution is exactly 0 at and beyond it
  glm::vec3 color{1.0f};               ///< linear RGB
  float intensity = 1.0f;              ///< scale on color
  glm::vec3 direction{0.0f, -1.0f, 0.0f};  ///< spot only, unit vector
  float cos_inner = 1.0f;              ///< spot only: full intensity inside this cone
  float cos_outer = 0.0f;              ///< spot only: zero outside this cone
};

/// Finite-radius distance attenuation: (1 - (d/r)^2)^2 for d < r, exactly 0 otherwise.
inline float light_attenuation(float distance, float radius) {
  if (!(distance < radius)) return 0.0f;
  const float x = distance / radius;
  const float f = 1.0f - x * x;
  return f * f;
}

/// How lights are placed by generate_lights().
struct LightSetSpec {
  std::uint32_t count = 256;
  std::uint64_t seed = 1;
  float min_radius_fraction = 0.02f;   ///< radius range as a fraction of the scene's bounds diagonal
  float max_radius_fraction = 0.08f;
  float spot_fraction = 0.0f;          ///< share of spot lights, [0,1]
  bool near_surfaces = true;           ///< place on/near scene triangles instead of uniformly in bounds
};

/// A set of lights, generated or read from a file.
struct LightSet {
  std::vector<Light> lights;
};

/// How the lights of a frame sequence move from their first frame's places.
enum class LightMotion : std::uint8_t {
  Static,  ///< every light where it was
  Orbit,   ///< each light circles its first position in the horizontal plane, at a radius of
           ///< kLightOrbitRadiusFraction of its range, kLightOrbitDegreesPerFrame per frame (every
           ///< other light the other way), starting at an angle set by its index
};
/// The orbit's radius as a fraction of the light's range: it keeps lighting what it lit, and the
/// tiles and clusters it touches change from frame to frame.
inline constexpr float kLightOrbitRadiusFraction = 0.5f;
/// Degrees a light turns per frame: once round in 1 s at 60 frames per second.
inline constexpr float kLightOrbitDegreesPerFrame = 6.0f;
/// The motion's name as `tbdrsim trace --light-motion` takes it ("static", "orbit").
const char* to_string(LightMotion m);
/// The motion of that name; throws InputError listing the names otherwise.
LightMotion parse_light_motion(const std::string& name);
/// The lights of frame `frame` (0: `first`) of a sequence under `motion`.
LightSet lights_in_motion(const LightSet& first, LightMotion motion, int frame);

/// Deterministic light placement: same scene, spec and seed give the same lights on any machine.
LightSet generate_lights(const Scene& scene, const LightSetSpec& spec);
/// Reads a light file (format in docs/lights.md); errors name file:line and the token.
LightSet read_light_file(const std::string& path);

}  // namespace tbdr
