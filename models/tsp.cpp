#include "models/tsp.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <limits>
#include <optional>
#include <span>
#include <stdexcept>
#include <thread>

#if defined(__SSE2__)
#include <xmmintrin.h>
#endif

#include "kernel/bits.hpp"
#include "models/light_lists.hpp"
#include "models/shading.hpp"
#include "models/texture_unit.hpp"

namespace tbdr {

LitSampleLedger::LitSampleLedger(int width, int height, int samples)
    : blocks_x_(static_cast<std::size_t>((width + kBlockMask) >> kBlockBits)),
      samples_(static_cast<std::size_t>(samples)),
      block_entries_((std::size_t{1} << (2 * kBlockBits)) * static_cast<std::size_t>(samples)) {
  blocks_ = blocks_x_ * static_cast<std::size_t>((height + kBlockMask) >> kBlockBits);
  held_.reset(new std::uint32_t[blocks_ * block_entries_]);  // default-initialised: untouched until zeroed
  state_ = std::make_unique<std::atomic<std::uint8_t>[]>(blocks_);
  wide_ = std::make_unique<std::atomic<std::uint64_t*>[]>(blocks_);
  for (std::size_t b = 0; b < blocks_; ++b) {
    state_[b].store(kUntouched, std::memory_order_relaxed);
    wide_[b].store(nullptr, std::memory_order_relaxed);
  }
}

LitSampleLedger::~LitSampleLedger() {
  for (std::size_t b = 0; b < blocks_; ++b) delete[] wide_[b].load(std::memory_order_relaxed);
}

void LitSampleLedger::make_ready(std::size_t b) {
  std::uint8_t expected = kUntouched;
  if (state_[b].compare_exchange_strong(expected, kZeroing, std::memory_order_acq_rel, std::memory_order_acquire)) {
    std::fill_n(held_.get() + b * block_entries_, block_entries_, std::uint32_t{0});
    state_[b].store(kReady, std::memory_order_release);
    return;
  }
  while (state_[b].load(std::memory_order_acquire) != kReady) std::this_thread::yield();  // another tile's thread zeroes it
}

void LitSampleLedger::add_wide(std::uint32_t& held, std::size_t b, std::size_t i, std::uint64_t lights) {
  std::uint64_t* wide = wide_[b].load(std::memory_order_acquire);
  if (wide == nullptr) {
    // Made once per block (tiles sharing the block use different entries of it).
    auto* fresh = new std::uint64_t[block_entries_]();
    std::uint64_t* expected = nullptr;
    if (wide_[b].compare_exchange_strong(expected, fresh, std::memory_order_acq_rel, std::memory_order_acquire)) {
      wide = fresh;
    } else {
      delete[] fresh;
      wide = expected;
    }
  }
  std::uint64_t& w = wide[i];
  if (held != kWide) {
    w = std::uint64_t{held >> kLightBits} << kWideLightBits | (held & kLightMask);
    held = kWide;
  }
  const std::uint64_t count = w >> kWideLightBits, sum = w & kWideLightMask;
  if (count + 1 >= (std::uint64_t{1} << kWideCountBits) || lights > kWideLightMask - sum) {
    throw std::overflow_error("LitSampleLedger: a sample holds more than 2^24 lit colour writes or 2^40 of their lights");
  }
  w += (std::uint64_t{1} << kWideLightBits) + lights;
}

Tsp::Tsp(RenderContext& ctx) : ctx_(ctx), texture_lines_out_(ctx.texture_lines), dram_out_(ctx.dram) {}

void Tsp::bind_outputs(std::vector<std::uint64_t>* texture_lines, DramTraffic* dram) {
  texture_lines_out_ = texture_lines;
  dram_out_ = dram;
}

namespace {

/// The lights one fragment evaluates: either an explicit list, or "every selected light" (whose
/// contributions are summed through the exact screen-tile candidates).
struct FragmentLights {
  const std::vector<std::uint32_t>* list = nullptr;  ///< explicit list, or null
  std::int32_t single = -1;                          ///< one light (proxy)
  bool all_selected = false;                         ///< every light of the draw's selection
  std::uint64_t count = 0;                           ///< lights charged
};

/// The perspective-correct uv of a triangle anywhere on its plane: the same interpolation as
/// perspective_barycentrics (screen-linear weights over w, renormalised) written as a ratio of
/// screen-linear functions, uv = N(X, Y) / D(X, Y), so that points outside the triangle (helper
/// lanes) cost a few multiply-adds.
struct UvPlane {
  double inv_area = 0;
  double d0 = 0, d1 = 0, d2 = 0;  ///< D = d0 + l1 d1 + l2 d2, l = screen barycentric weights
  double u0 = 0, u1 = 0, u2 = 0;  ///< N_u, the same way
  double v0 = 0, v1 = 0, v2 = 0;  ///< N_v

  UvPlane(const TriangleSetup& t, const std::array<glm::vec2, 3>& uv) {
    inv_area = t.area_x2 > 0 ? 1.0 / static_cast<double>(t.area_x2) : 0.0;
    double at_u[3], at_v[3];  // uv at the setup's (clipped, reordered) vertices, times 1/w
    for (int k = 0; k < 3; ++k) {
      const double b0 = t.bary[k].x, b1 = t.bary[k].y, b2 = t.bary[k].z, q = t.inv_w[k];
      at_u[k] = (uv[0].x * b0 + uv[1].x * b1 + uv[2].x * b2) * q;
      at_v[k] = (uv[0].y * b0 + uv[1].y * b1 + uv[2].y * b2) * q;
    }
    d0 = t.inv_w[0];
    d1 = t.inv_w[1] - d0;
    d2 = t.inv_w[2] - d0;
    u0 = at_u[0];
    u1 = at_u[1] - u0;
    u2 = at_u[2] - u0;
    v0 = at_v[0];
    v1 = at_v[1] - v0;
    v2 = at_v[2] - v0;
  }
  /// uv at fixed-point (X, Y), from the raw edge values E1, E2 there.
  glm::vec2 at(std::int64_t e1, std::int64_t e2) const {
    const double l1 = static_cast<double>(e1) * inv_area, l2 = static_cast<double>(e2) * inv_area;
    const double inv_d = 1.0 / (d0 + l1 * d1 + l2 * d2);
    return {static_cast<float>((u0 + l1 * u1 + l2 * u2) * inv_d), static_cast<float>((v0 + l1 * v1 + l2 * v2) * inv_d)};
  }
};

/// The uvs of a quad's 4 pixel centres from its first pixel's edge values and the edge steps of
/// one pixel right (e?x) and down (e?y). The weights are carried from the first pixel in single
/// precision (fp32, as a GPU interpolates), 4 lanes at a time where SSE2 is available.
class QuadUv {
 public:
  QuadUv(const UvPlane& plane, std::int64_t e1x, std::int64_t e1y, std::int64_t e2x, std::int64_t e2y)
      : plane_(plane), e1x_(e1x), e1y_(e1y), e2x_(e2x), e2y_(e2y) {
#if defined(__SSE2__)
    const auto f = [](double v) { return static_cast<float>(v); };
    const double ia = plane.inv_area;
    const double l1x = static_cast<double>(e1x) * ia, l1y = static_cast<double>(e1y) * ia;
    const double l2x = static_cast<double>(e2x) * ia, l2y = static_cast<double>(e2y) * ia;
    l1_step_ = _mm_setr_ps(0.0f, f(l1x), f(l1y), f(l1x + l1y));
    l2_step_ = _mm_setr_ps(0.0f, f(l2x), f(l2y), f(l2x + l2y));
    d_[0] = _mm_set1_ps(f(plane.d0));
    d_[1] = _mm_set1_ps(f(plane.d1));
    d_[2] = _mm_set1_ps(f(plane.d2));
    u_[0] = _mm_set1_ps(f(plane.u0));
    u_[1] = _mm_set1_ps(f(plane.u1));
    u_[2] = _mm_set1_ps(f(plane.u2));
    v_[0] = _mm_set1_ps(f(plane.v0));
    v_[1] = _mm_set1_ps(f(plane.v1));
    v_[2] = _mm_set1_ps(f(plane.v2));
#endif
  }
  /// uv[lane] for the pixels (x,y), (x+1,y), (x,y+1), (x+1,y+1) given E1, E2 at (x,y).
  void at(std::int64_t e1, std::int64_t e2, std::array<glm::vec2, 4>& uv) const {
#if defined(__SSE2__)
    const double ia = plane_.inv_area;
    const __m128 l1 = _mm_add_ps(_mm_set1_ps(static_cast<float>(static_cast<double>(e1) * ia)), l1_step_);
    const __m128 l2 = _mm_add_ps(_mm_set1_ps(static_cast<float>(static_cast<double>(e2) * ia)), l2_step_);
    auto plane = [&](const __m128* c) { return _mm_add_ps(_mm_add_ps(c[0], _mm_mul_ps(l1, c[1])), _mm_mul_ps(l2, c[2])); };
    const __m128 inv_d = _mm_div_ps(_mm_set1_ps(1.0f), plane(d_));
    const __m128 u = _mm_mul_ps(plane(u_), inv_d), v = _mm_mul_ps(plane(v_), inv_d);
    _mm_storeu_ps(&uv[0].x, _mm_unpacklo_ps(u, v));
    _mm_storeu_ps(&uv[2].x, _mm_unpackhi_ps(u, v));
#else
    uv = {plane_.at(e1, e2), plane_.at(e1 + e1x_, e2 + e2x_), plane_.at(e1 + e1y_, e2 + e2y_),
          plane_.at(e1 + e1x_ + e1y_, e2 + e2x_ + e2y_)};
#endif
  }

