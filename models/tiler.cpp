#include "models/tiler.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace tbdr {

Tiler::Tiler(const HwConfig& hw, const Viewport& viewport, const SamplePattern& pattern)
    : hw_(hw),
      pattern_(pattern),
      test_(hw.tiling.binning == BinningTest::BoundingBox ? TileTest::BoundingBox : TileTest::Exact),
      tile_w_(static_cast<int>(hw.tiling.tile_width)),
      tile_h_(static_cast<int>(hw.tiling.tile_height)),
      tiles_x_((viewport.width_px + tile_w_ - 1) / tile_w_),
      tiles_y_((viewport.height_px + tile_h_ - 1) / tile_h_),
      viewport_(viewport),
      area_{0, 0, viewport.width_px, viewport.height_px},
      region_tiles_(static_cast<std::uint64_t>(tiles_x_) * static_cast<std::uint64_t>(tiles_y_)),
      tiles_(static_cast<std::size_t>(tiles_x_) * static_cast<std::size_t>(tiles_y_)),
      open_keys_(static_cast<std::uint32_t>(hw.tiling.prim_block_max_vertices)) {}

void Tiler::set_render_area(const PixelRect& area) {
  area_ = area;
  region_tiles_ = 0;
  for (int t = 0; t < tile_count(); ++t) region_tiles_ += in_render_area(t) ? 1 : 0;
}

Tiler::BlockVertices::BlockVertices(std::uint32_t max_vertices) {
  // At most half full (a block holds at most max_vertices keys): short probe runs.
  std::size_t slots = 8;
  shift_ = 61;
  while (slots < 2 * static_cast<std::size_t>(max_vertices)) {
    slots *= 2;
    --shift_;
  }
  keys_.assign(slots, 0);
  stamps_.assign(slots, 0);
}

std::size_t Tiler::BlockVertices::slot_of(std::uint64_t key) const {
  return static_cast<std::size_t>((key * 0x9E3779B97F4A7C15ull) >> shift_);  // Fibonacci hashing
}

bool Tiler::BlockVertices::contains(std::uint64_t key) const {
  const std::size_t mask = keys_.size() - 1;
  for (std::size_t i = slot_of(key);; i = (i + 1) & mask) {
    if (stamps_[i] != stamp_) return false;
    if (keys_[i] == key) return true;
  }
}

void Tiler::BlockVertices::insert(std::uint64_t key) {
  if (2 * (static_cast<std::size_t>(size_) + 1) > keys_.size()) throw std::logic_error("Tiler: more vertices in a block than its maximum");
  const std::size_t mask = keys_.size() - 1;
  std::size_t i = slot_of(key);
  while (stamps_[i] == stamp_) i = (i + 1) & mask;
  keys_[i] = key;
  stamps_[i] = stamp_;
  ++size_;
}

void Tiler::BlockVertices::clear() {
  size_ = 0;
  if (++stamp_ == 0) {  // wrapped: no slot may keep a stamp from 2^32 blocks ago
    std::fill(stamps_.begin(), stamps_.end(), 0u);
    stamp_ = 1;
  }
}

PixelRect Tiler::tile_rect(int t) const {
  const int tx = t % tiles_x_, ty = t / tiles_x_;
  return intersect({tx * tile_w_, ty * tile_h_, (tx + 1) * tile_w_, (ty + 1) * tile_h_},
                   {0, 0, viewport_.width_px, viewport_.height_px});
}

std::uint64_t Tiler::block_bytes(std::uint32_t vertices, std::uint32_t prims, std::uint32_t varyings) const {
  const auto& t = hw_.tiling;
  const double vertex_bytes = static_cast<double>(t.pb_vertex_position_bytes + t.pb_varying_bytes * varyings);
  const double compressed = std::ceil(vertex_bytes * vertices * t.pb_compression_ratio);
  return static_cast<std::uint64_t>(t.prim_block_header_bytes) + static_cast<std::uint64_t>(compressed) +
         static_cast<std::uint64_t>(t.prim_index_bytes) * prims;
}

