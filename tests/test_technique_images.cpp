// Every technique computes the same image up to what its attachment formats keep: conservative
// culling never changes a pixel, and every write is quantised to its target's format
// (FormatPrecision), so each technique's tolerance follows from its formats (kTolerances). Compared
// on the atrium without its translucent glass, and with the glass for the compute-shaded techniques
// (their translucent pass over the kernel-written frame), at a small resolution, with plain
// forward (one rgba8 write of the float sum) as the reference.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <map>

#include "models/hw_config.hpp"
#include "models/command_processor.hpp"
#include "app/image_output.hpp"
#include "scene/lights.hpp"
#include "scene/scene_library.hpp"
#include "stat_lookup.hpp"
#include "techniques/technique.hpp"
#include "atrium_trace_setup.hpp"

namespace tbdr {
namespace {

/// The atrium at detail 1 with its translucent instances removed (same hash: the trace refers
/// to the atrium; the simulator draws what this scene holds).
Scene opaque_atrium() {
  Scene s = load_scene("atrium:1");
  std::vector<Instance> kept;
  for (const auto& inst : s.instances) {
    if (s.materials[s.submeshes[inst.submesh].material].alpha_mode != AlphaMode::Translucent) kept.push_back(inst);
  }
  s.instances = kept;
  return s;
}

ImageRGB8 final_image(const FrameResult& f) {
  if (auto it = f.images.attachments.find(f.final_color); it != f.images.attachments.end()) {
    return color_to_image(it->second.color, f.images.width, f.images.height);
  }
  return color_to_image(f.images.image_buffers.at(f.final_color).color, f.images.width, f.images.height);
}

/// How far a technique's image may be from plain forward's, per channel in 1/255 steps: the
/// largest difference and the share of channels more than 1/255 off.
struct Tolerance {
  int worst = 1;
  double share_over_one = 0.0;
};

/// Each technique's tolerance from its formats (default: 1/255 everywhere).
/// - One rgba8 write (or rgba8 image) of the same float sum as the reference: the forward
///   family with light lists, forward_light_stack, visibility_buffer at 1 sample: 1/255 from
///   the summation order.
/// - forward_multipass: an rgba8 target accumulates one additive pass per light (64 here), and
///   every pass whose light reaches the pixel rounds the sum to 1/255 again (up to 1/2 step each):
///   the error grows with the lights overlapping a pixel (measured 9/255 on 2 % of channels with
///   untextured albedo, 13/255 on 2.3 % with the atrium's textured albedo: the tolerance is 16).
/// - deferred: its light volumes add into the rgba8 frame one light at a time, the rounding of
///   forward_multipass (the same 1352 channels with an exact rgba32f G-buffer); the G-buffer adds
///   its own: the albedo rounds to 1/255 and is multiplied by the light falling on the pixel
///   (several times 1 near the lights), the 10-bit normal moves the Blinn-Phong lobe (exponent 32)
///   by up to 32 x 1.4e-3 of its height (56 more channels; an rgba8 normal 400 more).
/// - clustered_deferred (albedo rgba8, normal rgb10a2) and tiled_deferred (Andersson's 4 x rgba8:
///   an 8-bit normal): one rgba8 image write, so only the G-buffer's rounding: measured 13/255 on
///   1.0 % and 1.4 % (textured albedo).
/// - light_prepass (rgba8 normal buffer, rgba16f light buffer): the 8-bit normal changes every
///   lit pixel's N.L by up to 1/255 rad x the light (measured 7/255 on half the channels); fp16
///   accumulation adds at most 2^-11 of the sum per light volume.
/// - deferred_tile_store (PLS albedo and light accumulator r11g11b10f, normal rgb10a2): 6- and
///   5-bit mantissas: the albedo and every accumulated light volume round to 1/64 .. 1/32 of their
///   value (measured 13/255 on 3.2 %, textured albedo).
/// - visibility_buffer with MSAA: the kernel resolves its samples in float and writes rgba8 once,
///   plain forward clamps each sample to [0, 1] in its rgba8 target before the resolve: on edges
///   between an over-bright and a dark surface they differ by up to the over-bright part (41/255
///   measured, on edge pixels only: 2.5 % of channels).
const std::map<std::string, Tolerance> kTolerances = {
    {"forward_multipass", {16, 0.04}},  {"deferred", {16, 0.04}},           {"clustered_deferred", {16, 0.04}},
    {"tiled_deferred", {16, 0.04}},     {"light_prepass", {10, 0.60}},      {"deferred_tile_store", {16, 0.15}},
};
/// The same at 4 samples per pixel.
const std::map<std::string, Tolerance> kMsaaTolerances = {
    {"forward_multipass", {16, 0.04}},
    {"visibility_buffer", {48, 0.05}},
};

/// Plain forward's image of a scene, and its pixels whose visible face depends on the depth test.
struct Reference {
  ImageRGB8 image;
  std::vector<std::uint8_t> ambiguous;  ///< per pixel: 1 where coplanar faces fight
  std::size_t n_ambiguous = 0;
};

Reference plain_forward_reference(const Scene& scene, const TraceSetup& setup, const HwConfig& hw) {
  Reference r;
  const Trace pf = generate_trace("plain_forward", setup);
  r.image = final_image(simulate_frame(pf, "plain_forward", scene, hw));
  // The scene has a few exactly coplanar overlapping faces: which one is visible there depends on
  // the depth test (less keeps the first drawn, less_equal/equal the last). Those pixels are not
  // defined by the scene; find them by rendering the reference with less_equal, and skip them.
  Trace pf_le = pf;
  for (auto& pl : pf_le.pipelines) {
    if (pl.depth_compare == CompareOp::Less) pl.depth_compare = CompareOp::LessEqual;
  }
  const ImageRGB8 ref_le = final_image(simulate_frame(pf_le, "plain_forward_le", scene, hw));
  r.ambiguous.assign(r.image.rgb.size() / 3, 0);
  for (std::size_t i = 0; i < r.image.rgb.size(); ++i) {
    if (r.image.rgb[i] != ref_le.rgb[i] && !r.ambiguous[i / 3]) {
      r.ambiguous[i / 3] = 1;
      ++r.n_ambiguous;
    }
  }
  return r;
}

/// How an image departs from the reference outside its ambiguous pixels.
struct ImageDiff {
  int worst = 0;                   ///< largest channel difference, of 255
  std::size_t channels_over_1 = 0;  ///< channels more than 1/255 apart
  std::size_t pixels_over_1 = 0;    ///< pixels with such a channel
  std::size_t compared = 0;         ///< channels compared (outside the ambiguous pixels)
};

ImageDiff diff_from(const ImageRGB8& img, const Reference& ref) {
  ImageDiff d;
  std::size_t last_pixel = SIZE_MAX;
  for (std::size_t i = 0; i < img.rgb.size(); ++i) {
    if (ref.ambiguous[i / 3]) continue;
    ++d.compared;
    const int c = std::abs(static_cast<int>(img.rgb[i]) - static_cast<int>(ref.image.rgb[i]));
    d.worst = std::max(d.worst, c);
    if (c <= 1) continue;
    ++d.channels_over_1;
    if (i / 3 != last_pixel) ++d.pixels_over_1;
    last_pixel = i / 3;
  }
  return d;
}

/// Renders every technique of `names` on `scene` and compares it with plain forward (see the file
/// comment).
void compare_with_plain_forward(const Scene& scene, int samples, const std::vector<std::string>& names,
                                const std::map<std::string, Tolerance>& tolerances) {
  TraceSetup setup = testing_support::atrium_entrance_setup(scene, 64, 192, 108);
  setup.samples = samples;
  const HwConfig hw = resolve_config({}, {}).hw;
  const Reference ref = plain_forward_reference(scene, setup, hw);
  std::printf("[ image    ] %zu of %zu pixels show coplanar faces (z-fighting) and are skipped\n", ref.n_ambiguous,
              ref.ambiguous.size());
  EXPECT_LT(ref.n_ambiguous, ref.ambiguous.size() / 500);
  for (const auto& name : names) {
    SCOPED_TRACE(name);
    const Trace t = generate_trace(name, setup);
    const FrameResult f = simulate_frame(t, name, scene, hw);
    ASSERT_FALSE(f.final_color.empty());
    const ImageRGB8 img = final_image(f);
    ASSERT_EQ(img.rgb.size(), ref.image.rgb.size());
    const ImageDiff d = diff_from(img, ref);
    const auto it = tolerances.find(name);
    const Tolerance tol = it == tolerances.end() ? Tolerance{} : it->second;
    const double share = static_cast<double>(d.channels_over_1) / static_cast<double>(d.compared);
    std::printf("[ image    ] %dx %-28s largest difference %d/255 (tolerance %d), %zu channels over 1/255 (%.2f %%, "
                "tolerance %.0f %%)\n",
                samples, name.c_str(), d.worst, tol.worst, d.channels_over_1, 100.0 * share, 100.0 * tol.share_over_one);
    EXPECT_LE(d.worst, tol.worst) << name;
    EXPECT_LE(share, tol.share_over_one) << name;
  }
}

TEST(TechniqueImages, EveryTechniqueMatchesPlainForward) {
  compare_with_plain_forward(opaque_atrium(), 1, technique_names(), kTolerances);
}

TEST(TechniqueImages, MsaaTechniquesMatchPlainForwardAt4x) {
  compare_with_plain_forward(opaque_atrium(), 4,
                             {"forward_multipass", "forward_plus", "clustered_forward", "practical_clustered_forward",
                              "cascaded_clustered_forward", "visibility_buffer"},
                             kMsaaTolerances);
}

TEST(TechniqueImages, CoarserFormatsCostPrecision) {
  // The tolerances above are the formats' doing: deferred's difference from plain forward grows as
  // its G-buffer gets coarser, from a 32-bit float one (rgba32f albedo and normal: what is left is
  // the rgba8 accumulation of its light volumes, as forward_multipass') to the default rgba8
  // albedo + rgb10a2 normal to an 8-bit normal (rgba8,rgba8).
  const Scene scene = opaque_atrium();
  const TraceSetup setup = testing_support::atrium_entrance_setup(scene, 64, 192, 108);
  const HwConfig hw = resolve_config({}, {}).hw;
  const ImageRGB8 ref = final_image(simulate_frame(generate_trace("plain_forward", setup), "pf", scene, hw));
  auto worst_with = [&](const std::string& layout) {
    TraceSetup with = setup;
    with.options["gbuffer"] = layout;
    const ImageRGB8 img = final_image(simulate_frame(generate_trace("deferred", with), "d", scene, hw));
    std::size_t over = 0;
    for (std::size_t i = 0; i < img.rgb.size(); ++i) {
      over += std::abs(static_cast<int>(img.rgb[i]) - static_cast<int>(ref.rgb[i])) > 1 ? 1 : 0;
    }
    return over;
  };
  const std::size_t exact = worst_with("rgba32f,rgba32f"), ten = worst_with("rgba8,rgb10a2"), eight = worst_with("rgba8,rgba8");
  std::printf("[ image    ] deferred channels over 1/255: rgba32f G-buffer %zu, rgba8+rgb10a2 %zu, rgba8+rgba8 %zu\n", exact,
              ten, eight);
  EXPECT_GT(ten, exact);
  EXPECT_GT(eight, ten);
}

TEST(TechniqueImages, GlassOverComputeLitFramesMatchesPlainForward) {
  // The full atrium, glass included. The compute-shaded techniques draw the glass in a forward pass
  // over their kernel-written frame: their images equal plain forward's within their formats'
  // tolerances.
  const Scene full = load_scene("atrium:1");
  compare_with_plain_forward(full, 1, {"tiled_deferred", "clustered_deferred", "visibility_buffer"}, kTolerances);
  // The test sees glass: plain forward's image with and without the glass differs on G > 0 pixels,
  // and without its translucent pass (translucent=skip) tiled deferred differs from plain forward
  // on those G pixels too (1292 of 192 x 108 = 20736), besides its G-buffer's rounding; with the
  // pass it differs on fewer than that rounding plus a tenth of G.
  TraceSetup setup = testing_support::atrium_entrance_setup(full, 64, 192, 108);
  const HwConfig hw = resolve_config({}, {}).hw;
  const Reference ref = plain_forward_reference(full, setup, hw);
  const Scene opaque = opaque_atrium();
  const ImageDiff glass = diff_from(final_image(simulate_frame(generate_trace("plain_forward", setup), "pf", opaque, hw)), ref);
  setup.options["translucent"] = "skip";
  const ImageDiff skipped =
      diff_from(final_image(simulate_frame(generate_trace("tiled_deferred", setup), "td", full, hw)), ref);
  std::printf("[ image    ] glass covers %zu pixels; tiled_deferred without its translucent pass differs on %zu\n",
              glass.pixels_over_1, skipped.pixels_over_1);
  EXPECT_GT(glass.pixels_over_1, 0u);
  EXPECT_GE(skipped.pixels_over_1, glass.pixels_over_1);
  setup.options["translucent"] = "forward";
  const ImageDiff drawn = diff_from(final_image(simulate_frame(generate_trace("tiled_deferred", setup), "td", full, hw)), ref);
  EXPECT_LT(drawn.pixels_over_1, skipped.pixels_over_1 - glass.pixels_over_1 + glass.pixels_over_1 / 10);
}

TEST(TechniqueImages, OnChipDeferredMatchesStoredDeferredWhetherItFitsOrSplits) {
  // Deferred with its G-buffer kept on chip (gbuffer_storage=onchip: one pass, the light volumes
  // fetch the G-buffer) computes the image of deferred with a stored G-buffer: the formats round
  // the same values, except the ambient term, which the on-chip G-buffer shader writes from the
  // exact albedo and the stored variant's ambient pass from the rgba8 one (1/255 at most). Also
  // when the pass does not fit 64 bits per pixel and the driver splits the render (split_render:
  // the light volumes then read the G-buffer from memory): then exactly the fitting image.
  const Scene scene = opaque_atrium();
  TraceSetup setup = testing_support::atrium_entrance_setup(scene, 64, 192, 108);
  const HwConfig hw = resolve_config({}, {}).hw;
  const FrameResult stored_frame = simulate_frame(generate_trace("deferred", setup), "d", scene, hw);
  setup.options["gbuffer_storage"] = "onchip";
  const Trace onchip = generate_trace("deferred", setup);
  const FrameResult fits = simulate_frame(onchip, "fits", scene, hw);
  const FrameResult split =
      simulate_frame(onchip, "split", scene, resolve_config({}, {"pls.tile_buffer_bits_per_pixel=64"}).hw);
  EXPECT_EQ(stat(fits, "frame/tile_memory", "split_renders"), 0.0);
  EXPECT_EQ(stat(split, "frame/tile_memory", "split_renders"), 1.0);
  // Compared in the rgba8 target's linear values (the sRGB image magnifies 1/255 near black).
  const auto& on = fits.images.attachments.at("color").color;
  const auto& ref = stored_frame.images.attachments.at("color").color;
  ASSERT_EQ(on.size(), ref.size());
  float worst = 0;
  for (std::size_t i = 0; i < on.size(); ++i) {
    for (int c = 0; c < 3; ++c) worst = std::max(worst, std::abs(on[i][c] - ref[i][c]));
  }
  EXPECT_LE(worst, 1.0f / 255.0f + 1e-6f);
  EXPECT_EQ(final_image(split).rgb, final_image(fits).rgb);
}

}  // namespace
}  // namespace tbdr
