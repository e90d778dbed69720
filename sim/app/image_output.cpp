// Image output: PNG writing (libdeflate; reading through stb_image, compiled into Debian's libstb), sRGB
// conversion, depth / id images, and heat maps with a legend drawn with stb_easy_font glyphs.
#include "app/image_output.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cassert>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <functional>
#include <limits>
#include <memory>
#include <new>
#include <stdexcept>
#include <type_traits>

#include "kernel/errors.hpp"
#include "kernel/output_file.hpp"

// stb_image: declarations only, the implementation lives in libstb. PNGs are written with
// libdeflate (a zlib stream and CRC-32s, as PNG defines them).
#include <libdeflate.h>
#include <stb/stb_image.h>

// stb_easy_font is header-only with static functions (no implementation define); not every one of
// them is used here.
#if defined(__GNUC__)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wunused-function"
#endif
#include <stb/stb_easy_font.h>
#if defined(__GNUC__)
#pragma GCC diagnostic pop
#endif

namespace tbdr {

// ---------------------------------------------------------------------------------------------
// ImageRGB8

ImageRGB8::ImageRGB8(int w, int h, Rgb8 fill) : width(w), height(h) {
  if (w < 0 || h < 0) throw std::invalid_argument("ImageRGB8: negative size");
  rgb.resize(static_cast<std::size_t>(w) * static_cast<std::size_t>(h) * 3);  // black: zeros
  if (fill == Rgb8{}) return;
  for (std::size_t i = 0; i < rgb.size(); i += 3) {
    rgb[i] = fill.r;
    rgb[i + 1] = fill.g;
    rgb[i + 2] = fill.b;
  }
}

Rgb8 ImageRGB8::at(int x, int y) const {
  assert(x >= 0 && y >= 0 && x < width && y < height);
  const std::size_t i = (static_cast<std::size_t>(y) * static_cast<std::size_t>(width) + x) * 3;
  return {rgb[i], rgb[i + 1], rgb[i + 2]};
}

void ImageRGB8::set(int x, int y, Rgb8 c) {
  if (x < 0 || y < 0 || x >= width || y >= height) return;
  const std::size_t i = (static_cast<std::size_t>(y) * static_cast<std::size_t>(width) + x) * 3;
  rgb[i] = c.r;
  rgb[i + 1] = c.g;
  rgb[i + 2] = c.b;
}

void ImageRGB8::fill_rect(int x0, int y0, int x1, int y1, Rgb8 c) {
  x0 = std::max(x0, 0);
  y0 = std::max(y0, 0);
  x1 = std::min(x1, width);
  y1 = std::min(y1, height);
  for (int y = y0; y < y1; ++y)
    for (int x = x0; x < x1; ++x) set(x, y, c);
}

// ---------------------------------------------------------------------------------------------
// PNG files

namespace {

/// libdeflate's fastest level (libdeflate.h: 1): the images are for looking at. stb_image_write's
/// own deflate (default level 8, 5 at its fastest) was a fifth of a 1080p run's profile with
/// images (issue 15); zlib at level 1 compresses the same rows several times faster, and
/// libdeflate at level 1 1.4-2x faster again than zlib at its level 1, to files within 4 % of
/// its size (1080p colour, normal, id and heat map images, 2026-12-04).
constexpr int kPngCompressionLevel = 1;

/// The longest row filter_row's 32-bit residual sums hold: 128 per byte at most.
constexpr std::size_t kMaxPngRowBytes = std::size_t{1} << 24;

/// Appends a big-endian 32-bit value.
void put_u32(std::vector<std::uint8_t>& out, std::uint32_t v) {
  for (int shift = 24; shift >= 0; shift -= 8) out.push_back(static_cast<std::uint8_t>(v >> shift));
}

/// Appends one PNG chunk (length, type, data, CRC-32 of type and data; PNG spec 5.3).
void put_chunk(std::vector<std::uint8_t>& out, const char type[4], const std::uint8_t* data, std::size_t size) {
  put_u32(out, static_cast<std::uint32_t>(size));
  const std::size_t start = out.size();
  out.insert(out.end(), type, type + 4);
  if (size > 0) out.insert(out.end(), data, data + size);
  put_u32(out, libdeflate_crc32(0, out.data() + start, out.size() - start));
}

/// A row's filter is chosen on a sample of it: blocks of kFilterCostBlock bytes every
/// kFilterCostStride bytes (a quarter of the row); then only the chosen filter runs over the
/// whole row. Choosing on every byte ran all five filters over every row, a fifth of an image's
/// CPU (1080p plain_forward, 2026-12-06); on the sample the files grow 0.5-6 % (heat maps most).
constexpr std::size_t kFilterCostBlock = 16;
constexpr std::size_t kFilterCostStride = 64;

/// The PNG filter of one row (PNG spec 9.2: none, sub, up, average, Paeth) into `dst` (type
/// byte first): the one with the smallest sum of absolute signed residuals (the heuristic of the
/// PNG spec 12.8 that libpng and stb_image_write use), summed over the sample above. The row and
/// the one above are copied behind bpp zero bytes (and the first row's "above" is zeros, as the
/// spec defines it), so that the loops have no edge tests and the compiler vectorises them.
void filter_row(const std::uint8_t* row, const std::uint8_t* above, std::size_t n, std::uint8_t* dst,
                std::array<std::vector<std::uint8_t>, 2>& scratch) {
  constexpr std::size_t bpp = 3;
  std::vector<std::uint8_t>& cur = scratch[0];
  std::vector<std::uint8_t>& prev = scratch[1];
  cur.assign(n + bpp, 0);
  prev.assign(n + bpp, 0);
  std::memcpy(cur.data() + bpp, row, n);
  if (above) std::memcpy(prev.data() + bpp, above, n);
  const std::uint8_t* x = cur.data() + bpp;   // x[i]: the byte
  const std::uint8_t* a = cur.data();         // a[i]: the byte bpp to its left (0 before the row)
  const std::uint8_t* b = prev.data() + bpp;  // b[i]: the byte above
  const std::uint8_t* c = prev.data();        // c[i]: the byte above a
  const auto none = [](int, int, int) { return 0; };
  const auto sub = [](int l, int, int) { return l; };
  const auto up = [](int, int u, int) { return u; };
  const auto average = [](int l, int u, int) { return (l + u) / 2; };
  const auto paeth = [](int pa_, int pb_, int pc_) {
    const int p = pa_ + pb_ - pc_, pa = std::abs(p - pa_), pb = std::abs(p - pb_), pc = std::abs(p - pc_);
    return pa <= pb && pa <= pc ? pa_ : (pb <= pc ? pb_ : pc_);
  };
  // One loop per filter (predictor known at compile time). 32-bit sums vectorise in twice the
  // lanes of 64-bit ones; a row's sum is at most 128 x n, within range for rows of up to 16 M
  // bytes (write_png refuses longer rows).
  auto cost = [&](auto predict) {
    std::int32_t sum = 0;
    for (std::size_t from = 0; from < n; from += kFilterCostStride) {
      const std::size_t to = std::min(n, from + kFilterCostBlock);
      for (std::size_t i = from; i < to; ++i) {
        const auto v = static_cast<std::uint8_t>(x[i] - predict(int{a[i]}, int{b[i]}, int{c[i]}));
        sum += std::abs(static_cast<int>(static_cast<std::int8_t>(v)));
      }
    }
    return sum;
  };
  auto apply = [&](auto predict) {
    std::uint8_t* out = dst + 1;
    for (std::size_t i = 0; i < n; ++i) out[i] = static_cast<std::uint8_t>(x[i] - predict(int{a[i]}, int{b[i]}, int{c[i]}));
  };
  const std::array<std::int32_t, 5> costs = {cost(none), cost(sub), cost(up), cost(average), cost(paeth)};
  const int best = static_cast<int>(std::min_element(costs.begin(), costs.end()) - costs.begin());
  dst[0] = static_cast<std::uint8_t>(best);
  switch (best) {
    case 0: std::memcpy(dst + 1, x, n); break;
    case 1: apply(sub); break;
    case 2: apply(up); break;
    case 3: apply(average); break;
    default: apply(paeth); break;
  }
}

}  // namespace

void write_png(const std::string& path, const ImageRGB8& image) {
  if (image.width <= 0 || image.height <= 0 ||
      image.rgb.size() != static_cast<std::size_t>(image.width) * image.height * 3)
    throw std::invalid_argument("write_png: image for " + path + " has an inconsistent size");
  const std::size_t n = static_cast<std::size_t>(image.width) * 3;
  const auto h = static_cast<std::size_t>(image.height);
  if (n > kMaxPngRowBytes) throw std::invalid_argument("write_png: image for " + path + " is wider than a row's filter costs can sum");
  // Both buffers are written whole before they are read: left uninitialised (zeroing them was
  // 12 MB of stores per 1080p image).
  const std::size_t filtered_size = (n + 1) * h;
  const std::unique_ptr<std::uint8_t[]> filtered(new std::uint8_t[filtered_size]);
  std::array<std::vector<std::uint8_t>, 2> scratch;
  for (std::size_t y = 0; y < h; ++y) {
    filter_row(image.rgb.data() + y * n, y > 0 ? image.rgb.data() + (y - 1) * n : nullptr, n, filtered.get() + y * (n + 1),
               scratch);
  }
  const std::unique_ptr<libdeflate_compressor, decltype(&libdeflate_free_compressor)> compressor(
      libdeflate_alloc_compressor(kPngCompressionLevel), &libdeflate_free_compressor);
  if (!compressor) throw std::bad_alloc();
  const std::size_t zbound = libdeflate_zlib_compress_bound(compressor.get(), filtered_size);
  const std::unique_ptr<std::uint8_t[]> z(new std::uint8_t[zbound]);
  const std::size_t zsize = libdeflate_zlib_compress(compressor.get(), filtered.get(), filtered_size, z.get(), zbound);
  if (zsize == 0) throw InputError(path, "cannot compress PNG image");
  std::vector<std::uint8_t> png = {137, 80, 78, 71, 13, 10, 26, 10};  // PNG signature
  std::vector<std::uint8_t> ihdr;
  put_u32(ihdr, static_cast<std::uint32_t>(image.width));
  put_u32(ihdr, static_cast<std::uint32_t>(image.height));
  ihdr.insert(ihdr.end(), {8, 2, 0, 0, 0});  // 8 bits, truecolour RGB, deflate, adaptive filters, no interlace
  png.reserve(zsize + 64);
  put_chunk(png, "IHDR", ihdr.data(), ihdr.size());
  put_chunk(png, "IDAT", z.get(), zsize);
  put_chunk(png, "IEND", nullptr, 0);
  // Whole or not at all (kernel/output_file.hpp).
  write_output_file(path, "PNG image", std::string_view(reinterpret_cast<const char*>(png.data()), png.size()));
}

ImageRGB8 read_png(const std::string& path) {
  int w = 0, h = 0, channels = 0;
  unsigned char* data = stbi_load(path.c_str(), &w, &h, &channels, 3);
  if (data == nullptr) {
    const char* reason = stbi_failure_reason();
    throw InputError(path, std::string("cannot read PNG image") + (reason ? std::string(" (") + reason + ")" : ""));
  }
  ImageRGB8 image;
  image.width = w;
  image.height = h;
  image.rgb.assign(data, data + static_cast<std::size_t>(w) * h * 3);
  stbi_image_free(data);
  return image;
}

// ---------------------------------------------------------------------------------------------
// Color conversion

std::uint8_t linear_to_srgb8(double linear) {
  double c = std::isnan(linear) ? 0.0 : std::clamp(linear, 0.0, 1.0);
  const double s = c <= 0.0031308 ? 12.92 * c : 1.055 * std::pow(c, 1.0 / 2.4) - 0.055;
  const double u = std::floor(s * 255.0 + 0.5);
  return static_cast<std::uint8_t>(std::clamp(u, 0.0, 255.0));
}

namespace {

void check_size(std::size_t n, int w, int h, const char* what) {
  if (w <= 0 || h <= 0 || n != static_cast<std::size_t>(w) * static_cast<std::size_t>(h))
    throw std::invalid_argument(std::string(what) + ": expected " + std::to_string(w) + "x" +
                                std::to_string(h) + " values, got " + std::to_string(n));
}

/// linear_to_srgb8 for single-precision inputs by table, exactly: the formula is monotone in its
/// input, so the code of x is the number of thresholds at or below x, where threshold k (1..255)
/// is the smallest float whose code is k or more (found once by bisection over the floats' bit
/// patterns, which order non-negative floats as their values). No pow per pixel: a bucket table
/// indexed by the float's exponent and top mantissa bits gives the code at the bucket's start,
/// and at most a step or two over the thresholds inside the bucket finish the count.
class SrgbTable {
 public:
  SrgbTable() {
    for (int k = 1; k <= 255; ++k) {
      // Bisection over [0, 1]'s bit patterns for the first float whose code reaches k.
      std::uint32_t lo = 0, hi = std::bit_cast<std::uint32_t>(1.0f);  // code(hi) = 255 >= k
      while (lo < hi) {
        const std::uint32_t mid = lo + (hi - lo) / 2;
        if (linear_to_srgb8(static_cast<double>(std::bit_cast<float>(mid))) >= k) {
          hi = mid;
        } else {
          lo = mid + 1;
        }
      }
      thresholds_[static_cast<std::size_t>(k - 1)] = std::bit_cast<float>(lo);
    }
    for (std::size_t b = 0; b < bucket_start_.size(); ++b) {
      const float first = std::bit_cast<float>(static_cast<std::uint32_t>(b << kBucketShift));
      bucket_start_[b] = static_cast<std::uint8_t>(std::upper_bound(thresholds_.begin(), thresholds_.end(), first) - thresholds_.begin());
    }
  }
  /// linear_to_srgb8(x) for a float x.
  std::uint8_t operator()(float x) const {
    if (!(x > 0.0f)) return 0;  // also NaN
    if (x >= thresholds_.back()) return 255;  // also every x >= 1: the buckets end below 1
    std::size_t i = bucket_start_[std::bit_cast<std::uint32_t>(x) >> kBucketShift];
    // Up to two steps without a branch (how far a bucket's codes mostly go: a loop's exit,
    // taken after 0, 1 or 2 steps at random, mispredicted), then the loop for any further ones.
    // Every step stops by i = 254: x < thresholds_[254].
    i += thresholds_[i] <= x ? 1 : 0;
    i += thresholds_[i] <= x ? 1 : 0;
    while (thresholds_[i] <= x) ++i;
    return static_cast<std::uint8_t>(i);
  }

