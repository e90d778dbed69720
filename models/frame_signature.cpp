#include "models/frame_signature.hpp"

#include <algorithm>
#include <cmath>

#include <glm/glm.hpp>

#include "models/clipper.hpp"
#include "models/geometry_unit.hpp"
#include "models/render_state.hpp"

namespace tbdr {

namespace {

/// A convex polygon in normalised device coordinates (x, y), at most the clipper's vertices plus
/// one per viewport edge.
struct NdcPolygon {
  std::array<glm::dvec2, kMaxClipPolygonVertices + 4> v{};
  int count = 0;
};

/// Cuts `in` to the half plane where coordinate `axis` (0: x, 1: y) times `sign` is at most 1
/// (Sutherland-Hodgman, one edge of the viewport square [-1, 1]^2).
NdcPolygon cut(const NdcPolygon& in, int axis, double sign) {
  NdcPolygon out;
  for (int i = 0; i < in.count; ++i) {
    const glm::dvec2 a = in.v[static_cast<std::size_t>(i)];
    const glm::dvec2 b = in.v[static_cast<std::size_t>((i + 1) % in.count)];
    const double da = 1.0 - sign * a[axis], db = 1.0 - sign * b[axis];  // >= 0: inside
    if (da >= 0) out.v[static_cast<std::size_t>(out.count++)] = a;
    if ((da >= 0) != (db >= 0)) out.v[static_cast<std::size_t>(out.count++)] = a + (b - a) * (da / (da - db));
  }
  return out;
}

/// Signed area of a polygon (shoelace), NDC units; positive counter-clockwise (GL front with y up).
double signed_area(const NdcPolygon& p) {
  double twice = 0;
  for (int i = 0; i < p.count; ++i) {
    const glm::dvec2 a = p.v[static_cast<std::size_t>(i)];
    const glm::dvec2 b = p.v[static_cast<std::size_t>((i + 1) % p.count)];
    twice += a.x * b.y - b.x * a.y;
  }
  return 0.5 * twice;
}

}  // namespace

std::vector<double> FrameSignature::values() const {
  std::vector<double> v;
  zip(*this, *this, [&v](const auto& x, const auto&, const StatDef&) { v.push_back(x.as_double()); });
  return v;
}

FrameSignature frame_signature(const Trace& frame, const Scene& scene) {
  FrameSignature out;
  const int width = frame.frame.width, height = frame.frame.height;
  if (width <= 0 || height <= 0) return out;
  double in_view = 0, opaque = 0, masked = 0, blended = 0, lights = 0, light_area = 0;
  const CameraXform camera = CameraXform::from(frame.camera, static_cast<float>(width) / static_cast<float>(height));
  const Viewport viewport{.width_px = width, .height_px = height};
  // One NDC unit of area is a quarter of the viewport's pixels.
  const double px_per_ndc_area = 0.25 * static_cast<double>(width) * static_cast<double>(height);
  const ClipConfig clip_config{.viewport = viewport, .cull = FaceCull::None};
  const double stride = kSignatureTriangleStride;
  for (const Instance& inst : scene.instances) {
    const SubMesh& mesh = scene.submeshes[inst.submesh];
    const Material& material = scene.materials[mesh.material];
    const bool captured = !mesh.clip_positions.empty();
    const glm::mat4 to_clip = camera.view_proj * inst.world;
    double* area = material.alpha_mode == AlphaMode::Opaque         ? &opaque
                   : material.alpha_mode == AlphaMode::PunchThrough ? &masked
                                                                    : &blended;
    const std::size_t mesh_triangles = mesh.indices.size() / 3;
    for (std::size_t t = 0; t < mesh_triangles; t += kSignatureTriangleStride) {
      ClipTriangle clip;
      for (std::size_t k = 0; k < 3; ++k) {
        const std::uint32_t index = mesh.indices[3 * t + k];
        clip[k] = captured ? mesh.clip_positions[index] : to_clip * glm::vec4(mesh.positions[index], 1.0f);
      }
      if (frustum_reject(clip)) continue;
      const ClipPolygon poly = clip_triangle(clip, clip_config);
      if (poly.count < 3) continue;
      NdcPolygon ndc;
      for (int i = 0; i < poly.count; ++i) {
        const glm::dvec4& p = poly.v[static_cast<std::size_t>(i)].position;
        ndc.v[static_cast<std::size_t>(ndc.count++)] = glm::dvec2(p.x / p.w, p.y / p.w);
      }
      // Facing from the whole (uncut) projected polygon: GL front is counter-clockwise.
      const double facing = signed_area(ndc);
      if (facing == 0 || (!material.double_sided && facing < 0)) continue;
      in_view += stride;
      NdcPolygon cut_poly = ndc;
      for (int axis = 0; axis < 2 && cut_poly.count >= 3; ++axis) {
        cut_poly = cut(cut(cut_poly, axis, 1.0), axis, -1.0);
      }
      if (cut_poly.count >= 3) *area += std::abs(signed_area(cut_poly)) * px_per_ndc_area * stride;
    }
  }
  for (const Light& light : frame.lights) {
    const PixelRect r = light_screen_rect(light, camera, viewport);
    if (r.empty()) continue;
    lights += 1;
    light_area += static_cast<double>(r.x1 - r.x0) * static_cast<double>(r.y1 - r.y0);
  }
  out.triangles_in_view.set(in_view);
  out.opaque_area_px.set(opaque);
  out.masked_area_px.set(masked);
  out.blended_area_px.set(blended);
  out.lights_in_view.set(lights);
  out.light_area_px.set(light_area);
  return out;
}

}  // namespace tbdr
