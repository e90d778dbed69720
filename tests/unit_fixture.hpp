#pragma once
// The one place where the unit tests (tests/test_unit_*.cpp) build hardware units and the
// contexts they read. The tests drive the units through these rigs and read the units' typed
// statistics; when a unit's constructor or RenderContext changes, only this header follows.
//
// Conventions of the rigs:
// - A 64x64 viewport with 8 sub-pixel bits and the default 32x32 tiles: a 2x2 tile grid.
// - Screen triangles are given in pixel coordinates, y down (pixel (0,0) top-left), exactly as the
//   geometry unit hands them to the tiler and the ISP; no camera is involved.
// - Hardware parameters come from the defaults plus `--set`-style overrides ("isp.tag_buffers=1").
#include <array>
#include <cmath>
#include <cstdint>
#include <deque>
#include <initializer_list>
#include <map>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <type_traits>
#include <utility>
#include <vector>

#include <glm/glm.hpp>
#include <gtest/gtest.h>

#include "models/compute_unit.hpp"
#include "models/frame_work.hpp"
#include "models/geometry_unit.hpp"
#include "models/hw_config.hpp"
#include "models/isp.hpp"
#include "models/light_lists.hpp"
#include "models/rasterizer.hpp"
#include "models/render_state.hpp"
#include "models/tile_memory.hpp"
#include "models/tiler.hpp"
#include "models/timing_model.hpp"
#include "trace/traffic.hpp"
#include "models/tsp.hpp"
#include "trace/trace.hpp"
#include "scene/camera.hpp"
#include "scene/lights.hpp"
#include "scene/scene.hpp"

