// The geometry unit on its own, with the identity camera (world position = clip position, w = 1):
// NDC is the world's (x, y, z), the visible volume the cube [-1, 1]^3, and a triangle that is
// counter-clockwise in (x, y) is front-facing (GL convention). Counts of culling, clipping, vertex
// shading behind the post-transform cache and fetch bytes are derived by hand.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <optional>
#include <span>
#include <vector>

#include <glm/gtc/matrix_transform.hpp>

#include "kernel/thread_pool.hpp"
#include "unit_fixture.hpp"

namespace tbdr {
namespace {

using namespace unit;

/// A scene of one instance per sub-mesh (identity placement).
Scene scene_of(const std::vector<SubMesh>& meshes, bool double_sided = false) {
  Scene s;
  Material m;
  m.name = "m";
  m.double_sided = double_sided;
  s.materials = {m};
  for (const auto& mesh : meshes) {
    s.submeshes.push_back(mesh);
    s.instances.push_back({static_cast<std::uint32_t>(s.submeshes.size() - 1), glm::mat4(1.0f), mesh.name});
  }
  return s;
}

DrawCmd draw_of(const std::string& submesh) {
  DrawCmd d;
  d.submesh = submesh;
  return d;
}

PipelineState culling(CullMode c) {
  PipelineState p;
  p.cull = c;
  return p;
}

GeometrySpec spec_of(Scene scene, std::vector<std::string> sets = {}) {
  GeometrySpec g;
  g.scene = std::move(scene);
  g.sets = std::move(sets);
  return g;
}

// Counter-clockwise (front) and clockwise (back) triangles in the middle of the screen.
const std::vector<glm::vec3> kFrontBack = {{-0.5f, -0.5f, 0}, {0.5f, -0.5f, 0}, {0, 0.5f, 0},   // CCW
                                           {-0.5f, -0.5f, 0}, {0, 0.5f, 0}, {0.5f, -0.5f, 0}};  // CW

TEST(UnitGeometry, BackFacesAreCulledPerThePipeline) {
  const Scene s = scene_of({make_mesh("pair", kFrontBack, {0, 1, 2, 3, 4, 5})});
  {
    GeometryRig rig(spec_of(s));
    rig.run(draw_of("pair"), make_shader(1), culling(CullMode::Back));
    EXPECT_EQ(rig.stats.draws.value(), 1u);
    EXPECT_EQ(rig.stats.primitives_in.value(), 2u);
    EXPECT_EQ(rig.stats.primitives_culled_backface.value(), 1u);
    EXPECT_EQ(rig.stats.primitives_out.value(), 1u);
    ASSERT_EQ(rig.prims.size(), 1u);
    EXPECT_TRUE(rig.prims[0].setup.front_facing);
  }
  {
    GeometryRig rig(spec_of(s));
    rig.run(draw_of("pair"), make_shader(1), culling(CullMode::Front));
    EXPECT_EQ(rig.stats.primitives_culled_backface.value(), 1u);
    ASSERT_EQ(rig.prims.size(), 1u);
    EXPECT_FALSE(rig.prims[0].setup.front_facing);
  }
  {
    GeometryRig rig(spec_of(s));
    rig.run(draw_of("pair"), make_shader(1), culling(CullMode::None));
    EXPECT_EQ(rig.stats.primitives_culled_backface.value(), 0u);
    EXPECT_EQ(rig.stats.primitives_out.value(), 2u);
  }
  // A double-sided material overrides the pipeline's culling.
  GeometryRig rig(spec_of(scene_of({make_mesh("pair", kFrontBack, {0, 1, 2, 3, 4, 5})}, true)));
  rig.run(draw_of("pair"), make_shader(1), culling(CullMode::Back));
  EXPECT_EQ(rig.stats.primitives_out.value(), 2u);
}

TEST(UnitGeometry, TrianglesOutsideTheFrustumAreRejected) {
  // Wholly right of x = 1; wholly beyond the far plane z = 1; wholly in front of the near plane
  // z = -1; and one in view: 3 frustum culls, 1 out.
  const Scene s = scene_of({make_mesh("t", {{1.5f, 0, 0}, {2.5f, 0, 0}, {2, 0.5f, 0},
                                            {-0.5f, -0.5f, 2}, {0.5f, -0.5f, 2}, {0, 0.5f, 2},
                                            {-0.5f, -0.5f, -3}, {0.5f, -0.5f, -3}, {0, 0.5f, -3},
                                            {-0.5f, -0.5f, 0}, {0.5f, -0.5f, 0}, {0, 0.5f, 0}},
                                     {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11})});
  GeometryRig rig(spec_of(s));
  rig.run(draw_of("t"));
  EXPECT_EQ(rig.stats.primitives_in.value(), 4u);
  EXPECT_EQ(rig.stats.primitives_culled_frustum.value(), 3u);
  EXPECT_EQ(rig.stats.primitives_out.value(), 1u);
}

TEST(UnitGeometry, ATriangleCrossingTheNearPlaneIsClippedIntoTwo) {
  // The apex at z = -3 lies beyond the near plane z = -w = -1: the edges to it are cut at a third
  // of their length, leaving the quad (-0.5,-0.5), (0.5,-0.5), (1/3,-1/6), (-1/3,-1/6), fanned
  // into 2 triangles.
  const Scene s = scene_of({make_mesh("t", {{-0.5f, -0.5f, 0}, {0.5f, -0.5f, 0}, {0, 0.5f, -3}}, {0, 1, 2})});
  GeometryRig rig(spec_of(s));
  rig.run(draw_of("t"));
  EXPECT_EQ(rig.stats.primitives_in.value(), 1u);
  EXPECT_EQ(rig.stats.primitives_clipped.value(), 1u);
  EXPECT_EQ(rig.stats.primitives_out.value(), 2u);
  ASSERT_EQ(rig.prims.size(), 2u);
  // The clipped vertices are new (no re-use in primitive blocks); the original ones keep theirs.
  std::uint64_t made_by_clipping = 0;
  ASSERT_EQ(rig.out.keys.size(), 2u);
  for (const VertexKeys& keys : rig.out.keys) {
    for (std::uint64_t k : keys) made_by_clipping += (k >> 63) & 1u;
  }
  EXPECT_EQ(made_by_clipping, 3u);  // (1/3,-1/6) once, (-1/3,-1/6) in both triangles of the fan
}

TEST(UnitGeometry, ZeroAreaTrianglesAreCulled) {
  // Three collinear vertices, and a triangle of 1e-5 NDC (0.08 sub-pixel units) that snaps to a
  // point.
  const Scene s = scene_of({make_mesh("t", {{-0.5f, 0, 0}, {0, 0, 0}, {0.5f, 0, 0},
                                            {0, 0, 0}, {1e-5f, 0, 0}, {0, 1e-5f, 0}},
                                     {0, 1, 2, 3, 4, 5})});
  GeometryRig rig(spec_of(s));
  rig.run(draw_of("t"), make_shader(1), culling(CullMode::None));
  EXPECT_EQ(rig.stats.primitives_culled_zero_area.value(), 2u);
  EXPECT_EQ(rig.stats.primitives_out.value(), 0u);
}

// A quad: 4 vertices, indices 0 1 2 0 2 3 (2-byte indices, 32-byte vertices).
const std::vector<glm::vec3> kQuad = {{-0.5f, -0.5f, 0}, {0.5f, -0.5f, 0}, {0.5f, 0.5f, 0}, {-0.5f, 0.5f, 0}};

TEST(UnitGeometry, ThePostTransformCacheShadesASharedVertexOnce) {
  // 32 entries: the 6 indices shade 4 vertices: 4 x 24 = 96 vertex ALU ops (geometry.
  // vertex_shader_alu_ops), 4 x 32 = 128 B of attributes and 6 x 2 = 12 B of indices fetched.
  GeometryRig rig(spec_of(scene_of({make_mesh("quad", kQuad, {0, 1, 2, 0, 2, 3})})));
  rig.run(draw_of("quad"));
  EXPECT_EQ(rig.stats.vertices_shaded.value(), 4u);
  EXPECT_EQ(rig.stats.vertex_alu_ops.value(), 96u);
  EXPECT_EQ(rig.stats.vertex_fetch_bytes.value(), 128u);
  EXPECT_EQ(rig.stats.index_fetch_bytes.value(), 12u);
  EXPECT_EQ(rig.dram.reads(DramClass::Vertices), 128u);
  EXPECT_EQ(rig.dram.reads(DramClass::Indices), 12u);
  EXPECT_EQ(rig.stats.primitives_out.value(), 2u);
}

TEST(UnitGeometry, ASmallerCacheShadesMoreVertices) {
  // FIFO of 2 entries over 0 1 2 0 2 3: 0 miss [0], 1 miss [0 1], 2 miss (evicts 0) [2 1],
  // 0 miss (evicts 1) [2 0], 2 hit, 3 miss: 5 shaded. No cache: all 6.
  const Scene s = scene_of({make_mesh("quad", kQuad, {0, 1, 2, 0, 2, 3})});
  GeometryRig two(spec_of(s, {"geometry.vertex_cache_entries=2"}));
  two.run(draw_of("quad"));
  EXPECT_EQ(two.stats.vertices_shaded.value(), 5u);
  EXPECT_EQ(two.stats.vertex_fetch_bytes.value(), 5u * 32u);
  GeometryRig none(spec_of(s, {"geometry.vertex_cache_entries=0"}));
  none.run(draw_of("quad"));
  EXPECT_EQ(none.stats.vertices_shaded.value(), 6u);
}

TEST(UnitGeometry, ANonIndexedDrawShadesEveryVertex) {
  // index_bytes 0: the 6 generated indices all shade, even with a cache; no index bytes.
  GeometryRig rig(spec_of(scene_of({make_mesh("quad", kQuad, {0, 1, 2, 0, 2, 3}, 0, 0, 48)})));
  rig.run(draw_of("quad"));
  EXPECT_EQ(rig.stats.vertices_shaded.value(), 6u);
  EXPECT_EQ(rig.stats.vertex_fetch_bytes.value(), 6u * 48u);
  EXPECT_EQ(rig.stats.index_fetch_bytes.value(), 0u);
}

TEST(UnitGeometry, AFullscreenDrawIsOneTriangleOfThreeVertices) {
  // Three generated vertices of 16 B (a vec4 position each), one triangle covering the viewport.
  GeometryRig rig(spec_of(scene_of({})));
  DrawCmd d;
  d.geometry = GeometryKind::Fullscreen;
  rig.run(d);
  EXPECT_EQ(rig.stats.vertices_shaded.value(), 3u);
  EXPECT_EQ(rig.stats.vertex_fetch_bytes.value(), 48u);
  EXPECT_EQ(rig.stats.primitives_out.value(), 1u);
  ASSERT_EQ(rig.prims.size(), 1u);
  EXPECT_EQ(rig.prims[0].setup.bbox, (PixelRect{0, 0, 64, 64}));
}

TEST(UnitGeometry, LightProxiesAreShadedPerSelectedLight) {
  // Quads: 4 vertices and 2 triangles per light whose sphere is in front of the camera; a light
  // behind it (z = +1 with the identity view looking down -z) has no screen rectangle: skipped.
  Light in_front;
  in_front.position = {0, 0, -0.5f};
  in_front.radius = 0.1f;
  Light behind;
  behind.position = {0, 0, 1};
  behind.radius = 0.1f;
  GeometrySpec g = spec_of(scene_of({}));
  g.lights = {in_front, behind};
  {
    GeometryRig rig(g);
    DrawCmd d;
    d.geometry = GeometryKind::LightQuads;
    rig.run(d, make_shader(1, 0, LightSource::Proxy), {}, {0, 1});
    EXPECT_EQ(rig.stats.vertices_shaded.value(), 4u);
    EXPECT_EQ(rig.stats.primitives_out.value(), 2u);
    for (const auto& p : rig.prims) EXPECT_EQ(p.proxy_light, 0);
  }
  // Spheres: an icosahedron (20 triangles, 60 vertices) per light at level 0, 4x as many per
  // subdivision: level 1 = 80 triangles, 240 vertices; both lights are submitted.
  GeometryRig rig(g);
  DrawCmd d;
  d.geometry = GeometryKind::LightSpheres;
  d.subdivisions = 1;
  rig.run(d, make_shader(1, 0, LightSource::Proxy), culling(CullMode::None), {0, 1});
  EXPECT_EQ(rig.stats.vertices_shaded.value(), 2u * 240u);
  EXPECT_EQ(rig.stats.primitives_in.value(), 2u * 80u);
  EXPECT_EQ(rig.stats.vertex_fetch_bytes.value(), 2u * 240u * 16u);
}

TEST(UnitGeometry, ObjectListsHoldTheLightsTouchingTheInstanceBounds) {
  // The quad's bounds are [-0.5, 0.5]^2 x {0}. Light 0 at (0, 0, 0.5), r 0.6: distance 0.5 -> in.
  // Light 1 at (2, 2, 0), r 1: nearest point (0.5, 0.5, 0), distance 2.12 -> out. Light 2 at
  // (1, 0, 0), r 0.5: nearest point (0.5, 0, 0), distance exactly 0.5 -> in (touching counts).
  Light l0, l1, l2;
  l0.position = {0, 0, 0.5f};
  l0.radius = 0.6f;
  l1.position = {2, 2, 0};
  l1.radius = 1.0f;
  l2.position = {1, 0, 0};
  l2.radius = 0.5f;
  GeometrySpec g = spec_of(scene_of({make_mesh("quad", kQuad, {0, 1, 2, 0, 2, 3})}));
  g.lights = {l0, l1, l2};
  GeometryRig rig(g);
  rig.run(draw_of("quad"), make_shader(1, 1, LightSource::ObjectList), {}, {0, 1, 2});
  ASSERT_EQ(rig.object_lights.size(), 1u);
  EXPECT_EQ(rig.object_lights[0], (std::vector<std::uint32_t>{0, 2}));
  // Only the selected lights are considered.
  rig.run(draw_of("quad"), make_shader(1, 1, LightSource::ObjectList), {}, {1, 2});
  ASSERT_EQ(rig.object_lights.size(), 2u);
  EXPECT_EQ(rig.object_lights[1], (std::vector<std::uint32_t>{2}));
}

TEST(UnitGeometry, ADrawWithACullBoxSetsUpWhatAFreshUnitSetsUp) {
  // A draw with a cull box keeps what vertex shading and clipping made of each instance, and the
  // next such draw only sets the kept screen triangles up under its own scissor: the same
  // primitives, vertex identities and counts as a geometry unit that never drew before. The mesh
  // has a front and a back face, a triangle beyond the frustum, one the near plane cuts in two
  // (both pieces reach the left half) and a small one in the right half; the second draw's
  // scissor keeps the left half of the 64x64 viewport only.
  const Scene s = scene_of({make_mesh("m", {{-0.5f, -0.5f, 0}, {0.5f, -0.5f, 0}, {0, 0.5f, 0},
                                            {-0.5f, -0.5f, 0}, {0, 0.5f, 0}, {0.5f, -0.5f, 0},
                                            {1.5f, 0, 0}, {2.5f, 0, 0}, {2, 0.5f, 0},
                                            {-0.3f, -0.5f, 0}, {0.5f, -0.5f, 0}, {0.1f, 0.5f, -3},
                                            {0.6f, -0.2f, 0}, {0.9f, -0.2f, 0}, {0.75f, 0.2f, 0}},
                                     {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14})});
  DrawCmd whole = draw_of("m");
  whole.cull = CullBox{glm::vec3(-10.0f), glm::vec3(10.0f)};
  DrawCmd left = whole;
  left.scissor = ScissorRect{0, 0, 32, 64};
  GeometryRig twice(spec_of(s)), fresh(spec_of(s));
  twice.run(whole, make_shader(1), culling(CullMode::Back));
  const std::size_t first = twice.prims.size();
  const GeometryStats after_first = twice.stats;
  twice.run(left, make_shader(1), culling(CullMode::Back));
  fresh.run(left, make_shader(1), culling(CullMode::Back));
  // The first draw: 5 triangles in, 1 beyond the frustum, 1 back face, 1 clipped into 2: 4 out.
  EXPECT_EQ(first, 4u);
  EXPECT_EQ(after_first.primitives_out.value(), 4u);
  // The second: the same counts as the fresh unit's, primitive by primitive the same records.
  EXPECT_EQ(twice.stats.primitives_in.value() - after_first.primitives_in.value(), fresh.stats.primitives_in.value());
  EXPECT_EQ(twice.stats.primitives_culled_frustum.value() - after_first.primitives_culled_frustum.value(),
            fresh.stats.primitives_culled_frustum.value());
  EXPECT_EQ(twice.stats.primitives_culled_backface.value() - after_first.primitives_culled_backface.value(),
            fresh.stats.primitives_culled_backface.value());
  EXPECT_EQ(twice.stats.primitives_clipped.value() - after_first.primitives_clipped.value(), fresh.stats.primitives_clipped.value());
  EXPECT_EQ(twice.stats.primitives_culled_scissor.value() - after_first.primitives_culled_scissor.value(),
            fresh.stats.primitives_culled_scissor.value());
  EXPECT_EQ(twice.stats.vertices_shaded.value() - after_first.vertices_shaded.value(), fresh.stats.vertices_shaded.value());
  EXPECT_EQ(fresh.stats.primitives_culled_scissor.value(), 1u);  // the small one, right of x = 32 px
  EXPECT_EQ(fresh.stats.primitives_clipped.value(), 1u);
  ASSERT_EQ(twice.prims.size() - first, fresh.prims.size());
  ASSERT_EQ(fresh.prims.size(), 3u);
  for (std::size_t i = 0; i < fresh.prims.size(); ++i) {
    const Primitive& a = twice.prims[first + i];
    const Primitive& b = fresh.prims[i];
    EXPECT_EQ(a.setup.bbox, b.setup.bbox) << i;
    EXPECT_EQ(a.setup.front_facing, b.setup.front_facing) << i;
    for (int v = 0; v < 3; ++v) {
      EXPECT_EQ(a.world[v], b.world[v]) << i;
      EXPECT_EQ(a.normal[v], b.normal[v]) << i;
      EXPECT_EQ(a.uv[v], b.uv[v]) << i;
      // The same vertex (index, or made by clipping), whatever the object number.
      EXPECT_EQ(twice.out.keys[first + i][v] & 0x80000000ffffffffull, fresh.out.keys[i][v] & 0x80000000ffffffffull) << i;
    }
  }
  // A draw culling the other faces makes its own (the kept instance is of the back-face mode).
  GeometryRig front(spec_of(s));
  twice.run(left, make_shader(1), culling(CullMode::Front));
  front.run(left, make_shader(1), culling(CullMode::Front));
  EXPECT_EQ(twice.prims.size() - first - 3, front.prims.size());
  EXPECT_EQ(front.prims.size(), 1u);  // the back face; the front one, both near-plane pieces and the small one culled
  EXPECT_EQ(front.stats.primitives_culled_backface.value(), 3u);
}

/// A sink recording what it is given, whose tile test is a function of the primitive (its
/// bounding box's corner pixels) it checks again in accept(): what it is handed is what it listed
/// for that primitive. With a pool, every `period`-th primitive it takes the pool for a job of its
/// own inside accept(), as a partial render does, after GeometryUnit::settle.
class PoolTakingSink final : public PrimitiveSink {
 public:
  PoolTakingSink(const GeometryUnit& unit, ThreadPool* pool, std::size_t period) : unit_(unit), pool_(pool), period_(period) {}
  void accept(const Primitive& p, const VertexKeys& k, std::optional<std::span<const int>> tiles) override {
    prims.push_back(p);
    keys.push_back(k);
    std::vector<int> expected;
    tiles_touched(p, expected);
    if (!tiles) ++unlisted;
    if (tiles && !std::equal(tiles->begin(), tiles->end(), expected.begin(), expected.end())) ++mislisted;
    if (pool_ != nullptr && prims.size() % period_ == 0) {
      unit_.settle();
      std::atomic<int> ran{0};
      pool_->for_each(4, [&](std::size_t, unsigned) { ++ran; });
      own_jobs_items += static_cast<std::size_t>(ran.load());
    }
  }
  bool tiles_touched(const Primitive& p, std::vector<int>& tiles) const override {
    tiles.push_back(p.setup.bbox.x0 + 1000 * p.setup.bbox.y0);
    tiles.push_back(p.setup.bbox.x1 + 1000 * p.setup.bbox.y1);
    return true;
  }
  std::vector<Primitive> prims;
  std::vector<VertexKeys> keys;
  std::size_t unlisted = 0, mislisted = 0, own_jobs_items = 0;

