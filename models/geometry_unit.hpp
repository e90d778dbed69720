#pragma once
// The geometry unit: vertex fetch (index and attribute bytes), vertex shading behind a
// post-transform vertex cache, clipping against the near plane, frustum / back-face / zero-area
// culling and the viewport transform to fixed point. It turns one draw into primitives.
#include <atomic>
#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include <glm/glm.hpp>

#include "models/clipper.hpp"
#include "models/hw_config.hpp"
#include "models/render_state.hpp"
#include "trace/traffic.hpp"
#include "kernel/stats.hpp"
#include "scene/scene.hpp"

namespace tbdr {

class ThreadPool;

/// The conservative screen rectangle of a light's sphere (empty when wholly behind the near
/// plane; the whole viewport when it crosses the near plane).
PixelRect light_screen_rect(const Light& light, const CameraXform& camera, const Viewport& viewport);

// Declared once: X(type, member = stored name, unit, Sum | Gauge, description).
#define TBDR_GEOMETRY_STATS(X) \
  X(Counter, draws, "draws", Sum, "Draw commands processed") \
  X(Counter, primitives_in, "primitives", Sum, "Triangles submitted by draws") \
  X(Counter, primitives_culled_frustum, "primitives", Sum, "Triangles outside the view frustum") \
  X(Counter, primitives_culled_backface, "primitives", Sum, "Triangles removed by face culling") \
  X(Counter, primitives_culled_zero_area, "primitives", Sum, "Triangles with zero area after snapping") \
  X(Counter, primitives_clipped, "primitives", Sum, "Triangles cut by the near (or far) plane") \
  X(Counter, primitives_culled_scissor, "primitives", Sum, "Screen triangles with no pixel inside the viewport and the draw's scissor rectangle (removed at setup)") \
  X(Counter, primitives_out, "primitives", Sum, "Screen triangles sent to the tiler") \
  X(Counter, vertices_shaded, "vertices", Sum, "Vertex shader invocations (post-transform cache misses)") \
  X(Counter, vertex_alu_ops, "ops", Sum, "Vertex shader ALU operations") \
  X(Counter, vertex_fetch_bytes, "bytes", Sum, "Vertex attribute bytes fetched") \
  X(Counter, index_fetch_bytes, "bytes", Sum, "Index buffer bytes fetched")
/// Statistics of the geometry unit.
struct GeometryStats {
  TBDR_STATS(TBDR_GEOMETRY_STATS)
};

/// The geometry unit of one GPU; stateless between draws but for its configuration (and the
/// instances' world bounds it keeps once a draw culls against them). A draw's cull box
/// (DrawCmd::cull) leaves out the instances whose bounds miss it, as the application never
/// submitted them: no fetch, no vertex shading, no primitives. Its scissor rectangle
/// (DrawCmd::scissor) cuts every primitive's pixel bounding box at setup.
class GeometryUnit {
 public:
  GeometryUnit(const HwConfig& hw, const Scene* scene, const std::vector<Light>& lights, const CameraXform& camera,
               const Viewport& viewport);
  /// The pass's render area (RenderContext::render_area): every draw's scissor rectangle is cut
  /// to it. Default: the whole viewport.
  void set_render_area(const PixelRect& area) { area_ = area; }
  /// ALU operations a vertex of a draw with `shader` costs: the shader's captured vertex cost
  /// (ShaderDesc::vertex_alu_ops), else the hardware parameter geometry.vertex_shader_alu_ops.
  std::uint64_t vertex_alu_ops_of(const ShaderDesc& shader) const;

  /// Processes one draw: delivers its accepted primitives to `out` as they are set up, and
  /// appends one object per drawn instance (or proxy) to `object_lights` (the lights touching the
  /// object's bounds, filled only when the shader reads an object list); counts fetch traffic
  /// into `dram`.
  void run_draw(const DrawContext& draw, std::uint32_t draw_index, PrimitiveSink& out,
                std::vector<std::vector<std::uint32_t>>& object_lights, GeometryStats& stats, DramTraffic& dram) const;

