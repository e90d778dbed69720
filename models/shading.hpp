#pragma once
// The fixed shading model every technique's image is computed with (Lambert diffuse plus
// Blinn-Phong specular, point and spot lights with the finite-radius attenuation), so images of
// different techniques can be compared pixel for pixel. Which lights a fragment evaluates is the
// technique's business; lights beyond their radius contribute exactly zero, so any conservative
// culling gives the same color.
#include <cstdint>
#include <span>

#include <glm/glm.hpp>

#include "scene/lights.hpp"

namespace tbdr {

/// The surface attributes at one shaded pixel: what a G-buffer would hold.
struct SurfacePoint {
  glm::vec3 position{0.0f};  ///< world space
  glm::vec3 normal{0.0f, 1.0f, 0.0f};  ///< world space, unit length, facing the viewer side
  glm::vec3 albedo{1.0f};    ///< linear RGB base color
  float alpha = 1.0f;        ///< coverage / opacity
  std::uint32_t material = 0xffffffffu;  ///< scene material (visibility-buffer work lists)
  std::uint32_t triangle = 0xffffffffu;  ///< frame-unique primitive id (visibility-buffer re-fetch)
};

/// Constants of the shading model.
struct ShadingModel {
  static constexpr float kAmbient = 0.03f;        ///< ambient term times albedo
  static constexpr float kSpecular = 0.25f;       ///< specular reflectance (white)
  static constexpr float kShininess = 32.0f;      ///< Blinn-Phong exponent

  /// Radiance leaving `s` towards `eye` from one light (0 outside its radius or cone). The test
  /// against the radius is inline: most candidate lights of a pixel are rejected by it.
  static glm::vec3 light_contribution(const SurfacePoint& s, glm::vec3 eye, const Light& light) {
    const glm::vec3 d = light.position - s.position;
    if (!(glm::dot(d, d) < light.radius * light.radius)) return glm::vec3(0.0f);
    return lit_contribution(s, eye, light);
  }
  /// light_contribution for a light whose sphere contains the surface point.
  static glm::vec3 lit_contribution(const SurfacePoint& s, glm::vec3 eye, const Light& light);
  /// The ambient term.
  static glm::vec3 ambient(const SurfacePoint& s) { return s.albedo * kAmbient; }
};

}  // namespace tbdr
