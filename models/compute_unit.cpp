#include "models/compute_unit.hpp"

#include <algorithm>
#include <bit>
#include <charconv>
#include <cmath>
#include <functional>
#include <optional>
#include <utility>

#include "models/geometry_unit.hpp"
#include "models/shading.hpp"
#include "models/tile_memory.hpp"
#include "kernel/errors.hpp"

namespace tbdr {

namespace {

// ALU costs of the kernels' inner steps (documented in docs/kernels.md).
constexpr std::uint64_t kSphereVolumeTestOps = 24;  // 4 plane dot products + 2 depth compares
constexpr std::uint64_t kDepthReduceOps = 2;        // min and max per sample
constexpr std::uint64_t kClusterIndexOps = 12;      // view depth, log/slice, tile index per sample
constexpr std::uint64_t kWorkListOps = 4;           // material lookup and append per pixel
constexpr std::uint64_t kRefetchVertexBytes = 32;   // position, normal, uv per re-fetched vertex
constexpr std::uint64_t kTileGridEntryBytes = 8;    // offset + count per tile or cluster
constexpr std::uint64_t kLightIndexBytes = 4;       // one light index
constexpr std::uint64_t kDepthBoundsTileBytes = 8;  // min and max depth per tile, FP32 each
constexpr std::uint64_t kUsedClusterBytes = 4;      // one cluster index in the compact used list
constexpr std::uint64_t kWorkListEntryBytes = 8;    // (tile, material) per work list entry
constexpr Format kImageFormat = Format::Rgba8;      // an image buffer is rgba8 (what the kernels store)
// Rows per item of a shading kernel on the thread pool: a host-side work split (no hardware
// meaning), 1080 rows = 68 items, enough to balance two to a few dozen threads.
constexpr int kShadeBandRows = 16;
constexpr std::uint64_t kImageBytesPerPixel = 4;    // bytes of kImageFormat
// Culling stays conservative against float rounding: a tile's depth range is widened by 0.1 %.
constexpr float kBoundsFarScale = 1.001f;
constexpr float kBoundsNearScale = 0.999f;

// Defaults of the kernels' trace parameters (docs/kernels.md): 16x16 pixel tiles (Andersson;
// Harada's Forward+); clusters of 64x64 pixels and 16 depth slices (Olsson, Billeter, Assarsson).
constexpr int kDefaultTilePx = 16;
constexpr int kDefaultClusterTilePx = 64;
constexpr int kDefaultClusterSlices = 16;


/// Which depth range of a tile tile_light_cull tests lights against (its `bounds` parameter).
enum class DepthRange : std::uint8_t {
  MinMax,  ///< between the tile's nearest and farthest visible depth
  Max,     ///< from the eye to the tile's farthest visible depth
  None,    ///< the whole frustum depth (no depth image needed)
};

/// A dispatch being run: its parameters, inputs and outputs, with errors at its trace line.
class Dispatch {
 public:
  Dispatch(const ComputeContext& ctx, const DispatchCmd& cmd, ComputeStats& stats, DramTraffic& dram)
      : ctx_(ctx), cmd_(cmd), stats_(stats), dram_(dram) {}

