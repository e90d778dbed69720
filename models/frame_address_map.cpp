#include "models/frame_address_map.hpp"

#include <algorithm>

namespace tbdr {

namespace {

// Every region gets at least one 4 KB page, the address space's granule; per-tile framebuffer
// areas and command buffers are whole 64-byte units, the default cache line (not
// cache.*.line_bytes, which a sweep varies: addresses must not move when a parameter is swept).
constexpr std::uint64_t kMinRegionBytes = 4096;
constexpr std::uint64_t kRegionAlignBytes = 64;

std::uint64_t sum(const std::array<std::uint64_t, kDramClassCount>& a) {
  std::uint64_t s = 0;
  for (auto b : a) s += b;
  return s;
}

}  // namespace

FrameAddressMap::FrameAddressMap(const FrameWork& work, AddressSpace& space) {
  std::uint64_t pb_bytes = kMinRegionBytes, vertex_bytes = kMinRegionBytes;
  for (const auto& cmd : work.commands) {
    const std::uint64_t cmd_bytes = sum(cmd.read_bytes) + sum(cmd.write_bytes);
    std::uint64_t stride = kRegionAlignBytes, spill_stride = 0;
    std::uint64_t max_tile = 1;
    for (const auto& r : cmd.renders) {
      std::uint64_t extent = r.binning.pb_write_bytes;
      for (const auto& t : r.tiles) {
        for (const auto& br : t.pb_reads) extent = std::max(extent, br.offset + br.bytes);
        stride = std::max({stride, sum(t.load_bytes) + sum(t.image_read_bytes), sum(t.store_bytes)});
        spill_stride = std::max({spill_stride, t.spill_read_bytes, t.spill_write_bytes});
        max_tile = std::max<std::uint64_t>(max_tile, static_cast<std::uint64_t>(t.tile_y * work.tiles_x + t.tile_x + 1));
      }
      pb_bytes = std::max(pb_bytes, extent);
      vertex_bytes += r.binning.vertex_fetch_bytes + r.binning.index_fetch_bytes;
    }
    stride = (stride + kRegionAlignBytes - 1) / kRegionAlignBytes * kRegionAlignBytes;
    fb_stride_.push_back(stride);
    fb_base_.push_back(cmd.is_dispatch ? 0 : space.allocate("framebuffer." + cmd.name, stride * max_tile, DramClass::Color));
    cmd_base_.push_back(space.allocate("buffers." + cmd.name, std::max<std::uint64_t>(cmd_bytes, kRegionAlignBytes), DramClass::Other));
    spill_stride = (spill_stride + kRegionAlignBytes - 1) / kRegionAlignBytes * kRegionAlignBytes;
    spill_stride_.push_back(spill_stride);
    // Allocated only when the pass spills, so that passes that fit keep their addresses.
    spill_base_.push_back(spill_stride == 0 ? 0 : space.allocate("tile_spill." + cmd.name, spill_stride * max_tile, DramClass::Spill));
  }
  if (work.texture_bytes > 0) texture_base_ = space.allocate("textures", work.texture_bytes, DramClass::Textures);
  pb_base_[0] = space.allocate("parameter_buffer.0", pb_bytes, DramClass::ParameterBuffer);
  pb_base_[1] = space.allocate("parameter_buffer.1", pb_bytes, DramClass::ParameterBuffer);
  vertex_base_ = space.allocate("vertex_and_index_buffers", vertex_bytes, DramClass::Vertices);
}

std::uint64_t FrameAddressMap::spill(std::size_t command, const TileWork& t, int tiles_x) const {
  return spill_base_[command] + static_cast<std::uint64_t>(t.tile_y * tiles_x + t.tile_x) * spill_stride_[command];
}

std::uint64_t FrameAddressMap::tile(std::size_t command, const TileWork& t, int tiles_x) const {
  return fb_base_[command] + static_cast<std::uint64_t>(t.tile_y * tiles_x + t.tile_x) * fb_stride_[command];
}

}  // namespace tbdr
