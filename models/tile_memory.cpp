#include "models/tile_memory.hpp"

#include "kernel/hash.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "models/rop.hpp"
#include "models/shading.hpp"
#include "kernel/errors.hpp"

namespace tbdr {

DramClass traffic_class_of(AttachmentUsage u) {
  switch (u) {
    case AttachmentUsage::Color: return DramClass::Color;
    case AttachmentUsage::Depth: return DramClass::DepthStencil;
    case AttachmentUsage::Gbuffer: return DramClass::Gbuffer;
    case AttachmentUsage::Visibility: return DramClass::Visibility;
  }
  return DramClass::Other;
}


std::uint32_t pls_light_stack_capacity(std::uint32_t pls_bytes_per_pixel) {
  return pls_bytes_per_pixel > kPlsStackCountBytes ? (pls_bytes_per_pixel - kPlsStackCountBytes) / kPlsLightIndexBytes
                                                   : 0;
}

void check_pls_layout(const PlsParams& p, const PassDesc& pass, const std::string& trace_path) {
  const std::uint32_t bytes = pass.pls_bytes_per_pixel();
  if (static_cast<std::int64_t>(bytes) > p.max_pls_bytes_per_pixel) {
    const std::string what = "pass '" + pass.name + "' declares " + std::to_string(bytes) +
                             " bytes of pixel local storage per pixel, more than pls.max_pls_bytes_per_pixel = " +
                             std::to_string(p.max_pls_bytes_per_pixel);
    if (!trace_path.empty()) throw InputError(trace_path, pass.line, what);
    throw InputError("pass '" + pass.name + "' (trace line " + std::to_string(pass.line) + ")", what);
  }
}

namespace {

/// Whether a shader of the pass that reads the PLS reads a stored surface for something counted
/// (not a colour): its cluster (its depth) or a G-buffer output it stores the surface to. As
/// Tsp::shade decides per batch.
bool pls_surface_counted(const RenderContext& ctx) {
  for (const DrawContext& d : ctx.draws) {
    const ShaderDesc& sh = *d.shader;
    if (sh.pls != PlsAccess::Read && sh.pls != PlsAccess::ReadWrite) continue;
    if (sh.light_source == LightSource::ClusterList) return true;
    const std::size_t outputs = std::min<std::size_t>(sh.color_outputs, ctx.color_targets.size());
    for (std::size_t o = 0; o < outputs; ++o) {
      if (ctx.color_targets[o]->usage != AttachmentUsage::Color) return true;
    }
  }
  return false;
}

}  // namespace

TileMemory::TileMemory(RenderContext& ctx, TileMemoryStats& stats)
    : ctx_(ctx), stats_(stats), in_memory_(ctx.pass->attachments.size(), 0), evicted_(ctx.pass->attachments.size(), 0) {
  const PassDesc& pass = *ctx.pass;
  check_pls_layout(ctx.hw->pls, pass);
  signatures_.assign(pass.attachments.size(), nullptr);
  if (ctx.tile_signatures != nullptr && ctx.hw->writeback.transaction_elimination != 0 && !ctx.framebuffer_in_dram) {
    const auto tw = static_cast<std::size_t>(ctx.hw->tiling.tile_width), th = static_cast<std::size_t>(ctx.hw->tiling.tile_height);
    const std::size_t tiles = (static_cast<std::size_t>(ctx.viewport.width_px) + tw - 1) / tw *
                              ((static_cast<std::size_t>(ctx.viewport.height_px) + th - 1) / th);
    for (std::size_t ai = 0; ai < pass.attachments.size(); ++ai) {
      const Attachment& a = pass.attachments[ai];
      if (a.usage == AttachmentUsage::Color && a.store == StoreOp::Store && !a.transient) {
        signatures_[ai] = ctx.tile_signatures->prepare(pass.name + "/" + a.name, tiles);
      }
    }
  }
  need_ = onchip_bytes_per_pixel();
  budget_ = static_cast<std::uint32_t>(ctx.hw->pls.tile_buffer_bits_per_pixel / 8);
  // imr: the attachments live in memory behind the ROP caches; there is no tile memory to fit.
  if (ctx.framebuffer_in_dram) need_ = 0;
  if (need_ > budget_ && ctx.hw->pls.over_budget == PlsOverBudget::SplitRender) find_split();
  // Within one render (before a split, after it, or without one) what does not fit spills, as the
  // driver then places it in memory tile buffers; unless the policy renders smaller tiles.
  fit_budget(ctx.hw->pls.over_budget == PlsOverBudget::SmallerTiles ? PlsOverBudget::SmallerTiles : PlsOverBudget::Spill);
  if (!pass.pls.empty()) {
    // The pass's pixel local storage lives in tile memory: sized from its declared layout.
    const std::size_t pixels = static_cast<std::size_t>(ctx.viewport.width_px) * static_cast<std::size_t>(ctx.viewport.height_px);
    pls_.stack_capacity = pls_light_stack_capacity(pass.pls_bytes_per_pixel());
    pls_.surface.assign(ctx.colour || pls_surface_counted(ctx) ? pixels : 0, ctx.colour);
    pls_.valid.assign(pixels, 0);
    pls_.accum.assign(ctx.colour ? pixels : 0, glm::vec3(0.0f));  // light sums: colours only
    pls_.stack.assign(ctx.colour ? pixels * pls_.stack_capacity : 0, 0);  // which lights: colours only
    pls_.stack_count.assign(pixels, 0);
    pls_.overflow.assign(pixels, 0);
    ctx.pls = &pls_;
  }
  // The lit colour writes each sample holds (Tsp::shade), when some shader of the pass writes
  // colour from lights: kept over the whole pass (its partial and split renders, imr's batches).
  const bool lit_colour = std::any_of(ctx.draws.begin(), ctx.draws.end(), [](const DrawContext& d) {
    return d.shader->color_outputs > 0 && d.shader->light_source != LightSource::None && d.shader->light_source != LightSource::Proxy;
  });
  if (lit_colour && !ctx.color_targets.empty()) {
    lit_samples_ = std::make_unique<LitSampleLedger>(ctx.viewport.width_px, ctx.viewport.height_px, ctx.pattern.count);
    ctx.lit_samples = lit_samples_.get();
  }
  stats_.onchip_need_bytes_per_pixel += need_;
  stats_.onchip_budget_bytes_per_pixel += budget_;
  stats_.tile_split_factor += static_cast<std::uint64_t>(split_);
}

std::uint32_t TileMemory::onchip_bytes_per_pixel() const {
  const PassDesc& pass = *ctx_.pass;
  std::uint32_t color = 0;
  for (std::size_t i = 0; i < pass.attachments.size(); ++i) {
    const Attachment& a = pass.attachments[i];
    if (is_depth_format(a.format) || pass.is_resolve_target(a) || in_memory_[i]) continue;  // depth lives in the ISP
    color += a.bytes_per_pixel();
  }
  // Pixel local storage and the colour attachments share the same per-pixel storage
  // (EXT_shader_pixel_local_storage: "the pixel local storage ... shares storage with the
  // framebuffer's color"; writing colour while PLS is live makes PLS undefined): a pass needs the
  // larger of the two, not their sum.
  return std::max(color, pass.pls_bytes_per_pixel());
}

void TileMemory::fit_budget(PlsOverBudget policy) {
  const std::uint32_t need = onchip_bytes_per_pixel();
  spill_fraction_ = 0;
  split_ = 1;
  if (need <= budget_) return;
  if (policy == PlsOverBudget::SmallerTiles) {
    split_ = static_cast<int>((need + budget_ - 1) / budget_);
  } else {
    spill_fraction_ = static_cast<double>(need - budget_) / static_cast<double>(need);
  }
}

void TileMemory::find_split() {
  const PassDesc& pass = *ctx_.pass;
  if (!pass.pls.empty()) return;  // pixel local storage cannot leave the chip between renders
  // Colour attachment k is written by a draw whose shader has more than k colour outputs.
  const std::vector<const Attachment*> targets = pass.color_targets();
  auto target_index = [&](const std::string& name) -> int {
    for (std::size_t k = 0; k < targets.size(); ++k) {
      if (targets[k]->name == name) return static_cast<int>(k);
    }
    return -1;
  };
  std::uint32_t outputs_before = 0;  // colour outputs written by the draws so far
  const auto& draws = ctx_.draws;
  for (std::size_t i = 0; i < draws.size() && split_draw_ < 0; ++i) {
    for (const auto& n : draws[i].cmd->fetch) {
      const int k = target_index(n);
      if (k >= 0 && static_cast<std::uint32_t>(k) < outputs_before) split_draw_ = static_cast<int>(i);
    }
    outputs_before = std::max(outputs_before, draws[i].shader->color_outputs);
  }
  if (split_draw_ < 0) return;
  // What the rest of the pass only reads stays in memory; what it writes comes back on chip.
  std::uint32_t outputs_after = 0;
  for (std::size_t i = static_cast<std::size_t>(split_draw_); i < draws.size(); ++i)
    outputs_after = std::max(outputs_after, draws[i].shader->color_outputs);
  bool any = false;
  for (std::size_t i = static_cast<std::size_t>(split_draw_); i < draws.size(); ++i) {
    for (const auto& n : draws[i].cmd->fetch) {
      const int k = target_index(n);
      if (k < 0 || static_cast<std::uint32_t>(k) < outputs_after) continue;
      for (std::size_t a = 0; a < pass.attachments.size(); ++a) {
        if (pass.attachments[a].name == n) evicted_[a] = 1;
      }
      any = true;
    }
  }
  if (!any) split_draw_ = -1;  // the rest writes all it fetches: no subpass boundary helps
}

void TileMemory::begin_split_render(std::vector<DrawContext>& draws) {
  const PassDesc& pass = *ctx_.pass;
  in_memory_ = evicted_;
  for (std::size_t i = static_cast<std::size_t>(split_draw_); i < draws.size(); ++i) {
    DrawContext& d = draws[i];
    for (const auto& n : d.cmd->fetch) {
      for (std::size_t a = 0; a < pass.attachments.size(); ++a) {
        const Attachment& att = pass.attachments[a];
        if (att.name != n || !in_memory_[a]) continue;
        d.fetch_bytes -= att.bytes_per_pixel();
        d.per_pixel_reads.emplace_back(traffic_class_of(att.usage), att.bytes_per_pixel());
        ++d.image_fetches;  // an input attachment in memory is sampled through the texture unit
      }
    }
  }
  ++stats_.split_renders;
  // The new render holds the rest; if that still does not fit, its excess spills.
  fit_budget(PlsOverBudget::Spill);
}

std::vector<PixelRect> TileMemory::strips(const PixelRect& tile) const {
  if (split_ <= 1) return {tile};
  std::vector<PixelRect> out;
  const int h = tile.height();
  const int strip = std::max(1, (h + split_ - 1) / split_);
  for (int y = tile.y0; y < tile.y1; y += strip) out.push_back({tile.x0, y, tile.x1, std::min(tile.y1, y + strip)});
  return out;
}

std::uint64_t TileMemory::attachment_bytes(const Attachment& a, const PixelRect& r) const {
  const std::uint64_t pixels = static_cast<std::uint64_t>(r.width()) * static_cast<std::uint64_t>(r.height());
  if (is_depth_format(a.format)) return pixels * a.samples * static_cast<std::uint64_t>(ctx_.hw->isp.depth_stencil_bytes_per_sample);
  return pixels * a.bytes_per_pixel();
}

std::uint64_t TileMemory::slot_bytes(const PixelRect& r, bool every_attachment) const {
  const double ratio = ctx_.hw->writeback.compression_ratio;
  std::uint64_t total = 0;
  for (std::size_t ai = 0; ai < ctx_.pass->attachments.size(); ++ai) {
    const Attachment& a = ctx_.pass->attachments[ai];
    if (!every_attachment && (a.transient || (a.load != LoadOp::Load && a.store != StoreOp::Store))) continue;
    total += static_cast<std::uint64_t>(std::ceil(static_cast<double>(attachment_bytes(a, r)) * ratio));
    if (signatures_[ai] != nullptr) total += kTileSignatureBytes;  // its signature, in the tile's slot
  }
  return total;
}

long TileMemory::whole_tile_index(const PixelRect& r) const {
  const int tw = static_cast<int>(ctx_.hw->tiling.tile_width), th = static_cast<int>(ctx_.hw->tiling.tile_height);
  const int W = ctx_.viewport.width_px, H = ctx_.viewport.height_px;
  if (r.x0 % tw != 0 || r.y0 % th != 0 || r.x1 != std::min(r.x0 + tw, W) || r.y1 != std::min(r.y0 + th, H)) return -1;
  const int tiles_x = (W + tw - 1) / tw;
  return static_cast<long>(r.y0 / th) * tiles_x + r.x0 / tw;
}

bool TileMemory::eliminate_store(std::size_t ai, const Attachment& a, const PixelRect& r, std::uint64_t compressed,
                                 DramTraffic& dram, TileMemoryStats& stats) const {
  TileSignatures::Table* table = signatures_[ai];
  const long tile = table != nullptr ? whole_tile_index(r) : -1;
  const AttachmentImage& img = ctx_.images->attachments.at(a.name);
  if (tile < 0 || img.color.empty()) return false;  // a strip of a tile, or no colours to sign
  Fnv1a64 h;
  const int W = ctx_.viewport.width_px;
  const std::size_t S = img.samples;
  for (int y = r.y0; y < r.y1; ++y) {
    const std::size_t row = (static_cast<std::size_t>(y) * static_cast<std::size_t>(W) + static_cast<std::size_t>(r.x0)) * S;
    h.update(&img.color[row], static_cast<std::size_t>(r.width()) * S * sizeof(glm::vec4));
  }
  const auto i = static_cast<std::size_t>(tile);
  const bool had = table->has_previous[i] != 0;
  const bool same = had && table->previous[i] == h.value();
  table->current[i] = h.value();
  table->has_current[i] = 1;
  // The previous frame's signature is read to compare (when there is one); this frame's is written.
  const std::uint64_t sig_read = had ? kTileSignatureBytes : 0;
  dram.read(traffic_class_of(a.usage), sig_read);
  dram.write(traffic_class_of(a.usage), kTileSignatureBytes);
  stats.signature_bytes += sig_read + kTileSignatureBytes;
  if (!same) return false;
  stats.eliminated_tile_stores += 1;
  stats.eliminated_store_bytes += compressed;
  return true;
}

void TileMemory::begin_tile(const PixelRect& r, bool resumed, DramTraffic& dram, TileMemoryStats& stats) const {
  const double ratio = ctx_.hw->writeback.compression_ratio;
  const int W = ctx_.viewport.width_px;
  for (std::size_t ai = 0; ai < ctx_.pass->attachments.size(); ++ai) {
    const Attachment& a = ctx_.pass->attachments[ai];
    if (in_memory_[ai]) continue;  // after a split render: read from memory as an image
    AttachmentImage& img = ctx_.images->attachments.at(a.name);
    const std::uint64_t bytes = attachment_bytes(a, r);
    if (ctx_.framebuffer_in_dram) {
      // imr: the attachment lives in memory behind the ROP caches, which clear it (imr.clear); a
      // load has nothing to do. A transient attachment is lowered to an ordinary one (an
      // immediate-mode GPU has no lazily allocated memory): it is cleared and written back alike.
      if (a.load == LoadOp::Clear && ctx_.rop) ctx_.rop->clear(a);
      if (a.load == LoadOp::Load) continue;
    } else if (resumed) {
      const auto b = static_cast<std::uint64_t>(std::ceil(static_cast<double>(bytes) * ratio));
      dram.read(traffic_class_of(a.usage), b);
      stats.partial_render_reload_bytes += b;
      continue;
    }
    if (a.load == LoadOp::Load && !a.transient) {
      stats.tile_load_bytes += bytes;
      dram.read(traffic_class_of(a.usage), static_cast<std::uint64_t>(std::ceil(static_cast<double>(bytes) * ratio)));
      continue;
    }
    if (a.load == LoadOp::Load && a.transient) continue;  // memoryless: nothing to load
    // clear (and don't care, made deterministic): initialise the tile's samples
    if (a.load == LoadOp::Clear) stats.tile_clear_bytes += bytes;
    const std::size_t S = img.samples;
    for (int y = r.y0; y < r.y1; ++y) {
      const std::size_t b = (static_cast<std::size_t>(y) * W + static_cast<std::size_t>(r.x0)) * S;
      const std::size_t e = (static_cast<std::size_t>(y) * W + static_cast<std::size_t>(r.x1)) * S;
      if (is_depth_format(a.format)) {
        std::fill(img.depth.begin() + static_cast<std::ptrdiff_t>(b), img.depth.begin() + static_cast<std::ptrdiff_t>(e), 1.0f);
        std::fill(img.stencil.begin() + static_cast<std::ptrdiff_t>(b), img.stencil.begin() + static_cast<std::ptrdiff_t>(e), 0);
      } else if (!img.color.empty()) {  // (no colours computed: no color array)
        std::fill(img.color.begin() + static_cast<std::ptrdiff_t>(b), img.color.begin() + static_cast<std::ptrdiff_t>(e), glm::vec4(0.0f));
      }
    }
  }
}

void TileMemory::spill(std::uint64_t read_bytes, std::uint64_t write_bytes, DramTraffic& dram, TileMemoryStats& stats) const {
  if (spill_fraction_ <= 0.0) return;
  const auto w = static_cast<std::uint64_t>(std::llround(spill_fraction_ * static_cast<double>(write_bytes)));
  const auto r = static_cast<std::uint64_t>(std::llround(spill_fraction_ * static_cast<double>(read_bytes))) + w;
  dram.write(DramClass::Spill, w);
  dram.read(DramClass::Spill, r);
  stats.spill_bytes += w + r;
}

void TileMemory::end_tile(const PixelRect& r, bool partial, DramTraffic& dram, TileMemoryStats& stats) const {
  const double ratio = ctx_.hw->writeback.compression_ratio;
  const int W = ctx_.viewport.width_px;
  for (std::size_t ai = 0; ai < ctx_.pass->attachments.size(); ++ai) {
    const Attachment& a = ctx_.pass->attachments[ai];
    if (in_memory_[ai]) continue;  // stored when the render before the split ended
    const std::uint64_t bytes = attachment_bytes(a, r);
    if (ctx_.framebuffer_in_dram && a.resolve.empty()) continue;  // imr: already in DRAM
    const auto compressed = static_cast<std::uint64_t>(std::ceil(static_cast<double>(bytes) * ratio));
    if (partial) {
      // The tile buffer is needed for the next render: everything leaves the chip, transient or not.
      dram.write(traffic_class_of(a.usage), compressed);
      stats.partial_render_store_bytes += compressed;
      continue;
    }
    if (!a.resolve.empty()) {
      // Average the samples into the resolve target (its own store op books the traffic).
      AttachmentImage& src = ctx_.images->attachments.at(a.name);
      AttachmentImage& dst = ctx_.images->attachments.at(a.resolve);
      const std::size_t S = src.samples;
      const bool colours = !src.color.empty() && !dst.color.empty();  // (none computed: nothing to average)
      for (int y = r.y0; y < r.y1 && colours; ++y) {
        for (int x = r.x0; x < r.x1; ++x) {
          const std::size_t p = static_cast<std::size_t>(y) * W + static_cast<std::size_t>(x);
          glm::vec4 sum(0.0f);
          for (std::size_t s = 0; s < S; ++s) sum += src.color[p * S + s];
          dst.color[p] = FormatPrecision::color(dst.format, sum / static_cast<float>(S));  // what the target keeps
        }
      }
      stats.resolved_samples += static_cast<std::uint64_t>(r.width()) * static_cast<std::uint64_t>(r.height()) * S;
    }
    if (a.store == StoreOp::Store && !a.transient) {
      if (eliminate_store(ai, a, r, compressed, dram, stats)) continue;
      stats.tile_store_bytes += bytes;
      stats.writeback_dram_bytes += compressed;
      dram.write(traffic_class_of(a.usage), compressed);
    }
  }
}

}  // namespace tbdr
