#pragma once
// DRAM traffic classes: every byte that crosses the chip boundary is booked to one of them, so a
// run can say which buffers of a technique went off chip. A trace's buffers name the class their
// bytes are booked to (`buffer ... traffic=T`), so the classes live with the trace.
#include <array>
#include <cstdint>
#include <string>

namespace tbdr {

/// What a DRAM access carries.
enum class DramClass : std::uint8_t {
  ParameterBuffer,  ///< tiler output: region headers, control streams, primitive blocks
  Vertices,         ///< vertex attribute fetch
  Indices,          ///< index buffer fetch
  Textures,         ///< texture fetch
  Color,            ///< color attachments (load, store, partial-render spill)
  DepthStencil,     ///< depth/stencil attachments (load, store, partial-render spill)
  Gbuffer,          ///< G-buffer attachments written off chip and read back
  Visibility,       ///< visibility-buffer ids
  LightData,        ///< the light array
  LightLists,       ///< light index lists and their grids (tile, cluster)
  WorkLists,        ///< per-material work lists and other compute buffers
  Spill,            ///< tile memory beyond the on-chip budget (pls.over_budget = spill)
  Other,            ///< anything else
  Count
};
inline constexpr std::size_t kDramClassCount = static_cast<std::size_t>(DramClass::Count);

/// The database name of a class ("parameter_buffer", "color", ...).
const char* to_string(DramClass c);

/// Bytes read from and written to DRAM, per class.
struct DramTraffic {
  std::array<std::uint64_t, kDramClassCount> read_bytes{};
  std::array<std::uint64_t, kDramClassCount> write_bytes{};

  void read(DramClass c, std::uint64_t bytes) { read_bytes[static_cast<std::size_t>(c)] += bytes; }
  void write(DramClass c, std::uint64_t bytes) { write_bytes[static_cast<std::size_t>(c)] += bytes; }
  std::uint64_t reads(DramClass c) const { return read_bytes[static_cast<std::size_t>(c)]; }
  std::uint64_t writes(DramClass c) const { return write_bytes[static_cast<std::size_t>(c)]; }
  std::uint64_t total_read() const;
  std::uint64_t total_written() const;
  DramTraffic& operator+=(const DramTraffic& o);
};

}  // namespace tbdr