namespace tbdr::unit {

/// One expected value of a counter of the statistics set `S` (expect_counters).
template <class S>
struct CounterIs {
  Counter S::*counter;
  std::uint64_t value;
};
/// Expects every listed counter of `stats` to hold its value; a failure names the entry's position.
template <class S>
void expect_counters(const S& stats, std::initializer_list<CounterIs<std::type_identity_t<S>>> expected) {
  std::size_t i = 0;
  for (const auto& e : expected) EXPECT_EQ((stats.*e.counter).value(), e.value) << "expected counter #" << i++;
}

inline constexpr int kViewportPx = 64;  ///< the rigs' default viewport: 64x64 pixels
inline constexpr int kTilePx = 32;      ///< the default tile size (tiling.tile_width/height)

/// The default hardware with `--set` overrides applied.
inline HwConfig make_hw(const std::vector<std::string>& sets = {}) { return resolve_config({}, sets).hw; }

inline Viewport make_viewport(int width = kViewportPx, int height = kViewportPx, int subpixel_bits = 8) {
  Viewport v;
  v.width_px = width;
  v.height_px = height;
  v.subpixel_bits = subpixel_bits;
  return v;
}

/// A triangle in pixel coordinates (y down), as the geometry unit hands it over.
struct ScreenTri {
  glm::vec2 v0{0.0f}, v1{0.0f}, v2{0.0f};
  float z = 0.5f;  ///< window depth of all three vertices
  HsrClass hsr = HsrClass::Opaque;
  std::uint32_t draw = 0;
  std::uint32_t material = kNoMaterial;  ///< kNoMaterial: no surface, no alpha test
  std::uint32_t varyings = 0;            ///< 32-bit varyings per vertex in the parameter buffer
  /// Vertex identities for primitive-block re-use; all zero = three vertices of its own.
  std::array<std::uint64_t, 3> keys{};
  std::array<glm::vec2, 3> uv{};
};

/// The primitive the geometry unit would emit for `t` (serial: makes default vertex keys unique).
inline Primitive make_primitive(const ScreenTri& t, const Viewport& vp, std::uint64_t serial) {
  const double scale = static_cast<double>(vp.subpixel_scale());
  ScreenTriangle st;
  const glm::vec2 v[3] = {t.v0, t.v1, t.v2};
  for (int i = 0; i < 3; ++i) {
    st.x_fixed[static_cast<std::size_t>(i)] = static_cast<std::int32_t>(std::llround(static_cast<double>(v[i].x) * scale));
    st.y_fixed[static_cast<std::size_t>(i)] = static_cast<std::int32_t>(std::llround(static_cast<double>(v[i].y) * scale));
    st.z[static_cast<std::size_t>(i)] = t.z;
    st.inv_w[static_cast<std::size_t>(i)] = 1.0f;
  }
  Primitive p;
  p.setup = setup_triangle(st, vp);
  p.draw = t.draw;
  p.material = t.material;
  p.hsr = t.hsr;
  p.varyings = t.varyings;
  p.uv = t.uv;
  for (int i = 0; i < 3; ++i) {
    const auto k = static_cast<std::size_t>(i);
    p.world[k] = glm::vec3(v[i].x, -v[i].y, -1.0f);
    p.normal[k] = glm::vec3(0.0f, 0.0f, 1.0f);
  }
  p.id = static_cast<std::uint32_t>(serial);
  return p;
}

/// The vertex identities of make_primitive(t, vp, serial): the triangle's keys, or three keys of
/// its own when it gives none.
inline VertexKeys make_vertex_keys(const ScreenTri& t, std::uint64_t serial) {
  const bool auto_keys = t.keys[0] == 0 && t.keys[1] == 0 && t.keys[2] == 0;
  VertexKeys keys;
  for (std::size_t i = 0; i < 3; ++i) keys[i] = auto_keys ? (std::uint64_t{1} << 62) | (serial * 3 + i) : t.keys[i];
  return keys;
}

/// A shader with the given costs (1 color output unless told otherwise).
inline ShaderDesc make_shader(std::uint32_t alu_ops, std::uint32_t light_alu_ops = 0, LightSource source = LightSource::None,
                              std::uint32_t color_outputs = 1, std::uint32_t tex_fetches = 0) {
  ShaderDesc s;
  s.name = "unit_shader";
  s.alu_ops = alu_ops;
  s.light_alu_ops = light_alu_ops;
  s.light_source = source;
  s.color_outputs = color_outputs;
  s.tex_fetches = tex_fetches;
  return s;
}

/// An attachment of a pass.
inline Attachment make_attachment(const std::string& name, Format format, LoadOp load = LoadOp::Clear,
                                  StoreOp store = StoreOp::Store, bool transient = false, std::uint32_t samples = 1,
                                  AttachmentUsage usage = AttachmentUsage::Color) {
  Attachment a;
  a.name = name;
  a.format = format;
  a.load = load;
  a.store = store;
  a.transient = transient;
  a.samples = samples;
  a.usage = is_depth_format(format) ? AttachmentUsage::Depth : usage;
  return a;
}

/// The usual forward pass: an rgba8 color target cleared and stored, a transient d24s8 depth
/// buffer cleared and never stored.
inline std::vector<Attachment> default_attachments(std::uint32_t samples = 1) {
  return {make_attachment("color", Format::Rgba8, LoadOp::Clear, StoreOp::Store, false, samples),
          make_attachment("depth", Format::D24s8, LoadOp::Clear, StoreOp::DontCare, true, samples)};
}

/// Candidate lights per screen bin (an exact acceleration of the images only, never of a count):
/// every light in every bin.
inline LightScreenBins every_light_everywhere(std::size_t lights, int width, int height) {
  LightScreenBins b;
  b.bins_x = (width + LightScreenBins::kBinPx - 1) / LightScreenBins::kBinPx;
  const int bins_y = (height + LightScreenBins::kBinPx - 1) / LightScreenBins::kBinPx;
  std::vector<std::uint32_t> all;
  for (std::uint32_t l = 0; l < lights; ++l) all.push_back(l);
  b.bins.assign(static_cast<std::size_t>(b.bins_x) * static_cast<std::size_t>(bins_y), all);
  return b;
}

/// The draws a rig has run: their commands, shaders and pipelines kept at stable addresses, and
/// the DrawContext the command processor would give the units for each.
class DrawStore {
 public:
  /// Stores one draw; returns its context selecting `selected_lights` among `light_count` lights.
  DrawContext add(const DrawCmd& cmd, const ShaderDesc& shader, const PipelineState& pipeline,
                  const std::vector<std::uint32_t>& selected_lights, std::size_t light_count) {
    cmds_.push_back(cmd);
    shaders_.push_back(shader);
    pipelines_.push_back(pipeline);
    DrawContext d;
    d.cmd = &cmds_.back();
    d.shader = &shaders_.back();
    d.pipeline = &pipelines_.back();
    d.lights = selected_lights;
    d.light_selected.assign(light_count, 0);
    for (std::uint32_t l : selected_lights) d.light_selected[l] = 1;
    return d;
  }

