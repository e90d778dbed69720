#pragma once
// The render of one pass through the units: geometry and binning of its draws in draw order
// (serial: the parameter buffer fills in submission order), then a render of every touched tile
// (tile memory load, ISP, TSP, tile memory store) whenever the parameter buffer fills and at the
// end. The tiles of one render run on a pool of threads: tiles own disjoint pixels of every
// attachment, PLS and per-pixel counter, and read the draws, primitives, light lists and texture
// layout without changing them. Each thread has its own worker context (ISP and TSP with their
// scratch, the tile's texture line list and DRAM traffic); each tile returns its TileWork and its
// statistic and traffic deltas, merged into the pass in tile dispatch order, so statistics,
// TileWork lists and images are the same at any thread count. A partial render is a barrier: its
// tiles finish before binning resumes.
#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <vector>

#include "models/pass_stats.hpp"
#include "models/frame_work.hpp"
#include "models/geometry_unit.hpp"
#include "models/hw_config.hpp"
#include "models/isp.hpp"
#include "models/render_state.hpp"
#include "models/tile_memory.hpp"
#include "models/tiler.hpp"
#include "models/tsp.hpp"
#include "trace/traffic.hpp"

namespace tbdr {

class ThreadPool;
class WorkFeed;

/// Tile indices in the configured dispatch order (tiling.tile_order).
std::vector<int> tile_order(int tiles_x, int tiles_y, TileOrder order);

/// Renders one pass through the units (see the file comment). The geometry unit delivers each
/// primitive to it (PrimitiveSink): it joins the render's table and is binned at once.
class PassRenderer final : private PrimitiveSink {
 public:
  /// `pool` runs the tiles of each render; its size() worker contexts are made here.
  PassRenderer(RenderContext& ctx, const HwConfig& frame_hw, PassStats& stats, DramTraffic& dram, CommandWork& cw,
               ThreadPool& pool);
  ~PassRenderer();
  PassRenderer(const PassRenderer&) = delete;
  PassRenderer& operator=(const PassRenderer&) = delete;

  /// Whether the pass's layout for the timing model (CommandWork's slots) is final before any
  /// tile renders: not when a tile may spill (its spill slot is measured) nor for gpu.mode=imr.
  bool layout_known_at_start() const;
  /// Hands the pass's work to `feed` as it goes (layout_known_at_start() must hold): opens the
  /// command there now, publishes each render when binned and each tile as merged; the caller
  /// closes the command (feed_command()) after finish().
  void publish_to(WorkFeed& feed);
  /// The command's index in the feed (publish_to).
  std::size_t feed_command() const { return feed_command_; }
  /// The pass's work: the caller's, or the feed's open command (publish_to). Its header's
  /// read_bytes may be set until the timing model takes the pass's first render to render.
  CommandWork& work() { return *cw_; }
  /// Geometry, binning and rendering of every draw; a partial render whenever the parameter
  /// buffer is full: bin() then finish().
  void run();
  /// Geometry and binning of every draw, partial renders included (their tiles render as they
  /// come), up to the pass's last render, binned and published but not rendered (gpu.mode=imr:
  /// everything). What a pass reads of earlier passes is read by its tiles only, so the frame
  /// bins the next pass before the tiles of this one (models/command_processor.cpp).
  void bin();
  /// Renders the last render's tiles (after bin()).
  void finish();
  /// Starts the last render's tiles on the pool's helpers and returns (finish() then joins
  /// them): the caller may bin the next pass meanwhile, with no other job on the pool.
  void start_finish();
  /// Runs `fn` once, before the next tiles of this pass render (the frame finishes the pass
  /// before it there, when this one was binned ahead of it).
  void before_tiles(std::function<void()> fn) { before_tiles_ = std::move(fn); }
  /// Host wall seconds the renders' tile loops took (the parallel part; bench/speed.sh reads it).
  double tile_seconds() const { return tile_seconds_; }

 private:
  /// What one thread renders tiles with: its own TSP and ISP (their scratch), the current tile's
  /// texture line list and the DRAM traffic the tile books.
  struct TileWorker;
  /// One tile (or strip of a tile) to render: its index and its pixels.
  struct TileJob {
    int tile = 0;
    PixelRect rect;
  };
  /// What a tile render returns: its work for the timing model and its statistic and traffic
  /// deltas, added to the pass's in tile order (merge).
  struct TileResult {
    TileWork work;
    IspStats isp;
    TspStats tsp;
    TileMemoryStats tile_memory;
    std::uint64_t pb_bytes_read = 0;  ///< TilerStats::pb_bytes_read of the tile
    DramTraffic dram;
  };

