#include "models/geometry_unit.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <limits>
#include <mutex>

#include <glm/gtc/matrix_transform.hpp>

#include "models/clipper.hpp"
#include "kernel/thread_pool.hpp"

namespace tbdr {

const char* to_string(HsrClass c) {
  switch (c) {
    case HsrClass::Opaque: return "opaque";
    case HsrClass::PunchThrough: return "punch_through";
    case HsrClass::Translucent: return "translucent";
  }
  return "?";
}

void PixelCounters::resize(std::size_t pixels, bool images) {
  shaded.assign(pixels, 0);
  const std::size_t n = images ? pixels : 0;
  rasterised_samples.assign(n, 0);
  lights_evaluated.assign(n, 0);
  triangle_id.assign(n, 0);
}

CameraXform CameraXform::from(const Camera& camera, float aspect) {
  CameraXform x;
  x.view = camera.view();
  x.proj = camera.projection(aspect);
  x.view_proj = x.proj * x.view;
  x.eye = camera.eye;
  x.near_plane = camera.near_plane;
  return x;
}

PixelRect light_screen_rect(const Light& light, const CameraXform& camera, const Viewport& viewport) {
  const PixelRect full{0, 0, viewport.width_px, viewport.height_px};
  const glm::vec3 c = glm::vec3(camera.view * glm::vec4(light.position, 1.0f));
  const float r = light.radius;
  // View space looks down -z; visible points have z < -near.
  if (c.z - r >= -camera.near_plane) return {};  // wholly behind the near plane
  if (c.z + r > -camera.near_plane) return full;  // crosses it: conservative
  float x0 = 1e30f, y0 = 1e30f, x1 = -1e30f, y1 = -1e30f;
  for (int i = 0; i < 8; ++i) {
    const glm::vec4 p(c.x + ((i & 1) ? r : -r), c.y + ((i & 2) ? r : -r), c.z + ((i & 4) ? r : -r), 1.0f);
    const glm::vec4 clip = camera.proj * p;
    const float nx = clip.x / clip.w, ny = clip.y / clip.w;
    // Pixel coordinates, y down (as the rasteriser's viewport transform).
    const float px = (nx * 0.5f + 0.5f) * static_cast<float>(viewport.width_px);
    const float py = (0.5f - ny * 0.5f) * static_cast<float>(viewport.height_px);
    x0 = std::min(x0, px);
    x1 = std::max(x1, px);
    y0 = std::min(y0, py);
    y1 = std::max(y1, py);
  }
  const auto clampi = [](float v, int lo, int hi) {
    if (!(v > static_cast<float>(lo))) return lo;
    if (v > static_cast<float>(hi)) return hi;
    return static_cast<int>(v);
  };
  // One pixel of margin on each side keeps the rectangle conservative under rounding.
  PixelRect rect{clampi(std::floor(x0) - 1.0f, 0, viewport.width_px), clampi(std::floor(y0) - 1.0f, 0, viewport.height_px),
                 clampi(std::ceil(x1) + 1.0f, 0, viewport.width_px), clampi(std::ceil(y1) + 1.0f, 0, viewport.height_px)};
  return rect.empty() ? PixelRect{} : rect;
}

HsrClass hsr_class_of(const PipelineState& pipeline, const ShaderDesc& shader, const DrawCmd& draw, const Scene* scene,
                      std::uint32_t material) {
  // Fragments that depend on what lies beneath (blending, reading pixel local storage, framebuffer
  // fetch, pushing onto a PLS light stack) need it shaded first and never hide it.
  if (pipeline.blend != BlendMode::Off) return HsrClass::Translucent;
  if (shader.pls == PlsAccess::Read || shader.pls == PlsAccess::ReadWrite) return HsrClass::Translucent;
  if (shader.pls == PlsAccess::Write && material == kNoMaterial) return HsrClass::Translucent;
  if (!draw.fetch.empty()) return HsrClass::Translucent;
  switch (pipeline.alpha) {
    case AlphaOverride::Opaque: return HsrClass::Opaque;
    case AlphaOverride::PunchThrough: return HsrClass::PunchThrough;
    case AlphaOverride::Translucent: return HsrClass::Translucent;
    case AlphaOverride::Material: break;
  }
  if (shader.discard) return HsrClass::PunchThrough;
  if (scene && material != kNoMaterial) {
    switch (scene->materials[material].alpha_mode) {
      case AlphaMode::Opaque: return HsrClass::Opaque;
      case AlphaMode::PunchThrough: return HsrClass::PunchThrough;
      case AlphaMode::Translucent: return HsrClass::Translucent;
    }
  }
  return HsrClass::Opaque;
}

/// What every primitive of one object shares.
struct GeometryUnit::Emit {
  std::uint32_t draw = 0;
  std::uint32_t object = 0;
  std::uint32_t material = kNoMaterial;
  std::int32_t proxy_light = -1;
  HsrClass hsr = HsrClass::Opaque;
  std::uint32_t varyings = 0;
  ClipConfig clip;
  PixelRect scissor;  ///< the draw's scissor rectangle (the viewport when it has none)
};

/// One draw's delivery: the sink and how many primitives the draw has delivered (a vertex made by
/// clipping gets an identity from it, unique within the draw, as primitive blocks never span draws).
struct GeometryUnit::DrawOutput {
  PrimitiveSink& sink;
  std::uint64_t delivered = 0;
};

GeometryUnit::GeometryUnit(const HwConfig& hw, const Scene* scene, const std::vector<Light>& lights,
                           const CameraXform& camera, const Viewport& viewport)
    : hw_(hw), scene_(scene), lights_(lights), camera_(camera), viewport_(viewport) {}

namespace {

}  // namespace

std::uint64_t GeometryUnit::vertex_alu_ops_of(const ShaderDesc& shader) const {
  return shader.vertex_alu_ops ? *shader.vertex_alu_ops : static_cast<std::uint64_t>(hw_.geometry.vertex_shader_alu_ops);
}

namespace {

FaceCull face_cull_of(CullMode m) {
  switch (m) {
    case CullMode::None: return FaceCull::None;
    case CullMode::Back: return FaceCull::Back;
    case CullMode::Front: return FaceCull::Front;
  }
  return FaceCull::None;
}

/// Counts vertex shader invocations of an index stream through a FIFO post-transform cache.
class VertexCacheFifo {
 public:
  explicit VertexCacheFifo(std::size_t entries) : slots_(entries, kEmpty) {}
  /// True on a miss (the vertex is shaded and inserted).
  bool access(std::uint32_t index) {
    if (slots_.empty()) return true;
    for (auto s : slots_) {
      if (s == index) return false;
    }
    slots_[next_] = index;
    next_ = (next_ + 1) % slots_.size();
    return true;
  }