 private:
  std::deque<DrawCmd> cmds_;
  std::deque<ShaderDesc> shaders_;
  std::deque<PipelineState> pipelines_;
};

/// What a render rig holds: the hardware, the pass, the lights.
struct RenderSpec {
  std::vector<std::string> sets{};  ///< hardware overrides
  int width = kViewportPx;
  int height = kViewportPx;
  std::vector<Attachment> attachments = default_attachments();
  std::vector<PlsVariable> pls{};
  std::vector<Light> lights{};
};

/// The fragment side of one render pass: ISP, TSP and tile memory on one RenderContext, with the
/// frame images they read and write. Scene material 0 is opaque; material 1 is punch-through
/// with a 2x1 alpha mask whose left half (u < 0.5) is transparent (cutoff 0.5).
class RenderRig {
 public:
  explicit RenderRig(RenderSpec spec = {}) : hw(make_hw(spec.sets)), lights(std::move(spec.lights)) {
    Material opaque;
    opaque.name = "opaque";
    Material masked;
    masked.name = "masked";
    masked.alpha_mode = AlphaMode::PunchThrough;
    masked.alpha_cutoff = 0.5f;
    masked.alpha_mask = 0;
    scene.materials = {opaque, masked};
    scene.alpha_masks.push_back(AlphaMask{2, 1, {0, 255}});

    pass.name = "unit_pass";
    pass.attachments = std::move(spec.attachments);
    pass.pls = std::move(spec.pls);

    ctx_.hw = &hw;
    ctx_.scene = &scene;
    ctx_.lights = &lights;
    ctx_.viewport = make_viewport(spec.width, spec.height, static_cast<int>(hw.geometry.subpixel_bits));
    ctx_.pass = &pass;
    ctx_.images = &images;
    ctx_.defer_shading = hw.gpu.mode == GpuMode::Tbdr;
    ctx_.framebuffer_in_dram = hw.gpu.mode == GpuMode::Imr;
    ctx_.dram = &dram;
    ctx_.texture_lines = &texture_lines;

    // Attachment images as the command processor prepares them (depth 1.0, stencil 0, color 0).
    const std::size_t pixels = static_cast<std::size_t>(spec.width) * static_cast<std::size_t>(spec.height);
    images.width = spec.width;
    images.height = spec.height;
    images.counters.resize(pixels);
    int samples = -1;
    for (const auto& a : pass.attachments) {
      images.attachments.emplace(a.name, AttachmentImage::cleared(a, pixels, true));
      bool resolve_target = false;
      for (const auto& o : pass.attachments) resolve_target = resolve_target || o.resolve == a.name;
      if (!resolve_target && samples < 0) samples = static_cast<int>(a.samples);
    }
    ctx_.pattern = standard_sample_pattern(samples < 0 ? 1 : samples, ctx_.viewport.subpixel_bits);
    for (const Attachment* a : pass.color_targets()) ctx_.color_targets.push_back(&images.attachments.at(a->name));
    if (const Attachment* d = pass.depth_attachment()) ctx_.depth = &images.attachments.at(d->name);
    light_bins_ = every_light_everywhere(lights.size(), spec.width, spec.height);
    ctx_.light_bins = &light_bins_;

    tile_memory_ = std::make_unique<TileMemory>(ctx_, tm_stats);
    tsp_ = std::make_unique<Tsp>(ctx_);
    isp_ = std::make_unique<Isp>(ctx_, *tsp_);
  }
  RenderRig(const RenderRig&) = delete;
  RenderRig& operator=(const RenderRig&) = delete;

