#pragma once
// The TSP and the USCs, functionally: shade the pixels the ISP hands over for one primitive, in
// 2x2 quads (helper lanes counted), charge the shader's declared cost (ALU ops, texture fetches,
// per-light ALU ops times the lights the fragment evaluates), evaluate punch-through alpha tests
// for real, and write the fixed shading model's color into the color targets (with blending).
// For scene triangles it also computes the texture lines each quad's fetches touch
// (models/texture_unit.hpp) and appends them to the tile's list (RenderContext::texture_lines).
#include <array>
#include <atomic>
#include <bit>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include <glm/glm.hpp>

#include "models/render_state.hpp"
#include "models/texture_unit.hpp"
#include "kernel/stats.hpp"

namespace tbdr {

// Declared once: X(type, member = stored name, unit, Sum | Gauge, description).
#define TBDR_TSP_STATS(X) \
  X(Counter, shader_invocations, "fragments", Sum, "Fragment shader invocations on covered pixels (helpers excluded)") \
  X(Counter, shaded_quads, "quads", Sum, "2x2 quads launched") \
  X(Counter, helper_lanes, "lanes", Sum, "Lanes of launched quads with no covered pixel (helpers)") \
  X(Counter, idle_quads, "quads", Sum, "Launched quads of batches with nothing to run (no ALU op, texel, tile-buffer or PLS byte, image read: a depth-only shader); part of shaded_quads") \
  X(Counter, lit_surface_invocations, "fragments", Sum, "Invocations on scene geometry whose shader evaluates lights (not proxies)") \
  X(Counter, shaded_samples, "samples", Sum, "Samples whose color a shader wrote") \
  X(Counter, fragment_alu_ops, "ops", Sum, "Fragment shader ALU ops, helper lanes included") \
  X(Counter, texture_fetches, "fetches", Sum, "Texture fetches, helper lanes included") \
  X(Counter, texels_filtered, "texels", Sum, "Bilinear-filtered texels the texture units produced: fetches (helper lanes included) x texture.filtered_texels_per_fetch") \
  X(Counter, texture_line_accesses, "lines", Sum, "Texture cache line accesses: distinct lines per quad and fetch, before merging within the tile") \
  X(Counter, texture_tile_lines, "lines", Sum, "Distinct texture lines each tile touched (its footprint), summed over tiles") \
  X(Counter, light_evaluations, "evaluations", Sum, "Lights evaluated by covered fragments") \
  X(Counter, alpha_test_killed_samples, "samples", Sum, "Punch-through samples discarded by the alpha test") \
  X(Counter, blended_samples, "samples", Sum, "Samples written with blending") \
  X(Counter, unassigned_cluster_fragments, "fragments", Sum, "Fragments whose cluster got no light list (not flagged)") \
  X(Counter, light_stack_overflow_fragments, "fragments", Sum, "Fragments whose PLS light stack overflowed (fell back to every light)") \
  X(Counter, pls_bytes_accessed, "bytes", Sum, "Pixel local storage bytes read and written by shaders (the pass's PLS layout per access)") \
  X(Counter, tile_buffer_read_bytes, "bytes", Sum, "On-chip tile buffer bytes read by blending and fetch") \
  X(Counter, tile_buffer_write_bytes, "bytes", Sum, "On-chip tile buffer bytes written by shaders") \
  X(Counter, hidden_lit_samples, "samples", Sum, "Samples lit scene-surface fragments shaded whose colour did not last to the end of the pass: replaced by a later unblended colour write, or (isp.early_z=0) failing the depth/stencil test after the shader; at 1 sample per pixel, fragments (LitSampleLedger)") \
  X(Counter, hidden_light_evaluations, "evaluations", Sum, "Lights evaluated by the fragments of hidden_lit_samples, counted once per hidden sample; at 1 sample per pixel, the light evaluations spent on hidden surfaces")
/// Statistics of fragment shading.
struct TspStats {
  TBDR_STATS(TBDR_TSP_STATS)
};

/// Per sample of one render pass, the colour writes of lit scene-surface fragments (a scene
/// triangle's, its shader evaluating lights: lit_surface_invocations' fragments) that the sample's
/// colour still holds, and the lights those fragments evaluated. Tsp::shade keeps it for every
/// colour-writing fragment: an unblended write that reads nothing of the target (no framebuffer
/// fetch) replaces the sample's colour, so what the sample held is hidden (counted in
/// TspStats::hidden_lit_samples and hidden_light_evaluations) and only the new write remains; a
/// blended write adds to what the sample holds. What it holds at the end of the pass is the final
/// image's (stored or resolved). Light-volume and full-screen fragments are not lit surfaces:
/// they replace or add, never count. The pass's TileMemory owns it (RenderContext::lit_samples);
/// tiles write disjoint samples, so tiles on several threads keep it without locks (a block of
/// samples is published once, atomically).
class LitSampleLedger {
 public:
  /// For a `width` x `height` frame of `samples` samples per pixel, none holding a lit write.
  LitSampleLedger(int width, int height, int samples);
  ~LitSampleLedger();
  LitSampleLedger(const LitSampleLedger&) = delete;
  LitSampleLedger& operator=(const LitSampleLedger&) = delete;
  /// A colour write at the samples `mask` of pixel (x, y): `replaces` (unblended) hides what the
  /// samples held; `lit` (a lit scene-surface fragment that evaluated `lights` lights) is then held.
  void write(int x, int y, std::uint32_t mask, bool replaces, bool lit, std::uint64_t lights, TspStats& stats) {
    const std::size_t b = static_cast<std::size_t>(y >> kBlockBits) * blocks_x_ + static_cast<std::size_t>(x >> kBlockBits);
    if (state_[b].load(std::memory_order_acquire) != kReady) {
      // Nothing lit was held in this block: only a lit write changes that.
      if (!lit) return;
      make_ready(b);
    }
    const std::size_t first = (static_cast<std::size_t>(y & kBlockMask) << kBlockBits | static_cast<std::size_t>(x & kBlockMask)) * samples_;
    std::uint32_t* held_at = held_.get() + b * block_entries_ + first;
    for (std::uint32_t m = mask; m != 0; m &= m - 1) {
      const auto s = static_cast<std::size_t>(std::countr_zero(m));
      std::uint32_t& held = held_at[s];
      if (replaces && held != 0) {
        if (held == kWide) {
          std::uint64_t& w = wide_[b].load(std::memory_order_acquire)[first + s];
          hide(w >> kWideLightBits, w & kWideLightMask, stats);
          w = 0;
        } else {
          hide(held >> kLightBits, held & kLightMask, stats);
        }
        held = 0;
      }
      if (lit) {
        if (held != kWide && held >> kLightBits < kMaxCount - 1 && lights <= kLightMask - (held & kLightMask)) {
          held += (std::uint32_t{1} << kLightBits) + static_cast<std::uint32_t>(lights);
        } else {
          add_wide(held, b, first + s, lights);
        }
      }
    }
  }
  /// `samples` samples of a lit fragment that evaluated `lights` lights, shaded but not written
  /// (isp.early_z=0: the depth or stencil test after the shader failed): hidden at once.
  static void hidden_unwritten(std::uint32_t samples, std::uint64_t lights, TspStats& stats) {
    stats.hidden_lit_samples += samples;
    stats.hidden_light_evaluations += std::uint64_t{samples} * lights;
  }

