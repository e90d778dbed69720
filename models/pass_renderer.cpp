#include "models/pass_renderer.hpp"

#include <algorithm>
#include <chrono>
#include <numeric>
#include <utility>

#include "kernel/thread_pool.hpp"
#include "models/rop.hpp"
#include "models/work_feed.hpp"

namespace tbdr {

std::vector<int> tile_order(int tiles_x, int tiles_y, TileOrder order) {
  // Bits of each tile coordinate interleaved into a Morton key: 16 bits order 65536 tiles per
  // axis, far more than any frame has, in a 32-bit key.
  constexpr int kMortonBitsPerAxis = 16;
  std::vector<int> out;
  out.reserve(static_cast<std::size_t>(tiles_x) * static_cast<std::size_t>(tiles_y));
  if (order == TileOrder::Morton) {
    std::vector<std::pair<std::uint64_t, int>> keyed;
    for (int ty = 0; ty < tiles_y; ++ty) {
      for (int tx = 0; tx < tiles_x; ++tx) {
        std::uint64_t key = 0;
        for (int b = 0; b < kMortonBitsPerAxis; ++b) {
          key |= (static_cast<std::uint64_t>((tx >> b) & 1) << (2 * b)) | (static_cast<std::uint64_t>((ty >> b) & 1) << (2 * b + 1));
        }
        keyed.push_back({key, ty * tiles_x + tx});
      }
    }
    std::sort(keyed.begin(), keyed.end());
    for (const auto& k : keyed) out.push_back(k.second);
  } else {
    for (int t = 0; t < tiles_x * tiles_y; ++t) out.push_back(t);
  }
  return out;
}

struct PassRenderer::TileWorker {
  explicit TileWorker(RenderContext& ctx) : tsp(ctx), isp(ctx, tsp) { tsp.bind_outputs(&texture_lines, &dram); }
  std::vector<std::uint64_t> texture_lines;  ///< the current tile's texture lines, as the TSP appends them
  DramTraffic dram;                          ///< what the current tile booked
  Tsp tsp;
  Isp isp;
};

PassRenderer::PassRenderer(RenderContext& ctx, const HwConfig& frame_hw, PassStats& stats, DramTraffic& dram,
                           CommandWork& cw, ThreadPool& pool)
    : hw_(pass_hw(frame_hw, ctx)), ctx_(bind(ctx, hw_)), stats_(stats), dram_(dram), cw_(&cw), pool_(pool),
      geometry_(hw_, ctx.scene, *ctx.lights, ctx.camera, ctx.viewport),
      tiler_(hw_, ctx.viewport, ctx.pattern),
      tile_memory_(ctx, stats.tile_memory),
      order_(tile_order(tiler_.tiles_x(), tiler_.tiles_y(), hw_.tiling.tile_order)),
      resumed_(static_cast<std::size_t>(tiler_.tile_count()), 0) {
  // The render area: the draws are scissored to it, and the render has only the tiles that
  // overlap it (a pass at its own size, as a shadow map or a blur target).
  if (ctx_.render_area.empty()) ctx_.render_area = {0, 0, ctx_.viewport.width_px, ctx_.viewport.height_px};
  geometry_.set_render_area(ctx_.render_area);
  tiler_.set_render_area(ctx_.render_area);
  std::erase_if(order_, [this](int t) { return !tiler_.in_render_area(t); });
  // After tile_memory_: it points ctx.pls at the pass's pixel local storage, which the TSPs read.
  for (unsigned w = 0; w < pool_.size(); ++w) workers_.push_back(std::make_unique<TileWorker>(ctx_));
  geometry_.use_pool(&pool_);  // binning sets up on the pool when it is free (not while tiles render)
  // The pass's framebuffer layout, known before any tile renders (FrameAddressMap places it then).
  // The first tile is never clipped more than another.
  cw_->tile_slot_bytes = tile_memory_.tile_slot_bytes(tiler_.tile_rect(0));
  cw_->partial_slot_bytes = tile_memory_.partial_slot_bytes(tiler_.tile_rect(0));
  cw_->tile_slots = static_cast<std::uint64_t>(tiler_.tile_count());
}

bool PassRenderer::layout_known_at_start() const {
  // A split render may leave the rest of the pass over budget: it spills then.
  return !ctx_.rop && tile_memory_.spill_fraction() <= 0.0 && tile_memory_.split_draw() < 0;
}

void PassRenderer::publish_to(WorkFeed& feed) {
  if (!layout_known_at_start()) throw std::logic_error("PassRenderer::publish_to: the pass's layout is known only at its end");
  cw_ = &feed.open(std::move(*cw_));
  feed_ = &feed;
  feed_command_ = feed.last_opened();
}

PassRenderer::~PassRenderer() = default;

void PassRenderer::run() {
  bin();
  finish();
}

void PassRenderer::bin() {
  for (std::uint32_t i = 0; i < ctx_.draws.size(); ++i) {
    if (!ctx_.rop && static_cast<int>(i) == tile_memory_.split_draw()) {
      // pls.over_budget = split_render: the driver ends the render at this subpass boundary.
      render(true);
      tile_memory_.begin_split_render(ctx_.draws);
    }
    geometry_.run_draw(ctx_.draws[i], i, *this, ctx_.object_lights, stats_.geometry, dram_);
  }
  if (ctx_.rop) {
    render_batch(true);  // the last batch (also when empty: the pass's clears, resolves and the ROP flush)
    cw_->renders.push_back(std::move(immediate_));
  } else {
    prepare_render(false);
  }
}

void PassRenderer::start_finish() {
  if (!ctx_.rop) start_tiles(false);
}

void PassRenderer::finish() {
  if (!ctx_.rop) {
    if (!tiles_started_) start_tiles(false);
    join_tiles();
  }
  // A spilling pass's spill slot: the most any tile render spilled, known now that all did (a
  // pass published as it goes spills nothing, and the feed's reader may be reading its fields).
  if (feed_ == nullptr) {
    for (const RenderWork& r : cw_->renders) {
      for (const TileWork& t : r.tiles) cw_->spill_slot_bytes = std::max({cw_->spill_slot_bytes, t.spill_read_bytes, t.spill_write_bytes});
    }
  }
}

bool PassRenderer::tiles_touched(const Primitive& p, std::vector<int>& tiles) const {
  if (ctx_.rop) return false;
  tiler_.touched_tiles(p, tiles);
  return true;
}

void PassRenderer::accept(const Primitive& p, const VertexKeys& keys, std::optional<std::span<const int>> tiles) {
  Primitive& taken = ctx_.prims.emplace_back(p);
  taken.id = ctx_.frame_prim_base++;
  if (ctx_.rop) {
    if (ctx_.prims.size() >= static_cast<std::size_t>(hw_.imr.primitives_per_batch)) render_batch(false);
    return;
  }
  switch (tiler_.bin(static_cast<std::uint32_t>(ctx_.prims.size() - 1), taken, keys, stats_.tiler, tiles)) {
    case BinResult::Binned: return;
    case BinResult::NoSample: ctx_.prims.pop_back(); return;  // touches no tile: no tile reads it
    case BinResult::Full: break;
  }
  const Primitive held = ctx_.prims.back();
  ctx_.prims.pop_back();
  ++stats_.tiler.partial_renders;
  geometry_.settle();  // the next window's set-up leaves the pool to the tiles
  render(true);
  ctx_.prims.push_back(held);
  tiler_.bin(0, ctx_.prims.back(), keys, stats_.tiler, tiles);  // binned: it touched a tile, and the buffer is empty
}

/// imr: no binning. The draws' primitives go down the pipeline in submission order, in batches
/// of imr.primitives_per_batch, each rasterised, depth tested and shaded over the whole frame as
/// it arrives, its depth and colour through the ROP caches: one render whose "tiles" are the
/// batches (FrameWork::immediate), each carrying its own geometry work. The batches share the
/// ROP caches in order: they render one after another, on the first worker.
void PassRenderer::render_batch(bool last) {
  batch_indices_.resize(ctx_.prims.size());
  std::iota(batch_indices_.begin(), batch_indices_.end(), 0u);
  TileWork tw = merge(render_tile(*workers_[0], 0, ctx_.render_area, batch_indices_, false, first_batch_, last));
  tw.geometry = binning_since_last_render();
  immediate_.tiles.push_back(std::move(tw));
  first_batch_ = false;
  ctx_.prims.clear();
}

HwConfig PassRenderer::pass_hw(const HwConfig& frame_hw, const RenderContext& ctx) {
  HwConfig hw = frame_hw;
  if (ctx.framebuffer_in_dram) {
    hw.tiling.tile_width = ctx.viewport.width_px;
    hw.tiling.tile_height = ctx.viewport.height_px;
    hw.tiling.pb_capacity_bytes = std::int64_t{1} << 62;
  }
  return hw;
}

RenderContext& PassRenderer::bind(RenderContext& ctx, const HwConfig& hw) {
  ctx.hw = &hw;
  return ctx;
}

BinningWork PassRenderer::binning_since_last_render() {
  const GeometryStats g = stats_.geometry - geometry_base_;
  const TilerStats b = stats_.tiler - tiler_base_;
  BinningWork w;
  w.vertices_shaded = g.vertices_shaded.value();
  w.vertex_alu_ops = g.vertex_alu_ops.value();
  w.vertex_fetch_bytes = g.vertex_fetch_bytes.value();
  w.index_fetch_bytes = g.index_fetch_bytes.value();
  w.primitives_in = g.primitives_in.value();
  w.primitives_binned = b.primitives_binned.value();
  w.tile_references = b.tile_references.value();
  geometry_base_ = stats_.geometry;
  tiler_base_ = stats_.tiler;
  return w;
}

AttachmentImage* PassRenderer::allocate_surfaces() {
  std::uint32_t outputs = 0;
  for (const DrawContext& d : ctx_.draws) outputs = std::max(outputs, d.shader->color_outputs);
  outputs = std::min<std::uint32_t>(outputs, static_cast<std::uint32_t>(ctx_.color_targets.size()));
  for (std::uint32_t o = 0; o < outputs; ++o) {
    AttachmentImage* t = ctx_.color_targets[o];
    if (t->usage == AttachmentUsage::Color) continue;
    // The TSP stores a fragment's surface in the first non-colour target among its outputs: with
    // the targets in one order for every draw, this one.
    if (!t->surface_valid.empty()) return nullptr;
    if (t->keeps_surface) t->surface.assign(t->sample_count, ctx_.colour);
    t->surface_valid.assign(t->sample_count, 0);
    return t;
  }
  return nullptr;
}

void PassRenderer::release_unwritten_surfaces(AttachmentImage* fresh) {
  if (fresh == nullptr) return;
  if (std::find(fresh->surface_valid.begin(), fresh->surface_valid.end(), std::uint8_t{1}) != fresh->surface_valid.end()) return;
  fresh->surface.release();
  fresh->surface_valid = {};
}

void PassRenderer::render(bool partial) {
  prepare_render(partial);
  render_tiles(partial);
}

void PassRenderer::prepare_render(bool partial) {
  RenderWork& rw = cw_->renders.emplace_back();
  rw.partial = partial;
  rw.binning = binning_since_last_render();
  DramTraffic pb;
  tiler_.finish_render(stats_.tiler, pb);
  if (!ctx_.framebuffer_in_dram) {
    dram_ += pb;
    rw.binning.pb_write_bytes = pb.writes(DramClass::ParameterBuffer);
  }
  jobs_.clear();
  for (int t : order_) {
    if (partial && tiler_.tile_primitives(t).empty()) continue;  // untouched: nothing to render yet
    for (const PixelRect& r : tile_memory_.strips(intersect(tiler_.tile_rect(t), ctx_.render_area))) jobs_.push_back({t, r});
  }
  // Before the next pass is set up: its draws may read the surfaces this one stores.
  fresh_ = allocate_surfaces();
  rw.tiles.reserve(jobs_.size());  // tiles published to the feed must not move
  if (feed_) feed_->publish_render(feed_command_, jobs_.size());
}

void PassRenderer::render_tiles(bool partial) {
  start_tiles(partial);
  join_tiles();
}

void PassRenderer::start_tiles(bool partial) {
  if (before_tiles_) {
    const std::function<void()> fn = std::move(before_tiles_);
    before_tiles_ = nullptr;
    fn();
  }
  RenderWork& rw = cw_->renders.back();
  // The pass before it, ended by before_tiles, may have released the store its tiles did not
  // write: this pass's shaders store into a new one then, as when it ended before this one began.
  running_fresh_ = fresh_ != nullptr ? fresh_ : allocate_surfaces();
  fresh_ = nullptr;
  running_partial_ = partial;
  tiles_started_ = true;
  const std::size_t n = jobs_.size();
  results_.clear();
  results_.resize(n);
  rendered_.assign(n, 0);
  merged_ = 0;
  tiles_start_ = std::chrono::steady_clock::now();
  pool_.start(n, [this, &rw, partial, n](std::size_t i, unsigned w) {
    const TileJob& j = jobs_[i];
    results_[i] = render_tile(*workers_[w], j.tile, j.rect, tiler_.tile_primitives(j.tile), partial);
    // Merged in dispatch order as soon as every tile before it is: whichever thread finishes the
    // tile a run of finished ones waited for merges them, and publishes them once it holds no
    // lock: publishing wakes the timing model, which may preempt this thread on its core, and a
    // lock held then would stall the other threads until the timing model yields the core.
    std::size_t ready = 0;
    {
      std::lock_guard lock(merge_mutex_);
      rendered_[i] = 1;
      const std::size_t before = merged_;
      for (; merged_ < n && rendered_[merged_] != 0; ++merged_) rw.tiles.push_back(merge(std::move(results_[merged_])));
      if (merged_ > before) ready = merged_;
    }
    if (feed_ && ready > 0) feed_->publish_tiles(feed_command_, ready);
  });
}

void PassRenderer::join_tiles() {
  pool_.join();
  tiles_started_ = false;
  tile_seconds_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - tiles_start_).count();
  release_unwritten_surfaces(running_fresh_);
  running_fresh_ = nullptr;
  results_.clear();
  if (running_partial_) {
    for (const TileJob& j : jobs_) resumed_[static_cast<std::size_t>(j.tile)] = 1;
  }
  tiler_.reset();
  ctx_.prims.clear();
}