 private:
  const UvPlane& plane_;
  std::int64_t e1x_, e1y_, e2x_, e2y_;
#if defined(__SSE2__)
  __m128 l1_step_, l2_step_;
  __m128 d_[3], u_[3], v_[3];
#endif
};

/// Perspective-correct barycentrics of a scene triangle at pixel (x, y)'s centre.
inline glm::vec3 pixel_barycentrics(const Primitive& p, std::int32_t x, std::int32_t y) {
  const int bits = p.setup.subpixel_bits;
  const std::int64_t half = std::int64_t{1} << (bits - 1);
  return perspective_barycentrics(p.setup, (std::int64_t{x} << bits) + half, (std::int64_t{y} << bits) + half);
}

/// The world position and the uv at barycentrics `b` of a scene triangle.
inline glm::vec3 position_at(const Primitive& p, glm::vec3 b) { return p.world[0] * b.x + p.world[1] * b.y + p.world[2] * b.z; }
inline glm::vec2 uv_at(const Primitive& p, glm::vec3 b) { return p.uv[0] * b.x + p.uv[1] * b.y + p.uv[2] * b.z; }

/// World position of a scene triangle's surface at pixel (x, y)'s centre: the one expression the
/// shading loop and the batch's bounds both use.
inline glm::vec3 triangle_position(const Primitive& p, std::int32_t x, std::int32_t y) {
  return position_at(p, pixel_barycentrics(p, x, y));
}

/// Asks the host processor to bring the cache line at `p` in for a read soon (nothing when null,
/// or where the compiler has no prefetch builtin). Host speed only.
inline void prefetch_for_read(const void* p) {
#if defined(__GNUC__)
  if (p != nullptr) __builtin_prefetch(p, 0, 3);
#else
  (void)p;
#endif
}

/// Relative widening of a light's radius^2 in the colour loop's pre-tests (the box test and the
/// vectorised per-fragment test): they may keep a light the exact test then rejects, never drop
/// one it accepts, whatever the rounding of their float arithmetic (errors of a few ulp, 1e-7
/// relative, against this 1e-4). The exact test is ShadingModel::lit_contribution's own.
constexpr float kReachMargin = 1.0001f;

/// Up to this many selected lights, an "every light" shader's colour loop tests each selected
/// light at the surface instead of cutting the screen bin's candidates to the batch's box: with a
/// handful the cut costs more than it saves (forward_multipass's one light per pass). Host speed
/// only: either way the same lights add the same contributions in the same order.
constexpr std::size_t kDirectLights = 8;

/// Widening of a triangle's world box for may_reach_triangle, relative to its largest coordinate
/// (ten times the rounding it covers, 1e-6).
constexpr float kTriangleBoxMargin = 1e-5f;

}  // namespace

bool may_reach_triangle(const Primitive& p, std::span<const std::uint32_t> reach, const std::vector<Light>& lights) {
  glm::vec3 lo = glm::min(glm::min(p.world[0], p.world[1]), p.world[2]);
  glm::vec3 hi = glm::max(glm::max(p.world[0], p.world[1]), p.world[2]);
  const glm::vec3 big = glm::max(glm::abs(lo), glm::abs(hi));
  const float widen = std::max({big.x, big.y, big.z}) * kTriangleBoxMargin;
  lo -= widen;
  hi += widen;
  for (const std::uint32_t l : reach) {
    const Light& light = lights[l];
    // Squared distance from the light to the box (0 inside).
    const glm::vec3 e = glm::max(glm::max(lo - light.position, light.position - hi), glm::vec3(0.0f));
    if (!(glm::dot(e, e) >= light.radius * light.radius * kReachMargin)) return true;
  }
  return false;
}

bool Tsp::surface_bounds(const Primitive& p, const DrawContext& d, std::span<const ShadePixel> pixels, glm::vec3& lo,
                         glm::vec3& hi) const {
  const int W = ctx_.viewport.width_px;
  lo = glm::vec3(std::numeric_limits<float>::infinity());
  hi = -lo;
  bool any = false;
  auto add = [&](glm::vec3 q) {
    lo = glm::min(lo, q);
    hi = glm::max(hi, q);
    any = true;
  };
  const bool from_triangle = p.material != kNoMaterial && ctx_.scene != nullptr;
  const ShaderDesc& sh = *d.shader;
  const bool pls_reads = ctx_.pls && (sh.pls == PlsAccess::Read || sh.pls == PlsAccess::ReadWrite);
  for (const ShadePixel& px : pixels) {
    const std::size_t pixel = static_cast<std::size_t>(px.y) * static_cast<std::size_t>(W) + static_cast<std::size_t>(px.x);
    if (from_triangle) {
      add(triangle_position(p, px.x, px.y));
    } else if (d.surface_source) {
      const std::size_t k = pixel * d.surface_source->samples;
      if (d.surface_source->surface_valid[k]) add(d.surface_source->surface.site(k).position);
    } else if (pls_reads && ctx_.pls->valid[pixel]) {
      add(ctx_.pls->surface.site(pixel).position);
    }
  }
  return any;
}

void Tsp::gather_near_lights(const std::vector<std::uint32_t>& bin, const DrawContext& d, glm::vec3 lo, glm::vec3 hi) {
  const auto& lights = *ctx_.lights;
  near_.bin = &bin;
  near_.index.clear();
  near_.x.clear();
  near_.y.clear();
  near_.z.clear();
  near_.reach2.clear();
  for (std::uint32_t l : bin) {
    if (!d.light_selected[l]) continue;
    const Light& light = lights[l];
    // Squared distance from the light to the box (0 inside): beyond its radius, the light reaches
    // none of the batch's surfaces.
    const glm::vec3 e = glm::max(glm::max(lo - light.position, light.position - hi), glm::vec3(0.0f));
    const float r2 = light.radius * light.radius * kReachMargin;
    if (!(glm::dot(e, e) < r2)) continue;
    near_.index.push_back(l);
    near_.x.push_back(light.position.x);
    near_.y.push_back(light.position.y);
    near_.z.push_back(light.position.z);
    near_.reach2.push_back(r2);
  }
  near_.hit.resize(near_.index.size());
}

glm::vec3 Tsp::near_lighting(const SurfacePoint& s, glm::vec3 eye) {
  const std::size_t n = near_.index.size();
  const float sx = s.position.x, sy = s.position.y, sz = s.position.z;
  const float* __restrict lx = near_.x.data();
  const float* __restrict ly = near_.y.data();
  const float* __restrict lz = near_.z.data();
  const float* __restrict r2 = near_.reach2.data();
  std::uint8_t* __restrict hit = near_.hit.data();
  // The radius pre-test over every near light (no branches: the compiler vectorises it).
  for (std::size_t j = 0; j < n; ++j) {
    const float dx = lx[j] - sx, dy = ly[j] - sy, dz = lz[j] - sz;
    hit[j] = static_cast<std::uint8_t>(dx * dx + dy * dy + dz * dz < r2[j]);
  }
  // The exact contribution of the lights that may reach (in order: the same sum as every light's).
  const auto& lights = *ctx_.lights;
  glm::vec3 c(0.0f);
  for (std::size_t j = 0; j < n; ++j) {
    if (hit[j]) c += ShadingModel::lit_contribution(s, eye, lights[near_.index[j]]);
  }
  return c;
}

void Tsp::texture_addresses(const Primitive& p, std::uint32_t tex_fetches, std::size_t quads, TspStats& stats) {
  // The uvs at the 4 pixel centres of every launched quad (helper lanes extrapolate the
  // triangle's plane, as hardware does) give the LOD and bilinear footprint each fetch slot reads.
  const int bits = p.setup.subpixel_bits;
  const std::int64_t half = std::int64_t{1} << (bits - 1);
  const TextureLayout& layout = *ctx_.textures;
  const TextureStorage& tex = layout.of_material(p.material);
  std::vector<std::uint64_t>& lines = *texture_lines_out_;
  // The tile's list keeps each line once: a small direct-mapped filter drops most repeats before
  // they are appended (the list is sorted and merged at the end of the tile). A list emptied by
  // the caller starts a new tile.
  if (lines.empty()) {
    if (++line_filter_epoch_ == 0) {
      line_filter_.fill({});
      line_filter_epoch_ = 1;
    }
  }
  const UvPlane plane(p.setup, p.uv);
  const std::int64_t step = std::int64_t{1} << bits;  // one pixel in fixed point
  const std::int64_t e1x = p.setup.a[1] * step, e1y = p.setup.b[1] * step;
  const std::int64_t e2x = p.setup.a[2] * step, e2y = p.setup.b[2] * step;
  const QuadUv quad_uv(plane, e1x, e1y, e2x, e2y);
  // Quads come in raster order: most of a quad's lines are its left neighbour's, already in the
  // list; only the blocks it adds are looked up.
  QuadFootprint* fp = &footprints_[0];
  QuadFootprint* prev = &footprints_[1];
  prev->blocks = false;  // nothing to compare the first quad with
  prev->count = 0;
  std::array<std::uint64_t, 16> fresh;
  std::uint64_t accesses = 0;
  for (std::size_t q = 0; q < quads; ++q) {
    const std::int64_t qx = static_cast<std::int64_t>(quad_seen_[q] & 0xffffffffu) * 2;
    const std::int64_t qy = static_cast<std::int64_t>(quad_seen_[q] >> 32) * 2;
    const std::int64_t x0 = (qx << bits) + half, y0 = (qy << bits) + half;
    const std::int64_t e1 = edge_value(p.setup, 1, x0, y0), e2 = edge_value(p.setup, 2, x0, y0);
    std::array<glm::vec2, 4> uv;
    quad_uv.at(e1, e2, uv);
    layout.quad_blocks(tex, uv, *fp);
    accesses += fp->count;
    std::uint32_t n = fp->count;
    const std::uint64_t* new_lines = fp->lines.data();
    if (fp->blocks) {
      const std::uint64_t added = layout.new_blocks(tex, *prev, *fp);
      n = added != 0 ? layout.block_lines(tex, *fp, added, fresh.data()) : 0;
      new_lines = fresh.data();
    }
    std::swap(fp, prev);
    for (std::uint32_t j = 0; j < n; ++j) {
      const std::uint64_t line = new_lines[j];
      LineFilterEntry& e = line_filter_[(line * 0x9E3779B97F4A7C15ull) >> (64 - kLineFilterBits)];
      if (e.epoch == line_filter_epoch_ && e.line == line) continue;
      e = {line, line_filter_epoch_};
      // Every fetch slot reads its own copy: the same line offset by whole copies.
      for (std::uint32_t k = 0; k < tex_fetches; ++k) lines.push_back(line + std::uint64_t{k} * tex.slot_bytes);
    }
  }
  stats.texture_line_accesses += accesses * tex_fetches;
}

namespace {
/// launched_quads, with the keys written (kKeys) or only counted where the bitmap holds them.
template <bool kKeys>
std::size_t launched_quads_in(std::span<const ShadePixel> pixels, std::vector<std::uint64_t>& quads) {
  quads.clear();
  const auto key = [](std::int32_t qx, std::int32_t qy) {
    return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(qy)) << 32) | static_cast<std::uint32_t>(qx);
  };
  // A batch within a box of at most 64 x 64 quads (a tile's batch: 32-pixel tiles span 16 x 16):
  // one bit per quad of the box, a row of quads per word, read back row by row and bit by bit,
  // which is ascending key order whatever the pixels' order. Any other batch: the merge below.
  constexpr std::int32_t kBoxQuads = 64;
  if (!pixels.empty()) {
    std::int32_t x_lo = pixels[0].x, x_hi = x_lo, y_lo = pixels[0].y, y_hi = y_lo;
    for (const ShadePixel& px : pixels) {
      x_lo = std::min(x_lo, px.x);
      x_hi = std::max(x_hi, px.x);
      y_lo = std::min(y_lo, px.y);
      y_hi = std::max(y_hi, px.y);
    }
    const std::int32_t qx0 = x_lo >> 1, qy0 = y_lo >> 1;
    // (Negative coordinates keep the merge: their keys do not sort as their quads' rows.)
    if (x_lo >= 0 && y_lo >= 0 && (x_hi >> 1) - qx0 < kBoxQuads && (y_hi >> 1) - qy0 < kBoxQuads) {
      std::array<std::uint64_t, kBoxQuads> rows;
      const auto n_rows = static_cast<std::size_t>((y_hi >> 1) - qy0 + 1);
      std::fill_n(rows.begin(), n_rows, std::uint64_t{0});
      // A quad row's bits gather in a register while its pixels come one after another (they
      // mostly do: rows in order), not through memory pixel by pixel.
      std::size_t row = static_cast<std::size_t>((pixels[0].y >> 1) - qy0);
      std::uint64_t bits = 0;
      for (const ShadePixel& px : pixels) {
        const auto r = static_cast<std::size_t>((px.y >> 1) - qy0);
        if (r != row) {
          rows[row] |= bits;
          bits = 0;
          row = r;
        }
        bits |= std::uint64_t{1} << ((px.x >> 1) - qx0);
      }
      rows[row] |= bits;
      if constexpr (!kKeys) {
        std::size_t n = 0;
        for (std::size_t r = 0; r < n_rows; ++r) n += bit_count(rows[r]);
        return n;
      }
      for (std::size_t r = 0; r < n_rows; ++r) {
        const auto qy = qy0 + static_cast<std::int32_t>(r);
        for (std::uint64_t m = rows[r]; m != 0; m &= m - 1) quads.push_back(key(qx0 + std::countr_zero(m), qy));
      }
      return quads.size();
    }
  }
  // Pixels come sorted by row then column: a quad row is at most two pixel rows, each ascending
  // in x, so one merge of the two yields its quads in order, each once.
  const std::size_t n = pixels.size();
  std::size_t i = 0;
  bool ordered = true;
  while (i < n && ordered) {
    const std::size_t a0 = i;
    while (i < n && pixels[i].y == pixels[a0].y) ++i;
    const std::size_t a1 = i, b0 = i;
    while (i < n && pixels[i].y == pixels[b0].y && (pixels[i].y >> 1) == (pixels[a0].y >> 1)) ++i;
    const std::size_t b1 = i;
    const std::int32_t last_row = b1 > b0 ? pixels[b0].y : pixels[a0].y;
    if ((b1 > b0 && pixels[b0].y < pixels[a0].y) || (i < n && pixels[i].y <= last_row)) ordered = false;
    const std::int32_t qy = pixels[a0].y >> 1;
    std::size_t a = a0, b = b0;
    std::int32_t last = std::numeric_limits<std::int32_t>::min(), prev_a = last, prev_b = last;
    while (a < a1 || b < b1) {
      std::int32_t qx;
      if (b == b1 || (a < a1 && pixels[a].x <= pixels[b].x)) {
        if (pixels[a].x <= prev_a) ordered = false;
        prev_a = pixels[a].x;
        qx = pixels[a++].x >> 1;
      } else {
        if (pixels[b].x <= prev_b) ordered = false;
        prev_b = pixels[b].x;
        qx = pixels[b++].x >> 1;
      }
      if (qx != last) quads.push_back(key(qx, qy));
      last = qx;
    }
  }
  if (!ordered) {  // a caller broke the order: sort instead (same result)
    quads.clear();
    for (const ShadePixel& px : pixels) quads.push_back(key(px.x >> 1, px.y >> 1));
    std::sort(quads.begin(), quads.end());
    quads.erase(std::unique(quads.begin(), quads.end()), quads.end());
  }
  return quads.size();
}
}  // namespace

