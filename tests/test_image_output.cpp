// Image output: sRGB conversion, PNG round trip, depth / id images, heat maps with a legend.
#include <gtest/gtest.h>

#include <stb/stb_image.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <set>
#include <tuple>

#include "kernel/errors.hpp"
#include "app/image_output.hpp"

namespace tbdr {
namespace {

std::filesystem::path temp_dir() {
  const auto dir = std::filesystem::temp_directory_path() / "tbdrsim_test_image_output";
  std::filesystem::create_directories(dir);
  return dir;
}

/// Reads a PNG back with stb_image directly (not through read_png), as RGB.
ImageRGB8 load_with_stb(const std::string& path) {
  int w = 0, h = 0, n = 0;
  unsigned char* data = stbi_load(path.c_str(), &w, &h, &n, 3);
  EXPECT_NE(data, nullptr) << path;
  ImageRGB8 img;
  if (data == nullptr) return img;
  img.width = w;
  img.height = h;
  img.rgb.assign(data, data + static_cast<std::size_t>(w) * h * 3);
  stbi_image_free(data);
  return img;
}

/// True if row y of `img` holds more than one color.
bool row_is_non_uniform(const ImageRGB8& img, int y) {
  for (int x = 1; x < img.width; ++x)
    if (!(img.at(x, y) == img.at(0, y))) return true;
  return false;
}

// The inline rounding the conversions use per pixel is std::lround over [0, 255] (every float a
// step of 1/8 apart, each value's neighbouring floats, and the ties) and at its edges; NaN gives 0.
TEST(ImageOutputColor, InlineRoundingIsLroundForNonNegativeValues) {
  std::vector<double> xs = {0.0, 0.49999999999999994, 0.5, 0.5000000000000001, 1.5, 2.5, 254.5, 255.0, 4503599627370495.5};
  for (int i = 0; i <= 255 * 8; ++i) {
    const double x = i / 8.0;
    xs.push_back(x);
    xs.push_back(std::nextafter(x, 0.0));
    xs.push_back(std::nextafter(x, 1e9));
  }
  for (const double x : xs) {
    EXPECT_EQ(lround_nonnegative(x), std::lround(x)) << x;
    const auto f = static_cast<float>(x);
    if (f < 1e7f) {
      EXPECT_EQ(lround_nonnegative(f), std::lround(f)) << f;
      EXPECT_EQ(lround_nonnegative(std::nextafter(f, 0.0f)), std::lround(std::nextafter(f, 0.0f))) << f;
      EXPECT_EQ(lround_nonnegative(std::nextafter(f, 1e9f)), std::lround(std::nextafter(f, 1e9f))) << f;
    }
  }
  EXPECT_EQ(lround_nonnegative(std::nan("")), 0);
  EXPECT_EQ(lround_nonnegative(std::nanf("")), 0);
}

TEST(ImageOutputColor, SrgbTransferFunctionExactValues) {
  EXPECT_EQ(linear_to_srgb8(0.0), 0);
  EXPECT_EQ(linear_to_srgb8(1.0), 255);
  EXPECT_EQ(linear_to_srgb8(0.5), 188);   // 187.516
  EXPECT_EQ(linear_to_srgb8(0.214), 127);  // 127.489
  EXPECT_EQ(linear_to_srgb8(0.001), 3);    // linear segment: 12.92 * 0.001 * 255 = 3.29
  EXPECT_EQ(linear_to_srgb8(-2.0), 0);
  EXPECT_EQ(linear_to_srgb8(7.0), 255);
  EXPECT_EQ(linear_to_srgb8(std::numeric_limits<double>::quiet_NaN()), 0);
  // Monotonic over the whole range.
  int prev = 0;
  for (int i = 0; i <= 1000; ++i) {
    const int v = linear_to_srgb8(i / 1000.0);
    EXPECT_GE(v, prev);
    prev = v;
  }
}

// color_to_image converts by table (no pow per pixel); it must give linear_to_srgb8's code for
// every float. Checked at each of the 255 code boundaries (the last float below it and the first
// at it, found by bisection over the float bit patterns) and on 2^22 floats spread evenly over the
// bit patterns of [0, 1], plus the special values.
TEST(ImageOutputColor, TableConversionEqualsTheFormulaForEveryFloat) {
  const auto code = [](float x) { return linear_to_srgb8(static_cast<double>(x)); };
  std::vector<float> xs = {0.0f, -0.0f, -1.0f, 1.0f, 1.5f, std::numeric_limits<float>::infinity(),
                           -std::numeric_limits<float>::infinity(), std::numeric_limits<float>::quiet_NaN(),
                           std::numeric_limits<float>::denorm_min(), 0.0031308f};
  const std::uint32_t one = std::bit_cast<std::uint32_t>(1.0f);
  for (int k = 1; k <= 255; ++k) {
    std::uint32_t lo = 0, hi = one;
    while (lo < hi) {
      const std::uint32_t mid = lo + (hi - lo) / 2;
      if (code(std::bit_cast<float>(mid)) >= k) hi = mid; else lo = mid + 1;
    }
    xs.push_back(std::bit_cast<float>(lo));
    xs.push_back(std::bit_cast<float>(lo - 1));
    EXPECT_EQ(code(std::bit_cast<float>(lo - 1)), k - 1) << "the formula is monotone: one code per boundary";
  }
  for (std::uint32_t b = 0; b <= one; b += one >> 22) xs.push_back(std::bit_cast<float>(b));
  while (xs.size() % 3 != 0) xs.push_back(0.5f);
  std::vector<glm::vec3> pixels(xs.size() / 3);
  for (std::size_t i = 0; i < pixels.size(); ++i) pixels[i] = {xs[3 * i], xs[3 * i + 1], xs[3 * i + 2]};
  const ImageRGB8 img = color_to_image(pixels, static_cast<int>(pixels.size()), 1);
  std::size_t wrong = 0;
  for (std::size_t i = 0; i < xs.size(); ++i) {
    if (img.rgb[i] != code(xs[i]) && ++wrong <= 5) ADD_FAILURE() << "x = " << xs[i] << ": table " << int{img.rgb[i]} << ", formula " << int{code(xs[i])};
  }
  EXPECT_EQ(wrong, 0u);
}

TEST(ImageOutputColor, PngRoundTripHasExactSrgbValues) {
  const int w = 3, h = 2;
  const std::vector<glm::vec4> linear = {
      {0, 0, 0, 1}, {1, 1, 1, 1}, {0.5f, 0.5f, 0.5f, 1}, {1, 0, 0.5f, 0}, {2, -1, 0, 1}, {0, 0.5f, 1, 1}};
  const ImageRGB8 img = color_to_image(linear, w, h);
  const auto path = (temp_dir() / "color.png").string();
  write_png(path, img);
  const ImageRGB8 back = load_with_stb(path);
  ASSERT_EQ(back.width, w);
  ASSERT_EQ(back.height, h);
  EXPECT_EQ(back.at(0, 0), (Rgb8{0, 0, 0}));
  EXPECT_EQ(back.at(1, 0), (Rgb8{255, 255, 255}));
  EXPECT_EQ(back.at(2, 0), (Rgb8{188, 188, 188}));
  EXPECT_EQ(back.at(0, 1), (Rgb8{255, 0, 188}));
  EXPECT_EQ(back.at(1, 1), (Rgb8{255, 0, 0}));
  EXPECT_EQ(back.at(2, 1), (Rgb8{0, 188, 255}));
  EXPECT_EQ(back, img);
  EXPECT_EQ(read_png(path), img);

  const std::vector<glm::vec3> rgb = {{0.5f, 0, 1}};
  EXPECT_EQ(color_to_image(rgb, 1, 1).at(0, 0), (Rgb8{188, 0, 255}));
  EXPECT_THROW(color_to_image(rgb, 2, 1), std::invalid_argument);
}

TEST(ImageOutputFiles, UnwritablePathThrowsInputErrorNamingIt) {
  const auto path = (temp_dir() / "no_such_dir" / "sub" / "out.png").string();
  try {
    write_png(path, ImageRGB8(2, 2));
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), path);
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos);
  }
  EXPECT_THROW(read_png(path), InputError);
}

