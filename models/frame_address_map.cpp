#include "models/frame_address_map.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>

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

FrameAddressMap::FrameAddressMap(const FrameWork& frame, std::uint64_t pb_bytes, AddressSpace& space)
    : space_(space), tiles_x_(std::max(1, frame.tiles_x)), immediate_(frame.immediate) {
  last_writer_.fill(-1);
  if (!frame.address_layout.empty()) {
    space.adopt(frame.address_layout);
    reuse_layout_ = true;
  }
  auto allocate = [&](const char* name, std::uint64_t bytes, DramClass cls) {
    return reuse_layout_ ? space.reuse_or_allocate(name, bytes, cls) : space.allocate(name, bytes, cls);
  };
  if (frame.texture_bytes > 0) texture_base_ = allocate("textures", frame.texture_bytes, DramClass::Textures);
  if (frame.framebuffer_bytes > 0) rop_framebuffer_base_ = allocate("framebuffer.imr", frame.framebuffer_bytes, DramClass::Color);
  pb_bytes = std::max(pb_bytes, kMinRegionBytes);
  pb_base_[0] = allocate("parameter_buffer.0", pb_bytes, DramClass::ParameterBuffer);
  pb_base_[1] = allocate("parameter_buffer.1", pb_bytes, DramClass::ParameterBuffer);
}

namespace {
std::uint64_t whole_units(std::uint64_t bytes) { return (bytes + kRegionAlignBytes - 1) / kRegionAlignBytes * kRegionAlignBytes; }
}  // namespace

void FrameAddressMap::add_command(const CommandWork& cmd) {
  const std::uint64_t slots = std::max<std::uint64_t>(1, cmd.tile_slots);
  fb_stride_.push_back(whole_units(std::max<std::uint64_t>(cmd.tile_slot_bytes, 1)));
  frame_.push_back(cmd.frame);
  fb_base_.push_back(cmd.is_dispatch ? 0 : place(fb_base_.size(), "framebuffer." + cmd.name, fb_stride_.back() * slots, DramClass::Color));
  tile_slots_.push_back(slots);
  partial_stride_.push_back(whole_units(std::max<std::uint64_t>(cmd.partial_slot_bytes, 1)));
  partial_base_.push_back(0);  // allocated at the first partial render
  cmd_base_.push_back(0);  // place_buffers
  buffers_placed_.push_back(false);
  spill_stride_.push_back(whole_units(cmd.spill_slot_bytes));
  // Allocated only when the pass spills, so that passes that fit keep their addresses.
  spill_base_.push_back(spill_stride_.back() == 0 ? 0
                                                  : place(fb_base_.size() - 1, "tile_spill." + cmd.name, spill_stride_.back() * slots, DramClass::Spill));
  vertex_base_.emplace_back();
  names_.push_back(cmd.name);
  // Whose data it reads: the latest earlier writer of each class.
  source_.push_back(last_writer_);
  written_.emplace_back();
}

void FrameAddressMap::place_buffers(std::size_t command, const CommandWork& cmd) {
  if (buffers_placed_.at(command)) return;
  const std::uint64_t cmd_bytes = sum(cmd.read_bytes) + sum(cmd.write_bytes);
  // In the high range, in command order (first fragment jobs start in command order), while the
  // other regions are placed as commands are taken: neither order depends on how the two
  // interleave, which the schedule (and so every swept parameter) decides.
  cmd_base_[command] = place(command, "buffers." + cmd.name, std::max<std::uint64_t>(cmd_bytes, kRegionAlignBytes), DramClass::Other, true);
  buffers_placed_[command] = true;
}

std::uint64_t FrameAddressMap::buffers(std::size_t command) const {
  if (!buffers_placed_.at(command)) throw std::logic_error("FrameAddressMap::buffers: the command's buffer area is not placed yet");
  return cmd_base_[command];
}

void FrameAddressMap::add_render(std::size_t command, const RenderWork& r) {
  std::uint64_t vertex_bytes = r.binning.vertex_fetch_bytes + r.binning.index_fetch_bytes;
  if (immediate_) {
    for (const auto& t : r.tiles) vertex_bytes += t.geometry.vertex_fetch_bytes + t.geometry.index_fetch_bytes;
  }
  if (r.partial && partial_base_.at(command) == 0) {
    partial_base_[command] = place(command, "partial_render." + names_[command], partial_stride_[command] * tile_slots_[command], DramClass::Color);
  }
  auto& bases = vertex_base_.at(command);
  // Allocated only when the render fetches geometry.
  bases.push_back(vertex_bytes == 0 ? 0
                                    : place(command, "vertices." + names_.at(command) + ".render" + std::to_string(bases.size()),
                                            vertex_bytes, DramClass::Vertices));
}

std::uint64_t FrameAddressMap::place(std::size_t command, const std::string& name, std::uint64_t bytes, DramClass cls, bool high) {
  // A sequence's later frames use the regions the frames before them allocated under the same name.
  if (frame_.at(command) > 0 || reuse_layout_) return space_.reuse_or_allocate(name, bytes, cls, high);
  return high ? space_.allocate_high(name, bytes, cls) : space_.allocate(name, bytes, cls);
}

