#include "scene/lights.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <fstream>
#include <optional>

#include "kernel/errors.hpp"
#include "kernel/random.hpp"
#include "scene/number_file.hpp"

namespace tbdr {

namespace {

/// Light colors: warm and cool tints of white and a few saturated hues, linear RGB.
constexpr glm::vec3 palette[] = {
    {1.00f, 0.85f, 0.65f},  // warm white (tungsten)
    {1.00f, 0.95f, 0.85f},  // neutral warm
    {0.80f, 0.88f, 1.00f},  // cool white
    {1.00f, 0.55f, 0.25f},  // amber
    {1.00f, 0.30f, 0.25f},  // red
    {0.35f, 1.00f, 0.45f},  // green
    {0.35f, 0.55f, 1.00f},  // blue
    {0.85f, 0.45f, 1.00f},  // violet
};
constexpr std::size_t palette_size = sizeof(palette) / sizeof(palette[0]);

/// Area-weighted triangle picking over every instance, in world space.
class TriangleSampler {
 public:
  explicit TriangleSampler(const Scene& scene) : scene_(scene) {
    double total = 0.0;
    for (std::uint32_t i = 0; i < scene.instances.size(); ++i) {
      const Instance& inst = scene.instances[i];
      if (inst.submesh >= scene.submeshes.size()) continue;
      const SubMesh& sm = scene.submeshes[inst.submesh];
      for (std::uint32_t t = 0; t < sm.triangle_count(); ++t) {
        glm::vec3 p[3];
        world_triangle(inst, sm, t, p);
        const double area = 0.5 * static_cast<double>(glm::length(glm::cross(p[1] - p[0], p[2] - p[0])));
        if (!(area > 0.0) || !std::isfinite(area)) continue;
        total += area;
        cumulative_.push_back(total);
        refs_.push_back({i, t});
      }
    }
  }
  bool empty() const { return cumulative_.empty(); }

  /// A uniformly distributed point on the scene's surface and the geometric normal there.
  void sample(Pcg32& rng, glm::vec3& point, glm::vec3& normal) const {
    const double target = rng.uniform_double() * cumulative_.back();
    auto it = std::upper_bound(cumulative_.begin(), cumulative_.end(), target);
    if (it == cumulative_.end()) --it;
    const Ref& r = refs_[static_cast<std::size_t>(it - cumulative_.begin())];
    const Instance& inst = scene_.instances[r.instance];
    glm::vec3 p[3];
    world_triangle(inst, scene_.submeshes[inst.submesh], r.triangle, p);
    // Uniform barycentrics: (1 - sqrt(u), sqrt(u) (1 - v), sqrt(u) v).
    const float su = std::sqrt(rng.uniform());
    const float v = rng.uniform();
    point = p[0] * (1.0f - su) + p[1] * (su * (1.0f - v)) + p[2] * (su * v);
    normal = glm::normalize(glm::cross(p[1] - p[0], p[2] - p[0]));
  }