TEST(ImageOutputIds, EqualIdsEqualColorsNoneBlack) {
  constexpr std::uint32_t kNone = 0xffffffffu;
  const std::vector<std::uint32_t> ids = {7, 7, kNone, 0, 1, 2, 7, 123456};
  const ImageRGB8 img = ids_to_image(ids, 4, 2, kNone);
  ASSERT_EQ(img.width, 4);
  ASSERT_EQ(img.height, 2);
  EXPECT_EQ(img.at(0, 0), img.at(1, 0));
  EXPECT_EQ(img.at(0, 0), img.at(2, 1));
  EXPECT_EQ(img.at(0, 0), id_color(7));
  EXPECT_EQ(img.at(2, 0), (Rgb8{0, 0, 0}));
  // Different ids (nearly always) differ, and none is black.
  std::set<std::tuple<int, int, int>> colors;
  for (std::uint32_t id = 0; id < 1000; ++id) {
    const Rgb8 c = id_color(id);
    EXPECT_FALSE(c == (Rgb8{0, 0, 0}));
    colors.insert({c.r, c.g, c.b});
  }
  EXPECT_GE(colors.size(), 990u);
  EXPECT_NE(img.at(3, 0), img.at(0, 1));
}

TEST(ImageOutputDepth, ContrastStretchedAndClearedDistinct) {
  const int w = 4, h = 1;
  const std::vector<float> depth = {0.25f, 0.5f, 1.0f, 0.75f};
  const ImageRGB8 bare = depth_to_image(depth, w, h, false);
  ASSERT_EQ(bare.height, h);
  EXPECT_EQ(bare.at(0, 0), (Rgb8{255, 255, 255}));  // nearest present
  EXPECT_EQ(bare.at(3, 0), (Rgb8{24, 24, 24}));     // farthest present
  EXPECT_EQ(bare.at(2, 0), kDepthClearedColor);
  const Rgb8 mid = bare.at(1, 0);
  EXPECT_EQ(mid.r, mid.g);
  EXPECT_LT(mid.r, 255);
  EXPECT_GT(mid.r, 24);

  const ImageRGB8 with_legend = depth_to_image(depth, w, h);
  EXPECT_GT(with_legend.height, h);
  for (int x = 0; x < w; ++x) EXPECT_EQ(with_legend.at(x, 0), bare.at(x, 0));

  // Nothing drawn: all cleared.
  const ImageRGB8 empty = depth_to_image(std::vector<float>(4, 1.0f), 2, 2, false);
  EXPECT_EQ(empty.at(1, 1), kDepthClearedColor);
}

