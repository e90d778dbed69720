#include "trace/traffic.hpp"

#include <numeric>

namespace tbdr {

const char* to_string(DramClass c) {
  switch (c) {
    case DramClass::ParameterBuffer: return "parameter_buffer";
    case DramClass::Vertices: return "vertices";
    case DramClass::Indices: return "indices";
    case DramClass::Textures: return "textures";
    case DramClass::Color: return "color";
    case DramClass::DepthStencil: return "depth_stencil";
    case DramClass::Gbuffer: return "gbuffer";
    case DramClass::Visibility: return "visibility";
    case DramClass::LightData: return "light_data";
    case DramClass::LightLists: return "light_lists";
    case DramClass::WorkLists: return "work_lists";
    case DramClass::Spill: return "spill";
    case DramClass::Other: return "other";
    case DramClass::Count: break;
  }
  return "?";
}

std::uint64_t DramTraffic::total_read() const {
  return std::accumulate(read_bytes.begin(), read_bytes.end(), std::uint64_t{0});
}

std::uint64_t DramTraffic::total_written() const {
  return std::accumulate(write_bytes.begin(), write_bytes.end(), std::uint64_t{0});
}

DramTraffic& DramTraffic::operator+=(const DramTraffic& o) {
  for (std::size_t i = 0; i < kDramClassCount; ++i) {
    read_bytes[i] += o.read_bytes[i];
    write_bytes[i] += o.write_bytes[i];
  }
  return *this;
}

}  // namespace tbdr
