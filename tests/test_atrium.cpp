// The built-in atrium: triangle counts per detail level (docs/scenes.md), determinism, materials,
// consistent winding, and the named viewpoints.
#include <gtest/gtest.h>

#include <algorithm>
#include <set>
#include <sstream>

#include <glm/gtc/matrix_transform.hpp>

#include "kernel/errors.hpp"
#include "scene/atrium.hpp"
#include "scene/camera.hpp"
#include "scene/scene_library.hpp"

namespace tbdr {
namespace {

const Material* find_material(const Scene& s, const std::string& name) {
  for (const Material& m : s.materials)
    if (m.name == name) return &m;
  return nullptr;
}

TEST(Atrium, TriangleCountsPerDetailLevel) {
  // The ranges documented in docs/scenes.md (measured: 13172, 49692, 169980, 629452, 2425140).
  const std::uint64_t lo[5] = {8'000, 35'000, 130'000, 500'000, 1'500'000};
  const std::uint64_t hi[5] = {16'000, 65'000, 220'000, 850'000, 3'500'000};
  std::uint64_t prev = 0;
  for (int d = 1; d <= 5; ++d) {
    const Scene s = make_atrium(d);
    const std::uint64_t n = s.triangle_count();
    EXPECT_GE(n, lo[d - 1]) << "detail " << d;
    EXPECT_LE(n, hi[d - 1]) << "detail " << d;
    if (prev) {
      EXPECT_GT(static_cast<double>(n) / static_cast<double>(prev), 3.0) << "detail " << d;
    }
    prev = n;
    EXPECT_EQ(s.name, "atrium");
    EXPECT_EQ(s.source, "atrium:" + std::to_string(d));
  }
}

TEST(Atrium, Deterministic) {
  const Scene a = make_atrium(2);
  const Scene b = make_atrium(2);
  EXPECT_EQ(a.content_hash, b.content_hash);
  ASSERT_EQ(a.submeshes.size(), b.submeshes.size());
  for (std::size_t i = 0; i < a.submeshes.size(); ++i) {
    EXPECT_EQ(a.submeshes[i].name, b.submeshes[i].name);
    EXPECT_EQ(a.submeshes[i].material, b.submeshes[i].material);
    EXPECT_EQ(a.submeshes[i].positions, b.submeshes[i].positions) << a.submeshes[i].name;
    EXPECT_EQ(a.submeshes[i].normals, b.submeshes[i].normals);
    EXPECT_EQ(a.submeshes[i].uvs, b.submeshes[i].uvs);
    EXPECT_EQ(a.submeshes[i].indices, b.submeshes[i].indices);
  }
  ASSERT_EQ(a.instances.size(), b.instances.size());
  for (std::size_t i = 0; i < a.instances.size(); ++i) {
    EXPECT_EQ(a.instances[i].submesh, b.instances[i].submesh);
    EXPECT_EQ(a.instances[i].world, b.instances[i].world);
  }
  ASSERT_EQ(a.alpha_masks.size(), b.alpha_masks.size());
  for (std::size_t i = 0; i < a.alpha_masks.size(); ++i) EXPECT_EQ(a.alpha_masks[i].alpha, b.alpha_masks[i].alpha);
  EXPECT_NE(make_atrium(1).content_hash, a.content_hash);
}

TEST(Atrium, MaterialsCoverEveryAlphaMode) {
  const Scene s = make_atrium(1);
  for (const char* name : {"stone", "floor", "plaster", "wood", "cloth_red", "foliage", "glass"}) {
    EXPECT_NE(find_material(s, name), nullptr) << name;
  }
  EXPECT_EQ(find_material(s, "stone")->alpha_mode, AlphaMode::Opaque);
  const Material* cloth = find_material(s, "cloth_red");
  const Material* leaf = find_material(s, "foliage");
  const Material* glass = find_material(s, "glass");
  EXPECT_EQ(cloth->alpha_mode, AlphaMode::PunchThrough);
  EXPECT_EQ(leaf->alpha_mode, AlphaMode::PunchThrough);
  EXPECT_EQ(glass->alpha_mode, AlphaMode::Translucent);
  EXPECT_LT(glass->base_color.w, 1.0f);
  ASSERT_GE(cloth->alpha_mask, 0);
  ASSERT_GE(leaf->alpha_mask, 0);
  EXPECT_NE(cloth->alpha_mask, leaf->alpha_mask);
  // Masks really cut: both fully transparent and fully opaque texels.
  for (const AlphaMask& m : s.alpha_masks) {
    EXPECT_EQ(m.alpha.size(), static_cast<std::size_t>(m.width) * static_cast<std::size_t>(m.height));
    EXPECT_NE(std::find(m.alpha.begin(), m.alpha.end(), 0), m.alpha.end());
    EXPECT_NE(std::find(m.alpha.begin(), m.alpha.end(), 255), m.alpha.end());
  }
  // The leaf is solid along its midrib and empty at the card's corners.
  const AlphaMask& lm = s.alpha_masks[static_cast<std::size_t>(leaf->alpha_mask)];
  EXPECT_FLOAT_EQ(lm.sample({0.5f, 0.5f}), 1.0f);
  EXPECT_FLOAT_EQ(lm.sample({0.02f, 0.98f}), 0.0f);
  // Distinct base colors.
  std::set<std::tuple<float, float, float>> colors;
  for (const Material& m : s.materials) colors.insert({m.base_color.x, m.base_color.y, m.base_color.z});
  EXPECT_EQ(colors.size(), s.materials.size());
  // Every alpha mode draws triangles.
  std::uint64_t per_mode[3] = {0, 0, 0};
  for (const Instance& inst : s.instances) {
    const SubMesh& sm = s.submeshes[inst.submesh];
    per_mode[static_cast<int>(s.materials[sm.material].alpha_mode)] += sm.triangle_count();
  }
  EXPECT_GT(per_mode[0], 0u);
  EXPECT_GT(per_mode[1], 1000u);
  EXPECT_GT(per_mode[2], 0u);
}

TEST(Atrium, WellFormedGeometryWithConsistentWinding) {
  const Scene s = make_atrium(2);
  for (const SubMesh& sm : s.submeshes) {
    ASSERT_EQ(sm.normals.size(), sm.positions.size()) << sm.name;
    ASSERT_EQ(sm.uvs.size(), sm.positions.size()) << sm.name;
    ASSERT_EQ(sm.indices.size() % 3, 0u) << sm.name;
    ASSERT_GT(sm.indices.size(), 0u) << sm.name;
    for (std::uint32_t i : sm.indices) ASSERT_LT(i, sm.positions.size()) << sm.name;
    if (s.materials[sm.material].double_sided) continue;
    // Single-sided surfaces: the counter-clockwise face normal agrees with the vertex normals.
    std::size_t agree = 0, total = 0;
    for (std::size_t t = 0; t < sm.indices.size(); t += 3) {
      const glm::vec3 a = sm.positions[sm.indices[t]], b = sm.positions[sm.indices[t + 1]],
                      c = sm.positions[sm.indices[t + 2]];
      const glm::vec3 g = glm::cross(b - a, c - a);
      if (glm::length(g) < 1e-9f) continue;  // degenerate (lathe poles)
      const glm::vec3 n = sm.normals[sm.indices[t]] + sm.normals[sm.indices[t + 1]] + sm.normals[sm.indices[t + 2]];
      ++total;
      if (glm::dot(g, n) > 0.0f) ++agree;
    }
    EXPECT_EQ(agree, total) << sm.name;
  }
  // Bounds: the building's outer walls and cornice, in meters.
  EXPECT_NEAR(s.bounds.min.y, 0.0f, 1e-4f);
  EXPECT_GT(s.bounds.max.y, 15.0f);
  EXPECT_GT(s.bounds.extent().x, 35.0f);
  EXPECT_GT(s.bounds.extent().z, 18.0f);
}

TEST(Atrium, OuterWallsFaceTheAislesInsideAndTheStreetOutside) {
  // Each vertical triangle of the outer walls: its counter-clockwise (front) face normal dotted
  // with the horizontal vector from the triangle toward the atrium's centre (0, y, 0). The inner
  // faces (|x| = outer_half_x or |z| = outer_half_z) must face the centre (dot > 0, about +1 for
  // unit vectors since the walls are axis aligned), the outer faces half a meter further out must
  // face away from it (dot < 0). Until generator version 2 both were inside out: the inner faces
  // were culled from inside, leaving a black band between the floor (ending at the inner face)
  // and the outer face behind it.
  const Scene s = make_atrium(2);
  const AtriumLayout L = atrium_layout();
  const SubMesh* walls = nullptr;
  for (const SubMesh& sm : s.submeshes)
    if (sm.name == "outer_walls") walls = &sm;
  ASSERT_NE(walls, nullptr);
  std::size_t inner = 0, outer = 0;
  for (std::size_t t = 0; t < walls->indices.size(); t += 3) {
    const glm::vec3 a = walls->positions[walls->indices[t]], b = walls->positions[walls->indices[t + 1]],
                    c = walls->positions[walls->indices[t + 2]];
    const glm::vec3 n = glm::normalize(glm::cross(b - a, c - a));
    if (std::abs(n.y) > 0.5f) continue;  // the wall tops' horizontal faces
    const glm::vec3 centroid = (a + b + c) / 3.0f;
    const glm::vec3 to_centre = glm::normalize(glm::vec3(-centroid.x, 0.0f, -centroid.z));
    // Only the long faces: the wall-top boxes' end faces are small and counted neither way.
    const bool at_inner = std::abs(std::abs(centroid.x) - L.outer_half_x) < 1e-3f ||
                          std::abs(std::abs(centroid.z) - L.outer_half_z) < 1e-3f;
    const bool at_outer = std::abs(std::abs(centroid.x) - (L.outer_half_x + 0.5f)) < 1e-3f ||
                          std::abs(std::abs(centroid.z) - (L.outer_half_z + 0.5f)) < 1e-3f;
    if (centroid.y > L.roof_height - 1e-3f) continue;  // wall tops
    if (at_inner) {
      ++inner;
      EXPECT_GT(glm::dot(n, to_centre), 0.2f) << "inner face at " << centroid.x << "," << centroid.y << "," << centroid.z;
    } else if (at_outer) {
      ++outer;
      EXPECT_LT(glm::dot(n, to_centre), -0.2f) << "outer face at " << centroid.x << "," << centroid.y << "," << centroid.z;
    }
  }
  // Four inner and four outer faces of several cells each.
  EXPECT_GE(inner, 8u * 4u);
  EXPECT_GE(outer, 2u * 4u);
}

TEST(Atrium, SpecsParseOnce) {
  EXPECT_FALSE(parse_atrium_spec("scene.glb"));
  EXPECT_FALSE(parse_atrium_spec("atriums"));
  ASSERT_TRUE(parse_atrium_spec("atrium"));
  EXPECT_FALSE(parse_atrium_spec("atrium")->detail);  // the default, default_atrium_detail
  EXPECT_EQ(parse_atrium_spec("atrium:4")->detail, 4);
  EXPECT_THROW(parse_atrium_spec("atrium:x"), InputError);
  EXPECT_THROW(parse_atrium_spec("atrium:-1"), InputError);
  EXPECT_THROW(parse_atrium_spec("atrium:2.5"), InputError);
}

TEST(Atrium, InvalidDetailThrows) {
  EXPECT_THROW(make_atrium(0), InputError);
  EXPECT_THROW(make_atrium(6), InputError);
  EXPECT_THROW(load_scene("atrium:6"), InputError);
  EXPECT_THROW(load_scene("atrium:x"), InputError);
  EXPECT_THROW(load_scene("atrium:"), InputError);
  try {
    make_atrium(0);
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("atrium:0"), std::string::npos) << e.what();
  }
}

TEST(Atrium, SceneLibrarySpecsAndInfo) {
  const Scene s = load_scene("atrium:1");
  EXPECT_EQ(s.source, "atrium:1");
  const Scene d = load_scene("atrium");
  EXPECT_EQ(d.source, "atrium:" + std::to_string(default_atrium_detail));
  std::ostringstream os;
  print_scene_info(s, os);
  const std::string info = os.str();
  for (const char* needle : {"scene         atrium", "source        atrium:1", "content hash  ", "triangles     ",
                             "punch-through", "translucent", "bounds        min", "textures      "}) {
    EXPECT_NE(info.find(needle), std::string::npos) << needle << "\n" << info;
  }
}

TEST(AtriumCamera, ViewpointsLookIntoTheBuilding) {
  const Scene s = make_atrium(1);
  const std::vector<std::string> names = atrium_viewpoint_names();
  ASSERT_GE(names.size(), 3u);
  EXPECT_EQ(names[0], "entrance");
  for (const char* n : {"entrance", "gallery", "top"})
    EXPECT_NE(std::find(names.begin(), names.end(), n), names.end()) << n;
  for (const std::string& n : names) {
    const Camera c = atrium_viewpoint(n, s);
    EXPECT_GT(c.far_plane, c.near_plane) << n;
    EXPECT_GT(c.near_plane, 0.0f) << n;
    // The courtyard's center is in front of the camera and inside the frustum's depth range.
    const glm::vec4 eye_space = c.view() * glm::vec4(s.bounds.center(), 1.0f);
    EXPECT_LT(eye_space.z, 0.0f) << n;
    const glm::vec4 clip = c.projection(16.0f / 9.0f) * eye_space;
    EXPECT_GT(clip.w, 0.0f) << n;
    EXPECT_LE(std::abs(clip.z), clip.w) << n;
  }
  // The entrance stands in the courtyard at eye height; the top view is above the roof.
  const Camera e = atrium_viewpoint("entrance", s);
  EXPECT_NEAR(e.eye.y, 1.7f, 1e-4f);
  EXPECT_GT(atrium_viewpoint("top", s).eye.y, s.bounds.max.y);
  EXPECT_GT(atrium_viewpoint("gallery", s).eye.y, atrium_layout().storey1_height);
  try {
    atrium_viewpoint("ceiling", s);
    ADD_FAILURE() << "no error for an unknown viewpoint";
  } catch (const InputError& err) {
    EXPECT_NE(std::string(err.what()).find("entrance"), std::string::npos) << err.what();
  }
}

TEST(AtriumCamera, ProjectionUsesTheGlDepthRange) {
  Camera c;
  c.eye = {0, 0, 0};
  c.target = {0, 0, -1};
  c.near_plane = 0.5f;
  c.far_plane = 50.0f;
  const glm::mat4 p = c.projection(1.0f);
  const glm::vec4 n = p * glm::vec4(0, 0, -0.5f, 1);
  const glm::vec4 f = p * glm::vec4(0, 0, -50.0f, 1);
  EXPECT_NEAR(n.z / n.w, -1.0f, 1e-5f);
  EXPECT_NEAR(f.z / f.w, 1.0f, 1e-5f);
}

TEST(Atrium, SharedSceneIsBuiltOncePerDetailAndTexelOption) {
  // shared_scene builds the atrium once per process for each (detail, colour texels) and shares
  // it afterwards: the same object for the same request ("atrium" is "atrium:3"), another for
  // the other texel option, and each equal to what load_scene builds.
  const std::shared_ptr<const Scene> bare = shared_scene("atrium:1", SceneLoadOptions{.colour_texels = false});
  EXPECT_EQ(shared_scene("atrium:1", SceneLoadOptions{.colour_texels = false}).get(), bare.get());
  const std::shared_ptr<const Scene> full = shared_scene("atrium:1");
  EXPECT_NE(full.get(), bare.get());
  EXPECT_EQ(shared_scene("atrium").get(), shared_scene("atrium:3").get());
  const Scene built = load_scene("atrium:1");
  EXPECT_EQ(full->content_hash, built.content_hash);
  EXPECT_EQ(bare->content_hash, built.content_hash);
  EXPECT_EQ(full->triangle_count(), built.triangle_count());
  ASSERT_FALSE(full->base_color_texels.empty());
  EXPECT_EQ(full->base_color_texels[0].rgba, built.base_color_texels[0].rgba);
  EXPECT_TRUE(bare->base_color_texels[0].rgba.empty());
  EXPECT_THROW(shared_scene("atrium:9"), InputError);  // the range is still checked
}

}  // namespace
}  // namespace tbdr
