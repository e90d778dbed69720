// The compute unit's kernels on the frame's thread pool: depth bounds, tile light culling, cluster
// flagging and light assignment, visibility-buffer work lists, shading with re-fetches and the
// material texture footprints run by rows of tiles (or bands of rows) on the pool. On a 320x200
// frame (13 rows of 16 px tiles, more than 7 threads' worth) with 400 lights of varied size and
// depth, a depth image with gaps and a visibility image of many triangles and 3 textured
// materials, every output is the same at 1, 2 and 7 threads as on the caller's thread alone, and
// the caller's-thread outputs are those of the kernels' definitions (computed here by brute force).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "kernel/thread_pool.hpp"
#include "models/geometry_unit.hpp"
#include "unit_fixture.hpp"

namespace tbdr {
namespace {

using namespace unit;

constexpr int kW = 320;
constexpr int kH = 200;
constexpr int kTilePx = 16;          // culling, depth bounds, clusters and work lists
constexpr int kRefetchTilePx = 24;   // vbuffer_shade's re-fetch tiles: not a multiple of its bands
constexpr int kSlices = 24;
constexpr int kCap = 8;              // max_lights_per_tile: some tiles overflow
constexpr int kLights = 400;

/// A fixed pseudo-random sequence in [0, 1) (Knuth's MMIX LCG, top 24 bits).
struct Lcg {
  std::uint64_t state;
  float next() {
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    return static_cast<float>(state >> 40) / static_cast<float>(1u << 24);
  }
};

/// 400 lights over the frame at view distances 2..30 with radii 0.2..2.7, and one behind the eye.
ComputeSpec spec() {
  ComputeSpec s;
  s.width = kW;
  s.height = kH;
  Lcg r{7};
  for (int i = 0; i < kLights; ++i) {
    const float px = r.next() * kW, py = r.next() * kH, d = 2.0f + r.next() * 28.0f, radius = 0.2f + r.next() * 2.5f;
    s.lights.push_back(light_at(world_at_pixel(px, py, d, kW, kH), radius));
  }
  s.lights.push_back(light_at({0, 0, 5}, 1.0f));
  s.buffers = {make_buffer("bounds", BufferContent::DepthBounds, DramClass::Other),
               make_buffer("grid", BufferContent::TileGrid, DramClass::LightLists),
               make_buffer("indices", BufferContent::LightIndexList, DramClass::LightLists),
               make_buffer("used", BufferContent::UsedClusters, DramClass::LightLists),
               make_buffer("cgrid", BufferContent::ClusterGrid, DramClass::LightLists),
               make_buffer("cindices", BufferContent::LightIndexList, DramClass::LightLists),
               make_buffer("work", BufferContent::WorkLists, DramClass::Other),
               make_buffer("lit", BufferContent::Image, DramClass::Color),
               make_buffer("lit2", BufferContent::Image, DramClass::Color)};
  ShaderDesc tiled = make_shader(20, 7, LightSource::TileList, 0, 3);
  tiled.name = "tiled";
  ShaderDesc clustered = make_shader(20, 7, LightSource::ClusterList, 0, 1);
  clustered.name = "clustered";
  s.shaders = {tiled, clustered};
  return s;
}

/// Window depth (GL range) of view distance z for compute_camera()'s near and far planes.
float window_depth(float z) {
  const Camera c = compute_camera();
  const float n = c.near_plane, f = c.far_plane;
  return 0.5f * ((f + n - 2.0f * n * f / z) / (f - n) + 1.0f);
}

/// Scene textures the material fetches sample: 3 materials on two textures and the default.
void add_materials(Scene& scene) {
  scene.textures = {TextureInfo{.name = "a", .format = "procedural", .width = 256, .height = 256, .channels = 4},
                    TextureInfo{.name = "b", .format = "procedural", .width = 128, .height = 64, .channels = 4}};
  scene.materials.resize(3);
  scene.materials[0].base_color_texture = 0;
  scene.materials[1].base_color_texture = 1;
}

/// What a frame of dispatches produced.
struct Outputs {
  std::vector<std::uint64_t> stats;  // every ComputeStats figure, in declaration order
  DramTraffic dram;
  std::vector<float> bounds_min, bounds_max;
  std::vector<std::vector<std::uint32_t>> tile_lists, cluster_lists;
  std::uint64_t overflowed = 0;
  std::vector<std::uint8_t> used;
  std::vector<std::uint64_t> texture_lines;
  std::vector<std::uint32_t> lights_evaluated, shaded;
  std::vector<glm::vec4> lit, lit2;
};

/// A rig holding the frame's depth and visibility images and the textured scene.
struct Frame {
  ComputeRig rig{spec()};
  std::unique_ptr<TextureLayout> layout;