std::size_t launched_quads(std::span<const ShadePixel> pixels, std::vector<std::uint64_t>& quads) {
  return launched_quads_in<true>(pixels, quads);
}

std::size_t launched_quad_count(std::span<const ShadePixel> pixels, std::vector<std::uint64_t>& scratch) {
  return launched_quads_in<false>(pixels, scratch);
}

/// One batch's decoded state: what the TSP's sequencer knows of a primitive's draw (shader,
/// outputs, blending, PLS access, light source) before it launches the batch's quads, and the way
/// the batch's fragments go. Made once per batch (Tsp::shade), read by every step after it.
/// Refers to itself (reach_lights, quad_uv): neither copied nor moved.
struct Tsp::Batch {
  Batch(const RenderContext& ctx, std::uint32_t prim_index, std::span<const ShadePixel> batch_pixels, bool lines_bound,
        std::optional<Format> accum_format);
  Batch(const Batch&) = delete;
  Batch& operator=(const Batch&) = delete;

  const Primitive& p;
  const DrawContext& d;
  const ShaderDesc& sh;
  std::span<const ShadePixel> pixels;
  const std::vector<Light>& lights;
  glm::vec3 eye;
  int W = 0;  ///< frame width in pixels
  int S = 0;  ///< samples per pixel
  /// Colours only when someone reads them (FrameInputs::colour): without, the same work is counted
  /// and the same surfaces, coverage and light stacks are kept, but no light is summed.
  bool colour = false;
  bool image_counters = false;
  bool from_triangle = false;      ///< a scene triangle (not a light volume or full-screen pass)
  bool texture_footprint = false;  ///< texture addresses of a scene triangle are generated
  const Material* mat = nullptr;
  const AlphaMask* mask_tex = nullptr;
  bool pls_reads = false, pls_writes = false;
  std::uint64_t pls_bytes = 0;  ///< the pass's PLS layout per pixel
  int bits = 0;                 ///< subpixel bits of the setup
  std::int64_t half = 0;        ///< half a pixel in fixed point
  std::uint32_t outputs = 0;    ///< colour outputs written
  std::uint32_t out_bytes_per_sample = 0;
  BlendMode blend = BlendMode::Off;
  LitSampleLedger* ledger = nullptr;
  bool lit_surface = false, replaces_colour = false, ledger_tracks = false;
  bool writes_kept_surface = false, reads_loaded_surface = false;
  std::optional<Format> pls_accum_format;
  bool stores_pls_surface = false, builds_surface = false, stores_surface = false;
  std::optional<UvPlane> uv_plane;
  std::optional<QuadUv> quad_uv;
  std::uint32_t proxy_light = 0;
  std::span<const std::uint32_t> reach_lights;  ///< empty: no reach test
  bool triangle_out_of_reach = false;
  bool volume_adds_light = false, volume_accumulates = false, counts_only = false;
  const ColorTexels* texels_first = nullptr;
  /// The batch's surface box, made when the colour loop first needs it.
  mutable std::optional<std::pair<glm::vec3, glm::vec3>> bounds;

