#pragma once
// State shared by the units of one render: the resolved draws, the primitives the geometry unit
// produced (what the parameter buffer holds), and the frame's attachment images. Each unit owns
// its own logic; these are the data that flow between them.
#include <cstdint>
#include <cstring>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include <glm/glm.hpp>

#include "models/hw_config.hpp"
#include "models/rasterizer.hpp"
#include "models/shading.hpp"
#include "trace/traffic.hpp"
#include "trace/trace.hpp"
#include "scene/camera.hpp"
#include "scene/scene.hpp"

namespace tbdr {

class TileSignatures;  // models/tile_signatures.hpp

struct TileLightGrid;
struct ClusterGrid;
struct DepthBounds;
struct ViewFrustum;
struct AttachmentImage;
class TextureLayout;
class RenderOutputUnit;
class LitSampleLedger;

/// The camera as the units use it: matrices and the eye position.
struct CameraXform {
  glm::mat4 view{1.0f};
  glm::mat4 proj{1.0f};
  glm::mat4 view_proj{1.0f};
  glm::vec3 eye{0.0f};
  float near_plane = 0.1f;
  static CameraXform from(const Camera& camera, float aspect);
};

/// How hidden-surface removal treats a primitive's fragments.
enum class HsrClass : std::uint8_t {
  Opaque,        ///< depth known at rasterisation: tags overwrite tags, shading deferred
  PunchThrough,  ///< alpha-tested / discard: shaded before its depth can be written
  Translucent,   ///< blended: what is beneath must be shaded first; never hides anything
};
const char* to_string(HsrClass c);

inline constexpr std::uint32_t kNoMaterial = std::numeric_limits<std::uint32_t>::max();

/// A draw resolved against the trace and the scene: what every unit needs to know about it.
struct DrawContext {
  const DrawCmd* cmd = nullptr;
  const AttachmentImage* surface_source = nullptr;  ///< generated geometry: where the pixel's surface is stored
  const TileLightGrid* tile_grid = nullptr;         ///< light_source=tile_list: the grid it reads
  const ClusterGrid* cluster_grid = nullptr;        ///< light_source=cluster_list: the grid it reads
  /// Stored images the shader samples at its own pixel (reads=): bytes per invocation per DRAM class.
  std::vector<std::pair<DramClass, std::uint32_t>> per_pixel_reads;
  /// Attachments of the pass the shader reads on chip at its own pixel (fetch=): bytes per invocation.
  std::uint32_t fetch_bytes = 0;
  /// Attachments of the pass it reads as images through the texture unit instead (fetches per
  /// invocation): those left in memory by a split render (pls.over_budget = split_render).
  std::uint32_t image_fetches = 0;
  const PipelineState* pipeline = nullptr;
  const ShaderDesc* shader = nullptr;
  std::vector<std::uint32_t> lights;  ///< indices of the lights the draw selects
  std::vector<std::uint8_t> light_selected;  ///< per light of the trace: 1 when selected
  std::uint32_t pass_draw_index = 0;  ///< position of the draw in its pass
};

/// One primitive after the geometry unit: rasteriser setup plus the original triangle's
/// attributes for the shader (perspective-correct barycentrics weight these). The render's table
/// holds one per binned primitive (312 bytes), so it keeps only what the tile units read: the
/// vertices' identities, which only binning reads, travel beside it (PrimitiveSink).
struct Primitive {
  TriangleSetup setup;
  std::uint32_t draw = 0;          ///< index into the render's DrawContext table
  std::uint32_t object = 0;        ///< index into the render's object table (object light lists)
  std::uint32_t material = kNoMaterial;
  std::int32_t proxy_light = -1;   ///< the light a proxy primitive stands for
  std::uint32_t varyings = 0;      ///< 32-bit varyings stored per vertex in the parameter buffer
  /// Frame-unique id: the primitive's position among all the frame's primitives the geometry unit
  /// delivered (SurfacePoint::triangle, the triangle-id image); set when the render takes it.
  std::uint32_t id = 0;
  HsrClass hsr = HsrClass::Opaque;
  std::array<glm::vec3, 3> world{};   ///< original triangle, world space
  std::array<glm::vec3, 3> normal{};  ///< original triangle, world space
  std::array<glm::vec2, 3> uv{};      ///< original triangle
};

/// A render's primitive records (the parameter buffer's contents, functionally), indexed like a
/// vector but stored in chunks of kChunkRecords that never move: growing copies nothing (a
/// vector's doubling copied a render's records and held both copies while it did: 347 MB peak
/// against 204 MB for forward_multipass's 513 K-primitive pass at 256 lights), and a record's
/// address stays valid. Chunks are
/// allocated uninitialised and kept when the store is cleared, so a frame's passes reuse the
/// pages its largest render faulted in, and the memory is that render's records.
class PrimitiveStore {
  static_assert(std::is_trivially_copyable_v<Primitive> && std::is_trivially_destructible_v<Primitive>,
                "records are copied into uninitialised storage and never destroyed");

