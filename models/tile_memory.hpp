#pragma once
// On-chip tile memory and pixel local storage: how many bytes per pixel a pass keeps on chip
// (its color-like attachments at their sample count, plus PLS) against the configured budget,
// the load ops at the start of a tile (clear / load from DRAM / don't care), the store ops and
// the writeback at its end (with the framebuffer compression ratio), the resolve of multisampled
// attachments, and the stores and reloads of a partial render. Transient attachments never
// touch DRAM. A pass over budget pays per pls.over_budget: `split_render` (the default, as the Mesa
// PowerVR driver does not merge a subpass into a render when its attachments would not fit the USC
// output registers, pvr_hw_pass.c) ends the render before the first draw that fetches an attachment
// an earlier draw wrote: everything is stored, and the rest of the pass is a new render that reads
// the fetched attachments from memory as images; `spill` (what that driver does within one
// subpass: render targets that do not fit go to memory-backed "tile buffers",
// USC_MRT_RESOURCE_TYPE_MEMORY) sends the share of every shader tile-buffer access that exceeds the
// budget to DRAM, and reads the spilled writes back at the end of the tile; `smaller_tiles` renders
// each tile as several strips that fit (each strip re-reads the tile's parameter buffer data and
// re-rasterises its primitives).
#include <cstdint>
#include <memory>
#include <vector>

#include "models/hw_config.hpp"
#include "models/render_state.hpp"
#include "models/tile_signatures.hpp"
#include "models/tsp.hpp"
#include "trace/traffic.hpp"
#include "kernel/stats.hpp"

namespace tbdr {

// Declared once: X(type, member = stored name, unit, Sum | Gauge, description).
#define TBDR_TILE_MEMORY_STATS(X) \
  X(Counter, onchip_need_bytes_per_pixel, "bytes/pixel", Gauge, "Tile memory the pass needs per pixel: the larger of its colour attachments x samples and its PLS (they share storage)") \
  X(Counter, onchip_budget_bytes_per_pixel, "bytes/pixel", Gauge, "Tile memory available per pixel") \
  X(Counter, tile_split_factor, "strips", Gauge, "Strips each tile is rendered in to fit the budget (1 = fits)") \
  X(Counter, tile_load_bytes, "bytes", Sum, "Attachment bytes loaded from DRAM into tile memory (uncompressed)") \
  X(Counter, tile_clear_bytes, "bytes", Sum, "Tile memory bytes initialised by clear load ops") \
  X(Counter, tile_store_bytes, "bytes", Sum, "Attachment bytes written back from tile memory (uncompressed)") \
  X(Counter, writeback_dram_bytes, "bytes", Sum, "Bytes the writeback sent to DRAM after compression") \
  X(Counter, partial_render_store_bytes, "bytes", Sum, "Bytes stored to DRAM at partial renders") \
  X(Counter, partial_render_reload_bytes, "bytes", Sum, "Bytes reloaded after partial renders") \
  X(Counter, spill_bytes, "bytes", Sum, "Tile buffer bytes spilled to DRAM and read back (pls.over_budget = spill)") \
  X(Counter, split_renders, "renders", Sum, "Renders begun at a subpass boundary because the pass does not fit on chip (pls.over_budget = split_render; stores and reloads booked as a partial render's)") \
  X(Counter, resolved_samples, "samples", Sum, "Multisampled samples averaged into resolve targets") \
  X(Counter, eliminated_tile_stores, "tiles", Sum, "Colour tile stores skipped because the tile's signature matched the previous frame's (writeback.transaction_elimination)") \
  X(Counter, eliminated_store_bytes, "bytes", Sum, "Bytes those skipped stores would have sent to DRAM (after compression)") \
  X(Counter, signature_bytes, "bytes", Sum, "Tile signature bytes read (the previous frame's) and written (this frame's) in memory")
/// Statistics of tile memory and writeback.
struct TileMemoryStats {
  TBDR_STATS(TBDR_TILE_MEMORY_STATS)
};

/// The forward light stack's layout in a pixel's local storage (docs/kernels.md; the
/// forward_light_stack generator writes it; Billeter 2015, "Forward Light Stack"): a 32-bit count,
/// then 16-bit light indices.
inline constexpr std::uint32_t kPlsStackCountBytes = 4;
inline constexpr std::uint32_t kPlsLightIndexBytes = 2;
/// Light indices a stack of `pls_bytes_per_pixel` bytes of pixel local storage holds.
std::uint32_t pls_light_stack_capacity(std::uint32_t pls_bytes_per_pixel);

/// Refuses a pass whose pixel local storage layout exceeds pls.max_pls_bytes_per_pixel, as a
/// driver refuses a shader that declares more than MAX_SHADER_PIXEL_LOCAL_STORAGE_SIZE_EXT
/// (InputError naming the pass and its trace line, its bytes and the limit).
void check_pls_layout(const PlsParams& p, const PassDesc& pass, const std::string& trace_path = {});

/// The DRAM traffic class of an attachment usage.
DramClass traffic_class_of(AttachmentUsage u);

/// Tile memory of one pass.
class TileMemory {
 public:
  /// Computes the pass's on-chip needs against the budget and records them (and split renders) in
  /// `stats`; refuses a
  /// pass whose pixel local storage exceeds pls.max_pls_bytes_per_pixel (check_pls_layout).
  /// Holds the pass's pixel local storage (if it declares one) and points `ctx.pls` at it; and,
  /// when a draw's shader evaluates lights and writes colour, the pass's lit-sample ledger
  /// (`ctx.lit_samples`: TspStats::hidden_lit_samples).
  TileMemory(RenderContext& ctx, TileMemoryStats& stats);
  TileMemory(const TileMemory&) = delete;
  TileMemory& operator=(const TileMemory&) = delete;