  /// Sets a scene draw's instances up (vertex shading, clipping, culling, triangle setup) on
  /// `pool`'s threads, a window of them at a time, and delivers their primitives in submission
  /// order: the same primitives and statistics at any thread count. While the caller's thread
  /// delivers a window to the sink, the next window is being set up on the pool's helpers (the
  /// pool's job until settle()). nullptr (the default): all on the caller's thread.
  void use_pool(ThreadPool* pool) { pool_ = pool; }
  /// Waits for the window being set up on the pool, if any: a sink calls it inside accept()
  /// before it uses the pool itself (a partial render); the pool is free after.
  void settle() const;

  /// Triangles of the icosphere used as a light proxy at this subdivision level (unit radius,
  /// circumscribing the unit sphere).
  static const std::vector<glm::vec3>& icosphere(std::uint32_t subdivisions);

 private:
  struct Emit;
  struct DrawOutput;
  /// The geometry counts of triangles set up but not yet counted in GeometryStats: they are
  /// counted when the next set-up triangle is delivered (or the instance ends), so a partial
  /// render that fires inside the sink sees the counts a one-at-a-time pipeline would.
  struct SetupCounts {
    std::uint32_t in = 0, culled_frustum = 0, culled_backface = 0, culled_zero_area = 0, clipped = 0,
                  culled_scissor = 0;
    void add_to(GeometryStats& stats) const;
    SetupCounts& operator+=(const SetupCounts& o);
    /// Adds the clipper's counts of one triangle (in, culled, clipped).
    void add_clipping(const ClipStats& cs);
  };
  /// A triangle set up for the tiler, not yet delivered: its record and its vertices' identities
  /// (those made by clipping get theirs at delivery, numbered by the draw's delivered count).
  struct SetUp {
    Primitive prim;
    VertexKeys keys{};
    SetupCounts before;                 ///< counts of the triangles set up since the previous one
    std::uint8_t made_by_clipping = 0;  ///< bit i: vertex i was made by clipping
  };
  /// Triangles per window of a draw's instances set up together (draw_scene): about 2.5 MB of
  /// records held at once (312 bytes each), and many windows per atrium draw for the threads.
  static constexpr std::size_t kSetupWindowTriangles = 8192;
  /// Clips, culls and sets up one triangle (its pieces after clipping) into `out`.
  void setup_triangles(const Emit& e, const glm::vec4 clip[3], const glm::vec3 world[3], const glm::vec3 normal[3],
                       const glm::vec2 uv[3], const std::uint64_t keys[3], std::vector<SetUp>& out,
                       SetupCounts& pending) const;
  /// Sets up one screen triangle the clipper made of a triangle (world, normal, uv, keys: the
  /// original's) into `out`, or counts it culled by the scissor.
  void set_up_screen_triangle(const Emit& e, const ScreenTriangle& st, const glm::vec3 world[3], const glm::vec3 normal[3],
                              const glm::vec2 uv[3], const std::uint64_t keys[3], std::vector<SetUp>& out,
                              SetupCounts& pending) const;
  /// What vertex shading and the clipper make of one scene instance under one face-cull mode:
  /// the same in every draw of the frame (the camera and viewport are fixed; a draw changes only
  /// its scissor, which applies at set-up, and the records' draw and object fields). Kept for the
  /// instances of draws with a cull box, which multi-pass renderers submit once per light
  /// (forward_multipass at 1080p, 1024 lights: 9.5 M triangles in 1025 draws of 170 k), so
  /// that a later draw only sets up the screen triangles clipping kept, with the same counts.
  struct ClippedInstance {
    /// One screen triangle, the index of its triangle's first index, and the clipping counts
    /// (triangles in, culled, clipped) of the triangles since the previous screen triangle.
    struct Piece {
      ScreenTriangle screen;
      std::uint32_t first_index = 0;
      SetupCounts before;
    };
    bool valid = false;
    FaceCull cull = FaceCull::None;
    std::uint64_t shaded = 0;              ///< vertices shaded (post-transform vertex cache misses)
    glm::vec3 lo{0.0f}, hi{0.0f};          ///< world bounds of its transformed vertices
    std::vector<glm::vec3> world, normal;  ///< per vertex, as vertex shading makes them
    std::vector<Piece> pieces;             ///< in submission order
    SetupCounts tail;                      ///< clipping counts after the last piece
  };
  /// Bytes of ClippedInstance kept at most (a few % of a large scene's run; instances past it are
  /// processed in full at every draw): 30 MB at atrium:3.
  static constexpr std::size_t kClippedInstanceBudgetBytes = std::size_t{256} << 20;
  /// Fills `c` for instance `ii` under `cull` (whether it is kept is the caller's budget call).
  void clip_instance(std::size_t ii, FaceCull cull, ClippedInstance& c) const;
  /// What set-up makes of one item of a draw (a scene instance, a light's proxy sphere) before
  /// the tiler takes it: independent of every other item, so items are set up on the pool's
  /// threads, each into its own ItemSetup, and delivered after in submission order (the same
  /// primitives, keys, objects and statistics at any thread count).
  struct ItemSetup {
    std::vector<SetUp> prims;
    /// The tiles each of prims touches, when the sink lists them ahead (binning's tile test on
    /// the set-up threads): prims[i]'s are tiles[tiles_end[i - 1] .. tiles_end[i]).
    std::vector<int> tiles;
    std::vector<std::uint32_t> tiles_end;
    std::vector<std::uint32_t> touching;  ///< its object's light list (delivered as the object's)
    GeometryStats stats;                  ///< vertex work, counted before its triangles
    SetupCounts tail;                     ///< triangles culled after its last delivered one
    std::uint64_t vertex_bytes = 0, index_bytes = 0;
  };
  /// Sets `count` items of a draw up with set_up_item(k, ItemSetup&) and delivers them in order,
  /// in windows (`window_end(first)`: the end of the window starting at item `first`): on the
  /// pool when it is free, the next window set up on its helpers while this thread delivers the
  /// one before (see settle), with the sink's tile test beside each item's set-up.
  template <class WindowEnd, class SetUpItem>
  void set_up_and_deliver(std::size_t count, WindowEnd window_end, SetUpItem set_up_item, DrawOutput& out,
                          std::vector<std::vector<std::uint32_t>>& object_lights, GeometryStats& stats, DramTraffic& dram) const;
  /// Hands a set-up triangle to the draw's sink, with the tiles it touches when the sink listed
  /// them ahead (PrimitiveSink::tiles_touched).
  void deliver(const SetUp& u, DrawOutput& out, GeometryStats& stats,
               std::optional<std::span<const int>> tiles = std::nullopt) const;
  void emit_triangle(const Emit& e, const glm::vec4 clip[3], const glm::vec3 world[3], const glm::vec3 normal[3],
                     const glm::vec2 uv[3], const std::uint64_t keys[3], DrawOutput& out, GeometryStats& stats) const;
  void draw_scene(const DrawContext& draw, std::uint32_t draw_index, DrawOutput& out,
                  std::vector<std::vector<std::uint32_t>>& object_lights, GeometryStats& stats, DramTraffic& dram) const;
  void draw_generated(const DrawContext& draw, std::uint32_t draw_index, DrawOutput& out,
                      std::vector<std::vector<std::uint32_t>>& object_lights, GeometryStats& stats, DramTraffic& dram) const;

