#pragma once
// Image output for `tbdrsim run --images DIR`: the final color image, a depth image, a triangle-id
// image and heat maps with a legend (color bar, tick labels, title, unit, mean and max), written as
// 8-bit RGB PNG files (libdeflate at its fastest level, adaptive row filters).
//
// Color conversion (exact, so that 8-bit images of different techniques can be compared):
//   c  = clamp(linear, 0, 1)                      (NaN -> 0), per channel, alpha ignored
//   s  = 12.92 * c                    if c <= 0.0031308
//        1.055 * c^(1/2.4) - 0.055    otherwise    (IEC 61966-2-1 sRGB transfer function)
//   u8 = floor(s * 255 + 0.5)                     (round half up), computed in double precision
// so linear 0 -> 0, 1 -> 255, 0.5 -> 188 (187.516), 0.001 -> 3, 0.214 -> 127 (127.489).
//
// Heat-map colormap: matplotlib's viridis (CC0), 32 control points of its 256-entry table
// interpolated linearly in sRGB; t = 0 gives exactly (68,1,84) and t = 1 exactly (253,231,37).
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

namespace tbdr {

/// std::lround(x) for 0 <= x < 2^52 (ties away from zero), inline: x - trunc(x) is exact there,
/// so rounding up exactly when that fraction is 0.5 or more gives the same integer. The image
/// conversions round a value per pixel, and std::lround is a library call. NaN gives 0 (the byte
/// std::lround's unspecified result became).
template <typename F>
constexpr long lround_nonnegative(F x) {
  if (!(x >= F(0))) return 0;
  const auto whole = static_cast<long>(x);
  return whole + (x - static_cast<F>(whole) >= F(0.5) ? 1 : 0);
}

/// One 8-bit sRGB color.
struct Rgb8 {
  std::uint8_t r = 0;
  std::uint8_t g = 0;
  std::uint8_t b = 0;
  bool operator==(const Rgb8&) const = default;
};

/// An 8-bit RGB image, rows top to bottom, 3 bytes per pixel (R, G, B), no padding.
struct ImageRGB8 {
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> rgb;