std::uint64_t Tiler::allocated_with(std::uint64_t extra_block_bytes, std::uint64_t extra_ctrl_blocks) const {
  const auto page = static_cast<std::uint64_t>(hw_.tiling.pb_page_bytes);
  const std::uint64_t open_bytes = open_ ? block_bytes(open_keys_.size(), open_prims_, open_varyings_) : 0;
  const std::uint64_t data = closed_block_bytes_ + open_bytes + extra_block_bytes;
  const std::uint64_t ctrl = (ctrl_blocks_ + extra_ctrl_blocks) * static_cast<std::uint64_t>(hw_.tiling.control_stream_block_bytes);
  const std::uint64_t headers = static_cast<std::uint64_t>(hw_.tiling.region_header_bytes) * region_tiles_;
  auto pages = [page](std::uint64_t b) { return (b + page - 1) / page * page; };
  return pages(data) + pages(ctrl) + pages(headers);
}

std::uint64_t Tiler::allocated_bytes() const { return allocated_with(0, 0); }

void Tiler::close_block() {
  if (!open_) return;
  block_sizes_.push_back(block_bytes(open_keys_.size(), open_prims_, open_varyings_));
  closed_block_bytes_ += block_sizes_.back();
  block_vertices_total_ += open_keys_.size();
  open_ = false;
  open_keys_.clear();
  open_prims_ = 0;
}

void Tiler::touched_tiles(const Primitive& p, std::vector<int>& out) const {
  for_each_overlapped_tile(p.setup, tile_w_, tile_h_, test_, pattern_, [&](int tx, int ty) { out.push_back(ty * tiles_x_ + tx); });
}

BinResult Tiler::bin(std::uint32_t index, const Primitive& p, const VertexKeys& vertex_keys, TilerStats& stats,
                     std::optional<std::span<const int>> tiles) {
  if (!tiles) {
    touched_.clear();
    touched_tiles(p, touched_);
    tiles = touched_;
  }
  const std::span<const int> touched = *tiles;
  if (touched.empty()) return BinResult::NoSample;  // covers no sample: dropped, nothing written

  // Which primitive block the primitive joins.
  std::uint32_t new_keys = 0;
  std::uint64_t keys[3];
  bool distinct[3];  // not an earlier vertex of this primitive
  bool fresh[3];     // nor one of the open block's
  for (int i = 0; i < 3; ++i) {
    keys[i] = vertex_keys[i];
    distinct[i] = true;
    for (int j = 0; j < i; ++j) distinct[i] = distinct[i] && keys[j] != keys[i];
    fresh[i] = distinct[i] && !open_keys_.contains(keys[i]);
    if (fresh[i]) ++new_keys;
  }
  const bool fits = open_ && open_draw_ == p.draw &&
                    open_prims_ < static_cast<std::uint32_t>(hw_.tiling.prim_block_max_primitives) &&
                    static_cast<std::size_t>(open_keys_.size()) + new_keys <= static_cast<std::size_t>(hw_.tiling.prim_block_max_vertices);
  const std::uint32_t block_id = static_cast<std::uint32_t>(block_sizes_.size()) + (open_ && !fits ? 1u : 0u);

  // Control stream growth.
  const auto entry = static_cast<std::uint64_t>(hw_.tiling.control_stream_entry_bytes);
  const auto cblock = static_cast<std::uint64_t>(hw_.tiling.control_stream_block_bytes);
  auto blocks_for = [&](std::uint64_t entries) { return (entries * entry + cblock - 1) / cblock; };
  std::uint64_t extra_ctrl = 0;
  for (int t : touched) {
    const auto& tb = tiles_[static_cast<std::size_t>(t)];
    if (tb.blocks.empty() || tb.blocks.back() != block_id) {
      extra_ctrl += blocks_for(tb.blocks.size() + 1) - blocks_for(tb.blocks.size());
    }
  }
  // Capacity check with the primitive's vertex data included (a new block adds its header).
  const std::uint64_t vertex_bytes = block_bytes(fits ? open_keys_.size() + new_keys : 3,
                                                 fits ? open_prims_ + 1 : 1, p.varyings) -
                                     (fits ? block_bytes(open_keys_.size(), open_prims_, p.varyings) : 0);
  const auto capacity = static_cast<std::uint64_t>(hw_.tiling.pb_capacity_bytes);
  if (binned_ > 0 && allocated_with(vertex_bytes, extra_ctrl) > capacity) return BinResult::Full;

  if (!fits) {
    close_block();
    open_ = true;
    open_draw_ = p.draw;
    open_varyings_ = p.varyings;
  }
  // The block's new vertices: the fresh ones when it joins the open block, else (a new block,
  // empty) each distinct one.
  for (int i = 0; i < 3; ++i) {
    if (fits ? fresh[i] : distinct[i]) open_keys_.insert(keys[i]);
  }
  ++open_prims_;
  for (int t : touched) {
    auto& tb = tiles_[static_cast<std::size_t>(t)];
    tb.prims.push_back(index);
    if (tb.blocks.empty() || tb.blocks.back() != block_id) {
      ctrl_blocks_ += blocks_for(tb.blocks.size() + 1) - blocks_for(tb.blocks.size());
      tb.blocks.push_back(block_id);
      ++stats.control_stream_entries;
    }
  }
  ++binned_;
  ++stats.primitives_binned;
  stats.tile_references += touched.size();
  return BinResult::Binned;
}