  /// Adds a draw of the pass; returns its index (ScreenTri::draw).
  std::uint32_t add_draw(const ShaderDesc& shader, const PipelineState& pipeline = {},
                         const std::vector<std::uint32_t>& selected_lights = {},
                         std::vector<std::pair<DramClass, std::uint32_t>> per_pixel_reads = {}) {
    DrawContext d = draws_.add(DrawCmd{}, shader, pipeline, selected_lights, lights.size());
    d.per_pixel_reads = std::move(per_pixel_reads);
    d.pass_draw_index = static_cast<std::uint32_t>(ctx_.draws.size());
    ctx_.draws.push_back(std::move(d));
    return static_cast<std::uint32_t>(ctx_.draws.size() - 1);
  }
  /// Adds a primitive to the render (what the parameter buffer holds); returns its index.
  std::uint32_t add_triangle(const ScreenTri& t) {
    ctx_.prims.push_back(make_primitive(t, ctx_.viewport, ctx_.prims.size()));
    return static_cast<std::uint32_t>(ctx_.prims.size() - 1);
  }
  /// The pixel rectangle of tile (tx, ty) of the default 32x32 grid.
  static PixelRect tile_rect(int tx, int ty) { return {tx * kTilePx, ty * kTilePx, (tx + 1) * kTilePx, (ty + 1) * kTilePx}; }

  /// The ISP renders `rect` with the given primitives (all of the render's, in order, by default).
  void render_tile(const PixelRect& rect, std::vector<std::uint32_t> prims = {}) {
    if (prims.empty()) {
      for (std::uint32_t i = 0; i < ctx_.prims.size(); ++i) prims.push_back(i);
    }
    isp_->render_tile(rect, prims, isp_stats, tsp_stats);
  }
  /// The set-up of most ISP and TSP tests: one draw of a 1-op shader, the triangles `tris` (in
  /// order), tile (0, 0) rendered. Returns the triangles' primitive indices.
  std::vector<std::uint32_t> render_one_draw(std::initializer_list<ScreenTri> tris) {
    add_draw(make_shader(1));
    std::vector<std::uint32_t> ids;
    for (const ScreenTri& t : tris) ids.push_back(add_triangle(t));
    render_tile(tile_rect(0, 0));
    return ids;
  }
  /// Gives the pass a lit-sample ledger (LitSampleLedger), as the tile memory does for a pass
  /// whose draws light colour: the TSP counts hidden_lit_samples from then on.
  void keep_lit_sample_ledger() {
    ledger_ = std::make_unique<LitSampleLedger>(ctx_.viewport.width_px, ctx_.viewport.height_px, ctx_.pattern.count);
    ctx_.lit_samples = ledger_.get();
  }
  /// The TSP shades `pixels` of primitive `prim` (one batch, sorted by row then column).
  void shade(std::uint32_t prim, const std::vector<ShadePixel>& pixels, std::vector<std::uint32_t>* alive = nullptr) {
    tsp_->shade(prim, pixels, alive, tsp_stats);
  }

  // Tile memory of the pass.
  std::uint32_t need_bytes_per_pixel() const { return tile_memory_->need_bytes_per_pixel(); }
  std::uint32_t budget_bytes_per_pixel() const { return tile_memory_->budget_bytes_per_pixel(); }
  std::vector<PixelRect> strips(const PixelRect& tile) const { return tile_memory_->strips(tile); }
  void begin_tile(const PixelRect& rect, bool resumed_after_partial = false) { tile_memory_->begin_tile(rect, resumed_after_partial, dram, tm_stats); }
  void end_tile(const PixelRect& rect, bool partial = false) { tile_memory_->end_tile(rect, partial, dram, tm_stats); }
  void spill(std::uint64_t tile_buffer_read_bytes, std::uint64_t tile_buffer_write_bytes) {
    tile_memory_->spill(tile_buffer_read_bytes, tile_buffer_write_bytes, dram, tm_stats);
  }
  double spill_fraction() const { return tile_memory_->spill_fraction(); }