 private:
  const GeometryUnit& unit_;
  ThreadPool* pool_;
  std::size_t period_;
};

TEST(UnitGeometry, WindowsSetUpOnThePoolWhileDeliveringGiveWhatOneThreadGives) {
  // 48 instances of a 1024-triangle grid: about 6 windows of kSetupWindowTriangles (8192), each
  // next one set up on the helpers while the caller delivers the one before. The sink takes the
  // pool inside accept() every 1000 primitives (as a partial render does, after settle()): the
  // primitives, their vertex identities, the tiles handed with them and the counts are those of a
  // unit without a pool.
  SubMesh grid;
  std::vector<glm::vec3> pos;
  std::vector<std::uint32_t> idx;
  constexpr int kCells = 16;  // 16 x 32 cells of 2 triangles each: 1024 triangles
  for (int y = 0; y <= 2 * kCells; ++y) {
    for (int x = 0; x <= kCells; ++x) pos.push_back({-0.9f + 0.05f * x, -0.9f + 0.05f * y, 0.0f});
  }
  for (int y = 0; y < 2 * kCells; ++y) {
    for (int x = 0; x < kCells; ++x) {
      const auto v = static_cast<std::uint32_t>(y * (kCells + 1) + x);
      idx.insert(idx.end(), {v, v + 1, v + kCells + 2, v, v + kCells + 2, v + kCells + 1});
    }
  }
  Scene scene;
  scene.materials.push_back(Material{});
  scene.submeshes.push_back(make_mesh("grid", pos, idx));
  for (int i = 0; i < 48; ++i) {
    const glm::mat4 shift = glm::translate(glm::mat4(1.0f), glm::vec3(0.02f * static_cast<float>(i % 8), 0.01f * static_cast<float>(i / 8), 0.0f));
    scene.instances.push_back({0, shift, "grid"});
  }
  const HwConfig hw = make_hw({});
  const std::vector<Light> lights;
  const CameraXform camera{};
  const Viewport viewport = make_viewport(kViewportPx, kViewportPx, static_cast<int>(hw.geometry.subpixel_bits));
  DrawStore store;
  const DrawContext draw = store.add(DrawCmd{}, make_shader(1), PipelineState{}, {}, 0);

  struct Run {
    GeometryStats stats;
    std::vector<Primitive> prims;
    std::vector<VertexKeys> keys;
    std::size_t unlisted = 0, mislisted = 0, own_jobs_items = 0;
  };
  auto run = [&](ThreadPool* pool) {
    GeometryUnit unit(hw, &scene, lights, camera, viewport);
    unit.use_pool(pool);
    PoolTakingSink sink(unit, pool, 1000);
    std::vector<std::vector<std::uint32_t>> object_lights;
    DramTraffic dram;
    Run r;
    unit.run_draw(draw, 0, sink, object_lights, r.stats, dram);
    r.prims = std::move(sink.prims);
    r.keys = std::move(sink.keys);
    r.unlisted = sink.unlisted;
    r.mislisted = sink.mislisted;
    r.own_jobs_items = sink.own_jobs_items;
    return r;
  };
  const Run alone = run(nullptr);
  ThreadPool pool(3);
  const Run pooled = run(&pool);
  ASSERT_EQ(alone.stats.primitives_in.value(), 48u * 1024u);
  ASSERT_EQ(alone.prims.size(), 48u * 1024u);  // all in view, none culled (no face culling)
  ASSERT_EQ(pooled.prims.size(), alone.prims.size());
  EXPECT_EQ(pooled.stats.primitives_out.value(), alone.stats.primitives_out.value());
  EXPECT_EQ(pooled.stats.vertices_shaded.value(), alone.stats.vertices_shaded.value());
  for (std::size_t i = 0; i < alone.prims.size(); ++i) {
    ASSERT_EQ(pooled.prims[i].setup.bbox, alone.prims[i].setup.bbox) << i;
    ASSERT_EQ(pooled.prims[i].object, alone.prims[i].object) << i;
    ASSERT_EQ(pooled.keys[i], alone.keys[i]) << i;
  }
  // Every scene triangle came with the tiles the sink listed for it, on either path.
  EXPECT_EQ(alone.unlisted, 0u);
  EXPECT_EQ(pooled.unlisted, 0u);
  EXPECT_EQ(alone.mislisted, 0u);
  EXPECT_EQ(pooled.mislisted, 0u);
  // 49 jobs of 4 items ran on the pool inside accept() (49152 / 1000).
  EXPECT_EQ(pooled.own_jobs_items, 49u * 4u);
}

}  // namespace
}  // namespace tbdr
