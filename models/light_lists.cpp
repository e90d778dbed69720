#include "models/light_lists.hpp"

#include "models/geometry_unit.hpp"
#include "kernel/thread_pool.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <numeric>

namespace tbdr {

ViewFrustum ViewFrustum::from(const Camera& camera, int width_px, int height_px) {
  ViewFrustum f;
  f.view = camera.view();
  f.tan_half_y = std::tan(glm::radians(camera.fov_y_deg) * 0.5f);
  f.tan_half_x = f.tan_half_y * static_cast<float>(width_px) / static_cast<float>(height_px);
  f.near_plane = camera.near_plane;
  f.far_plane = camera.far_plane;
  f.width_px = width_px;
  f.height_px = height_px;
  return f;
}

float ViewFrustum::distance_of_window_depth(float depth01) const {
  const double n = near_plane, fa = far_plane;
  const double z_ndc = 2.0 * static_cast<double>(depth01) - 1.0;
  return static_cast<float>((2.0 * n * fa) / ((fa + n) - z_ndc * (fa - n)));
}

float ViewFrustum::distance_of(const glm::vec3& world) const { return -(view * glm::vec4(world, 1.0f)).z; }

ViewSphere ViewSphere::of(const ViewFrustum& f, const Light& light) {
  return {glm::vec3(f.view * glm::vec4(light.position, 1.0f)), light.radius};
}

TileSides TileSides::of(const ViewFrustum& f, const PixelRect& rect) {
  // NDC extents of the rectangle (y up in NDC, rows grow downwards).
  const float ax = (2.0f * static_cast<float>(rect.x0) / static_cast<float>(f.width_px) - 1.0f) * f.tan_half_x;
  const float bx = (2.0f * static_cast<float>(rect.x1) / static_cast<float>(f.width_px) - 1.0f) * f.tan_half_x;
  const float ay = (1.0f - 2.0f * static_cast<float>(rect.y1) / static_cast<float>(f.height_px)) * f.tan_half_y;
  const float by = (1.0f - 2.0f * static_cast<float>(rect.y0) / static_cast<float>(f.height_px)) * f.tan_half_y;
  // Inside: x >= ax*(-z), x <= bx*(-z), y >= ay*(-z), y <= by*(-z).
  TileSides t;
  t.normals = {glm::normalize(glm::vec3(1.0f, 0.0f, ax)), glm::normalize(glm::vec3(-1.0f, 0.0f, -bx)),
               glm::normalize(glm::vec3(0.0f, 1.0f, ay)), glm::normalize(glm::vec3(0.0f, -1.0f, -by))};
  return t;
}

bool sphere_touches_tile_volume(const ViewFrustum& f, const Light& light, const PixelRect& rect, float d0, float d1) {
  return TileSides::of(f, rect).touches(ViewSphere::of(f, light), d0, d1);
}

DepthBounds DepthBounds::compute(const ViewFrustum& f, const AttachmentImage& depth, int tile_px, ThreadPool* pool) {
  DepthBounds b;
  b.tile_px = tile_px;
  b.tiles_x = (f.width_px + tile_px - 1) / tile_px;
  b.tiles_y = (f.height_px + tile_px - 1) / tile_px;
  const std::size_t n = static_cast<std::size_t>(b.tiles_x) * static_cast<std::size_t>(b.tiles_y);
  b.min_distance.assign(n, 1e30f);
  b.max_distance.assign(n, -1e30f);
  const std::size_t S = depth.samples;
  // One item per row of tiles: it alone writes its tiles' bounds.
  auto tile_row = [&](std::size_t ty, unsigned /*worker*/) {
    const int y_end = std::min(f.height_px, (static_cast<int>(ty) + 1) * tile_px);
    for (int y = static_cast<int>(ty) * tile_px; y < y_end; ++y) {
      for (int x = 0; x < f.width_px; ++x) {
        const std::size_t t = static_cast<std::size_t>((y / tile_px) * b.tiles_x + x / tile_px);
        const std::size_t p = (static_cast<std::size_t>(y) * static_cast<std::size_t>(f.width_px) + static_cast<std::size_t>(x)) * S;
        for (std::size_t s = 0; s < S; ++s) {
          const float d = depth.depth[p + s];
          if (!(d < 1.0f)) continue;
          const float dist = f.distance_of_window_depth(d);
          b.min_distance[t] = std::min(b.min_distance[t], dist);
          b.max_distance[t] = std::max(b.max_distance[t], dist);
        }
      }
    }
  };
  const auto rows = static_cast<std::size_t>(b.tiles_y);
  if (pool != nullptr) {
    pool->for_each(rows, tile_row);
  } else {
    for (std::size_t ty = 0; ty < rows; ++ty) tile_row(ty, 0);
  }
  return b;
}

namespace {

/// Light indices in all the lists of a grid.
std::uint64_t entries_of(const std::vector<std::vector<std::uint32_t>>& lists) {
  return std::transform_reduce(lists.begin(), lists.end(), std::uint64_t{0}, std::plus<>(),
                               [](const auto& l) { return static_cast<std::uint64_t>(l.size()); });
}

}  // namespace

std::uint64_t TileLightGrid::total_entries() const { return entries_of(lists); }

std::uint64_t ClusterGrid::used_count() const { return std::accumulate(used.begin(), used.end(), std::uint64_t{0}); }

std::uint64_t ClusterGrid::total_entries() const { return entries_of(lists); }

void ClusterGrid::configure(const ViewFrustum& f, int tile_px_, int slices_, Slicing s, float min_depth_) {
  tile_px = tile_px_;
  tiles_x = (f.width_px + tile_px - 1) / tile_px;
  tiles_y = (f.height_px + tile_px - 1) / tile_px;
  slicing = s;
  near_plane = f.near_plane;
  far_plane = f.far_plane;
  min_depth = std::max(min_depth_, f.near_plane);
  if (s == Slicing::Cubical) {
    slice_ratio = 1.0f + 2.0f * f.tan_half_y * static_cast<float>(tile_px) / static_cast<float>(f.height_px);
    // As many slices as reach the far plane, at most slices_.
    const int needed = 1 + static_cast<int>(std::ceil(std::log(far_plane / min_depth) / std::log(slice_ratio)));
    slices = std::max(1, std::min(slices_, needed));
  } else {
    slices = slices_;
  }
  log_depth_range = std::log(far_plane / near_plane);
  log_slice_ratio = std::log(slice_ratio);
  const std::size_t n = static_cast<std::size_t>(tiles_x) * static_cast<std::size_t>(tiles_y) * static_cast<std::size_t>(slices);
  used.assign(n, 0);
  lists.assign(n, {});
}

int ClusterGrid::slice_of(float d) const {
  int k = 0;
  if (slicing == Slicing::Log) {
    if (d <= near_plane) return 0;
    k = static_cast<int>(std::floor(std::log(d / near_plane) / log_depth_range * slices));
  } else {
    if (d <= min_depth) return 0;
    k = 1 + static_cast<int>(std::floor(std::log(d / min_depth) / log_slice_ratio));
  }
  return std::clamp(k, 0, slices - 1);
}

void ClusterGrid::slice_range(int k, float& d0, float& d1) const {
  if (slicing == Slicing::Log) {
    d0 = near_plane * std::pow(far_plane / near_plane, static_cast<float>(k) / slices);
    d1 = near_plane * std::pow(far_plane / near_plane, static_cast<float>(k + 1) / slices);
  } else {
    d0 = k == 0 ? 0.0f : min_depth * std::pow(slice_ratio, static_cast<float>(k - 1));
    d1 = min_depth * std::pow(slice_ratio, static_cast<float>(k));
  }
  if (k == 0) d0 = 0.0f;
  if (k == slices - 1) d1 = 1e30f;  // the last slice takes everything beyond
  // Guard against float rounding at slice boundaries: widen slightly (conservative).
  d0 *= 0.999f;
  d1 *= 1.001f;
}

LightScreenBins LightScreenBins::build(const std::vector<Light>& lights, const CameraXform& camera, const Viewport& viewport) {
  LightScreenBins b;
  b.bins_x = (viewport.width_px + kBinPx - 1) / kBinPx;
  const int bins_y = (viewport.height_px + kBinPx - 1) / kBinPx;
  b.bins.assign(static_cast<std::size_t>(b.bins_x) * static_cast<std::size_t>(bins_y), {});
  for (std::uint32_t l = 0; l < lights.size(); ++l) {
    const PixelRect r = light_screen_rect(lights[l], camera, viewport);
    if (r.empty()) continue;
    for (int ty = r.y0 / kBinPx; ty <= (r.y1 - 1) / kBinPx; ++ty) {
      for (int tx = r.x0 / kBinPx; tx <= (r.x1 - 1) / kBinPx; ++tx) {
        b.bins[static_cast<std::size_t>(ty * b.bins_x + tx)].push_back(l);
      }
    }
  }
  return b;
}

}  // namespace tbdr
