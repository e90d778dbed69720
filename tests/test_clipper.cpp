// Tests of models/clipper: frustum rejection, near/far/guard-band clipping, viewport transform,
// culling and counters; clipped coverage checked against the unclipped part in front.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <vector>

#include <glm/gtc/matrix_transform.hpp>

#include "models/clipper.hpp"
#include "models/rasterizer.hpp"

namespace tbdr {
namespace {

constexpr int kBits = 8;
constexpr std::int64_t kOne = 1 << kBits;

/// A clip-space vertex from NDC coordinates and w.
glm::vec4 ndc(float x, float y, float z, float w = 1.0f) { return {x * w, y * w, z * w, w}; }

ClipConfig config(int w, int h, FaceCull cull = FaceCull::None) {
  ClipConfig c;
  c.viewport = Viewport{w, h, kBits};
  c.cull = cull;
  return c;
}

/// Per-sample hit counts of a set of screen triangles over the whole viewport.
std::vector<int> sample_hits(const std::vector<ScreenTriangle>& tris, const Viewport& vp, const SamplePattern& p) {
  std::vector<int> hits(static_cast<size_t>(vp.width_px) * vp.height_px * p.count, 0);
  for (const ScreenTriangle& t : tris) {
    rasterize_in_rect(setup_triangle(t, vp), PixelRect{0, 0, vp.width_px, vp.height_px}, p,
                      [&](int x, int y, std::uint32_t m, const float*) {
                        for (int s = 0; s < p.count; ++s) {
                          if (m >> s & 1u) ++hits[(static_cast<size_t>(y) * vp.width_px + x) * p.count + s];
                        }
                      });
  }
  return hits;
}

/// NDC of a fixed-point screen position (inverse of the viewport transform, y down).
glm::dvec2 fixed_to_ndc(double x_fixed, double y_fixed, const Viewport& vp) {
  return {x_fixed / (vp.width_px * static_cast<double>(kOne)) * 2.0 - 1.0,
          1.0 - y_fixed / (vp.height_px * static_cast<double>(kOne)) * 2.0};
}

/// Ground truth by ray casting: is the point of the original clip-space triangle seen at this NDC
/// position in front of the near plane (and behind the far plane)? Also returns its weights.
bool ray_hits_front_part(const std::array<glm::dvec4, 3>& v, glm::dvec2 p, glm::dvec3* beta_out = nullptr) {
  glm::dmat3 m;
  for (int i = 0; i < 3; ++i) m[i] = glm::dvec3(v[i].x - p.x * v[i].w, v[i].y - p.y * v[i].w, 1.0);
  if (std::abs(glm::determinant(m)) < 1e-12) return false;
  const glm::dvec3 beta = glm::inverse(m) * glm::dvec3(0.0, 0.0, 1.0);
  if (beta_out) *beta_out = beta;
  if (beta.x < 0.0 || beta.y < 0.0 || beta.z < 0.0) return false;
  const glm::dvec4 c = beta.x * v[0] + beta.y * v[1] + beta.z * v[2];
  return c.w > 0.0 && c.z >= -c.w && c.z <= c.w;
}

/// Classifies a sample robustly: 1 inside, 0 outside, -1 when the boundary passes within two
/// sub-pixel units (snapping of clipped vertices may legitimately decide either way there).
template <class Inside>
int robust_class(std::int64_t x, std::int64_t y, Inside inside) {
  const bool c = inside(x, y);
  for (int dx : {-2, 2}) {
    for (int dy : {-2, 2}) {
      if (inside(x + dx, y + dy) != c) return -1;
    }
  }
  return c ? 1 : 0;
}

TEST(ClipperFrustum, TriviallyRejectsTrianglesOutsideOnePlane) {
  const ClipConfig cfg = config(64, 64);
  const std::vector<ClipTriangle> outside = {
      {ndc(-1.5f, 0, 0), ndc(-2, 1, 0), ndc(-1.1f, -1, 0)},     // left
      {ndc(1.5f, 0, 0), ndc(2, 1, 0), ndc(1.1f, -1, 0)},        // right
      {ndc(0, -1.5f, 0), ndc(1, -2, 0), ndc(-1, -1.1f, 0)},     // bottom
      {ndc(0, 1.5f, 0), ndc(1, 2, 0), ndc(-1, 1.1f, 0)},        // top
      {ndc(0, 0, -1.5f), ndc(1, 0, -2), ndc(0, 1, -1.01f)},     // in front of the near plane
      {ndc(0, 0, 1.5f), ndc(1, 0, 2), ndc(0, 1, 1.01f)},        // beyond the far plane
  };
  for (FarPlaneMode far : {FarPlaneMode::Clip, FarPlaneMode::RejectOnly}) {
    ClipConfig c = cfg;
    c.far_plane = far;
    ClipStats stats;
    std::vector<ScreenTriangle> out;
    for (const ClipTriangle& t : outside) {
      EXPECT_TRUE(frustum_reject(t));
      EXPECT_EQ(clip_and_cull(t, c, stats, out), 0);
    }
    EXPECT_EQ(stats.in, outside.size());
    EXPECT_EQ(stats.culled_frustum, outside.size());
    EXPECT_EQ(stats.clipped, 0u);
    EXPECT_TRUE(out.empty());
  }
  // Outside different planes, but crossing the screen: kept, not clipped (guard band).
  const ClipTriangle straddling{ndc(-3, -3, 0), ndc(3, -3, 0), ndc(0, 3, 0)};
  EXPECT_FALSE(frustum_reject(straddling));
  ClipStats stats;
  std::vector<ScreenTriangle> out;
  EXPECT_EQ(clip_and_cull(straddling, cfg, stats, out), 1);
  EXPECT_EQ(stats.clipped, 0u);
  // Non-finite input is rejected rather than rasterised.
  const float nan = std::numeric_limits<float>::quiet_NaN();
  EXPECT_TRUE(frustum_reject({ndc(0, 0, 0), ndc(nan, 0, 0), ndc(0, 1, 0)}));
}

TEST(ClipperNear, OneVertexBehindGivesQuadWithExactVertices) {
  // w = 1 everywhere: V0 is behind the near plane (z = -3 < -w).
  const ClipTriangle t{glm::vec4(0, 0, -3, 1), glm::vec4(1, 0, 0, 1), glm::vec4(0, 1, 0, 1)};
  const ClipPolygon poly = clip_triangle(t, config(64, 64));
  ASSERT_EQ(poly.count, 4);
  EXPECT_TRUE(poly.clipped);
  // In winding order: the V0-V1 intersection, V1, V2, the V2-V0 intersection.
  const glm::dvec4 expected_pos[4] = {{2.0 / 3, 0, -1, 1}, {1, 0, 0, 1}, {0, 1, 0, 1}, {0, 2.0 / 3, -1, 1}};
  const glm::dvec3 expected_bary[4] = {{1.0 / 3, 2.0 / 3, 0}, {0, 1, 0}, {0, 0, 1}, {1.0 / 3, 0, 2.0 / 3}};
  for (int i = 0; i < 4; ++i) {
    for (int c = 0; c < 4; ++c) EXPECT_NEAR(poly.v[i].position[c], expected_pos[i][c], 1e-12) << i;
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(poly.v[i].bary[c], expected_bary[i][c], 1e-12) << i;
  }
  ClipStats stats;
  std::vector<ScreenTriangle> out;
  EXPECT_EQ(clip_and_cull(t, config(64, 64), stats, out), 2);
  EXPECT_EQ(stats.clipped, 1u);
  EXPECT_EQ(stats.out, 2u);
  EXPECT_EQ(stats.accepted(), 1u);
  // Clipped vertices lie on the near plane: window depth 0.
  EXPECT_EQ(out[0].z[0], 0.0f);
  EXPECT_NEAR(out[0].bary[0].y, 2.0f / 3.0f, 1e-6f);
}

TEST(ClipperNear, TwoVerticesBehindGivesTriangle) {
  const ClipTriangle t{glm::vec4(0, 0, 1, 1), glm::vec4(1, 0, -3, 1), glm::vec4(0, 1, -3, 1)};
  const ClipPolygon poly = clip_triangle(t, config(64, 64));
  ASSERT_EQ(poly.count, 3);
  // V0 is kept; the new vertices are at t = 2/4 along V0-V1 and V0-V2.
  EXPECT_NEAR(poly.v[0].position.x, 0.0, 1e-12);
  EXPECT_NEAR(poly.v[1].position.x, 0.5, 1e-12);
  EXPECT_NEAR(poly.v[1].position.z, -1.0, 1e-12);
  EXPECT_NEAR(poly.v[2].position.y, 0.5, 1e-12);
  EXPECT_NEAR(poly.v[2].bary.x, 0.5, 1e-12);
  EXPECT_NEAR(poly.v[2].bary.z, 0.5, 1e-12);
  ClipStats stats;
  std::vector<ScreenTriangle> out;
  EXPECT_EQ(clip_and_cull(t, config(64, 64), stats, out), 1);
  EXPECT_EQ(stats.clipped, 1u);
  // Nothing left in front: culled as outside the frustum, after clipping.
  const ClipTriangle behind{glm::vec4(0, 0, -1.5f, 1), glm::vec4(1, 0, -3, 1), glm::vec4(-5, 1, 3, -2)};
  ClipStats s2;
  EXPECT_EQ(clip_and_cull(behind, config(64, 64), s2, out), 0);
  EXPECT_EQ(s2.culled_frustum, 1u);
}

TEST(ClipperNear, ClippedCoverageEqualsFrontPartOfTriangle) {
  // w = 1 and depth depending on x only, so that the near plane cuts the triangle along a
  // vertical line at a pixel corner (never a sample) with exact intersections: the clipped
  // pieces must cover exactly the unclipped triangle's samples in front of that line.
  const Viewport vp{64, 64, kBits};  // x_fixed = (x_ndc + 1) * 8192, y_fixed = (1 - y_ndc) * 8192
  const std::int32_t x[3] = {0, 8192, 8192}, y[3] = {2048, 0, 12288};
  struct Case {
    int behind;   // vertices behind the near plane
    double cut;   // fixed-point column of the cut
    double sign;  // +1: in front to the right of the cut, -1: to the left
  };
  for (const Case& c : {Case{1, 1024.0, 1.0}, Case{2, 7168.0, -1.0}}) {
    ClipTriangle clip;
    for (int i = 0; i < 3; ++i) {
      // z_ndc = -1 exactly on the cut, > -1 in front of it.
      clip[i] = glm::vec4(static_cast<float>(x[i] / 8192.0 - 1.0), static_cast<float>(1.0 - y[i] / 8192.0),
                          static_cast<float>(c.sign * (x[i] - c.cut) / 8192.0 - 1.0), 1.0f);
    }
    std::vector<ScreenTriangle> out;
    ClipStats stats;
    clip_and_cull(clip, config(64, 64), stats, out);
    ASSERT_EQ(stats.clipped, 1u);
    ASSERT_EQ(static_cast<int>(out.size()), c.behind == 1 ? 2 : 1);
    ScreenTriangle whole;
    for (int i = 0; i < 3; ++i) {
      whole.x_fixed[i] = x[i];
      whole.y_fixed[i] = y[i];
    }
    const TriangleSetup ws = setup_triangle(whole, vp);
    for (int samples : {1, 2, 4, 8}) {
      const SamplePattern p = standard_sample_pattern(samples, kBits);
      const std::vector<int> hits = sample_hits(out, vp, p);
      int covered = 0;
      for (int py = 0; py < vp.height_px; ++py) {
        for (int px = 0; px < vp.width_px; ++px) {
          for (int s = 0; s < samples; ++s) {
            const glm::i64vec2 q = sample_position_fixed(p, px, py, s);
            const bool in_front = c.sign * (static_cast<double>(q.x) - c.cut) > 0.0;
            const int expected = (covers_point(ws, q.x, q.y) && in_front) ? 1 : 0;
            covered += expected;
            ASSERT_EQ(hits[(static_cast<size_t>(py) * vp.width_px + px) * samples + s], expected)
                << c.behind << " behind, " << samples << "x, pixel " << px << "," << py << " sample " << s;
          }
        }
      }
      EXPECT_GT(covered, 10);
    }
  }
}

TEST(ClipperNear, PerspectiveClippingMatchesRayCastAndBarycentrics) {
  const Viewport vp{64, 48, kBits};
  const glm::dmat4 proj = glm::perspective(glm::radians(60.0), 64.0 / 48.0, 0.1, 100.0);
  // Camera at the origin looking down -z; C is behind the camera (w < 0 in clip space).
  const glm::dvec3 world[3] = {{-1.0, -0.5, -3.0}, {1.5, -0.3, -2.0}, {0.2, 0.4, 1.0}};
  std::array<glm::dvec4, 3> clip_d;
  ClipTriangle clip;
  for (int i = 0; i < 3; ++i) {
    clip_d[i] = proj * glm::dvec4(world[i], 1.0);
    clip[i] = glm::vec4(clip_d[i]);
    clip_d[i] = glm::dvec4(clip[i]);  // the exact float input
  }
  ASSERT_LT(clip_d[2].w, 0.0);
  std::vector<ScreenTriangle> out;
  ClipStats stats;
  clip_and_cull(clip, config(64, 48), stats, out);
  ASSERT_EQ(stats.clipped, 1u);
  ASSERT_FALSE(out.empty());
  for (int samples : {1, 4}) {
    const SamplePattern p = standard_sample_pattern(samples, kBits);
    const std::vector<int> hits = sample_hits(out, vp, p);
    int robust_in = 0, mismatches = 0;
    for (int py = 0; py < vp.height_px; ++py) {
      for (int px = 0; px < vp.width_px; ++px) {
        for (int s = 0; s < samples; ++s) {
          const glm::i64vec2 q = sample_position_fixed(p, px, py, s);
          const int h = hits[(static_cast<size_t>(py) * vp.width_px + px) * samples + s];
          EXPECT_LE(h, 1);
          const int cls = robust_class(q.x, q.y, [&](std::int64_t x, std::int64_t y) {
            return ray_hits_front_part(clip_d, fixed_to_ndc(static_cast<double>(x), static_cast<double>(y), vp));
          });
          if (cls < 0) continue;
          robust_in += cls;
          if (h != cls) ++mismatches;
        }
      }
    }
    EXPECT_EQ(mismatches, 0) << samples << "x";
    EXPECT_GT(robust_in, 100);
  }
  // Perspective-correct weights relative to the original triangle match the ray cast.
  const SamplePattern p1 = standard_sample_pattern(1, kBits);
  double worst = 0.0;
  int checked = 0;
  for (const ScreenTriangle& t : out) {
    const TriangleSetup s = setup_triangle(t, vp);
    rasterize_in_rect(s, PixelRect{0, 0, vp.width_px, vp.height_px}, p1, [&](int x, int y, std::uint32_t, const float*) {
      const glm::i64vec2 q = sample_position_fixed(p1, x, y, 0);
      glm::dvec3 beta;
      if (!ray_hits_front_part(clip_d, fixed_to_ndc(static_cast<double>(q.x), static_cast<double>(q.y), vp), &beta)) {
        return;
      }
      const glm::vec3 w = perspective_barycentrics(s, q.x, q.y);
      for (int i = 0; i < 3; ++i) worst = std::max(worst, std::abs(static_cast<double>(w[i]) - beta[i]));
      ++checked;
    });
  }
  EXPECT_GT(checked, 100);
  EXPECT_LT(worst, 2e-3);
}

TEST(ClipperNear, MeshCrossingNearPlaneStaysWatertight) {
  // A jittered floor grid that runs from far in front of the camera to behind it.
  const Viewport vp{64, 48, kBits};
  const double fov_y = glm::radians(70.0), aspect = 64.0 / 48.0, near = 0.1;
  const glm::dmat4 proj = glm::perspective(fov_y, aspect, near, 100.0);
  const double floor_y = -0.05, x0 = -0.4, x1 = 0.4, z0 = -2.0, z1 = 0.6;
  const int nx = 10, nz = 13;
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> jitter(-0.2, 0.2);
  std::vector<std::vector<glm::vec4>> v(nz + 1, std::vector<glm::vec4>(nx + 1));
  for (int j = 0; j <= nz; ++j) {
    for (int i = 0; i <= nx; ++i) {
      double x = x0 + (x1 - x0) * i / nx, z = z0 + (z1 - z0) * j / nz;
      if (i > 0 && i < nx) x += jitter(rng) * (x1 - x0) / nx;
      if (j > 0 && j < nz) z += jitter(rng) * (z1 - z0) / nz;
      v[j][i] = glm::vec4(proj * glm::dvec4(x, floor_y, z, 1.0));
    }
  }
  std::vector<ScreenTriangle> out;
  ClipStats stats;
  const ClipConfig cfg = config(64, 48, FaceCull::None);
  for (int j = 0; j < nz; ++j) {
    for (int i = 0; i < nx; ++i) {
      const glm::vec4 a = v[j][i], b = v[j][i + 1], c = v[j + 1][i + 1], d = v[j + 1][i];
      if ((i + j) % 2) {
        clip_and_cull({a, b, c}, cfg, stats, out);
        clip_and_cull({a, c, d}, cfg, stats, out);
      } else {
        clip_and_cull({a, b, d}, cfg, stats, out);
        clip_and_cull({b, c, d}, cfg, stats, out);
      }
    }
  }
  EXPECT_GE(stats.clipped, 8u) << stats.clipped;
  const double tan_half = std::tan(fov_y / 2.0);
  auto floor_visible = [&](std::int64_t xf, std::int64_t yf) {
    const glm::dvec2 n = fixed_to_ndc(static_cast<double>(xf), static_cast<double>(yf), vp);
    const glm::dvec3 dir(n.x * tan_half * aspect, n.y * tan_half, -1.0);
    if (dir.y >= 0.0) return false;
    const glm::dvec3 hit = dir * (floor_y / dir.y);
    return hit.x >= x0 && hit.x <= x1 && hit.z >= z0 && hit.z <= z1 && -hit.z >= near;
  };
  for (int samples : {1, 4}) {
    const SamplePattern p = standard_sample_pattern(samples, kBits);
    const std::vector<int> hits = sample_hits(out, vp, p);
    int double_hits = 0, mismatches = 0, robust_in = 0;
    for (int py = 0; py < vp.height_px; ++py) {
      for (int px = 0; px < vp.width_px; ++px) {
        for (int s = 0; s < samples; ++s) {
          const glm::i64vec2 q = sample_position_fixed(p, px, py, s);
          const int h = hits[(static_cast<size_t>(py) * vp.width_px + px) * samples + s];
          double_hits += h > 1;
          const int cls = robust_class(q.x, q.y, floor_visible);
          if (cls < 0) continue;
          robust_in += cls;
          mismatches += h != cls;
        }
      }
    }
    EXPECT_EQ(double_hits, 0) << samples << "x";
    EXPECT_EQ(mismatches, 0) << samples << "x";
    EXPECT_GT(robust_in, 200);
  }
}

TEST(ClipperCull, BackFrontAndNone) {
  // Counter-clockwise in NDC (y up): front-facing in GL.
  const ClipTriangle ccw{ndc(-0.5f, -0.5f, 0), ndc(0.5f, -0.5f, 0), ndc(0, 0.5f, 0)};
  const ClipTriangle cw{ccw[0], ccw[2], ccw[1]};
  struct Case {
    FaceCull cull;
    bool front_ccw;
    int ccw_out, cw_out;
  };
  for (const Case& c : {Case{FaceCull::Back, true, 1, 0}, Case{FaceCull::Front, true, 0, 1},
                        Case{FaceCull::None, true, 1, 1}, Case{FaceCull::Back, false, 0, 1}}) {
    ClipConfig cfg = config(32, 32, c.cull);
    cfg.front_ccw = c.front_ccw;
    ClipStats stats;
    std::vector<ScreenTriangle> out;
    EXPECT_EQ(clip_and_cull(ccw, cfg, stats, out), c.ccw_out) << to_string(c.cull);
    if (c.ccw_out) {
      EXPECT_EQ(out.back().front_facing, c.front_ccw);
      // In our y-down screen space a GL counter-clockwise triangle has negative signed area.
      const ScreenTriangle& t = out.back();
      EXPECT_LT(signed_area_x2(t.x_fixed[0], t.y_fixed[0], t.x_fixed[1], t.y_fixed[1], t.x_fixed[2], t.y_fixed[2]), 0);
    }
    EXPECT_EQ(clip_and_cull(cw, cfg, stats, out), c.cw_out) << to_string(c.cull);
    if (c.cw_out) {
      EXPECT_EQ(out.back().front_facing, !c.front_ccw);
    }
    EXPECT_EQ(stats.culled_backface, static_cast<std::uint64_t>(2 - c.ccw_out - c.cw_out));
    EXPECT_EQ(stats.in, 2u);
  }
}

TEST(ClipperCull, ZeroAreaTrianglesAreCulledAndCounted) {
  ClipStats stats;
  std::vector<ScreenTriangle> out;
  const ClipConfig cfg = config(32, 32, FaceCull::None);
  // Collinear.
  EXPECT_EQ(clip_and_cull({ndc(-0.5f, -0.5f, 0), ndc(0, 0, 0), ndc(0.5f, 0.5f, 0)}, cfg, stats, out), 0);
  // Non-degenerate in float, but all three vertices snap to the same fixed-point position.
  const float e = 1e-5f;
  EXPECT_EQ(clip_and_cull({ndc(0.1f, 0.1f, 0), ndc(0.1f + e, 0.1f, 0), ndc(0.1f, 0.1f + e, 0)}, cfg, stats, out), 0);
  EXPECT_EQ(stats.culled_zero_area, 2u);
  EXPECT_EQ(stats.culled_backface, 0u);
  EXPECT_EQ(stats.accepted(), 0u);
}

TEST(ClipperViewport, TransformIsYDownWithSubpixelFixedPoint) {
  const Viewport vp{1920, 1080, 8};
  const ScreenVertex tl = viewport_transform(glm::dvec4(-2.0, 2.0, -2.0, 2.0), vp);  // NDC (-1, 1, -1)
  EXPECT_EQ(tl.x_fixed, 0);
  EXPECT_EQ(tl.y_fixed, 0);
  EXPECT_EQ(tl.z, 0.0f);
  EXPECT_EQ(tl.inv_w, 0.5f);
  const ScreenVertex br = viewport_transform(glm::dvec4(1.0, -1.0, 1.0, 1.0), vp);
  EXPECT_EQ(br.x_fixed, 1920 * 256);
  EXPECT_EQ(br.y_fixed, 1080 * 256);
  EXPECT_EQ(br.z, 1.0f);
  const ScreenVertex c = viewport_transform(glm::dvec4(0.0, 0.0, 0.0, 4.0), vp);
  EXPECT_EQ(c.x_fixed, 960 * 256);
  EXPECT_EQ(c.y_fixed, 540 * 256);
  EXPECT_EQ(c.z, 0.5f);
  // Rounding to the nearest sub-pixel unit: 1/3 px from the left in a 3 px wide viewport.
  const Viewport small{3, 3, 8};
  const ScreenVertex r = viewport_transform(glm::dvec4(-1.0 + 2.0 / 9.0, 0.0, 0.0, 1.0), small);
  EXPECT_EQ(r.x_fixed, 85);  // 85.33 -> 85
  const ScreenVertex r4 = viewport_transform(glm::dvec4(-1.0 + 2.0 / 9.0, 0.0, 0.0, 1.0), Viewport{3, 3, 4});
  EXPECT_EQ(r4.x_fixed, 5);  // 5.33 -> 5
}

TEST(ClipperFar, ClipOrRejectOnly) {
  // A triangle reaching beyond the far plane (z > w at one vertex).
  const ClipTriangle t{ndc(-0.5f, -0.5f, 0.5f), ndc(0.5f, -0.5f, 0.5f), ndc(0, 0.5f, 3.0f)};
  ClipConfig cfg = config(32, 32, FaceCull::None);
  {
    ClipStats stats;
    std::vector<ScreenTriangle> out;
    EXPECT_EQ(clip_and_cull(t, cfg, stats, out), 2);
    EXPECT_EQ(stats.clipped, 1u);
    for (const ScreenTriangle& s : out) {
      for (float z : s.z) {
        EXPECT_LE(z, 1.0f);
      }
    }
  }
  cfg.far_plane = FarPlaneMode::RejectOnly;
  {
    ClipStats stats;
    std::vector<ScreenTriangle> out;
    EXPECT_EQ(clip_and_cull(t, cfg, stats, out), 1);
    EXPECT_EQ(stats.clipped, 0u);
    EXPECT_EQ(out[0].z[2], 2.0f);  // 3 * 0.5 + 0.5: beyond the depth range, kept for the depth test
  }
  EXPECT_STREQ(to_string(FarPlaneMode::RejectOnly), "reject");
}

TEST(ClipperGuardBand, HugeTrianglesAreClippedToTheBandAndStayWatertight) {
  const Viewport vp{40, 30, kBits};
  ClipConfig cfg = config(40, 30, FaceCull::None);
  // Within the default band: not clipped. Beyond an explicit band of 3 viewports: clipped.
  const ClipTriangle big{ndc(-50, -50, 0), ndc(50, -50, 0), ndc(0, 50, 0)};
  {
    ClipStats stats;
    std::vector<ScreenTriangle> out;
    clip_and_cull(big, cfg, stats, out);
    EXPECT_EQ(stats.clipped, 0u);
  }
  cfg.guard_band_ndc = 3.0;
  EXPECT_EQ(guard_band_ndc(cfg), 3.0);
  {
    ClipStats stats;
    std::vector<ScreenTriangle> out;
    clip_and_cull(big, cfg, stats, out);
    EXPECT_EQ(stats.clipped, 1u);
    for (const ScreenTriangle& t : out) {
      for (int k = 0; k < 3; ++k) {
        EXPECT_LE(std::abs(t.x_fixed[k] - 20 * kOne), 4 * 20 * kOne + 1);
        EXPECT_LE(std::abs(t.y_fixed[k] - 15 * kOne), 4 * 15 * kOne + 1);
      }
    }
  }
  // Two enormous triangles (one vertex far outside any band) sharing a diagonal cover every
  // sample of the viewport exactly once.
  cfg.guard_band_ndc = 0.0;
  std::vector<ScreenTriangle> out;
  ClipStats stats;
  const float far_out = 1e7f;
  clip_and_cull({ndc(-1, -1, 0), ndc(far_out, -1, 0), ndc(-1, far_out, 0)}, cfg, stats, out);
  clip_and_cull({ndc(far_out, -1, 0), ndc(far_out, far_out, 0), ndc(-1, far_out, 0)}, cfg, stats, out);
  EXPECT_EQ(stats.clipped, 2u);
  for (int samples : {1, 4}) {
    const std::vector<int> hits = sample_hits(out, vp, standard_sample_pattern(samples, kBits));
    for (size_t i = 0; i < hits.size(); ++i) ASSERT_EQ(hits[i], 1) << samples << "x sample index " << i;
  }
}

TEST(ClipperStats, EveryTriangleEndsInOneBucket) {
  std::mt19937 rng(2);
  std::uniform_real_distribution<float> u(-3.0f, 3.0f), w(-0.5f, 3.0f);
  ClipStats total;
  std::vector<ScreenTriangle> out;
  const ClipConfig cfg = config(50, 40, FaceCull::Back);
  for (int i = 0; i < 2000; ++i) {
    ClipTriangle t;
    for (auto& v : t) v = glm::vec4(u(rng), u(rng), u(rng), w(rng));
    // clip_and_cull adds to the counts it is given: this triangle's share is after - before.
    const ClipStats before = total;
    const int n = clip_and_cull(t, cfg, total, out);
    EXPECT_EQ(total.in - before.in, 1u);
    EXPECT_EQ((total.culled() - before.culled()) + (total.accepted() - before.accepted()), 1u);
    EXPECT_EQ(total.out - before.out, static_cast<std::uint64_t>(n));
    EXPECT_EQ(n > 0, total.accepted() - before.accepted() == 1u);
  }
  EXPECT_EQ(total.in, 2000u);
  EXPECT_EQ(total.out, out.size());
  EXPECT_GT(total.culled_frustum, 0u);
  EXPECT_GT(total.culled_backface, 0u);
  EXPECT_GT(total.clipped, 0u);
  EXPECT_GT(total.accepted(), 0u);
  for (const ScreenTriangle& t : out) {
    EXPECT_TRUE(t.front_facing);
    for (int k = 0; k < 3; ++k) {
      EXPECT_LE(std::abs(static_cast<std::int64_t>(t.x_fixed[k])), kMaxFixedCoord);
      EXPECT_NEAR(t.bary[k].x + t.bary[k].y + t.bary[k].z, 1.0f, 1e-5f);
      EXPECT_GE(t.z[k], 0.0f);
      EXPECT_LE(t.z[k], 1.0f);
    }
  }
}

}  // namespace
}  // namespace tbdr
