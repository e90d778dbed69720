// Clustered deferred shading (Olsson, Billeter & Assarsson 2012), as the thesis chapter in
// reference/ implements it: a G-buffer pass, then three compute dispatches: clustering (flag the
// clusters that hold a visible sample, compacted into a list of used clusters), light assignment
// (every light against every used cluster) and shading (one pixel per invocation, looping over its
// cluster's list).
// Billeter's table: off-chip buffers = G-buffers; 1 geometry pass; overshading no; MSAA no;
// blending no.
//
// Pass `gbuffer`: option `gbuffer` targets (albedo rgba8 + normal rgb10a2) + depth d24s8, stored.
// barrier; dispatch cluster_flag (tiles_x x tiles_y groups, one per tile as in the thesis; reads
//   depth, writes used_clusters); barrier; dispatch cluster_light_assign (one group per cluster of
//   the grid, 64 threads over the lights; reads lights + used_clusters, writes cluster_grid +
//   light_index); barrier; dispatch deferred_shade (16x16 pixel groups, one pixel per thread; reads
//   the G-buffer, depth, lights and the lists; writes buffer `color`, the lit frame).
// Buffers: used_clusters 4 + 4 B x clusters; cluster_grid 8 B (offset, count) x clusters;
//   light_index clusters x max_lights_per_cluster x index_bytes; clusters = ceil(W/tile_px) x
//   ceil(H/tile_px) x slices.
// Shader `clustered_deferred_lit` (the per-pixel cost of deferred_shade): decode 4 (+1 per extra
//   target) + position reconstruction 8 + cluster lookup 6 + ambient 3 + output 5 ALU, one fetch per
//   G-buffer target + 1 for depth, light_source=cluster_list, 12 ALU per light.
// Translucent (BLEND) geometry is not drawn (see tiled_deferred.cpp and docs/techniques.md).
#include <algorithm>

#include "techniques/technique.hpp"

namespace tbdr {

namespace {

Trace generate_clustered_deferred(const TraceSetup& setup, const TechniqueOptions& options) {
  reject_msaa(setup, "clustered_deferred", "its G-buffer holds one surface per pixel (Billeter 2015: MSAA no)");
  require_lights(setup, "clustered_deferred");
  Trace t = begin_trace(setup, "clustered_deferred", options);
  const std::string lights = add_light_buffer(t);
  const GbufferLayout layout = gbuffer_layout_option(options, "gbuffer");
  const auto tile_px = static_cast<std::uint32_t>(options.get_int("tile_px", 4, 1024));
  const auto slices = static_cast<std::uint32_t>(options.get_int("slices", 1, 1024));
  const std::uint32_t cap = list_cap_option(options, "max_lights_per_cluster", t.lights.size());
  const std::uint32_t index_bytes = index_bytes_option(options, "index_bytes", t.lights.size());

  const std::uint32_t tiles_x = tiles_for(setup.width, tile_px);
  const std::uint32_t tiles_y = tiles_for(setup.height, tile_px);
  const std::uint64_t clusters = std::uint64_t{tiles_x} * tiles_y * slices;
  const std::string used = add_buffer(t, "used_clusters", 4 + clusters * kUsedClusterEntryBytes,
                                      TrafficClass::LightLists, BufferContent::UsedClusters);
  const std::string grid = add_buffer(t, "cluster_grid", clusters * kGridEntryBytes, TrafficClass::LightLists,
                                      BufferContent::ClusterGrid);
  const std::string index = add_buffer(t, "light_index", clusters * cap * index_bytes, TrafficClass::LightLists,
                                       BufferContent::LightIndexList);
  const std::string frame = add_buffer(t, "color", std::uint64_t(setup.width) * std::uint64_t(setup.height) * 4,
                                       TrafficClass::Color, BufferContent::Image);

  PassDesc gbuffer = make_gbuffer_pass(t, layout);
  const auto targets = static_cast<std::uint32_t>(layout.formats.size());
  t.shaders.push_back(make_shader("clustered_deferred_lit",
                                  kGbufferDecodeAluOps + kGbufferExtraTargetAluOps * layout.extra_targets() +
                                      kPositionReconstructAluOps + kClusterLookupAluOps + kAmbientAluOps +
                                      kOutputAluOps,
                                  targets + 1, 0, kLightAluOps, LightSource::ClusterList, 1));

  const std::map<std::string, std::string> params = {
      {"tile_px", std::to_string(tile_px)}, {"slices", std::to_string(slices)}, {"slicing", "log"}};
  auto assign_params = params;
  assign_params["dense"] = "no";
  std::vector<std::string> stored = layout.names;
  stored.push_back("depth");
  std::vector<std::string> shade_reads = stored;
  shade_reads.insert(shade_reads.end(), {lights, grid, index});
  const std::uint32_t edge = std::min(tile_px, kKernelGroupEdge);

  t.commands.emplace_back(std::move(gbuffer));
  t.commands.emplace_back(make_barrier(stored));
  t.commands.emplace_back(make_dispatch("cluster_flag", tiles_x, tiles_y, 1, edge, edge, 1, {"depth"}, {used}, params));
  t.commands.emplace_back(make_barrier({used}));
  t.commands.emplace_back(make_dispatch("cluster_light_assign", tiles_x * tiles_y, slices, 1, 64, 1, 1,
                                        {lights, used}, {grid, index}, assign_params));
  t.commands.emplace_back(make_barrier({grid, index}));
  t.commands.emplace_back(make_dispatch("deferred_shade", tiles_for(setup.width, kKernelGroupEdge),
                                        tiles_for(setup.height, kKernelGroupEdge), 1, kKernelGroupEdge,
                                        kKernelGroupEdge, 1, shade_reads, {frame},
                                        {{"shader", "clustered_deferred_lit"},
                                         {"tile_px", std::to_string(kKernelGroupEdge)}}));
  return t;
}

}  // namespace

TechniqueInfo technique_clustered_deferred() {
  return {"clustered_deferred",
          "G-buffer, then cluster flagging, light assignment over used clusters and a shading dispatch "
          "(Olsson et al. 2012; the reference thesis chapter)",
          {{"gbuffer", "rgba8,rgb10a2",
            "G-buffer color targets: albedo, normal, extras (the thesis: depth, normal and albedo buffers)"},
           {"tile_px", "128", "cluster screen tile edge in pixels (the thesis chapter: 128 px tiles)"},
           {"slices", "16", "exponential depth slices between near and far (the thesis chapter: 16)"},
           {"max_lights_per_cluster", "all",
            "light index list capacity per cluster, sizes light_index (the thesis: 64 lights per partition, "
            "1 KB per cluster); all = the light count, so no list can overflow"},
           {"index_bytes", "auto",
            "bytes per light index: 1, 2, 4 or auto (smallest that addresses every light; the thesis uses 8-bit "
            "indices)"}},
          &generate_clustered_deferred};
}

}  // namespace tbdr