 private:
  struct Ref {
    std::uint32_t instance;
    std::uint32_t triangle;
  };
  static void world_triangle(const Instance& inst, const SubMesh& sm, std::uint32_t t, glm::vec3 out[3]) {
    for (int k = 0; k < 3; ++k) {
      const glm::vec3& q = sm.positions[sm.indices[3 * static_cast<std::size_t>(t) + static_cast<std::size_t>(k)]];
      out[k] = glm::vec3(inst.world * glm::vec4(q, 1.0f));
    }
  }
  const Scene& scene_;
  std::vector<double> cumulative_;
  std::vector<Ref> refs_;
};

// ---- light file helpers ----

std::string format_float(float f) {
  char buf[48];
  // std::to_chars with precision 9 in general format is printf's %.9g in the "C" locale: enough
  // digits for a float to read back bit-identically.
  const auto res = std::to_chars(buf, buf + sizeof buf, f, std::chars_format::general, 9);
  return std::string(buf, res.ptr);
}

}  // namespace

LightSet generate_lights(const Scene& scene, const LightSetSpec& spec) {
  const std::string where = "light set";
  if (!(spec.min_radius_fraction > 0.0f) || !(spec.max_radius_fraction >= spec.min_radius_fraction) ||
      !std::isfinite(spec.max_radius_fraction)) {
    throw InputError(where, "radius fractions must satisfy 0 < min <= max (got " +
                                format_float(spec.min_radius_fraction) + ", " + format_float(spec.max_radius_fraction) +
                                ")");
  }
  if (!(spec.spot_fraction >= 0.0f && spec.spot_fraction <= 1.0f)) {
    throw InputError(where, "spot_fraction must be in [0,1], got " + format_float(spec.spot_fraction));
  }
  const Bounds& b = scene.bounds;
  float diag = glm::length(b.extent());
  if (!(diag > 0.0f) || !std::isfinite(diag)) diag = 1.0f;

  std::optional<TriangleSampler> sampler;
  if (spec.near_surfaces) {
    sampler.emplace(scene);
    if (sampler->empty()) sampler.reset();
  }

  LightSet set;
  set.lights.reserve(spec.count);
  for (std::uint32_t i = 0; i < spec.count; ++i) {
    // One stream per light: light i is the same whatever the count.
    Pcg32 rng = Pcg32::from_seed(splitmix64(spec.seed) ^ splitmix64(0x4c49474854ULL + i));
    Light l;
    l.radius = diag * rng.range(spec.min_radius_fraction, spec.max_radius_fraction);
    if (sampler) {
      glm::vec3 p, n;
      sampler->sample(rng, p, n);
      // Off the surface along its normal by 10%..50% of the radius, kept inside the bounds.
      p += n * (l.radius * rng.range(0.1f, 0.5f));
      l.position = glm::clamp(p, b.min, b.max);
    } else {
      const float x = rng.uniform(), y = rng.uniform(), z = rng.uniform();
      l.position = b.min + b.extent() * glm::vec3(x, y, z);
    }
    l.color = palette[rng.next() % palette_size];
    l.intensity = rng.range(0.5f, 2.0f);
    // Spots are spread evenly through the list: exactly floor(count * fraction) of them.
    const double f = static_cast<double>(spec.spot_fraction);
    const bool spot = std::floor(static_cast<double>(i + 1) * f) > std::floor(static_cast<double>(i) * f);
    if (spot) {
      l.type = Light::Type::Spot;
      float dx, dz;
      do {
        dx = rng.range(-1.0f, 1.0f);
        dz = rng.range(-1.0f, 1.0f);
      } while (dx * dx + dz * dz > 1.0f);
      // Down with a tilt of at most atan(0.5), about 27 degrees.
      l.direction = glm::normalize(glm::vec3(0.5f * dx, -1.0f, 0.5f * dz));
      // Outer half-angle between 20 and 45 degrees (cosines, no trigonometry needed), inner narrower.
      l.cos_outer = rng.range(0.70710678f, 0.93969262f);
      l.cos_inner = 1.0f - (1.0f - l.cos_outer) * 0.6f;
    }
    set.lights.push_back(l);
  }
  return set;
}

LightSet read_light_file(const std::string& path) {
  NumberFile file(path, "tbdrsim-lights", 1, "light file");
  LightSet set;
  std::vector<std::string> tok;
  while (file.next(tok)) {
    Light l;
    std::size_t expected = 0;
    if (tok[0] == "point") {
      l.type = Light::Type::Point;
      expected = 9;
    } else if (tok[0] == "spot") {
      l.type = Light::Type::Spot;
      expected = 14;
    } else {
      file.fail("unknown light type '" + tok[0] + "' (expected 'point' or 'spot')");
    }
    if (tok.size() != expected) {
      file.fail(tok[0] + " light needs " + std::to_string(expected - 1) + " numbers, got " + std::to_string(tok.size() - 1) +
                (tok.size() > expected ? " (extra token '" + tok[expected] + "')" : ""));
    }
    static const char* names[] = {"type", "x", "y", "z", "radius", "r", "g", "b", "intensity",
                                  "dx", "dy", "dz", "cos_inner", "cos_outer"};
    float v[14] = {};
    for (std::size_t k = 1; k < expected; ++k) v[k] = file.number(tok[k], names[k]);
    l.position = {v[1], v[2], v[3]};
    l.radius = v[4];
    l.color = {v[5], v[6], v[7]};
    l.intensity = v[8];
    if (!(l.radius > 0.0f)) file.fail("radius must be > 0, got '" + tok[4] + "'");
    for (int k = 5; k <= 8; ++k) {
      if (v[k] < 0.0f) file.fail(std::string(names[k]) + " must be >= 0, got '" + tok[static_cast<std::size_t>(k)] + "'");
    }
    if (l.type == Light::Type::Spot) {
      l.direction = {v[9], v[10], v[11]};
      l.cos_inner = v[12];
      l.cos_outer = v[13];
      const float len = glm::length(l.direction);
      if (std::abs(len - 1.0f) > 1e-3f) file.fail("spot direction must be a unit vector (length " + format_float(len) + ")");
      if (l.cos_inner < -1.0f || l.cos_inner > 1.0f || l.cos_outer < -1.0f || l.cos_outer > 1.0f ||
          l.cos_inner < l.cos_outer) {
        file.fail("spot cones need -1 <= cos_outer <= cos_inner <= 1, got cos_inner '" + tok[12] + "' cos_outer '" + tok[13] + "'");
      }
    }
    set.lights.push_back(l);
  }
  return set;
}

const char* to_string(LightMotion m) { return m == LightMotion::Static ? "static" : "orbit"; }

LightMotion parse_light_motion(const std::string& name) {
  for (LightMotion m : {LightMotion::Static, LightMotion::Orbit}) {
    if (name == to_string(m)) return m;
  }
  throw InputError("--light-motion " + name, "unknown light motion; valid: static, orbit");
}

LightSet lights_in_motion(const LightSet& first, LightMotion motion, int frame) {
  LightSet set = first;
  if (motion == LightMotion::Static) return set;
  // A light's first place is on its circle (at its start angle), so frame 0 is where it was put.
  constexpr float kStartAngleStepDeg = 137.5f;  // the golden angle: neighbours' start angles spread evenly
  for (std::size_t i = 0; i < set.lights.size(); ++i) {
    Light& l = set.lights[i];
    const float r = kLightOrbitRadiusFraction * first.lights[i].radius;
    const float start = glm::radians(kStartAngleStepDeg * static_cast<float>(i % 360));
    const float dir = i % 2 == 0 ? 1.0f : -1.0f;
    const float a = start + dir * glm::radians(kLightOrbitDegreesPerFrame * static_cast<float>(frame));
    const glm::vec3 centre = first.lights[i].position - r * glm::vec3(std::cos(start), 0.0f, std::sin(start));
    l.position = centre + r * glm::vec3(std::cos(a), 0.0f, std::sin(a));
  }
  return set;
}

}  // namespace tbdr
