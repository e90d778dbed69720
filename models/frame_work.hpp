#pragma once
// The work a frame is made of, as the functional pipeline measured it, in the form the timing
// model schedules: per render (a pass, or a part of it cut by a partial render) the binning work,
// then per tile the parameter-buffer reads, tile loads, rasterisation, shading and stores; per
// dispatch its compute and memory traffic. Every number here is a count the functional units
// computed; the timing model only decides when each piece runs.
#include <array>
#include <cstdint>
#include <deque>
#include <string>
#include <vector>

#include "models/address_space.hpp"

#include "models/rasterizer.hpp"
#include "trace/traffic.hpp"

namespace tbdr {

/// A contiguous DRAM range an operation reads or writes (offset within its region).
struct ByteRange {
  std::uint64_t offset = 0;
  std::uint64_t bytes = 0;
};

/// One line request of an immediate-mode GPU's ROP caches to memory (models/rop.hpp): a miss's
/// fetch or a dirty line's write-back, at its offset in the framebuffer address space.
struct FramebufferAccess {
  std::uint64_t offset = 0;
  std::uint32_t bytes = 0;
  bool write = false;
  DramClass cls = DramClass::Color;
};

/// Binning work of one render: geometry processing and the parameter buffer writes.
struct BinningWork {
  std::uint64_t vertices_shaded = 0;
  std::uint64_t vertex_alu_ops = 0;
  std::uint64_t vertex_fetch_bytes = 0;
  std::uint64_t index_fetch_bytes = 0;
  std::uint64_t primitives_in = 0;
  std::uint64_t primitives_binned = 0;
  std::uint64_t tile_references = 0;
  std::uint64_t pb_write_bytes = 0;
};

/// One tile render (a strip, when the pass is split to fit tile memory). On an immediate-mode GPU
/// (FrameWork::immediate) one batch of a pass's primitives over the whole frame instead: its
/// geometry, rasterisation and shading, and its ROP caches' traffic.
struct TileWork {
  int tile_x = 0;
  int tile_y = 0;
  PixelRect rect;
  std::vector<ByteRange> pb_reads;        ///< parameter buffer ranges read by the ISP
  std::array<std::uint64_t, kDramClassCount> load_bytes{};   ///< tile loads (load ops, partial reloads)
  /// Stored images the shaders read at their pixels (G-buffer, visibility ids: `reads=`): the
  /// shaders' own reads through the texture cache and SLC while the tile shades.
  std::array<std::uint64_t, kDramClassCount> image_read_bytes{};
  std::array<std::uint64_t, kDramClassCount> store_bytes{};  ///< tile stores (store ops, partial stores, spill)
  std::uint64_t primitives = 0;           ///< primitives fetched and set up
  std::uint64_t samples = 0;              ///< samples rasterised and depth tested
  std::uint64_t invocations = 0;          ///< fragment shader invocations
  std::uint64_t quads = 0;
  /// Of `quads`, those of batches with nothing to run (TspStats::idle_quads): their tasks retire as
  /// soon as they are issued and hold no task slot while the tile's other tasks work.
  std::uint64_t idle_quads = 0;
  std::uint64_t alu_ops = 0;              ///< fragment ALU ops (helpers included)
  std::uint64_t texels = 0;              ///< bilinear-filtered texels (texture.texels_per_clock's unit)
  /// Part of alu_ops / texels the ISP waited for before it could go on (punch-through depth
  /// resolves, models/isp.hpp): the tile's ISP time includes the USCs' time for it.
  std::uint64_t isp_wait_alu_ops = 0;
  std::uint64_t isp_wait_texels = 0;
  /// Texture lines the tile's fragment shading touched (its footprint): sorted, unique offsets in
  /// the texture address space (FrameWork::texture_bytes; models/texture_unit.hpp).
  std::vector<std::uint64_t> texture_lines;
  std::uint64_t texture_line_accesses = 0;  ///< distinct lines per quad and fetch, summed (before merging)
  std::uint64_t tile_buffer_bytes = 0;    ///< on-chip tile buffer bytes read + written
  /// Tile-buffer bytes past the on-chip budget (pls.over_budget = spill) that the shaders read and
  /// write in memory instead: their own loads and stores during shading, not tile loads/stores.
  std::uint64_t spill_read_bytes = 0;
  std::uint64_t spill_write_bytes = 0;
  std::uint64_t tag_bytes = 0;            ///< tag buffer bytes read + written
  std::uint64_t depth_bytes = 0;          ///< on-chip depth/stencil bytes read + written
  // Immediate mode only:
  BinningWork geometry;  ///< the batch's geometry, processed as the batch goes down the pipeline
  std::vector<FramebufferAccess> rop_depth;  ///< ROP depth cache misses and write-backs, while the ISP tests
  std::vector<FramebufferAccess> rop_color;  ///< ROP colour cache misses and write-backs (and the pass's flush)
};

/// One render: binning, then its tiles in dispatch order.
struct RenderWork {
  BinningWork binning;
  std::vector<TileWork> tiles;
  bool partial = false;
};

/// A pass or a dispatch, in trace order.
struct CommandWork {
  std::string name;            ///< "pass0.main" / "dispatch1.tile_light_cull"
  /// The frame of a sequence it belongs to (0 for a single frame): the timing model starts a
  /// frame's work after the one before it as gpu.frames_in_flight allows.
  int frame = 0;
  bool is_dispatch = false;
  bool depends_on_previous = false;  ///< reads something an earlier command produced
  /// A pass's renders (a deque: a render published to the timing model stays where it is while
  /// the functional run appends the next, models/work_feed.hpp).
  std::deque<RenderWork> renders;
  /// A pass's framebuffer layout, known when it starts (FrameAddressMap places it then): one
  /// slot per tile of `tile_slot_bytes`, what a tile's load and store ops can move (the
  /// attachments it loads or stores, TileMemory::tile_slot_bytes), for `tile_slots` tiles; and,
  /// once it has a partial render, one slot per tile of `partial_slot_bytes` for what partial
  /// renders store and the renders after them reload (every attachment).
  std::uint64_t tile_slot_bytes = 0;
  std::uint64_t partial_slot_bytes = 0;
  std::uint64_t tile_slots = 0;
  /// A spilling pass's spill slot per tile (pls.over_budget = spill): the most any tile render
  /// spilled (its larger direction), known when the pass is complete; 0 when nothing spills.
  std::uint64_t spill_slot_bytes = 0;
  std::array<std::uint64_t, kDramClassCount> read_bytes{};   ///< dispatch traffic; for passes, buffers read once at the start
  std::array<std::uint64_t, kDramClassCount> write_bytes{};  ///< dispatch traffic
  // dispatches
  std::uint64_t compute_alu_ops = 0;
  std::uint64_t compute_threads = 0;
  std::uint64_t compute_texels = 0;  ///< bilinear-filtered texels (texture.texels_per_clock's unit)
  /// Texture lines the dispatch's material fetches touched: each workgroup tile's footprint
  /// (sorted, unique offsets in the texture address space, as TileWork::texture_lines) one after
  /// another in dispatch order. Their bytes are not in read_bytes: they go through the texture cache.
  std::vector<std::uint64_t> texture_lines;
  std::uint64_t texture_line_accesses = 0;  ///< distinct lines per quad and fetch, summed (before merging)