  /// Depth stored at sample `s` of pixel (x, y) of the pass's depth attachment.
  float depth_at(int x, int y, int s = 0) const {
    return ctx_.depth->depth[(static_cast<std::size_t>(y) * static_cast<std::size_t>(ctx_.viewport.width_px) +
                              static_cast<std::size_t>(x)) * ctx_.depth->samples + static_cast<std::size_t>(s)];
  }
  int samples_per_pixel() const { return ctx_.pattern.count; }

  HwConfig hw;
  Scene scene;
  std::vector<Light> lights;
  PassDesc pass;
  FrameImages images;
  DramTraffic dram;                          ///< what the units booked to DRAM
  std::vector<std::uint64_t> texture_lines;  ///< the tile's texture lines (TSP)
  IspStats isp_stats;
  TspStats tsp_stats;
  TileMemoryStats tm_stats;

 private:
  DrawStore draws_;
  LightScreenBins light_bins_;
  RenderContext ctx_;
  std::unique_ptr<TileMemory> tile_memory_;
  std::unique_ptr<LitSampleLedger> ledger_;
  std::unique_ptr<Tsp> tsp_;
  std::unique_ptr<Isp> isp_;
};

/// The tiler and its parameter buffer for one viewport.
class TilerRig {
 public:
  explicit TilerRig(const std::vector<std::string>& sets = {}, int width = kViewportPx, int height = kViewportPx)
      : hw(make_hw(sets)), viewport(make_viewport(width, height, static_cast<int>(hw.geometry.subpixel_bits))),
        pattern(standard_sample_pattern(1, viewport.subpixel_bits)) {
    tiler_ = std::make_unique<Tiler>(hw, viewport, pattern);
  }
  TilerRig(const TilerRig&) = delete;
  TilerRig& operator=(const TilerRig&) = delete;

  /// Bins the triangle as the next primitive of the render; false when the parameter buffer is
  /// full (nothing binned: a partial render is due). `tiles_listed_ahead`: its tiles looked up
  /// first (Tiler::touched_tiles, as the geometry unit's set-up threads do) and handed to bin().
  bool bin(const ScreenTri& t, bool tiles_listed_ahead = false) {
    const Primitive p = make_primitive(t, viewport, serial_);
    const VertexKeys keys = make_vertex_keys(t, serial_++);
    const auto index = static_cast<std::uint32_t>(binned_);
    std::vector<int> tiles;
    if (tiles_listed_ahead) tiler_->touched_tiles(p, tiles);
    const bool ok = tiler_->bin(index, p, keys, stats,
                                tiles_listed_ahead ? std::optional<std::span<const int>>(tiles) : std::nullopt) != BinResult::Full;
    if (ok) ++binned_;
    return ok;
  }
  /// Closes the render: books the parameter buffer writes into `dram`.
  void finish_render() { tiler_->finish_render(stats, dram); }
  /// Frees the parameter buffer (after a render).
  void reset() {
    tiler_->reset();
    binned_ = 0;
  }
  Tiler& tiler() { return *tiler_; }
  /// Tile index of (tx, ty).
  int tile(int tx, int ty) const { return ty * tiler_->tiles_x() + tx; }

  HwConfig hw;
  Viewport viewport;
  SamplePattern pattern;
  TilerStats stats;
  DramTraffic dram;