 private:
  /// Buckets of 2^16 float bit patterns: 7 mantissa bits, 1/128 of an octave, across which the
  /// code grows by at most about 1 (the curve's steepest relative slope is 1/2.4 near 255).
  static constexpr unsigned kBucketShift = 16;
  std::array<float, 255> thresholds_{};
  /// The code of each bucket's first float, for the buckets of [0, 1).
  std::array<std::uint8_t, (0x3f800000u >> kBucketShift)> bucket_start_{};
};

/// The table, built once (thread-safe static initialisation).
const SrgbTable& srgb_table() {
  static const SrgbTable table;
  return table;
}

template <typename Vec>
ImageRGB8 color_image(const std::vector<Vec>& linear, int w, int h) {
  check_size(linear.size(), w, h, "color_to_image");
  const SrgbTable& srgb = srgb_table();
  ImageRGB8 image(w, h);
  for (std::size_t i = 0; i < linear.size(); ++i) {
    image.rgb[3 * i] = srgb(linear[i].x);
    image.rgb[3 * i + 1] = srgb(linear[i].y);
    image.rgb[3 * i + 2] = srgb(linear[i].z);
  }
  return image;
}

}  // namespace

ImageRGB8 color_to_image(const std::vector<glm::vec4>& linear, int w, int h) {
  return color_image(linear, w, h);
}

ImageRGB8 color_to_image(const std::vector<glm::vec3>& linear, int w, int h) {
  return color_image(linear, w, h);
}

Rgb8 linear_to_srgb8(const glm::vec3& linear) {
  const SrgbTable& srgb = srgb_table();
  return {srgb(linear.x), srgb(linear.y), srgb(linear.z)};
}

// ---------------------------------------------------------------------------------------------
// Colormap: matplotlib viridis (CC0, van der Walt & Smith), entries 0, 8, 16, 25, ... 255 of its
// 256-entry table (index round(i * 255 / 31)); linear interpolation stays within 1.7/255 of the
// full table.

namespace {

struct ControlPoint {
  int index;  // position in the 256-entry table
  float r, g, b;
};

constexpr std::array<ControlPoint, 32> kViridis = {{
    {0, 0.267004f, 0.004874f, 0.329415f},   {8, 0.277018f, 0.050344f, 0.375715f},
    {16, 0.282327f, 0.094955f, 0.417331f},  {25, 0.282623f, 0.140926f, 0.457517f},
    {33, 0.278012f, 0.180367f, 0.486697f},  {41, 0.269308f, 0.218818f, 0.509577f},
    {49, 0.257322f, 0.256130f, 0.526563f},  {58, 0.241237f, 0.296485f, 0.539709f},
    {66, 0.225863f, 0.330805f, 0.547314f},  {74, 0.210503f, 0.363727f, 0.552206f},
    {82, 0.195860f, 0.395433f, 0.555276f},  {90, 0.182256f, 0.426184f, 0.557120f},
    {99, 0.168126f, 0.459988f, 0.558082f},  {107, 0.156270f, 0.489624f, 0.557936f},
    {115, 0.144759f, 0.519093f, 0.556572f}, {123, 0.133743f, 0.548535f, 0.553541f},
    {132, 0.123463f, 0.581687f, 0.547445f}, {140, 0.119423f, 0.611141f, 0.538982f},
    {148, 0.124780f, 0.640461f, 0.527068f}, {156, 0.143303f, 0.669459f, 0.511215f},
    {165, 0.180653f, 0.701402f, 0.488189f}, {173, 0.226397f, 0.728888f, 0.462789f},
    {181, 0.281477f, 0.755203f, 0.432552f}, {189, 0.344074f, 0.780029f, 0.397381f},
    {197, 0.412913f, 0.803041f, 0.357269f}, {206, 0.496615f, 0.826376f, 0.306377f},
    {214, 0.575563f, 0.844566f, 0.256415f}, {222, 0.657642f, 0.860219f, 0.203082f},
    {230, 0.741388f, 0.873449f, 0.149561f}, {239, 0.835270f, 0.886029f, 0.102646f},
    {247, 0.916242f, 0.896091f, 0.100717f}, {255, 0.993248f, 0.906157f, 0.143936f},
}};

std::uint8_t unit_to_u8(double v) {
  return static_cast<std::uint8_t>(std::clamp(std::floor(v * 255.0 + 0.5), 0.0, 255.0));
}

Rgb8 lerp(Rgb8 a, Rgb8 b, double f) {
  auto mix = [f](std::uint8_t x, std::uint8_t y) {
    return static_cast<std::uint8_t>(std::clamp(std::floor(x + (y - x) * f + 0.5), 0.0, 255.0));
  };
  return {mix(a.r, b.r), mix(a.g, b.g), mix(a.b, b.b)};
}

}  // namespace

Rgb8 colormap_color(double t) {
  if (std::isnan(t)) t = 0;
  const double pos = std::clamp(t, 0.0, 1.0) * 255.0;
  std::size_t k = 0;
  while (k + 2 < kViridis.size() && pos >= kViridis[k + 1].index) ++k;
  const ControlPoint& a = kViridis[k];
  const ControlPoint& b = kViridis[k + 1];
  const double f = std::clamp((pos - a.index) / (b.index - a.index), 0.0, 1.0);
  return {unit_to_u8(a.r + (b.r - a.r) * f), unit_to_u8(a.g + (b.g - a.g) * f),
          unit_to_u8(a.b + (b.b - a.b) * f)};
}

// ---------------------------------------------------------------------------------------------
// Text

int legend_text_scale(int width) { return width >= 1280 ? 3 : width >= 480 ? 2 : 1; }

namespace {

std::string printable(const std::string& text) {
  std::string s = text;
  for (char& c : s)
    if (c < ' ' || c > '~') c = '?';
  return s;
}

}  // namespace

int text_width(const std::string& text, int scale) {
  std::string s = printable(text);
  return stb_easy_font_width(s.data()) * scale;
}

int draw_text(ImageRGB8& image, int x, int y, const std::string& text, int scale, Rgb8 color) {
  std::string s = printable(text);
  if (s.empty()) return 0;
  // Each quad is 4 vertices of 16 bytes; no glyph has more than ~20 segments.
  std::vector<char> buffer(s.size() * 24 * 64 + 64);
  const int quads = stb_easy_font_print(0, 0, s.data(), nullptr, buffer.data(), static_cast<int>(buffer.size()));
  for (int q = 0; q < quads; ++q) {
    float v0[2], v2[2];
    std::memcpy(v0, buffer.data() + q * 64, sizeof v0);        // top-left
    std::memcpy(v2, buffer.data() + q * 64 + 32, sizeof v2);   // bottom-right
    const int x0 = x + static_cast<int>(std::lround(v0[0])) * scale;
    const int y0 = y + static_cast<int>(std::lround(v0[1])) * scale;
    const int x1 = x + static_cast<int>(std::lround(v2[0])) * scale;
    const int y1 = y + static_cast<int>(std::lround(v2[1])) * scale;
    image.fill_rect(x0, y0, x1, y1, color);
  }
  return stb_easy_font_width(s.data()) * scale;
}

// ---------------------------------------------------------------------------------------------
// Numbers

std::string format_legend_number(double v, int significant) {
  if (std::isnan(v)) return "nan";
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  significant = std::clamp(significant, 1, 15);
  if (v == 0) return "0";
  const std::string sign = v < 0 ? "-" : "";
  double a = std::fabs(v);
  // Round to `significant` digits first so that 999.9 becomes "1k", not "1000".
  {
    const int exponent = static_cast<int>(std::floor(std::log10(a)));
    const double scale = std::pow(10.0, significant - 1 - exponent);
    a = std::round(a * scale) / scale;
  }
  auto trim = [](std::string s) {
    if (s.find('.') != std::string::npos) {
      while (!s.empty() && s.back() == '0') s.pop_back();
      if (!s.empty() && s.back() == '.') s.pop_back();
    }
    return s;
  };
  auto fixed = [&](double x) {
    // Digits after the point so that x shows `significant` significant digits.
    const int exponent = static_cast<int>(std::floor(std::log10(x)));
    const int decimals = std::max(0, significant - 1 - exponent);
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.*f", decimals, x);
    return trim(buf);
  };
  if (a < 1e-3) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.*e", significant - 1, a);
    std::string s = buf;
    const auto e = s.find('e');
    return sign + trim(s.substr(0, e)) + s.substr(e);
  }
  static const std::array<std::pair<double, const char*>, 4> kSuffixes = {
      {{1e12, "T"}, {1e9, "G"}, {1e6, "M"}, {1e3, "k"}}};
  for (const auto& [base, suffix] : kSuffixes)
    if (a >= base) return sign + fixed(a / base) + suffix;
  return sign + fixed(a);
}

