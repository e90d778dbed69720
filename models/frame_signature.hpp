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

#include "kernel/stats.hpp"
#include "scene/lights.hpp"
#include "scene/scene.hpp"
#include "trace/trace.hpp"

namespace tbdr {

/// Every how-many-th triangle of each instance the signature projects (its first, then every
/// stride-th): 1/16 of atrium:3's 170 k triangles cost about 1 ms a frame at any resolution (300
/// frames: 0.33 to 0.38 CPU s measured by hand, against about 0.4 s to simulate one 1080p frame),
/// and each area is still a sum over thousands of triangles.
inline constexpr std::uint32_t kSignatureTriangleStride = 16;

// What one frame draws, as the signature sees it (all figures scaled to the whole scene; rows of
// scope sampling/frame<k>).
#define TBDR_FRAME_SIGNATURE_STATS(X)                                                                      \
  X(Accumulator, triangles_in_view, "triangles", Gauge,                                                     \
    "Signature: scene triangles its view does not reject (frustum, facing), from every kSignatureTriangleStride-th") \
  X(Accumulator, opaque_area_px, "pixels", Gauge,                                                          \
    "Signature: screen area of its opaque triangles before hidden-surface removal (depth complexity x pixels), sampled") \
  X(Accumulator, masked_area_px, "pixels", Gauge, "Signature: the same for punch-through (alpha-masked) materials") \
  X(Accumulator, blended_area_px, "pixels", Gauge, "Signature: the same for translucent (blended) materials")     \
  X(Accumulator, lights_in_view, "lights", Gauge, "Signature: lights whose screen rectangle is not empty")          \
  X(Accumulator, light_area_px, "pixels", Gauge, "Signature: sum of the lights' screen rectangles (the pixels each may touch)")

/// A frame's signature.
struct FrameSignature {
  TBDR_STATS(TBDR_FRAME_SIGNATURE_STATS)
  /// The figures in declaration order (the features sampling compares).
  std::vector<double> values() const;
};

/// The signature of one frame of a trace (its camera, lights and size) over `scene`: every
/// instance's sampled triangles transformed by the camera (or taken as captured clip positions),
/// clipped against the near plane, projected, cut to the viewport and measured.
FrameSignature frame_signature(const Trace& frame, const Scene& scene);

}  // namespace tbdr
