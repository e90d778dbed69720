#pragma once
// The functional rasteriser of the ISP: fixed-point triangle setup with the top-left fill rule,
// the standard MSAA sample positions, coverage and depth per pixel inside a rectangle (a tile),
// perspective-correct barycentrics relative to the original (pre-clip) triangle, and the
// triangle/tile overlap tests the tiler bins with. Pure functions, exact integer coverage.
//
// Conventions (shared with models/clipper.hpp):
// - Screen space is y down: pixel (0,0) is the top-left pixel of the image, as in image files.
//   Pixel (px,py) covers [px,px+1) x [py,py+1); a sample sits at (px + sx, py + sy) with the
//   sample offset (sx,sy) in [0,1) taken from the standard D3D/Vulkan patterns.
// - Positions are fixed point with `subpixel_bits` fractional bits (PowerVR: 8), so a sample
//   position is an exact integer and edge functions are exact in int64: no cracks, no double hits.
//   Vertex coordinates must lie within +-kMaxFixedCoord (the clipper's guard band ensures it).
// - Winding: the signed area A2 = (x1-x0)*(y2-y0) - (x2-x0)*(y1-y0) is computed in these y-down
//   coordinates. A triangle that is counter-clockwise in GL window space (y up) has A2 < 0 here;
//   on the screen as displayed it still looks counter-clockwise. Setup reorders the vertices so
//   that A2 > 0 (visually clockwise on the y-down screen), and then each edge function is positive
//   on the triangle's inside.
// - Fill rule (top-left, as in D3D and GL): with that orientation, the edge from P to Q (dx, dy)
//   is a top edge when dy == 0 and dx > 0 (horizontal, inside below it), a left edge when dy < 0
//   (inside to its right). A sample exactly on a top or left edge is inside; exactly on a bottom
//   or right edge it is outside. A sample on a vertex is inside only when both edges meeting there
//   are top/left edges.
// - Depth is the screen-space plane of the vertices' z (window depth, [0,1] after the clipper),
//   evaluated in double from the exact integer edge values at the pixel's corner plus a per-sample
//   offset, rounded once to float (depth_at_sample): the same sample always gets the same depth
//   whatever rectangle or traversal order reached it, and a sample on a vertex gets that vertex's
//   z (the double error is far below half a float ulp).
#include <algorithm>
#include <array>
#include <bit>
#include <cassert>
#include <cstdint>
#include <limits>
#include <vector>

#include <glm/glm.hpp>

#include "kernel/bits.hpp"

