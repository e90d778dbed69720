#include "models/rop.hpp"

#include <bit>

#include "models/tile_memory.hpp"  // traffic_class_of: an attachment's DRAM class, as the tile memory charges it

namespace tbdr {

namespace {
/// Images start on a 4 KiB page of the framebuffer address space (the address space's granule).
constexpr std::uint64_t kImageAlignBytes = 4096;
}  // namespace

RenderOutputUnit::RenderOutputUnit(const HwConfig& hw, int width, int height)
    : width_(width),
      blocks_x_((width + kBlockPixels - 1) / kBlockPixels),
      blocks_y_((height + kBlockPixels - 1) / kBlockPixels),
      depth_bytes_per_sample_(static_cast<std::uint64_t>(hw.isp.depth_stencil_bytes_per_sample)),
      depth_cache_("rop.depth_cache", hw.cache.rop_depth),
      color_cache_("rop.color_cache", hw.cache.rop_color),
      fast_clear_(hw.imr.clear == ImrClear::Fast),
      color_line_bytes_(static_cast<std::uint64_t>(hw.cache.rop_color.line_bytes)),
      depth_line_bytes_(static_cast<std::uint64_t>(hw.cache.rop_depth.line_bytes)) {}

RenderOutputUnit::Image& RenderOutputUnit::place(const Attachment& a) {
  auto [it, inserted] = images_.try_emplace(a.name);
  if (inserted) {
    Image& img = it->second;
    img.samples = a.samples;
    img.bytes_per_sample = is_depth_format(a.format) ? static_cast<std::uint32_t>(depth_bytes_per_sample_) : bytes_per_sample(a.format);
    img.cls = traffic_class_of(a.usage);
    img.base = next_base_;
    const std::uint64_t bytes = static_cast<std::uint64_t>(blocks_x_) * static_cast<std::uint64_t>(blocks_y_) * kBlockPixels *
                                kBlockPixels * img.samples * img.bytes_per_sample;
    const std::uint64_t line = is_depth_format(a.format) ? depth_line_bytes_ : color_line_bytes_;
    img.lines = (bytes + line - 1) / line;
    img.cleared.assign(img.lines, false);
    next_base_ += (bytes + kImageAlignBytes - 1) / kImageAlignBytes * kImageAlignBytes;
  }
  it->second.stored = a.store == StoreOp::Store && !a.transient;
  return it->second;
}

void RenderOutputUnit::clear(const Attachment& a) {
  Image& img = place(a);
  const std::uint64_t line = is_depth_format(a.format) ? depth_line_bytes_ : color_line_bytes_;
  Cache& cache = is_depth_format(a.format) ? depth_cache_ : color_cache_;
  if (fast_clear_) {
    // Lines in the cache take the clear value there (dirty: memory does not hold it yet).
    for (std::uint64_t l = 0; l < img.lines; ++l) {
      const std::uint64_t addr = img.base + l * line;
      if (cache.probe(addr)) {
        cache.access(addr, static_cast<std::uint32_t>(line), true, img.cls);
      } else {
        img.cleared[l] = true;
      }
    }
    return;
  }
  for (std::uint64_t l = 0; l < img.lines; ++l) {
    const std::uint64_t addr = img.base + l * line;
    // Written past the cache; a cached copy is stale and dropped by overwriting it clean.
    if (cache.probe(addr)) cache.access(addr, static_cast<std::uint32_t>(line), true, img.cls);
    color_out_.push_back({addr, static_cast<std::uint32_t>(line), true, img.cls});
    stats_->clear_bytes += line;
  }
}

void RenderOutputUnit::bind_pass(const PassDesc& pass, RopStats& stats) {
  stats_ = &stats;
  const Attachment* d = pass.depth_attachment();
  depth_ = d ? &place(*d) : nullptr;
  targets_.clear();
  for (const Attachment* a : pass.color_targets()) targets_.push_back(&place(*a));
  next_primitive();
}

void RenderOutputUnit::place_pass(const PassDesc& pass) {
  if (const Attachment* d = pass.depth_attachment()) place(*d);
  for (const Attachment* a : pass.color_targets()) place(*a);
  for (const Attachment& a : pass.attachments) {
    if (a.load == LoadOp::Clear) place(a);  // (TileMemory::begin_tile clears these)
  }
}

std::uint64_t RenderOutputUnit::address(const Image& img, int x, int y, int s) const {
  const auto block = static_cast<std::uint64_t>(y / kBlockPixels) * static_cast<std::uint64_t>(blocks_x_) +
                     static_cast<std::uint64_t>(x / kBlockPixels);
  const auto in_block = static_cast<std::uint64_t>((y % kBlockPixels) * kBlockPixels + x % kBlockPixels);
  const std::uint64_t sample = (block * kBlockPixels * kBlockPixels + in_block) * img.samples + static_cast<std::uint64_t>(s);
  return img.base + sample * img.bytes_per_sample;
}

void RenderOutputUnit::access(Cache& cache, Image& img, std::uint64_t addr, bool write, std::vector<FramebufferAccess>& out,
                              std::uint64_t& last) {
  const DramClass cls = img.cls;
  RopStats& stats = *stats_;
  const std::uint64_t line = cache.line_addr(addr);
  const std::uint64_t key = line * 2 + (write ? 1 : 0);
  if (key == last) return;
  last = key;
  const auto bytes = static_cast<std::uint32_t>(cache.line_bytes());
  stats.accessed_bytes += bytes;
  // Writes allocate without a fetch: the caches keep per-byte valid masks, so a written line need
  // not be read first (what is not written stays as it is in memory when the line is written back).
  // A fast-cleared line's first access finds the clear value in the metadata: installed dirty
  // (memory does not hold it), nothing fetched.
  bool cleared = false;
  const std::uint64_t l = (line - img.base) / bytes;
  if (l < img.lines && img.cleared[l]) {
    img.cleared[l] = false;
    cleared = true;
  }
  const CacheAccess r = cache.access(line, bytes, write || cleared, cls);
  if (cleared && !r.hit) ++stats.fast_cleared_fills;
  if (!r.hit && !write && !cleared) {
    out.push_back({line, bytes, false, cls});
    stats.fill_bytes += bytes;
  }
  if (r.writeback) {
    out.push_back({r.victim_addr, bytes, true, r.victim_cls});
    stats.writeback_bytes += bytes;
  }
}

void RenderOutputUnit::depth(int x, int y, int s, bool write) {
  RopStats& stats = *stats_;
  if (!depth_) return;
  const std::size_t before = depth_out_.size();
  const std::uint64_t accessed = stats.accessed_bytes.value();
  access(depth_cache_, *depth_, address(*depth_, x, y, s), write, depth_out_, last_depth_);
  if (stats.accessed_bytes.value() == accessed) return;
  ++stats.depth_accesses;
  for (std::size_t i = before; i < depth_out_.size(); ++i) {
    if (!depth_out_[i].write) ++stats.depth_misses;
  }
}

void RenderOutputUnit::color(std::size_t target, int x, int y, std::uint32_t mask, bool read) {
  RopStats& stats = *stats_;
  if (target >= targets_.size()) return;
  Image& img = *targets_[target];
  while (mask != 0) {
    const int s = std::countr_zero(mask);
    mask &= mask - 1;
    const std::uint64_t addr = address(img, x, y, s);
    for (int write = read ? 0 : 1; write < 2; ++write) {
      const std::size_t before = color_out_.size();
      const std::uint64_t accessed = stats.accessed_bytes.value();
      access(color_cache_, img, addr, write != 0, color_out_, last_color_);
      if (stats.accessed_bytes.value() == accessed) continue;
      ++stats.color_accesses;
      for (std::size_t i = before; i < color_out_.size(); ++i) {
        if (!color_out_[i].write) ++stats.color_read_misses;
      }
    }
  }
}

void RenderOutputUnit::flush() {
  RopStats& stats = *stats_;
  // Fast-clear eliminate: a stored image's cleared lines that no draw touched get the clear value
  // in memory now (a later command may read the image as a texture).
  std::vector<Image*> bound(targets_.begin(), targets_.end());
  if (depth_) bound.push_back(depth_);
  for (Image* img : bound) {
    const std::uint64_t line = img == depth_ ? depth_line_bytes_ : color_line_bytes_;
    for (std::uint64_t l = 0; l < img->lines; ++l) {
      if (!img->cleared[l]) continue;
      img->cleared[l] = false;
      if (!img->stored) continue;
      color_out_.push_back({img->base + l * line, static_cast<std::uint32_t>(line), true, img->cls});
      stats.clear_bytes += line;
    }
  }
  for (Cache* c : {&depth_cache_, &color_cache_}) {
    const auto bytes = static_cast<std::uint32_t>(c->line_bytes());
    c->flush([&](std::uint64_t line, DramClass cls) {
      color_out_.push_back({line, bytes, true, cls});
      stats.writeback_bytes += bytes;
    });
  }
  next_primitive();
}

}  // namespace tbdr
