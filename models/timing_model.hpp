#pragma once
// The cycle-approximate timing model: schedules the frame's work (models/frame_work.hpp, measured
// by the functional pipeline) on the GPU's units as resources with throughput, latency and
// bounded queues, in the discrete-event kernel, with every DRAM access going through the caches
// and the banked DRAM at real addresses (models/memory_system.hpp).
//
// Units and their service times (cycles of the core clock):
//   binning engine (geometry + tiler): max(primitives in / geometry.primitives_per_clock,
//     primitives binned / tiling.primitives_per_clock), while its vertex shaders reserve the USCs'
//     ALU server and its vertex/index reads and parameter-buffer writes stream through memory;
//   tile fetch (DMA): a tile's parameter-buffer reads and tile loads, up to isp.tiles_in_flight
//     tiles between fetch and leaving the ISP;
//   ISP: max(primitives, samples / (isp.samples_per_clock x isp.raster_pipes)) per tile, plus
//     the USC time of the shading it waited for at punch-through depth resolves, one tile at a
//     time, in the configured tile order; a resolved tile waits in the ISP (ISP stall) until the
//     USCs have task slots for it (usc.count x usc.tasks_in_flight resident tasks of
//     usc.threads_per_task threads; models/task_slots.hpp);
//   USCs: several resident tiles share, in arrival order, the ALU server (ALU ops / (usc.count x
//     usc.lanes x usc.alu_ops_per_lane_per_clock)), the texture units (texels / (texture.units x
//     texture.texels_per_clock)) and the tile buffer (bytes / (usc.count x
//     pls.tile_buffer_bytes_per_clock)), while their texture lines, shader image reads and spilled
//     tile-buffer bytes go through the caches with the resident tasks' requests in flight;
//   pixel back end: stored bytes / writeback.bytes_per_clock, while the stores stream to memory.
// Frames of a sequence (CommandWork::frame) follow each other as gpu.frames_in_flight and
// gpu.frame_period_us allow: with 2 the next frame's first binning overlaps the last tiles of the
// frame before, as between passes; with 1 it waits for them; caches, SLC and DRAM keep their state.
// Phases: a render's tiles start when its binning is done; binning of the next pass overlaps the
// tiles of the current one (two parameter buffers), but after a partial render the next binning
// waits (the parameter buffer is only freed when its tiles are done); a command that reads what
// an earlier one produced waits for all earlier work.
#include <array>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "models/busy_intervals.hpp"
#include "models/frame_work.hpp"
#include "models/hw_config.hpp"
#include "models/memory_system.hpp"
#include "trace/traffic.hpp"
#include "kernel/stats.hpp"

namespace tbdr {

/// The units the timing model schedules, in the order TimingResult::units reports them.
enum class TimedUnit : std::uint8_t {
  Binning,       ///< geometry, tiling and the vertex work on the USCs' behalf
  TileFetch,     ///< reading a tile's primitive lists and loads (busy while any tile is fetched)
  Isp,           ///< hidden surface removal: rasterisation and punch-through depth resolves
  Usc,           ///< the unified shading clusters' ALUs
  Texture,       ///< the texture units' filtering
  TileBuffer,    ///< the on-chip tile buffer's port (PLS, framebuffer fetch, spills)
  PixelBackEnd,  ///< formatting and storing a finished tile
};
/// How many TimedUnit there are.
inline constexpr std::size_t kTimedUnitCount = 7;
/// Their names in the results (UnitTime::name, the database's `frame/unit.<name>` scopes), by enum.
inline constexpr std::array<std::string_view, kTimedUnitCount> kTimedUnitNames = {
    "binning", "tile_fetch", "isp", "usc", "texture", "tile_buffer", "pixel_back_end"};
/// The index of `u` in TimingResult::units and in each command's busy intervals.
constexpr std::size_t index_of(TimedUnit u) { return static_cast<std::size_t>(u); }

/// Busy, stalled and idle time of one unit over the frame.
struct UnitTime {
  std::string name;
  double busy_cycles = 0;
  double stalled_cycles = 0;
};

/// The busy intervals of one unit during one command (its reservations for that command's work).
struct UnitBusy {
  std::string unit;
  std::vector<BusyInterval> intervals;
};

/// Start and end of a command (pass or dispatch), and when each unit worked for it.
struct CommandTime {
  std::string name;
  double start_cycle = 0;
  double binning_end_cycle = 0;
  double end_cycle = 0;
  std::vector<UnitBusy> unit_busy;  ///< the units that worked for it, in TimingResult::units order
};

/// One frame of a sequence as the timing model ran it (a single frame is a sequence of one).
struct FrameTime {
  double start_cycle = 0;  ///< when its first binning or dispatch started
  double end_cycle = 0;    ///< when its last render or dispatch finished
  /// Bytes the DRAM had transferred (read + written, every class) when it finished (the last
  /// frame: at the end of the run, its queued writes drained): a frame's bytes are the difference
  /// from the frame before (what DRAM moved between their ends).
  std::uint64_t dram_bytes_at_end = 0;
  /// The memory system's statistics when it finished (as dram_bytes_at_end; a sequence of more
  /// than one frame only): the caches' and DRAM's energy of a frame is the difference.
  MemorySystemStats memory_at_end;
};

/// What the timing model measured.
struct TimingResult {
  double frame_cycles = 0;
  double frame_time_ps = 0;
  std::vector<CommandTime> commands;
  std::vector<FrameTime> frames;  ///< per frame of the sequence, in order (CommandWork::frame)
  /// The address space's regions at the end (FrameWork::address_layout of a later run that is to
  /// place its frames' data where this run did).
  std::vector<AddressRegion> address_layout;
  std::vector<UnitTime> units;  ///< one per TimedUnit, in its order
  /// The busy and stalled time of `u`.
  const UnitTime& unit(TimedUnit u) const { return units.at(index_of(u)); }
  /// Per DRAM channel ("dram.ch0", ...): when its data bus transferred, over the frame.
  std::vector<UnitBusy> dram_bus;
  DramTraffic requested;              ///< bytes the units requested, per class (before the caches)
  DramTraffic dram;                   ///< bytes DRAM transferred, per class (after the caches)
  MemorySystemStats memory;           ///< the memory system's own totals (energies of caches and DRAM)
  MemorySnapshot memory_units;        ///< every statistic of the clients, caches and DRAM at the frame's end
  std::vector<TileRecord> tiles;      ///< per tile: cycles, samples, DRAM bytes
  std::uint64_t events = 0;
  /// Texture fetch: lines the shaded quads accessed (distinct per quad and fetch), lines of the
  /// tiles' footprints (each sent once per tile through the texture cache), and how many of
  /// those missed the texture cache.
  std::uint64_t texture_line_accesses = 0;
  std::uint64_t texture_footprint_lines = 0;
  std::uint64_t texture_cache_misses = 0;
};

class WorkFeed;

class DramObserver;  // models/dram_observer.hpp

/// Runs the timing model over a frame's work; `dram_observer` (optional) sees the DRAM's requests
/// and commands.
TimingResult run_timing(const HwConfig& hw, const FrameWork& work, DramObserver* dram_observer = nullptr);
/// Runs the timing model over a frame's work as `feed` hands it over (models/work_feed.hpp): on
/// its own thread while the functional run publishes the commands, with the same result.
TimingResult run_timing(const HwConfig& hw, WorkFeed& feed, DramObserver* dram_observer = nullptr);

}  // namespace tbdr
