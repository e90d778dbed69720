#pragma once
// The ISP (image synthesis processor): per tile, rasterises the tile's primitives in submission
// order, runs the depth and stencil tests against on-chip depth/stencil, and removes hidden
// surfaces with a tag buffer that holds one primitive id per sample. Opaque primitives only
// overwrite tags; punch-through primitives flush the tags they cover (all tags with a single tag
// buffer) to the TSP, are shaded, and write depth only for samples that survive their alpha
// test; translucent primitives flush the tags they cover and are shaded with blending at once.
// What is left in the tag buffer is shaded when the tile ends. In tbr/imr modes there is no tag
// buffer: every fragment that passes early depth testing is shaded immediately.
#include <cstdint>
#include <vector>

#include "models/render_state.hpp"
#include "models/tsp.hpp"
#include "kernel/stats.hpp"

namespace tbdr {

// Declared once: X(type, member = stored name, unit, Sum | Gauge, description).
#define TBDR_ISP_STATS(X) \
  X(Counter, tiles_rendered, "tiles", Sum, "Tile renders (each sub-tile of a split tile counts)") \
  X(Counter, primitives_fetched, "primitives", Sum, "Primitives read from tile lists and set up") \
  X(Counter, samples_rasterised, "samples", Sum, "Samples covered by rasterised primitives") \
  X(Counter, depth_test_failed_samples, "samples", Sum, "Samples failing the depth test") \
  X(Counter, stencil_test_failed_samples, "samples", Sum, "Samples failing the stencil test") \
  X(Counter, hsr_removed_samples, "samples", Sum, "Samples whose pending tag was overwritten before shading") \
  X(Counter, tag_flushes, "flushes", Sum, "Mid-tile tag buffer flushes forced by punch-through or translucent primitives") \
  X(Counter, tag_flushed_samples, "samples", Sum, "Samples sent to the TSP by mid-tile flushes") \
  X(Counter, punch_through_samples, "samples", Sum, "Punch-through samples passing depth test") \
  X(Counter, translucent_samples, "samples", Sum, "Translucent samples passing depth test") \
  X(Counter, depth_buffer_read_bytes, "bytes", Sum, "On-chip depth/stencil bytes read by tests") \
  X(Counter, depth_buffer_write_bytes, "bytes", Sum, "On-chip depth/stencil bytes written") \
  X(Counter, tag_buffer_read_bytes, "bytes", Sum, "Tag buffer bytes read (flushes)") \
  X(Counter, tag_buffer_write_bytes, "bytes", Sum, "Tag buffer bytes written")
/// Statistics of the ISP.
struct IspStats {
  TBDR_STATS(TBDR_ISP_STATS)
};

/// The ISP of one GPU, working on one tile at a time.
class Isp {
 public:
  Isp(RenderContext& ctx, Tsp& tsp);
  /// Renders the primitives of `prims` (indices into ctx.prims) inside `rect`; depth/stencil and
  /// color contents are read and written in the frame images (loaded/stored by TileMemory).
  void render_tile(const PixelRect& rect, const std::vector<std::uint32_t>& prims, IspStats& isp, TspStats& tsp);

 private:
  struct PendingSample {
    std::uint32_t tag;
    std::int32_t x, y;
    std::uint32_t bit;
  };
  /// Shades the tags of the samples selected by `select` (all valid tags when null).
  void flush(const PixelRect& rect, const std::vector<std::uint8_t>* select, bool mid_tile, IspStats& isp, TspStats& tsp);
  /// Merges consecutive samples of one pixel into ShadePixels (samples are in raster order).
  static void build_batch(const PendingSample* begin, const PendingSample* end, std::vector<ShadePixel>& batch);

  RenderContext& ctx_;
  Tsp& tsp_;
  std::vector<std::uint32_t> tags_;
  std::vector<PendingSample> pending_;
  std::vector<PendingSample> flush_samples_;
  std::vector<float> pending_depth_;
  std::vector<std::uint8_t> select_;
  std::vector<ShadePixel> batch_;
  std::vector<std::uint32_t> alive_;
};

}  // namespace tbdr
