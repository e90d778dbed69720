#pragma once
// Transaction elimination (writeback.transaction_elimination): before the pixel back end stores a
// colour tile it computes the tile's signature and compares it with the signature the same tile of
// the same pass had in the previous frame of a sequence. When they match, memory already holds
// these pixels and the store is skipped. The signatures live in memory, one per tile and stored
// colour attachment: reading the previous one and writing the new one is the mechanism's own
// traffic (TileMemory::end_tile books it). Arm's Mali GPUs do this ("Transaction Elimination": a
// CRC per tile compared with the previous frame's); the model's signature is a 64-bit FNV-1a hash
// of the tile's stored values, so equal signatures mean equal pixels for every tile it compares.
#include <cstddef>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace tbdr {

/// Bytes of one tile's signature in memory (a 64-bit signature per tile and colour attachment).
inline constexpr std::uint64_t kTileSignatureBytes = 8;

/// The signatures of every pass's stored colour attachments, kept from one frame of a sequence to
/// the next (the run driver owns them; FrameInputs::tile_signatures points at them).
class TileSignatures {
 public:
  /// One pass attachment's signatures, per tile (row-major tile index).
  struct Table {
    std::vector<std::uint64_t> previous, current;
    std::vector<char> has_previous, has_current;  ///< (char, not bool: tiles write their own entry concurrently)
  };
  /// A new frame: the signatures of the frame that ended become the previous frame's.
  void begin_frame();
  /// The table of `key` (a pass's attachment: "<pass>/<attachment>") sized for `tiles` tiles, made
  /// ready before the pass's tiles render (not thread-safe: from the pass's set-up). Tiles then
  /// read their previous entry and write their current one, each its own.
  Table* prepare(const std::string& key, std::size_t tiles);

 private:
  std::map<std::string, Table> tables_;
};

}  // namespace tbdr
