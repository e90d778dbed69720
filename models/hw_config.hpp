#pragma once
// The hardware configuration every unit reads: plain members grouped by the INI section that sets
// them. The declarations (defaults, units, ranges, docs, sources) live in hw_config.cpp, once;
// `tbdrsim params` prints them. Choice parameters are enums here: their text (what config files,
// `tbdrsim params` and the database show) is looked up once, when the configuration is built.
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "kernel/params.hpp"

namespace tbdr {

/// How the GPU renders (gpu.mode): the three architectures one trace can be compared across.
enum class GpuMode : std::uint8_t {
  Tbdr,  ///< binning + tag-buffer hidden-surface removal before shading (PowerVR)
  Tbr,   ///< binning, early-Z only (Mali-like)
  Imr,   ///< no binning, framebuffer in DRAM behind caches
};
inline constexpr std::array<ChoiceName<GpuMode>, 3> kGpuModeNames{
    {{GpuMode::Tbdr, "tbdr"}, {GpuMode::Tbr, "tbr"}, {GpuMode::Imr, "imr"}}};

/// How the tiler decides that a primitive touches a tile (tiling.binning).
enum class BinningTest : std::uint8_t {
  Exact,        ///< the triangle's edges against the tile's samples
  BoundingBox,  ///< the triangle's bounding box only (more tile references, cheaper test)
};
inline constexpr std::array<ChoiceName<BinningTest>, 2> kBinningTestNames{
    {{BinningTest::Exact, "exact"}, {BinningTest::BoundingBox, "bbox"}}};

/// Order in which the tiles of a render are dispatched to the ISP (tiling.tile_order).
enum class TileOrder : std::uint8_t {
  RowMajor,  ///< left to right, top to bottom
  Morton,    ///< Z-order: interleaved bits of the tile coordinates
};
inline constexpr std::array<ChoiceName<TileOrder>, 2> kTileOrderNames{
    {{TileOrder::RowMajor, "row_major"}, {TileOrder::Morton, "morton"}}};

/// What a pass that needs more bytes per pixel than the tile buffer holds pays (pls.over_budget).
enum class PlsOverBudget : std::uint8_t {
  SplitRender,   ///< end the render before the first draw that reads back what does not fit; else spill
  Spill,         ///< the excess share of tile-buffer accesses goes to memory
  SmallerTiles,  ///< each tile is rendered in strips that fit
};
inline constexpr std::array<ChoiceName<PlsOverBudget>, 3> kPlsOverBudgetNames{
    {{PlsOverBudget::SplitRender, "split_render"}, {PlsOverBudget::Spill, "spill"},
     {PlsOverBudget::SmallerTiles, "smaller_tiles"}}};

/// How gpu.mode=imr clears a depth or colour attachment (imr.clear).
enum class ImrClear : std::uint8_t {
  Fast,   ///< blocks marked cleared in on-chip metadata: nothing written, nothing fetched on first touch
  Write,  ///< the clear value written to the whole attachment in memory
};
inline constexpr std::array<ChoiceName<ImrClear>, 2> kImrClearNames{{{ImrClear::Fast, "fast"}, {ImrClear::Write, "write"}}};

/// Physical address bit order of dram.address_mapping, most significant field first.
enum class DramMapping : std::uint8_t {
  RowBankChannelColumn,  ///< consecutive rows' worth of bytes alternate channels, then banks
  RowChannelBankColumn,  ///< consecutive rows' worth of bytes alternate banks, then channels
};
inline constexpr std::array<ChoiceName<DramMapping>, 2> kDramMappingNames{
    {{DramMapping::RowBankChannelColumn, "row_bank_channel_column"},
     {DramMapping::RowChannelBankColumn, "row_channel_bank_column"}}};

/// The config-file spelling of each choice.
inline const char* to_string(GpuMode v) { return choice_name<GpuMode>(kGpuModeNames, v); }
inline const char* to_string(BinningTest v) { return choice_name<BinningTest>(kBinningTestNames, v); }
inline const char* to_string(TileOrder v) { return choice_name<TileOrder>(kTileOrderNames, v); }
inline const char* to_string(PlsOverBudget v) { return choice_name<PlsOverBudget>(kPlsOverBudgetNames, v); }
inline const char* to_string(DramMapping v) { return choice_name<DramMapping>(kDramMappingNames, v); }
inline const char* to_string(ImrClear v) { return choice_name<ImrClear>(kImrClearNames, v); }

/// [gpu] whole-GPU identity, clock and rendering mode.
struct GpuParams {
  std::string name;
  double core_clock_mhz = 0;
  GpuMode mode = GpuMode::Tbdr;
  double frame_period_us = 0;  ///< display frame period the energy is also reported at (0: race to idle only)
  std::int64_t frames_in_flight = 2;  ///< frames of a sequence whose work may overlap (1: one after another)
};

/// [geometry] vertex fetch, vertex shading and primitive setup (clip, cull, viewport).
struct GeometryParams {
  double primitives_per_clock = 0;
  double vertex_fetch_bytes_per_clock = 0;
  std::int64_t vertex_cache_entries = 0;
  std::int64_t vertex_shader_alu_ops = 0;
  std::int64_t subpixel_bits = 0;
};

/// [tiling] binning and the parameter buffer in DRAM.
struct TilingParams {
  std::int64_t tile_width = 0;
  std::int64_t tile_height = 0;
  BinningTest binning = BinningTest::Exact;
  TileOrder tile_order = TileOrder::Morton;
  double primitives_per_clock = 0;
  std::int64_t pb_capacity_bytes = 0;
  std::int64_t pb_page_bytes = 0;
  std::int64_t region_header_bytes = 0;
  std::int64_t control_stream_block_bytes = 0;
  std::int64_t control_stream_entry_bytes = 0;
  std::int64_t prim_block_max_vertices = 0;
  std::int64_t prim_block_max_primitives = 0;
  std::int64_t prim_block_header_bytes = 0;
  std::int64_t pb_vertex_position_bytes = 0;
  std::int64_t pb_varying_bytes = 0;
  double pb_compression_ratio = 0;
  std::int64_t prim_index_bytes = 0;
};

/// [isp] image synthesis processor: rasterisation, depth/stencil, hidden-surface removal.
struct IspParams {
  std::int64_t tiles_in_flight = 0;
  std::int64_t raster_pipes = 0;
  std::int64_t samples_per_clock = 0;
  std::int64_t tag_buffers = 0;
  std::int64_t tag_bits = 0;
  std::int64_t depth_stencil_bytes_per_sample = 0;
  std::int64_t forward_pixel_kill_window = 0;
  std::int64_t early_z = 1;
};

/// [usc] unified shading clusters (the TSP's shader cores).
struct UscParams {
  std::int64_t count = 0;
  std::int64_t lanes = 0;
  double alu_ops_per_lane_per_clock = 0;
  std::int64_t tasks_in_flight = 0;
  std::int64_t threads_per_task = 0;
};

/// [texture] texture processing units.
struct TextureParams {
  std::int64_t units = 0;
  double texels_per_clock = 0;            ///< bilinear-filtered texels per clock per unit
  std::int64_t filtered_texels_per_fetch = 0;  ///< filtered texels one fetch costs (1 bilinear, 2 trilinear)
  std::int64_t bytes_per_texel = 0;
  std::int64_t outstanding_requests = 0;  ///< memory requests in flight per tile footprint
};

/// [pls] on-chip tile memory and pixel local storage.
struct PlsParams {
  std::int64_t tile_buffer_bits_per_pixel = 0;
  double tile_buffer_bytes_per_clock = 0;  ///< per USC
  std::int64_t max_pls_bytes_per_pixel = 0;
  PlsOverBudget over_budget = PlsOverBudget::SplitRender;
};

/// [memory] the units' DMA streams: how they issue their byte ranges to the memory system.
struct MemoryParams {
  std::int64_t stream_outstanding_requests = 0;
};

/// [writeback] the pixel back end that stores tiles to DRAM.
struct WritebackParams {
  double compression_ratio = 0;
  double bytes_per_clock = 0;
  std::int64_t transaction_elimination = 0;  ///< 1: skip storing a colour tile whose signature matches the previous frame's
};

/// [cache.*] one set-associative cache with LRU replacement.
struct CacheParams {
  std::int64_t size_bytes = 0;
  std::int64_t ways = 0;
  std::int64_t line_bytes = 0;
  std::int64_t hit_latency_cycles = 0;
};

/// The caches of the memory hierarchy.
struct CachesParams {
  CacheParams texture;
  CacheParams vertex;
  CacheParams slc;
  CacheParams rop_depth;  ///< gpu.mode=imr: the render output unit's depth/stencil cache
  CacheParams rop_color;  ///< gpu.mode=imr: the render output unit's colour cache
};

/// [imr] the immediate-mode pipeline of gpu.mode=imr (no binning: primitives flow from geometry
/// through rasterisation and shading to the ROP caches as they are submitted).
struct ImrParams {
  std::int64_t primitives_per_batch = 0;  ///< primitives scheduled as one unit down the pipeline
  ImrClear clear = ImrClear::Fast;
};

/// [dram] the external memory: channels, banks, row buffers, timing and queues.
struct DramParams {
  std::string name;
  std::int64_t channels = 0;
  std::int64_t banks = 0;
  std::int64_t row_bytes = 0;
  std::int64_t burst_bytes = 0;
  double clock_mhz = 0;                   ///< command clock CK
  double transfers_per_clock = 0;         ///< data transfers per DQ pin per CK cycle (DDR: 2; LPDDR5 WCK 4:1: 8)
  std::int64_t bus_width_bits = 0;        ///< data bus (DQ) width of one channel
  double t_rcd_ns = 0;
  double t_rp_ns = 0;
  double t_cl_ns = 0;
  double t_ras_ns = 0;
  double t_wr_ns = 0;
  double t_rrd_ns = 0;   ///< activate to activate, different banks of a channel
  double t_faw_ns = 0;   ///< window holding at most four activates per channel
  double t_wtr_ns = 0;   ///< end of write data to a read command (write-to-read turnaround)
  double t_rtw_ns = 0;   ///< end of read data to the start of write data (read-to-write turnaround)
  std::int64_t bank_groups = 1;  ///< bank groups per channel (bank b is in group b mod bank_groups)
  double t_ccd_l_ns = 0;  ///< column to column, same bank group: burst start to burst start (0: the data bus only)
  double t_ccd_s_ns = 0;  ///< column to column, different bank groups (0: the data bus only)
  double t_refi_ns = 0;  ///< all-bank refresh interval per channel (0: no refresh)
  double t_rfc_ns = 0;   ///< all-bank refresh cycle time: the channel's banks are unusable (0: no refresh)
  double active_standby_mw = 0;     ///< background power per channel while a row is open (IDD3N x VDD)
  double precharge_standby_mw = 0;  ///< background power per channel with every bank precharged (IDD2N x VDD)
  double refresh_nj = 0;            ///< energy of one all-bank refresh of a channel above active standby
  double powerdown_after_ns = 0;     ///< idle time after which a channel enters power-down (0: never)
  double active_powerdown_mw = 0;    ///< background power per channel in power-down with a row open (IDD3P x VDD)
  double precharge_powerdown_mw = 0; ///< background power per channel in power-down, all precharged (IDD2P x VDD)
  double t_xp_ns = 0;                ///< power-down exit: the first command waits this long after the request arrives
  double self_refresh_mw = 0;        ///< background power per channel in self-refresh, refresh included (IDD6 x VDD)
  double controller_latency_ns = 0;
  std::int64_t read_queue_entries = 0;
  std::int64_t write_queue_entries = 0;
  std::int64_t max_chain_bytes = 0;  ///< consecutive line misses queued as one entry (burst chain)
  DramMapping address_mapping = DramMapping::RowBankChannelColumn;
  double write_high_watermark = 0;  ///< fraction of write_queue_entries that starts a write drain
  double write_low_watermark = 0;   ///< fraction of write_queue_entries that ends it