 public:
  static constexpr std::size_t kChunkBits = 14;  ///< 16 K records (5 MB) a chunk
  static constexpr std::size_t kChunkRecords = std::size_t{1} << kChunkBits;

  PrimitiveStore() = default;
  /// Moves the chunks and records; the source is left empty.
  PrimitiveStore(PrimitiveStore&& o) noexcept : chunks_(std::move(o.chunks_)), size_(std::exchange(o.size_, 0)) {}
  PrimitiveStore& operator=(PrimitiveStore&& o) noexcept {
    chunks_ = std::move(o.chunks_);
    size_ = std::exchange(o.size_, 0);
    return *this;
  }

  Primitive& operator[](std::size_t i) { return chunks_[i >> kChunkBits].get()[i & (kChunkRecords - 1)]; }
  const Primitive& operator[](std::size_t i) const { return chunks_[i >> kChunkBits].get()[i & (kChunkRecords - 1)]; }
  std::size_t size() const { return size_; }
  bool empty() const { return size_ == 0; }
  /// Appends a copy of `p`; returns the stored record.
  Primitive& emplace_back(const Primitive& p) {
    if (size_ == chunks_.size() * kChunkRecords) chunks_.push_back(Chunk(static_cast<Primitive*>(::operator new(kChunkRecords * sizeof(Primitive)))));
    Primitive* slot = &(*this)[size_];
    std::memcpy(static_cast<void*>(slot), &p, sizeof(Primitive));
    ++size_;
    return *slot;
  }
  void push_back(const Primitive& p) { emplace_back(p); }
  void pop_back() { --size_; }
  Primitive& back() { return (*this)[size_ - 1]; }
  /// Forgets the records; keeps the chunks.
  void clear() { size_ = 0; }