// ---------------------------------------------------------------------------------------------
// Legend strip

namespace {

constexpr Rgb8 kLegendBackground{245, 245, 245};
constexpr Rgb8 kLegendText{20, 20, 20};
constexpr Rgb8 kLegendSeparator{90, 90, 90};

/// One labelled position on the color bar; lower `priority` values are placed first, and a label
/// that would overlap an already placed one is dropped.
struct LegendTick {
  double t = 0;
  std::string label;
  int align = 0;  // -1: label starts at the tick, 0: centred, +1: label ends at the tick
  int priority = 0;
};

/// A small colored square with a caption, drawn after the tick labels (e.g. "cleared").
struct LegendSwatch {
  Rgb8 color;
  std::string caption;
};

/// Everything a legend strip shows.
struct Legend {
  std::vector<std::string> lines;        // text lines above the bar
  std::function<Rgb8(double)> bar;       // color at t in [0, 1]
  std::vector<LegendTick> ticks;
  std::vector<LegendSwatch> swatches;
};

/// Returns `map` with a legend strip appended below it (same width, taller).
/// Splits `text` at spaces into lines at most `max_width` pixels wide (a single word wider than
/// that stays on its own line and is clipped).
std::vector<std::string> wrap_text(const std::string& text, int max_width, int scale) {
  std::vector<std::string> lines;
  std::string current;
  std::size_t pos = 0;
  while (pos <= text.size()) {
    std::size_t end = text.find(' ', pos);
    if (end == std::string::npos) end = text.size();
    const std::string word = text.substr(pos, end - pos);
    const std::string candidate = current.empty() ? word : current + " " + word;
    if (!current.empty() && text_width(candidate, scale) > max_width) {
      lines.push_back(current);
      current = word;
    } else {
      current = candidate;
    }
    pos = end + 1;
  }
  if (!current.empty() || lines.empty()) lines.push_back(current);
  return lines;
}

ImageRGB8 append_legend(const ImageRGB8& map, const Legend& legend_in) {
  const int s = legend_text_scale(map.width);
  const int margin = std::min(8 * s, std::max(1, map.width / 16));
  Legend legend = legend_in;
  legend.lines.clear();
  for (const std::string& line : legend_in.lines)
    for (std::string& l : wrap_text(line, map.width - 2 * margin, s)) legend.lines.push_back(std::move(l));
  const int line_h = 12 * s;
  const int pad = 4 * s;
  const int bar_h = 10 * s;
  const int tick_h = 3 * s;
  const int swatch_rows = legend.swatches.empty() ? 0 : 1;
  const int legend_h = s /*separator*/ + pad + static_cast<int>(legend.lines.size()) * line_h + pad +
                       bar_h + tick_h + s + line_h + swatch_rows * (line_h + 2 * s) + pad;

  ImageRGB8 out(map.width, map.height + legend_h, kLegendBackground);
  std::copy(map.rgb.begin(), map.rgb.end(), out.rgb.begin());
  int y = map.height;
  out.fill_rect(0, y, out.width, y + s, kLegendSeparator);
  y += s + pad;

  for (const std::string& line : legend.lines) {
    draw_text(out, margin, y + s, line, s, kLegendText);
    y += line_h;
  }
  y += pad;

  // Color bar with a thin frame.
  const int x0 = margin;
  const int x1 = std::max(x0 + 2, out.width - margin);  // exclusive
  const int span = std::max(1, x1 - x0 - 1);
  for (int x = x0; x < x1; ++x) {
    const Rgb8 c = legend.bar(static_cast<double>(x - x0) / span);
    out.fill_rect(x, y, x + 1, y + bar_h, c);
  }
  const int bar_y = y;
  y += bar_h;

  // Ticks: place labels by priority, skipping any that would overlap a placed one.
  std::vector<LegendTick> ticks = legend.ticks;
  std::stable_sort(ticks.begin(), ticks.end(),
                   [](const LegendTick& a, const LegendTick& b) { return a.priority < b.priority; });
  std::vector<std::pair<int, int>> placed;  // label extents [left, right)
  const int gap = 6 * s;
  for (const LegendTick& tick : ticks) {
    const int tx = x0 + static_cast<int>(std::lround(std::clamp(tick.t, 0.0, 1.0) * span));
    const int w = text_width(tick.label, s);
    int left = tick.align < 0 ? tx : tick.align > 0 ? tx - w + 1 : tx - w / 2;
    left = std::clamp(left, 0, std::max(0, out.width - w));
    const int right = left + w;
    bool overlaps = false;
    for (const auto& [l, r] : placed)
      if (left < r + gap && l < right + gap) overlaps = true;
    if (overlaps) continue;
    placed.emplace_back(left, right);
    out.fill_rect(tx - (s - 1) / 2, bar_y + bar_h, tx - (s - 1) / 2 + s, y + tick_h, kLegendText);
    draw_text(out, left, y + tick_h + s + s, tick.label, s, kLegendText);
  }
  y += tick_h + s + line_h;

  if (!legend.swatches.empty()) {
    y += 2 * s;
    int x = margin;
    for (const LegendSwatch& sw : legend.swatches) {
      out.fill_rect(x, y + s, x + 9 * s, y + 10 * s, kLegendSeparator);
      out.fill_rect(x + s, y + 2 * s, x + 8 * s, y + 9 * s, sw.color);
      x += 12 * s;
      x += draw_text(out, x, y + 2 * s, sw.caption, s, kLegendText) + 12 * s;
    }
  }
  return out;
}

/// Linear ticks at "nice" steps (1, 2, 2.5, 5 x 10^k) strictly inside (lo, hi).
std::vector<double> nice_linear_ticks(double lo, double hi, int target) {
  std::vector<double> out;
  const double range = hi - lo;
  if (!(range > 0) || target < 1) return out;
  const double raw = range / target;
  const double mag = std::pow(10.0, std::floor(std::log10(raw)));
  double step = 10 * mag;
  for (double m : {1.0, 2.0, 2.5, 5.0, 10.0})
    if (m * mag >= raw) {
      step = m * mag;
      break;
    }
  const double first = std::ceil(lo / step);
  for (double k = first;; k += 1) {
    double v = k * step;
    if (std::fabs(v) < step * 1e-9) v = 0;
    if (v >= hi - step * 1e-6) break;
    if (v > lo + step * 1e-6) out.push_back(v);
    if (out.size() > 1000) break;
  }
  return out;
}

struct ValueStats {
  std::size_t count = 0;  // finite values
  double min = 0;
  double max = 0;
  double mean = 0;
  bool no_data = false;  // some value is not finite (drawn in kNoDataColor)
};

template <typename T>
ValueStats value_stats(const std::vector<T>& values) {
  ValueStats st;
  if constexpr (std::is_integral_v<T> && std::is_unsigned_v<T> && sizeof(T) <= 4) {
    // Counts: every value finite; an exact 64-bit sum (up to 2^32 values of up to 2^32 - 1) and
    // no branch per value, so the loop vectorises (the pass was a third of a heat map's CPU).
    if (values.empty()) return st;
    std::uint64_t sum = 0;
    T lo = std::numeric_limits<T>::max(), hi = 0;
    for (const T v : values) {
      sum += v;
      lo = std::min(lo, v);
      hi = std::max(hi, v);
    }
    st.count = values.size();
    st.min = static_cast<double>(lo);
    st.max = static_cast<double>(hi);
    st.mean = static_cast<double>(sum) / static_cast<double>(st.count);
    return st;
  }
  double sum = 0;
  bool first = true;
  for (const T raw : values) {
    const auto v = static_cast<double>(raw);
    if (!std::isfinite(v)) {
      st.no_data = true;
      continue;
    }
    ++st.count;
    sum += v;
    if (first || v < st.min) st.min = v;
    if (first || v > st.max) st.max = v;
    first = false;
  }
  if (st.count > 0) st.mean = sum / static_cast<double>(st.count);
  return st;
}

/// The range a heat map's colours span: the spec's bounds, else from 0 (or the minimum when
/// negative) to the maximum of the finite values.
HeatmapRange range_of(const ValueStats& st, const HeatmapSpec& spec) {
  HeatmapRange r;
  r.lo = spec.min_value ? *spec.min_value : std::min(0.0, st.min);
  r.hi = spec.max_value ? *spec.max_value : st.max;
  if (!std::isfinite(r.lo)) r.lo = 0;
  if (!std::isfinite(r.hi)) r.hi = r.lo + 1;
  if (!(r.hi > r.lo)) r.hi = r.lo + 1;
  return r;
}

/// The legend of a heat map whose values have the statistics `st` and whose colours span `range`
/// (both from one pass over the values: a 1080p map has 2 M of them).
Legend heatmap_legend(const ValueStats& st, const HeatmapRange& range, const HeatmapSpec& spec, int bar_width,
                      int text_scale, const std::string& per_what) {
  Legend legend;
  std::string title = spec.title.empty() ? std::string("Heat map") : spec.title;
  if (!spec.unit.empty()) title += " (" + spec.unit + ")";
  if (spec.log_scale) title += ", log scale";
  legend.lines.push_back(title);
  if (st.count == 0) {
    legend.lines.push_back("no data");
  } else {
    legend.lines.push_back("min " + format_legend_number(st.min, 4) + "   mean " +
                           format_legend_number(st.mean, 4) + "   max " + format_legend_number(st.max, 4) +
                           "   " + per_what);
  }
  legend.bar = [](double t) { return colormap_color(t); };

  std::string lo_label = format_legend_number(range.lo);
  std::string hi_label = format_legend_number(range.hi);
  if (st.count > 0 && st.min < range.lo) lo_label = "<=" + lo_label;
  if (st.count > 0 && st.max > range.hi) hi_label = ">=" + hi_label;
  legend.ticks.push_back({0.0, lo_label, -1, 0});
  legend.ticks.push_back({1.0, hi_label, +1, 0});

  const int label_room = 48 * text_scale;  // a label plus spacing, in pixels
  const int target = std::clamp(bar_width / label_room, 1, 10);
  if (!spec.log_scale) {
    for (double v : nice_linear_ticks(range.lo, range.hi, target))
      legend.ticks.push_back({heatmap_position(v, range, false), format_legend_number(v), 0, 1});
  } else {
    // Offsets d = v - lo at 1, 2, 5 x 10^k, decades first; no fractions when the range spans
    // ten or more (counts).
    const double top = range.hi - range.lo;
    const double first = top >= 10 ? 1.0 : std::pow(10.0, std::floor(std::log10(top)) - 2);
    for (double decade = first; decade < top; decade *= 10) {
      for (double m : {1.0, 2.0, 5.0}) {
        const double d = m * decade;
        if (d >= top * (1 - 1e-9) || d <= 0) continue;
        const double v = range.lo + d;
        const double t = heatmap_position(v, range, true);
        if (t < 0.02) continue;  // crowded against the low end
        legend.ticks.push_back({t, format_legend_number(v), 0, m == 1.0 ? 1 : 2});
      }
    }
  }
  if (st.no_data) legend.swatches.push_back({kNoDataColor, "no data"});
  return legend;
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// Depth and ids

ImageRGB8 depth_to_image(const std::vector<float>& depth01, int w, int h, bool legend) {
  check_size(depth01.size(), w, h, "depth_to_image");
  float dmin = std::numeric_limits<float>::infinity();
  float dmax = -std::numeric_limits<float>::infinity();
  for (float d : depth01) {
    if (!(d < 1.0f)) continue;  // cleared or NaN
    dmin = std::min(dmin, d);
    dmax = std::max(dmax, d);
  }
  const bool any = dmin <= dmax;
  constexpr int kNear = 255;
  constexpr int kFar = 24;
  auto grey_at = [&](double t) {  // t: 0 near .. 1 far
    const auto g = static_cast<std::uint8_t>(kNear - lround_nonnegative((kNear - kFar) * std::clamp(t, 0.0, 1.0)));
    return Rgb8{g, g, g};
  };
  const double span = static_cast<double>(dmax) - static_cast<double>(dmin);
  ImageRGB8 image(w, h);
  for (std::size_t i = 0; i < depth01.size(); ++i) {
    const float d = depth01[i];
    Rgb8 c = kDepthClearedColor;
    if (d < 1.0f) c = span > 0 ? grey_at((static_cast<double>(d) - dmin) / span) : grey_at(0);
    image.rgb[3 * i] = c.r;
    image.rgb[3 * i + 1] = c.g;
    image.rgb[3 * i + 2] = c.b;
  }
  if (!legend) return image;

  Legend lg;
  lg.bar = grey_at;
  lg.lines.push_back("Depth (window z in [0,1]), grey stretched over the depths below 1.0");
  if (!any) {
    lg.lines.push_back("no geometry: every pixel is cleared (1.0)");
    lg.bar = [](double) { return kDepthClearedColor; };
  } else {
    // Enough decimals that min and max differ in the labels.
    int decimals = 3;
    if (span > 0) decimals = std::clamp(static_cast<int>(std::ceil(-std::log10(span))) + 1, 3, 7);
    auto fmt = [decimals](double v) {
      char buf[64];
      std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
      return std::string(buf);
    };
    lg.lines.push_back("white = nearest " + fmt(dmin) + ", dark grey = farthest " + fmt(dmax));
    lg.ticks.push_back({0.0, "near " + fmt(dmin), -1, 0});
    lg.ticks.push_back({1.0, "far " + fmt(dmax), +1, 0});
    if (span > 0) lg.ticks.push_back({0.5, fmt(dmin + span / 2), 0, 1});
  }
  lg.swatches.push_back({kDepthClearedColor, "cleared (depth 1.0)"});
  return append_legend(image, lg);
}

Rgb8 id_color(std::uint32_t id) {
  // murmur3 finalizer, then each channel squeezed into [56, 255] so no id is black.
  std::uint32_t x = id;
  x ^= x >> 16;
  x *= 0x85ebca6bu;
  x ^= x >> 13;
  x *= 0xc2b2ae35u;
  x ^= x >> 16;
  auto ch = [](std::uint32_t byte) { return static_cast<std::uint8_t>(56 + byte * 199 / 255); };
  return {ch(x & 0xffu), ch((x >> 8) & 0xffu), ch((x >> 16) & 0xffu)};
}

ImageRGB8 ids_to_image(const std::vector<std::uint32_t>& ids, int w, int h, std::uint32_t none) {
  check_size(ids.size(), w, h, "ids_to_image");
  ImageRGB8 image(w, h);
  for (std::size_t i = 0; i < ids.size(); ++i) {
    const Rgb8 c = ids[i] == none ? Rgb8{} : id_color(ids[i]);
    image.rgb[3 * i] = c.r;
    image.rgb[3 * i + 1] = c.g;
    image.rgb[3 * i + 2] = c.b;
  }
  return image;
}

// ---------------------------------------------------------------------------------------------
// Heat maps

HeatmapRange heatmap_range(const std::vector<double>& values, const HeatmapSpec& spec) {
  return range_of(value_stats(values), spec);
}

double heatmap_position(double v, const HeatmapRange& range, bool log_scale) {
  if (std::isnan(v)) return 0;
  const double d = v - range.lo;
  if (d <= 0) return 0;
  if (v >= range.hi) return 1;
  const double t = log_scale ? std::log10(1 + d) / std::log10(1 + (range.hi - range.lo))
                             : d / (range.hi - range.lo);
  return std::clamp(t, 0.0, 1.0);
}

namespace {

/// A heat map of counts colours each count once, from a table up to the largest count, when that
/// table has at most one entry per this many pixels (a 1080p counter's largest count is tens to
/// hundreds against 2 M pixels); a larger one (a rare huge count) would cost more than it saves.
constexpr std::size_t kCountTableShare = 8;

/// heatmap_to_image for values of type T (double, or counts read as they are stored).
template <typename T>
ImageRGB8 values_heatmap(const std::vector<T>& values, int w, int h, const HeatmapSpec& spec) {
  check_size(values.size(), w, h, "heatmap_to_image");
  const ValueStats st = value_stats(values);
  const HeatmapRange range = range_of(st, spec);
  ImageRGB8 image(w, h);
  // Counts: the colour of every count up to the largest, once each (the mapping below, per value
  // instead of per pixel), when that table is small against the frame.
  bool drawn = false;
  if constexpr (std::is_integral_v<T>) {
    const auto top = static_cast<std::uint64_t>(st.count > 0 ? st.max : 0);
    if (top < values.size() / kCountTableShare) {
      std::vector<Rgb8> colour(top + 1);
      for (std::uint64_t v = 0; v <= top; ++v) colour[v] = colormap_color(heatmap_position(static_cast<double>(v), range, spec.log_scale));
      for (std::size_t i = 0; i < values.size(); ++i) {
        const Rgb8 c = colour[static_cast<std::size_t>(values[i])];
        image.rgb[3 * i] = c.r;
        image.rgb[3 * i + 1] = c.g;
        image.rgb[3 * i + 2] = c.b;
      }
      drawn = true;
    }
  }
  // Otherwise neighbouring pixels mostly hold the same value: the colour of the previous one is
  // reused (the same colour the mapping gives, without the colormap's interpolation per pixel).
  double last_v = std::numeric_limits<double>::quiet_NaN();
  Rgb8 last_c = kNoDataColor;
  for (std::size_t i = 0; !drawn && i < values.size(); ++i) {
    const auto v = static_cast<double>(values[i]);
    if (!(v == last_v)) {
      last_c = std::isfinite(v) ? colormap_color(heatmap_position(v, range, spec.log_scale)) : kNoDataColor;
      last_v = v;
    }
    const Rgb8 c = last_c;
    image.rgb[3 * i] = c.r;
    image.rgb[3 * i + 1] = c.g;
    image.rgb[3 * i + 2] = c.b;
  }
  const int s = legend_text_scale(w);
  const Legend legend = heatmap_legend(st, range, spec, w - 16 * s, s,
                                       "(per pixel, " + std::to_string(w) + "x" + std::to_string(h) + ")");
  return append_legend(image, legend);
}

}  // namespace

ImageRGB8 heatmap_to_image(const std::vector<double>& values, int w, int h, const HeatmapSpec& spec) {
  return values_heatmap(values, w, h, spec);
}

ImageRGB8 heatmap_to_image(const std::vector<std::uint32_t>& counts, int w, int h, const HeatmapSpec& spec) {
  return values_heatmap(counts, w, h, spec);
}

namespace {

/// Checks a tile grid and frame for the per-tile maps (`what` names the caller in the message).
void check_tile_grid(const std::vector<double>& values_per_tile, int tiles_x, int tiles_y, int tile_w, int tile_h, int w,
                     int h, const char* what) {
  check_size(values_per_tile.size(), tiles_x, tiles_y, what);
  if (tile_w <= 0 || tile_h <= 0 || w <= 0 || h <= 0)
    throw std::invalid_argument(std::string(what) + ": tile and frame sizes must be positive");
}

/// The value of the tile covering pixel (x, y), NaN past the grid.
double tile_value_at(const std::vector<double>& values_per_tile, int tiles_x, int tiles_y, int tile_w, int tile_h, int x,
                     int y) {
  const int tx = x / tile_w, ty = y / tile_h;
  if (tx >= tiles_x || ty >= tiles_y) return std::numeric_limits<double>::quiet_NaN();
  return values_per_tile[static_cast<std::size_t>(ty) * static_cast<std::size_t>(tiles_x) + static_cast<std::size_t>(tx)];
}

}  // namespace

std::vector<double> expand_tiles_to_pixels(const std::vector<double>& values_per_tile, int tiles_x,
                                           int tiles_y, int tile_w, int tile_h, int w, int h) {
  check_tile_grid(values_per_tile, tiles_x, tiles_y, tile_w, tile_h, w, h, "expand_tiles_to_pixels");
  std::vector<double> out(static_cast<std::size_t>(w) * h);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) out[static_cast<std::size_t>(y) * w + x] = tile_value_at(values_per_tile, tiles_x, tiles_y, tile_w, tile_h, x, y);
  }
  return out;
}