 private:
  /// The samples are kept in blocks of 2^kBlockBits x 2^kBlockBits pixels, each zeroed at the
  /// first lit write in it (the array is allocated uninitialised): a pass touches the blocks its
  /// lit fragments write (a deferred lighting pass, its glass), and a tile's samples lie in a few
  /// contiguous blocks. Host speed and memory only: every block size counts the same.
  static constexpr int kBlockBits = 3;
  static constexpr int kBlockMask = (1 << kBlockBits) - 1;
  /// A sample's entry: the lit writes it holds (top kCountBits bits) and their lights (the rest),
  /// or kWide: they no longer fit, and its block's wide entry (64 bits: kWideCountBits and the
  /// rest) holds them. Four bytes a sample where they fit (every sample of the atrium's frames:
  /// each page of entries is a page fault on first touch).
  static constexpr int kCountBits = 8;
  static constexpr int kLightBits = 32 - kCountBits;
  static constexpr std::uint32_t kLightMask = (std::uint32_t{1} << kLightBits) - 1;
  static constexpr std::uint32_t kMaxCount = (std::uint32_t{1} << kCountBits) - 1;  ///< count field of kWide
  static constexpr std::uint32_t kWide = ~std::uint32_t{0};
  static constexpr int kWideCountBits = 24;
  static constexpr int kWideLightBits = 64 - kWideCountBits;
  static constexpr std::uint64_t kWideLightMask = (std::uint64_t{1} << kWideLightBits) - 1;
  static void hide(std::uint64_t count, std::uint64_t lights, TspStats& stats) {
    stats.hidden_lit_samples += count;
    stats.hidden_light_evaluations += lights;
  }
  /// Adds one lit write of `lights` lights to the sample of entry `held`, index `i` of block `b`,
  /// in its wide entry (moved there first; std::overflow_error past the wide entry's fields).
  void add_wide(std::uint32_t& held, std::size_t b, std::size_t i, std::uint64_t lights);
  /// A block's state: untouched, being zeroed by one thread, zeroed (its entries are valid).
  static constexpr std::uint8_t kUntouched = 0, kZeroing = 1, kReady = 2;
  /// Zeroes block `b` unless a thread did: tiles that share a block (tile sizes not a multiple of
  /// its side, strips) write different samples of it, after it is zeroed.
  void make_ready(std::size_t b);