namespace tbdr {

/// Largest number of samples per pixel supported (standard 16x pattern).
inline constexpr int kMaxSamplesPerPixel = 16;
/// Largest magnitude of a fixed-point vertex coordinate; keeps every edge product exact in int64.
inline constexpr std::int64_t kMaxFixedCoord = std::int64_t{1} << 28;

/// The render target's extent in pixels and the rasteriser's sub-pixel precision.
struct Viewport {
  int width_px = 0;
  int height_px = 0;
  int subpixel_bits = 8;  ///< fractional bits of screen coordinates (PowerVR: 8)
  std::int64_t subpixel_scale() const { return std::int64_t{1} << subpixel_bits; }
};
/// Throws std::invalid_argument unless the size is positive, bits in [1,16] and the viewport in
/// fixed point leaves room for a guard band of at least 4 viewports on each side.
void validate_viewport(const Viewport& viewport);

/// A triangle after clipping, viewport transform and culling: what the parameter buffer holds.
struct ScreenTriangle {
  std::array<std::int32_t, 3> x_fixed{};  ///< screen x, sub-pixel fixed point, y-down convention
  std::array<std::int32_t, 3> y_fixed{};  ///< screen y, sub-pixel fixed point, row 0 at the top
  std::array<float, 3> z{};               ///< window depth, [0,1] (GL: z_ndc*0.5+0.5)
  std::array<float, 3> inv_w{};           ///< 1/w_clip, for perspective-correct interpolation
  /// Weights of this vertex relative to the ORIGINAL (pre-clip) triangle's three vertices:
  /// (1,0,0), (0,1,0), (0,0,1) for an unclipped triangle.
  std::array<glm::vec3, 3> bary{glm::vec3{1, 0, 0}, glm::vec3{0, 1, 0}, glm::vec3{0, 0, 1}};
  bool front_facing = true;               ///< per the clipper's front-face winding
};

/// Twice the signed area in fixed point (y-down): > 0 visually clockwise, < 0 counter-clockwise.
inline std::int64_t signed_area_x2(std::int64_t x0, std::int64_t y0, std::int64_t x1, std::int64_t y1,
                                   std::int64_t x2, std::int64_t y2) {
  return (x1 - x0) * (y2 - y0) - (x2 - x0) * (y1 - y0);
}

/// A rectangle of pixels, half-open: [x0,x1) x [y0,y1).
struct PixelRect {
  int x0 = 0;
  int y0 = 0;
  int x1 = 0;
  int y1 = 0;
  bool empty() const { return x0 >= x1 || y0 >= y1; }
  int width() const { return x1 - x0; }
  int height() const { return y1 - y0; }
  friend bool operator==(const PixelRect&, const PixelRect&) = default;
};
/// The overlap of two rectangles (possibly empty).
inline PixelRect intersect(const PixelRect& a, const PixelRect& b) {
  return {a.x0 > b.x0 ? a.x0 : b.x0, a.y0 > b.y0 ? a.y0 : b.y0, a.x1 < b.x1 ? a.x1 : b.x1,
          a.y1 < b.y1 ? a.y1 : b.y1};
}

/// Sample positions of one MSAA mode: offsets from the pixel's top-left corner, sub-pixel units.
struct SamplePattern {
  int count = 1;
  int subpixel_bits = 8;
  std::array<std::int32_t, kMaxSamplesPerPixel> dx{};  ///< in [0, 2^subpixel_bits)
  std::array<std::int32_t, kMaxSamplesPerPixel> dy{};
  std::uint32_t full_mask() const { return count >= 32 ? ~0u : ((1u << count) - 1u); }
};
/// The D3D/Vulkan standard sample positions for 1, 2, 4, 8 or 16 samples per pixel
/// (1x: (0.5,0.5); 2x: (0.75,0.75),(0.25,0.25); 4x: (0.375,0.125),(0.875,0.375),
/// (0.125,0.625),(0.625,0.875); 8x and 16x on the 1/16 grid). Throws std::invalid_argument for
/// another count, or when subpixel_bits cannot hold the positions exactly (1x needs 1 bit,
/// 2x 2, 4x 3, 8x and 16x 4) or exceeds 16.
SamplePattern standard_sample_pattern(int samples, int subpixel_bits = 8);

/// Per-triangle state of the rasteriser: edge equations with the fill-rule bias, depth plane,
/// pixel bounding box clipped to the viewport and the draw's scissor rectangle. Vertices are
/// reordered to positive area. Every binned primitive holds one (Primitive::setup), so it keeps
/// only what the coverage, depth and interpolation formulas read (184 bytes; the vertices' fixed
/// point positions are folded into the edge equations, the viewport into the bounding box).
struct TriangleSetup {
  /// Edge k is opposite vertex k: E_k(X,Y) = a[k]*X + b[k]*Y + c[k], = area_x2 at vertex k,
  /// 0 on the edge; barycentric weight of vertex k is E_k / area_x2.
  std::array<std::int64_t, 3> a{}, b{}, c{};
  std::int64_t area_x2 = 0;     ///< twice the area, > 0 after reordering
  double dz1 = 0.0;  ///< (z1 - z0) / area_x2
  double dz2 = 0.0;  ///< (z2 - z0) / area_x2
  /// Pixels that may hold a covered sample, inside the viewport and the scissor rectangle: every
  /// coverage test (rasterize_in_rect, covers_any_sample, the tiler's binning) stays inside it,
  /// so the scissor test (Vulkan: samples outside the rectangle are discarded) happens here once.
  PixelRect bbox;
  std::array<float, 3> z{};
  std::array<float, 3> inv_w{};
  std::array<glm::vec3, 3> bary{};
  int subpixel_bits = 8;
  /// 0 for a top/left edge, -1 otherwise: a sample is covered iff E_k + bias[k] >= 0 for all k.
  std::array<std::int8_t, 3> bias{};
  bool empty = true;            ///< zero area, or no pixel of the viewport (and scissor) can be covered
  bool front_facing = true;
};

/// Setup of one screen triangle for the given viewport (degenerate triangles come out empty).
TriangleSetup setup_triangle(const ScreenTriangle& tri, const Viewport& viewport);
/// The same with a scissor rectangle (pixels, half-open; clamped to the viewport): the bounding
/// box is cut to it, and a triangle with no pixel inside it comes out empty.
TriangleSetup setup_triangle(const ScreenTriangle& tri, const Viewport& viewport, const PixelRect& scissor);

/// The fixed-point position of sample `s` of pixel (px, py).
inline glm::i64vec2 sample_position_fixed(const SamplePattern& pattern, int px, int py, int s) {
  return {(std::int64_t{px} << pattern.subpixel_bits) + pattern.dx[s],
          (std::int64_t{py} << pattern.subpixel_bits) + pattern.dy[s]};
}

/// Raw edge value E_k at a fixed-point position (no fill-rule bias).
inline std::int64_t edge_value(const TriangleSetup& t, int k, std::int64_t x_fixed, std::int64_t y_fixed) {
  return t.a[k] * x_fixed + t.b[k] * y_fixed + t.c[k];
}

/// Whether the sample at fixed-point (X,Y) is covered, by the top-left rule (ignores the viewport).
inline bool covers_point(const TriangleSetup& t, std::int64_t x_fixed, std::int64_t y_fixed) {
  if (t.area_x2 <= 0) return false;
  return ((edge_value(t, 0, x_fixed, y_fixed) + t.bias[0]) | (edge_value(t, 1, x_fixed, y_fixed) + t.bias[1]) |
          (edge_value(t, 2, x_fixed, y_fixed) + t.bias[2])) >= 0;
}

/// Depth of the triangle's plane at a pixel's top-left corner, from the raw edge values E1, E2
/// there (double; the first half of the one depth formula every path uses).
inline double depth_at_corner(const TriangleSetup& t, std::int64_t e1, std::int64_t e2) {
  return static_cast<double>(t.z[0]) + static_cast<double>(e1) * t.dz1 + static_cast<double>(e2) * t.dz2;
}
/// Depth change from a pixel's corner to a sample at sub-pixel offset (dx, dy) (second half).
inline double depth_sample_offset(const TriangleSetup& t, std::int32_t dx, std::int32_t dy) {
  const std::int64_t e1 = t.a[1] * dx + t.b[1] * dy;
  const std::int64_t e2 = t.a[2] * dx + t.b[2] * dy;
  return static_cast<double>(e1) * t.dz1 + static_cast<double>(e2) * t.dz2;
}
/// Depth of the triangle's plane at sample s of pixel (px, py): float(corner + offset), exactly
/// what rasterize_in_rect reports for that sample, whatever rectangle or order reached it.
inline float depth_at_sample(const TriangleSetup& t, const SamplePattern& pattern, int px, int py, int s) {
  const std::int64_t cx = std::int64_t{px} << t.subpixel_bits, cy = std::int64_t{py} << t.subpixel_bits;
  return static_cast<float>(depth_at_corner(t, edge_value(t, 1, cx, cy), edge_value(t, 2, cx, cy)) +
                            depth_sample_offset(t, pattern.dx[s], pattern.dy[s]));
}

/// Linear screen-space barycentrics of the setup's (reordered) vertices at fixed-point (X,Y).
glm::dvec3 screen_barycentrics(const TriangleSetup& t, std::int64_t x_fixed, std::int64_t y_fixed);
/// Perspective-correct barycentric weights relative to the ORIGINAL (pre-clip) triangle's
/// vertices at fixed-point (X,Y): interpolate any vertex attribute of the original triangle
/// with them (position, normal, uv). They sum to 1.
glm::vec3 perspective_barycentrics(const TriangleSetup& t, std::int64_t x_fixed, std::int64_t y_fixed);

namespace detail {
/// Narrows [lo,hi) to the n with base + step*n >= 0 (exact integer arithmetic).
inline void narrow_span(std::int64_t base, std::int64_t step, std::int64_t& lo, std::int64_t& hi) {
  if (step > 0) {
    if (base < 0) {
      const std::int64_t n_min = (-base + step - 1) / step;
      if (n_min > lo) lo = n_min;
    }
  } else if (step < 0) {
    if (base < 0) {
      hi = lo;
    } else {
      const std::int64_t n_max = base / -step;
      if (n_max + 1 < hi) hi = n_max + 1;
    }
  } else if (base < 0) {
    hi = lo;
  }
}

/// The edge functions of a triangle walked over a rectangle row by row: for each row, the span
/// of pixels where each edge holds for at least one sample and, inside it, the span where every
/// edge holds for every sample (exact integer arithmetic). rasterize_rect_n and count_rect_n read
/// coverage only through it, so what one visits the other counts.
template <int N>
struct EdgeWalk {
  std::int64_t step_x[3], step_y[3], row[3], max_off[3], min_off[3];
  std::int64_t off[3][N];
  std::int64_t width;