 private:
  struct Free {
    void operator()(Primitive* p) const { ::operator delete(static_cast<void*>(p)); }
  };
  using Chunk = std::unique_ptr<Primitive, Free>;
  std::vector<Chunk> chunks_;
  std::size_t size_ = 0;
};

/// The identity of a primitive's three vertices (vertex re-use within a primitive block).
using VertexKeys = std::array<std::uint64_t, 3>;

/// Where the geometry unit delivers a draw's primitives, one at a time in submission order, with
/// their vertices' identities: the pass renderer bins each as it arrives (a full parameter
/// buffer may end the render in the middle of a draw, as the hardware's partial render does).
class PrimitiveSink {
 public:
  virtual ~PrimitiveSink() = default;
  /// Takes a primitive. `tiles`: the tiles it touches as tiles_touched() listed them when the
  /// geometry unit asked ahead, else nothing.
  virtual void accept(const Primitive& p, const VertexKeys& keys, std::optional<std::span<const int>> tiles) = 0;
  /// Binning's tile test ahead of accept(), on the threads that set primitives up: appends the
  /// tiles `p` touches to `tiles` and returns true, or returns false when the sink does not bin
  /// into tiles. Called on any thread, concurrently: it must only read.
  virtual bool tiles_touched(const Primitive& /*p*/, std::vector<int>& /*tiles*/) const { return false; }
};

/// A sink that keeps what it is given (tests, and any caller that wants a draw's primitives).
struct PrimitiveList final : PrimitiveSink {
  std::vector<Primitive> prims;
  std::vector<VertexKeys> keys;  ///< per primitive
  void accept(const Primitive& p, const VertexKeys& k, std::optional<std::span<const int>> /*tiles*/) override {
    prims.push_back(p);
    keys.push_back(k);
  }
};

/// An attachment's contents for the whole frame (kept across passes by name).
struct AttachmentImage {
  Format format = Format::Rgba8;
  std::uint32_t samples = 1;
  AttachmentUsage usage = AttachmentUsage::Color;
  bool defined = false;               ///< holds stored contents a later pass may load
  /// width*height*samples, colour attachments (AttachmentUsage::Color); empty when the frame
  /// computes no colours (FrameOptions::colour): then nothing reads or writes them. G-buffer and
  /// visibility attachments hold their surfaces instead (`surface`).
  std::vector<glm::vec4> color;
  std::vector<float> depth;           ///< width*height*samples, depth formats
  std::vector<std::uint8_t> stencil;  ///< width*height*samples, depth formats
  /// G-buffer / visibility attachments: the surface each pixel's data stands for (kept in the
  /// first such attachment a shader writes; width*height*samples, looks only with colours) and
  /// whether it was written.
  SurfaceStore surface;
  std::vector<std::uint8_t> surface_valid;
  /// Whether the surfaces are stored (`surface`) or only marked written (`surface_valid`): with
  /// colours always; without, only when a command of the trace reads them
  /// (stored_surface_readers): a deferred G-buffer read only by light volumes counts the same
  /// without its 52 bytes per sample.
  bool keeps_surface = true;
  std::size_t sample_count = 0;  ///< width*height*samples: the size of each array above that is kept
  /// A cleared image for attachment `a` over `pixels` pixels (depth 1, stencil 0, color 0; a
  /// color array only for colour attachments with `colour`).
  static AttachmentImage cleared(const Attachment& a, std::size_t pixels, bool colour) {
    AttachmentImage img;
    img.format = a.format;
    img.samples = a.samples;
    img.usage = a.usage;
    img.sample_count = pixels * a.samples;
    if (is_depth_format(a.format)) {
      img.depth.assign(img.sample_count, 1.0f);
      img.stencil.assign(img.sample_count, 0);
    } else if (colour && a.usage == AttachmentUsage::Color) {
      img.color.assign(img.sample_count, glm::vec4(0.0f));
    }
    return img;
  }
};

/// Whether a draw of generated geometry (a light volume, a full-screen pass) reads the surface
/// stored in the G-buffer or visibility attachment it shades (DrawContext::surface_source) when no
/// colours are computed: a cluster list needs its depth, and a shader writing a G-buffer or
/// visibility target (`writes_surface_target`) stores it on. Colours read it always.
inline bool reads_stored_surface(const ShaderDesc& sh, bool writes_surface_target) {
  return sh.light_source == LightSource::ClusterList || writes_surface_target;
}

/// Pixel local storage of one pass, functionally: per pixel the stored surface, a light
/// accumulator and a stack of light indices (see docs/kernels.md).
/// Without colours, the arrays only colours read are left empty: the stored surfaces unless a
/// shader reading the PLS needs them for a count (its cluster, a G-buffer output), the light sums
/// and the stacks' light indices (their counts and overflow flags stay: they decide what is
/// charged).
struct PlsState {
  std::uint32_t stack_capacity = 0;      ///< light indices a pixel's PLS holds
  SurfaceStore surface;                  ///< width*height (looks only with colours), or empty (above)
  std::vector<std::uint8_t> valid;       ///< 1 when the surface is defined
  std::vector<glm::vec3> accum;          ///< light accumulator (empty when no colours are computed)
  std::vector<std::uint32_t> stack;      ///< width*height*stack_capacity light indices (empty without colours)
  std::vector<std::uint16_t> stack_count;
  std::vector<std::uint8_t> overflow;    ///< 1 when more lights were pushed than fit

  /// Pushes `light` on the pixel's stack, or marks the pixel overflowed when the stack is full.
  void push_light(std::size_t pixel, std::uint32_t light) {
    auto& n = stack_count[pixel];
    if (n < stack_capacity) {
      if (!stack.empty()) stack[pixel * stack_capacity + n] = light;
      ++n;
    } else {
      overflow[pixel] = 1;
    }
  }
};

/// A 1-sample color image written by a compute kernel (a `buffer ... content=image`).
struct ImageBuffer {
  std::vector<glm::vec4> color;  ///< width*height; empty when no colours are computed
};


/// Per-pixel observations for the images written with --images (and `shaded`, which the
/// covered_pixels statistic also reads). Without images the other three stay empty: the units
/// that count into them skip it.
struct PixelCounters {
  std::vector<std::uint32_t> rasterised_samples;  ///< overdraw: depth-tested samples per pixel
  std::vector<std::uint32_t> shaded;               ///< shader invocations per pixel (helpers excluded)
  std::vector<std::uint32_t> lights_evaluated;     ///< lights evaluated per pixel, all invocations
  std::vector<std::uint32_t> triangle_id;          ///< last primitive shaded at the pixel (+1, 0 none)
  void resize(std::size_t pixels, bool images = true);
  bool images() const { return !triangle_id.empty(); }  ///< the image-only counters are kept
};

/// The frame's images and per-pixel counters.
struct FrameImages {
  int width = 0;
  int height = 0;
  std::map<std::string, AttachmentImage> attachments;
  std::map<std::string, ImageBuffer> image_buffers;                   ///< by buffer name
  std::map<std::string, std::shared_ptr<TileLightGrid>> tile_grids;   ///< by tile_grid buffer name
  std::map<std::string, std::shared_ptr<ClusterGrid>> cluster_grids;  ///< by cluster_grid / used_clusters buffer name
  std::map<std::string, std::shared_ptr<DepthBounds>> depth_bounds;   ///< by depth_bounds buffer name
  std::map<std::string, std::uint64_t> buffer_bytes_written;          ///< bytes a dispatch wrote per buffer
  PixelCounters counters;
};

}  // namespace tbdr

