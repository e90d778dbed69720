#pragma once
// The statistics of one render pass, one typed set per unit of the render pipeline (geometry,
// tiler, ISP, TSP, tile memory, ROP): what the pass renderer fills and the command processor sums
// into the frame's.
#include <string>
#include <vector>

#include "kernel/stats.hpp"
#include "models/geometry_unit.hpp"
#include "models/isp.hpp"
#include "models/rop.hpp"
#include "models/tile_memory.hpp"
#include "models/tiler.hpp"
#include "models/tsp.hpp"

namespace tbdr {

/// Statistics of one pass (or, summed, of the frame), one set per unit.
struct PassStats {
  GeometryStats geometry;
  TilerStats tiler;
  IspStats isp;
  TspStats tsp;
  TileMemoryStats tile_memory;
  RopStats rop;  ///< gpu.mode=imr: the ROP caches (zero otherwise)
  /// Adds another pass: counts sum, gauges take the larger level.
  PassStats& operator+=(const PassStats& o) {
    geometry += o.geometry;
    tiler += o.tiler;
    isp += o.isp;
    tsp += o.tsp;
    tile_memory += o.tile_memory;
    rop += o.rop;
    return *this;
  }
};

}  // namespace tbdr