  Frame() {
    // Depth: a slope from 3 to 23 along x with a ripple along y; every 11th pixel uncovered.
    std::vector<float> depth(static_cast<std::size_t>(kW) * kH);
    for (int y = 0; y < kH; ++y) {
      for (int x = 0; x < kW; ++x) {
        const std::size_t p = static_cast<std::size_t>(y) * kW + static_cast<std::size_t>(x);
        const float z = 3.0f + 20.0f * static_cast<float>(x) / kW + 2.0f * std::sin(0.1f * static_cast<float>(y));
        depth[p] = p % 11 == 0 ? 1.0f : window_depth(z);
      }
    }
    rig.add_depth_image("depth", depth);
    // Visibility: a surface where depth is covered; blocks of 3 x 5 pixels share a triangle (so
    // triangles cross tile and band rows), its material the triangle modulo 3; quad uvs from the
    // quad and the triangle.
    std::vector<std::uint8_t> valid(depth.size());
    for (std::size_t p = 0; p < depth.size(); ++p) valid[p] = depth[p] < 1.0f ? 1 : 0;
    rig.add_gbuffer("vis", valid);
    auto& surfaces = rig.images.attachments.at("vis").surface;
    for (int y = 0; y < kH; ++y) {
      for (int x = 0; x < kW; ++x) {
        const std::size_t p = static_cast<std::size_t>(y) * kW + static_cast<std::size_t>(x);
        SurfacePoint s = surfaces[p];
        s.triangle = static_cast<std::uint32_t>((y / 5) * kW + x) / 3;
        s.material = s.triangle % 3;
        const float u = static_cast<float>(x >> 1) / 64.0f + 0.01f * static_cast<float>(s.triangle % 7);
        const float v = static_cast<float>(y >> 1) / 48.0f;
        s.quad_uv = {glm::vec2(u, v), glm::vec2(u + 1.0f / 128, v), glm::vec2(u, v + 1.0f / 96), glm::vec2(u + 1.0f / 128, v + 1.0f / 96)};
        surfaces.set(p, s);
      }
    }
    add_materials(rig.scene);
    layout = std::make_unique<TextureLayout>(&rig.scene, rig.hw, 3);
  }