  /// Whether reach_lights is not empty and none of its lights reaches `position`.
  bool out_of_reach_at(const glm::vec3& position) const {
    return !reach_lights.empty() &&
           std::none_of(reach_lights.begin(), reach_lights.end(), [&](std::uint32_t l) { return ShadingModel::reaches(lights[l], position); });
  }

 private:
  void decode_outputs(const RenderContext& ctx);
  void decode_surface_needs(const RenderContext& ctx);
  void decode_reach_test(const RenderContext& ctx);
  void decode_counts_only(const RenderContext& ctx);
};

Tsp::Batch::Batch(const RenderContext& ctx, std::uint32_t prim_index, std::span<const ShadePixel> batch_pixels,
                  bool lines_bound, std::optional<Format> accum_format)
    : p(ctx.prims[prim_index]),
      d(ctx.draws[p.draw]),
      sh(*d.shader),
      pixels(batch_pixels),
      lights(*ctx.lights),
      eye(ctx.camera.eye),
      W(ctx.viewport.width_px),
      S(ctx.pattern.count),
      colour(ctx.colour),
      image_counters(ctx.images->counters.images()),
      pls_accum_format(accum_format) {
  from_triangle = p.material != kNoMaterial && ctx.scene != nullptr;
  // Texture addresses of scene triangles (other primitives read attachments or on-chip data).
  texture_footprint = from_triangle && sh.tex_fetches > 0 && ctx.textures && lines_bound;
  mat = from_triangle ? &ctx.scene->materials[p.material] : nullptr;
  mask_tex = (mat && mat->alpha_mask >= 0) ? &ctx.scene->alpha_masks[static_cast<std::size_t>(mat->alpha_mask)] : nullptr;
  pls_reads = ctx.pls && (sh.pls == PlsAccess::Read || sh.pls == PlsAccess::ReadWrite);
  pls_writes = ctx.pls && (sh.pls == PlsAccess::Write || sh.pls == PlsAccess::ReadWrite);
  pls_bytes = ctx.pls ? ctx.pass->pls_bytes_per_pixel() : 0;
  bits = p.setup.subpixel_bits;
  half = std::int64_t{1} << (bits - 1);
  decode_outputs(ctx);
  decode_surface_needs(ctx);
  decode_reach_test(ctx);
  decode_counts_only(ctx);
  // A textured scene triangle whose every fragment samples its base colour (colours, no reach
  // test that could leave it out): the fragments' barycentrics and texels first, each texel
  // prefetched, then the shading loop reads them. A minified texture's texels miss the host's
  // caches; issued one per shading iteration they waited one after another, from that loop
  // several are in flight at once (plain_forward with images 9 % less CPU). Not for a multi-pass
  // renderer's passes, whose texels the earlier passes left in the caches.
  texels_first = colour && from_triangle && builds_surface && reach_lights.empty() && mat->base_color_texels >= 0
                     ? &ctx.scene->base_color_texels[static_cast<std::size_t>(mat->base_color_texels)]
                     : nullptr;
}

// The colour outputs, their bytes and blending, and the lit-sample ledger they keep.
void Tsp::Batch::decode_outputs(const RenderContext& ctx) {
  outputs = std::min<std::uint32_t>(sh.color_outputs, static_cast<std::uint32_t>(ctx.color_targets.size()));
  for (std::uint32_t o = 0; o < outputs; ++o) out_bytes_per_sample += bytes_per_sample(ctx.color_targets[o]->format);
  blend = d.pipeline->blend;
  // The pass's lit-sample ledger (LitSampleLedger), for colour-writing fragments. A lit
  // scene-surface fragment is lit_surface_invocations' kind; an unblended write replaces the
  // sample's colour unless the shader read the pass's attachments (framebuffer fetch, or those a
  // split render left in memory, read as images): what it writes then depends on what was there.
  ledger = outputs > 0 ? ctx.lit_samples : nullptr;
  lit_surface = from_triangle && sh.light_source != LightSource::None && sh.light_source != LightSource::Proxy;
  replaces_colour = blend == BlendMode::Off && d.fetch_bytes == 0 && d.image_fetches == 0;
  ledger_tracks = ledger != nullptr && (lit_surface || replaces_colour);
}

// Which surfaces the batch reads, builds and stores.
void Tsp::Batch::decode_surface_needs(const RenderContext& ctx) {
  // Whether anything reads a stored surface (G-buffer or PLS) this batch loads: its colour, its
  // cluster (its depth), or a G-buffer target it is stored to. Without colours, a light volume's
  // fragments read none of it: the same counts without touching the stored surfaces.
  for (std::uint32_t o = 0; o < outputs; ++o) {
    const AttachmentImage* t = ctx.color_targets[o];
    if (t->usage != AttachmentUsage::Color && t->keeps_surface) writes_kept_surface = true;
  }
  reads_loaded_surface = colour || reads_stored_surface(sh, writes_kept_surface);
  if (reads_loaded_surface && d.surface_source && d.surface_source->surface.empty()) {
    throw std::logic_error("Tsp::shade: a draw reads a stored surface the frame did not keep (stored_surface_readers)");
  }
  // Whether a scene triangle's fragments need their surface: for colours, for a cluster (the
  // depth), to store it (a G-buffer target, the PLS surfaces) and for the alpha test (the uv).
  // Without, a fragment counts the same (forward+ without images: its tile's lights).
  stores_pls_surface = pls_writes && outputs == 0 && !ctx.pls->surface.empty();
  builds_surface = reads_loaded_surface || p.hsr == HsrClass::PunchThrough || stores_pls_surface;
  // The quad uvs a stored surface of a scene triangle carries (SurfacePoint::quad_uv, read by the
  // kernels that shade stored surfaces), computed as texture_addresses computes them; a surface
  // shaded where it is made (forward) needs none.
  stores_surface = writes_kept_surface || stores_pls_surface;
  if (from_triangle && builds_surface && stores_surface) {
    const std::int64_t step = std::int64_t{1} << bits;
    uv_plane.emplace(p.setup, p.uv);
    quad_uv.emplace(*uv_plane, p.setup.a[1] * step, p.setup.b[1] * step, p.setup.a[2] * step, p.setup.b[2] * step);
  }
}

