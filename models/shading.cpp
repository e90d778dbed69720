#include "models/shading.hpp"

#include <cmath>

namespace tbdr {

glm::vec3 ShadingModel::lit_contribution(const SurfacePoint& s, glm::vec3 eye, const Light& light) {
  const glm::vec3 to_light = light.position - s.position;
  const float dist2 = glm::dot(to_light, to_light);
  if (!(dist2 < light.radius * light.radius)) return glm::vec3(0.0f);  // beyond the radius: exactly 0
  const float dist = std::sqrt(dist2);
  const float atten = light_attenuation(dist, light.radius);
  if (atten <= 0.0f) return glm::vec3(0.0f);
  const glm::vec3 l = dist > 0.0f ? to_light / dist : s.normal;
  float cone = 1.0f;
  if (light.type == Light::Type::Spot) {
    const float cd = glm::dot(-l, light.direction);
    if (cd <= light.cos_outer) return glm::vec3(0.0f);
    const float span = light.cos_inner - light.cos_outer;
    cone = span > 0.0f ? glm::clamp((cd - light.cos_outer) / span, 0.0f, 1.0f) : 1.0f;
  }
  const float n_dot_l = glm::dot(s.normal, l);
  if (n_dot_l <= 0.0f) return glm::vec3(0.0f);
  const glm::vec3 v = glm::normalize(eye - s.position);
  const glm::vec3 h = glm::normalize(l + v);
  const float spec = std::pow(glm::max(glm::dot(s.normal, h), 0.0f), kShininess) * kSpecular;
  return light.color * (light.intensity * atten * cone) * (s.albedo * n_dot_l + glm::vec3(spec * n_dot_l));
}

}  // namespace tbdr
