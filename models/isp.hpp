#pragma once
// The ISP (image synthesis processor): per tile, rasterises the tile's primitives in submission
// order, runs the depth and stencil tests against on-chip depth/stencil, and removes hidden
// surfaces with isp.tag_buffers tag buffers that hold, per sample, a stack of primitive ids
// (layers) still to be shaded, bottom first (Imagination, US 8,446,409, Howson: "Method and
// apparatus for rendering computer graphic images of translucent and opaque objects"):
// - an opaque sample that passes the depth test clears every layer at the sample (those tags are
//   never shaded) and becomes the only layer; it writes depth at once;
// - a translucent or punch-through sample is pushed as a further layer; a punch-through layer's
//   depth is unresolved until its shader has run the alpha test;
// - the tag buffers are flushed to the TSP (every layer of the tile, in submission order) when a
//   sample needs a layer and all isp.tag_buffers are taken, or when a primitive's depth test at a
//   sample depends on an unresolved punch-through layer (its verdict against the layer's depth
//   differs from the one against the depth buffer); the flush shades the punch-through layers,
//   writes depth where their alpha test kept the sample, and the primitive is then depth tested
//   again (its stencil ops wait for that final verdict);
// - a mid-tile flush that resolves punch-through depth makes the ISP wait until the USCs have run
//   the unresolved punch-through primitives' shaders (Imagination, PowerVR Architecture Guide,
//   "Do Not Use Discard": alpha-tested primitives write depth only after the fragment shader ran,
//   and "subsequent primitives cannot be processed until the depth buffers are updated"); the
//   layers beneath need not finish first (only color writes are ordered per sample). That shading
//   work is counted in resolve_wait_alu_ops / resolve_wait_texels and the timing model adds its
//   USC time to the tile's ISP time.
// What is left in the layers is shaded when the tile ends. With one tag buffer every translucent
// or punch-through sample over a pending tag flushes the tile; with more, layers wait and a later
// opaque primitive in front removes them unshaded. In tbr/imr modes there is no tag buffer: every
// fragment that passes early depth testing is shaded in submission order, at once, or in tbr with
// forward pixel kill (Arm Mali) after the next isp.forward_pixel_kill_window primitives, unless
// one of them wrote an opaque sample over it meanwhile. With isp.early_z=0 (tbr/imr) the tests
// come after the shader: every rasterised sample is shaded and only those passing write colour.
#include <bit>
#include <cstdint>
#include <deque>
#include <vector>

#include "models/render_state.hpp"
#include "models/tsp.hpp"
#include "kernel/stats.hpp"

namespace tbdr {

// Declared once: X(type, member = stored name, unit, Sum | Gauge, description).
#define TBDR_ISP_STATS(X) \
  X(Counter, tiles_rendered, "tiles", Sum, "Tile renders (each sub-tile of a split tile counts)") \
  X(Counter, primitives_fetched, "primitives", Sum, "Primitives read from tile lists and set up") \
  X(Counter, samples_rasterised, "samples", Sum, "Samples covered by rasterised primitives") \
  X(Counter, depth_test_failed_samples, "samples", Sum, "Samples failing the depth test") \
  X(Counter, stencil_test_failed_samples, "samples", Sum, "Samples failing the stencil test") \
  X(Counter, hsr_removed_samples, "samples", Sum, "Pending tags (any layer) removed by a later opaque sample before shading") \
  X(Counter, tag_flushes, "flushes", Sum, "Mid-tile tag buffer flushes (no free layer, or a depth test needing a punch-through's alpha result)") \
  X(Counter, tag_flushed_samples, "samples", Sum, "Samples sent to the TSP by mid-tile flushes") \
  X(Counter, resolve_flushes, "flushes", Sum, "Mid-tile flushes that resolved punch-through depth (the ISP waits for their shading)") \
  X(Counter, resolve_wait_alu_ops, "ops", Sum, "Fragment ALU ops the ISP waited for at punch-through depth resolves") \
  X(Counter, resolve_wait_texels, "texels", Sum, "Texels the ISP waited for at punch-through depth resolves") \
  X(Counter, punch_through_samples, "samples", Sum, "Punch-through samples passing depth test") \
  X(Counter, translucent_samples, "samples", Sum, "Translucent samples passing depth test") \
  X(Counter, depth_buffer_read_bytes, "bytes", Sum, "On-chip depth/stencil bytes read by tests") \
  X(Counter, depth_buffer_write_bytes, "bytes", Sum, "On-chip depth/stencil bytes written") \
  X(Counter, tag_buffer_read_bytes, "bytes", Sum, "Tag buffer bytes read (flushes)") \
  X(Counter, tag_buffer_write_bytes, "bytes", Sum, "Tag buffer bytes written") \
  X(Counter, forward_pixel_kill_samples, "samples", Sum, "gpu.mode=tbr: queued samples killed before shading by a later opaque sample (isp.forward_pixel_kill_window)")
/// Statistics of the ISP.
struct IspStats {
  TBDR_STATS(TBDR_ISP_STATS)
};

/// The ISP of one GPU, working on one tile at a time.
class Isp {
 public:
  Isp(RenderContext& ctx, Tsp& tsp);
  /// Renders the primitives of `prims` (indices into ctx.prims) inside `rect`; depth/stencil and
  /// color contents are read and written in the frame images (loaded/stored by TileMemory).
  void render_tile(const PixelRect& rect, const std::vector<std::uint32_t>& prims, IspStats& isp, TspStats& tsp);

