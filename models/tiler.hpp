#pragma once
// The tiler: bins every primitive into the tiles it overlaps and writes the parameter buffer with
// its real byte layout: primitive blocks (at most N vertices of screen-space vertex data plus
// per-primitive index data), per-tile control streams in fixed-size blocks listing the primitive
// blocks that touch the tile, and one region header per tile, allocated in pages. When the next
// primitive would not fit in the configured capacity, bin() refuses it and the caller runs a
// partial render.
#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "models/frame_work.hpp"
#include "models/hw_config.hpp"
#include "models/rasterizer.hpp"
#include "models/render_state.hpp"
#include "trace/traffic.hpp"
#include "kernel/stats.hpp"

namespace tbdr {

// Declared once: X(type, member = stored name, unit, Sum | Gauge, description).
#define TBDR_TILER_STATS(X) \
  X(Counter, primitives_binned, "primitives", Sum, "Primitives written to the parameter buffer") \
  X(Counter, tile_references, "references", Sum, "Sum over primitives of the tiles each touches") \
  X(Counter, primitive_blocks, "blocks", Sum, "Primitive blocks written") \
  X(Counter, pb_vertices, "vertices", Sum, "Vertices written into primitive blocks") \
  X(Counter, control_stream_entries, "entries", Sum, "Control stream entries (tile x primitive block)") \
  X(Counter, pb_primitive_block_bytes, "bytes", Sum, "Primitive block bytes written") \
  X(Counter, pb_control_stream_bytes, "bytes", Sum, "Control stream bytes allocated (whole blocks)") \
  X(Counter, pb_region_header_bytes, "bytes", Sum, "Region header bytes written") \
  X(Counter, pb_bytes_written, "bytes", Sum, "Parameter buffer bytes written in all") \
  X(Counter, pb_bytes_read, "bytes", Sum, "Parameter buffer bytes read back by the ISP") \
  X(Counter, pb_peak_allocated_bytes, "bytes", Gauge, "Largest page-rounded parameter buffer use of one render") \
  X(Counter, partial_renders, "renders", Sum, "Renders forced by a full parameter buffer")
/// Statistics of the tiler and the parameter buffer.
struct TilerStats {
  TBDR_STATS(TBDR_TILER_STATS)
};

/// What Tiler::bin did with a primitive.
enum class BinResult : std::uint8_t {
  Binned,    ///< written to the parameter buffer and the lists of the tiles it touches
  NoSample,  ///< covers no sample of any tile: dropped, nothing written
  Full,      ///< would overflow the parameter buffer: nothing written, a partial render is due
};

/// The tiling engine and the parameter buffer of one render.
class Tiler {
 public:
  Tiler(const HwConfig& hw, const Viewport& viewport, const SamplePattern& pattern);

  int tiles_x() const { return tiles_x_; }
  int tiles_y() const { return tiles_y_; }
  int tile_count() const { return tiles_x_ * tiles_y_; }
  int tile_width() const { return tile_w_; }
  int tile_height() const { return tile_h_; }
  /// Pixel rectangle of tile t (clipped to the viewport).
  PixelRect tile_rect(int t) const;
  /// The render's area (RenderContext::render_area): region headers are written for the tiles
  /// that overlap it only, as for a render target of that size. Default: the whole viewport.
  void set_render_area(const PixelRect& area);
  /// Whether tile t overlaps the render area (the tiles a render has).
  bool in_render_area(int t) const { return !intersect(tile_rect(t), area_).empty(); }
  /// The render area.
  const PixelRect& render_area() const { return area_; }