  std::size_t blocks_x_ = 0;
  std::size_t samples_ = 1;
  std::size_t block_entries_ = 0;  ///< entries of a block: 2^(2 kBlockBits) pixels x samples
  std::unique_ptr<std::uint32_t[]> held_;            ///< blocks x block_entries_, block after block
  std::unique_ptr<std::atomic<std::uint8_t>[]> state_;  ///< per block
  std::unique_ptr<std::atomic<std::uint64_t*>[]> wide_;  ///< per block: its wide entries, made at its first kWide
  std::size_t blocks_ = 0;
};

/// One pixel of a shading batch: absolute coordinates, the samples shaded and, of those, the
/// samples whose colour is written (all of them, unless late depth/stencil tests after the shader
/// discard some: isp.early_z=0).
struct ShadePixel {
  std::int32_t x = 0;
  std::int32_t y = 0;
  std::uint32_t mask = 0;
  std::uint32_t write = ~0u;
};

/// The PLS variable a light accumulation is kept in (deferred_tile_store's layout): what is added
/// to it keeps its format's precision.
inline constexpr const char* kPlsAccumulatorName = "light_accum";

/// The 2x2 quads (aligned to even coordinates) that `pixels` launch, written to `quads` as
/// (row << 32 | column) quad keys, ascending, each once; returns their number. Linear: a bitmap
/// for a batch within 64 x 64 quads (a tile's), else a merge of pixels sorted by row then column
/// (Tsp::shade's contract), a sort otherwise.
std::size_t launched_quads(std::span<const ShadePixel> pixels, std::vector<std::uint64_t>& quads);
/// How many quads launched_quads would write, without writing their keys where its bitmap holds
/// them (a tile's batch); otherwise it writes them into `scratch`.
std::size_t launched_quad_count(std::span<const ShadePixel> pixels, std::vector<std::uint64_t>& scratch);

/// Whether any of the lights `reach` (indices into `lights`) may reach a point of scene triangle
/// `p` interpolated at barycentrics inside it, as the TSP interpolates a fragment's position
/// (p.world weighted in float): true whenever ShadingModel::reaches holds at such a point. False
/// only when the triangle's world box, widened by 1e-5 of its largest coordinate (ten times the
/// rounding of the interpolation: float weights in [0, 1] summing to 1 within a few ulp, three
/// products and two sums), lies beyond every light's radius^2 with the colour loop's margin
/// (kReachMargin, for the distance's own rounding). (A non-finite vertex makes every interpolated
/// position NaN or infinite, reached by no light: either answer is exact.) The TSP leaves the
/// colour of such a triangle's fragments out (forward_multipass: most of a pass's fragments).
bool may_reach_triangle(const Primitive& p, std::span<const std::uint32_t> reach, const std::vector<Light>& lights);

/// The fragment shading stage.
class Tsp {
 public:
  /// Appends texture lines to ctx.texture_lines and books shader image reads to ctx.dram (as
  /// they are when it is made) until bind_outputs says otherwise.
  explicit Tsp(RenderContext& ctx);
  /// Where this TSP appends the tile's texture lines and books the shaders' image reads: one list
  /// and one traffic account per thread when tiles render in parallel (models/command_processor).
  void bind_outputs(std::vector<std::uint64_t>* texture_lines, DramTraffic* dram);
  /// Shades `pixels` (one primitive, one tile, sorted by row then column). For punch-through
  /// primitives, `alive` receives per pixel the samples that survived the alpha test.
  void shade(std::uint32_t prim_index, std::span<const ShadePixel> pixels, std::vector<std::uint32_t>* alive,
             TspStats& stats);