 private:
  /// One layer of a sample's stack: the primitive and, for punch-through, its depth there.
  struct Layer {
    std::uint32_t list_pos;  ///< the primitive's position in the tile's list (its tag)
    float z;
    bool unresolved;  ///< punch-through that writes depth and has not been alpha tested yet
  };
  /// A sample of the current primitive that passed the stencil test (its stencil pass or
  /// depth-fail op is applied once the depth test's final verdict is known).
  struct Candidate {
    std::uint32_t li;  ///< sample index in the tile
    std::int32_t x, y;
    std::uint32_t bit;
    float z;
    bool depth_pass;  ///< against the depth buffer as it is now
  };
  struct PendingSample {
    std::uint32_t tag;
    std::int32_t x, y;
    std::uint32_t bit;
    float z;
    bool unresolved;
  };
  /// A layer pushed since the tile's last flush, kept in push order: primitive by primitive in
  /// submission order, raster order within each, which is the order the flush shades them in.
  /// It is still pending unless an opaque sample emptied its stack after the push (then its slot
  /// is beyond the stack's depth or holds a later primitive's layer).
  struct PushedLayer {
    PendingSample sample;  ///< tag: the primitive's position in the tile's list
    std::uint32_t li;      ///< sample index in the tile
    std::uint32_t slot;    ///< its place in the sample's stack
  };
  /// The tile being rendered, as the per-primitive steps read it (set by begin_tile).
  struct TileFrame {
    PixelRect rect{};
    int W = 0, S = 1, rw = 0, L = 1;  ///< frame width, samples per pixel, tile width, layers per sample
    bool late_z = false;              ///< tbr / imr with isp.early_z=0: shade every rasterised sample
    std::size_t fpk_window = 0;       ///< tbr forward pixel kill: primitives queued before shading
    std::uint64_t ds_bytes = 0, tag_bytes = 0;  ///< per sample: depth/stencil and tag buffer bytes
    float* depth = nullptr;           ///< the frame's depth (null: no depth attachment)
    std::uint8_t* stencil = nullptr;
    bool has_stencil = false;
    std::uint32_t* overdraw = nullptr;  ///< per pixel: rasterised samples (only with images)
    /// Index of a sample in the frame's depth and stencil.
    std::size_t global_index(std::int32_t x, std::int32_t y, std::uint32_t bit) const {
      return (static_cast<std::size_t>(y) * static_cast<std::size_t>(W) + static_cast<std::size_t>(x)) * static_cast<std::size_t>(S) +
             static_cast<std::size_t>(std::countr_zero(bit));
    }
  };
  /// One primitive's visit of the tile: what its pipeline asks of the tests, and what rasterising
  /// it counted (the candidates are candidates_[0, n_cand)).
  struct PrimitiveVisit {
    const Primitive* p;
    const PipelineState* pl;
    std::uint32_t prim_index = 0, list_pos = 0;
    bool depth_on = false, write_on = false, stencil_on = false;
    bool early_write = false;    ///< tbr / imr: an opaque primitive writes its depth at the test
    bool layered = false;        ///< not opaque: its samples stack on the layers beneath
    bool open_verdicts = false;  ///< tbdr: a punch-through layer may still change a depth verdict
    std::uint8_t ref = 0;        ///< stencil reference
    std::uint32_t depth_outcomes = 0;
    std::uint64_t rasterised = 0, depth_reads = 0;
    std::uint64_t final_fails = 0;  ///< tbdr: samples whose depth test failed for good
    /// tbdr: a sample cannot take the primitive without a punch-through's alpha result or a free
    /// layer: the tile's layers are flushed first.
    bool conflict = false;
    std::size_t n_cand = 0;
  };
  /// Prepares the tile's state (stacks, forward pixel kill queue) and fills `tf`.
  void begin_tile(const PixelRect& rect, TileFrame& tf);
  /// The visit of the primitive at `list_pos` of the tile's list, before rasterising.
  PrimitiveVisit begin_primitive(const TileFrame& tf, std::uint32_t list_pos, std::uint32_t prim_index) const;
  /// tbdr: a primitive the tile's depth bounds hide everywhere, counted without a per-sample test.
  void count_hidden_primitive(const TileFrame& tf, const PrimitiveVisit& v, IspStats& isp);
  /// tbdr's common case (no stencil, no open verdict, no ROP): rasterises into candidates.
  void rasterize_deferred(const TileFrame& tf, PrimitiveVisit& v);
  /// Every other case: stencil and depth tests per sample, candidates (tbdr) or pending samples.
  void rasterize_general(const TileFrame& tf, PrimitiveVisit& v, IspStats& isp);
  /// tbdr: flushes first on a conflict, then applies the final verdicts and pushes the tags.
  void take_verdicts(const TileFrame& tf, const PrimitiveVisit& v, const std::vector<std::uint32_t>& prims, IspStats& isp,
                     TspStats& tsp);
  /// tbr / imr: shades the primitive's samples now, or queues them for forward pixel kill.
  void shade_in_submission_order(const TileFrame& tf, const PrimitiveVisit& v, std::uint32_t& arrivals, IspStats& isp,
                                 TspStats& tsp);
  /// Shades every layer of the tile in submission order and empties the stacks; a mid-tile flush
  /// that resolves punch-through depth makes the ISP wait for those punch-through shaders.
  void flush(const std::vector<std::uint32_t>& prims, bool mid_tile, IspStats& isp, TspStats& tsp);
  /// Writes a punch-through primitive's depth where its alpha test kept the sample.
  void write_punch_depth(const PendingSample* begin, const PendingSample* end, IspStats& isp);
  /// imr: the colour outputs of the batch just shaded (batch_; alive_ for a punch-through
  /// primitive) through the ROP's colour cache.
  void rop_color_outputs(std::uint32_t prim_index, bool punch);
  /// tbr forward pixel kill: a primitive's early-Z survivors waiting to be shaded.
  struct Queued {
    std::uint32_t seq;   ///< arrival order in the tile
    std::uint32_t prim;
    bool killable;       ///< its shader has no side effect beyond its colour (no PLS, no fetch)
    std::vector<PendingSample> samples;
  };
  /// Shades the oldest queued primitive's samples that no later opaque sample killed.
  void shade_queued(const PixelRect& rect, IspStats& isp, TspStats& tsp);
  /// Tile sample index of a pending sample.
  std::size_t tile_sample(const PixelRect& rect, const PendingSample& ps) const;
  /// Appends a sample to a batch: to its last pixel when it is the same pixel, else as a new one.
  /// (Defined here: the flush calls it per layer, and a call per sample cost 2 % of a 1080p run.)
  static void add_to_batch(const PendingSample& s, std::vector<ShadePixel>& batch) {
    if (!batch.empty() && batch.back().x == s.x && batch.back().y == s.y) {
      batch.back().mask |= s.bit;
    } else {
      batch.push_back({s.x, s.y, s.bit});
    }
  }
  /// Merges consecutive samples of one pixel into ShadePixels (samples are in raster order).
  static void build_batch(const PendingSample* begin, const PendingSample* end, std::vector<ShadePixel>& batch);

