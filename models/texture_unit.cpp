#include "models/texture_unit.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "models/hw_config.hpp"
#include "kernel/bits.hpp"
#include "scene/scene.hpp"

namespace tbdr {

namespace {

/// Spreads the bits of v to the even bit positions (the x half of a Morton code).
inline std::uint64_t spread_bits(std::uint32_t v) {
  std::uint64_t x = v;
  x = (x | (x << 16)) & 0x0000FFFF0000FFFFull;
  x = (x | (x << 8)) & 0x00FF00FF00FF00FFull;
  x = (x | (x << 4)) & 0x0F0F0F0F0F0F0F0Full;
  x = (x | (x << 2)) & 0x3333333333333333ull;
  x = (x | (x << 1)) & 0x5555555555555555ull;
  return x;
}

inline std::uint64_t align_up(std::uint64_t v, std::uint64_t a) { return (v + a - 1) / a * a; }

bool usable_texture(const Scene& scene, int index) {
  if (index < 0 || static_cast<std::size_t>(index) >= scene.textures.size()) return false;
  const TextureInfo& t = scene.textures[static_cast<std::size_t>(index)];
  return !t.missing && t.width > 0 && t.height > 0;
}

/// Texel coordinates along one axis of a bilinear fetch at normalised coordinate c: floor(c *
/// size - 0.5) and the next texel, both wrapped (repeat) into [0, size).
inline void bilinear_pair(float c, std::uint32_t size, std::int64_t& t0, std::int64_t& t1) {
  if (!(std::fabs(c) < 1048576.0f)) c = std::isfinite(c) ? c - std::floor(c) : 0.0f;  // keeps c * size exact enough
  const float x = c * static_cast<float>(size) - 0.5f;
  auto i = static_cast<std::int64_t>(x);           // truncation,
  i -= static_cast<std::int64_t>(x < static_cast<float>(i));  // then floor
  const auto n = static_cast<std::int64_t>(size);
  if ((size & (size - 1)) == 0) {
    t0 = i & (n - 1);
    t1 = (i + 1) & (n - 1);
  } else {
    t0 = ((i % n) + n) % n;
    t1 = t0 + 1 == n ? 0 : t0 + 1;
  }
}

}  // namespace

std::uint64_t TextureStorage::twiddled_index(std::uint32_t l, std::uint32_t x, std::uint32_t y) const {
  const std::uint32_t m = level[l].block_log2;
  const std::uint32_t mask = (std::uint32_t{1} << m) - 1;
  // One of x >> m, y >> m is always 0: the shorter side is a single block.
  return spread_bits(x & mask) + (spread_bits(y & mask) << 1) +
         ((static_cast<std::uint64_t>(x >> m) + static_cast<std::uint64_t>(y >> m)) << (2 * m));
}

TextureLayout::TextureLayout(const Scene* scene, std::uint32_t slots, std::uint32_t bytes_per_texel,
                             std::uint32_t line_bytes)
    : slots_(std::max<std::uint32_t>(1, slots)),
      bytes_per_texel_(std::max<std::uint32_t>(1, bytes_per_texel)),
      line_bytes_(std::max<std::uint32_t>(1, line_bytes)) {
  line_pow2_ = std::has_single_bit(line_bytes_);
  line_shift_ = static_cast<std::uint32_t>(std::countr_zero(line_bytes_));
  std::vector<std::uint32_t> storage_of_texture;
  if (scene) {
    std::vector<std::uint8_t> used(scene->textures.size(), 0);
    for (const Material& m : scene->materials) {
      if (usable_texture(*scene, m.base_color_texture)) used[static_cast<std::size_t>(m.base_color_texture)] = 1;
    }
    storage_of_texture.assign(scene->textures.size(), 0);
    for (std::size_t t = 0; t < scene->textures.size(); ++t) {
      if (!used[t]) continue;
      storage_of_texture[t] = static_cast<std::uint32_t>(storages_.size());
      add_storage(static_cast<std::int32_t>(t), static_cast<std::uint32_t>(scene->textures[t].width),
                  static_cast<std::uint32_t>(scene->textures[t].height));
    }
  }
  add_storage(-1, kDefaultTextureSize, kDefaultTextureSize);
  const auto fallback = static_cast<std::uint32_t>(storages_.size() - 1);
  if (scene) {
    material_storage_.reserve(scene->materials.size());
    for (const Material& m : scene->materials) {
      material_storage_.push_back(usable_texture(*scene, m.base_color_texture)
                                      ? storage_of_texture[static_cast<std::size_t>(m.base_color_texture)]
                                      : fallback);
    }
  }
}

TextureLayout::TextureLayout(const Scene* scene, const HwConfig& hw, std::uint32_t slots)
    : TextureLayout(scene, slots, static_cast<std::uint32_t>(hw.texture.bytes_per_texel),
                    static_cast<std::uint32_t>(hw.cache.texture.line_bytes)) {}

void TextureLayout::add_storage(std::int32_t scene_texture, std::uint32_t width, std::uint32_t height) {
  TextureStorage s;
  s.scene_texture = scene_texture;
  s.width = width;
  s.height = height;
  s.levels = static_cast<std::uint32_t>(std::bit_width(std::max(width, height)));
  // Texels per line, when lines hold whole power-of-two texel blocks.
  const bool blocks = line_pow2_ && std::has_single_bit(bytes_per_texel_) && line_bytes_ >= bytes_per_texel_;
  const int k = blocks ? static_cast<int>(line_shift_) - std::countr_zero(bytes_per_texel_) : 0;
  texel_shift_ = static_cast<std::uint32_t>(std::countr_zero(bytes_per_texel_));
  std::uint64_t offset = 0;
  for (std::uint32_t l = 0; l < s.levels; ++l) {
    TextureLevel& lv = s.level[l];
    lv.width = std::max<std::uint32_t>(1, width >> l);
    lv.height = std::max<std::uint32_t>(1, height >> l);
    const std::uint64_t w2 = std::bit_ceil(lv.width), h2 = std::bit_ceil(lv.height);
    lv.block_log2 = static_cast<std::uint32_t>(std::countr_zero(std::min(w2, h2)));
    lv.offset = offset;
    lv.bytes = w2 * h2 * bytes_per_texel_;
    offset = align_up(offset + lv.bytes, line_bytes_);
    if (blocks) {
      // A line is 2^k consecutive twiddled texels: inside one m x m Morton block, an aligned
      // ceil(k/2) x floor(k/2) (log2) block; beyond it, whole Morton blocks along the longer side.
      const int lw = std::countr_zero(w2), lh = std::countr_zero(h2), lm = static_cast<int>(lv.block_log2);
      int cx = 0, cy = 0;
      if (k <= 2 * lm) {
        cx = (k + 1) / 2;
        cy = k / 2;
      } else if (lw >= lh) {
        cx = std::min(lw, k - lm);
        cy = lm;
      } else {
        cx = lm;
        cy = std::min(lh, k - lm);
      }
      lv.line_x_log2 = static_cast<std::uint32_t>(cx);
      lv.line_y_log2 = static_cast<std::uint32_t>(cy);
      lv.line_cols = ((lv.width - 1) >> cx) + 1;
      lv.line_rows = ((lv.height - 1) >> cy) + 1;
      // Block counting in fixed point needs the level to be the texture scaled by exactly 2^-l
      // (power-of-two sizes, not clamped at 1), so the block grid wraps with the texture.
      lv.line_blocks = (lv.width << l) == width && (lv.height << l) == height && std::has_single_bit(width) &&
                     std::has_single_bit(height) && width <= (1u << 18) && height <= (1u << 18);
    }
  }
  s.slot_bytes = offset;
  s.base = total_bytes_;
  total_bytes_ += s.slot_bytes * slots_;
  storages_.push_back(s);
}

std::uint32_t TextureLayout::quad_level(const TextureStorage& t, const std::array<glm::vec2, 4>& uv) const {
  const float w = static_cast<float>(t.width), h = static_cast<float>(t.height);
#if defined(__SSE2__)
  const __m128 a = _mm_loadu_ps(&uv[0].x);  // u0 v0 u1 v1
  const __m128 b = _mm_loadu_ps(&uv[2].x);  // u2 v2 u3 v3
  const __m128 d = _mm_mul_ps(_mm_sub_ps(_mm_shuffle_ps(a, b, _MM_SHUFFLE(1, 0, 3, 2)), _mm_movelh_ps(a, a)),
                              _mm_setr_ps(w, h, w, h));  // dxu dxv dyu dyv
  const __m128 sq = _mm_mul_ps(d, d);
  const __m128 sum = _mm_add_ps(sq, _mm_shuffle_ps(sq, sq, _MM_SHUFFLE(2, 3, 0, 1)));  // |d/dx|^2 in lane 0, |d/dy|^2 in 2
  const float rho2 = _mm_cvtss_f32(_mm_max_ss(sum, _mm_movehl_ps(sum, sum)));
#else
  const float dxu = (uv[1].x - uv[0].x) * w, dxv = (uv[1].y - uv[0].y) * h;
  const float dyu = (uv[2].x - uv[0].x) * w, dyv = (uv[2].y - uv[0].y) * h;
  const float rho2 = std::max(dxu * dxu + dxv * dxv, dyu * dyu + dyv * dyv);
#endif
  const auto top = static_cast<int>(t.levels) - 1;
  if (!(rho2 < std::numeric_limits<float>::infinity())) return static_cast<std::uint32_t>(top);  // inf, NaN
  if (!(rho2 >= std::numeric_limits<float>::min())) return 0;  // 0 or denormal: magnified
  // level = round(0.5 * log2(rho2)), halves up: with e = floor(log2(rho2)) (the exponent of a
  // normal float), (e + 1) / 2 rounded down.
  const int e = static_cast<int>((std::bit_cast<std::uint32_t>(rho2) >> 23) & 0xffu) - 127;
  return static_cast<std::uint32_t>(std::clamp((e + 1) >> 1, 0, top));
}

std::uint64_t TextureLayout::line_of(const TextureStorage& t, std::uint32_t l, std::uint32_t x, std::uint32_t y) const {
  const std::uint64_t byte = t.base + t.level[l].offset + t.twiddled_index(l, x, y) * bytes_per_texel_;
  return line_pow2_ ? (byte >> line_shift_) << line_shift_ : byte / line_bytes_ * line_bytes_;
}

void TextureLayout::footprint_by_texel(const TextureStorage& t, const std::array<glm::vec2, 4>& uv,
                                       QuadFootprint& out) const {
  out.level = quad_level(t, uv);
  out.blocks = false;
  const TextureLevel& lv = t.level[out.level];
  out.count = 0;
  auto add = [&](std::uint64_t line) {
    for (std::uint32_t j = 0; j < out.count; ++j) {
      if (out.lines[j] == line) return;
    }
    out.lines[out.count++] = line;
  };
  for (const glm::vec2& c : uv) {
    std::int64_t x0, x1, y0, y1;
    bilinear_pair(c.x, lv.width, x0, x1);
    bilinear_pair(c.y, lv.height, y0, y1);
    for (const std::int64_t y : {y0, y1}) {
      for (const std::int64_t x : {x0, x1}) {
        add(line_of(t, out.level, static_cast<std::uint32_t>(x), static_cast<std::uint32_t>(y)));
      }
    }
  }
}

namespace {

/// Spread of every byte value to the even bits of 16 (a Morton code's x half).
struct SpreadTable {
  std::array<std::uint16_t, 256> v{};
  constexpr SpreadTable() {
    for (std::uint32_t i = 0; i < 256; ++i) {
      std::uint32_t s = 0;
      for (int b = 0; b < 8; ++b) s |= ((i >> b) & 1u) << (2 * b);
      v[i] = static_cast<std::uint16_t>(s);
    }
  }
};
constexpr SpreadTable kSpread;

/// spread_bits for values below 2^24.
inline std::uint64_t spread24(std::uint32_t x) {
  return std::uint64_t{kSpread.v[x & 0xffu]} | (std::uint64_t{kSpread.v[(x >> 8) & 0xffu]} << 16) |
         (std::uint64_t{kSpread.v[(x >> 16) & 0xffu]} << 32);
}

/// floor(c) for |c| < 2^30.
inline float floor_small(float c) {
  const auto i = static_cast<std::int32_t>(c);
  return static_cast<float>(i - static_cast<std::int32_t>(c < static_cast<float>(i)));
}

/// The blocks a bilinear pair covers in an 8x8 window: 1x1, 2x1, 1x2 or 2x2, by (dx + 2 dy).
constexpr std::array<std::uint64_t, 4> kPairBlocks{0x1, 0x3, 0x101, 0x303};

/// Per byte (window row), the low k bits: the columns kept when the window shifts by 8 - k.
constexpr std::uint64_t low_columns(int k) { return k <= 0 ? 0 : (0x0101010101010101ull * ((1u << k) - 1u)); }

}  // namespace

void TextureLayout::quad_blocks(const TextureStorage& t, const std::array<glm::vec2, 4>& uv, QuadFootprint& out) const {
  out.level = quad_level(t, uv);
  const std::uint32_t l = out.level;
  const TextureLevel& lv = t.level[l];
  // Only near-zero, finite first coordinates: the others must lie within 3 repeats of it.
  if (!lv.line_blocks || !(std::fabs(uv[0].x) < 1e9f && std::fabs(uv[0].y) < 1e9f)) return footprint_by_texel(t, uv, out);
  const std::uint32_t cols = lv.line_cols, rows = lv.line_rows;
  out.blocks = true;
  if (cols == 1 && rows == 1) {  // the whole level is one line
    out.mask = 1;
    out.base_x = out.base_y = 0;
    out.count = 1;
    return;
  }
  // Fixed point (32 bits), 1/256 of a level-0 texel, relative to the integer part of the first uv
  // (repeats keep their spacing) plus 4 repeats (all positive). At level l the bilinear pair along x is
  // t0 = floor(X / 2^(8+l) - 0.5) and t0 + 1, i.e. the line blocks (X -/+ 2^(7+l)) >> (8+l+cx)
  // (a shift past every bit when one block spans the level). Level sizes are the texture's
  // scaled by exactly 2^-l (line_blocks), so the block grid wraps every `cols` blocks.
  const float ou = floor_small(uv[0].x), ov = floor_small(uv[0].y);
  const float su = static_cast<float>(t.width) * 256.0f, sv = static_cast<float>(t.height) * 256.0f;
  const auto off_u = static_cast<std::int32_t>(t.width << 10), off_v = static_cast<std::int32_t>(t.height << 10);
  const std::int32_t half = std::int32_t{1} << (7 + l);
  const int sx = cols == 1 ? 63 : static_cast<int>(8 + l + lv.line_x_log2);
  const int sy = rows == 1 ? 63 : static_cast<int>(8 + l + lv.line_y_log2);
  // Each fetch's pair of blocks is placed in an 8x8 window anchored 3 blocks before the first
  // fetch's first block: pos = column + 8 row of its first block, idx = its shape (kPairBlocks).
  alignas(16) std::array<std::int32_t, 4> pos, idx;
  std::int32_t anchor_x = 0, anchor_y = 0;
#if defined(__SSE2__)
  {
    const __m128 a = _mm_loadu_ps(&uv[0].x);  // u0 v0 u1 v1
    const __m128 b = _mm_loadu_ps(&uv[2].x);  // u2 v2 u3 v3
    const __m128 du = _mm_sub_ps(_mm_shuffle_ps(a, b, _MM_SHUFFLE(2, 0, 2, 0)), _mm_set1_ps(ou));
    const __m128 dv = _mm_sub_ps(_mm_shuffle_ps(a, b, _MM_SHUFFLE(3, 1, 3, 1)), _mm_set1_ps(ov));
    const __m128 abs = _mm_castsi128_ps(_mm_set1_epi32(0x7fffffff));
    const __m128 lim = _mm_set1_ps(3.0f);
    if (_mm_movemask_ps(_mm_and_ps(_mm_cmplt_ps(_mm_and_ps(du, abs), lim), _mm_cmplt_ps(_mm_and_ps(dv, abs), lim))) != 0xf) {
      return footprint_by_texel(t, uv, out);
    }
    const __m128i x = _mm_add_epi32(_mm_cvttps_epi32(_mm_mul_ps(du, _mm_set1_ps(su))), _mm_set1_epi32(off_u));
    const __m128i y = _mm_add_epi32(_mm_cvttps_epi32(_mm_mul_ps(dv, _mm_set1_ps(sv))), _mm_set1_epi32(off_v));
    const __m128i h = _mm_set1_epi32(half);
    const __m128i cx = _mm_cvtsi32_si128(sx), cy = _mm_cvtsi32_si128(sy);
    const __m128i bx = _mm_sra_epi32(_mm_sub_epi32(x, h), cx), by = _mm_sra_epi32(_mm_sub_epi32(y, h), cy);
    const __m128i ex = _mm_sub_epi32(_mm_sra_epi32(_mm_add_epi32(x, h), cx), bx);
    const __m128i ey = _mm_sub_epi32(_mm_sra_epi32(_mm_add_epi32(y, h), cy), by);
    anchor_x = _mm_cvtsi128_si32(bx) - 3;
    anchor_y = _mm_cvtsi128_si32(by) - 3;
    const __m128i rx = _mm_sub_epi32(bx, _mm_set1_epi32(anchor_x)), ry = _mm_sub_epi32(by, _mm_set1_epi32(anchor_y));
    const __m128i seven = _mm_set1_epi32(7);
    // Inside the window: rx >= 0 and rx + ex <= 7 (the same for rows); any negative term fails.
    const __m128i bad = _mm_or_si128(_mm_or_si128(rx, _mm_sub_epi32(_mm_sub_epi32(seven, rx), ex)),
                                     _mm_or_si128(ry, _mm_sub_epi32(_mm_sub_epi32(seven, ry), ey)));
    if (_mm_movemask_ps(_mm_castsi128_ps(bad)) != 0) return footprint_by_texel(t, uv, out);
    _mm_store_si128(reinterpret_cast<__m128i*>(pos.data()), _mm_add_epi32(rx, _mm_slli_epi32(ry, 3)));
    _mm_store_si128(reinterpret_cast<__m128i*>(idx.data()), _mm_add_epi32(ex, _mm_slli_epi32(ey, 1)));
  }
#else
  for (std::size_t i = 0; i < 4; ++i) {
    const float du = uv[i].x - ou, dv = uv[i].y - ov;
    if (!(std::fabs(du) < 3.0f && std::fabs(dv) < 3.0f)) return footprint_by_texel(t, uv, out);
    const std::int32_t x = static_cast<std::int32_t>(du * su) + off_u, y = static_cast<std::int32_t>(dv * sv) + off_v;
    const std::int32_t bx = sx > 31 ? 0 : (x - half) >> sx, ex = (sx > 31 ? 0 : (x + half) >> sx) - bx;
    const std::int32_t by = sy > 31 ? 0 : (y - half) >> sy, ey = (sy > 31 ? 0 : (y + half) >> sy) - by;
    if (i == 0) {
      anchor_x = bx - 3;
      anchor_y = by - 3;
    }
    const std::int32_t rx = bx - anchor_x, ry = by - anchor_y;
    if (rx < 0 || rx + ex > 7 || ry < 0 || ry + ey > 7) return footprint_by_texel(t, uv, out);
    pos[i] = rx + 8 * ry;
    idx[i] = ex + 2 * ey;
  }
#endif
  std::uint64_t mask = 0;
  for (std::size_t i = 0; i < 4; ++i) mask |= kPairBlocks[static_cast<std::size_t>(idx[i])] << pos[i];
  // With fewer than 8 blocks a side, the span must not wrap onto itself.
  if (cols < 8) {
    std::uint64_t c = mask | (mask >> 32);
    c |= c >> 16;
    c |= c >> 8;
    c &= 0xffu;
    if (std::bit_width(c) - static_cast<std::uint64_t>(std::countr_zero(c)) > cols) return footprint_by_texel(t, uv, out);
  }
  if (rows < 8) {
    const auto lo = static_cast<std::uint32_t>(std::countr_zero(mask)) >> 3, hi = (static_cast<std::uint32_t>(std::bit_width(mask)) - 1) >> 3;
    if (hi - lo + 1 > rows) return footprint_by_texel(t, uv, out);
  }
  out.mask = mask;
  out.base_x = static_cast<std::uint32_t>(anchor_x) & (cols - 1);  // powers of two
  out.base_y = static_cast<std::uint32_t>(anchor_y) & (rows - 1);
  out.count = bit_count(mask);
}

std::uint32_t TextureLayout::block_lines(const TextureStorage& t, const QuadFootprint& fp, std::uint64_t bits,
                                         std::uint64_t* out) const {
  const TextureLevel& lv = t.level[fp.level];
  const std::uint64_t level_base = t.base + lv.offset;
  const std::uint32_t col_mask = lv.line_cols - 1, row_mask = lv.line_rows - 1;
  const std::uint32_t m = lv.block_log2, low = (std::uint32_t{1} << m) - 1;
  const std::uint64_t line_mask = ~std::uint64_t{line_bytes_ - 1};
  std::uint32_t n = 0;
  while (bits != 0) {
    const auto bit = static_cast<std::uint32_t>(std::countr_zero(bits));
    bits &= bits - 1;
    const std::uint32_t x = ((fp.base_x + (bit & 7)) & col_mask) << lv.line_x_log2;
    const std::uint32_t y = ((fp.base_y + (bit >> 3)) & row_mask) << lv.line_y_log2;
    const std::uint64_t texel = spread24(x & low) + (spread24(y & low) << 1) +
                                ((static_cast<std::uint64_t>(x >> m) + static_cast<std::uint64_t>(y >> m)) << (2 * m));
    out[n++] = level_base + ((texel << texel_shift_) & line_mask);
  }
  return n;
}

std::uint64_t TextureLayout::new_blocks(const TextureStorage& t, const QuadFootprint& prev, const QuadFootprint& cur) const {
  if (!prev.blocks || !cur.blocks || prev.level != cur.level) return cur.mask;
  const TextureLevel& lv = t.level[cur.level];
  // Offsets of prev's window in cur's, wrapped to the nearest copy; with fewer than 16 blocks a
  // side two window positions could alias the same block, so only equal windows compare.
  auto offset = [](std::uint32_t a, std::uint32_t b, std::uint32_t n, std::int32_t& d) {
    d = static_cast<std::int32_t>(a) - static_cast<std::int32_t>(b);
    if (n < 16) return d == 0;
    if (d > static_cast<std::int32_t>(n / 2)) d -= static_cast<std::int32_t>(n);
    if (d < -static_cast<std::int32_t>(n / 2)) d += static_cast<std::int32_t>(n);
    return d > -8 && d < 8;
  };
  std::int32_t dc = 0, dr = 0;
  if (!offset(prev.base_x, cur.base_x, lv.line_cols, dc) || !offset(prev.base_y, cur.base_y, lv.line_rows, dr)) {
    return cur.mask;
  }
  // prev's bit c + 8r lies at column c + dc, row r + dr of cur's window.
  std::uint64_t p = prev.mask;
  p = dc >= 0 ? (p << dc) & ~low_columns(dc) : (p >> -dc) & low_columns(8 + dc);
  p = dr >= 0 ? p << (8 * dr) : p >> (8 * -dr);
  return cur.mask & ~p;
}

void TextureLayout::quad_footprint(const TextureStorage& t, const std::array<glm::vec2, 4>& uv, QuadFootprint& out) const {
  quad_blocks(t, uv, out);
  if (out.blocks) block_lines(t, out, out.mask, out.lines.data());
}

std::uint32_t TextureLayout::append_quad_lines(const TextureStorage& t, std::uint32_t slot,
                                               const std::array<glm::vec2, 4>& uv,
                                               std::vector<std::uint64_t>& lines) const {
  QuadFootprint fp;
  quad_footprint(t, uv, fp);
  const std::uint64_t shift = std::uint64_t{slot} * t.slot_bytes;
  for (std::uint32_t j = 0; j < fp.count; ++j) lines.push_back(fp.lines[j] + shift);
  return fp.count;
}

}  // namespace tbdr