  /// The world-space bounds of scene instance `i` (what a draw's cull box is tested against).
  const Bounds& instance_bounds(std::size_t i) const;

  const HwConfig& hw_;
  const Scene* scene_;
  /// World-space bounds of every scene instance (its transformed vertices, as draw_scene
  /// transforms them), computed at the first draw with a cull box: the scene has one box in all.
  /// Draws run one after another (binning is serial), so filling it lazily needs no lock.
  mutable std::vector<Bounds> instance_bounds_;
  /// Per scene instance, what ClippedInstance keeps (sized at the first draw with a cull box,
  /// filled by the thread that sets the instance up: one per instance per draw) and the bytes
  /// kept so far.
  mutable std::vector<ClippedInstance> clipped_;
  mutable std::atomic<std::size_t> clipped_bytes_{0};
  const std::vector<Light>& lights_;
  ThreadPool* pool_ = nullptr;  ///< use_pool
  mutable bool set_up_posted_ = false;  ///< the pool's job is a window's set-up (settle())
  CameraXform camera_;
  Viewport viewport_;
  PixelRect area_{0, 0, viewport_.width_px, viewport_.height_px};
};

/// The hidden-surface class of a draw's fragments for a material (kNoMaterial for generated geometry).
HsrClass hsr_class_of(const PipelineState& pipeline, const ShaderDesc& shader, const DrawCmd& draw, const Scene* scene,
                      std::uint32_t material);

}  // namespace tbdr
