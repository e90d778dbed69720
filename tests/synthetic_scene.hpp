#pragma once
// Small synthetic scenes and traces for tests whose expected counts are worked out by hand: camera
// at the origin looking down -z with a 60 degree field of view, square frames, quads facing the
// camera spanning chosen pixel columns.
#include <cmath>
#include <string>
#include <vector>

#include "trace/trace.hpp"
#include "scene/scene.hpp"

namespace tbdr {
namespace synthetic {

inline constexpr int kSize = 64;  // 64x64 pixels = 4 tiles of 32x32 on the default GPU
inline const float kTan30 = std::tan(glm::radians(30.0f));

/// World x at depth d that projects to pixel column px (camera at the origin looking down -z,
/// 60 degree field of view, square frame).
inline float world_x(float px, float d) { return (px / (kSize / 2.0f) - 1.0f) * d * kTan30; }

/// Adds a camera-facing quad at depth `d` spanning pixel columns [px0, px1) (the full height and
/// beyond), with uv running 0..1 across it.
inline void add_quad(Scene& s, const std::string& name, float d, float px0, float px1, std::uint32_t material) {
  SubMesh m;
  m.name = name;
  m.material = material;
  const float x0 = world_x(px0, d), x1 = world_x(px1, d), y = d * kTan30 * 1.5f;
  m.positions = {{x0, -y, -d}, {x1, -y, -d}, {x1, y, -d}, {x0, y, -d}};
  m.normals.assign(4, glm::vec3(0, 0, 1));
  m.uvs = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  m.indices = {0, 1, 2, 0, 2, 3};
  m.index_bytes = 2;
  s.submeshes.push_back(m);
  s.instances.push_back({static_cast<std::uint32_t>(s.submeshes.size() - 1), glm::mat4(1.0f), name});
}

inline Scene base_scene() {
  Scene s;
  s.name = "synthetic";
  s.source = "synthetic";
  Material opaque;
  opaque.name = "opaque";
  opaque.base_color = {0.8f, 0.5f, 0.3f, 1.0f};
  Material masked;
  masked.name = "masked";
  masked.alpha_mode = AlphaMode::PunchThrough;
  masked.alpha_cutoff = 0.5f;
  masked.alpha_mask = 0;
  Material glass;
  glass.name = "glass";
  glass.alpha_mode = AlphaMode::Translucent;
  glass.base_color = {0.2f, 0.4f, 0.9f, 0.5f};
  s.materials = {opaque, masked, glass};
  // 2x1 mask: the left half of the uv range is transparent, the right half opaque.
  s.alpha_masks.push_back(AlphaMask{2, 1, {0, 255}});
  return s;
}

inline Trace base_trace() {
  Trace t;
  t.frame = {kSize, kSize, 1, 0};
  t.camera.eye = {0, 0, 0};
  t.camera.target = {0, 0, -1};
  t.camera.up = {0, 1, 0};
  t.camera.fov_y_deg = 60;
  t.camera.near_plane = 0.5f;
  t.camera.far_plane = 50;
  ShaderDesc sh;
  sh.name = "lit";
  sh.alu_ops = 10;
  sh.tex_fetches = 1;
  sh.varyings = 8;
  sh.color_outputs = 1;
  t.shaders.push_back(sh);
  PipelineState opaque;
  opaque.name = "opaque";
  opaque.shader = "lit";
  PipelineState blend = opaque;
  blend.name = "blend";
  blend.depth_write = false;
  blend.blend = BlendMode::Alpha;
  t.pipelines = {opaque, blend};
  return t;
}

inline PassDesc base_pass() {
  PassDesc p;
  p.name = "main";
  Attachment color;
  color.name = "color";
  color.format = Format::Rgba8;
  Attachment depth;
  depth.name = "depth";
  depth.format = Format::D24s8;
  depth.usage = AttachmentUsage::Depth;
  depth.store = StoreOp::DontCare;
  depth.transient = true;
  p.attachments = {color, depth};
  return p;
}

inline DrawCmd draw_of(const std::string& submesh, const std::string& pipeline = "opaque") {
  DrawCmd d;
  d.pipeline = pipeline;
  d.submesh = submesh;
  return d;
}

/// A full-frame quad behind an 80x80 grid of small quads (12800 triangles: about 280 KB of
/// parameter buffer, so 64 KiB forces partial renders).
inline Scene partial_render_grid_scene() {
  Scene s = base_scene();
  add_quad(s, "back", 6, -32, 96, 0);
  SubMesh grid;
  grid.name = "grid";
  grid.material = 0;
  const int n = 80;
  const float d = 3, h = d * kTan30;
  for (int j = 0; j <= n; ++j) {
    for (int i = 0; i <= n; ++i) {
      grid.positions.push_back({-h + 2 * h * static_cast<float>(i) / n, -h + 2 * h * static_cast<float>(j) / n, -d});
      grid.normals.push_back({0, 0, 1});
      grid.uvs.push_back({0, 0});
    }
  }
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      const auto a = static_cast<std::uint32_t>(j * (n + 1) + i), b = a + 1, c = a + n + 1, e = c + 1;
      grid.indices.insert(grid.indices.end(), {a, b, e, a, e, c});
    }
  }
  s.submeshes.push_back(grid);
  s.instances.push_back({static_cast<std::uint32_t>(s.submeshes.size() - 1), glm::mat4(1.0f), "grid"});
  return s;
}

}  // namespace synthetic
}  // namespace tbdr
