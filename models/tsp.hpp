#pragma once
// The TSP and the USCs, functionally: shade the pixels the ISP hands over for one primitive, in
// 2x2 quads (helper lanes counted), charge the shader's declared cost (ALU ops, texture fetches,
// per-light ALU ops times the lights the fragment evaluates), evaluate punch-through alpha tests
// for real, and write the fixed shading model's color into the color targets (with blending).
// For scene triangles it also computes the texture lines each quad's fetches touch
// (models/texture_unit.hpp) and appends them to the tile's list (RenderContext::texture_lines).
#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "models/render_state.hpp"
#include "models/texture_unit.hpp"
#include "kernel/stats.hpp"

namespace tbdr {

/// Statistics of fragment shading.
struct TspStats {
  StatGroup group;
  Counter invocations{group, {"shader_invocations", "fragments", "Fragment shader invocations on covered pixels (helpers excluded)"}};
  Counter quads{group, {"shaded_quads", "quads", "2x2 quads launched"}};
  Counter helper_lanes{group, {"helper_lanes", "lanes", "Lanes of launched quads with no covered pixel (helpers)"}};
  Counter lit_surface_invocations{group, {"lit_surface_invocations", "fragments", "Invocations on scene geometry whose shader evaluates lights (not proxies)"}};
  Counter shaded_samples{group, {"shaded_samples", "samples", "Samples whose color a shader wrote"}};
  Counter alu_ops{group, {"fragment_alu_ops", "ops", "Fragment shader ALU ops, helper lanes included"}};
  Counter texture_fetches{group, {"texture_fetches", "fetches", "Texture fetches, helper lanes included"}};
  Counter texels{group, {"texels_filtered", "texels", "Texels read by the texture units"}};
  Counter texture_line_accesses{group, {"texture_line_accesses", "lines", "Texture cache line accesses: distinct lines per quad and fetch, before merging within the tile"}};
  Counter texture_tile_lines{group, {"texture_tile_lines", "lines", "Distinct texture lines each tile touched (its footprint), summed over tiles"}};
  Counter light_evaluations{group, {"light_evaluations", "evaluations", "Lights evaluated by covered fragments"}};
  Counter alpha_killed{group, {"alpha_test_killed_samples", "samples", "Punch-through samples discarded by the alpha test"}};
  Counter blended_samples{group, {"blended_samples", "samples", "Samples written with blending"}};
  Counter unassigned_cluster_fragments{group, {"unassigned_cluster_fragments", "fragments", "Fragments whose cluster got no light list (not flagged)"}};
  Counter light_stack_overflow_fragments{group, {"light_stack_overflow_fragments", "fragments", "Fragments whose PLS light stack overflowed (fell back to every light)"}};
  Counter pls_bytes_accessed{group, {"pls_bytes_accessed", "bytes", "Pixel local storage bytes read and written by shaders (the pass's PLS layout per access)"}};
  Counter tile_buffer_read_bytes{group, {"tile_buffer_read_bytes", "bytes", "On-chip tile buffer bytes read by blending and fetch"}};
  Counter tile_buffer_write_bytes{group, {"tile_buffer_write_bytes", "bytes", "On-chip tile buffer bytes written by shaders"}};
  explicit TspStats(std::string scope) : group(std::move(scope)) {}
};

/// One pixel of a shading batch: absolute coordinates and the samples to write.
struct ShadePixel {
  std::int32_t x = 0;
  std::int32_t y = 0;
  std::uint32_t mask = 0;
};

/// The fragment shading stage.
class Tsp {
 public:
  explicit Tsp(RenderContext& ctx);
  /// Shades `pixels` (one primitive, one tile, sorted by row then column). For punch-through
  /// primitives, `alive` receives per pixel the samples that survived the alpha test.
  void shade(std::uint32_t prim_index, std::span<const ShadePixel> pixels, std::vector<std::uint32_t>* alive,
             TspStats& stats);

 private:
  /// Texture lines of the quads of one scene triangle's batch (quad_seen_[0, quads)): appended to
  /// ctx_.texture_lines, counted in stats.texture_line_accesses. Kept out of line: the pixel loop
  /// of shade() compiles better without it.
  [[gnu::noinline]] void texture_addresses(const Primitive& p, std::uint32_t tex_fetches, std::size_t quads,
                                           TspStats& stats);

  RenderContext& ctx_;
  std::vector<std::uint64_t> quad_seen_;  ///< scratch: quads launched in this batch
  std::array<QuadFootprint, 2> footprints_;  ///< scratch: the current and the previous quad's texture lines
  /// Texture lines recently appended to the tile's list (direct mapped; valid for the epoch).
  struct LineFilterEntry {
    std::uint64_t line = 0;
    std::uint32_t epoch = 0;
  };
  static constexpr int kLineFilterBits = 11;
  std::array<LineFilterEntry, std::size_t{1} << kLineFilterBits> line_filter_{};
  std::uint32_t line_filter_epoch_ = 0;
};

}  // namespace tbdr