 private:
  /// Texture lines of the quads of one scene triangle's batch (quad_seen_[0, quads)): appended to
  /// ctx_.texture_lines, counted in stats.texture_line_accesses. Kept out of line: the pixel loops
  /// of shade() compile better without it.
  [[gnu::noinline]] void texture_addresses(const Primitive& p, std::uint32_t tex_fetches, std::size_t quads,
                                           TspStats& stats);

  /// The world-space box of the surfaces `pixels` shade (false: none has a surface).
  bool surface_bounds(const Primitive& p, const DrawContext& d, std::span<const ShadePixel> pixels, glm::vec3& lo,
                      glm::vec3& hi) const;
  /// Rebuilds near_ from screen bin `bin`: the selected lights of draw `d` whose sphere reaches the box.
  void gather_near_lights(const std::vector<std::uint32_t>& bin, const DrawContext& d, glm::vec3 lo, glm::vec3 hi);
  /// Sum of the contributions of near_'s lights at `s`, in near_'s (ascending) order.
  glm::vec3 near_lighting(const SurfacePoint& s, glm::vec3 eye);

  // The steps of shade(), in the order a batch goes through them (models/tsp.cpp says which
  // hardware step each models). Those run per fragment are inlined into the loops that call them
  // (host speed: out of line, each reread the batch's state through a pointer; clustered_forward
  // at 960x540 ran 3 % more instructions in shade).
  struct Batch;     ///< one batch's decoded draw state
  struct Fragment;  ///< one fragment in flight
  /// Launches the batch's quads; counts invocations, quads, helper lanes, fetches. Returns the quads.
  [[gnu::always_inline]] inline std::uint64_t launch_quads(const Batch& b, TspStats& stats);
  /// Remakes target_formats_, pls_formats_ and pls_accum_format_ when the pass changed.
  void refresh_pass_formats();
  /// The counting path: fragments with a fixed light count and no surface of their own. Returns the lights evaluated.
  std::uint64_t shade_counted_fragments(const Batch& b, std::vector<std::uint32_t>* alive, TspStats& stats);
  /// The counting path's PLS effects of a fragment of a shader without colour outputs.
  void counted_pls_effects(const Batch& b, std::size_t pixel, const Light* volume_light);
  /// The general path: every fragment shaded in turn. Returns the lights evaluated.
  std::uint64_t shade_fragments(const Batch& b, std::vector<std::uint32_t>* alive, TspStats& stats);
  /// Every fragment's barycentrics and base colour texel into frag_bary_, frag_texel_ (prefetched).
  void prefetch_base_texels(const Batch& b);
  /// The surface fragment `f` shades (interpolated or read from a stored surface).
  [[gnu::always_inline]] inline void fragment_surface(const Batch& b, Fragment& f, TspStats& stats);
  /// A scene triangle's surface at `f`'s pixel: interpolation, base colour sample, alpha test.
  [[gnu::always_inline]] inline void interpolate_surface(const Batch& b, Fragment& f, TspStats& stats);
  /// A stored surface's entry `k` (or only its position, out of reach) into `f`.
  [[gnu::always_inline]] inline void read_stored_surface(const Batch& b, const SurfaceStore& store, std::size_t k, Fragment& f);
  /// The lights fragment `f` evaluates (f.fl).
  [[gnu::always_inline]] inline void select_lights(const Batch& b, Fragment& f, TspStats& stats);
  /// The sum of `f`'s lights' contributions at its surface.
  [[gnu::always_inline]] inline glm::vec3 fragment_lighting(const Batch& b, const Fragment& f);
  /// The batch's surface box (made at the first call; `fallback` when no fragment has a surface).
  const std::pair<glm::vec3, glm::vec3>& batch_bounds(const Batch& b, const glm::vec3& fallback) const;
  /// PLS writes of a shader without colour outputs.
  [[gnu::always_inline]] inline void store_in_pls(const Batch& b, const Fragment& f);
  /// Fragment `f`'s colour outputs: lit colour blended into the targets, surface to a G-buffer target.
  [[gnu::always_inline]] inline void write_colour_outputs(const Batch& b, const Fragment& f, TspStats& stats);
  /// Fragment `f`'s surface into the first G-buffer / visibility target.
  [[gnu::always_inline]] inline void store_in_surface_target(const Batch& b, const Fragment& f);
  /// `src` blended into the written samples of the batch's colour targets.
  void blend_into_colour_targets(const Batch& b, std::size_t pixel, std::uint32_t write_mask, const glm::vec4& src);
  /// `add` into the pixel's PLS light accumulator, kept as its format holds it.
  [[gnu::always_inline]] inline void accumulate_in_pls(const Batch& b, std::size_t pixel, const glm::vec3& add);
  /// Marks the pixel's PLS undefined (a colour output was written).
  [[gnu::always_inline]] inline void invalidate_pls(std::size_t pixel);
  /// A surface as the batch's G-buffer targets (`pls`: the PLS variables) keep it.
  SurfacePoint stored_surface(const Batch& b, bool pls, SurfacePoint q) const;
  /// One fragment's colour write in the pass's lit-sample ledger.
  [[gnu::always_inline]] inline void keep_ledger(const Batch& b, const ShadePixel& px, std::uint32_t write_mask, std::uint64_t lights, TspStats& stats);
  /// Tile buffer traffic of `written` colour samples.
  [[gnu::always_inline]] inline void charge_written_samples(const Batch& b, std::uint64_t written, TspStats& stats);
  /// The batch's per-fragment charges, booked once.
  void charge_batch(const Batch& b, std::uint64_t helpers, std::uint64_t light_sum, TspStats& stats);

