#pragma once
// Light lists built by the culling and assignment kernels: per screen tile (tiled shading,
// Forward+) and per cluster (clustered shading, Olsson; cascaded near-cubical clusters, Billeter).
// A light is kept when its bounding sphere can reach the tile's or cluster's view-space volume, so
// lists are conservative and shading from them gives the image of shading every light.
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "models/render_state.hpp"

namespace tbdr {

/// The view frustum geometry the culling tests need (a symmetric perspective projection).
struct ViewFrustum {
  glm::mat4 view{1.0f};
  float tan_half_x = 1.0f;  ///< tan of half the horizontal field of view
  float tan_half_y = 1.0f;  ///< tan of half the vertical field of view
  float near_plane = 0.1f;
  float far_plane = 100.0f;
  int width_px = 1;
  int height_px = 1;
  static ViewFrustum from(const Camera& camera, int width_px, int height_px);
  /// View-space distance (positive, along -z) of a window depth in [0,1] (GL depth range).
  float distance_of_window_depth(float depth01) const;
  /// View-space distance of a world position.
  float distance_of(const glm::vec3& world) const;
};

class ThreadPool;

/// A light's bounding sphere in view space: transformed once per light, tested against many
/// tiles or clusters.
struct ViewSphere {
  glm::vec3 center{0.0f};
  float radius = 0.0f;
  static ViewSphere of(const ViewFrustum& f, const Light& light);
};

/// The four side planes (through the eye, unit inward normals) of a pixel rectangle's view-space
/// volume: set up once per tile, shared by every light and depth range tested against it.
struct TileSides {
  std::array<glm::vec3, 4> normals{};
  static TileSides of(const ViewFrustum& f, const PixelRect& rect);
  /// True when `s` can intersect the volume between view distances [d0, d1].
  bool touches(const ViewSphere& s, float d0, float d1) const {
    const float dist = -s.center.z;
    if (dist + s.radius < d0 || dist - s.radius > d1) return false;
    for (const glm::vec3& n : normals) {
      if (glm::dot(n, s.center) < -s.radius) return false;
    }
    return true;
  }
};

/// True when the light's sphere can intersect the view-space volume of pixel rectangle `rect`
/// between distances [d0, d1] (planes through the eye for the sides, d0/d1 for the ends).
bool sphere_touches_tile_volume(const ViewFrustum& f, const Light& light, const PixelRect& rect, float d0, float d1);

/// Per-tile view-space depth bounds of the covered samples (empty tile: min > max).
struct DepthBounds {
  int tile_px = 16;
  int tiles_x = 0;
  int tiles_y = 0;
  std::vector<float> min_distance;
  std::vector<float> max_distance;
  /// Computes the bounds of a depth image (window depth < 1 counts as covered); with a pool, rows
  /// of tiles on its threads (each tile's bounds are its own: the same at any thread count).
  static DepthBounds compute(const ViewFrustum& f, const AttachmentImage& depth, int tile_px, ThreadPool* pool = nullptr);
};

/// Per screen tile light lists (the grid plus the index list a tile culling kernel writes).
struct TileLightGrid {
  int tile_px = 16;
  int tiles_x = 0;
  int tiles_y = 0;
  std::uint32_t max_lights_per_tile = 0;  ///< cap of the index list format; 0 = none
  std::vector<std::vector<std::uint32_t>> lists;  ///< per tile, light indices ascending
  std::uint64_t overflowed_tiles = 0;     ///< tiles whose list exceeds the cap (kept whole, counted)
  const std::vector<std::uint32_t>& at_pixel(int x, int y) const {
    return lists[static_cast<std::size_t>((y / tile_px) * tiles_x + x / tile_px)];
  }
  std::uint64_t total_entries() const;
};

/// How cluster depth slices are placed.
enum class Slicing : std::uint8_t {
  Log,      ///< exponential between near and far (Olsson et al. 2012)
  Cubical,  ///< near-cubical clusters: each slice as deep as a tile is wide there (Billeter 2015)
};

/// A cluster grid: screen tiles x depth slices, each with a light list.
struct ClusterGrid {
  int tile_px = 64;
  int tiles_x = 0;
  int tiles_y = 0;
  int slices = 16;
  Slicing slicing = Slicing::Log;
  float near_plane = 0.1f;
  float far_plane = 100.0f;
  float min_depth = 0.1f;     ///< start of the first slice (cubical)
  float slice_ratio = 1.0f;   ///< cubical: z_{k+1} / z_k
  float log_depth_range = 1.0f;  ///< log(far / near), set by configure (slice_of divides by it)
  float log_slice_ratio = 1.0f;  ///< log(slice_ratio), set by configure
  std::vector<std::uint8_t> used;  ///< per cluster: 1 when flagged (or dense)
  std::vector<std::vector<std::uint32_t>> lists;
  std::uint64_t used_count() const;
  std::uint64_t total_entries() const;
  /// The slice of a view-space distance (clamped to the grid).
  int slice_of(float distance) const;
  /// [start, end) distance of slice k.
  void slice_range(int k, float& d0, float& d1) const;
  std::size_t index(int tx, int ty, int slice) const {
    return (static_cast<std::size_t>(slice) * tiles_y + static_cast<std::size_t>(ty)) * tiles_x + static_cast<std::size_t>(tx);
  }
  std::size_t cluster_of(int x, int y, float distance) const { return index(x / tile_px, y / tile_px, slice_of(distance)); }
  /// Sets up the slicing for a frustum (cubical: ratio from the tile size and the field of view).
  void configure(const ViewFrustum& f, int tile_px_, int slices_, Slicing s, float min_depth_);
};

}  // namespace tbdr