  /// Runs the frame's dispatches with `pool` (null: the caller's thread) and gathers the outputs.
  Outputs run(ThreadPool* pool) {
    Outputs o;
    ComputeContext cc = rig.context();
    cc.pool = pool;
    cc.textures = layout.get();
    cc.texture_lines = &o.texture_lines;
    cc.colour = true;
    const std::string tp = std::to_string(kTilePx);
    const std::vector<DispatchCmd> cmds = {
        make_dispatch("depth_bounds", {"depth"}, {"bounds"}, {{"tile_px", tp}}),
        make_dispatch("tile_light_cull", {"depth", "bounds"}, {"grid", "indices"},
                      {{"tile_px", tp}, {"max_lights_per_tile", std::to_string(kCap)}}),
        make_dispatch("cluster_flag", {"depth"}, {"used"}, {{"tile_px", tp}, {"slices", std::to_string(kSlices)}}),
        make_dispatch("cluster_light_assign", {"used"}, {"cgrid", "cindices"}, {{"tile_px", tp}, {"slices", std::to_string(kSlices)}}),
        make_dispatch("vbuffer_worklists", {"vis"}, {"work"}, {{"tile_px", tp}}),
        make_dispatch("vbuffer_shade", {"vis", "grid", "indices"}, {"lit"}, {{"shader", "tiled"}, {"tile_px", std::to_string(kRefetchTilePx)}}),
        make_dispatch("deferred_shade", {"vis", "cgrid", "cindices"}, {"lit2"}, {{"shader", "clustered"}})};
    ComputeStats stats;
    std::string image;
    for (const DispatchCmd& d : cmds) run_dispatch(cc, d, stats, o.dram, image);
    ComputeStats::zip(stats, stats, [&](const auto& x, const auto&, const StatDef&) { o.stats.push_back(static_cast<std::uint64_t>(x.value())); });
    const FrameImages& im = rig.images;
    o.bounds_min = im.depth_bounds.at("bounds")->min_distance;
    o.bounds_max = im.depth_bounds.at("bounds")->max_distance;
    o.tile_lists = im.tile_grids.at("grid")->lists;
    o.overflowed = im.tile_grids.at("grid")->overflowed_tiles;
    o.used = im.cluster_grids.at("cgrid")->used;
    o.cluster_lists = im.cluster_grids.at("cgrid")->lists;
    o.lights_evaluated = im.counters.lights_evaluated;
    o.shaded = im.counters.shaded;
    o.lit = im.image_buffers.at("lit").color;
    o.lit2 = im.image_buffers.at("lit2").color;
    return o;
  }
};

void expect_same(const Outputs& a, const Outputs& b, unsigned threads) {
  EXPECT_EQ(a.stats, b.stats) << threads << " threads";
  EXPECT_EQ(a.dram.read_bytes, b.dram.read_bytes) << threads << " threads";
  EXPECT_EQ(a.dram.write_bytes, b.dram.write_bytes) << threads << " threads";
  EXPECT_EQ(a.bounds_min, b.bounds_min) << threads << " threads";
  EXPECT_EQ(a.bounds_max, b.bounds_max) << threads << " threads";
  EXPECT_EQ(a.tile_lists, b.tile_lists) << threads << " threads";
  EXPECT_EQ(a.overflowed, b.overflowed) << threads << " threads";
  EXPECT_EQ(a.used, b.used) << threads << " threads";
  EXPECT_EQ(a.cluster_lists, b.cluster_lists) << threads << " threads";
  EXPECT_EQ(a.texture_lines, b.texture_lines) << threads << " threads";
  EXPECT_EQ(a.lights_evaluated, b.lights_evaluated) << threads << " threads";
  EXPECT_EQ(a.shaded, b.shaded) << threads << " threads";
  EXPECT_TRUE(a.lit == b.lit) << threads << " threads";
  EXPECT_TRUE(a.lit2 == b.lit2) << threads << " threads";
}

TEST(ComputeThreads, CullingFlaggingWorkListsAndFootprintsAreTheSameAtOneTwoAndSevenThreads) {
  Frame serial;
  const Outputs want = serial.run(nullptr);
  // The frame is big enough to split: 13 rows of tiles, lists, overflows, used clusters,
  // texture lines and re-fetches all present.
  ASSERT_EQ(want.bounds_min.size(), 20u * 13u);
  for (unsigned threads : {1u, 2u, 7u}) {
    Frame f;
    ThreadPool pool(threads);
    expect_same(f.run(&pool), want, threads);
  }
}

/// The serial run's figures against the kernels' definitions, computed here by brute force.
TEST(ComputeThreads, KernelOutputsAreThoseOfTheirDefinitions) {
  Frame f;
  ThreadPool pool(2);
  const Outputs o = f.run(&pool);
  const ComputeRig& rig = f.rig;
  const auto& lights = rig.trace.lights;
  const int tiles_x = (kW + kTilePx - 1) / kTilePx, tiles_y = (kH + kTilePx - 1) / kTilePx;
  std::vector<PixelRect> rects;
  for (const Light& l : lights) rects.push_back(light_screen_rect(l, rig.camera, rig.viewport));
  auto tile_rect = [&](int tx, int ty, int tile_px) {
    return intersect({tx * tile_px, ty * tile_px, (tx + 1) * tile_px, (ty + 1) * tile_px}, {0, 0, kW, kH});
  };

  // Tile lists: every light whose rectangle meets the tile and whose sphere touches the tile's
  // volume between its depth bounds widened by 0.1 % (min x 0.999, max x 1.001), ascending.
  std::uint64_t entries = 0, overflowed = 0;
  for (int ty = 0; ty < tiles_y; ++ty) {
    for (int tx = 0; tx < tiles_x; ++tx) {
      const std::size_t t = static_cast<std::size_t>(ty * tiles_x + tx);
      std::vector<std::uint32_t> list;
      if (o.bounds_min[t] <= o.bounds_max[t]) {
        const PixelRect rect = tile_rect(tx, ty, kTilePx);
        for (std::uint32_t l = 0; l < lights.size(); ++l) {
          if (rects[l].empty() || intersect(rects[l], rect).empty()) continue;
          if (sphere_touches_tile_volume(rig.frustum, lights[l], rect, o.bounds_min[t] * 0.999f, o.bounds_max[t] * 1.001f)) list.push_back(l);
        }
      }
      EXPECT_EQ(o.tile_lists[t], list) << "tile " << tx << "," << ty;
      entries += list.size();
      overflowed += list.size() > static_cast<std::size_t>(kCap) ? 1 : 0;
    }
  }
  EXPECT_GT(entries, 1000u);
  EXPECT_GT(overflowed, 0u);
  EXPECT_EQ(o.overflowed, overflowed);

  // Cluster lists: every light in every used cluster its rectangle's tiles and its depth extent's
  // slices reach, whose sphere touches the cluster, ascending.
  const ClusterGrid& g = *rig.images.cluster_grids.at("cgrid");
  std::vector<std::vector<std::uint32_t>> clusters(g.lists.size());
  for (std::uint32_t l = 0; l < lights.size(); ++l) {
    if (rects[l].empty()) continue;
    const float dist = rig.frustum.distance_of(lights[l].position);
    for (int s = g.slice_of(std::max(0.0f, dist - lights[l].radius)); s <= g.slice_of(dist + lights[l].radius); ++s) {
      float d0 = 0, d1 = 0;
      g.slice_range(s, d0, d1);
      for (int ty = rects[l].y0 / kTilePx; ty <= (rects[l].y1 - 1) / kTilePx; ++ty) {
        for (int tx = rects[l].x0 / kTilePx; tx <= (rects[l].x1 - 1) / kTilePx; ++tx) {
          const std::size_t c = g.index(tx, ty, s);
          if (g.used[c] && sphere_touches_tile_volume(rig.frustum, lights[l], tile_rect(tx, ty, kTilePx), d0, d1)) clusters[c].push_back(l);
        }
      }
    }
  }
  EXPECT_EQ(o.cluster_lists, clusters);
  EXPECT_GT(std::count(o.used.begin(), o.used.end(), 1), 100);

  // Work lists and re-fetches: distinct (tile, material) and (re-fetch tile, triangle) pairs.
  const AttachmentImage& vis = rig.images.attachments.at("vis");
  std::set<std::pair<int, std::uint32_t>> work, refetch;
  for (int y = 0; y < kH; ++y) {
    for (int x = 0; x < kW; ++x) {
      const std::size_t p = static_cast<std::size_t>(y) * kW + static_cast<std::size_t>(x);
      if (!vis.surface_valid[p]) continue;
      work.insert({(y / kTilePx) * tiles_x + x / kTilePx, vis.surface[p].material});
      const int rx = (kW + kRefetchTilePx - 1) / kRefetchTilePx;
      refetch.insert({(y / kRefetchTilePx) * rx + x / kRefetchTilePx, vis.surface[p].triangle});
    }
  }
  ComputeStats stats;
  std::size_t i = 0;
  std::map<std::string, std::uint64_t> by_name;
  ComputeStats::zip(stats, stats, [&](const auto&, const auto&, const StatDef& d) { by_name[d.name] = o.stats[i++]; });
  EXPECT_EQ(by_name.at("work_list_entries"), work.size());
  EXPECT_EQ(by_name.at("refetched_vertices"), 3 * refetch.size());

  // Material footprints: per workgroup tile of vbuffer_shade (its tile_px, 24 px),
  // the sorted distinct lines of the 2 material fetches (3 fetches, 1 on the visibility image)
  // of every distinct (quad, triangle), appended in tile order.
  std::vector<std::uint64_t> lines;
  std::uint64_t accesses = 0;
  QuadFootprint fp;
  for (int ty = 0; ty < kH; ty += kRefetchTilePx) {
    for (int tx = 0; tx < kW; tx += kRefetchTilePx) {
      std::map<std::pair<std::uint64_t, std::uint32_t>, std::size_t> quads;  // (quad, triangle) -> a surface
      for (int y = ty; y < std::min(kH, ty + kRefetchTilePx); ++y) {
        for (int x = tx; x < std::min(kW, tx + kRefetchTilePx); ++x) {
          const std::size_t p = static_cast<std::size_t>(y) * kW + static_cast<std::size_t>(x);
          if (vis.surface_valid[p]) quads.insert({{static_cast<std::uint64_t>(y >> 1) * 8192u + static_cast<std::uint64_t>(x >> 1), vis.surface[p].triangle}, p});
        }
      }
      std::set<std::uint64_t> tile;
      for (const auto& [key, p] : quads) {
        const SurfacePoint& s = vis.surface[p];
        const TextureStorage& tex = f.layout->of_material(s.material);
        f.layout->quad_footprint(tex, s.quad_uv, fp);
        accesses += std::uint64_t{fp.count} * 2;
        for (std::uint32_t j = 0; j < fp.count; ++j) {
          for (std::uint64_t fetch = 0; fetch < 2; ++fetch) tile.insert(fp.lines[j] + fetch * tex.slot_bytes);
        }
      }
      lines.insert(lines.end(), tile.begin(), tile.end());
    }
  }
  EXPECT_GT(lines.size(), 1000u);
  EXPECT_EQ(o.texture_lines, lines);
  EXPECT_EQ(by_name.at("compute_texture_line_accesses"), accesses);
  EXPECT_EQ(by_name.at("compute_texture_tile_lines"), lines.size());
}

}  // namespace
}  // namespace tbdr