  /// Data rate per DQ pin, MT/s: clock_mhz x transfers_per_clock.
  double data_rate_mtps() const { return clock_mhz * transfers_per_clock; }
  /// Peak data bandwidth of one channel, GB/s: data rate x bus_width_bits / 8 bytes.
  double channel_peak_bandwidth_gbps() const {
    return data_rate_mtps() * static_cast<double>(bus_width_bits) / 8.0 / 1000.0;
  }
  /// Peak data bandwidth of all channels, GB/s (derived: the one source is clock, rate, width, channels).
  double peak_bandwidth_gbps() const { return channel_peak_bandwidth_gbps() * static_cast<double>(channels); }
};

/// [energy] energy per access and per op, leakage per unit, the process node that scales them.
struct EnergyParams {
  double process_nm = 0;  ///< CMOS node the on-chip figures are scaled to
  double vdd_v = 0;       ///< core supply at that node
  double dram_read_pj_per_bit = 0;
  double dram_write_pj_per_bit = 0;
  double dram_io_pj_per_bit = 0;
  double dram_activate_precharge_nj = 0;
  double alu_op_pj_45nm = 0;               ///< one FP32 ALU op's arithmetic at 45 nm, 0.9 V
  double register_file_bytes_per_op = 0;   ///< operand bytes read and written per ALU op
  double register_file_bytes_per_usc = 0;  ///< a USC's register storage (CACTI array)
  double texel_pj_45nm = 0;                ///< one bilinear-filtered texel's arithmetic at 45 nm, 0.9 V
  double usc_leakage_mw = 0;               ///< logic leakage of one USC at the configured node (SRAM apart)
  double texture_unit_leakage_mw = 0;      ///< logic leakage of one texture unit
  double fixed_function_leakage_mw = 0;    ///< logic leakage of one fixed-function unit
  double gated_leakage_fraction = 0;       ///< share of a power-gated unit's leakage still drawn while idle
};

/// The whole GPU as the units see it. Built only from resolved parameters (hw_params().build()).
struct HwConfig {
  GpuParams gpu;
  GeometryParams geometry;
  TilingParams tiling;
  IspParams isp;
  UscParams usc;
  TextureParams texture;
  PlsParams pls;
  WritebackParams writeback;
  MemoryParams memory;
  CachesParams cache;
  ImrParams imr;
  DramParams dram;
  EnergyParams energy;
};

/// The preset the declared defaults are: configs/series6xt_gx6450.ini sets nothing, so a
/// configuration resolved without a config file is named after it (one hardware, one label with
/// and without the file; tests/test_params.cpp pins the file's hash to the defaults').
inline constexpr const char* kDefaultsPreset = "series6xt_gx6450";

/// The single declaration of every hardware parameter.
const ParamRegistry<HwConfig>& hw_params();

/// A resolved configuration: the struct the units read, plus the values and origins it came from.
struct ResolvedConfig {
  HwConfig hw;
  ResolvedParams params;
  std::string hash;   ///< hw_params().table().hash(params)
  std::string label;  ///< hw_params().table().label(): the preset's name and the values set on top of it
};

/// Resolves defaults + config files + --set overrides (InputError on any bad input).
ResolvedConfig resolve_config(const std::vector<std::string>& config_files,
                              const std::vector<std::string>& overrides);

}  // namespace tbdr
