#include "models/shading.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>

namespace tbdr {

namespace {

/// The Blinn-Phong exponent as a whole number: the specular power is computed by repeated
/// squaring (five multiplications for 32) instead of a powf call per lit light.
constexpr unsigned kWholeShininess = static_cast<unsigned>(ShadingModel::kShininess);
static_assert(static_cast<float>(kWholeShininess) == ShadingModel::kShininess, "the exponent must be whole");

/// x^n by binary exponentiation.
float whole_power(float x, unsigned n) {
  float r = 1.0f;
  for (; n != 0; n >>= 1) {
    if (n & 1u) r *= x;
    x *= x;
  }
  return r;
}

}  // namespace

glm::vec3 ShadingModel::lit_contribution(const SurfacePoint& s, glm::vec3 eye, const Light& light) {
  const glm::vec3 to_light = light.position - s.position;
  const float dist2 = glm::dot(to_light, to_light);
  if (!(dist2 < light.radius * light.radius)) return glm::vec3(0.0f);  // beyond the radius: exactly 0
  const float dist = std::sqrt(dist2);
  const float atten = light_attenuation(dist, light.radius);
  if (atten <= 0.0f) return glm::vec3(0.0f);
  const glm::vec3 l = dist > 0.0f ? to_light / dist : s.normal;
  float cone = 1.0f;
  if (light.type == Light::Type::Spot) {
    const float cd = glm::dot(-l, light.direction);
    if (cd <= light.cos_outer) return glm::vec3(0.0f);
    const float span = light.cos_inner - light.cos_outer;
    cone = span > 0.0f ? glm::clamp((cd - light.cos_outer) / span, 0.0f, 1.0f) : 1.0f;
  }
  const float n_dot_l = glm::dot(s.normal, l);
  if (n_dot_l <= 0.0f) return glm::vec3(0.0f);
  const glm::vec3 v = glm::normalize(eye - s.position);
  const glm::vec3 h = glm::normalize(l + v);
  const float spec = whole_power(glm::max(glm::dot(s.normal, h), 0.0f), kWholeShininess) * kSpecular;
  return light.color * (light.intensity * atten * cone) * (s.albedo * n_dot_l + glm::vec3(spec * n_dot_l));
}

namespace {

/// A unorm channel of `bits` bits: clamped to [0, 1], rounded to the nearest of 2^bits - 1 steps.
float unorm(float x, int bits) {
  const auto steps = static_cast<float>((1u << bits) - 1u);
  if (!(x > 0.0f)) return 0.0f;  // also NaN
  if (x >= 1.0f) return 1.0f;
  return std::nearbyint(x * steps) / steps;
}

/// A small float channel: `mantissa` bits, exponent bias 15 (fp16, r11g11b10f's 5-bit exponent),
/// rounded to nearest even, saturating at the largest finite value; unsigned ones clamp
/// negatives to 0. The rounding step is the power of two 2^(lead - mantissa), lead being the
/// exponent of x's leading bit (at least the smallest normal exponent, -14: below it, the
/// denormal step), read from x's exponent field; dividing by a power of two and multiplying back
/// are exact, and adding and subtracting 2^23 rounds a value below 2^23 to the nearest integer,
/// ties to even (IEEE 754's default rounding): the same value as
/// nearbyint(|x| / ldexp(1, lead - mantissa)) * step, without the library calls
/// (test UnitTsp.SmallFloatRoundingMatchesTheLibraryFormulaEverywhere).
float small_float(float x, int mantissa, bool is_signed) {
  constexpr int kMinExponent = -14;  // smallest normal exponent with a 5-bit exponent, bias 15
  constexpr int kMaxExponent = 15;
  constexpr int kFloatBias = 127;
  constexpr float kRoundingMagic = 8388608.0f;  // 2^23: float's spacing is 1 from here on
  if (std::isnan(x)) return 0.0f;
  if (!is_signed && x < 0.0f) return 0.0f;
  const float a = std::fabs(x);
  if (a == 0.0f) return x;
  const int exponent = static_cast<int>(std::bit_cast<std::uint32_t>(a) >> 23) - kFloatBias;  // infinity: 128
  const int lead = std::max(exponent, kMinExponent);  // float denormals (exponent -127) too
  const auto power_of_two = [](int e) { return std::bit_cast<float>(static_cast<std::uint32_t>(e + kFloatBias) << 23); };
  const float step = power_of_two(lead - mantissa);  // -24 .. 118: a normal float
  const float units = a * power_of_two(mantissa - lead);  // a / step, exact; below 2^(mantissa+1) (or infinite)
  const float rounded = (units + kRoundingMagic) - kRoundingMagic;
  const float largest = power_of_two(kMaxExponent + 1) - power_of_two(kMaxExponent - mantissa);  // (2 - 2^-mantissa) 2^15, exact
  const float q = std::min(rounded * step, largest);
  return std::copysign(q, x);
}

/// Octahedral encoding of a unit vector into [-1, 1]^2 and back (Cigolle et al. 2014, "A Survey
/// of Efficient Representations for Independent Unit Vectors").
glm::vec2 octahedral(glm::vec3 n) {
  n /= (std::fabs(n.x) + std::fabs(n.y) + std::fabs(n.z));
  glm::vec2 p(n.x, n.y);
  if (n.z < 0.0f) {
    p = glm::vec2((1.0f - std::fabs(n.y)) * (n.x >= 0.0f ? 1.0f : -1.0f), (1.0f - std::fabs(n.x)) * (n.y >= 0.0f ? 1.0f : -1.0f));
  }
  return p;
}
glm::vec3 from_octahedral(glm::vec2 p) {
  glm::vec3 n(p.x, p.y, 1.0f - std::fabs(p.x) - std::fabs(p.y));
  if (n.z < 0.0f) {
    n = glm::vec3((1.0f - std::fabs(p.y)) * (p.x >= 0.0f ? 1.0f : -1.0f), (1.0f - std::fabs(p.x)) * (p.y >= 0.0f ? 1.0f : -1.0f), n.z);
  }
  return n;
}

/// Channels a colour format stores (0 for integer and depth formats: nothing to quantise).
int channels_of(Format f) {
  switch (f) {
    case Format::R8: case Format::R16f: case Format::R32f: return 1;
    case Format::Rg8: case Format::Rg16f: case Format::Rg32f: return 2;
    case Format::R11g11b10f: return 3;
    case Format::Rgba8: case Format::Rgb10a2: case Format::Rgba16f: case Format::Rgba32f: return 4;
    default: return 0;
  }
}

/// Channel c of a value written to format f (c < channels_of(f)).
float channel(Format f, int c, float x) {
  switch (f) {
    case Format::R8: case Format::Rg8: case Format::Rgba8: return unorm(x, 8);
    case Format::Rgb10a2: return unorm(x, c < 3 ? 10 : 2);
    case Format::R11g11b10f: return small_float(x, c < 2 ? 6 : 5, false);
    case Format::R16f: case Format::Rg16f: case Format::Rgba16f: return small_float(x, 10, true);
    default: return x;  // 32-bit float
  }
}

bool is_unorm(Format f) {
  return f == Format::R8 || f == Format::Rg8 || f == Format::Rgba8 || f == Format::Rgb10a2;
}

}  // namespace

glm::vec4 FormatPrecision::other_color(Format f, const glm::vec4& v) {
  const int n = channels_of(f);
  if (n == 0) return v;
  glm::vec4 out(0.0f, 0.0f, 0.0f, 1.0f);
  for (int c = 0; c < n; ++c) out[c] = channel(f, c, v[c]);
  return out;
}

void FormatPrecision::surface(Attribute a, Format f, SurfacePoint& s) {
  if (a == Attribute::Other) return;
  const int n = channels_of(f);
  if (n == 0) return;
  if (a == Attribute::Albedo && f == Format::Rgba8) {  // the G-buffers' usual albedo: four channels at once, bit for bit unorm
    const glm::vec4 q = detail::unorm8_4(glm::vec4(s.albedo, s.alpha));
    s.albedo = glm::vec3(q);
    s.alpha = q.w;
  } else if (a == Attribute::Albedo) {
    for (int c = 0; c < std::min(n, 3); ++c) s.albedo[c] = channel(f, c, s.albedo[c]);
    if (n == 4) s.alpha = channel(f, 3, s.alpha);
  } else {  // Attribute::Normal
    glm::vec3 q = s.normal;
    if (n >= 3) {
      const bool unsigned_range = is_unorm(f) || f == Format::R11g11b10f;
      for (int c = 0; c < 3; ++c) {
        q[c] = unsigned_range ? channel(f, c, q[c] * 0.5f + 0.5f) * 2.0f - 1.0f : channel(f, c, q[c]);
      }
    } else if (n == 2) {
      glm::vec2 p = octahedral(q);
      for (int c = 0; c < 2; ++c) p[c] = is_unorm(f) ? channel(f, c, p[c] * 0.5f + 0.5f) * 2.0f - 1.0f : channel(f, c, p[c]);
      q = from_octahedral(p);
    } else {
      return;  // one channel cannot hold a normal
    }
    const float len = glm::length(q);
    if (len > 0.0f) s.normal = q / len;
  }
}

}  // namespace tbdr
