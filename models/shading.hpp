#pragma once
// The fixed shading model every technique's image is computed with (Lambert diffuse plus
// Blinn-Phong specular, point and spot lights with the finite-radius attenuation), so images of
// different techniques can be compared pixel for pixel. Which lights a fragment evaluates is the
// technique's business; lights beyond their radius contribute exactly zero, so any conservative
// culling gives the same color.
#include <array>
#include <bit>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <type_traits>
#include <vector>

#include <glm/glm.hpp>

#include "scene/lights.hpp"
#include "trace/trace.hpp"

namespace tbdr {

/// The surface attributes at one shaded pixel: what a G-buffer would hold.
struct SurfacePoint {
  glm::vec3 position{0.0f};  ///< world space
  glm::vec3 normal{0.0f, 1.0f, 0.0f};  ///< world space, unit length, facing the viewer side
  glm::vec3 albedo{1.0f};    ///< linear RGB base color
  float alpha = 1.0f;        ///< coverage / opacity
  std::uint32_t material = 0xffffffffu;  ///< scene material (visibility-buffer work lists)
  std::uint32_t triangle = 0xffffffffu;  ///< frame-unique primitive id (visibility-buffer re-fetch)
  /// The uvs at the 4 pixel centres of the pixel's 2x2 quad, (x,y), (x+1,y), (x,y+1), (x+1,y+1)
  /// from its even corner, on the triangle's perspective-correct uv plane (helper lanes
  /// extrapolate it), exactly as the TSP computes them for its texture fetches: a kernel that
  /// reads the surface samples the material's textures at the same level and texels. Set for
  /// surfaces of scene triangles (material != none).
  std::array<glm::vec2, 4> quad_uv{};
};

/// The parts of a stored surface that runs without colours read too: where it is (clusters, the
/// colour loop's light cut), its material and triangle (visibility-buffer work lists and
/// re-fetches) and its quad uvs (the shading kernels' material fetches). 52 bytes.
struct SurfaceSite {
  glm::vec3 position;
  std::uint32_t material;
  std::uint32_t triangle;
  std::array<glm::vec2, 4> quad_uv;
};

/// The parts of a stored surface only colours read (the shading model): 28 bytes.
struct SurfaceLook {
  glm::vec3 normal;
  glm::vec3 albedo;
  float alpha;
};

/// The surfaces a G-buffer, visibility attachment or PLS stores, one per sample, as two arrays:
/// the sites every run reads and the looks kept only when the frame computes colours
/// (FrameInputs::colour). At 3840x2160 a store is 8.3 M samples: 431 MB without colours instead
/// of the 663 MB of whole SurfacePoints. Values read back are bit-identical to those stored; a
/// store without looks reads back SurfacePoint's defaults for them (nothing reads them then).
/// The arrays are not initialised: a sample is read only where its owner's valid flag
/// (AttachmentImage::surface_valid, PlsState::valid) says set() stored it. So allocating a store
/// writes nothing: the pages a frame's tiles write are faulted in by the threads that write them,
/// and those of samples never written (the sky) are never touched.
class SurfaceStore {
  static_assert(std::is_trivially_default_constructible_v<SurfaceSite> && std::is_trivially_default_constructible_v<SurfaceLook>,
                "a store's allocation must write nothing");

 public:
  /// `n` unset surfaces; their looks only with `colour`.
  void assign(std::size_t n, bool colour) {
    release();
    if (n == 0) return;
    sites_.reset(new SurfaceSite[n]);  // default-initialised: no writes (see the class comment)
    if (colour) looks_.reset(new SurfaceLook[n]);
    size_ = n;
  }
  /// Gives the memory back (empty() after).
  void release() {
    sites_.reset();
    looks_.reset();
    size_ = 0;
  }
  bool empty() const { return size_ == 0; }
  std::size_t size() const { return size_; }
  /// The site of sample `k` (set before), without copying its look.
  const SurfaceSite& site(std::size_t k) const { return sites_[k]; }
  /// The look of sample `k` (set before; the store keeps looks, with colours), without its site.
  const SurfaceLook& look(std::size_t k) const { return looks_[k]; }
  /// The whole surface of sample `k` (set before).
  SurfacePoint operator[](std::size_t k) const {
    SurfacePoint s;
    const SurfaceSite& a = sites_[k];
    s.position = a.position;
    s.material = a.material;
    s.triangle = a.triangle;
    s.quad_uv = a.quad_uv;
    if (looks_) {
      const SurfaceLook& b = looks_[k];
      s.normal = b.normal;
      s.albedo = b.albedo;
      s.alpha = b.alpha;
    }
    return s;
  }
  /// Stores `s` at sample `k` (its look only if looks are kept).
  void set(std::size_t k, const SurfacePoint& s) {
    sites_[k] = site_of(s);
    if (looks_) looks_[k] = look_of(s);
  }