  [[noreturn]] void fail(const std::string& msg) const {
    throw InputError(*ctx_.trace_path, cmd_.line, "kernel '" + std::string(to_string(cmd_.kernel)) + "': " + msg);
  }
  void allow(std::initializer_list<const char*> keys) {
    for (const auto& [k, v] : cmd_.params) {
      bool ok = false;
      for (const char* a : keys) ok = ok || k == a;
      if (!ok) {
        std::string known;
        for (const char* a : keys) known += (known.empty() ? "" : ", ") + std::string(a);
        fail("unknown parameter '" + k + "' (known: " + (known.empty() ? "none" : known) + ")");
      }
    }
  }
  int get_int(const char* key, int def, int lo, int hi) const {
    auto it = cmd_.params.find(key);
    if (it == cmd_.params.end()) return def;
    int v = 0;
    const auto& t = it->second;
    auto r = std::from_chars(t.data(), t.data() + t.size(), v);
    if (r.ec != std::errc{} || r.ptr != t.data() + t.size() || v < lo || v > hi) {
      fail("parameter " + std::string(key) + "='" + t + "' is not an integer in [" + std::to_string(lo) + ", " +
           std::to_string(hi) + "]");
    }
    return v;
  }
  float get_float(const char* key, float def, float lo, float hi) const {
    auto it = cmd_.params.find(key);
    if (it == cmd_.params.end()) return def;
    float v = 0;
    const auto& t = it->second;
    auto r = std::from_chars(t.data(), t.data() + t.size(), v);
    if (r.ec != std::errc{} || r.ptr != t.data() + t.size() || !(v >= lo && v <= hi)) {
      fail("parameter " + std::string(key) + "='" + t + "' is not a number in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
    }
    return v;
  }
  /// A choice parameter as its enumerator (`def` when absent), looked up once per dispatch.
  template <class E>
  E get_choice(const char* key, E def, std::initializer_list<std::pair<E, const char*>> choices) const {
    auto it = cmd_.params.find(key);
    if (it == cmd_.params.end()) return def;
    for (const auto& [value, name] : choices) {
      if (it->second == name) return value;
    }
    std::string known;
    for (const auto& c : choices) known += (known.empty() ? "" : "|") + std::string(c.second);
    fail("parameter " + std::string(key) + "='" + it->second + "' is not one of " + known);
  }
  const ShaderDesc& shader() const {
    auto it = cmd_.params.find("shader");
    if (it == cmd_.params.end()) fail("parameter shader=NAME is required");
    const ShaderDesc* s = ctx_.trace->find_shader(it->second);
    if (!s) fail("unknown shader '" + it->second + "'");
    return *s;
  }

  /// A read attachment image of the given kind (depth, or with stored surfaces).
  const AttachmentImage* read_depth() const {
    for (const auto& n : cmd_.reads) {
      auto it = ctx_.images->attachments.find(n);
      if (it != ctx_.images->attachments.end() && is_depth_format(it->second.format)) return &it->second;
    }
    return nullptr;
  }
  const AttachmentImage* read_surfaces() const {
    for (const auto& n : cmd_.reads) {
      auto it = ctx_.images->attachments.find(n);
      if (it != ctx_.images->attachments.end() && !it->second.surface.empty()) return &it->second;
    }
    return nullptr;
  }
  /// Fetches of shader `sh` that sample material textures: those beyond one per image read
  /// (G-buffer targets, depth, visibility ids are each fetched once per shaded sample).
  std::uint32_t material_fetches(const ShaderDesc& sh) const {
    std::uint32_t images = 0;
    for (const auto& n : cmd_.reads) images += ctx_.images->attachments.count(n) > 0 ? 1u : 0u;
    return sh.tex_fetches > images ? sh.tex_fetches - images : 0;
  }
  /// The first buffer in `names` holding `content`, or "".
  std::string buffer_with(const std::vector<std::string>& names, BufferContent content) const {
    for (const auto& n : names) {
      const BufferDesc* b = ctx_.trace->find_buffer(n);
      if (b && b->content == content) return n;
    }
    return {};
  }

  /// Books the DRAM reads of every input: images at their full size, buffers at their declared
  /// size except light lists and grids, which are booked at the size their producer wrote.
  void charge_reads() {
    const std::uint64_t pixels = static_cast<std::uint64_t>(ctx_.viewport.width_px) * static_cast<std::uint64_t>(ctx_.viewport.height_px);
    for (const auto& n : cmd_.reads) {
      if (auto it = ctx_.images->attachments.find(n); it != ctx_.images->attachments.end()) {
        const AttachmentImage& img = it->second;
        const std::uint64_t bps = is_depth_format(img.format) ? static_cast<std::uint64_t>(ctx_.hw->isp.depth_stencil_bytes_per_sample)
                                                                : bytes_per_sample(img.format);
        dram_.read(traffic_class_of(img.usage), pixels * img.samples * bps);
        continue;
      }
      const BufferDesc* b = ctx_.trace->find_buffer(n);
      if (!b) continue;
      dram_.read(b->traffic, written_bytes(n, b->bytes));
    }
  }
  /// Books a write of `bytes` to buffer `name` and remembers the size for later readers.
  void charge_write(const std::string& name, std::uint64_t bytes) {
    const BufferDesc* b = ctx_.trace->find_buffer(name);
    const DramClass c = b ? b->traffic : DramClass::Other;
    dram_.write(c, bytes);
    ctx_.images->buffer_bytes_written[name] = bytes;
  }
  std::uint64_t written_bytes(const std::string& name, std::uint64_t declared) const {
    auto it = ctx_.images->buffer_bytes_written.find(name);
    return it == ctx_.images->buffer_bytes_written.end() ? declared : it->second;
  }

  const ComputeContext& ctx_;
  const DispatchCmd& cmd_;
  ComputeStats& stats_;
  DramTraffic& dram_;
};

/// Runs fn(item, worker) for every item in [0, count): on the context's pool when it has one,
/// else in item order on the caller's thread. Items write only their own outputs.
void run_items(const ComputeContext& ctx, std::size_t count, const std::function<void(std::size_t, unsigned)>& fn) {
  if (ctx.pool != nullptr) {
    ctx.pool->for_each(count, fn);
  } else {
    for (std::size_t i = 0; i < count; ++i) fn(i, 0);
  }
}

std::vector<PixelRect> light_rects(const ComputeContext& ctx) {
  std::vector<PixelRect> r;
  r.reserve(ctx.trace->lights.size());
  for (const auto& l : ctx.trace->lights) r.push_back(light_screen_rect(l, ctx.camera, ctx.viewport));
  return r;
}

/// The lights' spheres in view space, in light order.
std::vector<ViewSphere> view_spheres(const ComputeContext& ctx) {
  std::vector<ViewSphere> v;
  v.reserve(ctx.trace->lights.size());
  for (const auto& l : ctx.trace->lights) v.push_back(ViewSphere::of(*ctx.frustum, l));
  return v;
}

/// Per row of `tile_px` tiles (`rows` of them), the lights whose screen rectangle reaches the
/// row, ascending: a tile then tests only its row's lights (rectangles are inside the viewport).
std::vector<std::vector<std::uint32_t>> lights_by_tile_row(const std::vector<PixelRect>& rects, int tile_px, int rows) {
  std::vector<std::vector<std::uint32_t>> r(static_cast<std::size_t>(rows));
  for (std::uint32_t l = 0; l < rects.size(); ++l) {
    const PixelRect& lr = rects[l];
    if (lr.empty()) continue;
    const int r0 = std::max(0, lr.y0 / tile_px), r1 = std::min(rows - 1, (lr.y1 - 1) / tile_px);
    for (int ty = r0; ty <= r1; ++ty) r[static_cast<std::size_t>(ty)].push_back(l);
  }
  return r;
}

/// Sum of the contributions of `list` (or every light via the exact candidates) at a surface.
glm::vec3 shade_surface(const ComputeContext& ctx, const SurfacePoint& s, int x, int y, const std::vector<std::uint32_t>* list) {
  glm::vec3 c = ShadingModel::ambient(s);
  const auto& lights = ctx.trace->lights;
  if (list) {
    for (std::uint32_t l : *list) c += ShadingModel::light_contribution(s, ctx.camera.eye, lights[l]);
  } else {
    for (std::uint32_t l : ctx.light_bins->at(x, y)) c += ShadingModel::light_contribution(s, ctx.camera.eye, lights[l]);
  }
  return c;
}

/// The distinct texture lines of one workgroup tile: an open-addressing hash set (a tile's quads
/// repeat each line about 8 times at 1080p; sorting every repeat cost more than hashing it),
/// emptied in the time of its size.
class TileLineSet {
 public:
  /// Adds `line`; true when it was not in the set.
  bool insert(std::uint64_t line) {
    if ((values_.size() + 1) * 2 > slots_.size()) grow();
    std::size_t i = slot_of(line);
    while (slots_[i] != kEmpty) {
      if (slots_[i] == line) return false;
      i = (i + 1) & (slots_.size() - 1);
    }
    slots_[i] = line;
    values_.push_back(line);
    return true;
  }
  void clear() {
    for (std::uint64_t v : values_) {
      std::size_t i = slot_of(v);
      while (slots_[i] != v) i = (i + 1) & (slots_.size() - 1);
      slots_[i] = kEmpty;
    }
    values_.clear();
  }

