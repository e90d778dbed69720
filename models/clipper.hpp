#pragma once
// The fixed-function back end of the geometry unit: trivial frustum rejection, clipping in
// homogeneous clip space, viewport transform to sub-pixel fixed point, back-face and zero-area
// culling. Pure functions; the caller keeps the counters and charges the timing.
//
// Conventions (see also models/rasterizer.hpp):
// - Input is clip space in the OpenGL convention: a point is visible when -w <= x, y, z <= w.
// - Trivial rejection: a triangle whose three vertices lie outside the same one of the six
//   frustum planes is culled ("frustum").
// - Clipping: always against the near plane z >= -w (and a tiny w > 0 plane, which never cuts
//   after near clipping with an ordinary perspective or orthographic projection). The far plane
//   z <= w is clipped in FarPlaneMode::Clip (default, GL behaviour); in FarPlaneMode::RejectOnly
//   only the trivial rejection applies, so a triangle crossing the far plane is kept whole and
//   its samples beyond it get window depth > 1 (a depth test against a cleared 1.0 drops them).
//   The side planes are not clipped: the rasteriser scissors to the viewport; only a triangle
//   reaching beyond the guard band (|x| or |y| > g*w) is clipped against the guard band so that
//   its fixed-point coordinates stay exact. The intersection of an edge with a plane is always
//   computed from its inside vertex towards its outside vertex, so two triangles sharing an edge
//   get bit-identical clipped vertices (no cracks along clipped edges).
// - The clipped convex polygon (3..10 vertices) is fanned from its first vertex; every vertex
//   carries barycentric weights relative to the original triangle's three vertices.
// - Viewport transform, y down with row 0 at the top as in images:
//     x_fixed = round((x_ndc*0.5 + 0.5) * width  * 2^bits)
//     y_fixed = round((0.5 - y_ndc*0.5) * height * 2^bits)
//     z = z_ndc*0.5 + 0.5 (float, clamped to [0,1] when the far plane is clipped), inv_w = 1/w.
//   Rounding is to nearest, halves up (floor(v + 0.5)), computed in double.
// - Facing from the exact fixed-point signed area (summed over the fan for clipped polygons):
//   counter-clockwise in GL window space (y up), i.e. signed_area_x2 < 0 in our y-down
//   coordinates, is front-facing when front_ccw (GL default). Zero area is culled before facing.
#include <array>
#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "models/rasterizer.hpp"

namespace tbdr {

/// Which faces the fixed-function culling discards (double-sided materials use None); the
/// trace's pipeline FaceCull maps onto it.
enum class FaceCull : std::uint8_t { None, Back, Front };
const char* to_string(FaceCull m);

/// What happens to triangles that cross the far plane (see the header comment).
enum class FarPlaneMode : std::uint8_t {
  Clip,        ///< clip against z <= w like GL (default)
  RejectOnly,  ///< no far clipping; only triangles wholly beyond the far plane are culled
};
const char* to_string(FarPlaneMode m);

/// The geometry back end's fixed-function state for one draw.
struct ClipConfig {
  Viewport viewport;
  FaceCull cull = FaceCull::Back;
  bool front_ccw = true;                       ///< GL glFrontFace(GL_CCW)
  FarPlaneMode far_plane = FarPlaneMode::Clip;
  /// Guard band half-extent in NDC units (1 = the viewport itself): triangles reaching beyond
  /// |x|,|y| <= g*w are clipped there. 0 = the largest band the fixed-point range allows
  /// (about 1000 viewports at 1080p with 8 bits); larger requests are capped to it.
  double guard_band_ndc = 0.0;
};

/// Primitive counters of the geometry back end. Every input triangle ends in exactly one of
/// culled_frustum, culled_backface, culled_zero_area or accepted(); `clipped` counts input
/// triangles a clip plane actually cut (whether or not they were culled afterwards), `out` the
/// screen triangles emitted (a clipped triangle may give several).
struct ClipStats {
  std::uint64_t in = 0;
  std::uint64_t culled_frustum = 0;    ///< trivially rejected, or nothing left after clipping
  std::uint64_t culled_backface = 0;   ///< back (or front) facing per FaceCull
  std::uint64_t culled_zero_area = 0;  ///< zero signed area in fixed point (after snapping)
  std::uint64_t clipped = 0;
  std::uint64_t out = 0;
  std::uint64_t culled() const { return culled_frustum + culled_backface + culled_zero_area; }
  std::uint64_t accepted() const { return in - culled(); }
  friend bool operator==(const ClipStats&, const ClipStats&) = default;
};

/// A vertex during clipping: homogeneous clip-space position and weights of the original vertices.
struct ClipVertex {
  glm::dvec4 position{0.0};
  glm::dvec3 bary{0.0};
};

/// Most vertices a clipped triangle can have: 3 plus one per clip plane (near, far, w>0, 4 guard band).
inline constexpr int kMaxClipPolygonVertices = 10;

/// A convex polygon left after clipping one triangle, in the triangle's winding order.
struct ClipPolygon {
  std::array<ClipVertex, kMaxClipPolygonVertices> v{};
  int count = 0;
  bool clipped = false;  ///< some plane actually cut the triangle
};

/// The triangle's vertices in clip space (OpenGL convention).
using ClipTriangle = std::array<glm::vec4, 3>;

/// True when all three vertices are outside the same frustum plane (x, y, near, far), or a
/// coordinate is not finite. The far plane counts in both FarPlaneModes.
bool frustum_reject(const ClipTriangle& clip);

/// The guard band half-extent in NDC actually used for this config (see ClipConfig).
double guard_band_ndc(const ClipConfig& config);

/// Clips the triangle against the near plane, the far plane (FarPlaneMode::Clip), w > 0 and the
/// guard band; returns the polygon (count 0 when nothing is left). No trivial rejection here.
ClipPolygon clip_triangle(const ClipTriangle& clip, const ClipConfig& config);

/// One vertex after the viewport transform (see the header comment for the formulas).
struct ScreenVertex {
  std::int32_t x_fixed = 0;
  std::int32_t y_fixed = 0;
  float z = 0.0f;
  float inv_w = 0.0f;
};
/// Viewport transform of a clip-space position with w > 0; coordinates are clamped to
/// +-kMaxFixedCoord (only reachable when the guard band is bypassed).
ScreenVertex viewport_transform(const glm::dvec4& clip, const Viewport& viewport, bool clamp_depth_01 = true);

/// The whole back end for one triangle: rejection, clipping, viewport transform, zero-area and
/// facing culling. Appends 0..kMaxClipPolygonVertices-2 screen triangles to `out`, updates
/// `stats`, returns how many were appended. Throws std::invalid_argument on a bad viewport.
int clip_and_cull(const ClipTriangle& clip, const ClipConfig& config, ClipStats& stats,
                  std::vector<ScreenTriangle>& out);

}  // namespace tbdr
