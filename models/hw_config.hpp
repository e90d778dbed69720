#pragma once
// The hardware configuration every unit reads: plain members grouped by the INI section that sets
// them. The declarations (defaults, units, ranges, docs, sources) live in hw_config.cpp, once;
// `tbdrsim params` prints them. Units convert choice strings to enums when they are built.
#include <cstdint>
#include <string>
#include <vector>

#include "kernel/params.hpp"

namespace tbdr {

/// [gpu] whole-GPU identity, clock and rendering mode.
struct GpuParams {
  std::string name;
  double core_clock_mhz = 0;
  std::string mode;  ///< tbdr | tbr | imr
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
  std::string binning;  ///< exact | bbox
  std::string tile_order;  ///< row_major | morton
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
  std::int64_t macrotiles = 0;
};

/// [isp] image synthesis processor: rasterisation, depth/stencil, hidden-surface removal.
struct IspParams {
  std::int64_t tiles_in_flight = 0;
  std::int64_t raster_pipes = 0;
  std::int64_t samples_per_clock = 0;
  std::int64_t tag_buffers = 0;
  std::int64_t tag_bits = 0;
  std::int64_t depth_stencil_bytes_per_sample = 0;
};

/// [usc] unified shading clusters (the TSP's shader cores).
struct UscParams {
  std::int64_t count = 0;
  std::int64_t lanes = 0;
  double alu_ops_per_lane_per_clock = 0;
  std::int64_t tasks_in_flight = 0;
  std::int64_t task_queue_entries = 0;
};

/// [texture] texture processing units.
struct TextureParams {
  std::int64_t units = 0;
  double texels_per_clock = 0;
  std::int64_t texels_per_fetch = 0;
  std::int64_t bytes_per_texel = 0;
  std::int64_t outstanding_requests = 0;  ///< memory requests in flight per tile footprint
};

/// [pls] on-chip tile memory and pixel local storage.
struct PlsParams {
  std::int64_t tile_buffer_bits_per_pixel = 0;
  std::int64_t max_pls_bytes_per_pixel = 0;
  std::string over_budget;  ///< smaller_tiles | spill
};

/// [writeback] the pixel back end that stores tiles to DRAM.
struct WritebackParams {
  double compression_ratio = 0;
  double bytes_per_clock = 0;
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
};

/// [dram] the external memory: channels, banks, row buffers, timing and queues.
struct DramParams {
  std::string name;
  std::int64_t channels = 0;
  std::int64_t banks = 0;
  std::int64_t row_bytes = 0;
  std::int64_t burst_bytes = 0;
  double bandwidth_gbps = 0;
  double clock_mhz = 0;
  double t_rcd_ns = 0;
  double t_rp_ns = 0;
  double t_cl_ns = 0;
  double t_ras_ns = 0;
  double t_wr_ns = 0;
  double controller_latency_ns = 0;
  std::int64_t read_queue_entries = 0;
  std::int64_t write_queue_entries = 0;
  std::int64_t max_chain_bytes = 0;  ///< consecutive line misses queued as one entry (burst chain)
  std::string address_mapping;  ///< row_bank_channel_column | row_channel_bank_column
};

/// [energy] energy per access and static power.
struct EnergyParams {
  double dram_read_pj_per_bit = 0;
  double dram_write_pj_per_bit = 0;
  double dram_io_pj_per_bit = 0;
  double dram_activate_precharge_nj = 0;
  double tile_buffer_pj_per_byte = 0;
  double tag_buffer_pj_per_byte = 0;
  double texture_cache_pj_per_byte = 0;
  double vertex_cache_pj_per_byte = 0;
  double slc_pj_per_byte = 0;
  double alu_op_pj = 0;
  double texel_pj = 0;
  double static_power_mw = 0;
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
  CachesParams cache;
  DramParams dram;
  EnergyParams energy;
};

/// The single declaration of every hardware parameter.
const ParamRegistry<HwConfig>& hw_params();

/// A resolved configuration: the struct the units read, plus the values and origins it came from.
struct ResolvedConfig {
  HwConfig hw;
  ResolvedParams params;
  std::string hash;  ///< hw_params().table().hash(params)
};

/// Resolves defaults + config files + --set overrides (InputError on any bad input).
ResolvedConfig resolve_config(const std::vector<std::string>& config_files,
                              const std::vector<std::string>& overrides);

}  // namespace tbdr