// The lights whose reach decides whether a fragment's colour is exactly 0.
void Tsp::Batch::decode_reach_test(const RenderContext& ctx) {
  // Fragments whose colour only their lights make (added to colour targets or to the PLS light
  // accumulator: no ambient term, no alpha, no stored surface, no alpha test), lit by a handful
  // of lights tested one by one: a multi-pass renderer's pass (its selected lights) or a light
  // volume (its light). Where none of those lights reaches the fragment's position its colour is
  // exactly 0 (light_contribution starts with ShadingModel::reaches) whatever the rest of its
  // surface, and that is not made (a triangle's normal and base colour texel) or not read (a
  // stored surface's look). Light volumes of deferred shading at 1080p: two thirds of their
  // fragments lie behind the light's sphere.
  bool adds_light_only = colour && (outputs == 0 || blend == BlendMode::Add);
  for (std::uint32_t o = 0; o < outputs && adds_light_only; ++o) adds_light_only = ctx.color_targets[o]->usage == AttachmentUsage::Color;
  proxy_light = static_cast<std::uint32_t>(std::max(p.proxy_light, 0));
  if (adds_light_only && from_triangle && p.hsr != HsrClass::PunchThrough && !ctx.pls && outputs > 0 &&
      sh.light_source == LightSource::All && d.lights.size() <= kDirectLights) {
    reach_lights = d.lights;
  } else if (adds_light_only && !from_triangle && sh.light_source == LightSource::Proxy && p.proxy_light >= 0) {
    reach_lights = std::span<const std::uint32_t>(&proxy_light, 1);
  }
  // A scene triangle none of whose fragments any of reach_lights reaches: its world box, widened
  // by the rounding of a fragment's interpolated position, lies beyond every light's radius (see
  // may_reach_triangle). Single-sampled only: a fragment's position is then its pixel centre's,
  // a covered sample inside the triangle, so it lies in the box; with MSAA the centre of a pixel
  // that a sample covers may lie outside. Its fragments add exactly 0 and only count
  // (shade_counted_fragments). forward_multipass at 1080p, 1024 lights: 123 M of its 133 M
  // fragments are in such triangles.
  triangle_out_of_reach = from_triangle && !reach_lights.empty() && S == 1 && !may_reach_triangle(p, reach_lights, lights);
}

// Whether the batch's fragments only count (shade_counted_fragments) instead of each being shaded.
void Tsp::Batch::decode_counts_only(const RenderContext& ctx) {
  // Fragments that only count (a light volume or a full-screen pass without colours): no
  // surface is built or read and every fragment evaluates the same number of lights; a light
  // volume may push its light on the pixel's PLS light stack. The general loop would do exactly
  // this for them, fragment by fragment; the counting path keeps only what the counts, the light
  // stacks and the image counters need. With colours, a light volume adding its light to colour
  // targets over a stored surface (deferred shading's, light pre-pass's light buffer; no PLS)
  // takes that path too: each fragment reads the stored surface's position, and where the light
  // reaches it the rest of the surface, and adds the light's contribution, as the general loop's
  // reach test (adds_light_only) and colour outputs do (deferred at 1080p: 22 M such fragments,
  // two thirds out of reach; 13 % less CPU with images).
  const bool fixed_lights = sh.light_source == LightSource::None || sh.light_source == LightSource::All ||
                            sh.light_source == LightSource::ObjectList || sh.light_source == LightSource::Proxy;
  // (A light volume with a reach test is one whose colour only its light makes: adds_light_only.)
  const bool volume_reach_test = !from_triangle && !reach_lights.empty();
  volume_adds_light = volume_reach_test && outputs > 0 && d.surface_source != nullptr && !ctx.pls;
  // The same into the PLS light accumulator over the PLS surface (deferred_tile_store: no colour
  // outputs), quantised to the accumulator's format where it adds something.
  volume_accumulates = volume_reach_test && outputs == 0 && pls_reads && pls_writes && d.surface_source == nullptr;
  // A light volume that only pushes its light on the PLS light stack (forward_light_stack) reads
  // no surface and makes no colour, with colours or without.
  const bool volume_pushes_only = outputs == 0 && !pls_reads && sh.light_source != LightSource::Proxy && d.surface_source == nullptr;
  counts_only = fixed_lights && ((!from_triangle && ((!reads_loaded_surface && !colour) || volume_adds_light || volume_accumulates ||
                                                     volume_pushes_only)) ||
                                 triangle_out_of_reach);
}

/// One fragment in flight through the TSP: its pixel, the samples it writes, the surface it
/// shades and the lights it evaluates.
struct Tsp::Fragment {
  /// Fragment `index` of batch `b`, before its surface is made.
  Fragment(const Batch& b, std::size_t index)
      : i(index),
        px(b.pixels[index]),
        pixel(static_cast<std::size_t>(px.y) * static_cast<std::size_t>(b.W) + static_cast<std::size_t>(px.x)),
        write_mask(px.mask & px.write) {}

  std::size_t i = 0;  ///< index in the batch
  const ShadePixel& px;
  std::size_t pixel = 0;  ///< index in the frame's pixels
  std::uint32_t write_mask = 0;
  SurfacePoint s;
  bool have_surface = false;
  bool out_of_reach = false;  ///< none of reach_lights reaches it: only its position is made or read
  FragmentLights fl;
};

void Tsp::shade(std::uint32_t prim_index, std::span<const ShadePixel> pixels, std::vector<std::uint32_t>* alive,
                TspStats& stats) {
  if (pixels.empty()) return;
  refresh_pass_formats();
  const Batch b(ctx_, prim_index, pixels, texture_lines_out_ != nullptr, pls_accum_format_);
  // The batch's work, to tell a batch with nothing to run (idle_quads) afterwards.
  const auto work = [&stats] {
    return stats.fragment_alu_ops.value() + stats.texels_filtered.value() + stats.pls_bytes_accessed.value() +
           stats.tile_buffer_read_bytes.value() + stats.tile_buffer_write_bytes.value();
  };
  const std::uint64_t work_before = work();
  const std::uint64_t quads = launch_quads(b, stats);
  if (alive) alive->assign(pixels.size(), 0);
  if (b.texture_footprint) texture_addresses(b.p, b.sh.tex_fetches, static_cast<std::size_t>(quads), stats);
  near_.bin = nullptr;  // gathered for another batch
  const std::uint64_t light_sum = b.counts_only ? shade_counted_fragments(b, alive, stats) : shade_fragments(b, alive, stats);
  charge_batch(b, quads * 4 - pixels.size(), light_sum, stats);
  if (work() == work_before && b.d.per_pixel_reads.empty()) stats.idle_quads += quads;
}

// Quad launch on the USCs: 2x2 pixel blocks aligned to even coordinates, every lane of a launched
// quad runs (helper lanes), each lane issuing the shader's texture fetches.
std::uint64_t Tsp::launch_quads(const Batch& b, TspStats& stats) {
  // Their keys only when the texture footprint walks them.
  const auto quads = static_cast<std::uint64_t>(b.texture_footprint ? launched_quads(b.pixels, quad_seen_)
                                                                     : launched_quad_count(b.pixels, quad_seen_));
  const std::uint64_t helpers = quads * 4 - b.pixels.size();
  stats.shader_invocations += b.pixels.size();
  stats.shaded_quads += quads;
  stats.helper_lanes += helpers;
  // The shader's fetches plus the attachments it reads as images after a split render.
  const std::uint64_t fetches = b.sh.tex_fetches + b.d.image_fetches;
  stats.texture_fetches += quads * 4 * fetches;
  // The texture units' work is counted in filtered texels (texture.texels_per_clock's unit): a
  // bilinear fetch is one, whatever the 4 texels it reads.
  stats.texels_filtered += quads * 4 * fetches * static_cast<std::uint64_t>(ctx_.hw->texture.filtered_texels_per_fetch);
  return quads;
}

