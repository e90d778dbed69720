#pragma once
// A frame's signature: a few figures of what it draws, computed from its camera, its lights and
// the scene's geometry without rasterising, shading or timing anything. Sampled simulation of a
// sequence (analysis/frame_sampling.hpp) groups frames by their signatures and simulates one frame
// per group, as MEGsim does with its frames' functional characteristics (Anglada et al.,
// "MEGsim: A Novel Methodology for Efficient Simulation of Graphics Workloads in GPUs", ISPASS
// 2022). The signature is a proxy and says so: its areas are of triangles before hidden-surface
// removal, taken from every kSignatureTriangleStride-th triangle and scaled up.
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "scene/lights.hpp"
#include "scene/scene.hpp"
#include "trace/trace.hpp"

namespace tbdr {

/// Every how-many-th triangle of each instance the signature projects (its first, then every
/// stride-th): 1/8 of the atrium's triangles cost about 1 ms a frame at any resolution, and each
/// area is a sum over thousands of triangles, so the sampling moves it by well under 1 %.
inline constexpr std::uint32_t kSignatureTriangleStride = 8;

/// What one frame draws, as the signature sees it (all figures scaled to the whole scene).
struct FrameSignature {
  double triangles_in_view = 0;   ///< triangles not rejected by the view frustum or face culling
  double opaque_area_px = 0;      ///< screen area of the opaque materials' visible-facing triangles, pixels (depth complexity x pixels)
  double masked_area_px = 0;      ///< the same for punch-through (alpha-masked) materials
  double blended_area_px = 0;     ///< the same for translucent (blended) materials
  double lights_in_view = 0;      ///< lights whose screen rectangle is not empty
  double light_area_px = 0;       ///< sum of the lights' screen rectangles, pixels (the pixels each light may touch)

  /// Number of figures; each one's row name, unit and meaning (in the database: sampling/frame<k>),
  /// and the values in that order.
  static constexpr std::size_t kFeatures = 6;
  struct Feature {
    const char* name;
    const char* unit;
    const char* description;
  };
  static const std::array<Feature, kFeatures>& features();
  std::array<double, kFeatures> values() const;
};

/// The signature of one frame of a trace (its camera, lights and size) over `scene`: every
/// instance's sampled triangles transformed by the camera (or taken as captured clip positions),
/// clipped against the near plane, projected, cut to the viewport and measured.
FrameSignature frame_signature(const Trace& frame, const Scene& scene);

}  // namespace tbdr