  ImageRGB8() = default;
  /// A width x height image filled with `fill`.
  ImageRGB8(int w, int h, Rgb8 fill = {});
  /// The color at (x, y); (0, 0) is the top-left pixel. No bounds check beyond an assert.
  Rgb8 at(int x, int y) const;
  /// Sets (x, y); pixels outside the image are ignored (clipping).
  void set(int x, int y, Rgb8 c);
  /// Fills the rectangle [x0, x1) x [y0, y1), clipped to the image.
  void fill_rect(int x0, int y0, int x1, int y1, Rgb8 c);
  bool operator==(const ImageRGB8&) const = default;
};

/// Writes `image` as an 8-bit RGB PNG. The directory must exist. Throws InputError(path, ...)
/// when the file cannot be written.
void write_png(const std::string& path, const ImageRGB8& image);

/// Reads a PNG (any channel count, converted to RGB). Throws InputError(path, ...) on failure.
ImageRGB8 read_png(const std::string& path);

/// Linear [0,1] -> 8-bit sRGB by the formula at the top of this file.
std::uint8_t linear_to_srgb8(double linear);

/// Linear float RGB(A) -> 8-bit sRGB image (alpha ignored). Throws std::invalid_argument when
/// the vector does not hold w * h colors.
ImageRGB8 color_to_image(const std::vector<glm::vec4>& linear, int w, int h);
ImageRGB8 color_to_image(const std::vector<glm::vec3>& linear, int w, int h);
/// One linear colour's sRGB bytes, as color_to_image converts each pixel (for images made pixel
/// by pixel from other data, without a frame-sized copy of their colours).
Rgb8 linear_to_srgb8(const glm::vec3& linear);

/// The heat-map colormap (viridis) at t in [0, 1] (clamped; NaN -> 0).
Rgb8 colormap_color(double t);

/// Fixed colors used by the depth and id images.
inline constexpr Rgb8 kDepthClearedColor{32, 48, 96};  ///< depth image: depth >= 1 (cleared)
inline constexpr Rgb8 kNoDataColor{128, 128, 128};     ///< heat map: non-finite value

/// Depth image. Depths below 1.0 are shown in grey, contrast-stretched between the minimum (white,
/// 255) and maximum (dark grey, 24) depth present below 1.0: g = 255 - round(231 * (d - min) /
/// (max - min)) (all 255 when min == max). Depth >= 1.0 (cleared) or NaN is kDepthClearedColor.
/// With `legend`, a strip below the image shows the grey ramp and the mapped depth range.
ImageRGB8 depth_to_image(const std::vector<float>& depth01, int w, int h, bool legend = true);

/// Triangle-id image: each id a fixed hash color (equal ids -> equal colors, never black, the
/// same in every run), `none` black. Same size as the frame (no legend).
ImageRGB8 ids_to_image(const std::vector<std::uint32_t>& ids, int w, int h, std::uint32_t none);

/// The hash color ids_to_image uses for `id`.
Rgb8 id_color(std::uint32_t id);

/// What a heat map shows and how its values are mapped to the colormap.
struct HeatmapSpec {
  std::string title;                ///< e.g. "Overdraw"
  std::string unit;                 ///< e.g. "fragments per pixel"
  bool log_scale = false;           ///< map log10(1 + v - lo) instead of v (zeros allowed)
  std::optional<double> max_value;  ///< top of the color scale (values above are clamped); default data max
  std::optional<double> min_value;  ///< bottom of the scale; default 0, or the data min if negative
};

/// The color range a heat map uses for `values` under `spec` (non-finite values ignored).
/// hi > lo always (a flat range is widened to [lo, lo + 1]).
struct HeatmapRange {
  double lo = 0;
  double hi = 1;
};
HeatmapRange heatmap_range(const std::vector<double>& values, const HeatmapSpec& spec);

/// Position in [0, 1] of value `v` on the color scale of `range` (clamped).
double heatmap_position(double v, const HeatmapRange& range, bool log_scale);

/// Heat map of one value per pixel (row-major, w * h values): the map at full resolution in rows
/// [0, h), then a legend strip below (the image is taller than h): title and unit, min / mean / max
/// of the values, and a color bar with tick labels. Non-finite values are kNoDataColor and are
/// left out of the statistics. Throws std::invalid_argument when values.size() != w * h.
ImageRGB8 heatmap_to_image(const std::vector<double>& values, int w, int h, const HeatmapSpec& spec);
/// The same map of per-pixel counts (the frame's counters), read as they are stored: the same
/// image as heatmap_to_image of the counts as doubles, without a 2 M-value copy at 1080p.
ImageRGB8 heatmap_to_image(const std::vector<std::uint32_t>& counts, int w, int h, const HeatmapSpec& spec);

/// Expands one value per tile (row-major, tiles_x * tiles_y) to one value per pixel of a w x h
/// frame; tile (tx, ty) covers pixels [tx*tile_w, (tx+1)*tile_w) x [ty*tile_h, (ty+1)*tile_h).
std::vector<double> expand_tiles_to_pixels(const std::vector<double>& values_per_tile, int tiles_x,
                                           int tiles_y, int tile_w, int tile_h, int w, int h);

/// Heat map of one value per tile: like heatmap_to_image on the expanded values, with thin darker
/// tile borders (when tiles are at least 4 px wide and high); the statistics are per tile.
ImageRGB8 heatmap_tiles_to_image(const std::vector<double>& values_per_tile, int tiles_x, int tiles_y,
                                 int tile_w, int tile_h, int w, int h, const HeatmapSpec& spec);

/// Formats a number for a legend with at most `significant` significant digits, trailing zeros
/// trimmed and k / M / G suffixes from 1000 up: 0 -> "0", 12.5 -> "12.5", 1234 -> "1.23k",
/// 2500000 -> "2.5M", 0.000012 -> "1.2e-05".
std::string format_legend_number(double v, int significant = 3);

/// Draws ASCII `text` (stb_easy_font glyphs scaled by `scale`) with its top-left at (x, y),
/// clipped to the image; returns the width in pixels. Characters outside ' '..'~' become '?'.
int draw_text(ImageRGB8& image, int x, int y, const std::string& text, int scale, Rgb8 color);

/// Width in pixels of `text` as draw_text would draw it.
int text_width(const std::string& text, int scale);

/// The text scale legends use for an image `width` pixels wide: 1 below 480, 2 below 1280, else 3
/// (stb_easy_font glyphs are about 7 px high at scale 1).
int legend_text_scale(int width);

}  // namespace tbdr
