#include "models/rasterizer.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>

namespace tbdr {

void validate_viewport(const Viewport& viewport) {
  if (viewport.width_px <= 0 || viewport.height_px <= 0) {
    throw std::invalid_argument("viewport size must be positive, got " + std::to_string(viewport.width_px) + "x" +
                                std::to_string(viewport.height_px));
  }
  if (viewport.subpixel_bits < 1 || viewport.subpixel_bits > 16) {
    throw std::invalid_argument("sub-pixel bits must be in [1,16], got " + std::to_string(viewport.subpixel_bits));
  }
  // A guard band of 4 viewports each side spans NDC [-9,9]: (0.5 + 0.5*9) * extent = 5 * extent.
  const std::int64_t extent = std::max(viewport.width_px, viewport.height_px);
  if (5 * (extent << viewport.subpixel_bits) > kMaxFixedCoord) {
    throw std::invalid_argument("viewport " + std::to_string(viewport.width_px) + "x" +
                                std::to_string(viewport.height_px) + " with " +
                                std::to_string(viewport.subpixel_bits) +
                                " sub-pixel bits exceeds the fixed-point range");
  }
}

SamplePattern standard_sample_pattern(int samples, int subpixel_bits) {
  // Positions on the 1/16 pixel grid from the pixel's top-left corner (D3D / Vulkan standard).
  static constexpr int kPos1[1][2] = {{8, 8}};
  static constexpr int kPos2[2][2] = {{12, 12}, {4, 4}};
  static constexpr int kPos4[4][2] = {{6, 2}, {14, 6}, {2, 10}, {10, 14}};
  static constexpr int kPos8[8][2] = {{9, 5}, {7, 11}, {13, 9}, {5, 3}, {3, 13}, {1, 7}, {11, 15}, {15, 1}};
  static constexpr int kPos16[16][2] = {{9, 9},  {7, 5},  {5, 10}, {12, 7}, {3, 6},  {10, 13}, {13, 11}, {11, 3},
                                        {6, 14}, {8, 1},  {4, 2},  {2, 12}, {0, 8},  {15, 4},  {14, 15}, {1, 0}};
  const int(*pos)[2] = nullptr;
  int min_bits = 0;
  switch (samples) {
    case 1: pos = kPos1; min_bits = 1; break;
    case 2: pos = kPos2; min_bits = 2; break;
    case 4: pos = kPos4; min_bits = 3; break;
    case 8: pos = kPos8; min_bits = 4; break;
    case 16: pos = kPos16; min_bits = 4; break;
    default:
      throw std::invalid_argument("unsupported sample count " + std::to_string(samples) +
                                  " (supported: 1, 2, 4, 8, 16)");
  }
  if (subpixel_bits < min_bits || subpixel_bits > 16) {
    throw std::invalid_argument(std::to_string(samples) + "x sample positions need " + std::to_string(min_bits) +
                                " to 16 sub-pixel bits, got " + std::to_string(subpixel_bits));
  }
  SamplePattern p;
  p.count = samples;
  p.subpixel_bits = subpixel_bits;
  for (int s = 0; s < samples; ++s) {
    // Exact: pos/16 * 2^bits, and 16 divides pos << bits whenever the position needs <= bits bits.
    p.dx[s] = static_cast<std::int32_t>((std::int64_t{pos[s][0]} << subpixel_bits) / 16);
    p.dy[s] = static_cast<std::int32_t>((std::int64_t{pos[s][1]} << subpixel_bits) / 16);
  }
  return p;
}

TriangleSetup setup_triangle(const ScreenTriangle& tri, const Viewport& viewport) {
  return setup_triangle(tri, viewport, PixelRect{0, 0, viewport.width_px, viewport.height_px});
}

TriangleSetup setup_triangle(const ScreenTriangle& tri, const Viewport& viewport, const PixelRect& scissor) {
  TriangleSetup t;
  t.subpixel_bits = viewport.subpixel_bits;
  t.front_facing = tri.front_facing;
  std::array<std::int32_t, 3> xf = tri.x_fixed, yf = tri.y_fixed;  // reordered below
  t.z = tri.z;
  t.inv_w = tri.inv_w;
  t.bary = tri.bary;
  std::int64_t area = signed_area_x2(xf[0], yf[0], xf[1], yf[1], xf[2], yf[2]);
  if (area == 0) return t;  // empty
  if (area < 0) {
    // Make the triangle visually clockwise on the y-down screen so every edge is positive inside.
    std::swap(xf[1], xf[2]);
    std::swap(yf[1], yf[2]);
    std::swap(t.z[1], t.z[2]);
    std::swap(t.inv_w[1], t.inv_w[2]);
    std::swap(t.bary[1], t.bary[2]);
    area = -area;
  }
  t.area_x2 = area;
  for (int k = 0; k < 3; ++k) {
    // Edge k runs from vertex k+1 to vertex k+2 (opposite vertex k).
    const std::int64_t px = xf[(k + 1) % 3], py = yf[(k + 1) % 3];
    const std::int64_t qx = xf[(k + 2) % 3], qy = yf[(k + 2) % 3];
    t.a[k] = py - qy;  // = -dy
    t.b[k] = qx - px;  // = dx
    t.c[k] = -(t.a[k] * px + t.b[k] * py);
    const bool left = t.a[k] > 0;                 // dy < 0: inside to the right
    const bool top = t.a[k] == 0 && t.b[k] > 0;   // horizontal, dx > 0: inside below
    t.bias[k] = static_cast<std::int8_t>((left || top) ? 0 : -1);
  }
  t.dz1 = (static_cast<double>(t.z[1]) - static_cast<double>(t.z[0])) / static_cast<double>(area);
  t.dz2 = (static_cast<double>(t.z[2]) - static_cast<double>(t.z[0])) / static_cast<double>(area);

  // Pixels whose samples (offsets in [0, 2^bits)) can fall in the vertices' bounding box.
  const int bits = t.subpixel_bits;
  const std::int64_t xmin = std::min({xf[0], xf[1], xf[2]});
  const std::int64_t xmax = std::max({xf[0], xf[1], xf[2]});
  const std::int64_t ymin = std::min({yf[0], yf[1], yf[2]});
  const std::int64_t ymax = std::max({yf[0], yf[1], yf[2]});
  // Inside the viewport and the scissor rectangle (itself clamped to the viewport by the max/min).
  const std::int64_t bx0 = std::max<std::int64_t>({xmin >> bits, 0, scissor.x0});
  const std::int64_t by0 = std::max<std::int64_t>({ymin >> bits, 0, scissor.y0});
  const std::int64_t bx1 = std::min<std::int64_t>({(xmax >> bits) + 1, viewport.width_px, scissor.x1});
  const std::int64_t by1 = std::min<std::int64_t>({(ymax >> bits) + 1, viewport.height_px, scissor.y1});
  if (bx0 >= bx1 || by0 >= by1) return t;  // outside the viewport or the scissor: empty
  t.bbox = {static_cast<int>(bx0), static_cast<int>(by0), static_cast<int>(bx1), static_cast<int>(by1)};
  t.empty = false;
  return t;
}

glm::dvec3 screen_barycentrics(const TriangleSetup& t, std::int64_t x_fixed, std::int64_t y_fixed) {
  if (t.area_x2 <= 0) return {1.0, 0.0, 0.0};
  const double inv_area = 1.0 / static_cast<double>(t.area_x2);
  const double l1 = static_cast<double>(edge_value(t, 1, x_fixed, y_fixed)) * inv_area;
  const double l2 = static_cast<double>(edge_value(t, 2, x_fixed, y_fixed)) * inv_area;
  return {1.0 - l1 - l2, l1, l2};
}

glm::vec3 perspective_barycentrics(const TriangleSetup& t, std::int64_t x_fixed, std::int64_t y_fixed) {
  const glm::dvec3 l = screen_barycentrics(t, x_fixed, y_fixed);
  // Screen-linear weights divided by w, renormalised: the clip-space (pre-projection) weights of
  // this triangle's vertices; those vertices are clip-space-linear blends of the original ones.
  const glm::dvec3 p{l.x * t.inv_w[0], l.y * t.inv_w[1], l.z * t.inv_w[2]};
  const double sum = p.x + p.y + p.z;
  const glm::dvec3 w = sum != 0.0 ? p / sum : l;
  const glm::dvec3 orig = w.x * glm::dvec3(t.bary[0]) + w.y * glm::dvec3(t.bary[1]) + w.z * glm::dvec3(t.bary[2]);
  return glm::vec3(orig);
}

bool covers_any_sample(const TriangleSetup& tri, const PixelRect& rect, const SamplePattern& pattern) {
  if (tri.empty) return false;
  assert(pattern.subpixel_bits == tri.subpixel_bits);
  const PixelRect r = intersect(rect, tri.bbox);
  if (r.empty()) return false;
  const int bits = tri.subpixel_bits;
  const int n = pattern.count;
  std::int64_t min_dx = pattern.dx[0], max_dx = pattern.dx[0], min_dy = pattern.dy[0], max_dy = pattern.dy[0];
  for (int s = 1; s < n; ++s) {
    min_dx = std::min<std::int64_t>(min_dx, pattern.dx[s]);
    max_dx = std::max<std::int64_t>(max_dx, pattern.dx[s]);
    min_dy = std::min<std::int64_t>(min_dy, pattern.dy[s]);
    max_dy = std::max<std::int64_t>(max_dy, pattern.dy[s]);
  }
  // Bounding box of the rectangle's sample positions.
  const std::int64_t x_lo = (std::int64_t{r.x0} << bits) + min_dx, x_hi = (std::int64_t{r.x1 - 1} << bits) + max_dx;
  const std::int64_t y_lo = (std::int64_t{r.y0} << bits) + min_dy, y_hi = (std::int64_t{r.y1 - 1} << bits) + max_dy;
  bool all_inside = true;
  for (int k = 0; k < 3; ++k) {
    const std::int64_t a = tri.a[k], b = tri.b[k], c = tri.c[k] + tri.bias[k];
    const std::int64_t e_max = a * (a > 0 ? x_hi : x_lo) + b * (b > 0 ? y_hi : y_lo) + c;
    if (e_max < 0) return false;  // the whole box is outside this edge
    const std::int64_t e_min = a * (a > 0 ? x_lo : x_hi) + b * (b > 0 ? y_lo : y_hi) + c;
    if (e_min < 0) all_inside = false;
  }
  if (all_inside) return true;  // the box holds samples and lies inside every edge
  // An edge crosses the box: exact test per sample row, solving each edge for its pixel span.
  const std::int64_t width = r.x1 - r.x0;
  std::int64_t step_x[3];
  for (int k = 0; k < 3; ++k) step_x[k] = tri.a[k] << bits;
  for (int py = r.y0; py < r.y1; ++py) {
    for (int s = 0; s < n; ++s) {
      const std::int64_t sx = (std::int64_t{r.x0} << bits) + pattern.dx[s];
      const std::int64_t sy = (std::int64_t{py} << bits) + pattern.dy[s];
      std::int64_t lo = 0, hi = width;
      for (int k = 0; k < 3 && lo < hi; ++k) {
        detail::narrow_span(tri.a[k] * sx + tri.b[k] * sy + tri.c[k] + tri.bias[k], step_x[k], lo, hi);
      }
      if (lo < hi) return true;
    }
  }
  return false;
}

std::uint64_t covered_samples(const TriangleSetup& tri, const PixelRect& rect, const SamplePattern& pattern) {
  if (tri.empty) return 0;
  assert(pattern.subpixel_bits == tri.subpixel_bits);
  const PixelRect r = intersect(rect, tri.bbox);
  if (r.empty()) return 0;
  switch (pattern.count) {
    case 1: return detail::count_rect_n<1>(tri, r, pattern);
    case 2: return detail::count_rect_n<2>(tri, r, pattern);
    case 4: return detail::count_rect_n<4>(tri, r, pattern);
    case 8: return detail::count_rect_n<8>(tri, r, pattern);
    case 16: return detail::count_rect_n<16>(tri, r, pattern);
    default: assert(false && "unsupported sample count"); return 0;
  }
}

SampleDepthBounds depth_bounds_in_rect(const TriangleSetup& tri, const PixelRect& rect, const SamplePattern& pattern) {
  const PixelRect r = intersect(rect, tri.bbox);
  if (r.empty()) return {tri.z[0], tri.z[0]};
  const int bits = tri.subpixel_bits;
  std::int64_t min_dx = pattern.dx[0], max_dx = pattern.dx[0], min_dy = pattern.dy[0], max_dy = pattern.dy[0];
  for (int s = 1; s < pattern.count; ++s) {
    min_dx = std::min<std::int64_t>(min_dx, pattern.dx[s]);
    max_dx = std::max<std::int64_t>(max_dx, pattern.dx[s]);
    min_dy = std::min<std::int64_t>(min_dy, pattern.dy[s]);
    max_dy = std::max<std::int64_t>(max_dy, pattern.dy[s]);
  }
  // The plane is linear in the sample position: its extremes over the box of the rectangle's
  // sample positions lie at the box's corners.
  const std::int64_t xs[2] = {(std::int64_t{r.x0} << bits) + min_dx, (std::int64_t{r.x1 - 1} << bits) + max_dx};
  const std::int64_t ys[2] = {(std::int64_t{r.y0} << bits) + min_dy, (std::int64_t{r.y1 - 1} << bits) + max_dy};
  double lo = std::numeric_limits<double>::infinity(), hi = -lo, magnitude = std::abs(static_cast<double>(tri.z[0]));
  double term1 = 0, term2 = 0;
  for (const std::int64_t x : xs) {
    for (const std::int64_t y : ys) {
      const std::int64_t e1 = edge_value(tri, 1, x, y), e2 = edge_value(tri, 2, x, y);
      const double z = depth_at_corner(tri, e1, e2);
      lo = std::min(lo, z);
      hi = std::max(hi, z);
      term1 = std::max(term1, std::abs(static_cast<double>(e1) * tri.dz1));
      term2 = std::max(term2, std::abs(static_cast<double>(e2) * tri.dz2));
    }
  }
  if (!std::isfinite(lo) || !std::isfinite(hi)) {
    const float nan = std::numeric_limits<float>::quiet_NaN();
    return {nan, nan};
  }
  // A sample's depth is z0 + E1*dz1 + E2*dz2 evaluated as corner + offset in double: a few
  // roundings of at most 2^-53 of the terms' magnitude each. 1e-12 of it is far more.
  magnitude += term1 + term2;
  const double margin = 1e-12 * (1.0 + magnitude);
  return {static_cast<float>(lo - margin), static_cast<float>(hi + margin)};
}

const char* to_string(TileTest t) {
  switch (t) {
    case TileTest::BoundingBox: return "bbox";
    case TileTest::Exact: return "exact";
  }
  return "?";
}

std::vector<TileCoord> overlapped_tiles(const TriangleSetup& tri, int tile_w_px, int tile_h_px, TileTest test,
                                        const SamplePattern& pattern) {
  std::vector<TileCoord> tiles;
  for_each_overlapped_tile(tri, tile_w_px, tile_h_px, test, pattern,
                           [&](int tx, int ty) { tiles.push_back({tx, ty}); });
  return tiles;
}

int count_overlapped_tiles(const TriangleSetup& tri, int tile_w_px, int tile_h_px, TileTest test,
                           const SamplePattern& pattern) {
  int count = 0;
  for_each_overlapped_tile(tri, tile_w_px, tile_h_px, test, pattern, [&](int, int) { ++count; });
  return count;
}

}  // namespace tbdr