 private:
  std::unique_ptr<Tiler> tiler_;
  std::uint64_t serial_ = 0;
  std::uint64_t binned_ = 0;
};

/// A sub-mesh of the given object-space triangles (normals +z, uvs 0), indexed as given.
inline SubMesh make_mesh(const std::string& name, std::vector<glm::vec3> positions, std::vector<std::uint32_t> indices,
                         std::uint32_t material = 0, std::uint32_t index_bytes = 2, std::uint32_t vertex_stride_bytes = 32) {
  SubMesh m;
  m.name = name;
  m.material = material;
  m.normals.assign(positions.size(), glm::vec3(0.0f, 0.0f, 1.0f));
  m.uvs.assign(positions.size(), glm::vec2(0.0f));
  m.positions = std::move(positions);
  m.indices = std::move(indices);
  m.index_bytes = index_bytes;
  m.vertex_stride_bytes = vertex_stride_bytes;
  return m;
}

/// What a geometry rig holds. The default camera is the identity (view = projection = I): a world
/// position IS its clip-space position with w = 1, so NDC = (x, y, z) and the visible volume is
/// the cube [-1, 1]^3; pixel column = (x + 1) * 32, row = (1 - y) * 32 on the 64x64 viewport.
struct GeometrySpec {
  std::vector<std::string> sets{};
  int width = kViewportPx;
  int height = kViewportPx;
  Scene scene{};                   ///< a default material is added when it has none
  std::vector<Light> lights{};
  CameraXform camera{};            ///< identity by default
};

/// The geometry unit on a scene, with the draws' statistics and emitted primitives.
class GeometryRig {
 public:
  explicit GeometryRig(GeometrySpec spec)
      : hw(make_hw(spec.sets)), scene(std::move(spec.scene)), lights(std::move(spec.lights)), camera(spec.camera),
        viewport(make_viewport(spec.width, spec.height, static_cast<int>(hw.geometry.subpixel_bits))) {
    if (scene.materials.empty()) scene.materials.push_back(Material{});
    unit_ = std::make_unique<GeometryUnit>(hw, &scene, lights, camera, viewport);
  }
  GeometryRig(const GeometryRig&) = delete;
  GeometryRig& operator=(const GeometryRig&) = delete;

  /// Runs one draw through the geometry unit (primitives appended to `prims`, their vertex
  /// identities to `out.keys`).
  void run(const DrawCmd& cmd, const ShaderDesc& shader = make_shader(1), const PipelineState& pipeline = {},
           const std::vector<std::uint32_t>& selected_lights = {}) {
    const DrawContext d = store_.add(cmd, shader, pipeline, selected_lights, lights.size());
    unit_->run_draw(d, draws_++, out, object_lights, stats, dram);
  }

  HwConfig hw;
  Scene scene;
  std::vector<Light> lights;
  CameraXform camera;
  Viewport viewport;
  GeometryStats stats;
  DramTraffic dram;
  PrimitiveList out;
  std::vector<Primitive>& prims = out.prims;
  std::vector<std::vector<std::uint32_t>> object_lights;

 private:
  DrawStore store_;
  std::unique_ptr<GeometryUnit> unit_;
  std::uint32_t draws_ = 0;
};

/// The camera of the compute rig: at the origin looking down -z, 60 degree vertical field of
/// view, near 0.5, far 50 (square frame: 60 degrees horizontally too).
inline Camera compute_camera() {
  Camera c;
  c.eye = {0, 0, 0};
  c.target = {0, 0, -1};
  c.up = {0, 1, 0};
  c.fov_y_deg = 60;
  c.near_plane = 0.5f;
  c.far_plane = 50;
  return c;
}

/// The world position at view distance `d` that projects to pixel position (px, py) (y down) for
/// compute_camera() on a width x height frame.
inline glm::vec3 world_at_pixel(float px, float py, float d, int width = kViewportPx, int height = kViewportPx) {
  const float t = std::tan(glm::radians(compute_camera().fov_y_deg) * 0.5f);
  const float w = static_cast<float>(width), h = static_cast<float>(height);
  return {(2.0f * px / w - 1.0f) * d * t * (w / h), (1.0f - 2.0f * py / h) * d * t, -d};
}

/// A light at `position` (world) of radius `radius`, default otherwise.
inline Light light_at(const glm::vec3& position, float radius) {
  Light l;
  l.position = position;
  l.radius = radius;
  return l;
}

/// What a compute rig holds: the trace's lights, buffers and shaders.
struct ComputeSpec {
  std::vector<std::string> sets{};
  int width = kViewportPx;
  int height = kViewportPx;
  Camera camera = compute_camera();
  std::vector<Light> lights{};
  std::vector<BufferDesc> buffers{};
  std::vector<ShaderDesc> shaders{};
};

/// A buffer declaration of the trace.
inline BufferDesc make_buffer(const std::string& name, BufferContent content, DramClass traffic, std::uint64_t bytes = 0) {
  return BufferDesc{.name = name, .bytes = bytes, .traffic = traffic, .content = content};
}

/// Compute dispatches on the frame's images.
class ComputeRig {
 public:
  explicit ComputeRig(ComputeSpec spec)
      : hw(make_hw(spec.sets)), camera_desc(spec.camera),
        camera(CameraXform::from(spec.camera, static_cast<float>(spec.width) / static_cast<float>(spec.height))),
        frustum(ViewFrustum::from(spec.camera, spec.width, spec.height)),
        viewport(make_viewport(spec.width, spec.height, static_cast<int>(hw.geometry.subpixel_bits))) {
    trace.frame = {spec.width, spec.height, 1, 0};
    trace.camera = spec.camera;
    trace.lights = std::move(spec.lights);
    trace.buffers = std::move(spec.buffers);
    trace.shaders = std::move(spec.shaders);
    images.width = spec.width;
    images.height = spec.height;
    images.counters.resize(static_cast<std::size_t>(spec.width) * static_cast<std::size_t>(spec.height));
    light_bins_ = every_light_everywhere(trace.lights.size(), spec.width, spec.height);
  }
  ComputeRig(const ComputeRig&) = delete;
  ComputeRig& operator=(const ComputeRig&) = delete;

