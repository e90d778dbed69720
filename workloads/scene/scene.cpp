#include "scene/scene.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

namespace tbdr {

const char* to_string(AlphaMode m) {
  switch (m) {
    case AlphaMode::Opaque: return "opaque";
    case AlphaMode::PunchThrough: return "punch-through";
    case AlphaMode::Translucent: return "translucent";
  }
  return "unknown";
}

float AlphaMask::sample(glm::vec2 uv) const {
  if (width <= 0 || height <= 0 || alpha.size() < static_cast<std::size_t>(width) * height) return 1.0f;
  if (!std::isfinite(uv.x) || !std::isfinite(uv.y)) return 0.0f;
  // Repeat wrapping: the fractional part in [0,1), then the nearest (containing) texel.
  const float fu = uv.x - std::floor(uv.x);
  const float fv = uv.y - std::floor(uv.y);
  int x = static_cast<int>(fu * static_cast<float>(width));
  int y = static_cast<int>(fv * static_cast<float>(height));
  x = std::clamp(x, 0, width - 1);
  y = std::clamp(y, 0, height - 1);
  return static_cast<float>(alpha[static_cast<std::size_t>(y) * width + x]) * (1.0f / 255.0f);
}

namespace {

/// sRGB EOTF (IEC 61966-2-1) of the 256 codes.
const std::array<float, 256> kSrgbToLinear = [] {
  std::array<float, 256> t{};
  for (int i = 0; i < 256; ++i) {
    const float c = static_cast<float>(i) / 255.0f;
    t[static_cast<std::size_t>(i)] = c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f);
  }
  return t;
}();

}  // namespace

const std::uint8_t* ColorTexels::texel_at(glm::vec2 uv) const {
  if (!decoded()) return nullptr;
  if (!std::isfinite(uv.x) || !std::isfinite(uv.y)) return nullptr;
  const float fu = uv.x - std::floor(uv.x);
  const float fv = uv.y - std::floor(uv.y);
  const int x = std::clamp(static_cast<int>(fu * static_cast<float>(width)), 0, width - 1);
  const int y = std::clamp(static_cast<int>(fv * static_cast<float>(height)), 0, height - 1);
  return &rgba[(static_cast<std::size_t>(y) * static_cast<std::size_t>(width) + static_cast<std::size_t>(x)) * 4];
}

glm::vec3 ColorTexels::linear_rgb(const std::uint8_t* texel) {
  return {kSrgbToLinear[texel[0]], kSrgbToLinear[texel[1]], kSrgbToLinear[texel[2]]};
}

glm::vec3 ColorTexels::sample_linear_rgb(glm::vec2 uv) const {
  if (!decoded()) return glm::vec3(1.0f);
  const std::uint8_t* texel = texel_at(uv);
  return texel != nullptr ? linear_rgb(texel) : glm::vec3(0.0f);  // a uv that is not finite: black
}

std::uint64_t TextureInfo::gpu_bytes() const {
  if (missing || width <= 0 || height <= 0) return 0;
  std::uint64_t w = static_cast<std::uint64_t>(width);
  std::uint64_t h = static_cast<std::uint64_t>(height);
  std::uint64_t total = 0;
  for (;;) {
    total += w * h * 4;
    if (w == 1 && h == 1) break;
    w = std::max<std::uint64_t>(1, w / 2);
    h = std::max<std::uint64_t>(1, h / 2);
  }
  return total;
}

std::uint64_t Scene::triangle_count() const {
  std::uint64_t n = 0;
  for (const Instance& inst : instances) {
    if (inst.submesh < submeshes.size()) n += submeshes[inst.submesh].triangle_count();
  }
  return n;
}

std::uint64_t Scene::vertex_count() const {
  std::uint64_t n = 0;
  for (const Instance& inst : instances) {
    if (inst.submesh < submeshes.size()) n += submeshes[inst.submesh].positions.size();
  }
  return n;
}

void update_bounds(Scene& scene) {
  constexpr float inf = std::numeric_limits<float>::infinity();
  glm::vec3 lo(inf), hi(-inf);
  bool any = false;
  for (const Instance& inst : scene.instances) {
    if (inst.submesh >= scene.submeshes.size()) continue;
    const SubMesh& sm = scene.submeshes[inst.submesh];
    const glm::mat4& m = inst.world;
    for (const glm::vec3& p : sm.positions) {
      const glm::vec3 w = glm::vec3(m * glm::vec4(p, 1.0f));
      lo = glm::min(lo, w);
      hi = glm::max(hi, w);
      any = true;
    }
  }
  scene.bounds = any ? Bounds{lo, hi} : Bounds{};
}

}  // namespace tbdr