// The pass's attachment and PLS formats (Tsp::target_formats_, pls_formats_), made again when the pass changes.
void Tsp::refresh_pass_formats() {
  // Every write keeps what its target's format holds (FormatPrecision): colour targets per format;
  // the surface a G-buffer stands for per the targets (or PLS variables) holding its attributes.
  if (formats_pass_ == ctx_.pass) return;
  formats_pass_ = ctx_.pass;
  target_formats_.clear();
  for (const Attachment* a : ctx_.pass->color_targets()) target_formats_.push_back({FormatPrecision::attribute_of(a->name), a->format});
  pls_formats_.clear();
  pls_accum_format_.reset();
  for (const PlsVariable& v : ctx_.pass->pls) {
    pls_formats_.push_back({FormatPrecision::attribute_of(v.name), v.format});
    if (v.name == kPlsAccumulatorName) pls_accum_format_ = v.format;
  }
}

// Lit-sample bookkeeping of one fragment's colour write (LitSampleLedger): its samples shaded but
// not written (late depth/stencil tests failed) are hidden at once; its written samples replace or
// add to what they held.
void Tsp::keep_ledger(const Batch& b, const ShadePixel& px, std::uint32_t write_mask, std::uint64_t lights, TspStats& stats) {
  if (b.lit_surface && (px.mask & ~px.write) != 0) {
    LitSampleLedger::hidden_unwritten(static_cast<std::uint32_t>(bit_count(px.mask & ~px.write)), lights, stats);
  }
  if (write_mask != 0) b.ledger->write(px.x, px.y, write_mask, b.replaces_colour, b.lit_surface, lights, stats);
}

// Attribute store precision: a surface as the G-buffer targets (or PLS variables) holding its
// attributes keep it. The formats keep the looks (normal, albedo, alpha), which a store keeps only
// with colours.
SurfacePoint Tsp::stored_surface(const Batch& b, bool pls, SurfacePoint q) const {
  if (!b.colour) return q;
  if (pls) {
    for (const auto& [attribute, format] : pls_formats_) FormatPrecision::surface(attribute, format, q);
  } else {
    for (std::uint32_t o = 0; o < b.outputs && o < target_formats_.size(); ++o) {
      if (ctx_.color_targets[o]->usage != AttachmentUsage::Color) FormatPrecision::surface(target_formats_[o].first, target_formats_[o].second, q);
    }
  }
  return q;
}

// Blending into the tile buffer: `src` blended into each written sample of the batch's colour
// targets (usage Color) as the target's format keeps it. An additive fragment that adds exactly 0
// (out of its lights' reach, facing away) leaves a target that keeps every channel as it is:
// dst + 0 is dst, which the format already holds.
void Tsp::blend_into_colour_targets(const Batch& b, std::size_t pixel, std::uint32_t write_mask, const glm::vec4& src) {
  const BlendMode blend = b.blend;
  const int S = b.S;
  const bool adds_zero = blend == BlendMode::Add && glm::vec3(src) == glm::vec3(0.0f);
  for (std::uint32_t o = 0; o < b.outputs; ++o) {
    AttachmentImage* target = ctx_.color_targets[o];
    if (target->usage != AttachmentUsage::Color) continue;
    if (adds_zero && FormatPrecision::keeps_every_channel(target->format)) continue;
    glm::vec4* dst = target->color.data() + pixel * static_cast<std::size_t>(S);
    const Format format = target->format;
    for (int smp = 0; smp < S; ++smp) {
      if (!(write_mask & (1u << smp))) continue;
      switch (blend) {
        case BlendMode::Off: dst[smp] = FormatPrecision::color(format, src); break;
        case BlendMode::Add: dst[smp] = FormatPrecision::color(format, dst[smp] + glm::vec4(glm::vec3(src), 0.0f)); break;
        case BlendMode::Alpha:
          dst[smp] = FormatPrecision::color(format, glm::vec4(glm::vec3(src) * src.w + glm::vec3(dst[smp]) * (1.0f - src.w),
                                                              src.w + dst[smp].w * (1.0f - src.w)));
          break;
      }
    }
  }
}

// The PLS light accumulator: a light's contribution added to the pixel's. Adding 0 keeps the
// accumulator as it is: it only ever holds 0 or what its format keeps, each channel a fixed point
// of FormatPrecision::color (most light-volume fragments lie out of their light's reach).
void Tsp::accumulate_in_pls(const Batch& b, std::size_t pixel, const glm::vec3& add) {
  if (add == glm::vec3(0.0f)) return;
  glm::vec3& acc = ctx_.pls->accum[pixel];
  acc += add;
  if (b.pls_accum_format) acc = glm::vec3(FormatPrecision::color(*b.pls_accum_format, glm::vec4(acc, 1.0f)));
}

// Writing a colour output makes the pixel's PLS undefined (EXT_shader_pixel_local_storage).
void Tsp::invalidate_pls(std::size_t pixel) {
  if (ctx_.pls) {
    ctx_.pls->valid[pixel] = 0;
    ctx_.pls->stack_count[pixel] = 0;
  }
}

// The tile buffer traffic of `written` colour samples: written, and read first when blended.
void Tsp::charge_written_samples(const Batch& b, std::uint64_t written, TspStats& stats) {
  stats.shaded_samples += written;
  stats.tile_buffer_write_bytes += written * b.out_bytes_per_sample;
  if (b.blend != BlendMode::Off) {
    stats.blended_samples += written;
    stats.tile_buffer_read_bytes += written * b.out_bytes_per_sample;
  }
}

// The counting path (Batch::counts_only): fragments that evaluate a fixed number of lights and
// build no surface of their own (light volumes, full-screen passes without colours, scene
// triangles out of every light's reach). Returns the lights the batch evaluated.
std::uint64_t Tsp::shade_counted_fragments(const Batch& b, std::vector<std::uint32_t>* alive, TspStats& stats) {
  const Primitive& p = b.p;
  std::uint64_t count = 0;
  switch (b.sh.light_source) {
    case LightSource::All: count = b.d.lights.size(); break;
    case LightSource::ObjectList: count = ctx_.object_lights[p.object].size(); break;
    case LightSource::Proxy: count = p.proxy_light >= 0 ? 1 : 0; break;
    default: break;
  }
  const Light* volume_light =
      b.volume_adds_light || b.volume_accumulates ? &b.lights[static_cast<std::size_t>(p.proxy_light)] : nullptr;
  std::uint32_t* const shaded = ctx_.images->counters.shaded.data();
  std::uint64_t written = 0;
  for (std::size_t i = 0; i < b.pixels.size(); ++i) {
    const ShadePixel& px = b.pixels[i];
    const std::size_t pixel = static_cast<std::size_t>(px.y) * static_cast<std::size_t>(b.W) + static_cast<std::size_t>(px.x);
    const std::uint32_t write_mask = px.mask & px.write;
    if (alive) (*alive)[i] = write_mask;
    if (b.ledger_tracks) keep_ledger(b, px, write_mask, count, stats);
    shaded[pixel] += 1;
    if (b.image_counters) {
      ctx_.images->counters.lights_evaluated[pixel] += static_cast<std::uint32_t>(count);
      if (write_mask != 0) ctx_.images->counters.triangle_id[pixel] = p.id + 1;
    }
    if (write_mask == 0) continue;
    if (b.outputs == 0) {
      counted_pls_effects(b, pixel, volume_light);
      continue;
    }
    written += static_cast<std::uint64_t>(bit_count(write_mask));
    if (volume_light) {
      glm::vec3 lit(0.0f);
      const std::size_t k = pixel * b.d.surface_source->samples;
      if (b.d.surface_source->surface_valid[k] && ShadingModel::reaches(*volume_light, b.d.surface_source->surface.site(k).position)) {
        lit = ShadingModel::lit_contribution(b.d.surface_source->surface[k], b.eye, *volume_light);
      }
      blend_into_colour_targets(b, pixel, write_mask, glm::vec4(lit, 0.0f));
    } else if (b.triangle_out_of_reach) {
      blend_into_colour_targets(b, pixel, write_mask, glm::vec4(0.0f));  // (adds 0: only formats that drop a channel change)
    }
    invalidate_pls(pixel);
  }
  charge_written_samples(b, written, stats);
  return count * b.pixels.size();
}

