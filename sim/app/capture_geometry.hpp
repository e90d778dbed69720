#pragma once
// Captured primitives the simulator's geometry unit does not take as they are, turned into the
// triangles that cover the same pixels: line segments as rectangles of the line's width (the
// Vulkan "strict lines" rule, Vulkan 1.3 section 28.5.1, the shape the hardware rasterises a wide
// line as), points as squares of their size (section 28.4), and instanced draws as every
// instance's triangles. Pure arithmetic on clip-space positions in the simulator's convention
// (OpenGL's: y up, -w <= z <= w), for `tbdrsim import` (sim/app/capture_convert.cpp).
#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

namespace tbdr {

/// Triangles made from lines or points: their clip positions, their texture coordinates (each
/// corner takes its vertex's), and a triangle list over them.
struct ExpandedPrimitives {
  std::vector<glm::vec4> clip;
  std::vector<glm::vec2> uvs;            ///< empty when the input had none
  std::vector<std::uint32_t> triangles;  ///< three indices a triangle
  std::uint64_t dropped = 0;             ///< segments or points behind the near plane or of zero length
};

/// The frame the expanded primitives are drawn in: pixels across and down (the clip-to-pixel
/// scale that turns a width in pixels into clip space).
struct FramePixels {
  float width = 1.0f;
  float height = 1.0f;
};

/// Each segment (two indices into `clip`) as a rectangle `width_px` wide centred on it: two
/// triangles. A segment is first clipped to the near plane (z >= -w), where an endpoint behind
/// the eye has no pixel position; one wholly behind it, or of zero length on screen, is dropped
/// (counted). `uvs` may be empty.
ExpandedPrimitives lines_as_rectangles(const std::vector<glm::vec4>& clip, const std::vector<glm::vec2>& uvs,
                                       const std::vector<std::uint32_t>& segments, float width_px, FramePixels frame);

/// Each point (an index into `clip`) as a square of `sizes_px[i]` pixels (or 1 when `sizes_px` is
/// empty) centred on it: two triangles. A point in front of the near plane or behind the eye is
/// dropped (counted), as the hardware culls a point whose vertex is outside the clip volume in z.
ExpandedPrimitives points_as_squares(const std::vector<glm::vec4>& clip, const std::vector<glm::vec2>& uvs,
                                     const std::vector<float>& sizes_px, const std::vector<std::uint32_t>& points,
                                     FramePixels frame);

/// The index list of `instances` instances of a draw whose vertices hold `per_instance` vertices
/// an instance, instance after instance: `indices` (within one instance) repeated, offset by
/// i x per_instance for instance i.
std::vector<std::uint32_t> instanced_indices(const std::vector<std::uint32_t>& indices, std::uint32_t per_instance,
                                             std::uint32_t instances);

}  // namespace tbdr