  /// A stored 1-sample depth image (window depths, width*height) the dispatches may read.
  void add_depth_image(const std::string& name, std::vector<float> depth) {
    AttachmentImage img;
    img.format = Format::D24s8;
    img.usage = AttachmentUsage::Depth;
    img.defined = true;
    img.sample_count = depth.size();
    img.stencil.assign(depth.size(), 0);
    img.depth = std::move(depth);
    images.attachments[name] = std::move(img);
  }
  /// A stored 1-sample rgba8 G-buffer whose pixels with valid[p] != 0 hold a surface (facing the
  /// camera at distance 5, each its own triangle).
  void add_gbuffer(const std::string& name, const std::vector<std::uint8_t>& valid) {
    AttachmentImage img;
    img.format = Format::Rgba8;
    img.usage = AttachmentUsage::Gbuffer;
    img.defined = true;
    img.sample_count = valid.size();
    img.color.assign(valid.size(), glm::vec4(0.0f));
    img.surface.assign(valid.size(), true);
    img.surface_valid = valid;
    for (std::size_t p = 0; p < valid.size(); ++p) {
      SurfacePoint s;
      s.position = glm::vec3(0.0f, 0.0f, -5.0f);
      s.normal = glm::vec3(0.0f, 0.0f, 1.0f);
      s.albedo = glm::vec3(0.5f);
      s.triangle = static_cast<std::uint32_t>(p);
      img.surface.set(p, s);
    }
    images.attachments[name] = std::move(img);
  }

  /// The context the rig's dispatches run in: its frame, trace and images; no texture address
  /// space (material fetches book no lines) unless the caller sets one.
  ComputeContext context() {
    ComputeContext cc;
    static_cast<FrameInputs&>(cc) = FrameInputs{.hw = &hw, .scene = &scene, .lights = &trace.lights, .camera = camera,
                                                .viewport = viewport, .frustum = &frustum, .light_bins = &light_bins_};
    cc.trace = &trace;
    cc.trace_path = &path_;
    cc.images = &images;
    return cc;
  }
  /// Runs one dispatch (throws InputError as the unit does).
  void dispatch(const DispatchCmd& cmd) { run_dispatch(context(), cmd, stats, dram, image_written); }
  /// The tile grid a culling dispatch wrote into buffer `name` (nullptr if none).
  const TileLightGrid* tile_grid(const std::string& name) const {
    auto it = images.tile_grids.find(name);
    return it == images.tile_grids.end() ? nullptr : it->second.get();
  }