 private:
  static SurfaceSite site_of(const SurfacePoint& s) { return {s.position, s.material, s.triangle, s.quad_uv}; }
  static SurfaceLook look_of(const SurfacePoint& s) { return {s.normal, s.albedo, s.alpha}; }

  std::unique_ptr<SurfaceSite[]> sites_;
  std::unique_ptr<SurfaceLook[]> looks_;  ///< null without colours
  std::size_t size_ = 0;
};

/// Constants of the shading model.
struct ShadingModel {
  static constexpr float kAmbient = 0.03f;        ///< ambient term times albedo
  static constexpr float kSpecular = 0.25f;       ///< specular reflectance (white)
  static constexpr float kShininess = 32.0f;      ///< Blinn-Phong exponent

  /// Radiance leaving `s` towards `eye` from one light (0 outside its radius or cone). The test
  /// against the radius is inline: most candidate lights of a pixel are rejected by it.
  static glm::vec3 light_contribution(const SurfacePoint& s, glm::vec3 eye, const Light& light) {
    if (!reaches(light, s.position)) return glm::vec3(0.0f);
    return lit_contribution(s, eye, light);
  }
  /// Whether a point lies inside the light's radius: light_contribution is exactly 0 where not,
  /// whatever the rest of the surface.
  static bool reaches(const Light& light, const glm::vec3& position) {
    const glm::vec3 d = light.position - position;
    return glm::dot(d, d) < light.radius * light.radius;
  }
  /// light_contribution for a light whose sphere contains the surface point.
  static glm::vec3 lit_contribution(const SurfacePoint& s, glm::vec3 eye, const Light& light);
  /// The ambient term.
  static glm::vec3 ambient(const SurfacePoint& s) { return s.albedo * kAmbient; }
};

namespace detail {

/// unorm(x, 8) of each channel of an rgba8 value, without branches (one vector for the four
/// channels): clamped to [0, 1] (NaN to 0), then rounded to 255 steps by adding and subtracting
/// 2^23 (round to nearest even, as nearbyint) below 255. Bit for bit the value of unorm(x, 8) in
/// models/shading.cpp (test UnitTsp.SmallFloatRoundingMatchesTheLibraryFormulaEverywhere).
inline glm::vec4 unorm8_4(const glm::vec4& v) {
  constexpr float kSteps = 255.0f;
  constexpr float kRoundingMagic = 8388608.0f;  // 2^23
#if defined(__GNUC__)
  // GCC's and Clang's generic vectors (any target: lowered to scalars where there is no SIMD).
  using Float4 = float __attribute__((vector_size(16)));
  const Float4 x = {v.x, v.y, v.z, v.w};
  const Float4 zero = {0.0f, 0.0f, 0.0f, 0.0f}, one = {1.0f, 1.0f, 1.0f, 1.0f};
  const Float4 positive = x > zero ? x : zero;  // NaN: 0
  const Float4 clamped = positive < one ? positive : one;
  const Float4 r = ((clamped * kSteps + kRoundingMagic) - kRoundingMagic) / kSteps;
  return {r[0], r[1], r[2], r[3]};
#else
  float out[4];
  for (int c = 0; c < 4; ++c) {
    const float x = v[c];
    const float clamped = x > 0.0f ? (x < 1.0f ? x : 1.0f) : 0.0f;  // NaN: 0
    out[c] = ((clamped * kSteps + kRoundingMagic) - kRoundingMagic) / kSteps;
  }
  return {out[0], out[1], out[2], out[3]};
#endif
}

/// small_float(x, mantissa, true) (models/shading.cpp) of one channel without branches, so that
/// the compiler computes four channels in one vector: the exponent field gives the rounding step,
/// NaN becomes +0 and the sign is put back at the end. `largest` is the format's largest finite
/// value, (2 - 2^-mantissa) 2^15. Bit for bit small_float (test
/// UnitTsp.SmallFloatRoundingMatchesTheLibraryFormulaEverywhere reads every lane).
inline float small_float_lane(float x, std::int32_t mantissa, float largest) {
  constexpr std::int32_t kMinExponent = -14;
  constexpr std::int32_t kFloatBias = 127;
  constexpr float kRoundingMagic = 8388608.0f;  // 2^23
  const std::uint32_t bits = std::bit_cast<std::uint32_t>(x);
  const std::uint32_t magnitude = bits & 0x7fffffffu;
  const float a = std::bit_cast<float>(magnitude);
  const std::int32_t exponent = static_cast<std::int32_t>(magnitude >> 23) - kFloatBias;  // NaN, infinity: 128
  const std::int32_t lead = exponent > kMinExponent ? exponent : kMinExponent;
  const float step = std::bit_cast<float>(static_cast<std::uint32_t>(lead - mantissa + kFloatBias) << 23);
  const float per_step = std::bit_cast<float>(static_cast<std::uint32_t>(mantissa - lead + kFloatBias) << 23);
  const float rounded = (a * per_step + kRoundingMagic) - kRoundingMagic;
  const float q = rounded * step;
  const float saturated = q < largest ? q : largest;  // (infinity too)
  const float signed_q = std::bit_cast<float>(std::bit_cast<std::uint32_t>(saturated) | (bits & 0x80000000u));
  return a == a ? signed_q : 0.0f;  // NaN: 0
}

/// An rgba16f value (the additive light passes' target, quantised at every blended sample):
/// small_float(x, 10, true) of each channel.
inline glm::vec4 half_float4(const glm::vec4& v) {
  constexpr float kLargest = 65504.0f;  // (2 - 2^-10) 2^15
  const float in[4] = {v.x, v.y, v.z, v.w};
  float out[4];
  for (int c = 0; c < 4; ++c) out[c] = small_float_lane(in[c], 10, kLargest);
  return {out[0], out[1], out[2], out[3]};
}

/// An r11g11b10f value (the PLS light accumulator of deferred_tile_store, quantised at every
/// light-volume fragment): small_float(x, 6, 6 and 5 mantissa bits, false) of red, green and blue
/// (negatives to +0, as the unsigned formats clamp them), alpha 1 (a channel the format lacks).
#if defined(__GNUC__)
[[gnu::always_inline]]
#endif
inline glm::vec4 r11g11b10f4(const glm::vec4& v) {
  constexpr std::int32_t kMantissa[4] = {6, 6, 5, 5};
  constexpr float kLargest[4] = {65024.0f, 65024.0f, 64512.0f, 64512.0f};  // (2 - 2^-m) 2^15
  const float in[4] = {v.x, v.y, v.z, v.w};
  float out[4];
  for (int c = 0; c < 4; ++c) {
    const float q = small_float_lane(in[c], kMantissa[c], kLargest[c]);
    out[c] = in[c] < 0.0f ? 0.0f : q;
  }
  return {out[0], out[1], out[2], 1.0f};
}

}  // namespace detail

/// What an attachment (or PLS variable) of a given format keeps of the values written to it: the
/// formats' precision, applied at every write (blending reads back what was stored).
struct FormatPrecision {
  /// The colour a target of format `f` holds after `v` is written: unorm formats clamp to [0, 1]
  /// and round to 2^bits - 1 steps (rgba8 8 bits, rgb10a2 10 and 2 for alpha); float formats round
  /// to their mantissa (fp16 10 bits, r11g11b10f 6/6/5 bits, unsigned) and saturate at their
  /// largest finite value; 32-bit float formats keep v. Channels the format lacks read back 0
  /// (alpha 1), Vulkan's "Conversion to RGBA" rule. Integer and depth formats keep v.
  /// Inline for the formats colour targets and PLS accumulators use most (additive light passes
  /// quantise every blended sample; GCC left the call out of line once it had three formats, and
  /// the value then crossed memory: a store-forwarding stall per call): one switch per value, the
  /// four channels at once.
#if defined(__GNUC__)
  [[gnu::always_inline]]
#endif
  static glm::vec4 color(Format f, const glm::vec4& v) {
    switch (f) {
      case Format::Rgba16f: return detail::half_float4(v);
      case Format::Rgba8: return detail::unorm8_4(v);
      case Format::R11g11b10f: return detail::r11g11b10f4(v);
      case Format::Rgba32f: return v;
      default: return other_color(f, v);
    }
  }
  /// Whether format `f` stores all four channels of a colour with FormatPrecision::color's
  /// rounding: every value such a target holds (its clear, 0, and what color() wrote) is a fixed
  /// point of color(f, .), so adding 0 to it changes nothing (but a -0 in fp16, which would become
  /// +0: an equal value; formats lacking a channel read it back as 0 or 1, which a cleared value
  /// need not be). Test UnitTsp.AddingZeroKeepsWhatAFourChannelTargetHolds.
  static bool keeps_every_channel(Format f) {
    return f == Format::Rgba8 || f == Format::Rgb10a2 || f == Format::Rgba16f || f == Format::Rgba32f;
  }
  /// What a G-buffer target (or PLS variable) keeps of the surface, from its name: found once per
  /// pass (the TSP quantises every stored fragment).
  enum class Attribute : std::uint8_t { Albedo, Normal, Other };
  static Attribute attribute_of(const std::string& name) {
    return name == "albedo" ? Attribute::Albedo : name == "normal" ? Attribute::Normal : Attribute::Other;
  }
  /// The surface a target holding attribute `a` (named "albedo", "normal" or other: attribute_of)
  /// of format `f` keeps: `albedo` stores the base colour (rgb, then alpha where the format has a
  /// fourth channel), `normal` the normal (unorm formats as n/2 + 1/2, two-channel formats
  /// octahedral, float formats n; read back renormalised). The generators lay G-buffers out this
  /// way (workloads/techniques: albedo, normal, then targets holding nothing the model uses);
  /// other names keep the surface.
  static void surface(Attribute a, Format f, SurfacePoint& s);

 private:
  /// color() of the other formats, channel by channel.
  static glm::vec4 other_color(Format f, const glm::vec4& v);
};

}  // namespace tbdr
