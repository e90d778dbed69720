#pragma once
// Per-tile records of a frame (the results database's `tiles` table): one row per command and
// tile, strips and partial renders of the same tile summed into it.
#include <cstddef>
#include <map>
#include <tuple>
#include <vector>

#include "kernel/stats.hpp"
#include "models/frame_work.hpp"

namespace tbdr {

/// Collects the tiles' cycles, samples and DRAM bytes as they finish, one row per (command, tile).
class TileRecordBook {
 public:
  /// Books a finished tile render of `command` that took `cycles` from fetch to stored.
  void add(std::size_t command, const TileWork& t, double cycles) {
    std::uint64_t bytes = 0;
    for (std::size_t c = 0; c < kDramClassCount; ++c) bytes += t.load_bytes[c] + t.image_read_bytes[c] + t.store_bytes[c];
    for (const auto& br : t.pb_reads) bytes += br.bytes;
    auto [it, inserted] = index_.try_emplace(std::make_tuple(command, t.tile_x, t.tile_y), rows_.size());
    if (inserted) rows_.push_back({static_cast<std::int64_t>(command), t.tile_x, t.tile_y, 0, 0, 0});
    TileRecord& row = rows_[it->second];
    row.cycles += cycles;
    row.samples += static_cast<double>(t.samples);
    row.dram_bytes += static_cast<double>(bytes);
  }
  /// The rows in the order their tiles first finished.
  std::vector<TileRecord> take() { return std::move(rows_); }

 private:
  std::vector<TileRecord> rows_;
  std::map<std::tuple<std::size_t, int, int>, std::size_t> index_;  ///< (command, x, y) -> row
};

}  // namespace tbdr