TEST(ImageOutputHeatmap, ColormapEndsAreViridis) {
  EXPECT_EQ(colormap_color(0.0), (Rgb8{68, 1, 84}));
  EXPECT_EQ(colormap_color(1.0), (Rgb8{253, 231, 37}));
  EXPECT_EQ(colormap_color(-3.0), colormap_color(0.0));
  EXPECT_EQ(colormap_color(9.0), colormap_color(1.0));
  // Lightness (green channel here) rises along viridis.
  int prev = -1;
  for (int i = 0; i <= 100; ++i) {
    const Rgb8 c = colormap_color(i / 100.0);
    EXPECT_GE(c.g, prev);
    prev = c.g;
  }
}

TEST(ImageOutputHeatmap, GradientGetsLegendAndEndColors) {
  const int w = 200, h = 40;
  std::vector<double> values(static_cast<std::size_t>(w) * h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) values[static_cast<std::size_t>(y) * w + x] = x * 0.5;  // 0 .. 99.5
  HeatmapSpec spec;
  spec.title = "Overdraw";
  spec.unit = "fragments per pixel";
  const ImageRGB8 img = heatmap_to_image(values, w, h, spec);
  EXPECT_EQ(img.width, w);
  ASSERT_GT(img.height, h);
  EXPECT_EQ(img.at(0, 0), colormap_color(0.0));
  EXPECT_EQ(img.at(0, h - 1), colormap_color(0.0));
  EXPECT_EQ(img.at(w - 1, 0), colormap_color(1.0));
  EXPECT_EQ(img.at(w / 2, 5), colormap_color(heatmap_position(values[w / 2], {0, 99.5}, false)));

  // The legend rows hold text and a color bar: several non-uniform rows.
  int non_uniform = 0;
  for (int y = h; y < img.height; ++y) non_uniform += row_is_non_uniform(img, y) ? 1 : 0;
  EXPECT_GE(non_uniform, 20);
  // The title line (first text row band below the separator) has dark text pixels.
  int dark = 0;
  for (int y = h + 2; y < h + 20; ++y)
    for (int x = 0; x < w; ++x) {
      const Rgb8 c = img.at(x, y);
      if (c.r < 60 && c.g < 60 && c.b < 60) ++dark;
    }
  EXPECT_GT(dark, 20);

  const auto path = (temp_dir() / "heat.png").string();
  write_png(path, img);
  EXPECT_EQ(load_with_stb(path), img);
}