ImageRGB8 heatmap_tiles_to_image(const std::vector<double>& values_per_tile, int tiles_x, int tiles_y,
                                 int tile_w, int tile_h, int w, int h, const HeatmapSpec& spec) {
  // Each pixel's tile value is looked up as it is drawn (no frame-sized copy of the values).
  check_tile_grid(values_per_tile, tiles_x, tiles_y, tile_w, tile_h, w, h, "expand_tiles_to_pixels");
  const ValueStats st = value_stats(values_per_tile);
  const HeatmapRange range = range_of(st, spec);
  ImageRGB8 image(w, h);
  const bool borders = tile_w >= 4 && tile_h >= 4;
  double last_v = std::numeric_limits<double>::quiet_NaN();  // a tile's value repeats along its row
  Rgb8 last_c = kNoDataColor;
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const double v = tile_value_at(values_per_tile, tiles_x, tiles_y, tile_w, tile_h, x, y);
      if (!(v == last_v)) {
        last_c = std::isfinite(v) ? colormap_color(heatmap_position(v, range, spec.log_scale)) : kNoDataColor;
        last_v = v;
      }
      Rgb8 c = last_c;
      if (borders && (x % tile_w == 0 || y % tile_h == 0)) c = lerp(c, Rgb8{0, 0, 0}, 0.45);
      image.set(x, y, c);
    }
  }
  const int s = legend_text_scale(w);
  const Legend legend = heatmap_legend(st, range, spec, w - 16 * s, s,
                                       "(per tile, " + std::to_string(tiles_x) + "x" + std::to_string(tiles_y) +
                                           " tiles of " + std::to_string(tile_w) + "x" + std::to_string(tile_h) + ")");
  return append_legend(image, legend);
}

}  // namespace tbdr
