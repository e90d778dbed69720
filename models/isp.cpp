#include "models/isp.hpp"

#include <algorithm>
#include <bit>
#include <cstddef>
#include <limits>
#include <span>

#include "kernel/bits.hpp"
#include "models/rop.hpp"

namespace tbdr {

namespace {

constexpr std::uint32_t kNoTag = 0xffffffffu;

// The ISP's per-sample visitor is inlined into the rasteriser's pixel loop (GCC declines on its
// own: the visitor is large and the loop is instantiated for five sample counts), so the loop
// keeps the primitive's state in registers. Compilers without the attribute decide for themselves.
#if defined(__GNUC__)
#define TBDR_ISP_INLINE_VISITOR __attribute__((always_inline))
#else
#define TBDR_ISP_INLINE_VISITOR
#endif

/// A comparison as the outcomes it passes, a table indexed by the outcome of `incoming` against
/// `stored`: bit 0 unordered (a NaN), bit 1 less, bit 2 equal, bit 4 greater. Set once per
/// primitive, so the per-sample test is three compares and a shift, not a switch.
constexpr std::uint32_t passing_outcomes(CompareOp op) {
  switch (op) {
    case CompareOp::Never: return 0x00;
    case CompareOp::Less: return 0x02;
    case CompareOp::Equal: return 0x04;
    case CompareOp::LessEqual: return 0x06;
    case CompareOp::Greater: return 0x10;
    case CompareOp::NotEqual: return 0x13;  // less, greater or unordered (IEEE: NaN != x)
    case CompareOp::GreaterEqual: return 0x14;
    case CompareOp::Always: return 0x17;
  }
  return 0x17;
}

/// Whether `incoming` passes the comparison whose passing_outcomes() is `outcomes`.
template <class T>
constexpr bool passes_outcomes(std::uint32_t outcomes, T incoming, T stored) {
  const auto outcome = static_cast<std::uint32_t>(incoming < stored) | static_cast<std::uint32_t>(incoming == stored) << 1 |
                       static_cast<std::uint32_t>(incoming > stored) << 2;
  return ((outcomes >> outcome) & 1u) != 0;
}

/// A depth test as the per-sample loops compile it: the five comparisons an unordered pair fails
/// as the one comparison each is (the same verdicts as their outcome sets, NaN included), any
/// other through its outcome set (passes_outcomes).
enum class DepthTest : std::uint8_t { ByOutcomes, Less, LessEqual, Equal, Greater, GreaterEqual };
template <DepthTest kTest>
constexpr bool passes_depth(std::uint32_t outcomes, float incoming, float stored) {
  if constexpr (kTest == DepthTest::Less) return incoming < stored;
  else if constexpr (kTest == DepthTest::LessEqual) return incoming <= stored;
  else if constexpr (kTest == DepthTest::Equal) return incoming == stored;
  else if constexpr (kTest == DepthTest::Greater) return incoming > stored;
  else if constexpr (kTest == DepthTest::GreaterEqual) return incoming >= stored;
  else return passes_outcomes(outcomes, incoming, stored);
}
/// Whether compiled test kTest gives comparison `op`'s verdict (its outcome set's) for every pair
/// of depths that order differently: signed zeros, infinities and NaN among them.
template <DepthTest kTest>
constexpr bool compiles_as(CompareOp op) {
  constexpr float kInf = std::numeric_limits<float>::infinity(), kNan = std::numeric_limits<float>::quiet_NaN();
  constexpr float kDepths[] = {-kInf, -1.0f, -0.0f, 0.0f, 0.25f, 1.0f, kInf, kNan};
  for (const float a : kDepths) {
    for (const float b : kDepths) {
      if (passes_depth<kTest>(0, a, b) != passes_outcomes(passing_outcomes(op), a, b)) return false;
    }
  }
  return true;
}
static_assert(compiles_as<DepthTest::Less>(CompareOp::Less) && compiles_as<DepthTest::LessEqual>(CompareOp::LessEqual) &&
                  compiles_as<DepthTest::Equal>(CompareOp::Equal) &&
                  compiles_as<DepthTest::Greater>(CompareOp::Greater) &&
                  compiles_as<DepthTest::GreaterEqual>(CompareOp::GreaterEqual),
              "a compiled depth test differs from its comparison's outcome set");
static_assert(!compiles_as<DepthTest::Less>(CompareOp::LessEqual) && !compiles_as<DepthTest::GreaterEqual>(CompareOp::Greater),
              "the check above tells comparisons apart");

template <class T>
bool passes(CompareOp op, T incoming, T stored) {
  return passes_outcomes(passing_outcomes(op), incoming, stored);
}

std::uint8_t apply_stencil(StencilOp op, std::uint8_t v, std::uint8_t ref) {
  switch (op) {
    case StencilOp::Keep: return v;
    case StencilOp::Zero: return 0;
    case StencilOp::Replace: return ref;
    case StencilOp::Incr: return v == 255 ? v : static_cast<std::uint8_t>(v + 1);
    case StencilOp::Decr: return v == 0 ? v : static_cast<std::uint8_t>(v - 1);
    case StencilOp::Invert: return static_cast<std::uint8_t>(~v);
    case StencilOp::IncrWrap: return static_cast<std::uint8_t>(v + 1);
    case StencilOp::DecrWrap: return static_cast<std::uint8_t>(v - 1);
  }
  return v;
}

}  // namespace

Isp::Isp(RenderContext& ctx, Tsp& tsp) : ctx_(ctx), tsp_(tsp) {}

void Isp::build_batch(const PendingSample* begin, const PendingSample* end, std::vector<ShadePixel>& batch) {
  batch.clear();
  for (const PendingSample* s = begin; s != end; ++s) add_to_batch(*s, batch);
}

void Isp::write_punch_depth(const PendingSample* begin, const PendingSample* end, IspStats& isp) {
  const PipelineState& pl = *ctx_.draws[ctx_.prims[begin->tag].draw].pipeline;
  if (!ctx_.depth || !pl.depth_write) return;
  float* depth = ctx_.depth->depth.data();
  const int W = ctx_.viewport.width_px;
  const int S = ctx_.pattern.count;
  const std::uint64_t ds_bytes = static_cast<std::uint64_t>(ctx_.hw->isp.depth_stencil_bytes_per_sample);
  // batch_[i] is the i-th distinct pixel of [begin, end), alive_[i] its samples kept by the alpha test.
  std::size_t i = 0;
  for (const PendingSample* s = begin; s != end; ++s) {
    while (i < batch_.size() && (batch_[i].x != s->x || batch_[i].y != s->y)) ++i;
    if (i >= batch_.size() || !(alive_[i] & s->bit)) continue;
    const std::size_t gi = (static_cast<std::size_t>(s->y) * W + static_cast<std::size_t>(s->x)) * S +
                           static_cast<std::size_t>(std::countr_zero(s->bit));
    // A later translucent layer may have written a nearer depth meanwhile: keep the nearer one.
    if (pl.depth_test && !passes<float>(pl.depth_compare, s->z, depth[gi])) continue;
    depth[gi] = s->z;
    widen_tile_depth(s->z);
    isp.depth_buffer_write_bytes += ds_bytes;
    if (ctx_.rop) ctx_.rop->depth(s->x, s->y, std::countr_zero(s->bit), true);
  }
}

void Isp::rop_color_outputs(std::uint32_t prim_index, bool punch) {
  const DrawContext& d = ctx_.draws[ctx_.prims[prim_index].draw];
  const std::size_t outputs = std::min<std::size_t>(d.shader->color_outputs, ctx_.color_targets.size());
  // Blending and framebuffer fetch read the target before writing it.
  const bool read = d.pipeline->blend != BlendMode::Off || d.fetch_bytes > 0;
  for (std::size_t i = 0; i < batch_.size(); ++i) {
    const std::uint32_t mask = punch ? alive_[i] : batch_[i].mask & batch_[i].write;
    if (mask == 0) continue;
    for (std::size_t o = 0; o < outputs; ++o) ctx_.rop->color(o, batch_[i].x, batch_[i].y, mask, read);
  }
}

void Isp::flush(const std::vector<std::uint32_t>& prims, bool mid_tile, IspStats& isp, TspStats& tsp) {
  const auto L = static_cast<std::size_t>(layers_per_sample_);
  unresolved_layers_ = 0;  // every layer leaves the stacks
  bool resolves = false;
  std::uint64_t flushed = 0;
  // Shade primitive by primitive, in submission order (a sample's layers were pushed in that
  // order, so each sample's layers are shaded bottom first); raster order within each: the order
  // the layers were pushed in, less those a later opaque sample hid. A primitive's pending
  // samples are merged into its batch of pixels as they are found (consecutive samples of one
  // pixel share a ShadePixel); the batch is shaded when the next primitive's first sample comes.
  // (Shading reads none of the stacks: the pending test of a later layer is not disturbed.)
  batch_.clear();
  flush_samples_.clear();  // the current primitive's samples, kept for a punch-through's depth writes
  std::uint32_t group_tag = kNoTag;
  bool group_punch = false, group_unresolved = false;
  const auto shade_group = [&] {
    // A mid-tile flush waits for the alpha test of the unresolved punch-through layers (their
    // shaders; the layers beneath need not finish first: only the color writes are ordered).
    const bool waited = mid_tile && group_punch && group_unresolved;
    const std::uint64_t alu0 = tsp.fragment_alu_ops.value(), texels0 = tsp.texels_filtered.value();
    tsp_.shade(group_tag, batch_, group_punch ? &alive_ : nullptr, tsp);
    if (waited) {
      isp.resolve_wait_alu_ops += tsp.fragment_alu_ops.value() - alu0;
      isp.resolve_wait_texels += tsp.texels_filtered.value() - texels0;
    }
    if (group_punch) write_punch_depth(flush_samples_.data(), flush_samples_.data() + flush_samples_.size(), isp);
  };
  for (const PushedLayer& pl : pushed_) {
    if (layers_hidden_ && (pl.slot >= depth_of_[pl.li] || layers_[pl.li * L + pl.slot].list_pos != pl.sample.tag)) continue;
    const std::uint32_t tag = prims[pl.sample.tag];
    if (tag != group_tag) {
      if (!batch_.empty()) shade_group();
      batch_.clear();
      flush_samples_.clear();
      group_tag = tag;
      group_punch = ctx_.prims[tag].hsr == HsrClass::PunchThrough;
      group_unresolved = pl.sample.unresolved;
    }
    ++flushed;
    resolves = resolves || pl.sample.unresolved;
    add_to_batch(pl.sample, batch_);
    if (group_punch) {
      flush_samples_.push_back(pl.sample);
      flush_samples_.back().tag = tag;
    }
  }
  if (!batch_.empty()) shade_group();
  for (const PushedLayer& pl : pushed_) depth_of_[pl.li] = 0;
  pushed_.clear();
  layers_hidden_ = false;
  if (flushed == 0) return;
  if (mid_tile) {
    ++isp.tag_flushes;
    isp.tag_flushed_samples += flushed;
  }
  isp.tag_buffer_read_bytes += flushed * static_cast<std::uint64_t>(ctx_.hw->isp.tag_bits / 8);
  if (mid_tile && resolves) ++isp.resolve_flushes;
}

void Isp::widen_tile_depth(float z) {
  if (!tile_depth_known_) return;
  // Written as negations so that a NaN makes the bounds NaN (no comparison then passes).
  if (!(z >= tile_depth_.lo)) tile_depth_.lo = z;
  if (!(z <= tile_depth_.hi)) tile_depth_.hi = z;
}

bool Isp::fails_depth_everywhere(const Primitive& p, const PixelRect& rect, std::uint32_t depth_outcomes) {
  const bool fails_below = (depth_outcomes & 0x02u) == 0;  // an incoming depth less than the stored fails
  const bool fails_above = (depth_outcomes & 0x10u) == 0;  // greater fails
  if (!fails_below && !fails_above) return false;
  if (!tile_depth_known_) {
    const int S = ctx_.pattern.count;
    const auto W = static_cast<std::size_t>(ctx_.viewport.width_px);
    const float* depth = ctx_.depth->depth.data();
    float lo = std::numeric_limits<float>::infinity(), hi = -lo;
    bool nan = false;
    for (int y = rect.y0; y < rect.y1; ++y) {
      const float* row = depth + (static_cast<std::size_t>(y) * W + static_cast<std::size_t>(rect.x0)) * static_cast<std::size_t>(S);
      const std::size_t n = static_cast<std::size_t>(rect.width()) * static_cast<std::size_t>(S);
      for (std::size_t i = 0; i < n; ++i) {
        lo = std::min(lo, row[i]);
        hi = std::max(hi, row[i]);
        nan |= row[i] != row[i];
      }
    }
    const float q = std::numeric_limits<float>::quiet_NaN();
    tile_depth_ = nan ? SampleDepthBounds{q, q} : SampleDepthBounds{lo, hi};
    tile_depth_known_ = true;
  }
  const SampleDepthBounds z = depth_bounds_in_rect(p.setup, rect, ctx_.pattern);
  // Every covered sample's depth lies in [z.lo, z.hi] and every stored depth in the tile's
  // bounds: strictly below them, each test's outcome is "less"; strictly above, "greater".
  return (fails_below && z.hi < tile_depth_.lo) || (fails_above && z.lo > tile_depth_.hi);
}

namespace {
/// How many primitives of a tile's list ahead the ISP asks for its record: the records of a
/// tile's list are scattered over the render's table (a host cache miss each), and a few
/// primitives' rasterisation is about the time such a miss takes.
constexpr std::uint32_t kPrefetchAhead = 4;
/// Asks the host's caches for the part of a primitive record the ISP reads (setup, draw, hsr).
inline void prefetch_isp_fields(const Primitive& p) {
  const char* a = reinterpret_cast<const char*>(&p);
  for (std::size_t off = 0; off < offsetof(Primitive, world); off += 64) __builtin_prefetch(a + off);
}
}  // namespace

void Isp::begin_tile(const PixelRect& rect, TileFrame& tf) {
  const int S = ctx_.pattern.count;
  tf.rect = rect;
  tf.W = ctx_.viewport.width_px;
  tf.S = S;
  tf.rw = rect.width();
  const std::size_t tile_samples = static_cast<std::size_t>(tf.rw) * static_cast<std::size_t>(rect.height()) * S;
  layers_per_sample_ = static_cast<int>(std::max<std::int64_t>(1, ctx_.hw->isp.tag_buffers));
  tf.L = layers_per_sample_;
  if (ctx_.defer_shading) {
    depth_of_.assign(tile_samples, 0);
    layers_.resize(tile_samples * static_cast<std::size_t>(tf.L));
    pushed_.clear();
    layers_hidden_ = false;
    unresolved_layers_ = 0;
    // A primitive has at most one candidate per tile sample: written without growth checks.
    if (candidates_.size() < tile_samples) candidates_.resize(tile_samples);
  }
  // tbr / imr with isp.early_z=0: every rasterised sample is shaded, the tests decide the writes.
  tf.late_z = !ctx_.defer_shading && ctx_.hw->isp.early_z == 0;
  // tbr: forward pixel kill queues this many primitives between early-Z and shading (it kills
  // early-Z survivors: nothing to kill when the tests come after the shader).
  tf.fpk_window = (!ctx_.defer_shading && !ctx_.framebuffer_in_dram && !tf.late_z)
                      ? static_cast<std::size_t>(std::max<std::int64_t>(0, ctx_.hw->isp.forward_pixel_kill_window))
                      : 0;
  if (tf.fpk_window > 0) {
    kill_seq_.assign(tile_samples, 0);
    queue_.clear();
  }
  tile_depth_known_ = false;
  tf.ds_bytes = static_cast<std::uint64_t>(ctx_.hw->isp.depth_stencil_bytes_per_sample);
  tf.tag_bytes = static_cast<std::uint64_t>(ctx_.hw->isp.tag_bits / 8);
  AttachmentImage* depth_img = ctx_.depth;
  tf.depth = depth_img ? depth_img->depth.data() : nullptr;
  tf.stencil = depth_img ? depth_img->stencil.data() : nullptr;
  tf.has_stencil = depth_img && has_stencil(depth_img->format);
  tf.overdraw = ctx_.images->counters.images() ? ctx_.images->counters.rasterised_samples.data() : nullptr;
}

Isp::PrimitiveVisit Isp::begin_primitive(const TileFrame& tf, std::uint32_t list_pos, std::uint32_t prim_index) const {
  const Primitive& p = ctx_.prims[prim_index];
  const PipelineState& pl = *ctx_.draws[p.draw].pipeline;
  PrimitiveVisit v{&p, &pl};
  v.prim_index = prim_index;
  v.list_pos = list_pos;
  v.depth_on = tf.depth && pl.depth_test;
  v.write_on = tf.depth && pl.depth_write;
  v.stencil_on = tf.has_stencil && pl.stencil_test;
  v.ref = static_cast<std::uint8_t>(pl.stencil_ref & 0xffu);
  v.early_write = !ctx_.defer_shading && p.hsr == HsrClass::Opaque && v.write_on;
  v.depth_outcomes = passing_outcomes(pl.depth_compare);
  v.layered = p.hsr != HsrClass::Opaque;
  v.open_verdicts = v.depth_on && unresolved_layers_ != 0;  // a punch-through may change a verdict
  return v;
}

void Isp::render_tile(const PixelRect& rect, const std::vector<std::uint32_t>& prims, IspStats& isp, TspStats& tsp) {
  TileFrame tf;
  begin_tile(rect, tf);
  ++isp.tiles_rendered;
  std::uint32_t arrivals = 0;  // tbr forward pixel kill: primitives queued in the tile so far
  RenderOutputUnit* const rop = ctx_.rop;  // imr: depth and colour go through the ROP caches
  for (std::uint32_t list_pos = 0; list_pos < prims.size(); ++list_pos) {
    const std::uint32_t prim_index = prims[list_pos];
    if (list_pos + kPrefetchAhead < prims.size()) prefetch_isp_fields(ctx_.prims[prims[list_pos + kPrefetchAhead]]);
    PrimitiveVisit v = begin_primitive(tf, list_pos, prim_index);
    ++isp.primitives_fetched;
    if (rop) rop->next_primitive();
    pending_.clear();
    rasterised_.clear();
    const bool defer = ctx_.defer_shading;
    if (defer && v.depth_on && !v.stencil_on && !v.open_verdicts && rop == nullptr &&
        fails_depth_everywhere(*v.p, rect, v.depth_outcomes)) {
      count_hidden_primitive(tf, v, isp);
      continue;
    }
    if (defer && !v.stencil_on && !v.open_verdicts && rop == nullptr && !ctx_.reference_loops) {
      rasterize_deferred(tf, v);
    } else {
      rasterize_general(tf, v, isp);
    }
    isp.samples_rasterised += v.rasterised;
    isp.depth_buffer_read_bytes += tf.ds_bytes * v.depth_reads;
    isp.depth_test_failed_samples += v.final_fails;
    if (defer) {
      // (Final fails need no flush: nothing of them is pending.)
      if (v.n_cand > 0) take_verdicts(tf, v, prims, isp, tsp);
    } else {
      shade_in_submission_order(tf, v, arrivals, isp, tsp);
    }
  }
  if (ctx_.defer_shading) flush(prims, false, isp, tsp);
  while (!queue_.empty()) shade_queued(rect, isp, tsp);
}

void Isp::count_hidden_primitive(const TileFrame& tf, const PrimitiveVisit& v, IspStats& isp) {
  // Every sample it covers fails the depth test for good (the tile's depth bounds say so):
  // counted span by span, as the per-sample loop would count them; nothing is pending.
  std::uint64_t n = 0;
  if (std::uint32_t* const overdraw = tf.overdraw) {
    const int W = tf.W;
    rasterize_in_rect(v.p->setup, tf.rect, ctx_.pattern, [&](int x, int y, std::uint32_t mask, const float*) {
      const auto k = bit_count(mask);
      overdraw[static_cast<std::size_t>(y) * static_cast<std::size_t>(W) + static_cast<std::size_t>(x)] += k;
      n += k;
    });
  } else {
    n = covered_samples(v.p->setup, tf.rect, ctx_.pattern);
  }
  isp.samples_rasterised += n;
  isp.depth_buffer_read_bytes += tf.ds_bytes * n;
  isp.depth_test_failed_samples += n;
}

void Isp::rasterize_deferred(const TileFrame& tf, PrimitiveVisit& v) {
  // The common deferred case (no stencil, no punch-through verdict open, no ROP): the general
  // per-sample loop with its branches on those taken out, the same counts, overdraw counters and
  // candidates. A failed depth test is final, so every candidate passes, and every rasterised
  // sample read the depth: the reads and the fails follow from the counts. (Each visit counts
  // into locals of its own, written back once: the tile's counters are captured by reference,
  // and the visitor would otherwise load and store them per sample.)
  const Primitive& p = *v.p;
  const PipelineState& pl = *v.pl;
  const PixelRect& rect = tf.rect;
  const int W = tf.W, S = tf.S, rw = tf.rw, L = tf.L, x0 = rect.x0, y0 = rect.y0;
  const std::uint32_t depth_outcomes = v.depth_outcomes;
  const bool depth_on = v.depth_on, layered = v.layered;
  const float* const depth = tf.depth;
  std::uint32_t* const overdraw = tf.overdraw;
  const std::uint8_t* const stack_depth = depth_of_.data();
  Candidate* const cand = candidates_.data();
  std::uint64_t rasterised = 0, depth_reads = 0, final_fails = 0;
  bool conflict = false;
  std::size_t n_cand = 0;
  auto visit = [&]<bool kDepthTest, bool kOverdraw>() {
    std::uint64_t counted = 0;
    bool full_stack = false;
    Candidate* out = cand + n_cand;
    rasterize_in_rect(p.setup, rect, ctx_.pattern, [&](int x, int y, std::uint32_t mask, const float* z) TBDR_ISP_INLINE_VISITOR {
      const std::size_t pixel = static_cast<std::size_t>(y) * static_cast<std::size_t>(W) + static_cast<std::size_t>(x);
      const std::size_t lbase = (static_cast<std::size_t>(y - y0) * rw + static_cast<std::size_t>(x - x0)) * S;
      const auto covered = bit_count(mask);
      counted += covered;
      if constexpr (kOverdraw) overdraw[pixel] += covered;
      for (std::uint32_t m = mask; m != 0; m &= m - 1) {
        const int s = std::countr_zero(m);
        if constexpr (kDepthTest) {
          if (!passes_outcomes(depth_outcomes, z[s], depth[pixel * static_cast<std::size_t>(S) + static_cast<std::size_t>(s)])) continue;
        }
        const auto li = static_cast<std::uint32_t>(lbase + static_cast<std::size_t>(s));
        full_stack = full_stack || (layered && stack_depth[li] >= L);
        *out++ = {li, x, y, 1u << s, z[s], true};
      }
    });
    rasterised += counted;
    conflict = conflict || full_stack;
    n_cand = static_cast<std::size_t>(out - cand);
  };
  // One sample per pixel: the same visit a row's run at a time (the depth test reads the
  // run's stored depths in a row; no coverage mask to walk).
  auto visit_spans = [&]<bool kDepthTest, bool kOverdraw, DepthTest kTest = DepthTest::ByOutcomes>() {
    std::uint64_t counted = 0;
    bool full_stack = false;
    Candidate* out = cand + n_cand;
    rasterize_spans_1x(p.setup, rect, ctx_.pattern, [&](int y, int xa, int xb, const float* z) TBDR_ISP_INLINE_VISITOR {
      const std::size_t row = static_cast<std::size_t>(y) * static_cast<std::size_t>(W) + static_cast<std::size_t>(xa);
      const auto n = static_cast<std::uint32_t>(xb - xa);
      counted += n;
      if constexpr (kOverdraw) {
        for (std::uint32_t i = 0; i < n; ++i) overdraw[row + i] += 1;
      }
      const auto li0 = static_cast<std::uint32_t>((y - y0) * rw + (xa - x0));
      for (std::uint32_t i = 0; i < n; ++i) {
        if constexpr (kDepthTest) {
          if (!passes_depth<kTest>(depth_outcomes, z[i], depth[row + i])) continue;
        }
        const std::uint32_t li = li0 + i;
        if (layered) full_stack = full_stack || stack_depth[li] >= L;
        *out++ = {li, xa + static_cast<std::int32_t>(i), y, 1u, z[i], true};
      }
    });
    rasterised += counted;
    conflict = conflict || full_stack;
    n_cand = static_cast<std::size_t>(out - cand);
  };
  // A span's depth tests compiled as the pipeline's comparison (the common five).
  const auto tested_spans = [&]<bool kOverdraw>() {
    switch (pl.depth_compare) {
      case CompareOp::Less: return visit_spans.template operator()<true, kOverdraw, DepthTest::Less>();
      case CompareOp::LessEqual: return visit_spans.template operator()<true, kOverdraw, DepthTest::LessEqual>();
      case CompareOp::Equal: return visit_spans.template operator()<true, kOverdraw, DepthTest::Equal>();
      case CompareOp::Greater: return visit_spans.template operator()<true, kOverdraw, DepthTest::Greater>();
      case CompareOp::GreaterEqual: return visit_spans.template operator()<true, kOverdraw, DepthTest::GreaterEqual>();
      default: return visit_spans.template operator()<true, kOverdraw, DepthTest::ByOutcomes>();
    }
  };
  const bool spans = S == 1;
  if (depth_on) {
    if (overdraw) {
      spans ? tested_spans.template operator()<true>() : visit.template operator()<true, true>();
    } else {
      spans ? tested_spans.template operator()<false>() : visit.template operator()<true, false>();
    }
    depth_reads = rasterised;
    final_fails = rasterised - n_cand;
  } else if (overdraw) {
    spans ? visit_spans.template operator()<false, true>() : visit.template operator()<false, true>();
  } else {
    spans ? visit_spans.template operator()<false, false>() : visit.template operator()<false, false>();
  }
  v.rasterised = rasterised;
  v.depth_reads = depth_reads;
  v.final_fails = final_fails;
  v.conflict = conflict;
  v.n_cand = n_cand;
}

void Isp::rasterize_general(const TileFrame& tf, PrimitiveVisit& v, IspStats& isp) {
  // Every case: stencil, open punch-through verdicts, the ROP (imr), tbr's and imr's tests before
  // shading, and late Z. The tile state the per-sample loop reads, as locals it can keep in
  // registers (rasterising changes none of it).
  const Primitive& p = *v.p;
  const PipelineState& pl = *v.pl;
  const PixelRect& rect = tf.rect;
  const int W = tf.W, S = tf.S, rw = tf.rw, L = tf.L, x0 = rect.x0, y0 = rect.y0;
  const std::uint32_t prim_index = v.prim_index, depth_outcomes = v.depth_outcomes;
  const bool depth_on = v.depth_on, stencil_on = v.stencil_on, early_write = v.early_write, layered = v.layered;
  const bool open_verdicts = v.open_verdicts, defer = ctx_.defer_shading, late_z = tf.late_z;
  const std::uint8_t ref = v.ref;
  const std::uint64_t ds_bytes = tf.ds_bytes;
  float* const depth = tf.depth;
  std::uint8_t* const stencil = tf.stencil;
  std::uint32_t* const overdraw = tf.overdraw;
  const std::uint8_t* const stack_depth = depth_of_.data();
  const Layer* const stacks = layers_.data();
  Candidate* const cand = candidates_.data();
  RenderOutputUnit* const rop = ctx_.rop;
  std::uint64_t rasterised = 0, depth_reads = 0, final_fails = 0;
  bool conflict = false;
  std::size_t n_cand = 0;
  rasterize_in_rect(p.setup, rect, ctx_.pattern, [&](int x, int y, std::uint32_t mask, const float* z) TBDR_ISP_INLINE_VISITOR {
    const std::size_t pixel = static_cast<std::size_t>(y) * static_cast<std::size_t>(W) + static_cast<std::size_t>(x);
    const std::size_t lbase = (static_cast<std::size_t>(y - y0) * rw + static_cast<std::size_t>(x - x0)) * S;
    for (std::uint32_t m = mask; m != 0; m &= m - 1) {
      const int s = std::countr_zero(m);
      if (overdraw) ++overdraw[pixel];
      ++rasterised;
      if (late_z) rasterised_.push_back({prim_index, x, y, 1u << s, z[s], false});
      const std::size_t gi = pixel * static_cast<std::size_t>(S) + static_cast<std::size_t>(s);
      if (rop && (depth_on || stencil_on)) rop->depth(x, y, s, false);
      if (stencil_on) {
        if (!passes<std::uint8_t>(pl.stencil_compare, ref, stencil[gi])) {
          ++isp.stencil_test_failed_samples;
          stencil[gi] = apply_stencil(pl.stencil_fail_op, stencil[gi], ref);
          if (rop && pl.stencil_fail_op != StencilOp::Keep) rop->depth(x, y, s, true);
          continue;
        }
      }
      if (defer) {
        // The depth test's verdict may change if a flush resolves punch-through depth first:
        // the stencil ops that depend on it wait for the final verdict. With no unresolved
        // punch-through layer in the tile, no flush can change the depth buffer: a failed
        // test is final now (its stencil op applies at once; a re-test after a flush would
        // read the depth again and fail again, counted in final_fails).
        bool pass = true;
        if (depth_on) {
          ++depth_reads;
          pass = passes_outcomes(depth_outcomes, z[s], depth[gi]);
          if (!pass && !open_verdicts) {
            ++final_fails;
            if (stencil_on) stencil[gi] = apply_stencil(pl.stencil_depth_fail_op, stencil[gi], ref);
            continue;
          }
        }
        const auto li = static_cast<std::uint32_t>(lbase + static_cast<std::size_t>(s));
        if (!conflict) {
          const int n = stack_depth[li];
          conflict = layered && pass && n >= L;
          if (open_verdicts) {
            // The verdict is open when a punch-through layer's depth, if its alpha test keeps
            // the sample, would change it (either way: a greater test may pass only against it).
            const Layer* stack = stacks + static_cast<std::size_t>(li) * static_cast<std::size_t>(L);
            for (int k = 0; k < n && !conflict; ++k) {
              conflict = stack[k].unresolved && passes_outcomes(depth_outcomes, z[s], stack[k].z) != pass;
            }
          }
        }
        cand[n_cand++] = {li, x, y, 1u << s, z[s], pass};
        continue;
      }
      if (depth_on) {
        ++depth_reads;
        if (!passes_outcomes(depth_outcomes, z[s], depth[gi])) {
          ++isp.depth_test_failed_samples;
          if (stencil_on) stencil[gi] = apply_stencil(pl.stencil_depth_fail_op, stencil[gi], ref);
          if (rop && stencil_on && pl.stencil_depth_fail_op != StencilOp::Keep) rop->depth(x, y, s, true);
          continue;
        }
      }
      if (stencil_on) stencil[gi] = apply_stencil(pl.stencil_pass_op, stencil[gi], ref);
      pending_.push_back({prim_index, x, y, 1u << s, z[s], false});
      if (early_write) {
        depth[gi] = z[s];
        isp.depth_buffer_write_bytes += ds_bytes;
      }
      if (rop && (early_write || (stencil_on && pl.stencil_pass_op != StencilOp::Keep))) rop->depth(x, y, s, true);
    }
  });
  v.rasterised = rasterised;
  v.depth_reads = depth_reads;
  v.final_fails = final_fails;
  v.conflict = conflict;
  v.n_cand = n_cand;
}

void Isp::take_verdicts(const TileFrame& tf, const PrimitiveVisit& v, const std::vector<std::uint32_t>& prims, IspStats& isp,
                        TspStats& tsp) {
  // tbdr: the candidates' final verdicts (after a flush when a sample could not take the
  // primitive): stencil ops, and the passing samples become tags.
  const Primitive& p = *v.p;
  const PipelineState& pl = *v.pl;
  const int L = tf.L;
  const std::uint32_t list_pos = v.list_pos, depth_outcomes = v.depth_outcomes;
  const bool depth_on = v.depth_on, write_on = v.write_on, stencil_on = v.stencil_on, layered = v.layered;
  const bool conflict = v.conflict;
  const std::uint8_t ref = v.ref;
  const std::uint64_t ds_bytes = tf.ds_bytes, tag_bytes = tf.tag_bytes, final_fails = v.final_fails;
  float* const depth = tf.depth;
  std::uint8_t* const stencil = tf.stencil;
  Candidate* const cand = candidates_.data();
  const std::size_t n_cand = v.n_cand;
  const std::span<Candidate> candidates(cand, n_cand);
  if (conflict) {
    flush(prims, true, isp, tsp);
    if (depth_on) {
      // The flush wrote the punch-through depths: test again against them (the samples that
      // failed for good read the depth again too).
      isp.depth_buffer_read_bytes += ds_bytes * (final_fails + candidates.size());
      for (Candidate& c : candidates) {
        c.depth_pass = passes_outcomes(depth_outcomes, c.z, depth[tf.global_index(c.x, c.y, c.bit)]);
      }
    }
  }
  // Final verdicts: stencil ops, and the passing samples become tags.
  const bool unresolved = p.hsr == HsrClass::PunchThrough && write_on;
  const bool writes_depth_now = write_on && p.hsr != HsrClass::PunchThrough;
  std::uint64_t kept = 0, failed = 0, hidden = 0;
  // The stacks through pointers taken once and a stack's depth read into a register: a
  // store through a byte reference (the depth) may alias anything, and the compiler would
  // load the vectors' pointers and the counters again after each.
  std::uint8_t* const stack_depths = depth_of_.data();
  Layer* const stack_layers = layers_.data();
  for (const Candidate& c : candidates) {
    if (!c.depth_pass) {
      ++failed;
      if (stencil_on) {
        const std::size_t gi = tf.global_index(c.x, c.y, c.bit);
        stencil[gi] = apply_stencil(pl.stencil_depth_fail_op, stencil[gi], ref);
      }
      continue;
    }
    ++kept;
    if (stencil_on) {
      const std::size_t gi = tf.global_index(c.x, c.y, c.bit);
      stencil[gi] = apply_stencil(pl.stencil_pass_op, stencil[gi], ref);
    }
    std::uint32_t n = stack_depths[c.li];
    if (!layered) {
      hidden += n;  // every layer beneath is hidden: never shaded
      n = 0;
    }
    pushed_.push_back({{list_pos, c.x, c.y, c.bit, c.z, unresolved}, c.li, n});
    stack_layers[static_cast<std::size_t>(c.li) * static_cast<std::size_t>(L) + n] = {list_pos, c.z, unresolved};
    stack_depths[c.li] = static_cast<std::uint8_t>(n + 1);
    // Opaque and translucent depth is known now; punch-through depth waits for the alpha test.
    if (writes_depth_now) {
      depth[tf.global_index(c.x, c.y, c.bit)] = c.z;
      widen_tile_depth(c.z);
    }
  }
  isp.depth_test_failed_samples += failed;
  isp.hsr_removed_samples += hidden;
  layers_hidden_ = layers_hidden_ || hidden != 0;
  if (unresolved) unresolved_layers_ += kept;
  isp.tag_buffer_write_bytes += tag_bytes * kept;
  if (writes_depth_now) isp.depth_buffer_write_bytes += ds_bytes * kept;
  if (p.hsr == HsrClass::PunchThrough) isp.punch_through_samples += kept;
  if (p.hsr == HsrClass::Translucent) isp.translucent_samples += kept;
}

void Isp::shade_in_submission_order(const TileFrame& tf, const PrimitiveVisit& v, std::uint32_t& arrivals, IspStats& isp,
                                    TspStats& tsp) {
  // tbr / imr: shade in submission order.
  const Primitive& p = *v.p;
  const PipelineState& pl = *v.pl;
  const PixelRect& rect = tf.rect;
  const std::uint32_t prim_index = v.prim_index;
  const bool write_on = v.write_on, early_write = v.early_write, late_z = tf.late_z;
  const std::size_t fpk_window = tf.fpk_window;
  const std::uint64_t ds_bytes = tf.ds_bytes;
  float* const depth = tf.depth;
  RenderOutputUnit* const rop = ctx_.rop;
  if (late_z ? rasterised_.empty() : pending_.empty()) return;
  if (p.hsr == HsrClass::PunchThrough) isp.punch_through_samples += pending_.size();
  if (p.hsr == HsrClass::Translucent) isp.translucent_samples += pending_.size();
  const bool punch = p.hsr == HsrClass::PunchThrough;
  if (fpk_window > 0 && !punch) {
    // Forward pixel kill: queue the samples; an opaque, depth-writing, unblended primitive marks
    // its samples, killing what earlier primitives still queued there.
    const DrawContext& d = ctx_.draws[p.draw];
    const std::uint32_t seq = ++arrivals;
    if (early_write && pl.blend == BlendMode::Off) {
      for (const PendingSample& ps : pending_) kill_seq_[tile_sample(rect, ps)] = seq;
    }
    queue_.push_back({seq, prim_index, d.shader->pls == PlsAccess::None && d.fetch_bytes == 0, pending_});
    if (p.hsr == HsrClass::Translucent && write_on) {
      for (const PendingSample& ps : pending_) {
        depth[tf.global_index(ps.x, ps.y, ps.bit)] = ps.z;
        isp.depth_buffer_write_bytes += ds_bytes;
      }
    }
    while (queue_.size() > fpk_window) shade_queued(rect, isp, tsp);
    return;
  }
  // A punch-through primitive's depth waits for its alpha test: what is queued is shaded first.
  while (!queue_.empty()) shade_queued(rect, isp, tsp);
  if (late_z) {
    // Late-Z: the shader runs on every rasterised sample; only those that passed the tests
    // (pending_, a subsequence of rasterised_ in the same raster order) write their colour.
    build_batch(rasterised_.data(), rasterised_.data() + rasterised_.size(), batch_);
    std::size_t i = 0;
    for (ShadePixel& px : batch_) px.write = 0;
    for (const PendingSample& ps : pending_) {
      while (batch_[i].x != ps.x || batch_[i].y != ps.y) ++i;
      batch_[i].write |= ps.bit;
    }
  } else {
    build_batch(pending_.data(), pending_.data() + pending_.size(), batch_);
  }
  tsp_.shade(prim_index, batch_, punch ? &alive_ : nullptr, tsp);
  if (rop) rop_color_outputs(prim_index, punch);
  if (punch) write_punch_depth(pending_.data(), pending_.data() + pending_.size(), isp);
  if (p.hsr == HsrClass::Translucent && write_on) {
    for (const PendingSample& ps : pending_) {
      depth[tf.global_index(ps.x, ps.y, ps.bit)] = ps.z;
      isp.depth_buffer_write_bytes += ds_bytes;
      if (rop) rop->depth(ps.x, ps.y, std::countr_zero(ps.bit), true);
    }
  }
}

std::size_t Isp::tile_sample(const PixelRect& rect, const PendingSample& ps) const {
  const auto S = static_cast<std::size_t>(ctx_.pattern.count);
  const auto col = static_cast<std::size_t>(ps.x - rect.x0), row = static_cast<std::size_t>(ps.y - rect.y0);
  return (row * static_cast<std::size_t>(rect.width()) + col) * S + static_cast<std::size_t>(std::countr_zero(ps.bit));
}

void Isp::shade_queued(const PixelRect& rect, IspStats& isp, TspStats& tsp) {
  Queued q = std::move(queue_.front());
  queue_.pop_front();
  std::size_t kept = 0;
  for (const PendingSample& ps : q.samples) {
    if (q.killable && kill_seq_[tile_sample(rect, ps)] > q.seq) {
      ++isp.forward_pixel_kill_samples;
      continue;
    }
    q.samples[kept++] = ps;
  }
  if (kept == 0) return;
  build_batch(q.samples.data(), q.samples.data() + kept, batch_);
  tsp_.shade(q.prim, batch_, nullptr, tsp);
}

}  // namespace tbdr