 private:
  static constexpr std::uint32_t kEmpty = 0xffffffffu;
  std::vector<std::uint32_t> slots_;
  std::size_t next_ = 0;
};

bool sphere_touches_box(const Light& l, const glm::vec3& lo, const glm::vec3& hi) {
  const glm::vec3 q = glm::clamp(l.position, lo, hi);
  const glm::vec3 d = q - l.position;
  return glm::dot(d, d) <= l.radius * l.radius;
}

std::vector<glm::vec3> make_icosphere(std::uint32_t level) {
  const float t = (1.0f + std::sqrt(5.0f)) / 2.0f;
  std::vector<glm::vec3> v = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                              {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  for (auto& p : v) p = glm::normalize(p);
  std::vector<glm::uvec3> f = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
                               {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
                               {3, 8, 9},  {4, 9, 5},  {2, 4, 11}, {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
  for (std::uint32_t l = 0; l < level; ++l) {
    std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> mid;
    auto midpoint = [&](std::uint32_t a, std::uint32_t b) {
      const auto key = std::minmax(a, b);
      auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      v.push_back(glm::normalize(v[a] + v[b]));
      const auto idx = static_cast<std::uint32_t>(v.size() - 1);
      mid[key] = idx;
      return idx;
    };
    std::vector<glm::uvec3> nf;
    for (const auto& tri : f) {
      const std::uint32_t a = midpoint(tri.x, tri.y), b = midpoint(tri.y, tri.z), c = midpoint(tri.z, tri.x);
      nf.push_back({tri.x, a, c});
      nf.push_back({tri.y, b, a});
      nf.push_back({tri.z, c, b});
      nf.push_back({a, b, c});
    }
    f = std::move(nf);
  }
  // Scale so every face plane is at distance >= 1: the polyhedron encloses the unit sphere.
  float min_dist = 1.0f;
  for (const auto& tri : f) {
    const glm::vec3 n = glm::normalize(glm::cross(v[tri.y] - v[tri.x], v[tri.z] - v[tri.x]));
    min_dist = std::min(min_dist, std::abs(glm::dot(n, v[tri.x])));
  }
  std::vector<glm::vec3> out;
  out.reserve(f.size() * 3);
  for (const auto& tri : f) {
    // Outward-facing, counter-clockwise seen from outside (front faces).
    out.push_back(v[tri.x] / min_dist);
    out.push_back(v[tri.y] / min_dist);
    out.push_back(v[tri.z] / min_dist);
  }
  return out;
}

}  // namespace

const std::vector<glm::vec3>& GeometryUnit::icosphere(std::uint32_t subdivisions) {
  static std::mutex m;
  static std::map<std::uint32_t, std::vector<glm::vec3>> cache;
  std::lock_guard<std::mutex> lock(m);
  auto it = cache.find(subdivisions);
  if (it == cache.end()) it = cache.emplace(subdivisions, make_icosphere(subdivisions)).first;
  return it->second;
}

void GeometryUnit::setup_triangles(const Emit& e, const glm::vec4 clip[3], const glm::vec3 world[3],
                                   const glm::vec3 normal[3], const glm::vec2 uv[3], const std::uint64_t keys[3],
                                   std::vector<SetUp>& out, SetupCounts& pending) const {
  ClipStats cs;
  thread_local std::vector<ScreenTriangle> screen;
  screen.clear();
  const ClipTriangle ct{clip[0], clip[1], clip[2]};
  clip_and_cull(ct, e.clip, cs, screen);
  pending.add_clipping(cs);
  for (const ScreenTriangle& st : screen) set_up_screen_triangle(e, st, world, normal, uv, keys, out, pending);
}

void GeometryUnit::set_up_screen_triangle(const Emit& e, const ScreenTriangle& st, const glm::vec3 world[3],
                                          const glm::vec3 normal[3], const glm::vec2 uv[3], const std::uint64_t keys[3],
                                          std::vector<SetUp>& out, SetupCounts& pending) const {
  SetUp& u = out.emplace_back();
  Primitive& p = u.prim;
  p.setup = setup_triangle(st, viewport_, e.scissor);
  if (p.setup.empty) {  // covers no pixel of the viewport inside the scissor
    ++pending.culled_scissor;
    out.pop_back();
    return;
  }
  u.before = pending;
  pending = SetupCounts{};
  p.draw = e.draw;
  p.object = e.object;
  p.material = e.material;
  p.proxy_light = e.proxy_light;
  p.hsr = e.hsr;
  p.varyings = e.varyings;
  u.made_by_clipping = 0;
  for (int i = 0; i < 3; ++i) {
    p.world[i] = world[i];
    p.normal[i] = normal[i];
    p.uv[i] = uv[i];
    // A vertex made by clipping is new (its identity is given at delivery); an original vertex
    // keeps its identity for block re-use.
    const glm::vec3 b = st.bary[i];
    int orig = -1;
    for (int k = 0; k < 3; ++k) {
      if (b[k] == 1.0f) orig = k;
    }
    if (orig >= 0) {
      u.keys[i] = keys[orig];
    } else {
      u.made_by_clipping |= static_cast<std::uint8_t>(1u << i);
    }
  }
}

void GeometryUnit::SetupCounts::add_clipping(const ClipStats& cs) {
  in += static_cast<std::uint32_t>(cs.in);
  culled_frustum += static_cast<std::uint32_t>(cs.culled_frustum);
  culled_backface += static_cast<std::uint32_t>(cs.culled_backface);
  culled_zero_area += static_cast<std::uint32_t>(cs.culled_zero_area);
  clipped += static_cast<std::uint32_t>(cs.clipped);
}

GeometryUnit::SetupCounts& GeometryUnit::SetupCounts::operator+=(const SetupCounts& o) {
  in += o.in;
  culled_frustum += o.culled_frustum;
  culled_backface += o.culled_backface;
  culled_zero_area += o.culled_zero_area;
  clipped += o.clipped;
  culled_scissor += o.culled_scissor;
  return *this;
}

void GeometryUnit::clip_instance(std::size_t ii, FaceCull cull, ClippedInstance& c) const {
  const Instance& inst = scene_->instances[ii];
  const SubMesh& sm = scene_->submeshes[inst.submesh];
  c.valid = true;
  c.cull = cull;
  // Transform every vertex of the instance once (what the vertex shader computes).
  thread_local std::vector<glm::vec4> clip;
  const glm::mat4 mvp = camera_.view_proj * inst.world;
  const glm::mat3 nrm = glm::transpose(glm::inverse(glm::mat3(inst.world)));
  const std::size_t nv = sm.positions.size();
  clip.resize(nv);
  c.world.resize(nv);
  c.normal.resize(nv);
  glm::vec3 lo(1e30f), hi(-1e30f);
  // A captured sub-mesh carries the clip positions its application's vertex shader wrote
  // (SubMesh::clip_positions): they are taken as they are, with no instance or camera transform.
  const bool captured_clip = sm.clip_positions.size() == nv;
  for (std::size_t v = 0; v < nv; ++v) {
    const glm::vec4 p(sm.positions[v], 1.0f);
    clip[v] = captured_clip ? sm.clip_positions[v] : mvp * p;
    c.world[v] = glm::vec3(inst.world * p);
    c.normal[v] = glm::normalize(nrm * sm.normals[v]);
    lo = glm::min(lo, c.world[v]);
    hi = glm::max(hi, c.world[v]);
  }
  c.lo = lo;
  c.hi = hi;

  // Vertex fetch and shading: indices through the post-transform cache.
  VertexCacheFifo cache(static_cast<std::size_t>(hw_.geometry.vertex_cache_entries));
  c.shaded = 0;
  for (std::uint32_t idx : sm.indices) {
    if (sm.index_bytes == 0 || cache.access(idx)) ++c.shaded;
  }

  // Clipping and culling: the screen triangles kept, each with the counts since the one before.
  ClipConfig config;
  config.viewport = viewport_;
  config.cull = cull;
  c.pieces.clear();
  c.tail = SetupCounts{};
  thread_local std::vector<ScreenTriangle> screen;
  for (std::size_t t = 0; t + 2 < sm.indices.size(); t += 3) {
    const ClipTriangle ct{clip[sm.indices[t]], clip[sm.indices[t + 1]], clip[sm.indices[t + 2]]};
    ClipStats cs;
    screen.clear();
    clip_and_cull(ct, config, cs, screen);
    c.tail.add_clipping(cs);
    for (const ScreenTriangle& st : screen) {
      c.pieces.push_back({st, static_cast<std::uint32_t>(t), c.tail});
      c.tail = SetupCounts{};
    }
  }
}

void GeometryUnit::SetupCounts::add_to(GeometryStats& stats) const {
  stats.primitives_in += in;
  stats.primitives_culled_frustum += culled_frustum;
  stats.primitives_culled_backface += culled_backface;
  stats.primitives_culled_zero_area += culled_zero_area;
  stats.primitives_clipped += clipped;
  stats.primitives_culled_scissor += culled_scissor;
}

void GeometryUnit::deliver(const SetUp& u, DrawOutput& out, GeometryStats& stats,
                           std::optional<std::span<const int>> tiles) const {
  u.before.add_to(stats);
  VertexKeys vertex_keys = u.keys;
  for (int i = 0; i < 3; ++i) {
    if ((u.made_by_clipping >> i) & 1u) vertex_keys[i] = 0x8000000000000000ull | (out.delivered * 3 + static_cast<std::uint64_t>(i));
  }
  out.sink.accept(u.prim, vertex_keys, tiles);
  ++out.delivered;
  ++stats.primitives_out;
}

void GeometryUnit::emit_triangle(const Emit& e, const glm::vec4 clip[3], const glm::vec3 world[3],
                                 const glm::vec3 normal[3], const glm::vec2 uv[3], const std::uint64_t keys[3],
                                 DrawOutput& out, GeometryStats& stats) const {
  thread_local std::vector<SetUp> set_up;
  set_up.clear();
  SetupCounts pending;
  setup_triangles(e, clip, world, normal, uv, keys, set_up, pending);
  for (const SetUp& u : set_up) deliver(u, out, stats);
  pending.add_to(stats);
}

namespace {

/// The draw's scissor rectangle in pixels, or the whole viewport (setup clamps it to the viewport).
PixelRect scissor_of(const DrawCmd& cmd, const Viewport& viewport) {
  if (!cmd.scissor) return {0, 0, viewport.width_px, viewport.height_px};
  const ScissorRect& s = *cmd.scissor;  // the reader bounds each coordinate by kMaxFrameSide
  return {static_cast<int>(s.x0), static_cast<int>(s.y0), static_cast<int>(s.x1), static_cast<int>(s.y1)};
}

/// Whether two closed world-space boxes share a point.
bool boxes_intersect(const Bounds& a, const CullBox& b) {
  return a.min.x <= b.max.x && a.max.x >= b.min.x && a.min.y <= b.max.y && a.max.y >= b.min.y &&
         a.min.z <= b.max.z && a.max.z >= b.min.z;
}

}  // namespace

const Bounds& GeometryUnit::instance_bounds(std::size_t i) const {
  if (instance_bounds_.size() != scene_->instances.size()) {
    instance_bounds_.assign(scene_->instances.size(), Bounds{});
    for (std::size_t ii = 0; ii < scene_->instances.size(); ++ii) {
      const Instance& inst = scene_->instances[ii];
      const SubMesh& sm = scene_->submeshes[inst.submesh];
      // The same float expression as draw_scene's world positions, so a vertex it computes lies
      // inside these bounds exactly.
      glm::vec3 lo(std::numeric_limits<float>::max()), hi(-std::numeric_limits<float>::max());
      for (const glm::vec3& p : sm.positions) {
        const glm::vec3 w = glm::vec3(inst.world * glm::vec4(p, 1.0f));
        lo = glm::min(lo, w);
        hi = glm::max(hi, w);
      }
      instance_bounds_[ii] = Bounds{lo, hi};  // an instance without vertices keeps lo > hi: never drawn
    }
  }
  return instance_bounds_[i];
}

void GeometryUnit::run_draw(const DrawContext& draw, std::uint32_t draw_index, PrimitiveSink& sink,
                            std::vector<std::vector<std::uint32_t>>& object_lights, GeometryStats& stats,
                            DramTraffic& dram) const {
  ++stats.draws;
  DrawOutput out{sink};
  if (draw.cmd->geometry == GeometryKind::Scene) {
    draw_scene(draw, draw_index, out, object_lights, stats, dram);
  } else {
    draw_generated(draw, draw_index, out, object_lights, stats, dram);
  }
}

void GeometryUnit::draw_scene(const DrawContext& draw, std::uint32_t draw_index, DrawOutput& out,
                              std::vector<std::vector<std::uint32_t>>& object_lights, GeometryStats& stats,
                              DramTraffic& dram) const {
  const DrawCmd& cmd = *draw.cmd;
  const bool wants_object_lists = draw.shader->light_source == LightSource::ObjectList;
  const std::uint64_t vertex_ops = vertex_alu_ops_of(*draw.shader);
  // The instances this draw submits; translucent ones back to front, as an application sorts them.
  std::vector<std::pair<float, std::size_t>> selected;
  for (std::size_t ii = 0; ii < scene_->instances.size(); ++ii) {
    const Instance& inst = scene_->instances[ii];
    const SubMesh& sm = scene_->submeshes[inst.submesh];
    const Material& mat = scene_->materials[sm.material];
    if (!cmd.submesh.empty() && sm.name != cmd.submesh) continue;
    if (!cmd.material.empty() && mat.name != cmd.material) continue;
    if (cmd.submesh.empty() && cmd.material.empty()) {
      const bool keep = cmd.subset == SceneSubset::All ||
                        (cmd.subset == SceneSubset::Opaque && mat.alpha_mode == AlphaMode::Opaque) ||
                        (cmd.subset == SceneSubset::Masked && mat.alpha_mode == AlphaMode::PunchThrough) ||
                        (cmd.subset == SceneSubset::Blended && mat.alpha_mode == AlphaMode::Translucent);
      if (!keep) continue;
    }
    // The application's object culling: an instance whose bounds miss the box is not submitted.
    if (cmd.cull && !boxes_intersect(instance_bounds(ii), *cmd.cull)) continue;
    float key = -std::numeric_limits<float>::max();  // opaque and punch-through first, in scene order
    if (hsr_class_of(*draw.pipeline, *draw.shader, *draw.cmd, scene_, sm.material) == HsrClass::Translucent && !sm.positions.empty()) {
      glm::vec3 lo(sm.positions[0]), hi(sm.positions[0]);
      for (const auto& p : sm.positions) {
        lo = glm::min(lo, p);
        hi = glm::max(hi, p);
      }
      const glm::vec3 c = glm::vec3(camera_.view * inst.world * glm::vec4((lo + hi) * 0.5f, 1.0f));
      key = c.z;  // more negative = farther: drawn first
    }
    selected.push_back({key, ii});
  }
  std::stable_sort(selected.begin(), selected.end(), [](const auto& a, const auto& b) { return a.first < b.first; });

  if (cmd.cull && clipped_.size() != scene_->instances.size()) clipped_.resize(scene_->instances.size());
  const std::uint32_t object_base = static_cast<std::uint32_t>(object_lights.size());
  auto set_up_instance = [&](std::size_t k, ItemSetup& o) {
    const std::size_t ii = selected[k].second;
    const Instance& inst = scene_->instances[ii];
    const SubMesh& sm = scene_->submeshes[inst.submesh];
    const Material& mat = scene_->materials[sm.material];
    Emit e;
    e.draw = draw_index;
    e.object = object_base + static_cast<std::uint32_t>(k);
    e.material = sm.material;
    e.hsr = hsr_class_of(*draw.pipeline, *draw.shader, *draw.cmd, scene_, sm.material);
    e.varyings = draw.shader->varyings;
    e.clip.viewport = viewport_;
    e.clip.cull = mat.double_sided ? FaceCull::None : face_cull_of(draw.pipeline->cull);
    e.scissor = intersect(scissor_of(cmd, viewport_), area_);

    // What vertex shading and clipping make of it: kept from an earlier draw with a cull box,
    // else made now (and kept, for a draw with a cull box, within the budget).
    thread_local ClippedInstance scratch;
    const ClippedInstance* ci = nullptr;
    if (cmd.cull && clipped_[ii].valid && clipped_[ii].cull == e.clip.cull) {
      ci = &clipped_[ii];
    } else {
      clip_instance(ii, e.clip.cull, scratch);
      ci = &scratch;
      if (cmd.cull && !clipped_[ii].valid) {
        const std::size_t bytes = scratch.pieces.size() * sizeof(ClippedInstance::Piece) +
                                  (scratch.world.size() + scratch.normal.size()) * sizeof(glm::vec3);
        if (clipped_bytes_.fetch_add(bytes) + bytes <= kClippedInstanceBudgetBytes) {
          clipped_[ii] = std::move(scratch);
          scratch = ClippedInstance{};
          ci = &clipped_[ii];
        } else {
          clipped_bytes_.fetch_sub(bytes);
        }
      }
    }
    if (wants_object_lists) {
      for (std::uint32_t l : draw.lights) {
        if (sphere_touches_box(lights_[l], ci->lo, ci->hi)) o.touching.push_back(l);
      }
    }
    o.index_bytes = std::uint64_t{sm.index_bytes} * sm.indices.size();
    o.vertex_bytes = ci->shaded * sm.vertex_stride_bytes;
    o.stats.vertices_shaded += ci->shaded;
    o.stats.vertex_alu_ops += ci->shaded * vertex_ops;
    o.stats.vertex_fetch_bytes += o.vertex_bytes;
    o.stats.index_fetch_bytes += o.index_bytes;

    // Set-up of the screen triangles (the draw's scissor), with the clipping counts of the
    // triangles before each, in order.
    const std::uint64_t key_base = std::uint64_t{e.object} << 32;
    o.prims.reserve(ci->pieces.size());
    for (const ClippedInstance::Piece& piece : ci->pieces) {
      o.tail += piece.before;
      const std::uint32_t i0 = sm.indices[piece.first_index], i1 = sm.indices[piece.first_index + 1],
                          i2 = sm.indices[piece.first_index + 2];
      const glm::vec3 w[3] = {ci->world[i0], ci->world[i1], ci->world[i2]};
      const glm::vec3 n[3] = {ci->normal[i0], ci->normal[i1], ci->normal[i2]};
      const glm::vec2 uv[3] = {sm.uvs[i0], sm.uvs[i1], sm.uvs[i2]};
      const std::uint64_t keys[3] = {key_base | i0, key_base | i1, key_base | i2};
      set_up_screen_triangle(e, piece.screen, w, n, uv, keys, o.prims, o.tail);
    }
    o.tail += ci->tail;
  };

  // Windows of instances holding about kSetupWindowTriangles triangles each (at least one
  // instance): enough work to share between threads, few enough records to hold at once.
  auto window_end = [&](std::size_t first) {
    std::size_t last = first, triangles = 0;
    while (last < selected.size() && (last == first || triangles < kSetupWindowTriangles)) {
      triangles += scene_->submeshes[scene_->instances[selected[last].second].submesh].indices.size() / 3;
      ++last;
    }
    return last;
  };
  set_up_and_deliver(selected.size(), window_end, set_up_instance, out, object_lights, stats, dram);
}

template <class WindowEnd, class SetUpItem>
void GeometryUnit::set_up_and_deliver(std::size_t count, WindowEnd window_end, SetUpItem set_up_item, DrawOutput& out,
                                      std::vector<std::vector<std::uint32_t>>& object_lights, GeometryStats& stats,
                                      DramTraffic& dram) const {
  // An item set up, then the tiler's tile test of its triangles, here on the set-up threads
  // rather than in the serial binning.
  auto set_up = [&](std::size_t k, ItemSetup& o) {
    set_up_item(k, o);
    for (const SetUp& u : o.prims) {
      if (!out.sink.tiles_touched(u.prim, o.tiles)) break;
      o.tiles_end.push_back(static_cast<std::uint32_t>(o.tiles.size()));
    }
  };
  // The pool's helpers, when it has some and they are free (not while the pool runs the pass
  // before's tiles: binning beside them sets up alone).
  auto pool_free = [&] { return pool_ != nullptr && pool_->size() > 1 && !pool_->started(); };
  std::vector<ItemSetup> window, next;
  auto set_up_window = [&](std::size_t from, std::vector<ItemSetup>& w) {
    if (pool_free() && w.size() > 1) {
      pool_->for_each(w.size(), [&](std::size_t k, unsigned) { set_up(from + k, w[k]); });
    } else {
      for (std::size_t k = 0; k < w.size(); ++k) set_up(from + k, w[k]);
    }
  };
  // A posted window is waited for before anything it refers to goes (an exception unwinding).
  struct PostedGuard {
    const GeometryUnit& unit;
    ~PostedGuard() {
      try {
        unit.settle();
      } catch (...) {
      }
    }
  } posted_guard{*this};

  std::size_t first = 0, last = window_end(0);
  window.resize(last - first);
  set_up_window(first, window);
  while (first < count) {
    // The next window is set up on the helpers while this thread delivers this one (the tiler's
    // binning is serial: the two overlap), and this thread sets up what is left of it after.
    const std::size_t next_first = last, next_last = next_first < count ? window_end(next_first) : next_first;
    next.clear();
    next.resize(next_last - next_first);
    const bool posted = !next.empty() && pool_free();
    if (posted) {
      pool_->start(next.size(), [&next, &set_up, next_first](std::size_t k, unsigned) { set_up(next_first + k, next[k]); });
      set_up_posted_ = true;
    }
    for (ItemSetup& o : window) {
      object_lights.push_back(std::move(o.touching));
      stats += o.stats;
      dram.read(DramClass::Vertices, o.vertex_bytes);
      dram.read(DramClass::Indices, o.index_bytes);
      const bool listed = o.tiles_end.size() == o.prims.size();
      for (std::size_t i = 0; i < o.prims.size(); ++i) {
        if (!listed) {
          deliver(o.prims[i], out, stats);
          continue;
        }
        const std::uint32_t from = i == 0 ? 0 : o.tiles_end[i - 1];
        deliver(o.prims[i], out, stats, std::span<const int>(o.tiles).subspan(from, o.tiles_end[i] - from));
      }
      o.tail.add_to(stats);
    }
    if (posted) {
      settle();  // (already waited for when a partial render inside delivery settled it)
    } else {
      set_up_window(next_first, next);
    }
    std::swap(window, next);
    first = next_first;
    last = next_last;
  }
}

void GeometryUnit::settle() const {
  if (!set_up_posted_) return;
  set_up_posted_ = false;
  pool_->join();
}

void GeometryUnit::draw_generated(const DrawContext& draw, std::uint32_t draw_index, DrawOutput& out,
                                  std::vector<std::vector<std::uint32_t>>& object_lights, GeometryStats& stats,
                                  DramTraffic& dram) const {
  const DrawCmd& cmd = *draw.cmd;
  Emit e;
  e.draw = draw_index;
  e.hsr = hsr_class_of(*draw.pipeline, *draw.shader, *draw.cmd, nullptr, kNoMaterial);
  e.varyings = draw.shader->varyings;
  e.clip.viewport = viewport_;
  e.clip.cull = face_cull_of(draw.pipeline->cull);
  e.scissor = intersect(scissor_of(cmd, viewport_), area_);
  constexpr std::uint64_t kPositionBytes = 16;  // generated vertices: one vec4 position each
  const glm::vec3 zero3[3] = {};
  const glm::vec2 zero2[3] = {};

  // The vertex work of `vertices` generated vertices, counted into `into`; their fetch bytes.
  auto vertex_work = [&](std::uint64_t vertices, GeometryStats& into) {
    into.vertices_shaded += vertices;
    into.vertex_alu_ops += vertices * vertex_alu_ops_of(*draw.shader);
    into.vertex_fetch_bytes += vertices * kPositionBytes;
    return vertices * kPositionBytes;
  };
  auto account = [&](std::uint64_t vertices) { dram.read(DramClass::Vertices, vertex_work(vertices, stats)); };

  if (cmd.geometry == GeometryKind::Fullscreen) {
    // One triangle covering the viewport, at depth 0.5 (z_ndc = 0); shaders read what lies beneath.
    e.object = static_cast<std::uint32_t>(object_lights.size());
    object_lights.push_back(draw.lights);
    e.clip.cull = FaceCull::None;
    const glm::vec4 c[3] = {{-1, -1, 0, 1}, {3, -1, 0, 1}, {-1, 3, 0, 1}};
    const std::uint64_t base = std::uint64_t{e.object} << 32;
    const std::uint64_t keys[3] = {base, base | 1, base | 2};
    account(3);
    emit_triangle(e, c, zero3, zero3, zero2, keys, out, stats);
    return;
  }

  if (cmd.geometry == GeometryKind::LightSpheres) {
    // One icosphere per selected light, each set up on its own (as a scene instance is) into an
    // ItemSetup: windows of them on the pool, delivered in light order.
    const auto& ico = icosphere(cmd.subdivisions);
    const std::uint32_t object_base = static_cast<std::uint32_t>(object_lights.size());
    auto set_up_light = [&](std::size_t k, ItemSetup& o) {
      const std::uint32_t l = draw.lights[k];
      const Light& light = lights_[l];
      Emit le = e;
      le.object = object_base + static_cast<std::uint32_t>(k);
      le.proxy_light = static_cast<std::int32_t>(l);
      o.touching = {l};
      o.vertex_bytes = vertex_work(ico.size(), o.stats);
      const std::uint64_t base = std::uint64_t{le.object} << 32;
      for (std::size_t t = 0; t + 2 < ico.size(); t += 3) {
        glm::vec4 c[3];
        glm::vec3 w[3];
        for (int v = 0; v < 3; ++v) {
          w[v] = light.position + ico[t + v] * light.radius;
          c[v] = camera_.view_proj * glm::vec4(w[v], 1.0f);
        }
        const std::uint64_t keys[3] = {base | t, base | (t + 1), base | (t + 2)};
        setup_triangles(le, c, w, zero3, zero2, keys, o.prims, o.tail);
      }
    };
    // Windows of about kSetupWindowTriangles triangles (80 a sphere at subdivision 1: 102 lights).
    const std::size_t per_window = std::max<std::size_t>(1, kSetupWindowTriangles / std::max<std::size_t>(1, ico.size() / 3));
    auto window_end = [&](std::size_t first) { return std::min(draw.lights.size(), first + per_window); };
    set_up_and_deliver(draw.lights.size(), window_end, set_up_light, out, object_lights, stats, dram);
    return;
  }
  // LightQuads: per light a screen-aligned quad bounding the sphere's projection, at its nearest depth.
  for (std::uint32_t l : draw.lights) {
    const Light& light = lights_[l];
    e.object = static_cast<std::uint32_t>(object_lights.size());
    object_lights.push_back({l});
    e.proxy_light = static_cast<std::int32_t>(l);
    const std::uint64_t base = std::uint64_t{e.object} << 32;
    const PixelRect r = light_screen_rect(light, camera_, viewport_);
    if (r.empty()) continue;
    const glm::vec3 cv = glm::vec3(camera_.view * glm::vec4(light.position, 1.0f));
    const float z_near_view = std::min(cv.z + light.radius, -camera_.near_plane * 1.0001f);
    const glm::vec4 zc = camera_.proj * glm::vec4(0.0f, 0.0f, z_near_view, 1.0f);
    const float w = zc.w;
    auto ndc_x = [&](int px) { return (2.0f * static_cast<float>(px) / static_cast<float>(viewport_.width_px) - 1.0f) * w; };
    auto ndc_y = [&](int py) { return (1.0f - 2.0f * static_cast<float>(py) / static_cast<float>(viewport_.height_px)) * w; };
    const glm::vec4 q[4] = {{ndc_x(r.x0), ndc_y(r.y1), zc.z, w}, {ndc_x(r.x1), ndc_y(r.y1), zc.z, w},
                            {ndc_x(r.x1), ndc_y(r.y0), zc.z, w}, {ndc_x(r.x0), ndc_y(r.y0), zc.z, w}};
    account(4);
    e.clip.cull = FaceCull::None;
    const glm::vec4 a[3] = {q[0], q[1], q[2]};
    const glm::vec4 b[3] = {q[0], q[2], q[3]};
    const std::uint64_t ka[3] = {base, base | 1, base | 2};
    const std::uint64_t kb[3] = {base, base | 2, base | 3};
    emit_triangle(e, a, zero3, zero3, zero2, ka, out, stats);
    emit_triangle(e, b, zero3, zero3, zero2, kb, out, stats);
  }
}

}  // namespace tbdr