  HwConfig hw;
  Camera camera_desc;
  CameraXform camera;
  ViewFrustum frustum;
  Viewport viewport;
  Trace trace;
  Scene scene;
  FrameImages images;
  ComputeStats stats;
  DramTraffic dram;
  std::string image_written;

 private:
  std::string path_ = "unit.trace";
  LightScreenBins light_bins_;
};

/// A dispatch command of `kernel` with its reads, writes and parameters.
inline DispatchCmd make_dispatch(const std::string& kernel, std::vector<std::string> reads, std::vector<std::string> writes,
                                 std::map<std::string, std::string> params = {}) {
  DispatchCmd d;
  d.kernel = parse_compute_kernel(kernel).value();
  d.reads = std::move(reads);
  d.writes = std::move(writes);
  d.params = std::move(params);
  return d;
}

// ---- the scheduler (timing model) on hand-made work ---------------------------------------------

/// One tile's measured work: no memory traffic unless the test adds it.
inline TileWork tile_work(int tx, int ty, std::uint64_t primitives, std::uint64_t samples, std::uint64_t alu_ops,
                          std::uint64_t texels = 0) {
  TileWork t;
  t.tile_x = tx;
  t.tile_y = ty;
  t.rect = {tx * kTilePx, ty * kTilePx, (tx + 1) * kTilePx, (ty + 1) * kTilePx};
  t.primitives = primitives;
  t.samples = samples;
  t.alu_ops = alu_ops;
  t.texels = texels;
  return t;
}
/// A render: its binning work and its tiles in dispatch order.
inline RenderWork render_work(std::vector<TileWork> tiles, BinningWork binning = {}, bool partial = false) {
  RenderWork r;
  r.tiles = std::move(tiles);
  r.binning = binning;
  r.partial = partial;
  return r;
}
/// Binning work of `primitives_in` primitives (nothing else, no memory traffic).
inline BinningWork binning_work(std::uint64_t primitives_in) {
  BinningWork b;
  b.primitives_in = primitives_in;
  return b;
}
/// A pass made of renders (several: partial renders).
/// Its framebuffer slots (final and partial renders') hold the most any of its tiles loads or
/// stores, its spill slot the most any tile spills.
inline CommandWork pass_work(const std::string& name, std::vector<RenderWork> renders) {
  CommandWork c;
  c.name = name;
  c.renders.assign(std::make_move_iterator(renders.begin()), std::make_move_iterator(renders.end()));
  c.tile_slots = (kViewportPx / kTilePx) * (kViewportPx / kTilePx);
  for (const RenderWork& r : c.renders) {
    for (const TileWork& t : r.tiles) {
      std::uint64_t load = 0, store = 0;
      for (std::size_t k = 0; k < kDramClassCount; ++k) {
        load += t.load_bytes[k];
        store += t.store_bytes[k];
      }
      c.tile_slot_bytes = std::max({c.tile_slot_bytes, load, store});
      c.partial_slot_bytes = c.tile_slot_bytes;
      c.spill_slot_bytes = std::max({c.spill_slot_bytes, t.spill_read_bytes, t.spill_write_bytes});
    }
  }
  return c;
}
/// A dispatch of `alu_ops` ALU operations and `texels` texels (no memory traffic).
inline CommandWork dispatch_work(const std::string& name, std::uint64_t alu_ops, std::uint64_t texels = 0) {
  CommandWork c;
  c.name = name;
  c.is_dispatch = true;
  c.compute_alu_ops = alu_ops;
  c.compute_texels = texels;
  return c;
}
/// A 64x64 frame of 32x32 tiles made of `commands`.
inline FrameWork frame_work(std::vector<CommandWork> commands) {
  FrameWork f;
  f.width = kViewportPx;
  f.height = kViewportPx;
  f.tile_width = kTilePx;
  f.tile_height = kTilePx;
  f.tiles_x = kViewportPx / kTilePx;
  f.commands = std::move(commands);
  return f;
}
/// Schedules `work` on the hardware with `sets` applied.
inline TimingResult run_schedule(const FrameWork& work, const std::vector<std::string>& sets = {}) {
  return run_timing(make_hw(sets), work);
}

}  // namespace tbdr::unit
