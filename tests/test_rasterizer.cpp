// Tests of models/rasterizer: fill rule, watertightness, MSAA masks, depth, barycentrics, tiles.
#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <map>
#include <random>
#include <set>
#include <vector>

#include "models/rasterizer.hpp"

namespace tbdr {
namespace {

constexpr int kBits = 8;
constexpr std::int32_t kOne = 1 << kBits;  // one pixel in fixed point

/// Fixed-point position of the center of pixel i.
std::int32_t center(int i) { return i * kOne + kOne / 2; }

ScreenTriangle make_tri(std::int32_t x0, std::int32_t y0, std::int32_t x1, std::int32_t y1, std::int32_t x2,
                        std::int32_t y2, float z0 = 0.5f, float z1 = 0.5f, float z2 = 0.5f) {
  ScreenTriangle t;
  t.x_fixed = {x0, x1, x2};
  t.y_fixed = {y0, y1, y2};
  t.z = {z0, z1, z2};
  t.inv_w = {1.0f, 1.0f, 1.0f};
  return t;
}

/// The same triangle with vertices 1 and 2 swapped (opposite winding).
ScreenTriangle flipped(ScreenTriangle t) {
  std::swap(t.x_fixed[1], t.x_fixed[2]);
  std::swap(t.y_fixed[1], t.y_fixed[2]);
  std::swap(t.z[1], t.z[2]);
  std::swap(t.inv_w[1], t.inv_w[2]);
  std::swap(t.bary[1], t.bary[2]);
  return t;
}

/// Per-sample hit counts over a whole viewport.
struct SampleCounts {
  int width, height, samples;
  std::vector<int> count;
  SampleCounts(int w, int h, int s) : width(w), height(h), samples(s), count(static_cast<size_t>(w) * h * s, 0) {}
  int& at(int x, int y, int s) { return count[(static_cast<size_t>(y) * width + x) * samples + s]; }
};

void accumulate(SampleCounts& counts, const TriangleSetup& setup, const SamplePattern& pattern) {
  rasterize_in_rect(setup, PixelRect{0, 0, counts.width, counts.height}, pattern,
                    [&](int x, int y, std::uint32_t mask, const float*) {
                      for (int s = 0; s < pattern.count; ++s) {
                        if (mask >> s & 1u) ++counts.at(x, y, s);
                      }
                    });
}

/// Pixels covered (any sample) by one triangle, 1x.
std::set<std::pair<int, int>> covered_pixels(const ScreenTriangle& tri, const Viewport& vp) {
  std::set<std::pair<int, int>> px;
  const TriangleSetup setup = setup_triangle(tri, vp);
  rasterize_in_rect(setup, PixelRect{0, 0, vp.width_px, vp.height_px}, standard_sample_pattern(1, vp.subpixel_bits),
                    [&](int x, int y, std::uint32_t, const float*) { px.insert({x, y}); });
  return px;
}

/// Checks that the union of `tris` covers exactly the samples of the fixed-point rectangle
/// [x0,x1) x [y0,y1) once each, and nothing else (the rectangle's top/left edges are in).
void expect_covers_rect_once(const std::vector<ScreenTriangle>& tris, const Viewport& vp, int samples,
                             std::int64_t x0, std::int64_t y0, std::int64_t x1, std::int64_t y1) {
  const SamplePattern pattern = standard_sample_pattern(samples, vp.subpixel_bits);
  SampleCounts counts(vp.width_px, vp.height_px, samples);
  for (const ScreenTriangle& t : tris) accumulate(counts, setup_triangle(t, vp), pattern);
  int wrong = 0, inside = 0;
  for (int y = 0; y < vp.height_px; ++y) {
    for (int x = 0; x < vp.width_px; ++x) {
      for (int s = 0; s < samples; ++s) {
        const glm::i64vec2 p = sample_position_fixed(pattern, x, y, s);
        const int expected = (p.x >= x0 && p.x < x1 && p.y >= y0 && p.y < y1) ? 1 : 0;
        inside += expected;
        if (counts.at(x, y, s) != expected) {
          if (++wrong <= 5) {
            ADD_FAILURE() << samples << "x: sample " << s << " of pixel (" << x << "," << y << ") at fixed ("
                          << p.x << "," << p.y << ") hit " << counts.at(x, y, s) << " times, expected " << expected;
          }
        }
      }
    }
  }
  EXPECT_EQ(wrong, 0);
  EXPECT_GT(inside, 0);
}

class RasterWatertight : public ::testing::TestWithParam<int> {};

TEST_P(RasterWatertight, FanAroundCenterCoversRectOnce) {
  const int samples = GetParam();
  const Viewport vp{48, 40, kBits};
  std::mt19937 rng(1234 + samples);
  // Rectangle with corners on pixel corners and on 1x sample positions.
  const std::int64_t x0 = 3 * kOne, y0 = center(2), x1 = center(41), y1 = 37 * kOne + 96;
  for (int trial = 0; trial < 20; ++trial) {
    std::uniform_int_distribution<std::int64_t> ux(x0 + 1, x1 - 1), uy(y0 + 1, y1 - 1);
    // Boundary points clockwise on screen (y down) from the top-left corner, some snapped to samples.
    const SamplePattern pattern = standard_sample_pattern(samples, kBits);
    auto maybe_snap = [&](std::int64_t v, std::int64_t lo, std::int64_t hi) {
      const int s = static_cast<int>(rng() % samples);
      const std::int64_t snapped = (v & ~std::int64_t{kOne - 1}) + (rng() % 2 ? pattern.dx[s] : pattern.dy[s]);
      return (rng() % 3 == 0 && snapped > lo && snapped < hi) ? snapped : v;
    };
    std::vector<std::pair<std::int64_t, std::int64_t>> ring;
    auto side = [&](int n, bool horizontal) {
      std::vector<std::int64_t> ts;
      for (int i = 0; i < n; ++i) ts.push_back(horizontal ? maybe_snap(ux(rng), x0, x1) : maybe_snap(uy(rng), y0, y1));
      std::sort(ts.begin(), ts.end());
      ts.erase(std::unique(ts.begin(), ts.end()), ts.end());
      return ts;
    };
    ring.push_back({x0, y0});
    for (std::int64_t x : side(3, true)) ring.push_back({x, y0});
    ring.push_back({x1, y0});
    for (std::int64_t y : side(3, false)) ring.push_back({x1, y});
    ring.push_back({x1, y1});
    auto bottom = side(3, true);
    for (auto it = bottom.rbegin(); it != bottom.rend(); ++it) ring.push_back({*it, y1});
    ring.push_back({x0, y1});
    auto left = side(3, false);
    for (auto it = left.rbegin(); it != left.rend(); ++it) ring.push_back({x0, *it});
    // Half of the trials put the centre exactly on a sample position.
    const int cs = trial % samples;
    const std::int64_t cx = trial % 2 == 0 ? 20 * kOne + pattern.dx[cs] : ux(rng);
    const std::int64_t cy = trial % 2 == 0 ? 19 * kOne + pattern.dy[cs] : uy(rng);
    std::vector<ScreenTriangle> tris;
    for (size_t i = 0; i < ring.size(); ++i) {
      const auto& a = ring[i];
      const auto& b = ring[(i + 1) % ring.size()];
      ScreenTriangle t = make_tri(static_cast<std::int32_t>(cx), static_cast<std::int32_t>(cy),
                                  static_cast<std::int32_t>(a.first), static_cast<std::int32_t>(a.second),
                                  static_cast<std::int32_t>(b.first), static_cast<std::int32_t>(b.second));
      tris.push_back(rng() % 2 ? t : flipped(t));
    }
    expect_covers_rect_once(tris, vp, samples, x0, y0, x1, y1);
  }
}

TEST_P(RasterWatertight, GridOfTrianglePairsCoversRectOnce) {
  const int samples = GetParam();
  const Viewport vp{64, 48, kBits};
  std::mt19937 rng(99 + samples);
  const int nx = 9, ny = 7;
  const std::int64_t x0 = kOne + 37, y0 = 2 * kOne, x1 = 61 * kOne + 128, y1 = 45 * kOne + 200;
  const double cw = static_cast<double>(x1 - x0) / nx, ch = static_cast<double>(y1 - y0) / ny;
  std::vector<std::vector<std::pair<std::int32_t, std::int32_t>>> v(ny + 1, std::vector<std::pair<std::int32_t, std::int32_t>>(nx + 1));
  std::uniform_real_distribution<double> jitter(-0.22, 0.22);
  for (int j = 0; j <= ny; ++j) {
    for (int i = 0; i <= nx; ++i) {
      double x = x0 + i * cw, y = y0 + j * ch;
      if (i > 0 && i < nx) x += jitter(rng) * cw;  // boundary vertices stay on the boundary lines
      if (j > 0 && j < ny) y += jitter(rng) * ch;
      std::int64_t xi = i == 0 ? x0 : i == nx ? x1 : static_cast<std::int64_t>(x);
      std::int64_t yi = j == 0 ? y0 : j == ny ? y1 : static_cast<std::int64_t>(y);
      if ((i + 2 * j) % 4 == 0) {  // some vertices exactly on a sample position of the pattern
        const SamplePattern p = standard_sample_pattern(samples, kBits);
        const int s = (i + j) % samples;
        if (i > 0 && i < nx) xi = (xi & ~std::int64_t{kOne - 1}) + p.dx[s];
        if (j > 0 && j < ny) yi = (yi & ~std::int64_t{kOne - 1}) + p.dy[s];
      }
      v[j][i] = {static_cast<std::int32_t>(xi), static_cast<std::int32_t>(yi)};
    }
  }
  std::vector<ScreenTriangle> tris;
  for (int j = 0; j < ny; ++j) {
    for (int i = 0; i < nx; ++i) {
      const auto a = v[j][i], b = v[j][i + 1], c = v[j + 1][i + 1], d = v[j + 1][i];
      ScreenTriangle t1, t2;
      if (rng() % 2) {
        t1 = make_tri(a.first, a.second, b.first, b.second, c.first, c.second);
        t2 = make_tri(a.first, a.second, c.first, c.second, d.first, d.second);
      } else {
        t1 = make_tri(a.first, a.second, b.first, b.second, d.first, d.second);
        t2 = make_tri(b.first, b.second, c.first, c.second, d.first, d.second);
      }
      tris.push_back(rng() % 2 ? t1 : flipped(t1));
      tris.push_back(rng() % 2 ? t2 : flipped(t2));
    }
  }
  expect_covers_rect_once(tris, vp, samples, x0, y0, x1, y1);
}

INSTANTIATE_TEST_SUITE_P(RasterMsaa, RasterWatertight, ::testing::Values(1, 2, 4, 8, 16));

TEST(RasterSamplePattern, StandardPositionsInFixedPoint) {
  const SamplePattern p1 = standard_sample_pattern(1, 8);
  EXPECT_EQ(p1.count, 1);
  EXPECT_EQ(p1.dx[0], 128);
  EXPECT_EQ(p1.dy[0], 128);
  const SamplePattern p2 = standard_sample_pattern(2, 8);
  EXPECT_EQ((std::vector<int>{p2.dx[0], p2.dy[0], p2.dx[1], p2.dy[1]}), (std::vector<int>{192, 192, 64, 64}));
  const SamplePattern p4 = standard_sample_pattern(4, 8);
  const std::vector<int> expected4{96, 32, 224, 96, 32, 160, 160, 224};  // 0.375,0.125 0.875,0.375 ...
  std::vector<int> got4;
  for (int s = 0; s < 4; ++s) {
    got4.push_back(p4.dx[s]);
    got4.push_back(p4.dy[s]);
  }
  EXPECT_EQ(got4, expected4);
  const SamplePattern p4b = standard_sample_pattern(4, 4);
  EXPECT_EQ(p4b.dx[0], 6);  // 0.375 * 16
  EXPECT_EQ(p4b.dy[3], 14);  // 0.875 * 16
  for (int n : {8, 16}) {
    const SamplePattern p = standard_sample_pattern(n, 8);
    std::set<std::pair<int, int>> distinct;
    for (int s = 0; s < n; ++s) {
      EXPECT_GE(p.dx[s], 0);
      EXPECT_LT(p.dx[s], 256);
      distinct.insert({p.dx[s], p.dy[s]});
    }
    EXPECT_EQ(static_cast<int>(distinct.size()), n);
  }
  EXPECT_EQ(standard_sample_pattern(8, 8).dx[0], 144);  // 9/16
  EXPECT_EQ(standard_sample_pattern(16, 8).dy[15], 0);
  EXPECT_THROW(standard_sample_pattern(3, 8), std::invalid_argument);
  EXPECT_THROW(standard_sample_pattern(4, 2), std::invalid_argument);
  EXPECT_THROW(standard_sample_pattern(8, 3), std::invalid_argument);
}

TEST(RasterFillRule, TopAndLeftEdgesInBottomAndRightOut) {
  const Viewport vp{8, 8, kBits};
  // Upper-left half of a square with sample-aligned corners: top and left edges, hypotenuse right.
  const ScreenTriangle upper = make_tri(center(1), center(1), center(5), center(1), center(1), center(5));
  // Lower-right half: bottom and right edges, hypotenuse is its left edge.
  const ScreenTriangle lower = make_tri(center(1), center(5), center(5), center(5), center(5), center(1));
  std::set<std::pair<int, int>> expect_upper, expect_lower;
  for (int y = 0; y < 8; ++y) {
    for (int x = 0; x < 8; ++x) {
      if (x >= 1 && y >= 1 && x + y < 6) expect_upper.insert({x, y});
      if (x < 5 && y < 5 && x + y >= 6) expect_lower.insert({x, y});
    }
  }
  for (const ScreenTriangle& t : {upper, flipped(upper)}) EXPECT_EQ(covered_pixels(t, vp), expect_upper);
  for (const ScreenTriangle& t : {lower, flipped(lower)}) EXPECT_EQ(covered_pixels(t, vp), expect_lower);
}

TEST(RasterFillRule, HorizontalAndVerticalEdgesOnSampleRows) {
  const Viewport vp{16, 16, kBits};
  // A rectangle [2,6] x [3,7] of pixel centres as two triangles: samples on its top row and left
  // column are in, on its bottom row and right column out.
  const std::int32_t l = center(2), r = center(6), t = center(3), b = center(7);
  std::set<std::pair<int, int>> got;
  for (const ScreenTriangle& tri : {make_tri(l, t, r, t, r, b), make_tri(l, t, r, b, l, b)}) {
    for (auto p : covered_pixels(tri, vp)) EXPECT_TRUE(got.insert(p).second) << "double hit";
  }
  std::set<std::pair<int, int>> expected;
  for (int y = 3; y < 7; ++y) {
    for (int x = 2; x < 6; ++x) expected.insert({x, y});
  }
  EXPECT_EQ(got, expected);
  // A single sample exactly on a horizontal edge: in when it is the top edge, out when the bottom.
  const TriangleSetup below = setup_triangle(make_tri(center(0), center(4), center(8), center(4), center(4), center(9)), vp);
  const TriangleSetup above = setup_triangle(make_tri(center(0), center(4), center(8), center(4), center(4), center(0)), vp);
  EXPECT_TRUE(covers_point(below, center(4), center(4)));   // top edge of `below`
  EXPECT_FALSE(covers_point(above, center(4), center(4)));  // bottom edge of `above`
  // ... and on a vertical edge: in on the left edge, out on the right edge.
  const TriangleSetup right_of = setup_triangle(make_tri(center(4), center(0), center(9), center(4), center(4), center(8)), vp);
  const TriangleSetup left_of = setup_triangle(make_tri(center(4), center(0), center(0), center(4), center(4), center(8)), vp);
  EXPECT_TRUE(covers_point(right_of, center(4), center(4)));
  EXPECT_FALSE(covers_point(left_of, center(4), center(4)));
}

TEST(RasterMsaa, HalfPlaneSplitsPixelMasks) {
  const Viewport vp{16, 16, kBits};
  // Everything left of x = 5.5 px (a vertical right edge through the middle of column 5).
  const std::int32_t xe = center(5);
  const ScreenTriangle left = make_tri(xe, -40 * kOne, xe, 60 * kOne, xe - 60 * kOne, 8 * kOne);
  // Everything above y = 6.5 px (a horizontal bottom edge through the middle of row 6).
  const std::int32_t ye = center(6);
  const ScreenTriangle above = make_tri(-40 * kOne, ye, 60 * kOne, ye, 8 * kOne, ye - 60 * kOne);
  struct Case {
    int samples;
    std::uint32_t left_mask, above_mask;
  };
  // 4x: x = .375 .875 .125 .625, y = .125 .375 .625 .875; 2x: (.75,.75) (.25,.25).
  for (const Case& c : {Case{1, 0x0, 0x0}, Case{2, 0x2, 0x2}, Case{4, 0x5, 0x3}}) {
    const SamplePattern p = standard_sample_pattern(c.samples, kBits);
    std::map<std::pair<int, int>, std::uint32_t> masks;
    auto mask_at = [&](int x, int y) {
      const auto it = masks.find({x, y});
      return it == masks.end() ? 0u : it->second;
    };
    auto collect = [&](const ScreenTriangle& t) {
      masks.clear();
      rasterize_in_rect(setup_triangle(t, vp), PixelRect{0, 0, 16, 16}, p,
                        [&](int x, int y, std::uint32_t m, const float*) { masks[{x, y}] = m; });
    };
    collect(left);
    EXPECT_EQ(mask_at(5, 3), c.left_mask) << c.samples << "x";
    EXPECT_EQ(mask_at(4, 3), p.full_mask());
    EXPECT_EQ(masks.count({6, 3}), 0u);
    collect(above);
    EXPECT_EQ(mask_at(3, 6), c.above_mask) << c.samples << "x";
    EXPECT_EQ(mask_at(3, 5), p.full_mask());
    EXPECT_EQ(masks.count({3, 7}), 0u);
  }
}

TEST(RasterMsaa, MasksAndDepthMatchPointTests) {
  const Viewport vp{40, 36, kBits};
  std::mt19937 rng(7);
  std::uniform_int_distribution<std::int32_t> coord(-6 * kOne, 46 * kOne);
  std::uniform_real_distribution<float> depth(0.0f, 1.0f);
  for (int samples : {1, 2, 4, 8, 16}) {
    const SamplePattern p = standard_sample_pattern(samples, kBits);
    for (int trial = 0; trial < 60; ++trial) {
      ScreenTriangle t = make_tri(coord(rng), coord(rng), coord(rng), coord(rng), coord(rng), coord(rng), depth(rng),
                                  depth(rng), depth(rng));
      if (trial % 3 == 0) {  // small triangles too
        t.x_fixed[1] = t.x_fixed[0] + static_cast<std::int32_t>(rng() % 900);
        t.y_fixed[2] = t.y_fixed[0] + static_cast<std::int32_t>(rng() % 900);
      }
      const TriangleSetup setup = setup_triangle(t, vp);
      std::vector<std::uint32_t> got(static_cast<size_t>(vp.width_px) * vp.height_px, 0);
      rasterize_in_rect(setup, PixelRect{-5, -5, 100, 100}, p, [&](int x, int y, std::uint32_t m, const float* d) {
        ASSERT_NE(m, 0u);
        ASSERT_EQ(got[y * vp.width_px + x], 0u) << "pixel visited twice";
        got[y * vp.width_px + x] = m;
        for (int s = 0; s < samples; ++s) {
          if (m >> s & 1u) {
            ASSERT_EQ(d[s], depth_at_sample(setup, p, x, y, s));
          }
        }
      });
      for (int y = 0; y < vp.height_px; ++y) {
        for (int x = 0; x < vp.width_px; ++x) {
          std::uint32_t expected = 0;
          for (int s = 0; s < samples; ++s) {
            const glm::i64vec2 q = sample_position_fixed(p, x, y, s);
            if (covers_point(setup, q.x, q.y)) expected |= 1u << s;
          }
          ASSERT_EQ(got[y * vp.width_px + x], expected) << samples << "x trial " << trial << " pixel " << x << "," << y;
        }
      }
    }
  }
}

TEST(RasterDepth, VertexDepthIsExactAndPlaneIsLinear) {
  const Viewport vp{32, 32, kBits};
  // Top-left vertex on a pixel centre with a top and a left edge: its sample is covered.
  const ScreenTriangle t = make_tri(center(2), center(3), center(20), center(3), center(2), center(25), 0.1f, 0.7f,
                                    0.35f);
  const TriangleSetup setup = setup_triangle(t, vp);
  const SamplePattern p1 = standard_sample_pattern(1, kBits);
  bool seen = false;
  rasterize_in_rect(setup, PixelRect{0, 0, 32, 32}, p1, [&](int x, int y, std::uint32_t, const float* d) {
    if (x == 2 && y == 3) {
      seen = true;
      EXPECT_EQ(d[0], 0.1f);
    }
    // Plane: z = 0.1 + 0.6 * (x - 2) / 18 + 0.25 * (y - 3) / 22 at pixel centres.
    const double expected = 0.1 + 0.6 * (x - 2) / 18.0 + 0.25 * (y - 3) / 22.0;
    EXPECT_NEAR(d[0], expected, 1e-6);
  });
  EXPECT_TRUE(seen);
  // Every vertex, wherever it is: depth_at_sample at its sample equals its z exactly.
  std::mt19937 rng(3);
  std::uniform_int_distribution<int> pix(0, 31);
  std::uniform_real_distribution<float> z(0.0f, 1.0f);
  for (int samples : {1, 4, 16}) {
    const SamplePattern p = standard_sample_pattern(samples, kBits);
    for (int trial = 0; trial < 200; ++trial) {
      int px[3], py[3], ps[3];
      ScreenTriangle r;
      for (int k = 0; k < 3; ++k) {
        px[k] = pix(rng);
        py[k] = pix(rng);
        ps[k] = static_cast<int>(rng() % samples);
        const glm::i64vec2 q = sample_position_fixed(p, px[k], py[k], ps[k]);
        r.x_fixed[k] = static_cast<std::int32_t>(q.x);
        r.y_fixed[k] = static_cast<std::int32_t>(q.y);
        r.z[k] = z(rng);
      }
      const TriangleSetup s = setup_triangle(r, vp);
      if (s.area_x2 == 0) continue;
      for (int k = 0; k < 3; ++k) EXPECT_EQ(depth_at_sample(s, p, px[k], py[k], ps[k]), r.z[k]);
    }
  }
}

TEST(RasterRect, TilesReproduceFullViewportExactly) {
  const Viewport vp{70, 50, kBits};
  std::mt19937 rng(11);
  std::uniform_int_distribution<std::int32_t> coord(-10 * kOne, 80 * kOne);
  std::uniform_real_distribution<float> z(0.0f, 1.0f);
  const SamplePattern p = standard_sample_pattern(4, kBits);
  for (int trial = 0; trial < 30; ++trial) {
    const TriangleSetup s = setup_triangle(
        make_tri(coord(rng), coord(rng), coord(rng), coord(rng), coord(rng), coord(rng), z(rng), z(rng), z(rng)), vp);
    std::map<std::pair<int, int>, std::vector<float>> full, tiled;
    auto record = [&](auto& out) {
      return [&out, &p](int x, int y, std::uint32_t m, const float* d) {
        std::vector<float> v(p.count, -1.0f);
        for (int i = 0; i < p.count; ++i) {
          if (m >> i & 1u) v[i] = d[i];
        }
        EXPECT_TRUE(out.emplace(std::pair{x, y}, v).second);
      };
    };
    rasterize_in_rect(s, PixelRect{0, 0, 70, 50}, p, record(full));
    for (int ty = 0; ty < 4; ++ty) {
      for (int tx = 0; tx < 5; ++tx) rasterize_in_rect(s, tile_rect(s, 16, 16, tx, ty), p, record(tiled));
    }
    EXPECT_EQ(full, tiled);  // bit-identical depths whatever rectangle reached the sample
  }
}

TEST(RasterBarycentrics, PerspectiveCorrectWeightsRecoverClipSpacePoint) {
  const Viewport vp{64, 64, kBits};
  // Original triangle in clip space with quite different w; screen positions from the projection.
  const glm::dvec4 v[3] = {{-0.8 * 1.0, -0.6 * 1.0, 0.0, 1.0}, {0.9 * 4.0, -0.7 * 4.0, 1.0, 4.0}, {0.1 * 2.0, 0.8 * 2.0, 0.5, 2.0}};
  auto to_fixed = [&](const glm::dvec4& c) {
    return glm::dvec2((c.x / c.w * 0.5 + 0.5) * vp.width_px * kOne, (0.5 - c.y / c.w * 0.5) * vp.height_px * kOne);
  };
  ScreenTriangle t;
  for (int k = 0; k < 3; ++k) {
    const glm::dvec2 f = to_fixed(v[k]);
    t.x_fixed[k] = static_cast<std::int32_t>(std::llround(f.x));
    t.y_fixed[k] = static_cast<std::int32_t>(std::llround(f.y));
    t.z[k] = static_cast<float>(v[k].z / v[k].w * 0.5 + 0.5);
    t.inv_w[k] = static_cast<float>(1.0 / v[k].w);
  }
  for (const ScreenTriangle& tri : {t, flipped(t)}) {
    const TriangleSetup s = setup_triangle(tri, vp);
    // At the vertices: unit weights of the original vertices.
    for (int k = 0; k < 3; ++k) {
      const glm::vec3 w = perspective_barycentrics(s, t.x_fixed[k], t.y_fixed[k]);
      for (int i = 0; i < 3; ++i) EXPECT_NEAR(w[i], i == k ? 1.0f : 0.0f, 1e-6f);
    }
    // Inside: a clip-space blend projects to a screen point whose weights give the blend back.
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> u(0.05, 1.0);
    for (int trial = 0; trial < 50; ++trial) {
      glm::dvec3 beta(u(rng), u(rng), u(rng));
      beta /= beta.x + beta.y + beta.z;
      const glm::dvec4 c = beta.x * v[0] + beta.y * v[1] + beta.z * v[2];
      const glm::dvec2 f = to_fixed(c);
      const glm::vec3 w = perspective_barycentrics(s, std::llround(f.x), std::llround(f.y));
      for (int i = 0; i < 3; ++i) EXPECT_NEAR(w[i], beta[i], 2e-3) << "trial " << trial;
      EXPECT_NEAR(w.x + w.y + w.z, 1.0f, 1e-5f);
    }
  }
}

TEST(RasterTiles, ExactMatchesBruteForceAndBboxIsSuperset) {
  const Viewport vp{100, 70, kBits};  // partial tiles at the right and bottom
  std::mt19937 rng(21);
  std::uniform_int_distribution<std::int32_t> coord(-20 * kOne, 120 * kOne);
  for (int samples : {1, 4}) {
    const SamplePattern p = standard_sample_pattern(samples, kBits);
    for (int tile : {16, 32}) {
      for (int trial = 0; trial < 80; ++trial) {
        ScreenTriangle t = make_tri(coord(rng), coord(rng), coord(rng), coord(rng), coord(rng), coord(rng));
        if (trial % 4 == 0) {  // thin slivers
          t.x_fixed[2] = t.x_fixed[1] + static_cast<std::int32_t>(rng() % 300);
          t.y_fixed[2] = t.y_fixed[1] + static_cast<std::int32_t>(rng() % 300);
        }
        const TriangleSetup s = setup_triangle(t, vp);
        const std::vector<TileCoord> exact = overlapped_tiles(s, tile, tile, TileTest::Exact, p);
        const std::vector<TileCoord> bbox = overlapped_tiles(s, tile, tile, TileTest::BoundingBox, p);
        // Brute force: a tile is touched iff one of its samples is covered.
        std::vector<TileCoord> brute;
        const int tiles_x = (vp.width_px + tile - 1) / tile, tiles_y = (vp.height_px + tile - 1) / tile;
        for (int ty = 0; ty < tiles_y; ++ty) {
          for (int tx = 0; tx < tiles_x; ++tx) {
            bool hit = false;
            for (int y = ty * tile; y < std::min(vp.height_px, (ty + 1) * tile) && !hit; ++y) {
              for (int x = tx * tile; x < std::min(vp.width_px, (tx + 1) * tile) && !hit; ++x) {
                for (int i = 0; i < samples && !hit; ++i) {
                  const glm::i64vec2 q = sample_position_fixed(p, x, y, i);
                  hit = covers_point(s, q.x, q.y);
                }
              }
            }
            if (hit) brute.push_back({tx, ty});
          }
        }
        ASSERT_EQ(exact, brute) << samples << "x tile " << tile << " trial " << trial;
        for (const TileCoord& c : exact) EXPECT_NE(std::find(bbox.begin(), bbox.end(), c), bbox.end());
        EXPECT_EQ(count_overlapped_tiles(s, tile, tile, TileTest::Exact, p), static_cast<int>(exact.size()));
      }
    }
  }
}

TEST(RasterTiles, ThinDiagonalTouchesFarFewerTilesExactly) {
  const Viewport vp{1024, 1024, kBits};
  const SamplePattern p = standard_sample_pattern(1, kBits);
  // A sliver from the top-left corner (16 px wide there) to the bottom-right corner.
  const TriangleSetup s = setup_triangle(make_tri(0, 0, 16 * kOne, 0, 1024 * kOne, 1024 * kOne), vp);
  const int exact = count_overlapped_tiles(s, 32, 32, TileTest::Exact, p);
  const int bbox = count_overlapped_tiles(s, 32, 32, TileTest::BoundingBox, p);
  EXPECT_EQ(bbox, 32 * 32);
  EXPECT_LE(exact, 3 * 32);
  EXPECT_GE(exact, 32);
}

TEST(RasterTiles, CoversAnySampleAgreesWithRasterizer) {
  const Viewport vp{64, 64, kBits};
  std::mt19937 rng(8);
  std::uniform_int_distribution<std::int32_t> coord(-4 * kOne, 68 * kOne);
  std::uniform_int_distribution<int> pos(-4, 68);
  const SamplePattern p = standard_sample_pattern(8, kBits);
  for (int trial = 0; trial < 300; ++trial) {
    ScreenTriangle t = make_tri(coord(rng), coord(rng), coord(rng), coord(rng), coord(rng), coord(rng));
    if (trial % 2) t.x_fixed[2] = t.x_fixed[0] + static_cast<std::int32_t>(rng() % 400) - 200;
    const TriangleSetup s = setup_triangle(t, vp);
    int a = pos(rng), b = pos(rng), c = pos(rng), d = pos(rng);
    const PixelRect r{std::min(a, b), std::min(c, d), std::max(a, b) + 1, std::max(c, d) + 1};
    bool visited = false;
    rasterize_in_rect(s, r, p, [&](int, int, std::uint32_t, const float*) { visited = true; });
    EXPECT_EQ(covers_any_sample(s, r, p), visited) << "trial " << trial;
  }
}

// covered_samples counts span by span what rasterize_in_rect visits pixel by pixel, and
// depth_bounds_in_rect holds every depth it reports: the ISP counts a primitive whose every
// sample fails the depth test without visiting it, so both must be exact (counts) and
// conservative (bounds) for any triangle, rectangle and sample count.
TEST(RasterRect, CoveredSamplesAndDepthBoundsAgreeWithTheVisit) {
  const Viewport vp{64, 64, kBits};
  std::mt19937 rng(11);
  std::uniform_int_distribution<std::int32_t> coord(-4 * kOne, 68 * kOne);
  std::uniform_int_distribution<int> pos(-4, 68);
  std::uniform_real_distribution<float> depth(0.0f, 1.0f);
  std::uint64_t total = 0;
  for (int samples : {1, 2, 4, 8, 16}) {
    const SamplePattern p = standard_sample_pattern(samples, kBits);
    for (int trial = 0; trial < 200; ++trial) {
      ScreenTriangle t = make_tri(coord(rng), coord(rng), coord(rng), coord(rng), coord(rng), coord(rng), depth(rng),
                                  depth(rng), depth(rng));
      if (trial % 2) t.x_fixed[2] = t.x_fixed[0] + static_cast<std::int32_t>(rng() % 400) - 200;
      const TriangleSetup s = setup_triangle(t, vp);
      const int a = pos(rng), b = pos(rng), c = pos(rng), d = pos(rng);
      const PixelRect r = trial % 5 == 0 ? PixelRect{0, 0, 64, 64}
                                         : PixelRect{std::min(a, b), std::min(c, d), std::max(a, b) + 1, std::max(c, d) + 1};
      std::uint64_t visited = 0;
      const SampleDepthBounds bounds = depth_bounds_in_rect(s, r, p);
      rasterize_in_rect(s, r, p, [&](int, int, std::uint32_t m, const float* z) {
        visited += static_cast<std::uint64_t>(std::popcount(m));
        for (int k = 0; k < samples; ++k) {
          if (m >> k & 1u) {
            ASSERT_LE(bounds.lo, z[k]) << samples << "x trial " << trial;
            ASSERT_GE(bounds.hi, z[k]) << samples << "x trial " << trial;
          }
        }
      });
      ASSERT_EQ(covered_samples(s, r, p), visited) << samples << "x trial " << trial;
      total += visited;
    }
  }
  EXPECT_GT(total, 100000u);  // the trials cover real areas, not only misses
  // The bounds are tight, not merely safe: a flat triangle's are its depth, to a float ulp.
  const TriangleSetup flat = setup_triangle(make_tri(0, 0, 64 * kOne, 0, 0, 64 * kOne, 0.25f, 0.25f, 0.25f), vp);
  const SampleDepthBounds b = depth_bounds_in_rect(flat, PixelRect{0, 0, 64, 64}, standard_sample_pattern(1, kBits));
  EXPECT_LE(b.lo, 0.25f);
  EXPECT_GE(b.hi, 0.25f);
  EXPECT_LE(b.hi - b.lo, 2 * std::nextafter(0.25f, 1.0f) - 2 * 0.25f);
}

// rasterize_spans_1x reports a row's covered run at once (the ISP's 1x depth-test loop reads it):
// the same pixels, in the same order, with bit-identical depths as rasterize_in_rect's visit one
// by one, runs longer than kSpanPixels in pieces; rectangles up to 200 pixels wide make pieces.
TEST(RasterRect, SpansAreTheVisitsPixelsAndDepths) {
  const Viewport vp{200, 96, kBits};
  std::mt19937 rng(23);
  std::uniform_int_distribution<std::int32_t> cx(-8 * kOne, 208 * kOne), cy(-8 * kOne, 104 * kOne);
  std::uniform_int_distribution<int> px(-4, 204), py(-4, 100);
  std::uniform_real_distribution<float> depth(0.0f, 1.0f);
  const SamplePattern p = standard_sample_pattern(1, kBits);
  struct Visit {
    int x, y;
    std::uint32_t z_bits;
    bool operator==(const Visit&) const = default;
  };
  std::uint64_t total = 0, pieces_at_limit = 0;
  for (int trial = 0; trial < 300; ++trial) {
    const ScreenTriangle t = make_tri(cx(rng), cy(rng), cx(rng), cy(rng), cx(rng), cy(rng), depth(rng), depth(rng), depth(rng));
    const TriangleSetup s = setup_triangle(t, vp);
    const int a = px(rng), b = px(rng), c = py(rng), d = py(rng);
    const PixelRect r = trial % 3 == 0 ? PixelRect{0, 0, 200, 96}
                                       : PixelRect{std::min(a, b), std::min(c, d), std::max(a, b) + 1, std::max(c, d) + 1};
    std::vector<Visit> one_by_one, by_span;
    rasterize_in_rect(s, r, p, [&](int x, int y, std::uint32_t m, const float* z) {
      ASSERT_EQ(m, 1u);
      one_by_one.push_back({x, y, std::bit_cast<std::uint32_t>(z[0])});
    });
    rasterize_spans_1x(s, r, p, [&](int y, int x0, int x1, const float* z) {
      ASSERT_LT(x0, x1);
      ASSERT_LE(x1 - x0, kSpanPixels);
      if (x1 - x0 == kSpanPixels) ++pieces_at_limit;
      for (int x = x0; x < x1; ++x) by_span.push_back({x, y, std::bit_cast<std::uint32_t>(z[x - x0])});
    });
    ASSERT_EQ(by_span, one_by_one) << "trial " << trial;
    total += one_by_one.size();
  }
  EXPECT_GT(total, 100000u);       // real areas, not only misses
  EXPECT_GT(pieces_at_limit, 50u);  // runs longer than kSpanPixels were cut
}

TEST(RasterSetup, DegenerateAndOffscreenTrianglesAreEmpty) {
  const Viewport vp{32, 32, kBits};
  EXPECT_TRUE(setup_triangle(make_tri(0, 0, 10 * kOne, 10 * kOne, 20 * kOne, 20 * kOne), vp).empty);
  EXPECT_TRUE(setup_triangle(make_tri(40 * kOne, 0, 50 * kOne, 0, 45 * kOne, 10 * kOne), vp).empty);
  const TriangleSetup s = setup_triangle(make_tri(-5 * kOne, -5 * kOne, 10 * kOne, 0, 0, 40 * kOne), vp);
  EXPECT_FALSE(s.empty);
  EXPECT_EQ(s.bbox, (PixelRect{0, 0, 11, 32}));
  EXPECT_GT(s.area_x2, 0);
  EXPECT_NO_THROW(validate_viewport(Viewport{1920, 1080, 8}));
  EXPECT_THROW(validate_viewport(Viewport{0, 1080, 8}), std::invalid_argument);
  EXPECT_THROW(validate_viewport(Viewport{1920, 1080, 17}), std::invalid_argument);
  EXPECT_THROW(validate_viewport(Viewport{100000, 1080, 12}), std::invalid_argument);
}

}  // namespace
}  // namespace tbdr