  /// A dispatch opened with its header (name, is_dispatch, depends_on_previous) before it ran
  /// takes what it computed from `ran`, the same dispatch run: its traffic and work (a
  /// dispatch has no renders and no slots; the header is left alone: a reader may be reading it
  /// meanwhile, models/work_feed.hpp).
  void take_dispatch_content(CommandWork&& ran) {
    read_bytes = ran.read_bytes;
    write_bytes = ran.write_bytes;
    compute_alu_ops = ran.compute_alu_ops;
    compute_threads = ran.compute_threads;
    compute_texels = ran.compute_texels;
    texture_lines = std::move(ran.texture_lines);
    texture_line_accesses = ran.texture_line_accesses;
  }
};

/// The whole frame's work.
struct FrameWork {
  int width = 0;
  int height = 0;
  int tile_width = 0;
  int tile_height = 0;
  int tiles_x = 0;
  std::uint64_t texture_bytes = 0;  ///< size of the texture address space TileWork::texture_lines index
  bool immediate = false;           ///< gpu.mode=imr: tiles are primitive batches over the whole frame
  int frames = 1;                   ///< frames of the sequence the commands belong to (CommandWork::frame)
  std::uint64_t framebuffer_bytes = 0;  ///< size of the address space FramebufferAccess::offset indexes
  /// Regions the address space holds before the first command (empty: none), which every frame
  /// reuses by name as a sequence's later frames do: a sampled window's frames get the addresses
  /// the sequence's first frames gave their data (TimingResult::address_layout of the first window).
  std::vector<AddressRegion> address_layout;
  std::vector<CommandWork> commands;
};

}  // namespace tbdr