TileWork PassRenderer::merge(TileResult&& r) {
  stats_.isp += r.isp;
  stats_.tsp += r.tsp;
  stats_.tile_memory += r.tile_memory;
  stats_.tiler.pb_bytes_read += r.pb_bytes_read;
  dram_ += r.dram;
  return std::move(r.work);
}

PassRenderer::TileResult PassRenderer::render_tile(TileWorker& w, int t, const PixelRect& r,
                                                   const std::vector<std::uint32_t>& prims, bool partial, bool begin,
                                                   bool end) {
  TileResult out;
  DramTraffic& dram = w.dram;  // the tile's traffic, from zero (the TSP books image reads here too)
  dram = DramTraffic{};
  w.texture_lines.clear();
  if (begin) tile_memory_.begin_tile(r, resumed_[static_cast<std::size_t>(t)] != 0, dram, out.tile_memory);
  const DramTraffic loaded = dram;
  w.isp.render_tile(r, prims, out.isp, out.tsp);
  const DramTraffic shaded = dram;  // what the shaders read from stored images (reads=)
  const IspStats& tile_isp = out.isp;
  const TspStats& tile_tsp = out.tsp;
  DramTraffic spill;
  tile_memory_.spill(tile_tsp.tile_buffer_read_bytes.value(), tile_tsp.tile_buffer_write_bytes.value(), spill,
                     out.tile_memory);
  if (end) tile_memory_.end_tile(r, partial, dram, out.tile_memory);
  TileWork& tw = out.work;
  tw.tile_x = t % tiler_.tiles_x();
  tw.tile_y = t / tiler_.tiles_x();
  tw.rect = r;
  for (std::size_t c = 0; c < kDramClassCount; ++c) {
    tw.image_read_bytes[c] = shaded.read_bytes[c] - loaded.read_bytes[c];
    tw.load_bytes[c] = dram.read_bytes[c] - tw.image_read_bytes[c];
    tw.store_bytes[c] = dram.write_bytes[c];
  }
  tw.primitives = tile_isp.primitives_fetched.value();
  tw.samples = tile_isp.samples_rasterised.value();
  tw.invocations = tile_tsp.shader_invocations.value();
  tw.quads = tile_tsp.shaded_quads.value();
  tw.idle_quads = tile_tsp.idle_quads.value();
  tw.alu_ops = tile_tsp.fragment_alu_ops.value();
  tw.texels = tile_tsp.texels_filtered.value();
  tw.isp_wait_alu_ops = tile_isp.resolve_wait_alu_ops.value();
  tw.isp_wait_texels = tile_isp.resolve_wait_texels.value();
  tw.texture_line_accesses = tile_tsp.texture_line_accesses.value();
  std::sort(w.texture_lines.begin(), w.texture_lines.end());
  tw.texture_lines.assign(w.texture_lines.begin(), std::unique(w.texture_lines.begin(), w.texture_lines.end()));
  out.tsp.texture_tile_lines += tw.texture_lines.size();
  // The footprint is what the texture unit requests (before the texture cache), booked like
  // the parameter buffer reads: after the tile's loads and stores were taken from `dram`.
  dram.read(DramClass::Textures, tw.texture_lines.size() * static_cast<std::uint64_t>(hw_.cache.texture.line_bytes));
  tw.spill_read_bytes = spill.reads(DramClass::Spill);
  tw.spill_write_bytes = spill.writes(DramClass::Spill);
  // The spilled share of the shaders' tile-buffer accesses goes to memory (spill reads = the
  // spilled share of the reads + the read-back of the spilled writes) on top of passing the USC's
  // pixel data path: a memory tile buffer is reached by the shader's own loads and stores, whose
  // data moves between the USC and memory no faster than between the USC and its on-chip tile
  // buffer, so a pass past the budget is never cheaper than one that fits.
  tw.tile_buffer_bytes = tile_tsp.tile_buffer_read_bytes.value() + tile_tsp.tile_buffer_write_bytes.value() +
                         tile_tsp.pls_bytes_accessed.value();
  dram += spill;  // booked after the tile's loads and stores were taken from `dram`
  tw.tag_bytes = tile_isp.tag_buffer_read_bytes.value() + tile_isp.tag_buffer_write_bytes.value();
  tw.depth_bytes = tile_isp.depth_buffer_read_bytes.value() + tile_isp.depth_buffer_write_bytes.value();
  if (ctx_.rop) {
    if (end) ctx_.rop->flush();  // the pass's images must be in memory for what follows
    tw.rop_depth = ctx_.rop->take_depth_accesses();
    tw.rop_color = ctx_.rop->take_color_accesses();
    // Booked after the tile's loads and stores were taken from `dram`: the timing model streams
    // these through the SLC as they are, not as stores.
    for (const auto* v : {&tw.rop_depth, &tw.rop_color}) {
      for (const FramebufferAccess& a : *v) {
        if (a.write) {
          dram.write(a.cls, a.bytes);
        } else {
          dram.read(a.cls, a.bytes);
        }
      }
    }
  } else {
    const std::uint64_t pb_read = prims.empty() ? 0 : tiler_.tile_read_bytes(t);
    out.pb_bytes_read = pb_read;
    dram.read(DramClass::ParameterBuffer, pb_read);
    if (!prims.empty()) tw.pb_reads = tiler_.tile_read_ranges(t);
  }
  out.dram = dram;
  return out;
}

}  // namespace tbdr