namespace tbdr {

/// The lights whose screen rectangle overlaps each square bin of the screen: an exact acceleration
/// of the image computation of "every light" shaders (a light outside a pixel's bin cannot reach
/// it). Not a model of hardware: what a technique is charged for comes from its light source.
struct LightScreenBins {
  /// Bin size: a host-speed choice only; every bin size gives the same images and figures.
  static constexpr int kBinPx = 32;
  int bins_x = 0;
  std::vector<std::vector<std::uint32_t>> bins;  ///< row-major, light indices in ascending order
  static LightScreenBins build(const std::vector<Light>& lights, const CameraXform& camera, const Viewport& viewport);
  /// The candidate lights of pixel (x, y).
  const std::vector<std::uint32_t>& at(int x, int y) const {
    return bins[static_cast<std::size_t>((y / kBinPx) * bins_x + x / kBinPx)];
  }
};

/// The frame's read-only inputs, shared by every render pass and compute dispatch.
struct FrameInputs {
  const HwConfig* hw = nullptr;
  const Scene* scene = nullptr;
  const std::vector<Light>* lights = nullptr;
  CameraXform camera;
  Viewport viewport;
  const ViewFrustum* frustum = nullptr;          ///< for cluster lookups
  const LightScreenBins* light_bins = nullptr;   ///< candidate lights per screen bin
  /// Compute the fragments' colours (images, image-equivalence checks). false: the units count
  /// the same work (lights, texture footprints, alpha tests, surfaces) and skip the colour
  /// arithmetic nothing reads; every statistic is the same either way.
  bool colour = true;
  /// Run the ISP's general per-sample loop everywhere, also where its lean loop for the common
  /// deferred case applies (Isp::render_tile): the reference the tests compare the lean loop
  /// with (tests/test_speed_equivalence.cpp). Every figure and image is the same either way.
  bool reference_loops = false;
  /// writeback.transaction_elimination: the tile signatures kept across a sequence's frames
  /// (models/tile_signatures.hpp); null when off.
  TileSignatures* tile_signatures = nullptr;
};

/// Everything the fragment units (ISP, TSP, tile memory) read while rendering one pass's tiles:
/// the frame's inputs, the pass, and the render's shared data (draws, primitives, targets).
struct RenderContext : FrameInputs {
  SamplePattern pattern;
  const PassDesc* pass = nullptr;
  /// The pass's render area in the frame's pixels (PassDesc::area; the whole viewport when it
  /// has none): only its pixels are rasterised, loaded, cleared and stored, only the tiles that
  /// overlap it are rendered.
  PixelRect render_area;
  FrameImages* images = nullptr;
  bool defer_shading = true;                  ///< tbdr: tag buffer HSR; tbr/imr: shade at early-Z
  bool framebuffer_in_dram = false;           ///< imr: attachments live in DRAM, no tile memory
  RenderOutputUnit* rop = nullptr;            ///< imr: the depth and colour caches the ISP and TSP go through
  std::vector<DrawContext> draws;             ///< the pass's draws, resolved
  std::vector<std::vector<std::uint32_t>> object_lights;  ///< per object: lights touching it
  PrimitiveStore prims;                       ///< the render's primitives (parameter buffer contents)
  std::vector<AttachmentImage*> color_targets;  ///< images the shaders' color outputs write, in order
  AttachmentImage* depth = nullptr;           ///< the pass's depth attachment image, or nullptr
  PlsState* pls = nullptr;                    ///< the pass's pixel local storage, or nullptr
  LitSampleLedger* lit_samples = nullptr;     ///< the pass's lit colour writes per sample (models/tsp.hpp), or nullptr
  DramTraffic* dram = nullptr;                ///< the pass's DRAM traffic (shader image reads)
  std::uint32_t frame_prim_base = 0;      ///< the next Primitive::id: primitives the frame's geometry delivered so far
  /// Texture addresses of scene triangles' fetches: where textures live, and the list the TSP
  /// appends the current tile's touched lines to (per quad and fetch slot, unsorted, repeats
  /// kept). Either null: no addresses are generated.
  const TextureLayout* textures = nullptr;
  std::vector<std::uint64_t>* texture_lines = nullptr;
};

}  // namespace tbdr
