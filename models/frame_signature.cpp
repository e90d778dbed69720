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

const std::array<FrameSignature::Feature, FrameSignature::kFeatures>& FrameSignature::features() {
  static const std::array<Feature, kFeatures> f{{
      {"triangles_in_view", "triangles", "Signature: scene triangles the frame's view does not reject (frustum, facing), sampled"},
      {"opaque_area_px", "pixels", "Signature: screen area of its opaque triangles before hidden-surface removal, sampled"},
      {"masked_area_px", "pixels", "Signature: screen area of its punch-through triangles before hidden-surface removal, sampled"},
      {"blended_area_px", "pixels", "Signature: screen area of its translucent triangles, sampled"},
      {"lights_in_view", "lights", "Signature: lights whose screen rectangle is not empty"},
      {"light_area_px", "pixels", "Signature: sum of the lights' screen rectangles"},
  }};
  return f;
}

std::array<double, FrameSignature::kFeatures> FrameSignature::values() const {
  return {triangles_in_view, opaque_area_px, masked_area_px, blended_area_px, lights_in_view, light_area_px};
}

FrameSignature frame_signature(const Trace& frame, const Scene& scene) {
  FrameSignature s;
  const int width = frame.frame.width, height = frame.frame.height;
  if (width <= 0 || height <= 0) return s;
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
    double* area = material.alpha_mode == AlphaMode::Opaque         ? &s.opaque_area_px
                   : material.alpha_mode == AlphaMode::PunchThrough ? &s.masked_area_px
                                                                    : &s.blended_area_px;
    const std::size_t triangles = mesh.indices.size() / 3;
    for (std::size_t t = 0; t < triangles; t += kSignatureTriangleStride) {
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
      s.triangles_in_view += stride;
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
    s.lights_in_view += 1;
    s.light_area_px += static_cast<double>(r.x1 - r.x0) * static_cast<double>(r.y1 - r.y0);
  }
  return s;
}

}  // namespace tbdr
