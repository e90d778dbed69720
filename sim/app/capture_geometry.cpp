#include "app/capture_geometry.hpp"

#include <cmath>

namespace tbdr {

namespace {

/// Appends the quad a, b, c, d (in order around it) as two triangles.
void push_quad(ExpandedPrimitives& out, std::uint32_t a, std::uint32_t b, std::uint32_t c, std::uint32_t d) {
  out.triangles.insert(out.triangles.end(), {a, b, c, a, c, d});
}

/// Clip position `c` moved by `offset_px` pixels on screen: the offset in NDC is
/// offset_px x 2 / frame size, and in clip space that times w (the perspective divide undone).
glm::vec4 moved(const glm::vec4& c, glm::vec2 offset_px, FramePixels frame) {
  return {c.x + offset_px.x * 2.0f / frame.width * c.w, c.y + offset_px.y * 2.0f / frame.height * c.w, c.z, c.w};
}

/// Whether a clip position lies in front of the near plane (z >= -w) with a positive w.
bool in_front(const glm::vec4& c) { return c.w > 0.0f && c.z >= -c.w; }

}  // namespace

ExpandedPrimitives lines_as_rectangles(const std::vector<glm::vec4>& clip, const std::vector<glm::vec2>& uvs,
                                       const std::vector<std::uint32_t>& segments, float width_px, FramePixels frame) {
  ExpandedPrimitives out;
  const float half = 0.5f * width_px;
  for (std::size_t s = 0; s + 1 < segments.size(); s += 2) {
    glm::vec4 a = clip[segments[s]], b = clip[segments[s + 1]];
    glm::vec2 ua = uvs.empty() ? glm::vec2(0) : uvs[segments[s]], ub = uvs.empty() ? glm::vec2(0) : uvs[segments[s + 1]];
    // Near-plane clip: the distance z + w is linear along the segment in clip space.
    const float da = a.z + a.w, db = b.z + b.w;
    if (da < 0.0f && db < 0.0f) {
      ++out.dropped;
      continue;
    }
    if (da < 0.0f || db < 0.0f) {
      const float t = da / (da - db);
      const glm::vec4 p = a + t * (b - a);
      const glm::vec2 up = ua + t * (ub - ua);
      if (da < 0.0f) {
        a = p;
        ua = up;
      } else {
        b = p;
        ub = up;
      }
    }
    if (!in_front(a) || !in_front(b)) {
      ++out.dropped;
      continue;
    }
    // The segment on screen, in pixels, and the unit normal to it.
    const glm::vec2 pa(a.x / a.w * 0.5f * frame.width, a.y / a.w * 0.5f * frame.height);
    const glm::vec2 pb(b.x / b.w * 0.5f * frame.width, b.y / b.w * 0.5f * frame.height);
    const glm::vec2 d = pb - pa;
    const float len = std::sqrt(d.x * d.x + d.y * d.y);
    if (!(len > 0.0f)) {
      ++out.dropped;
      continue;
    }
    const glm::vec2 n = glm::vec2(-d.y, d.x) / len * half;
    const auto base = static_cast<std::uint32_t>(out.clip.size());
    out.clip.insert(out.clip.end(), {moved(a, n, frame), moved(a, -n, frame), moved(b, -n, frame), moved(b, n, frame)});
    if (!uvs.empty()) out.uvs.insert(out.uvs.end(), {ua, ua, ub, ub});
    push_quad(out, base, base + 1, base + 2, base + 3);
  }
  return out;
}

ExpandedPrimitives points_as_squares(const std::vector<glm::vec4>& clip, const std::vector<glm::vec2>& uvs,
                                     const std::vector<float>& sizes_px, const std::vector<std::uint32_t>& points,
                                     FramePixels frame) {
  ExpandedPrimitives out;
  for (std::uint32_t i : points) {
    const glm::vec4 c = clip[i];
    if (!in_front(c) || c.z > c.w) {
      ++out.dropped;
      continue;
    }
    const float half = 0.5f * (sizes_px.empty() ? 1.0f : sizes_px[i]);
    const auto base = static_cast<std::uint32_t>(out.clip.size());
    out.clip.insert(out.clip.end(), {moved(c, {-half, -half}, frame), moved(c, {half, -half}, frame),
                                     moved(c, {half, half}, frame), moved(c, {-half, half}, frame)});
    if (!uvs.empty()) out.uvs.insert(out.uvs.end(), 4, uvs[i]);
    push_quad(out, base, base + 1, base + 2, base + 3);
  }
  return out;
}

std::vector<std::uint32_t> instanced_indices(const std::vector<std::uint32_t>& indices, std::uint32_t per_instance,
                                             std::uint32_t instances) {
  std::vector<std::uint32_t> out;
  out.reserve(indices.size() * instances);
  for (std::uint32_t i = 0; i < instances; ++i) {
    for (std::uint32_t v : indices) out.push_back(v + i * per_instance);
  }
  return out;
}

}  // namespace tbdr