TEST(ImageOutputHeatmap, CountsGiveTheSameImageAsTheirValuesAsDoubles) {
  // The frame's counters are mapped as stored (no copy as doubles): every pixel and the legend
  // (min / mean / max, ticks) must be the image the same values as doubles give.
  const int w = 96, h = 30;
  std::vector<std::uint32_t> counts(static_cast<std::size_t>(w) * h);
  for (std::size_t i = 0; i < counts.size(); ++i) counts[i] = static_cast<std::uint32_t>((i * 7919u) % 37u + (i % w) / 8u);
  const std::vector<double> values(counts.begin(), counts.end());
  for (const bool log_scale : {false, true}) {
    HeatmapSpec spec{"Lights evaluated", "lights per pixel", log_scale, std::nullopt, std::nullopt};
    const ImageRGB8 from_counts = heatmap_to_image(counts, w, h, spec);
    EXPECT_EQ(from_counts, heatmap_to_image(values, w, h, spec)) << "log_scale " << log_scale;
    EXPECT_GT(from_counts.height, h);  // the legend is there
  }
  // The counts above go through a colour per count (their largest, 47, is below an eighth of the
  // 2880 pixels); one count of 100000 takes them the per-pixel way, and a clamped range (a
  // spec's max) maps every count above it to the top colour either way.
  std::vector<std::uint32_t> wide = counts;
  wide[17] = 100000;
  const std::vector<double> wide_values(wide.begin(), wide.end());
  HeatmapSpec plain{"Overdraw", "samples", false, std::nullopt, std::nullopt};
  EXPECT_EQ(heatmap_to_image(wide, w, h, plain), heatmap_to_image(wide_values, w, h, plain));
  HeatmapSpec clamped{"Overdraw", "samples", false, 20.0, std::nullopt};
  EXPECT_EQ(heatmap_to_image(counts, w, h, clamped), heatmap_to_image(values, w, h, clamped));
}