 private:
  // No line starts at the last byte of the address space: an empty slot.
  static constexpr std::uint64_t kEmpty = ~std::uint64_t{0};
  // Fibonacci hashing: multiply by 2^64 / golden ratio, keep the top bits (line offsets are
  // multiples of the line size, so their low bits are all zero).
  static constexpr std::uint64_t kHashMultiplier = 0x9E3779B97F4A7C15ull;
  static constexpr std::size_t kInitialSlots = 1024;

  std::size_t slot_of(std::uint64_t v) const { return static_cast<std::size_t>((v * kHashMultiplier) >> shift_); }
  void grow() {
    const std::size_t n = slots_.empty() ? kInitialSlots : slots_.size() * 2;
    slots_.assign(n, kEmpty);
    shift_ = 64 - static_cast<unsigned>(std::countr_zero(n));
    for (std::uint64_t v : values_) {
      std::size_t i = slot_of(v);
      while (slots_[i] != kEmpty) i = (i + 1) & (n - 1);
      slots_[i] = v;
    }
  }

  std::vector<std::uint64_t> slots_;
  std::vector<std::uint64_t> values_;
  unsigned shift_ = 64;
};

/// The texture lines of a shading kernel's material fetches (slots 0 .. fetches-1 of each surface's
/// material texture): per workgroup tile of `group_px` pixels, every (2x2 quad, triangle) with a
/// stored surface reads the bilinear footprint of its quad uvs (SurfacePoint::quad_uv, what the TSP
/// computes for the same quad), the tile's lines sorted and kept once and appended to
/// ctx.texture_lines, and the lines booked as texture reads (what the texture unit requests, before
/// the texture cache), as render tiles' footprints are.
void material_texture_lines(const ComputeContext& ctx, const AttachmentImage& surfaces, std::uint32_t fetches, int group_px,
                            ComputeStats& stats, DramTraffic& dram) {
  if (fetches == 0 || ctx.textures == nullptr || ctx.texture_lines == nullptr) return;
  const TextureLayout& layout = *ctx.textures;
  const int W = ctx.viewport.width_px, H = ctx.viewport.height_px;
  const std::size_t S = surfaces.samples;
  const int g = std::max(1, group_px);
  const int rows = (H + g - 1) / g;
  // One item per row of workgroup tiles, with its own lines (its tiles' footprints in tile order)
  // and counts, appended in row order after: the serial order at any thread count.
  struct RowLines {
    std::vector<std::uint64_t> lines;
    std::uint64_t accesses = 0;
  };
  std::vector<RowLines> row_lines(static_cast<std::size_t>(rows));
  auto tile_row = [&](std::size_t row, unsigned /*worker*/) {
    RowLines& out = row_lines[row];
    const int ty = static_cast<int>(row) * g, y_end = std::min(H, ty + g);
    // Slot 0's lines, kept once with their texture's copy stride: a texture's copies follow one
    // another and textures do not overlap (TextureLayout), so the copies of distinct slot-0
    // lines are distinct lines.
    TileLineSet seen;
    std::vector<std::pair<std::uint64_t, std::uint64_t>> firsts;  // (slot-0 line, copy stride)
    std::vector<std::uint64_t> lines;
    QuadFootprint fp;
    for (int tx = 0; tx < W; tx += g) {
      const int x_end = std::min(W, tx + g);
      seen.clear();
      firsts.clear();
      // Each 2x2 quad (its pixels inside this tile) reads the footprint of every distinct triangle
      // among its samples once; the triangle's surfaces in the quad carry the same quad uvs.
      for (int qy = ty >> 1; qy <= (y_end - 1) >> 1; ++qy) {
        for (int qx = tx >> 1; qx <= (x_end - 1) >> 1; ++qx) {
          std::uint32_t triangles[4 * kMaxSamplesPerPixel];
          std::size_t n = 0;
          for (int y = std::max(2 * qy, ty); y <= std::min(2 * qy + 1, y_end - 1); ++y) {
            for (int x = std::max(2 * qx, tx); x <= std::min(2 * qx + 1, x_end - 1); ++x) {
              const std::size_t p = static_cast<std::size_t>(y) * static_cast<std::size_t>(W) + static_cast<std::size_t>(x);
              for (std::size_t smp = 0; smp < S; ++smp) {
                const std::size_t k = p * S + smp;
                if (!surfaces.surface_valid[k]) continue;
                const SurfaceSite& s = surfaces.surface.site(k);
                if (s.material == kNoMaterial) continue;
                if (std::find(triangles, triangles + n, s.triangle) != triangles + n) continue;
                triangles[n++] = s.triangle;
                const TextureStorage& tex = layout.of_material(s.material);
                layout.quad_footprint(tex, s.quad_uv, fp);
                out.accesses += std::uint64_t{fp.count} * fetches;
                for (std::uint32_t j = 0; j < fp.count; ++j) {
                  if (seen.insert(fp.lines[j])) firsts.push_back({fp.lines[j], tex.slot_bytes});
                }
              }
            }
          }
        }
      }
      lines.clear();
      for (const auto& [line, stride] : firsts) {
        for (std::uint32_t f = 0; f < fetches; ++f) lines.push_back(line + std::uint64_t{f} * stride);
      }
      std::sort(lines.begin(), lines.end());
      out.lines.insert(out.lines.end(), lines.begin(), lines.end());
    }
  };
  run_items(ctx, row_lines.size(), tile_row);
  std::uint64_t accesses = 0, total = 0;
  for (const RowLines& r : row_lines) total += r.lines.size();
  ctx.texture_lines->reserve(ctx.texture_lines->size() + total);
  for (const RowLines& r : row_lines) {
    ctx.texture_lines->insert(ctx.texture_lines->end(), r.lines.begin(), r.lines.end());
    accesses += r.accesses;
  }
  stats.compute_texture_line_accesses += accesses;
  stats.compute_texture_tile_lines += total;
  dram.read(DramClass::Textures, total * layout.line_bytes());
}

/// Shades every stored surface of an image with the shader's light source (every light, a tile
/// grid's or a cluster grid's lists) and resolves multisampled surfaces; with `refetch_tile_px` > 0
/// (visibility buffer) each tile re-fetches the three vertices of every triangle it shades.
ImageBuffer shade_surfaces(const ComputeContext& ctx, const AttachmentImage& surfaces, const ShaderDesc& sh,
                           const TileLightGrid* tgrid, const ClusterGrid* cgrid, int refetch_tile_px, ComputeStats& stats,
                           DramTraffic& dram) {
  const int W = ctx.viewport.width_px, H = ctx.viewport.height_px;
  const std::uint64_t pixels = static_cast<std::uint64_t>(W) * static_cast<std::uint64_t>(H);
  const auto n_lights = static_cast<std::uint64_t>(ctx.trace->lights.size());
  const bool vbuffer = refetch_tile_px > 0;
  const int tile_px = vbuffer ? refetch_tile_px : 1;
  const std::uint64_t shaded_before = stats.compute_shaded_pixels.value();
  ImageBuffer img;
  if (ctx.colour) img.color.assign(pixels, glm::vec4(0.0f));
  // Bands of rows are independent (each pixel writes only its own image and counter entries): they
  // run on the pool, each with its own statistics, merged in band order after. With re-fetches a
  // band holds whole rows of tiles, so each band counts the distinct (tile, triangle) pairs of its
  // own tiles and the frame's count is their sum.
  const int band_rows = vbuffer ? (kShadeBandRows + tile_px - 1) / tile_px * tile_px : kShadeBandRows;
  const int bands = (H + band_rows - 1) / band_rows;
  const std::uint64_t tiles_x = static_cast<std::uint64_t>((W + tile_px - 1) / tile_px);
  std::vector<ComputeStats> band_stats(static_cast<std::size_t>(bands));
  std::vector<std::uint64_t> band_refetched(static_cast<std::size_t>(bands), 0);
  auto shade_band = [&](std::size_t band, unsigned /*worker*/) {
    ComputeStats& stats = band_stats[band];
    std::vector<std::uint64_t> refetched;  // (tile << 32) | triangle, a run of equal pairs once
    const int y_end = std::min(H, static_cast<int>(band + 1) * band_rows);
    for (int y = static_cast<int>(band) * band_rows; y < y_end; ++y) {
      for (int x = 0; x < W; ++x) {
        const std::size_t p = static_cast<std::size_t>(y) * W + static_cast<std::size_t>(x);
        // Shade each distinct surface of the pixel once (with MSAA a pixel's samples may hold
        // several triangles) and resolve: the average over the samples, uncovered ones black.
        const std::size_t S = surfaces.samples;
        glm::vec3 sum(0.0f);
        std::uint32_t shaded_triangles[kMaxSamplesPerPixel];
        glm::vec3 shaded_colors[kMaxSamplesPerPixel];
        std::size_t n_shaded = 0;
        for (std::size_t smp = 0; smp < S; ++smp) {
          if (!surfaces.surface_valid[p * S + smp]) continue;
          const SurfaceSite& s = surfaces.surface.site(p * S + smp);
          std::size_t k = 0;
          while (k < n_shaded && shaded_triangles[k] != s.triangle) ++k;
          if (k == n_shaded) {
            const std::vector<std::uint32_t>* list = nullptr;
            std::uint64_t count = n_lights;
            if (tgrid) list = &tgrid->at_pixel(x, y);
            if (cgrid) list = &cgrid->lists[cgrid->cluster_of(x, y, ctx.frustum->distance_of(s.position))];
            if (list) count = list->size();
            shaded_triangles[k] = s.triangle;
            shaded_colors[k] = ctx.colour ? shade_surface(ctx, surfaces.surface[p * S + smp], x, y, list) : glm::vec3(0.0f);  // FrameInputs::colour
            ++n_shaded;
            ++stats.compute_shaded_pixels;
            stats.compute_light_evaluations += count;
            stats.compute_alu_ops += sh.alu_ops + std::uint64_t{sh.light_alu_ops} * count;
            if (ctx.images->counters.images()) ctx.images->counters.lights_evaluated[p] += static_cast<std::uint32_t>(count);
            ctx.images->counters.shaded[p] += 1;
            if (vbuffer) {
              const std::uint64_t key = ((static_cast<std::uint64_t>(y / tile_px) * tiles_x + static_cast<std::uint64_t>(x / tile_px)) << 32) | s.triangle;
              if (refetched.empty() || refetched.back() != key) refetched.push_back(key);
            }
          }
          sum += shaded_colors[k];
        }
        if (n_shaded > 0 && ctx.colour) img.color[p] = FormatPrecision::color(kImageFormat, glm::vec4(sum / static_cast<float>(S), 1.0f));
      }
    }
    std::sort(refetched.begin(), refetched.end());
    band_refetched[band] = static_cast<std::uint64_t>(std::unique(refetched.begin(), refetched.end()) - refetched.begin());
  };
  run_items(ctx, static_cast<std::size_t>(bands), shade_band);
  std::uint64_t refetched = 0;
  for (std::size_t b = 0; b < static_cast<std::size_t>(bands); ++b) {
    stats += band_stats[b];
    refetched += band_refetched[b];
  }
  // Threads of uncovered pixels exit after reading their G-buffer sample: no texture fetches.
  stats.compute_texture_fetches += (stats.compute_shaded_pixels.value() - shaded_before) * sh.tex_fetches;
  if (vbuffer) {
    // Each tile re-fetches the three vertices of every triangle it shades (Burns & Hunt).
    stats.refetched_vertices += refetched * 3;
    dram.read(DramClass::Vertices, refetched * 3 * kRefetchVertexBytes);
  }
  return img;
}

/// One dispatch being run: its command, where its figures go, and the frame's size.
struct KernelRun {
  Dispatch& k;
  const ComputeContext& ctx;
  const DispatchCmd& cmd;
  ComputeStats& stats;
  DramTraffic& dram;
  std::string& image_written;
  int W, H;
  std::uint64_t pixels, n_lights;

