#include "models/isp.hpp"

#include <algorithm>

namespace tbdr {

namespace {

constexpr std::uint32_t kNoTag = 0xffffffffu;

template <class T>
bool passes(CompareOp op, T incoming, T stored) {
  switch (op) {
    case CompareOp::Never: return false;
    case CompareOp::Less: return incoming < stored;
    case CompareOp::Equal: return incoming == stored;
    case CompareOp::LessEqual: return incoming <= stored;
    case CompareOp::Greater: return incoming > stored;
    case CompareOp::NotEqual: return incoming != stored;
    case CompareOp::GreaterEqual: return incoming >= stored;
    case CompareOp::Always: return true;
  }
  return true;
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
  for (const PendingSample* s = begin; s != end; ++s) {
    if (!batch.empty() && batch.back().x == s->x && batch.back().y == s->y) {
      batch.back().mask |= s->bit;
    } else {
      batch.push_back({s->x, s->y, s->bit});
    }
  }
}

void Isp::flush(const PixelRect& rect, const std::vector<std::uint8_t>* select, bool mid_tile, IspStats& isp,
                TspStats& tsp) {
  const int S = ctx_.pattern.count;
  const int rw = rect.width();
  flush_samples_.clear();
  for (int y = rect.y0; y < rect.y1; ++y) {
    for (int x = rect.x0; x < rect.x1; ++x) {
      const std::size_t base = (static_cast<std::size_t>(y - rect.y0) * rw + static_cast<std::size_t>(x - rect.x0)) * S;
      for (int s = 0; s < S; ++s) {
        const std::size_t li = base + static_cast<std::size_t>(s);
        if (tags_[li] == kNoTag || (select && !(*select)[li])) continue;
        flush_samples_.push_back({tags_[li], x, y, 1u << s});
        tags_[li] = kNoTag;
      }
    }
  }
  if (flush_samples_.empty()) return;
  if (mid_tile) {
    ++isp.tag_flushes;
    isp.tag_flushed_samples += flush_samples_.size();
  }
  isp.tag_buffer_read_bytes += flush_samples_.size() * static_cast<std::uint64_t>(ctx_.hw->isp.tag_bits / 8);
  // Shade primitive by primitive, in submission order; raster order within each.
  std::stable_sort(flush_samples_.begin(), flush_samples_.end(),
                   [](const PendingSample& a, const PendingSample& b) { return a.tag < b.tag; });
  std::size_t i = 0;
  while (i < flush_samples_.size()) {
    std::size_t j = i;
    while (j < flush_samples_.size() && flush_samples_[j].tag == flush_samples_[i].tag) ++j;
    build_batch(flush_samples_.data() + i, flush_samples_.data() + j, batch_);
    tsp_.shade(flush_samples_[i].tag, batch_, nullptr, tsp);
    i = j;
  }
}

void Isp::render_tile(const PixelRect& rect, const std::vector<std::uint32_t>& prims, IspStats& isp, TspStats& tsp) {
  const int S = ctx_.pattern.count;
  const int W = ctx_.viewport.width_px;
  const int rw = rect.width();
  const std::size_t tile_samples = static_cast<std::size_t>(rw) * static_cast<std::size_t>(rect.height()) * S;
  tags_.assign(tile_samples, kNoTag);
  ++isp.tiles_rendered;
  const std::uint64_t ds_bytes = static_cast<std::uint64_t>(ctx_.hw->isp.depth_stencil_bytes_per_sample);
  const std::uint64_t tag_bytes = static_cast<std::uint64_t>(ctx_.hw->isp.tag_bits / 8);
  AttachmentImage* depth_img = ctx_.depth;
  float* depth = depth_img ? depth_img->depth.data() : nullptr;
  std::uint8_t* stencil = depth_img ? depth_img->stencil.data() : nullptr;
  const bool has_st = depth_img && has_stencil(depth_img->format);
  auto& overdraw = ctx_.images->counters.rasterised_samples;

  for (const std::uint32_t prim_index : prims) {
    const Primitive& p = ctx_.prims[prim_index];
    const PipelineState& pl = *ctx_.draws[p.draw].pipeline;
    ++isp.primitives_fetched;
    const bool depth_on = depth && pl.depth_test;
    const bool write_on = depth && pl.depth_write;
    const bool stencil_on = has_st && pl.stencil_test;
    const auto ref = static_cast<std::uint8_t>(pl.stencil_ref & 0xffu);
    const bool deferred_opaque = ctx_.defer_shading && p.hsr == HsrClass::Opaque;
    const bool early_write = !ctx_.defer_shading && p.hsr == HsrClass::Opaque && write_on;
    pending_.clear();
    pending_depth_.clear();

    rasterize_in_rect(p.setup, rect, ctx_.pattern, [&](int x, int y, std::uint32_t mask, const float* z) {
      const std::size_t pixel = static_cast<std::size_t>(y) * static_cast<std::size_t>(W) + static_cast<std::size_t>(x);
      const std::size_t lbase = (static_cast<std::size_t>(y - rect.y0) * rw + static_cast<std::size_t>(x - rect.x0)) * S;
      for (int s = 0; s < S; ++s) {
        if (!(mask & (1u << s))) continue;
        ++overdraw[pixel];
        ++isp.samples_rasterised;
        const std::size_t gi = pixel * static_cast<std::size_t>(S) + static_cast<std::size_t>(s);
        if (stencil_on) {
          if (!passes<std::uint8_t>(pl.stencil_compare, ref, stencil[gi])) {
            ++isp.stencil_test_failed_samples;
            stencil[gi] = apply_stencil(pl.stencil_fail_op, stencil[gi], ref);
            continue;
          }
        }
        if (depth_on) {
          isp.depth_buffer_read_bytes += ds_bytes;
          if (!passes<float>(pl.depth_compare, z[s], depth[gi])) {
            ++isp.depth_test_failed_samples;
            if (stencil_on) stencil[gi] = apply_stencil(pl.stencil_depth_fail_op, stencil[gi], ref);
            continue;
          }
        }
        if (stencil_on) stencil[gi] = apply_stencil(pl.stencil_pass_op, stencil[gi], ref);
        if (deferred_opaque) {
          const std::size_t li = lbase + static_cast<std::size_t>(s);
          if (tags_[li] != kNoTag) ++isp.hsr_removed_samples;
          tags_[li] = prim_index;
          isp.tag_buffer_write_bytes += tag_bytes;
          if (write_on) {
            depth[gi] = z[s];
            isp.depth_buffer_write_bytes += ds_bytes;
          }
        } else {
          pending_.push_back({prim_index, x, y, 1u << s});
          pending_depth_.push_back(z[s]);
          if (early_write) {
            depth[gi] = z[s];
            isp.depth_buffer_write_bytes += ds_bytes;
          }
        }
      }
    });
    if (pending_.empty()) continue;
    if (p.hsr == HsrClass::PunchThrough) isp.punch_through_samples += pending_.size();
    if (p.hsr == HsrClass::Translucent) isp.translucent_samples += pending_.size();
    if (ctx_.defer_shading) {
      // What lies beneath must be shaded before this primitive can be.
      if (ctx_.hw->isp.tag_buffers <= 1) {
        flush(rect, nullptr, true, isp, tsp);
      } else {
        select_.assign(tile_samples, 0);
        for (const auto& ps : pending_) {
          int s = 0;
          while (!(ps.bit & (1u << s))) ++s;
          select_[(static_cast<std::size_t>(ps.y - rect.y0) * rw + static_cast<std::size_t>(ps.x - rect.x0)) * S +
                  static_cast<std::size_t>(s)] = 1;
        }
        flush(rect, &select_, true, isp, tsp);
      }
    }
    build_batch(pending_.data(), pending_.data() + pending_.size(), batch_);
    const bool punch = p.hsr == HsrClass::PunchThrough;
    tsp_.shade(prim_index, batch_, punch ? &alive_ : nullptr, tsp);
    if (p.hsr == HsrClass::Translucent && write_on) {
      for (std::size_t k = 0; k < pending_.size(); ++k) {
        int s = 0;
        while (!(pending_[k].bit & (1u << s))) ++s;
        depth[(static_cast<std::size_t>(pending_[k].y) * W + static_cast<std::size_t>(pending_[k].x)) * S +
              static_cast<std::size_t>(s)] = pending_depth_[k];
        isp.depth_buffer_write_bytes += ds_bytes;
      }
    }
    if (punch && write_on) {
      // Depth is written only where the alpha test kept the sample.
      std::size_t k = 0;
      for (std::size_t i = 0; i < batch_.size(); ++i) {
        while (k < pending_.size() && pending_[k].x == batch_[i].x && pending_[k].y == batch_[i].y) {
          if (alive_[i] & pending_[k].bit) {
            int s = 0;
            while (!(pending_[k].bit & (1u << s))) ++s;
            const std::size_t gi = (static_cast<std::size_t>(pending_[k].y) * W + static_cast<std::size_t>(pending_[k].x)) * S +
                                   static_cast<std::size_t>(s);
            depth[gi] = pending_depth_[k];
            isp.depth_buffer_write_bytes += ds_bytes;
          }
          ++k;
        }
      }
    }
  }
  flush(rect, nullptr, false, isp, tsp);
}

}  // namespace tbdr
