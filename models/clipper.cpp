#include "models/clipper.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>

namespace tbdr {

namespace {

/// Smallest w kept by the w > 0 plane; never cuts after near clipping of ordinary projections.
constexpr double kMinClipW = 1e-7;

/// The planes a triangle may be clipped against, in clipping order.
enum class Plane : std::uint8_t { Near, Far, MinW, GuardRight, GuardLeft, GuardBottom, GuardTop };

double plane_distance(Plane plane, const glm::dvec4& p, double guard) {
  switch (plane) {
    case Plane::Near: return p.z + p.w;
    case Plane::Far: return p.w - p.z;
    case Plane::MinW: return p.w - kMinClipW;
    case Plane::GuardRight: return guard * p.w - p.x;
    case Plane::GuardLeft: return guard * p.w + p.x;
    case Plane::GuardBottom: return guard * p.w + p.y;  // y_ndc = -g is the bottom of the screen
    case Plane::GuardTop: return guard * p.w - p.y;
  }
  return 0.0;
}

/// Sutherland-Hodgman against one plane. Intersections are interpolated from the inside vertex
/// towards the outside one so that a shared edge clips identically in both of its triangles.
void clip_against(ClipPolygon& poly, Plane plane, double guard) {
  std::array<double, kMaxClipPolygonVertices> d{};
  bool any_out = false;
  for (int i = 0; i < poly.count; ++i) {
    d[i] = plane_distance(plane, poly.v[i].position, guard);
    any_out |= !(d[i] >= 0.0);
  }
  if (!any_out) return;
  poly.clipped = true;
  ClipPolygon out;
  out.clipped = true;
  auto push = [&out](const ClipVertex& v) {
    assert(out.count < kMaxClipPolygonVertices);
    if (out.count < kMaxClipPolygonVertices) out.v[out.count++] = v;
  };
  for (int i = 0; i < poly.count; ++i) {
    const int j = (i + 1) % poly.count;
    const bool in_i = d[i] >= 0.0, in_j = d[j] >= 0.0;
    if (in_i) push(poly.v[i]);
    if (in_i != in_j) {
      const int in = in_i ? i : j, o = in_i ? j : i;
      if (d[in] > 0.0) {  // an inside vertex exactly on the plane is its own intersection
        const double t = d[in] / (d[in] - d[o]);
        const ClipVertex& a = poly.v[in];
        const ClipVertex& b = poly.v[o];
        push({a.position + t * (b.position - a.position), a.bary + t * (b.bary - a.bary)});
      }
    }
  }
  poly = out;
}

bool finite(const glm::vec4& v) {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z) && std::isfinite(v.w);
}

/// Outcode: one bit per frustum plane the point is outside of.
unsigned outcode(const glm::dvec4& p) {
  unsigned c = 0;
  if (p.x < -p.w) c |= 1u;
  if (p.x > p.w) c |= 2u;
  if (p.y < -p.w) c |= 4u;
  if (p.y > p.w) c |= 8u;
  if (p.z < -p.w) c |= 16u;
  if (p.z > p.w) c |= 32u;
  return c;
}

/// Whether any clip plane clip_triangle uses has a vertex outside it (the common case is no).
bool needs_clipping(const ClipTriangle& clip, const ClipConfig& config) {
  const double guard = guard_band_ndc(config);
  const bool far = config.far_plane == FarPlaneMode::Clip;
  for (const glm::vec4& v : clip) {
    const glm::dvec4 p(v);
    const double gw = guard * p.w;
    if (!(p.z + p.w >= 0.0) || !(p.w - kMinClipW >= 0.0) || (far && !(p.w - p.z >= 0.0)) || !(gw - p.x >= 0.0) ||
        !(gw + p.x >= 0.0) || !(gw + p.y >= 0.0) || !(gw - p.y >= 0.0)) {
      return true;
    }
  }
  return false;
}

}  // namespace

const char* to_string(FaceCull m) {
  switch (m) {
    case FaceCull::None: return "none";
    case FaceCull::Back: return "back";
    case FaceCull::Front: return "front";
  }
  return "?";
}

const char* to_string(FarPlaneMode m) {
  switch (m) {
    case FarPlaneMode::Clip: return "clip";
    case FarPlaneMode::RejectOnly: return "reject";
  }
  return "?";
}

bool frustum_reject(const ClipTriangle& clip) {
  if (!finite(clip[0]) || !finite(clip[1]) || !finite(clip[2])) return true;
  return (outcode(glm::dvec4(clip[0])) & outcode(glm::dvec4(clip[1])) & outcode(glm::dvec4(clip[2]))) != 0;
}

double guard_band_ndc(const ClipConfig& config) {
  const Viewport& vp = config.viewport;
  const double extent_fixed = static_cast<double>(std::max(vp.width_px, vp.height_px)) *
                              static_cast<double>(vp.subpixel_scale());
  // (0.5 + 0.5*g) * extent_fixed <= kMaxFixedCoord, with one NDC unit of margin for rounding.
  const double g_max = std::floor(2.0 * static_cast<double>(kMaxFixedCoord) / extent_fixed) - 2.0;
  if (config.guard_band_ndc <= 0.0) return g_max;
  return std::max(1.0, std::min(config.guard_band_ndc, g_max));
}