  /// Takes a primitive from the geometry unit: tbdr bins it (dropped when it touches no tile; a
  /// partial render first when the parameter buffer is full), imr adds it to the current batch.
  void accept(const Primitive& p, const VertexKeys& keys, std::optional<std::span<const int>> tiles) override;
  /// tbdr: the tiler's tile test (Tiler::touched_tiles); imr bins nothing.
  bool tiles_touched(const Primitive& p, std::vector<int>& tiles) const override;
  /// imr: renders the batch of primitives taken since the last (`last`: the pass's last batch).
  void render_batch(bool last);
  /// imr has no binning: the whole frame is one "tile" and nothing goes through a parameter buffer.
  static HwConfig pass_hw(const HwConfig& frame_hw, const RenderContext& ctx);
  /// Points the context at the pass's hardware.
  static RenderContext& bind(RenderContext& ctx, const HwConfig& hw);
  /// The binning work since the previous render.
  BinningWork binning_since_last_render();
  /// Renders every tile the binned primitives touch (all tiles for the last render of the pass):
  /// prepare_render then render_tiles.
  void render(bool partial);
  /// Ends a render's binning: its RenderWork and parameter buffer bytes, its tile jobs; publishes it.
  void prepare_render(bool partial);
  /// Renders the prepared render's tiles (before_tiles first).
  void render_tiles(bool partial);
  /// render_tiles in two halves: the tiles posted to the pool, then joined and the render ended.
  void start_tiles(bool partial);
  void join_tiles();
  /// One tile (or strip of a tile) on worker `w`: loads, ISP and TSP, stores; what it cost.
  /// imr renders a pass as batches over the whole frame: the tile memory's begin (clears) only
  /// with the first (`begin`), its end (resolves) and the ROP flush only with the last (`end`).
  TileResult render_tile(TileWorker& w, int t, const PixelRect& r, const std::vector<std::uint32_t>& prims, bool partial,
                         bool begin = true, bool end = true);
  /// Adds a tile's deltas to the pass; returns its work.
  TileWork merge(TileResult&& r);
  /// The G-buffer or visibility target the pass's shaders store surfaces in (the first
  /// non-colour target they write), when it holds none yet: allocated before the tiles run (the
  /// TSP would allocate it at its first write, from whichever thread). Returns it, or nullptr.
  AttachmentImage* allocate_surfaces();
  /// Releases what allocate_surfaces allocated if no tile stored a surface in it, leaving it as
  /// the TSP would have.
  static void release_unwritten_surfaces(AttachmentImage* fresh);

  HwConfig hw_;  ///< the frame's hardware, with one frame-sized tile in imr mode
  RenderContext& ctx_;
  PassStats& stats_;
  DramTraffic& dram_;
  CommandWork* cw_;           ///< the pass's work: the caller's, or the feed's open command
  WorkFeed* feed_ = nullptr;  ///< where renders and tiles are published as they are made (publish_to)
  std::size_t feed_command_ = 0;  ///< the pass's command in feed_
  std::function<void()> before_tiles_;  ///< before_tiles
  // The render whose tiles start_tiles posted (until join_tiles).
  bool tiles_started_ = false;
  bool running_partial_ = false;
  AttachmentImage* running_fresh_ = nullptr;  ///< its surface store, released if no tile wrote it
  std::chrono::steady_clock::time_point tiles_start_;
  AttachmentImage* fresh_ = nullptr;     ///< what the prepared render's allocate_surfaces allocated
  ThreadPool& pool_;
  GeometryUnit geometry_;
  Tiler tiler_;
  TileMemory tile_memory_;
  std::vector<std::unique_ptr<TileWorker>> workers_;  ///< one per thread of the pool
  std::vector<int> order_;               ///< tile indices in dispatch order
  std::vector<std::uint8_t> resumed_;    ///< per tile: rendered before by a partial render
  std::vector<TileJob> jobs_;            ///< the current render's tiles, in dispatch order
  std::vector<TileResult> results_;      ///< their results, by job
  std::vector<std::uint8_t> rendered_;   ///< by job: its result is ready to merge
  std::size_t merged_ = 0;               ///< jobs merged so far (in dispatch order)
  std::mutex merge_mutex_;               ///< held while a thread marks its job done and merges
  RenderWork immediate_;                 ///< imr: the pass's one render, a "tile" per batch
  std::vector<std::uint32_t> batch_indices_;  ///< imr: the current batch's primitive indices
  bool first_batch_ = true;              ///< imr: no batch rendered yet (it clears the attachments)
  GeometryStats geometry_base_;          ///< the statistics at the start of the current render
  TilerStats tiler_base_;
  double tile_seconds_ = 0;
};

}  // namespace tbdr