void Tiler::finish_render(TilerStats& stats, DramTraffic& dram) {
  close_block();
  // The layout: region headers, then the control streams tile after tile, then the primitive blocks.
  const auto header = static_cast<std::uint64_t>(hw_.tiling.region_header_bytes);
  const auto entry = static_cast<std::uint64_t>(hw_.tiling.control_stream_entry_bytes);
  ctrl_offsets_.resize(tiles_.size());
  std::uint64_t ctrl = header * tiles_.size();
  for (std::size_t i = 0; i < tiles_.size(); ++i) {
    ctrl_offsets_[i] = ctrl;
    ctrl += tiles_[i].blocks.size() * entry;
  }
  data_base_ = ctrl;
  block_offsets_.resize(block_sizes_.size());
  std::uint64_t o = 0;
  for (std::size_t b = 0; b < block_sizes_.size(); ++b) {
    block_offsets_[b] = o;
    o += block_sizes_[b];
  }
  const std::uint64_t ctrl_bytes = ctrl_blocks_ * static_cast<std::uint64_t>(hw_.tiling.control_stream_block_bytes);
  const std::uint64_t headers = header * region_tiles_;  // the layout keeps the grid's places; only the area's are written
  stats.primitive_blocks += block_sizes_.size();
  stats.pb_vertices += block_vertices_total_;
  stats.pb_primitive_block_bytes += closed_block_bytes_;
  stats.pb_control_stream_bytes += ctrl_bytes;
  stats.pb_region_header_bytes += headers;
  stats.pb_bytes_written += closed_block_bytes_ + ctrl_bytes + headers;
  const std::uint64_t alloc = allocated_bytes();
  if (alloc > stats.pb_peak_allocated_bytes.value()) stats.pb_peak_allocated_bytes += alloc - stats.pb_peak_allocated_bytes.value();
  dram.write(DramClass::ParameterBuffer, closed_block_bytes_ + ctrl_bytes + headers);
}

std::uint64_t Tiler::tile_read_bytes(int t) const {
  const auto& tb = tiles_[static_cast<std::size_t>(t)];
  std::uint64_t bytes = static_cast<std::uint64_t>(hw_.tiling.region_header_bytes) +
                        tb.blocks.size() * static_cast<std::uint64_t>(hw_.tiling.control_stream_entry_bytes);
  for (std::uint32_t b : tb.blocks) bytes += block_sizes_[b];
  return bytes;
}

std::vector<ByteRange> Tiler::tile_read_ranges(int t) const {
  if (ctrl_offsets_.size() != tiles_.size() || block_offsets_.size() != block_sizes_.size()) {
    throw std::logic_error("Tiler::tile_read_ranges: the render is not finished (finish_render)");
  }
  std::vector<ByteRange> out;
  const auto header = static_cast<std::uint64_t>(hw_.tiling.region_header_bytes);
  const auto entry = static_cast<std::uint64_t>(hw_.tiling.control_stream_entry_bytes);
  out.push_back({header * static_cast<std::uint64_t>(t), header});
  const auto& tb = tiles_[static_cast<std::size_t>(t)];
  if (!tb.blocks.empty()) out.push_back({ctrl_offsets_[static_cast<std::size_t>(t)], tb.blocks.size() * entry});
  for (std::uint32_t b : tb.blocks) out.push_back({data_base_ + block_offsets_[b], block_sizes_[b]});
  return out;
}

void Tiler::reset() {
  block_offsets_.clear();
  ctrl_offsets_.clear();
  data_base_ = 0;
  for (auto& tb : tiles_) {
    tb.prims.clear();
    tb.blocks.clear();
  }
  block_sizes_.clear();
  open_ = false;
  open_keys_.clear();
  open_prims_ = 0;
  closed_block_bytes_ = 0;
  ctrl_blocks_ = 0;
  binned_ = 0;
  block_vertices_total_ = 0;
}

}  // namespace tbdr
