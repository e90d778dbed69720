#include "models/tile_memory.hpp"

#include <algorithm>
#include <cmath>
#include <string>

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

TileMemory::TileMemory(RenderContext& ctx, TileMemoryStats& stats) : ctx_(ctx), stats_(stats) {
  const PassDesc& pass = *ctx.pass;
  check_pls_layout(ctx.hw->pls, pass);
  std::uint32_t color = 0;
  for (const auto& a : pass.attachments) {
    if (is_depth_format(a.format) || pass.is_resolve_target(a)) continue;  // depth lives in the ISP
    color += a.bytes_per_pixel();
  }
  // Pixel local storage and the colour attachments share the same per-pixel storage
  // (EXT_shader_pixel_local_storage: "the pixel local storage ... shares storage with the
  // framebuffer's color"; writing colour while PLS is live makes PLS undefined): a pass needs the
  // larger of the two, not their sum.
  need_ = std::max(color, pass.pls_bytes_per_pixel());
  budget_ = static_cast<std::uint32_t>(ctx.hw->pls.tile_buffer_bits_per_pixel / 8);
  if (need_ > budget_) {
    if (ctx.hw->pls.over_budget == PlsOverBudget::Spill) {
      spill_fraction_ = static_cast<double>(need_ - budget_) / static_cast<double>(need_);
    } else {
      split_ = static_cast<int>((need_ + budget_ - 1) / budget_);
    }
  }
  if (!pass.pls.empty()) {
    // The pass's pixel local storage lives in tile memory: sized from its declared layout.
    const std::size_t pixels = static_cast<std::size_t>(ctx.viewport.width_px) * static_cast<std::size_t>(ctx.viewport.height_px);
    pls_.stack_capacity = pls_light_stack_capacity(pass.pls_bytes_per_pixel());
    pls_.surface.assign(pixels, SurfacePoint{});
    pls_.valid.assign(pixels, 0);
    pls_.accum.assign(pixels, glm::vec3(0.0f));
    pls_.stack.assign(pixels * pls_.stack_capacity, 0);
    pls_.stack_count.assign(pixels, 0);
    pls_.overflow.assign(pixels, 0);
    ctx.pls = &pls_;
  }
  stats_.onchip_need_bytes_per_pixel += need_;
  stats_.onchip_budget_bytes_per_pixel += budget_;
  stats_.tile_split_factor += static_cast<std::uint64_t>(split_);
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

void TileMemory::begin_tile(const PixelRect& r, bool resumed, DramTraffic& dram) {
  const double ratio = ctx_.hw->writeback.compression_ratio;
  const int W = ctx_.viewport.width_px;
  for (const auto& a : ctx_.pass->attachments) {
    AttachmentImage& img = ctx_.images->attachments.at(a.name);
    const std::uint64_t bytes = attachment_bytes(a, r);
    if (ctx_.framebuffer_in_dram) {
      // imr: the attachment lives in DRAM; a clear writes it there, a load has nothing to do.
      if (a.load == LoadOp::Clear && !a.transient) dram.write(traffic_class_of(a.usage), bytes);
      if (a.load == LoadOp::Load) continue;
    } else if (resumed) {
      const auto b = static_cast<std::uint64_t>(std::ceil(static_cast<double>(bytes) * ratio));
      dram.read(traffic_class_of(a.usage), b);
      stats_.partial_render_reload_bytes += b;
      continue;
    }
    if (a.load == LoadOp::Load && !a.transient) {
      stats_.tile_load_bytes += bytes;
      dram.read(traffic_class_of(a.usage), static_cast<std::uint64_t>(std::ceil(static_cast<double>(bytes) * ratio)));
      continue;
    }
    if (a.load == LoadOp::Load && a.transient) continue;  // memoryless: nothing to load
    // clear (and don't care, made deterministic): initialise the tile's samples
    if (a.load == LoadOp::Clear) stats_.tile_clear_bytes += bytes;
    const std::size_t S = img.samples;
    for (int y = r.y0; y < r.y1; ++y) {
      const std::size_t b = (static_cast<std::size_t>(y) * W + static_cast<std::size_t>(r.x0)) * S;
      const std::size_t e = (static_cast<std::size_t>(y) * W + static_cast<std::size_t>(r.x1)) * S;
      if (is_depth_format(a.format)) {
        std::fill(img.depth.begin() + static_cast<std::ptrdiff_t>(b), img.depth.begin() + static_cast<std::ptrdiff_t>(e), 1.0f);
        std::fill(img.stencil.begin() + static_cast<std::ptrdiff_t>(b), img.stencil.begin() + static_cast<std::ptrdiff_t>(e), 0);
      } else {
        std::fill(img.color.begin() + static_cast<std::ptrdiff_t>(b), img.color.begin() + static_cast<std::ptrdiff_t>(e), glm::vec4(0.0f));
      }
    }
  }
}

void TileMemory::spill(std::uint64_t read_bytes, std::uint64_t write_bytes, DramTraffic& dram) {
  if (spill_fraction_ <= 0.0) return;
  const auto w = static_cast<std::uint64_t>(std::llround(spill_fraction_ * static_cast<double>(write_bytes)));
  const auto r = static_cast<std::uint64_t>(std::llround(spill_fraction_ * static_cast<double>(read_bytes))) + w;
  dram.write(DramClass::Spill, w);
  dram.read(DramClass::Spill, r);
  stats_.spill_bytes += w + r;
}

void TileMemory::end_tile(const PixelRect& r, bool partial, DramTraffic& dram) {
  const double ratio = ctx_.hw->writeback.compression_ratio;
  const int W = ctx_.viewport.width_px;
  for (const auto& a : ctx_.pass->attachments) {
    const std::uint64_t bytes = attachment_bytes(a, r);
    if (ctx_.framebuffer_in_dram && a.resolve.empty()) continue;  // imr: already in DRAM
    const auto compressed = static_cast<std::uint64_t>(std::ceil(static_cast<double>(bytes) * ratio));
    if (partial) {
      // The tile buffer is needed for the next render: everything leaves the chip, transient or not.
      dram.write(traffic_class_of(a.usage), compressed);
      stats_.partial_render_store_bytes += compressed;
      continue;
    }
    if (!a.resolve.empty()) {
      // Average the samples into the resolve target (its own store op books the traffic).
      AttachmentImage& src = ctx_.images->attachments.at(a.name);
      AttachmentImage& dst = ctx_.images->attachments.at(a.resolve);
      const std::size_t S = src.samples;
      for (int y = r.y0; y < r.y1; ++y) {
        for (int x = r.x0; x < r.x1; ++x) {
          const std::size_t p = static_cast<std::size_t>(y) * W + static_cast<std::size_t>(x);
          glm::vec4 sum(0.0f);
          for (std::size_t s = 0; s < S; ++s) sum += src.color[p * S + s];
          dst.color[p] = FormatPrecision::color(dst.format, sum / static_cast<float>(S));  // what the target keeps
        }
      }
      stats_.resolved_samples += static_cast<std::uint64_t>(r.width()) * static_cast<std::uint64_t>(r.height()) * S;
    }
    if (a.store == StoreOp::Store && !a.transient) {
      stats_.tile_store_bytes += bytes;
      stats_.writeback_dram_bytes += compressed;
      dram.write(traffic_class_of(a.usage), compressed);
    }
  }
}

}  // namespace tbdr