ClipPolygon clip_triangle(const ClipTriangle& clip, const ClipConfig& config) {
  ClipPolygon poly;
  poly.count = 3;
  for (int i = 0; i < 3; ++i) {
    poly.v[i].position = glm::dvec4(clip[i]);
    poly.v[i].bary = glm::dvec3(0.0);
    poly.v[i].bary[i] = 1.0;
  }
  const double guard = guard_band_ndc(config);
  constexpr Plane kPlanes[] = {Plane::Near,       Plane::Far,       Plane::MinW,       Plane::GuardRight,
                               Plane::GuardLeft,  Plane::GuardBottom, Plane::GuardTop};
  for (Plane plane : kPlanes) {
    if (plane == Plane::Far && config.far_plane != FarPlaneMode::Clip) continue;
    clip_against(poly, plane, guard);
    if (poly.count < 3) {
      poly.count = 0;
      break;
    }
  }
  return poly;
}

namespace {
/// floor(v + 0.5) clamped to +-kMaxFixedCoord, without a libm call.
std::int32_t round_to_fixed(double v) {
  const double limit = static_cast<double>(kMaxFixedCoord);
  v = v + 0.5;
  if (!(v > -limit)) return static_cast<std::int32_t>(-kMaxFixedCoord);
  if (!(v < limit)) return static_cast<std::int32_t>(kMaxFixedCoord);
  std::int64_t i = static_cast<std::int64_t>(v);  // truncates towards zero
  if (static_cast<double>(i) > v) --i;
  return static_cast<std::int32_t>(i);
}
}  // namespace

ScreenVertex viewport_transform(const glm::dvec4& clip, const Viewport& viewport, bool clamp_depth_01) {
  const double inv_w = 1.0 / clip.w;
  const double x_ndc = clip.x * inv_w;
  const double y_ndc = clip.y * inv_w;
  const double z_ndc = clip.z * inv_w;
  const double scale = static_cast<double>(viewport.subpixel_scale());
  ScreenVertex v;
  v.x_fixed = round_to_fixed((x_ndc * 0.5 + 0.5) * viewport.width_px * scale);
  v.y_fixed = round_to_fixed((0.5 - y_ndc * 0.5) * viewport.height_px * scale);
  double z = z_ndc * 0.5 + 0.5;
  z = z > 0.0 ? z : 0.0;
  if (clamp_depth_01 && z > 1.0) z = 1.0;
  v.z = static_cast<float>(z);
  v.inv_w = static_cast<float>(inv_w);
  return v;
}

int clip_and_cull(const ClipTriangle& clip, const ClipConfig& config, ClipStats& stats,
                  std::vector<ScreenTriangle>& out) {
  validate_viewport(config.viewport);
  ++stats.in;
  if (frustum_reject(clip)) {
    ++stats.culled_frustum;
    return 0;
  }
  ClipPolygon poly;
  if (needs_clipping(clip, config)) {
    poly = clip_triangle(clip, config);
  } else {
    poly.count = 3;
    for (int i = 0; i < 3; ++i) {
      poly.v[i].position = glm::dvec4(clip[i]);
      poly.v[i].bary[i] = 1.0;
    }
  }
  if (poly.clipped) ++stats.clipped;
  if (poly.count < 3) {
    ++stats.culled_frustum;
    return 0;
  }
  const int n = poly.count;
  if (poly.clipped) {
    // What is left in front of the eye may lie wholly outside a side (or the far) plane even
    // though the original vertices behind the eye did not.
    unsigned all = ~0u;
    for (int i = 0; i < n; ++i) all &= outcode(poly.v[i].position);
    if (all != 0) {
      ++stats.culled_frustum;
      return 0;
    }
  }
  const bool clamp_depth = config.far_plane == FarPlaneMode::Clip;
  std::array<ScreenVertex, kMaxClipPolygonVertices> sv;
  for (int i = 0; i < n; ++i) sv[i] = viewport_transform(poly.v[i].position, config.viewport, clamp_depth);

  // Exact fixed-point areas of the fan pieces; their sum is the polygon's area.
  std::array<std::int64_t, kMaxClipPolygonVertices> piece_area{};
  std::int64_t total = 0;
  for (int j = 1; j + 1 < n; ++j) {
    piece_area[j] = signed_area_x2(sv[0].x_fixed, sv[0].y_fixed, sv[j].x_fixed, sv[j].y_fixed, sv[j + 1].x_fixed,
                                   sv[j + 1].y_fixed);
    total += piece_area[j];
  }
  if (total == 0) {
    ++stats.culled_zero_area;
    return 0;
  }
  const bool front = config.front_ccw ? total < 0 : total > 0;
  if ((config.cull == FaceCull::Back && !front) || (config.cull == FaceCull::Front && front)) {
    ++stats.culled_backface;
    return 0;
  }
  int emitted = 0;
  for (int j = 1; j + 1 < n; ++j) {
    // Pieces that snapped to nothing or folded over (slivers of a clipped polygon) cover no area.
    if (piece_area[j] == 0 || (piece_area[j] < 0) != (total < 0)) continue;
    ScreenTriangle t;
    const int idx[3] = {0, j, j + 1};
    for (int k = 0; k < 3; ++k) {
      const ScreenVertex& v = sv[idx[k]];
      t.x_fixed[k] = v.x_fixed;
      t.y_fixed[k] = v.y_fixed;
      t.z[k] = v.z;
      t.inv_w[k] = v.inv_w;
      t.bary[k] = glm::vec3(poly.v[idx[k]].bary);
    }
    t.front_facing = front;
    out.push_back(t);
    ++emitted;
  }
  stats.out += static_cast<std::uint64_t>(emitted);
  return emitted;
}

}  // namespace tbdr