  EdgeWalk(const TriangleSetup& t, const PixelRect& r, const SamplePattern& p) : width(r.x1 - r.x0) {
    const int bits = t.subpixel_bits;
    for (int k = 0; k < 3; ++k) {
      step_x[k] = t.a[k] << bits;
      step_y[k] = t.b[k] << bits;
      // Biased edge value at the top-left corner of pixel (r.x0, r.y0).
      row[k] = t.a[k] * (std::int64_t{r.x0} << bits) + t.b[k] * (std::int64_t{r.y0} << bits) + t.c[k] + t.bias[k];
      max_off[k] = std::numeric_limits<std::int64_t>::min();
      min_off[k] = std::numeric_limits<std::int64_t>::max();
      for (int s = 0; s < N; ++s) {
        off[k][s] = t.a[k] * p.dx[s] + t.b[k] * p.dy[s];
        if (off[k][s] > max_off[k]) max_off[k] = off[k][s];
        if (off[k][s] < min_off[k]) min_off[k] = off[k][s];
      }
    }
  }
  /// The current row's pixels [lo,hi) (offsets from the rectangle's x0) with at least one covered
  /// sample (exact for 1x), and [full_lo,full_hi) inside it where every sample is covered (empty:
  /// full_lo == full_hi == hi). False when the row has no covered sample.
  /// (Always inlined, as the other steps: a translation unit as large as the ISP's exhausts GCC's
  /// inlining budget, and a call per row measured 3 % of a 1080p run.)
  [[gnu::always_inline]] bool span(std::int64_t& lo, std::int64_t& hi, std::int64_t& full_lo, std::int64_t& full_hi) const {
    lo = 0;
    hi = width;
    for (int k = 0; k < 3 && lo < hi; ++k) narrow_span(row[k] + max_off[k], step_x[k], lo, hi);
    if (lo >= hi) return false;
    full_lo = lo;
    full_hi = hi;
    if constexpr (N > 1) {
      for (int k = 0; k < 3 && full_lo < full_hi; ++k) narrow_span(row[k] + min_off[k], step_x[k], full_lo, full_hi);
      if (full_lo >= full_hi) full_lo = full_hi = hi;
    }
    return true;
  }
  /// Biased edge value k at the corner of pixel n of the current row.
  [[gnu::always_inline]] std::int64_t edge_at(int k, std::int64_t n) const { return row[k] + step_x[k] * n; }
  /// Covered samples of a pixel whose corner edge values are e0, e1, e2.
  [[gnu::always_inline]] std::uint32_t mask(std::int64_t e0, std::int64_t e1, std::int64_t e2) const {
    std::uint32_t m = 0;
    for (int s = 0; s < N; ++s) {
      if (((e0 + off[0][s]) | (e1 + off[1][s]) | (e2 + off[2][s])) >= 0) m |= 1u << s;
    }
    return m;
  }
  [[gnu::always_inline]] void next_row() {
    for (int k = 0; k < 3; ++k) row[k] += step_y[k];
  }
};

template <int N, class Fn>
void rasterize_rect_n(const TriangleSetup& t, const PixelRect& r, const SamplePattern& p, Fn& fn) {
  EdgeWalk<N> walk(t, r, p);
  double z_off[N];
  for (int s = 0; s < N; ++s) z_off[s] = depth_sample_offset(t, p.dx[s], p.dy[s]);
  const std::uint32_t full = N >= 32 ? ~0u : ((1u << N) - 1u);
  float depth[N];
  for (int py = r.y0; py < r.y1; ++py, walk.next_row()) {
    std::int64_t lo, hi, full_lo, full_hi;
    if (!walk.span(lo, hi, full_lo, full_hi)) continue;
    std::int64_t e0 = walk.edge_at(0, lo), e1 = walk.edge_at(1, lo), e2 = walk.edge_at(2, lo);
    for (std::int64_t n = lo; n < hi; ++n) {
      const double z_corner = depth_at_corner(t, e1 - t.bias[1], e2 - t.bias[2]);
      std::uint32_t mask = 0;
      if (N == 1 || (n >= full_lo && n < full_hi)) {
        mask = full;
        for (int s = 0; s < N; ++s) depth[s] = static_cast<float>(z_corner + z_off[s]);
      } else {
        mask = walk.mask(e0, e1, e2);
        for (std::uint32_t m = mask; m != 0; m &= m - 1) {
          const int s = std::countr_zero(m);
          depth[s] = static_cast<float>(z_corner + z_off[s]);
        }
      }
      if (mask != 0) fn(r.x0 + static_cast<int>(n), py, mask, static_cast<const float*>(depth));
      e0 += walk.step_x[0];
      e1 += walk.step_x[1];
      e2 += walk.step_x[2];
    }
  }
}

/// The samples rasterize_rect_n<N> would report, counted span by span (no depth, no visit).
template <int N>
std::uint64_t count_rect_n(const TriangleSetup& t, const PixelRect& r, const SamplePattern& p) {
  EdgeWalk<N> walk(t, r, p);
  std::uint64_t samples = 0;
  for (int py = r.y0; py < r.y1; ++py, walk.next_row()) {
    std::int64_t lo, hi, full_lo, full_hi;
    if (!walk.span(lo, hi, full_lo, full_hi)) continue;
    if constexpr (N == 1) {
      samples += static_cast<std::uint64_t>(hi - lo);
    } else {
      samples += static_cast<std::uint64_t>(full_hi - full_lo) * N;
      for (std::int64_t n = lo; n < hi; ++n) {
        if (n == full_lo) n = full_hi;  // skip the fully covered pixels, counted above
        if (n >= hi) break;
        samples += bit_count(walk.mask(walk.edge_at(0, n), walk.edge_at(1, n), walk.edge_at(2, n)));
      }
    }
  }
  return samples;
}
}  // namespace detail

/// Visits every pixel of `rect` (clipped to the triangle's bounding box and the viewport) that has
/// at least one covered sample, calling fn(int x, int y, uint32_t coverage_mask,
/// const float* depth) with bit s of the mask set when sample s is covered and depth[s] the
/// triangle's depth at sample s (defined only for covered samples). Rows top to bottom, pixels
/// left to right. `pattern.subpixel_bits` must equal the setup's.
template <class Fn>
void rasterize_in_rect(const TriangleSetup& tri, const PixelRect& rect, const SamplePattern& pattern, Fn&& fn) {
  if (tri.empty) return;
  assert(pattern.subpixel_bits == tri.subpixel_bits);
  const PixelRect r = intersect(rect, tri.bbox);
  if (r.empty()) return;
  switch (pattern.count) {
    case 1: detail::rasterize_rect_n<1>(tri, r, pattern, fn); break;
    case 2: detail::rasterize_rect_n<2>(tri, r, pattern, fn); break;
    case 4: detail::rasterize_rect_n<4>(tri, r, pattern, fn); break;
    case 8: detail::rasterize_rect_n<8>(tri, r, pattern, fn); break;
    case 16: detail::rasterize_rect_n<16>(tri, r, pattern, fn); break;
    default: assert(false && "unsupported sample count"); break;
  }
}

/// Longest run of pixels rasterize_spans_1x reports at once (its depth buffer on the stack).
inline constexpr int kSpanPixels = 64;

/// One sample per pixel, row by row: calls fn(int y, int x_begin, int x_end, const float* depth)
/// for the covered pixels [x_begin, x_end) of each row of `rect` (clipped to the triangle's box),
/// depth[i] being pixel x_begin + i's depth: the pixels, depths and order rasterize_in_rect
/// reports one by one (the same edge walk and depth formula), a row's run in pieces of at most
/// kSpanPixels. For loops that read a row's pixels together (the ISP's depth test). Requires
/// pattern.count == 1.
template <class Fn>
void rasterize_spans_1x(const TriangleSetup& tri, const PixelRect& rect, const SamplePattern& pattern, Fn&& fn) {
  if (tri.empty) return;
  assert(pattern.count == 1 && pattern.subpixel_bits == tri.subpixel_bits);
  const PixelRect r = intersect(rect, tri.bbox);
  if (r.empty()) return;
  detail::EdgeWalk<1> walk(tri, r, pattern);
  const double z_off = depth_sample_offset(tri, pattern.dx[0], pattern.dy[0]);
  float depth[kSpanPixels];
  for (int py = r.y0; py < r.y1; ++py, walk.next_row()) {
    std::int64_t lo, hi, full_lo, full_hi;
    if (!walk.span(lo, hi, full_lo, full_hi)) continue;
    for (std::int64_t a = lo; a < hi; a += kSpanPixels) {
      const std::int64_t n = std::min<std::int64_t>(hi - a, kSpanPixels);
      // Exact integer edge values, so pixel k's are those rasterize_rect_n reaches by stepping.
      std::int64_t e1 = walk.edge_at(1, a) - tri.bias[1], e2 = walk.edge_at(2, a) - tri.bias[2];
      for (std::int64_t k = 0; k < n; ++k) {
        depth[k] = static_cast<float>(depth_at_corner(tri, e1, e2) + z_off);
        e1 += walk.step_x[1];
        e2 += walk.step_x[2];
      }
      fn(py, r.x0 + static_cast<int>(a), r.x0 + static_cast<int>(a + n), static_cast<const float*>(depth));
    }
  }
}

/// The number of samples rasterize_in_rect(tri, rect, pattern, ...) would report (the sum of
/// its masks' popcounts), found span by span without visiting pixels.
std::uint64_t covered_samples(const TriangleSetup& tri, const PixelRect& rect, const SamplePattern& pattern);

/// Bounds of the depth rasterize_in_rect reports for any sample inside `rect`: every reported
/// depth d has lo <= d <= hi (the plane's extremes over the rectangle's sample positions, widened
/// by far more than the double rounding of the per-sample formula, then rounded to float, which
/// keeps the order). NaN bounds when the plane is not finite; only meaningful for a triangle
/// that is not empty.
struct SampleDepthBounds {
  float lo = 0;
  float hi = 0;
};
SampleDepthBounds depth_bounds_in_rect(const TriangleSetup& tri, const PixelRect& rect, const SamplePattern& pattern);

/// Whether the triangle covers at least one sample of `pattern` inside `rect` (clipped to the
/// viewport): exact w.r.t. sample coverage and the fill rule, i.e. true iff rasterize_in_rect
/// would visit a pixel. Cheap corner tests accept or reject most rectangles; only rectangles a
/// triangle edge crosses fall back to exact per-row span tests.
bool covers_any_sample(const TriangleSetup& tri, const PixelRect& rect, const SamplePattern& pattern);

/// How the tiler decides that a triangle touches a tile.
enum class TileTest : std::uint8_t {
  BoundingBox,  ///< the tile overlaps the triangle's pixel bounding box (conservative)
  Exact,        ///< the triangle covers at least one sample inside the tile (covers_any_sample)
};
const char* to_string(TileTest t);

/// A tile's column and row in the tile grid (tile (0,0) at the top-left of the viewport).
struct TileCoord {
  int tx = 0;
  int ty = 0;
  friend bool operator==(const TileCoord&, const TileCoord&) = default;
};

/// The pixels of tile (tx,ty) for the given tile size that the triangle's bounding box holds
/// (the bounding box lies in the viewport, so this is the tile clipped to the viewport as far as
/// any coverage test can tell).
inline PixelRect tile_rect(const TriangleSetup& tri, int tile_w_px, int tile_h_px, int tx, int ty) {
  return intersect({tx * tile_w_px, ty * tile_h_px, (tx + 1) * tile_w_px, (ty + 1) * tile_h_px}, tri.bbox);
}

/// Calls fn(tx, ty) for every tile the triangle touches per `test`, row by row.
template <class Fn>
void for_each_overlapped_tile(const TriangleSetup& tri, int tile_w_px, int tile_h_px, TileTest test,
                              const SamplePattern& pattern, Fn&& fn) {
  if (tri.empty) return;
  assert(tile_w_px > 0 && tile_h_px > 0);
  const int tx0 = tri.bbox.x0 / tile_w_px, tx1 = (tri.bbox.x1 - 1) / tile_w_px;
  const int ty0 = tri.bbox.y0 / tile_h_px, ty1 = (tri.bbox.y1 - 1) / tile_h_px;
  for (int ty = ty0; ty <= ty1; ++ty) {
    for (int tx = tx0; tx <= tx1; ++tx) {
      if (test == TileTest::BoundingBox ||
          covers_any_sample(tri, tile_rect(tri, tile_w_px, tile_h_px, tx, ty), pattern)) {
        fn(tx, ty);
      }
    }
  }
}
/// The tiles the triangle touches per `test`, row by row.
std::vector<TileCoord> overlapped_tiles(const TriangleSetup& tri, int tile_w_px, int tile_h_px, TileTest test,
                                        const SamplePattern& pattern);
/// How many tiles the triangle touches per `test`.
int count_overlapped_tiles(const TriangleSetup& tri, int tile_w_px, int tile_h_px, TileTest test,
                           const SamplePattern& pattern);

}  // namespace tbdr