// PLS effects of a counted fragment of a shader without colour outputs, as the general loop's
// (store_in_pls): without colours, a light volume's push of its light on the stack (a proxy
// accumulates colour only); a light volume accumulating its light over the PLS surface.
void Tsp::counted_pls_effects(const Batch& b, std::size_t pixel, const Light* volume_light) {
  if (b.pls_writes && b.sh.light_source != LightSource::Proxy && b.p.proxy_light >= 0) {
    ctx_.pls->push_light(pixel, static_cast<std::uint32_t>(b.p.proxy_light));
  }
  if (b.volume_accumulates && ctx_.pls->valid[pixel]) {
    if (ctx_.pls->surface.empty()) throw std::logic_error("Tsp::shade: a PLS surface is read but the pass keeps none");
    if (ShadingModel::reaches(*volume_light, ctx_.pls->surface.site(pixel).position)) {
      accumulate_in_pls(b, pixel, ShadingModel::lit_contribution(ctx_.pls->surface[pixel], b.eye, *volume_light));
    }
  }
}

// Texture unit, ahead of the shading loop: every fragment's barycentrics and base colour texel
// (Batch::texels_first), each texel's cache line prefetched on the host.
void Tsp::prefetch_base_texels(const Batch& b) {
  const std::size_t n = b.pixels.size();
  frag_bary_.resize(n);
  frag_texel_.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    frag_bary_[i] = pixel_barycentrics(b.p, b.pixels[i].x, b.pixels[i].y);
    frag_texel_[i] = b.texels_first->texel_at(uv_at(b.p, frag_bary_[i]));
    prefetch_for_read(frag_texel_[i]);
  }
}

// The general path: every fragment's surface, light list, lighting, PLS and colour writes in
// turn. Returns the lights the batch's fragments evaluated.
std::uint64_t Tsp::shade_fragments(const Batch& b, std::vector<std::uint32_t>* alive, TspStats& stats) {
  if (b.texels_first) prefetch_base_texels(b);
  std::uint64_t light_sum = 0;
  for (std::size_t i = 0; i < b.pixels.size(); ++i) {
    Fragment f(b, i);
    const ShadePixel& px = f.px;
    fragment_surface(b, f, stats);
    if (alive) (*alive)[i] = f.write_mask;
    select_lights(b, f, stats);
    light_sum += f.fl.count;  // the per-fragment charges are booked for the batch (charge_batch)
    ctx_.images->counters.shaded[f.pixel] += 1;
    if (b.image_counters) ctx_.images->counters.lights_evaluated[f.pixel] += static_cast<std::uint32_t>(f.fl.count);
    if (b.ledger_tracks) keep_ledger(b, px, f.write_mask, f.fl.count, stats);
    if (f.write_mask == 0) continue;
    // The frame-unique id (as SurfacePoint::triangle).
    if (b.image_counters) ctx_.images->counters.triangle_id[f.pixel] = b.p.id + 1;
    if (b.pls_writes && b.outputs == 0) store_in_pls(b, f);
    if (b.outputs == 0) continue;
    write_colour_outputs(b, f, stats);
  }
  return light_sum;
}

// The surface a fragment shades: interpolated from a scene triangle, or read from the stored
// surface (G-buffer or PLS) a light volume or full-screen pass shades.
void Tsp::fragment_surface(const Batch& b, Fragment& f, TspStats& stats) {
  if (b.from_triangle && !b.builds_surface) {
    f.have_surface = true;  // (nothing reads it: see Batch::builds_surface)
  } else if (b.from_triangle) {
    interpolate_surface(b, f, stats);
  } else if (!b.reads_loaded_surface) {
    // Nothing reads the surface (have_surface only gates reads of it).
  } else if (b.d.surface_source) {
    const std::size_t k = f.pixel * b.d.surface_source->samples;
    if (b.d.surface_source->surface_valid[k]) {
      read_stored_surface(b, b.d.surface_source->surface, k, f);
      f.have_surface = true;
    }
  } else if (b.pls_reads && ctx_.pls->valid[f.pixel]) {
    if (ctx_.pls->surface.empty()) throw std::logic_error("Tsp::shade: a PLS surface is read but the pass keeps none");
    read_stored_surface(b, ctx_.pls->surface, f.pixel, f);
    f.have_surface = true;
  }
}

// Attribute load from a stored surface (G-buffer or PLS): all of it, or only its position where
// none of reach_lights reaches it.
void Tsp::read_stored_surface(const Batch& b, const SurfaceStore& store, std::size_t k, Fragment& f) {
  const glm::vec3& position = store.site(k).position;
  f.out_of_reach = b.out_of_reach_at(position);
  if (f.out_of_reach) {
    f.s.position = position;
  } else {
    f.s = store[k];
  }
}

// Varying interpolation (the iterators) of a scene triangle at the pixel centre: position, normal,
// uv; then the base colour sample, the quad uvs a stored surface carries and the alpha test.
void Tsp::interpolate_surface(const Batch& b, Fragment& f, TspStats& stats) {
  const Primitive& p = b.p;
  const Material* mat = b.mat;
  const glm::vec3 bc = b.texels_first ? frag_bary_[f.i] : pixel_barycentrics(p, f.px.x, f.px.y);
  SurfacePoint& s = f.s;
  s.position = position_at(p, bc);
  s.alpha = mat->base_color.w;
  s.material = p.material;
  s.triangle = p.id;
  f.have_surface = true;
  f.out_of_reach = b.out_of_reach_at(s.position);
  if (f.out_of_reach) return;
  glm::vec3 n = p.normal[0] * bc.x + p.normal[1] * bc.y + p.normal[2] * bc.z;
  const float len = glm::length(n);
  n = len > 0.0f ? n / len : glm::vec3(0.0f, 1.0f, 0.0f);
  if (!p.setup.front_facing) n = -n;
  s.normal = n;
  const glm::vec2 uv = uv_at(p, bc);
  s.albedo = glm::vec3(mat->base_color);
  // Texture sample: the base colour texture the fetches are charged for, at the pixel (glTF: factor x texel).
  if (b.texels_first && frag_texel_[f.i]) {
    s.albedo *= ColorTexels::linear_rgb(frag_texel_[f.i]);
  } else if (b.colour && mat->base_color_texels >= 0) {
    s.albedo *= ctx_.scene->base_color_texels[static_cast<std::size_t>(mat->base_color_texels)].sample_linear_rgb(uv);
  }
  if (b.quad_uv) {
    const std::int64_t qx = f.px.x & ~std::int32_t{1}, qy = f.px.y & ~std::int32_t{1};
    const std::int64_t x0 = (qx << b.bits) + b.half, y0 = (qy << b.bits) + b.half;
    b.quad_uv->at(edge_value(p.setup, 1, x0, y0), edge_value(p.setup, 2, x0, y0), s.quad_uv);
  }
  // Punch-through alpha test: a fragment below the material's cutoff is discarded.
  if (p.hsr == HsrClass::PunchThrough) {
    const float a = s.alpha * (b.mask_tex ? b.mask_tex->sample(uv) : 1.0f);
    if (a < mat->alpha_cutoff) {
      stats.alpha_test_killed_samples += static_cast<std::uint64_t>(bit_count(f.write_mask));
      f.write_mask = 0;
    }
  }
}

// Light list fetch: the lights a fragment evaluates, per its shader's light source (every selected
// light, its object's, its proxy, its screen tile's, its cluster's, its pixel's PLS light stack).
void Tsp::select_lights(const Batch& b, Fragment& f, TspStats& stats) {
  const DrawContext& d = b.d;
  FragmentLights& fl = f.fl;
  switch (b.sh.light_source) {
    case LightSource::None: break;
    case LightSource::All:
      fl.all_selected = true;
      fl.count = d.lights.size();
      break;
    case LightSource::ObjectList:
      fl.list = &ctx_.object_lights[b.p.object];
      fl.count = fl.list->size();
      break;
    case LightSource::Proxy:
      fl.single = b.p.proxy_light;
      fl.count = b.p.proxy_light >= 0 ? 1 : 0;
      break;
    case LightSource::TileList:
      fl.list = &d.tile_grid->at_pixel(f.px.x, f.px.y);
      fl.count = fl.list->size();
      break;
    case LightSource::ClusterList:
      if (f.have_surface) {
        const std::size_t c = d.cluster_grid->cluster_of(f.px.x, f.px.y, ctx_.frustum->distance_of(f.s.position));
        fl.list = &d.cluster_grid->lists[c];
        fl.count = fl.list->size();
        if (!d.cluster_grid->used[c]) stats.unassigned_cluster_fragments += 1;
      }
      break;
    case LightSource::PlsStack:
      if (ctx_.pls && ctx_.pls->overflow[f.pixel]) {
        fl.all_selected = true;
        fl.count = d.lights.size();
        stats.light_stack_overflow_fragments += 1;
      } else if (ctx_.pls) {
        fl.count = ctx_.pls->stack_count[f.pixel];
      }
      break;
  }
}

