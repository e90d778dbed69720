#pragma once
// The built-in procedural scene: a Sponza-like courtyard ("atrium") in meters, Y up, the long
// axis along X. Two storeys of arcades on stone columns surround a rectangular courtyard; behind
// them run aisles closed by plaster walls, with wooden ceiling beams; above the upper arcade an
// attic wall ends in a stone cornice under the roof. Cloth banners (alpha-tested) hang in front
// of the upper arcades, potted plants with alpha-tested leaf cards stand in the courtyard and the
// aisles, glass balustrades (blended) close the upper arcades and a glass canopy covers the
// entrance. A detail level (1..5) scales the tessellation, about 4x triangles per level.
// docs/scenes.md lists the triangle counts, materials and viewpoints.
#include <cstdint>

#include "scene/scene.hpp"

namespace tbdr {

/// Bump when the generator's output changes: it is part of the atrium's content hash.
inline constexpr int atrium_generator_version = 3;  // 3: base colour texels

/// The detail levels the generator builds (about 4x triangles per level, from ~13 k at level 1 to
/// ~2.4 M at level 5: docs/scenes.md).
inline constexpr int kAtriumMinDetail = 1;
inline constexpr int kAtriumMaxDetail = 5;

/// The atrium's main dimensions in meters (what cameras need to place themselves).
struct AtriumLayout {
  float court_half_x = 15.0f;    ///< courtyard half length along x, to the column centers
  float court_half_z = 6.0f;     ///< courtyard half width along z, to the column centers
  float aisle_depth = 4.0f;      ///< column line to the outer wall
  float outer_half_x = 19.0f;    ///< outer walls at x = +-outer_half_x
  float outer_half_z = 10.0f;    ///< outer walls at z = +-outer_half_z
  float bay_m = 3.0f;            ///< column spacing
  float storey1_height = 6.5f;   ///< upper gallery floor level
  float storey2_height = 12.5f;  ///< upper gallery ceiling
  float roof_height = 16.0f;     ///< roof and cornice level
};

/// The layout every atrium uses (independent of the detail level).
inline AtriumLayout atrium_layout() { return AtriumLayout{}; }

/// Builds the atrium at a detail level in kAtriumMinDetail..kAtriumMaxDetail (1..5); throws InputError("atrium:N") otherwise.
/// Deterministic: the same detail gives the same scene on every machine and run. Without
/// `colour_texels` the textures' texels (read only for the colour of images) are left empty.
Scene make_atrium(int detail, bool colour_texels = true);

}  // namespace tbdr
