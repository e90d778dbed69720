#pragma once
// The geometry unit: vertex fetch (index and attribute bytes), vertex shading behind a
// post-transform vertex cache, clipping against the near plane, frustum / back-face / zero-area
// culling and the viewport transform to fixed point. It turns one draw into primitives.
#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "models/hw_config.hpp"
#include "models/render_state.hpp"
#include "models/traffic.hpp"
#include "kernel/stats.hpp"
#include "scene/scene.hpp"

namespace tbdr {

/// The conservative screen rectangle of a light's sphere (empty when wholly behind the near
/// plane; the whole viewport when it crosses the near plane).
PixelRect light_screen_rect(const Light& light, const CameraXform& camera, const Viewport& viewport);

/// Statistics of the geometry unit.
struct GeometryStats {
  StatGroup group;
  Counter draws{group, {"draws", "draws", "Draw commands processed"}};
  Counter primitives_in{group, {"primitives_in", "primitives", "Triangles submitted by draws"}};
  Counter culled_frustum{group, {"primitives_culled_frustum", "primitives", "Triangles outside the view frustum"}};
  Counter culled_backface{group, {"primitives_culled_backface", "primitives", "Triangles removed by face culling"}};
  Counter culled_zero_area{group, {"primitives_culled_zero_area", "primitives", "Triangles with zero area after snapping"}};
  Counter clipped{group, {"primitives_clipped", "primitives", "Triangles cut by the near (or far) plane"}};
  Counter primitives_out{group, {"primitives_out", "primitives", "Screen triangles sent to the tiler"}};
  Counter vertices_shaded{group, {"vertices_shaded", "vertices", "Vertex shader invocations (post-transform cache misses)"}};
  Counter vertex_alu_ops{group, {"vertex_alu_ops", "ops", "Vertex shader ALU operations"}};
  Counter vertex_fetch_bytes{group, {"vertex_fetch_bytes", "bytes", "Vertex attribute bytes fetched"}};
  Counter index_fetch_bytes{group, {"index_fetch_bytes", "bytes", "Index buffer bytes fetched"}};
  explicit GeometryStats(std::string scope) : group(std::move(scope)) {}
};

/// The geometry unit of one GPU; stateless between draws but for its configuration.
class GeometryUnit {
 public:
  GeometryUnit(const HwConfig& hw, const Scene* scene, const std::vector<Light>& lights, const CameraXform& camera,
               const Viewport& viewport);

  /// Processes one draw: appends its accepted primitives to `out` and one object per drawn
  /// instance (or proxy) to `object_lights` (the lights touching the object's bounds, filled only
  /// when the shader reads an object list); counts fetch traffic into `dram`.
  void run_draw(const DrawContext& draw, std::uint32_t draw_index, std::vector<Primitive>& out,
                std::vector<std::vector<std::uint32_t>>& object_lights, GeometryStats& stats, DramTraffic& dram) const;

  /// Triangles of the icosphere used as a light proxy at this subdivision level (unit radius,
  /// circumscribing the unit sphere).
  static const std::vector<glm::vec3>& icosphere(std::uint32_t subdivisions);

 private:
  struct Emit;
  void emit_triangle(const Emit& e, const glm::vec4 clip[3], const glm::vec3 world[3], const glm::vec3 normal[3],
                     const glm::vec2 uv[3], const std::uint64_t keys[3], std::vector<Primitive>& out,
                     GeometryStats& stats) const;
  void draw_scene(const DrawContext& draw, std::uint32_t draw_index, std::vector<Primitive>& out,
                  std::vector<std::vector<std::uint32_t>>& object_lights, GeometryStats& stats, DramTraffic& dram) const;
  void draw_generated(const DrawContext& draw, std::uint32_t draw_index, std::vector<Primitive>& out,
                      std::vector<std::vector<std::uint32_t>>& object_lights, GeometryStats& stats, DramTraffic& dram) const;

  const HwConfig& hw_;
  const Scene* scene_;
  const std::vector<Light>& lights_;
  CameraXform camera_;
  Viewport viewport_;
};

/// The hidden-surface class of a draw's fragments for a material (kNoMaterial for generated geometry).
HsrClass hsr_class_of(const PipelineState& pipeline, const ShaderDesc& shader, const DrawCmd& draw, const Scene* scene,
                      std::uint32_t material);

}  // namespace tbdr