  /// tbdr: whether every sample `p` covers inside `rect` fails the depth test whose
  /// passing_outcomes() are given, by the tile's depth bounds alone (found on first use).
  bool fails_depth_everywhere(const Primitive& p, const PixelRect& rect, std::uint32_t depth_outcomes);
  /// Keeps the tile's depth bounds (when known) around a depth just written.
  void widen_tile_depth(float z);

  RenderContext& ctx_;
  Tsp& tsp_;
  int layers_per_sample_ = 1;           ///< isp.tag_buffers
  std::vector<Layer> layers_;           ///< tile samples x layers_per_sample_
  std::vector<std::uint8_t> depth_of_;  ///< per tile sample: layers in use
  /// Unresolved punch-through layers pushed since the tile's last flush (an upper bound: a layer
  /// an opaque sample hides still counts). 0: no flush can change the depth buffer.
  std::uint64_t unresolved_layers_ = 0;
  std::vector<Candidate> candidates_;  ///< tbdr: one per tile sample, the current primitive's first n
  std::vector<PendingSample> pending_;
  std::vector<PendingSample> rasterised_;  ///< isp.early_z=0: every sample the primitive covers
  std::vector<PushedLayer> pushed_;  ///< the layers pushed since the tile's last flush
  /// Whether an opaque sample emptied a non-empty stack since the tile's last flush: only then
  /// may a layer in pushed_ no longer be pending (a light-volume pass: never).
  bool layers_hidden_ = false;
  std::vector<PendingSample> flush_samples_;  ///< flush: the punch-through primitive being shaded, its samples
  std::vector<ShadePixel> batch_;
  std::vector<std::uint32_t> alive_;
  std::deque<Queued> queue_;             ///< tbr forward pixel kill: primitives waiting to be shaded
  std::vector<std::uint32_t> kill_seq_;  ///< per tile sample: 1 + arrival of the latest opaque sample there
  /// Bounds of the depth buffer over the current tile (valid while tile_depth_known_; NaN when it
  /// holds a NaN): widened by every depth write, so always a superset of what the tile holds.
  SampleDepthBounds tile_depth_{};
  bool tile_depth_known_ = false;
};

}  // namespace tbdr