  std::uint32_t need_bytes_per_pixel() const { return need_; }
  std::uint32_t budget_bytes_per_pixel() const { return budget_; }
  /// The strips a tile is rendered in (one strip when the pass fits).
  std::vector<PixelRect> strips(const PixelRect& tile) const;
  // The tile operations book their counts in `stats` (the tile's own, when tiles render in
  // parallel) and write only the tile's pixels: tiles may run on several threads at once.
  /// Start of a tile render: load ops, or the reload of what a partial render stored.
  void begin_tile(const PixelRect& rect, bool resumed_after_partial, DramTraffic& dram, TileMemoryStats& stats) const;
  /// End of a tile render: store ops (partial = a partial render: everything goes to DRAM).
  void end_tile(const PixelRect& rect, bool partial, DramTraffic& dram, TileMemoryStats& stats) const;
  /// Books the spill of one tile render: the over-budget share of the shaders' tile buffer
  /// reads and writes goes to DRAM, plus the read-back of the spilled writes.
  void spill(std::uint64_t tile_buffer_read_bytes, std::uint64_t tile_buffer_write_bytes, DramTraffic& dram,
             TileMemoryStats& stats) const;
  /// What the load and store ops of a render of tile `rect` can move: the attachments the pass
  /// loads or stores (not transient), compressed as writeback.compression_ratio says. The timing
  /// model's framebuffer slot per tile, known before any tile renders.
  std::uint64_t tile_slot_bytes(const PixelRect& rect) const { return slot_bytes(rect, false); }
  /// What a partial render of tile `rect` stores and the render after it reloads: every attachment.
  std::uint64_t partial_slot_bytes(const PixelRect& rect) const { return slot_bytes(rect, true); }
  /// Share of tile buffer accesses that go to memory (0 when the pass fits or tiles are split).
  double spill_fraction() const { return spill_fraction_; }
  /// pls.over_budget = split_render on a pass over budget: the index of the draw before which the
  /// render ends (the first draw that fetches a colour attachment an earlier draw wrote), or -1.
  int split_draw() const { return split_draw_; }
  /// Starts the render after the split: the attachments the rest of the pass only fetches stay in
  /// memory (not reloaded, not stored again), the draws read them as images (their fetch bytes
  /// become per-pixel reads of the attachment's DRAM class), and the budget holds the rest.
  void begin_split_render(std::vector<DrawContext>& draws);

 private:
  std::uint64_t attachment_bytes(const Attachment& a, const PixelRect& r) const;
  /// Compressed bytes of the attachments a tile's load and store ops move (or of every one).
  std::uint64_t slot_bytes(const PixelRect& r, bool every_attachment) const;
  /// Bytes per pixel the pass keeps on chip: its colour-like attachments not in memory, or its PLS.
  std::uint32_t onchip_bytes_per_pixel() const;
  /// Sets spill_fraction_ (policy spill) or split_ (smaller_tiles) for the current need.
  void fit_budget(PlsOverBudget policy);
  /// The split point and the attachments that then stay in memory (pls.over_budget = split_render).
  void find_split();
  RenderContext& ctx_;
  TileMemoryStats& stats_;
  std::uint32_t need_ = 0;
  std::uint32_t budget_ = 0;
  int split_ = 1;
  double spill_fraction_ = 0;
  int split_draw_ = -1;
  std::vector<std::uint8_t> in_memory_;  ///< per attachment of the pass: 1 after the split
  std::vector<std::uint8_t> evicted_;    ///< per attachment: stays in memory after the split
  PlsState pls_;  ///< the pass's pixel local storage (empty when it declares none)
  std::unique_ptr<LitSampleLedger> lit_samples_;  ///< the pass's lit colour writes per sample, or null
  /// writeback.transaction_elimination: per attachment, its signature table (a stored colour
  /// attachment of a tile-based pass; null for the others, or when off).
  std::vector<TileSignatures::Table*> signatures_;
  /// Transaction elimination of `a`'s store of tile `r` (a whole tile, its colours computed):
  /// books the signatures' traffic and returns true when the store is skipped.
  bool eliminate_store(std::size_t ai, const Attachment& a, const PixelRect& r, std::uint64_t compressed, DramTraffic& dram,
                       TileMemoryStats& stats) const;
  /// The tile index of `r` when it is a whole tile of the frame's grid, else -1.
  long whole_tile_index(const PixelRect& r) const;
};

}  // namespace tbdr