  RenderContext& ctx_;
  std::vector<std::uint64_t>* texture_lines_out_;  ///< the current tile's texture lines (see bind_outputs)
  DramTraffic* dram_out_;                          ///< the shaders' image reads (see bind_outputs)
  std::vector<std::uint64_t> quad_seen_;  ///< scratch: quads launched in this batch
  /// Scratch of a textured scene triangle's batch whose every fragment samples its base colour
  /// (see Tsp::shade): each fragment's barycentrics and texel (ColorTexels::texel_at).
  std::vector<glm::vec3> frag_bary_;
  std::vector<const std::uint8_t*> frag_texel_;
  /// The colour loop's candidate lights for the current batch and screen bin, structure of arrays
  /// (the radius test runs over contiguous floats, several lights per instruction).
  struct NearLights {
    std::vector<std::uint32_t> index;  ///< light indices, ascending
    std::vector<float> x, y, z;        ///< light positions
    std::vector<float> reach2;         ///< radius^2 widened by kReachMargin (a superset of the exact test)
    std::vector<std::uint8_t> hit;     ///< scratch: 1 where the light may reach the current surface
    const std::vector<std::uint32_t>* bin = nullptr;  ///< the screen bin they were gathered from
  };
  NearLights near_;
  /// The current pass's colour targets and PLS variables (the surface attribute their name holds, format), for FormatPrecision.
  const PassDesc* formats_pass_ = nullptr;
  std::vector<std::pair<FormatPrecision::Attribute, Format>> target_formats_;
  std::vector<std::pair<FormatPrecision::Attribute, Format>> pls_formats_;
  std::optional<Format> pls_accum_format_;
  std::array<QuadFootprint, 2> footprints_;  ///< scratch: the current and the previous quad's texture lines
  /// Texture lines recently appended to the tile's list (direct mapped; valid for the epoch).
  struct LineFilterEntry {
    std::uint64_t line = 0;
    std::uint32_t epoch = 0;
  };
  static constexpr int kLineFilterBits = 11;
  std::array<LineFilterEntry, std::size_t{1} << kLineFilterBits> line_filter_{};
  std::uint32_t line_filter_epoch_ = 0;
};

}  // namespace tbdr