  /// Tiles of `tile_px` pixels across and down the frame.
  void tiles_of(int tile_px, int& tx, int& ty) const {
    tx = (W + tile_px - 1) / tile_px;
    ty = (H + tile_px - 1) / tile_px;
  }
  /// Keeps the kernel's output image and charges its writes.
  void write_image(const std::string& name, ImageBuffer&& img) {
    ctx.images->image_buffers[name] = std::move(img);
    k.charge_write(name, pixels * kImageBytesPerPixel);
    image_written = name;
  }
};

/// depth_bounds: the nearest and farthest visible distance per tile.
void run_depth_bounds(KernelRun& r) {
  Dispatch& k = r.k;
  const ComputeContext& ctx = r.ctx;
  const DispatchCmd& cmd = r.cmd;
  ComputeStats& stats = r.stats;
  [[maybe_unused]] DramTraffic& dram = r.dram;
  [[maybe_unused]] const int W = r.W, H = r.H;
  [[maybe_unused]] const std::uint64_t pixels = r.pixels, n_lights = r.n_lights;
  k.allow({"tile_px"});
  const int tile_px = k.get_int("tile_px", kDefaultTilePx, 1, 1024);
  const AttachmentImage* depth = k.read_depth();
  if (!depth) k.fail("needs a depth image in reads=");
  const std::string out = k.buffer_with(cmd.writes, BufferContent::DepthBounds);
  if (out.empty()) k.fail("needs a depth_bounds buffer in writes=");
  auto b = std::make_shared<DepthBounds>(DepthBounds::compute(*ctx.frustum, *depth, tile_px, ctx.pool));
  stats.compute_alu_ops += pixels * depth->samples * kDepthReduceOps;
  k.charge_write(out, b->min_distance.size() * kDepthBoundsTileBytes);
  ctx.images->depth_bounds[out] = b;
}

/// tile_light_cull and tiled_deferred_shade (`shade`): the lights touching each tile, and for the
/// second the pixels shaded from their tile's list in the same pass (Andersson's single pass).
void run_tile_light_cull(KernelRun& r, bool shade) {
  Dispatch& k = r.k;
  const ComputeContext& ctx = r.ctx;
  const DispatchCmd& cmd = r.cmd;
  ComputeStats& stats = r.stats;
  [[maybe_unused]] DramTraffic& dram = r.dram;
  [[maybe_unused]] const int W = r.W, H = r.H;
  [[maybe_unused]] const std::uint64_t pixels = r.pixels, n_lights = r.n_lights;
  if (shade) {
    k.allow({"tile_px", "max_lights_per_tile", "bounds", "shader"});
  } else {
    k.allow({"tile_px", "max_lights_per_tile", "bounds"});
  }
  const int tile_px = k.get_int("tile_px", kDefaultTilePx, 1, 1024);
  const int cap = k.get_int("max_lights_per_tile", 0, 0, 1 << 20);
  const DepthRange bounds_mode = k.get_choice("bounds", DepthRange::MinMax,
                                              {{DepthRange::MinMax, "minmax"}, {DepthRange::Max, "max"}, {DepthRange::None, "none"}});
  auto grid = std::make_shared<TileLightGrid>();
  grid->tile_px = tile_px;
  r.tiles_of(tile_px, grid->tiles_x, grid->tiles_y);
  grid->max_lights_per_tile = static_cast<std::uint32_t>(cap);
  const std::size_t tiles = static_cast<std::size_t>(grid->tiles_x) * static_cast<std::size_t>(grid->tiles_y);
  grid->lists.assign(tiles, {});
  // Depth bounds: from a depth_bounds buffer, else computed here from a depth image.
  std::shared_ptr<DepthBounds> bounds;
  const std::string bname = k.buffer_with(cmd.reads, BufferContent::DepthBounds);
  if (!bname.empty()) {
    auto it = ctx.images->depth_bounds.find(bname);
    if (it == ctx.images->depth_bounds.end()) k.fail("depth_bounds buffer '" + bname + "' was not written by a depth_bounds dispatch");
    if (it->second->tile_px != tile_px) k.fail("depth_bounds buffer '" + bname + "' has another tile size");
    bounds = it->second;
  } else if (const AttachmentImage* depth = k.read_depth(); depth && bounds_mode != DepthRange::None) {
    bounds = std::make_shared<DepthBounds>(DepthBounds::compute(*ctx.frustum, *depth, tile_px, ctx.pool));
    stats.compute_alu_ops += pixels * depth->samples * kDepthReduceOps;
  }
  // Each tile keeps the lights whose screen rectangle meets it and whose sphere touches its
  // volume, ascending (what a hierarchical kernel computes). One item per row of tiles: it alone
  // writes its tiles' lists and counts its overflows.
  const auto rects = light_rects(ctx);
  const auto spheres = view_spheres(ctx);
  const auto row_lights = lights_by_tile_row(rects, tile_px, grid->tiles_y);
  std::vector<std::uint64_t> row_overflows(static_cast<std::size_t>(grid->tiles_y), 0);
  run_items(ctx, static_cast<std::size_t>(grid->tiles_y), [&](std::size_t row, unsigned /*worker*/) {
    const int ty = static_cast<int>(row);
    for (int tx = 0; tx < grid->tiles_x; ++tx) {
      const std::size_t t = static_cast<std::size_t>(ty * grid->tiles_x + tx);
      float d0 = 0.0f, d1 = 1e30f;
      if (bounds) {
        if (bounds->min_distance[t] > bounds->max_distance[t]) continue;  // nothing visible: empty list
        d1 = bounds->max_distance[t] * kBoundsFarScale;
        if (bounds_mode == DepthRange::MinMax) d0 = bounds->min_distance[t] * kBoundsNearScale;
      }
      const PixelRect rect = intersect({tx * tile_px, ty * tile_px, (tx + 1) * tile_px, (ty + 1) * tile_px}, {0, 0, W, H});
      const TileSides sides = TileSides::of(*ctx.frustum, rect);
      std::vector<std::uint32_t>& list = grid->lists[t];
      for (std::uint32_t l : row_lights[row]) {
        if (intersect(rects[l], rect).empty()) continue;
        if (sides.touches(spheres[l], d0, d1)) list.push_back(l);
      }
      if (cap > 0 && list.size() > static_cast<std::size_t>(cap)) ++row_overflows[row];
    }
  });
  for (std::uint64_t o : row_overflows) grid->overflowed_tiles += o;
  stats.light_volume_tests += tiles * n_lights;
  stats.compute_alu_ops += tiles * n_lights * kSphereVolumeTestOps;
  stats.light_list_entries += grid->total_entries();
  stats.light_list_overflows += grid->overflowed_tiles;
  if (!shade) {
    const std::string gname = k.buffer_with(cmd.writes, BufferContent::TileGrid);
    const std::string lname = k.buffer_with(cmd.writes, BufferContent::LightIndexList);
    if (gname.empty() || lname.empty()) k.fail("needs a tile_grid and a light_index_list buffer in writes=");
    k.charge_write(gname, tiles * kTileGridEntryBytes);
    k.charge_write(lname, grid->total_entries() * kLightIndexBytes);
    ctx.images->tile_grids[gname] = grid;
    return;
  }
  // Andersson's single pass: shade every pixel from its tile's list (kept in group-shared memory).
  const ShaderDesc& sh = k.shader();
  const AttachmentImage* surfaces = k.read_surfaces();
  if (!surfaces) k.fail("needs a G-buffer image (written by a pass) in reads=");
  const std::string out = k.buffer_with(cmd.writes, BufferContent::Image);
  if (out.empty()) k.fail("needs an image buffer in writes=");
  ImageBuffer img = shade_surfaces(ctx, *surfaces, sh, grid.get(), nullptr, 0, stats, dram);
  material_texture_lines(ctx, *surfaces, k.material_fetches(sh), tile_px, stats, dram);
  r.write_image(out, std::move(img));
}

/// cluster_flag and cluster_light_assign (`assign`): the clusters holding visible samples, and the
/// lights touching each used cluster.
void run_clusters(KernelRun& r, bool assign) {
  Dispatch& k = r.k;
  const ComputeContext& ctx = r.ctx;
  const DispatchCmd& cmd = r.cmd;
  ComputeStats& stats = r.stats;
  [[maybe_unused]] DramTraffic& dram = r.dram;
  [[maybe_unused]] const int W = r.W, H = r.H;
  [[maybe_unused]] const std::uint64_t pixels = r.pixels, n_lights = r.n_lights;
  if (assign) {
    k.allow({"tile_px", "slices", "slicing", "min_depth", "dense"});
  } else {
    k.allow({"tile_px", "slices", "slicing", "min_depth"});
  }
  const int tile_px = k.get_int("tile_px", kDefaultClusterTilePx, 1, 1024);
  const int slices = k.get_int("slices", kDefaultClusterSlices, 1, 4096);
  const Slicing slicing = k.get_choice("slicing", Slicing::Log, {{Slicing::Log, "log"}, {Slicing::Cubical, "cubical"}});
  const float min_depth = k.get_float("min_depth", ctx.frustum->near_plane, 0.0f, 1e6f);
  auto grid = std::make_shared<ClusterGrid>();
  grid->configure(*ctx.frustum, tile_px, slices, slicing, min_depth);
  const std::size_t clusters = grid->used.size();
  if (!assign) {
    const AttachmentImage* depth = k.read_depth();
    if (!depth) k.fail("needs a depth image in reads=");
    const std::string out = k.buffer_with(cmd.writes, BufferContent::UsedClusters);
    if (out.empty()) k.fail("needs a used_clusters buffer in writes=");
    // One item per row of cluster tiles: it alone flags that row's clusters.
    run_items(ctx, static_cast<std::size_t>(grid->tiles_y), [&](std::size_t row, unsigned /*worker*/) {
      const int y_end = std::min(H, (static_cast<int>(row) + 1) * tile_px);
      for (int y = static_cast<int>(row) * tile_px; y < y_end; ++y) {
        for (int x = 0; x < W; ++x) {
          const std::size_t p = (static_cast<std::size_t>(y) * W + static_cast<std::size_t>(x)) * depth->samples;
          for (std::size_t s = 0; s < depth->samples; ++s) {
            const float d = depth->depth[p + s];
            if (d < 1.0f) grid->used[grid->cluster_of(x, y, ctx.frustum->distance_of_window_depth(d))] = 1;
          }
        }
      }
    });
    stats.compute_alu_ops += pixels * depth->samples * kClusterIndexOps;
    stats.clusters_used += grid->used_count();
    k.charge_write(out, clusters / 8 + grid->used_count() * kUsedClusterBytes);  // flag bits + compact list of used clusters
    ctx.images->cluster_grids[out] = grid;
    return;
  }
  const bool dense_param = k.get_choice("dense", false, {{true, "yes"}, {false, "no"}});
  const std::string used_name = k.buffer_with(cmd.reads, BufferContent::UsedClusters);
  if (!dense_param && !used_name.empty()) {
    auto it = ctx.images->cluster_grids.find(used_name);
    if (it == ctx.images->cluster_grids.end()) k.fail("used_clusters buffer '" + used_name + "' was not written by cluster_flag");
    const ClusterGrid& f = *it->second;
    if (f.tile_px != grid->tile_px || f.slices != grid->slices || f.slicing != grid->slicing) {
      k.fail("cluster geometry differs from the cluster_flag dispatch that wrote '" + used_name + "'");
    }
    grid->used = f.used;
  } else {
    std::fill(grid->used.begin(), grid->used.end(), 1);
  }
  // Each light is tested against the used clusters its screen rectangle and depth extent reach.
  // One item per row of cluster tiles, lights ascending: it alone writes that row's lists.
  const auto rects = light_rects(ctx);
  const auto spheres = view_spheres(ctx);
  const auto row_lights = lights_by_tile_row(rects, tile_px, grid->tiles_y);
  const auto& lights = ctx.trace->lights;
  std::vector<std::pair<int, int>> light_slices(lights.size());  // first and last slice each light reaches
  for (std::uint32_t l = 0; l < lights.size(); ++l) {
    const float dist = ctx.frustum->distance_of(lights[l].position);
    light_slices[l] = {grid->slice_of(std::max(0.0f, dist - lights[l].radius)), grid->slice_of(dist + lights[l].radius)};
  }
  std::vector<std::pair<float, float>> slice_ranges(static_cast<std::size_t>(grid->slices));
  for (int s = 0; s < grid->slices; ++s) grid->slice_range(s, slice_ranges[static_cast<std::size_t>(s)].first, slice_ranges[static_cast<std::size_t>(s)].second);
  run_items(ctx, static_cast<std::size_t>(grid->tiles_y), [&](std::size_t row, unsigned /*worker*/) {
    const int ty = static_cast<int>(row);
    std::vector<TileSides> sides(static_cast<std::size_t>(grid->tiles_x));
    for (int tx = 0; tx < grid->tiles_x; ++tx) {
      sides[static_cast<std::size_t>(tx)] =
          TileSides::of(*ctx.frustum, intersect({tx * tile_px, ty * tile_px, (tx + 1) * tile_px, (ty + 1) * tile_px}, {0, 0, W, H}));
    }
    for (std::uint32_t l : row_lights[row]) {
      const PixelRect& lr = rects[l];
      for (int s = light_slices[l].first; s <= light_slices[l].second; ++s) {
        const auto [d0, d1] = slice_ranges[static_cast<std::size_t>(s)];
        for (int tx = lr.x0 / tile_px; tx <= (lr.x1 - 1) / tile_px; ++tx) {
          const std::size_t c = grid->index(tx, ty, s);
          if (!grid->used[c]) continue;
          if (sides[static_cast<std::size_t>(tx)].touches(spheres[l], d0, d1)) grid->lists[c].push_back(l);
        }
      }
    }
  });
  const std::uint64_t processed = grid->used_count();
  stats.light_volume_tests += processed * n_lights;
  stats.compute_alu_ops += processed * n_lights * kSphereVolumeTestOps;
  stats.light_list_entries += grid->total_entries();
  const std::string gname = k.buffer_with(cmd.writes, BufferContent::ClusterGrid);
  const std::string lname = k.buffer_with(cmd.writes, BufferContent::LightIndexList);
  if (gname.empty() || lname.empty()) k.fail("needs a cluster_grid and a light_index_list buffer in writes=");
  k.charge_write(gname, clusters * kTileGridEntryBytes);
  k.charge_write(lname, grid->total_entries() * kLightIndexBytes);
  ctx.images->cluster_grids[gname] = grid;
}

/// deferred_shade and vbuffer_shade (`vbuffer`): every stored surface shaded from the lights its
/// shader reads.
void run_surface_shade(KernelRun& r, bool vbuffer) {
  Dispatch& k = r.k;
  const ComputeContext& ctx = r.ctx;
  const DispatchCmd& cmd = r.cmd;
  ComputeStats& stats = r.stats;
  [[maybe_unused]] DramTraffic& dram = r.dram;
  [[maybe_unused]] const int W = r.W, H = r.H;
  [[maybe_unused]] const std::uint64_t pixels = r.pixels, n_lights = r.n_lights;
  k.allow({"shader", "tile_px"});
  const ShaderDesc& sh = k.shader();
  const AttachmentImage* surfaces = k.read_surfaces();
  if (!surfaces) k.fail("needs a G-buffer or visibility image (written by a pass) in reads=");
  const std::string out = k.buffer_with(cmd.writes, BufferContent::Image);
  if (out.empty()) k.fail("needs an image buffer in writes=");
  const TileLightGrid* tgrid = nullptr;
  const ClusterGrid* cgrid = nullptr;
  if (sh.light_source == LightSource::TileList) {
    const std::string g = k.buffer_with(cmd.reads, BufferContent::TileGrid);
    auto it = ctx.images->tile_grids.find(g);
    if (g.empty() || it == ctx.images->tile_grids.end()) k.fail("light_source=tile_list needs a tile_grid written by tile_light_cull in reads=");
    tgrid = it->second.get();
  } else if (sh.light_source == LightSource::ClusterList) {
    const std::string g = k.buffer_with(cmd.reads, BufferContent::ClusterGrid);
    auto it = ctx.images->cluster_grids.find(g);
    if (g.empty() || it == ctx.images->cluster_grids.end()) k.fail("light_source=cluster_list needs a cluster_grid written by cluster_light_assign in reads=");
    cgrid = it->second.get();
  } else if (sh.light_source != LightSource::All) {
    k.fail(std::string("light_source '") + to_string(sh.light_source) + "' cannot be used by a compute kernel");
  }
  const int tile_px = k.get_int("tile_px", kDefaultTilePx, 1, 1024);
  ImageBuffer img = shade_surfaces(ctx, *surfaces, sh, tgrid, cgrid, vbuffer ? tile_px : 0, stats, dram);
  material_texture_lines(ctx, *surfaces, k.material_fetches(sh), tile_px, stats, dram);
  r.write_image(out, std::move(img));
}

/// vbuffer_worklists: one entry per distinct (tile, material).
void run_vbuffer_worklists(KernelRun& r) {
  Dispatch& k = r.k;
  const ComputeContext& ctx = r.ctx;
  const DispatchCmd& cmd = r.cmd;
  ComputeStats& stats = r.stats;
  [[maybe_unused]] DramTraffic& dram = r.dram;
  [[maybe_unused]] const int W = r.W, H = r.H;
  [[maybe_unused]] const std::uint64_t pixels = r.pixels, n_lights = r.n_lights;
  k.allow({"tile_px"});
  const int tile_px = k.get_int("tile_px", kDefaultTilePx, 1, 1024);
  const AttachmentImage* vis = k.read_surfaces();
  if (!vis) k.fail("needs a visibility image (written by a pass) in reads=");
  const std::string out = k.buffer_with(cmd.writes, BufferContent::WorkLists);
  if (out.empty()) k.fail("needs a work_lists buffer in writes=");
  // One entry per distinct (tile, material). One item per row of tiles, counting its own tiles'
  // pairs; the rows' counts add up to the frame's.
  const int rows = (H + tile_px - 1) / tile_px;
  const std::uint64_t tiles_x = static_cast<std::uint64_t>((W + tile_px - 1) / tile_px);
  std::vector<std::uint64_t> row_entries(static_cast<std::size_t>(rows), 0);
  run_items(ctx, row_entries.size(), [&](std::size_t row, unsigned /*worker*/) {
    std::vector<std::uint64_t> pairs;  // (tile << 32) | material, a run of equal pairs once
    const int y_end = std::min(H, (static_cast<int>(row) + 1) * tile_px);
    for (int y = static_cast<int>(row) * tile_px; y < y_end; ++y) {
      for (int x = 0; x < W; ++x) {
        const std::size_t p = static_cast<std::size_t>(y) * W + static_cast<std::size_t>(x);
        if (!vis->surface_valid[p * vis->samples]) continue;
        const std::uint64_t key = ((static_cast<std::uint64_t>(row) * tiles_x + static_cast<std::uint64_t>(x / tile_px)) << 32) |
                                  vis->surface[p * vis->samples].material;
        if (pairs.empty() || pairs.back() != key) pairs.push_back(key);
      }
    }
    std::sort(pairs.begin(), pairs.end());
    row_entries[row] = static_cast<std::uint64_t>(std::unique(pairs.begin(), pairs.end()) - pairs.begin());
  });
  std::uint64_t entries = 0;
  for (std::uint64_t e : row_entries) entries += e;
  stats.compute_alu_ops += pixels * kWorkListOps;
  stats.work_list_entries += entries;
  k.charge_write(out, entries * kWorkListEntryBytes);
}

/// The kernels: each ComputeKernel and the function that runs it (the flag says which of a pair).
/// transfer and captured_compute (`alu`): work an application recorded that the simulator knows by
/// its memory traffic and cost, not by what it computes. Reads its `reads=` buffers (each once, at
/// the bytes declared or last written) and writes its `writes=` buffers whole. captured_compute
/// adds `alu_ops` ALU operations and `tex_fetches` texture fetches per thread (a compute shader's
/// static SPIR-V count); transfer has none: a blit, copy, resolve, clear or fill is a stream of
/// memory reads and writes (the transfer path's filtering is not costed).
void run_recorded(KernelRun& r, bool alu) {
  Dispatch& k = r.k;
  if (alu) {
    k.allow({"alu_ops", "tex_fetches"});
    const std::uint64_t threads = r.cmd.group_count() * r.cmd.group_size[0] * r.cmd.group_size[1] * r.cmd.group_size[2];
    r.stats.compute_alu_ops += threads * static_cast<std::uint64_t>(k.get_int("alu_ops", 0, 0, 1 << 20));
    r.stats.compute_texture_fetches += threads * static_cast<std::uint64_t>(k.get_int("tex_fetches", 0, 0, 1 << 16));
  } else {
    k.allow({});
  }
  for (const auto& n : r.cmd.writes) {
    const BufferDesc* b = r.ctx.trace->find_buffer(n);
    if (!b) k.fail("writes '" + n + "', which is not a declared buffer");
    k.charge_write(n, b->bytes);
  }
}

struct KernelDesc {
  ComputeKernel kernel;
  void (*run)(KernelRun&, bool);
  bool flag = false;
};
const KernelDesc kKernels[] = {
    {ComputeKernel::DepthBounds, [](KernelRun& r, bool) { run_depth_bounds(r); }},
    {ComputeKernel::TileLightCull, run_tile_light_cull, false},
    {ComputeKernel::TiledDeferredShade, run_tile_light_cull, true},
    {ComputeKernel::ClusterFlag, run_clusters, false},
    {ComputeKernel::ClusterLightAssign, run_clusters, true},
    {ComputeKernel::DeferredShade, run_surface_shade, false},
    {ComputeKernel::VbufferShade, run_surface_shade, true},
    {ComputeKernel::VbufferWorklists, [](KernelRun& r, bool) { run_vbuffer_worklists(r); }},
    {ComputeKernel::Transfer, run_recorded, false},
    {ComputeKernel::CapturedCompute, run_recorded, true},
};

}  // namespace

void run_dispatch(const ComputeContext& ctx, const DispatchCmd& cmd, ComputeStats& stats, DramTraffic& dram,
                  std::string& image_written) {
  Dispatch k(ctx, cmd, stats, dram);
  const int W = ctx.viewport.width_px, H = ctx.viewport.height_px;
  ++stats.dispatches;
  stats.workgroups += cmd.group_count();
  stats.threads += cmd.group_count() * cmd.group_size[0] * cmd.group_size[1] * cmd.group_size[2];
  k.charge_reads();
  KernelRun r{k, ctx, cmd, stats, dram, image_written, W, H,
              static_cast<std::uint64_t>(W) * static_cast<std::uint64_t>(H), static_cast<std::uint64_t>(ctx.trace->lights.size())};
  for (const KernelDesc& d : kKernels) {
    if (d.kernel == cmd.kernel) return d.run(r, d.flag);
  }
  k.fail(std::string("kernel '") + to_string(cmd.kernel) + "' is not implemented");
}

}  // namespace tbdr