// The batch's surface box for the near-light cut (Batch::bounds), made at its first use.
const std::pair<glm::vec3, glm::vec3>& Tsp::batch_bounds(const Batch& b, const glm::vec3& fallback) const {
  if (b.bounds) return *b.bounds;
  auto& bounds = b.bounds.emplace();
  if (b.texels_first) {
    // The fragments' barycentrics are at hand (the texel prefetch made them): the box of their
    // positions, exactly as surface_bounds makes it (triangle_position's values, the same folds
    // from the same start).
    glm::vec3 lo(std::numeric_limits<float>::infinity()), hi = -lo;
    for (std::size_t j = 0; j < b.pixels.size(); ++j) {
      const glm::vec3 q = position_at(b.p, frag_bary_[j]);
      lo = glm::min(lo, q);
      hi = glm::max(hi, q);
    }
    bounds = {lo, hi};
  } else if (!surface_bounds(b.p, b.d, b.pixels, bounds.first, bounds.second)) {
    bounds.first = bounds.second = fallback;
  }
  return bounds;
}

// Light evaluation: the sum of the fragment's lights' contributions at its surface.
glm::vec3 Tsp::fragment_lighting(const Batch& b, const Fragment& f) {
  const SurfacePoint& s = f.s;
  const FragmentLights& fl = f.fl;
  const auto& lights = b.lights;
  glm::vec3 c(0.0f);
  if (!f.have_surface || f.out_of_reach) return c;  // (out of reach: the loops below would add exactly 0s)
  if (fl.all_selected && b.d.lights.size() <= kDirectLights) {
    // A few selected lights (a multi-pass renderer's pass): each tested at the surface, in
    // ascending order as below; those a bin or the batch's box would cut add exactly 0.
    for (const std::uint32_t l : b.d.lights) c += ShadingModel::light_contribution(s, b.eye, lights[l]);
  } else if (fl.all_selected) {
    // The pixel's screen-bin candidates, cut once per batch and bin to those reaching the
    // batch's surfaces (lights beyond their radius add exactly 0: the sum is unchanged).
    const auto& [lo, hi] = batch_bounds(b, s.position);
    const std::vector<std::uint32_t>& bin = ctx_.light_bins->at(f.px.x, f.px.y);
    if (near_.bin != &bin) gather_near_lights(bin, b.d, lo, hi);
    c = near_lighting(s, b.eye);
  } else if (fl.list) {
    for (std::uint32_t l : *fl.list) c += ShadingModel::light_contribution(s, b.eye, lights[l]);
  } else if (fl.single >= 0) {
    c += ShadingModel::light_contribution(s, b.eye, lights[static_cast<std::size_t>(fl.single)]);
  } else if (b.sh.light_source == LightSource::PlsStack && ctx_.pls) {
    const std::uint32_t* st = ctx_.pls->stack.data() + f.pixel * ctx_.pls->stack_capacity;
    for (std::uint32_t k = 0; k < ctx_.pls->stack_count[f.pixel]; ++k) {
      c += ShadingModel::light_contribution(s, b.eye, lights[st[k]]);
    }
  }
  return c;
}

// Pixel local storage writes of a shader without colour outputs: a scene triangle stores its
// surface (and clears the pixel's light state), a proxy accumulates its light, a light volume
// pushes its light on the pixel's stack.
void Tsp::store_in_pls(const Batch& b, const Fragment& f) {
  if (b.from_triangle) {
    if (!ctx_.pls->surface.empty()) ctx_.pls->surface.set(f.pixel, stored_surface(b, true, f.s));
    ctx_.pls->valid[f.pixel] = 1;
    if (b.colour) ctx_.pls->accum[f.pixel] = glm::vec3(0.0f);
    ctx_.pls->stack_count[f.pixel] = 0;
    ctx_.pls->overflow[f.pixel] = 0;
  } else if (b.sh.light_source == LightSource::Proxy) {
    if (f.have_surface && b.colour) accumulate_in_pls(b, f.pixel, fragment_lighting(b, f));
  } else if (b.p.proxy_light >= 0) {
    ctx_.pls->push_light(f.pixel, static_cast<std::uint32_t>(b.p.proxy_light));
  }
}

// Colour outputs handed to the tile buffer: the fragment's lit colour (lights, ambient, the PLS
// accumulator) blended into the colour targets, its surface stored to a G-buffer target.
void Tsp::write_colour_outputs(const Batch& b, const Fragment& f, TspStats& stats) {
  glm::vec3 lit(0.0f);
  if (f.have_surface && b.colour) {
    lit = fragment_lighting(b, f);
    if (b.blend != BlendMode::Add) lit += ShadingModel::ambient(f.s);
    if (b.pls_reads && ctx_.pls->valid[f.pixel]) lit += ctx_.pls->accum[f.pixel];
  }
  const glm::vec4 src(lit, f.have_surface ? f.s.alpha : 0.0f);
  charge_written_samples(b, static_cast<std::uint64_t>(bit_count(f.write_mask)), stats);
  if (b.colour) blend_into_colour_targets(b, f.pixel, f.write_mask, src);
  if (f.have_surface) store_in_surface_target(b, f);
  invalidate_pls(f.pixel);
}

// G-buffer / visibility store: the first colour output that is not a Color target keeps the
// surface the data stands for (PassRenderer::allocate_surfaces made its arrays; only its marks
// when no command reads it).
void Tsp::store_in_surface_target(const Batch& b, const Fragment& f) {
  const int S = b.S;
  for (std::uint32_t o = 0; o < b.outputs; ++o) {
    AttachmentImage* target = ctx_.color_targets[o];
    if (target->usage == AttachmentUsage::Color) continue;
    if (target->surface_valid.empty()) {  // (a TSP driven alone; PassRenderer::allocate_surfaces makes them before tiles run)
      if (target->keeps_surface) target->surface.assign(target->sample_count, b.colour);
      target->surface_valid.assign(target->sample_count, 0);
    }
    const std::size_t k0 = f.pixel * static_cast<std::size_t>(S);
    const SurfacePoint stored = target->keeps_surface ? stored_surface(b, false, f.s) : SurfacePoint{};
    for (int smp = 0; smp < S; ++smp) {
      if (!(f.write_mask & (1u << smp))) continue;
      if (target->keeps_surface) target->surface.set(k0 + static_cast<std::size_t>(smp), stored);
      target->surface_valid[k0 + static_cast<std::size_t>(smp)] = 1;
    }
    return;
  }
}

// What every fragment of the batch is charged, booked once (integer sums: the same totals): PLS
// and tile buffer traffic, shader image reads, ALU ops and light evaluations (helper lanes too).
void Tsp::charge_batch(const Batch& b, std::uint64_t helpers, std::uint64_t light_sum, TspStats& stats) {
  const ShaderDesc& sh = b.sh;
  const std::uint64_t n = b.pixels.size();
  // Pixel local storage traffic: the pass's whole PLS layout, read and/or written per fragment.
  if (b.pls_reads) stats.pls_bytes_accessed += n * b.pls_bytes;
  if (b.pls_writes && b.outputs == 0) stats.pls_bytes_accessed += n * b.pls_bytes;
  // Framebuffer fetch: the fetched attachments are read from the tile buffer at each pixel.
  stats.tile_buffer_read_bytes += n * b.d.fetch_bytes;
  if (b.from_triangle && sh.light_source != LightSource::None && sh.light_source != LightSource::Proxy) stats.lit_surface_invocations += n;
  for (const auto& [cls, bytes] : b.d.per_pixel_reads) dram_out_->read(cls, n * bytes);
  stats.fragment_alu_ops += n * sh.alu_ops + std::uint64_t{sh.light_alu_ops} * light_sum;
  stats.light_evaluations += light_sum;
  // Helper lanes run the same code (their light loops as long as the batch's average fragment).
  stats.fragment_alu_ops += helpers * sh.alu_ops + (helpers * std::uint64_t{sh.light_alu_ops} * light_sum) / n;
}

}  // namespace tbdr