  /// Bins primitive `index` of the render's primitive table, whose vertices are `keys`. Returns
  /// Full, binning nothing, when the page-rounded parameter buffer would exceed its capacity:
  /// the caller renders what is binned (a partial render), calls reset(), and bins the primitive
  /// again. NoSample: the primitive touches no tile (the caller need not keep it).
  /// `tiles`: what touched_tiles() gives for `p`, when the caller looked it up ahead.
  BinResult bin(std::uint32_t index, const Primitive& p, const VertexKeys& keys, TilerStats& stats,
                std::optional<std::span<const int>> tiles = std::nullopt);
  /// Appends the tiles `p` touches (tile indices, row by row) to `out`: the tiling engine's tile
  /// test (tiling.binning). Only reads: callable on several threads at once.
  void touched_tiles(const Primitive& p, std::vector<int>& out) const;
  /// Closes the open primitive block and books the render's parameter buffer writes and region
  /// headers (call once per render, before the tiles are rendered).
  void finish_render(TilerStats& stats, DramTraffic& dram);
  /// Primitives binned into tile t, in submission order.
  const std::vector<std::uint32_t>& tile_primitives(int t) const { return tiles_[static_cast<std::size_t>(t)].prims; }
  /// Parameter buffer bytes the ISP reads to render tile t: region header, control stream and
  /// every primitive block it references.
  std::uint64_t tile_read_bytes(int t) const;
  /// The parameter buffer ranges the ISP reads for tile t (offsets in the parameter buffer:
  /// region headers first, then the control streams tile by tile, then the primitive blocks).
  std::vector<ByteRange> tile_read_ranges(int t) const;
  /// True when nothing has been binned since the last reset.
  bool empty() const { return binned_ == 0; }
  /// Frees the parameter buffer after a render.
  void reset();
  /// Current page-rounded allocation.
  std::uint64_t allocated_bytes() const;

 private:
  struct TileBin {
    std::vector<std::uint32_t> prims;
    std::vector<std::uint32_t> blocks;  ///< primitive blocks referenced, in order (control stream entries)
  };
  std::uint64_t block_bytes(std::uint32_t vertices, std::uint32_t prims, std::uint32_t varyings) const;
  std::uint64_t allocated_with(std::uint64_t extra_block_bytes, std::uint64_t extra_ctrl_blocks) const;
  void close_block();

  const HwConfig& hw_;
  SamplePattern pattern_;
  TileTest test_;
  int tile_w_, tile_h_, tiles_x_, tiles_y_;
  Viewport viewport_;
  PixelRect area_;                  ///< the render area (set_render_area)
  std::uint64_t region_tiles_ = 0;  ///< tiles overlapping it: one region header each
  std::vector<TileBin> tiles_;
  std::vector<std::uint64_t> block_sizes_;  ///< bytes of each closed block
  // The parameter buffer's layout, built by finish_render before the tiles read it (from
  // several threads: tile_read_ranges only reads).
  std::vector<std::uint64_t> block_offsets_;  ///< each closed block's offset in the primitive data
  std::vector<std::uint64_t> ctrl_offsets_;   ///< each tile's control stream offset
  std::uint64_t data_base_ = 0;               ///< where the primitive blocks start
  /// The distinct vertices of the open primitive block: their keys in an open-addressing table
  /// (a linear search of up to tiling.prim_block_max_vertices keys, three or six times per
  /// primitive, was half of binning's serial time), emptied in O(1) by a stamp per block.
  class BlockVertices {
   public:
    explicit BlockVertices(std::uint32_t max_vertices);
    bool contains(std::uint64_t key) const;
    void insert(std::uint64_t key);  ///< (a key not contained)
    std::uint32_t size() const { return size_; }
    void clear();

   private:
    std::size_t slot_of(std::uint64_t key) const;
    std::vector<std::uint64_t> keys_;
    std::vector<std::uint32_t> stamps_;  ///< a slot holds a key of this block when its stamp is stamp_
    std::uint32_t stamp_ = 1;
    std::uint32_t size_ = 0;
    int shift_ = 0;  ///< 64 - log2(slots)
  };
  // The open primitive block.
  BlockVertices open_keys_;
  std::uint32_t open_prims_ = 0;
  std::uint32_t open_draw_ = 0;
  std::uint32_t open_varyings_ = 0;
  bool open_ = false;
  std::uint64_t closed_block_bytes_ = 0;
  std::uint64_t ctrl_blocks_ = 0;  ///< control stream blocks allocated over all tiles
  std::uint64_t binned_ = 0;
  std::uint64_t block_vertices_total_ = 0;
  std::vector<int> touched_;  ///< scratch
};

}  // namespace tbdr