TEST(ImageOutputHeatmap, MaxValueClampsAndLogScaleMapsEnds) {
  const std::vector<double> values = {0, 1, 10, 100, 1000, 5000};
  HeatmapSpec spec{"Lights", "lights per pixel", true, 1000.0, std::nullopt};
  const HeatmapRange r = heatmap_range(values, spec);
  EXPECT_EQ(r.lo, 0);
  EXPECT_EQ(r.hi, 1000);
  const ImageRGB8 img = heatmap_to_image(values, 6, 1, spec);
  EXPECT_EQ(img.at(0, 0), colormap_color(0));
  EXPECT_EQ(img.at(4, 0), colormap_color(1));
  EXPECT_EQ(img.at(5, 0), colormap_color(1));  // clamped at max_value
  EXPECT_NEAR(heatmap_position(10, r, true), std::log10(11.0) / std::log10(1001.0), 1e-12);
  // Constant data: everything at the low end, no division by zero.
  const ImageRGB8 flat = heatmap_to_image(std::vector<double>(4, 0.0), 2, 2, HeatmapSpec{});
  EXPECT_EQ(flat.at(1, 1), colormap_color(0));
}

TEST(ImageOutputHeatmap, TilesExpandWithBorders) {
  const std::vector<double> tiles = {0, 1, 2, 3, 4, 5};  // 3 x 2 tiles of 8x8, frame 20 x 12
  const auto px = expand_tiles_to_pixels(tiles, 3, 2, 8, 8, 20, 12);
  ASSERT_EQ(px.size(), 240u);
  EXPECT_EQ(px[0], 0);
  EXPECT_EQ(px[19], 2);               // (19, 0): tile 2 (clipped at the frame edge)
  EXPECT_EQ(px[11 * 20 + 9], 4);      // (9, 11): tile (1, 1)
  const ImageRGB8 img = heatmap_tiles_to_image(tiles, 3, 2, 8, 8, 20, 12, HeatmapSpec{"Cycles", "cycles", false, {}, {}});
  ASSERT_GT(img.height, 12);
  EXPECT_EQ(img.at(3, 3), colormap_color(0));
  EXPECT_EQ(img.at(19, 11), colormap_color(1));
  EXPECT_NE(img.at(8, 3), img.at(9, 3));  // border column of tile 1 is darker
}

TEST(ImageOutputText, NumberFormatting) {
  EXPECT_EQ(format_legend_number(0), "0");
  EXPECT_EQ(format_legend_number(12.5), "12.5");
  EXPECT_EQ(format_legend_number(1200), "1.2k");
  EXPECT_EQ(format_legend_number(1234), "1.23k");
  EXPECT_EQ(format_legend_number(999.9), "1k");
  EXPECT_EQ(format_legend_number(2500000), "2.5M");
  EXPECT_EQ(format_legend_number(-3), "-3");
  EXPECT_EQ(format_legend_number(0.125), "0.125");
  EXPECT_EQ(format_legend_number(0.000012), "1.2e-05");
  EXPECT_EQ(format_legend_number(17), "17");
  EXPECT_EQ(format_legend_number(2.3141, 4), "2.314");
}

TEST(ImageOutputText, DrawTextMarksPixelsAndScales) {
  ImageRGB8 img(100, 30, Rgb8{255, 255, 255});
  const int w1 = draw_text(img, 2, 2, "Hi 1.2k", 1, Rgb8{0, 0, 0});
  EXPECT_EQ(w1, text_width("Hi 1.2k", 1));
  EXPECT_EQ(text_width("Hi 1.2k", 3), 3 * w1);
  int black = 0;
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x) black += img.at(x, y) == (Rgb8{0, 0, 0}) ? 1 : 0;
  EXPECT_GT(black, 10);
  EXPECT_EQ(legend_text_scale(1920), 3);
  EXPECT_EQ(legend_text_scale(1024), 2);
  EXPECT_EQ(legend_text_scale(320), 1);
  // Non-ASCII text and clipping outside the image are harmless.
  draw_text(img, 90, 25, "\xc3\xa9\t~", 2, Rgb8{1, 2, 3});
}

}  // namespace
}  // namespace tbdr