void FrameAddressMap::end_command(const CommandWork& cmd) {
  if (ended_ >= fb_base_.size()) throw std::logic_error("FrameAddressMap::end_command: no command is open");
  const std::size_t c = ended_;
  if (names_[c] != cmd.name) throw std::logic_error("FrameAddressMap::end_command: " + cmd.name + " ends before " + names_[c]);
  record_writes(c, cmd);
  ++ended_;
  // The commands added after it took the latest writers known then: what this one wrote is
  // newer (the sources they would have taken had they been added after it ended).
  for (std::size_t later = c + 1; later < source_.size(); ++later) {
    for (std::size_t k = 0; k < kDramClassCount; ++k) {
      if (last_writer_[k] == static_cast<int>(c)) source_[later][k] = static_cast<int>(c);
    }
  }
}

void FrameAddressMap::record_writes(std::size_t c, const CommandWork& cmd) {
  // What the command wrote where: addresses as the timing model issues them, tile stores class
  // after class from the tile's slot, a dispatch's writes after its reads in its buffer area.
  auto& w = written_[c];
  if (cmd.is_dispatch) {
    if (sum(cmd.write_bytes) > 0 && !buffers_placed_[c]) {
      throw std::logic_error("FrameAddressMap::end_command: " + cmd.name + " ends before its buffer area was placed");
    }
    std::uint64_t offset = sum(cmd.read_bytes);
    for (std::size_t k = 0; k < kDramClassCount; ++k) {
      if (cmd.write_bytes[k] == 0) continue;
      w[k].all = {cmd_base_[c] + offset, cmd.write_bytes[k]};
      offset += cmd.write_bytes[k];
      last_writer_[k] = static_cast<int>(c);
    }
    return;
  }
  for (std::size_t ri = 0; ri < cmd.renders.size(); ++ri) {
    const RenderWork& r = cmd.renders[ri];
    for (const auto& t : r.tiles) {
      // A render after a partial render reloads from the partial slots; a partial render stores there.
      if (sum(t.load_bytes) > tile_slot_bytes(c, ri > 0) || sum(t.store_bytes) > tile_slot_bytes(c, r.partial) ||
          std::max(t.spill_read_bytes, t.spill_write_bytes) > spill_stride_[c]) {
        throw std::logic_error("FrameAddressMap: a tile of " + cmd.name + " loads, stores or spills more than its slot holds");
      }
      const auto index = static_cast<std::size_t>(t.tile_y * tiles_x_ + t.tile_x);
      std::uint64_t offset = 0;
      for (std::size_t k = 0; k < kDramClassCount; ++k) {
        if (t.store_bytes[k] == 0) continue;
        auto& tiles = w[k].tiles;
        if (tiles.size() <= index) tiles.resize(index + 1, ByteRange{0, 0});
        tiles[index] = {tile(c, t, r.partial) + offset, t.store_bytes[k]};  // the last render's stores
        w[k].per_tile = true;
        offset += t.store_bytes[k];
        last_writer_[k] = static_cast<int>(c);
      }
    }
  }
}

std::span<const ByteRange> FrameAddressMap::sources(std::size_t command, DramClass k, int tile_index, std::uint64_t bytes,
                                                    std::uint64_t piece, std::uint64_t& start) const {
  start = 0;
  const int writer = source_[command][static_cast<std::size_t>(k)];
  if (writer < 0 || bytes == 0 || piece == 0) return {};
  const Written& w = written_[static_cast<std::size_t>(writer)][static_cast<std::size_t>(k)];
  if (!w.per_tile) {
    if (w.all.bytes == 0) return {};
    if (tile_index >= 0) start = (static_cast<std::uint64_t>(tile_index) * bytes) % w.all.bytes;
    return {&w.all, 1};
  }
  if (tile_index >= 0) {
    const auto i = static_cast<std::size_t>(tile_index);
    if (i >= w.tiles.size() || w.tiles[i].bytes == 0) return {};
    return {&w.tiles[i], 1};
  }
  sources_.clear();
  for (const ByteRange& r : w.tiles) {
    if (r.bytes > 0) sources_.push_back(r);
  }
  return sources_;
}

std::vector<ByteRange> FrameAddressMap::produced(std::size_t command, DramClass k, int tile_index, std::uint64_t bytes,
                                                std::uint64_t piece) const {
  std::vector<ByteRange> out;
  for_each_produced(command, k, tile_index, bytes, piece, [&](std::uint64_t offset, std::uint64_t n) { out.push_back({offset, n}); });
  return out;
}

std::uint64_t FrameAddressMap::produced_bytes(std::size_t command, DramClass k, int tile_index) const {
  const int writer = source_[command][static_cast<std::size_t>(k)];
  if (writer < 0) return 0;
  const Written& w = written_[static_cast<std::size_t>(writer)][static_cast<std::size_t>(k)];
  if (!w.per_tile) return w.all.bytes;
  if (tile_index >= 0) {
    const auto i = static_cast<std::size_t>(tile_index);
    return i < w.tiles.size() ? w.tiles[i].bytes : 0;
  }
  std::uint64_t total = 0;
  for (const ByteRange& r : w.tiles) total += r.bytes;
  return total;
}

std::uint64_t FrameAddressMap::spill(std::size_t command, const TileWork& t) const {
  return spill_base_[command] + static_cast<std::uint64_t>(t.tile_y * tiles_x_ + t.tile_x) * spill_stride_[command];
}

std::uint64_t FrameAddressMap::tile(std::size_t command, const TileWork& t, bool partial) const {
  const auto index = static_cast<std::uint64_t>(t.tile_y * tiles_x_ + t.tile_x);
  if (partial) {
    if (partial_base_[command] == 0) throw std::logic_error("FrameAddressMap::tile: " + names_[command] + " has no partial render");
    return partial_base_[command] + index * partial_stride_[command];
  }
  return fb_base_[command] + index * fb_stride_[command];
}

}  // namespace tbdr
