// glTF loading: the sample models in shared/scenes load with their real counts; hand-written
// fixtures pin down topology conversion, transforms, alpha masks and every validation error.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <functional>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>

#include <nlohmann/json.hpp>
#include <stb/stb_image_write.h>

#include "kernel/errors.hpp"
#include "kernel/hash.hpp"
#include "scene/camera.hpp"
#include "scene/gltf_loader.hpp"
#include "scene/scene_library.hpp"

namespace tbdr {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;

// ---------------------------------------------------------------------------------------------
// Fixture files

/// A per-test temporary directory, removed at the end of the test.
class TempDir {
 public:
  TempDir() {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    static int serial = 0;
    dir_ = fs::temp_directory_path() / (std::string("tbdrsim_gltf_") + info->test_suite_name() + "_" + info->name() +
                                        "_" + std::to_string(++serial));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  void write(const std::string& name, const std::string& bytes) const {
    std::ofstream(path(name), std::ios::binary) << bytes;
  }

 private:
  fs::path dir_;
};

/// Builds a binary buffer and the glTF JSON describing it, one accessor at a time.
class GltfBuilder {
 public:
  GltfBuilder() {
    doc_["asset"] = {{"version", "2.0"}};
    doc_["buffers"] = json::array();
    doc_["bufferViews"] = json::array();
    doc_["accessors"] = json::array();
    doc_["meshes"] = json::array();
    doc_["nodes"] = json::array();
    doc_["scenes"] = json::array({json{{"nodes", json::array()}}});
    doc_["scene"] = 0;
  }

  /// Appends raw bytes as a new buffer view (4-byte aligned); returns its index.
  int view(const void* data, std::size_t bytes, int stride = 0) {
    while (bin_.size() % 4) bin_.push_back(0);
    json v = {{"buffer", 0}, {"byteOffset", bin_.size()}, {"byteLength", bytes}};
    if (stride) v["byteStride"] = stride;
    const auto* p = static_cast<const std::uint8_t*>(data);
    bin_.insert(bin_.end(), p, p + bytes);
    doc_["bufferViews"].push_back(v);
    return static_cast<int>(doc_["bufferViews"].size() - 1);
  }
  int accessor(int view_index, int component_type, std::size_t count, const std::string& type) {
    doc_["accessors"].push_back({{"bufferView", view_index}, {"componentType", component_type},
                                 {"count", count}, {"type", type}});
    return static_cast<int>(doc_["accessors"].size() - 1);
  }
  int vec3(const std::vector<float>& xyz) {
    return accessor(view(xyz.data(), xyz.size() * 4), 5126, xyz.size() / 3, "VEC3");
  }
  int vec2(const std::vector<float>& uv) { return accessor(view(uv.data(), uv.size() * 4), 5126, uv.size() / 2, "VEC2"); }
  int indices16(const std::vector<std::uint16_t>& idx) {
    return accessor(view(idx.data(), idx.size() * 2), 5123, idx.size(), "SCALAR");
  }
  int indices8(const std::vector<std::uint8_t>& idx) {
    return accessor(view(idx.data(), idx.size()), 5121, idx.size(), "SCALAR");
  }
  int indices32(const std::vector<std::uint32_t>& idx) {
    return accessor(view(idx.data(), idx.size() * 4), 5125, idx.size(), "SCALAR");
  }
  /// A mesh with one primitive; returns the mesh index.
  int mesh(const std::string& name, json primitive) {
    doc_["meshes"].push_back({{"name", name}, {"primitives", json::array({primitive})}});
    return static_cast<int>(doc_["meshes"].size() - 1);
  }
  /// A node; root nodes are added to the scene.
  int node(json n, bool root = true) {
    doc_["nodes"].push_back(n);
    const int i = static_cast<int>(doc_["nodes"].size() - 1);
    if (root) doc_["scenes"][0]["nodes"].push_back(i);
    return i;
  }
  json& doc() { return doc_; }
  const std::vector<std::uint8_t>& bin() const { return bin_; }

  /// Writes name.gltf and name.bin (the .bin named `bin_name`, or not written when empty).
  std::string write_gltf(const TempDir& dir, const std::string& name, const std::string& bin_name) {
    doc_["buffers"] = json::array();
    if (!bin_.empty()) doc_["buffers"].push_back({{"uri", name + ".bin"}, {"byteLength", bin_.size()}, {"name", "geometry"}});
    if (!bin_name.empty()) dir.write(bin_name, std::string(bin_.begin(), bin_.end()));
    dir.write(name + ".gltf", doc_.dump(1));
    return dir.path(name + ".gltf");
  }
  std::string write_gltf(const TempDir& dir, const std::string& name) { return write_gltf(dir, name, name + ".bin"); }

  /// Writes a .glb with the buffer in its BIN chunk.
  std::string write_glb(const TempDir& dir, const std::string& name) {
    doc_["buffers"] = json::array({json{{"byteLength", bin_.size()}}});
    std::string js = doc_.dump();
    while (js.size() % 4) js.push_back(' ');
    std::vector<std::uint8_t> bin = bin_;
    while (bin.size() % 4) bin.push_back(0);
    std::string out;
    auto u32 = [&](std::uint32_t v) { out.append(reinterpret_cast<const char*>(&v), 4); };
    out += "glTF";
    u32(2);
    u32(static_cast<std::uint32_t>(12 + 8 + js.size() + 8 + bin.size()));
    u32(static_cast<std::uint32_t>(js.size()));
    u32(0x4E4F534A);
    out += js;
    u32(static_cast<std::uint32_t>(bin.size()));
    u32(0x004E4942);
    out.append(bin.begin(), bin.end());
    dir.write(name + ".glb", out);
    return dir.path(name + ".glb");
  }

 private:
  json doc_;
  std::vector<std::uint8_t> bin_;
};

/// A unit quad in the z=0 plane, counter-clockwise seen from +z.
const std::vector<float> quad_positions = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0};

/// A document of one root node drawing the quad's corners with 16-bit `indices` (mesh `name`).
GltfBuilder quad_corners(const std::string& name, const std::vector<std::uint16_t>& indices) {
  GltfBuilder g;
  const int pos = g.vec3(quad_positions);
  const int idx = g.indices16(indices);
  g.node({{"mesh", g.mesh(name, {{"attributes", {{"POSITION", pos}}}, {"indices", idx}})}});
  return g;
}

std::string load_error(const std::string& path) {
  try {
    load_gltf(path);
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no error)";
}

bool has_warning(const Scene& s, const std::string& needle) {
  for (const std::string& w : s.warnings)
    if (w.find(needle) != std::string::npos) return true;
  return false;
}

// ---------------------------------------------------------------------------------------------
// Fixtures: what loads

TEST(GltfLoad, IndexedQuadCountsStrideAndFlatNormals) {
  TempDir dir;
  GltfBuilder g;
  const int pos = g.vec3(quad_positions);
  const int idx = g.indices16({0, 1, 2, 0, 2, 3});
  g.node({{"mesh", g.mesh("Quad", {{"attributes", {{"POSITION", pos}}}, {"indices", idx}})}, {"name", "q"}});
  const Scene s = load_gltf(g.write_gltf(dir, "quad"));
  ASSERT_EQ(s.submeshes.size(), 1u);
  ASSERT_EQ(s.instances.size(), 1u);
  EXPECT_EQ(s.triangle_count(), 2u);
  EXPECT_EQ(s.vertex_count(), 4u);
  const SubMesh& sm = s.submeshes[0];
  EXPECT_EQ(sm.index_bytes, 2u);
  EXPECT_EQ(sm.vertex_stride_bytes, 12u);  // POSITION only
  EXPECT_EQ(sm.name, "Quad");
  EXPECT_EQ(s.instances[0].node, "q");
  ASSERT_EQ(sm.normals.size(), 4u);
  for (const glm::vec3& n : sm.normals) EXPECT_NEAR(n.z, 1.0f, 1e-6f);  // generated, flat
  EXPECT_EQ(s.name, "quad");
  EXPECT_EQ(s.materials.size(), 1u);  // the default material for a primitive without one
  EXPECT_EQ(s.materials[0].alpha_mode, AlphaMode::Opaque);
  EXPECT_FLOAT_EQ(s.bounds.max.x, 1.0f);
  EXPECT_FLOAT_EQ(s.bounds.min.y, 0.0f);
  EXPECT_TRUE(s.warnings.empty());
}

TEST(GltfLoad, SharedSceneLoadsAGltfFileAfreshEachTime) {
  // shared_scene keeps only the procedural atrium; a file is read again on every call, so a
  // file rewritten between two calls is seen as it is now (here: a quad, then a triangle).
  TempDir dir;
  const std::string path = quad_corners("Quad", {0, 1, 2, 0, 2, 3}).write_gltf(dir, "shape");
  const std::shared_ptr<const Scene> first = shared_scene(path);
  EXPECT_EQ(first->triangle_count(), 2u);
  EXPECT_EQ(quad_corners("Tri", {0, 1, 2}).write_gltf(dir, "shape"), path);
  const std::shared_ptr<const Scene> second = shared_scene(path);
  EXPECT_NE(first.get(), second.get());
  EXPECT_EQ(second->triangle_count(), 1u);
}

TEST(GltfLoad, IndexComponentTypesAndNonIndexed) {
  TempDir dir;
  GltfBuilder g;
  const int pos = g.vec3(quad_positions);
  const int i8 = g.indices8({0, 1, 2, 0, 2, 3});
  const int i32 = g.indices32({0, 1, 2, 0, 2, 3});
  const int m8 = g.mesh("u8", {{"attributes", {{"POSITION", pos}}}, {"indices", i8}});
  const int m32 = g.mesh("u32", {{"attributes", {{"POSITION", pos}}}, {"indices", i32}});
  const int tri = g.vec3({0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0});
  const int mflat = g.mesh("flat", {{"attributes", {{"POSITION", tri}}}});
  g.node({{"mesh", m8}});
  g.node({{"mesh", m32}});
  g.node({{"mesh", mflat}});
  const Scene s = load_gltf(g.write_gltf(dir, "types"));
  ASSERT_EQ(s.submeshes.size(), 3u);
  EXPECT_EQ(s.submeshes[0].index_bytes, 1u);
  EXPECT_EQ(s.submeshes[1].index_bytes, 4u);
  EXPECT_EQ(s.submeshes[2].index_bytes, 0u);  // non-indexed
  EXPECT_EQ(s.submeshes[2].indices, (std::vector<std::uint32_t>{0, 1, 2, 3, 4, 5}));
  EXPECT_EQ(s.triangle_count(), 6u);
}

TEST(GltfLoad, StripAndFanBecomeTriangleLists) {
  TempDir dir;
  GltfBuilder g;
  // Six vertices in a zig-zag strip / around a fan center.
  const int pos = g.vec3({0, 0, 0, 0, 1, 0, 1, 0, 0, 1, 1, 0, 2, 0, 0, 2, 1, 0});
  const int idx = g.indices16({0, 1, 2, 3, 4, 5});
  const int strip = g.mesh("strip", {{"attributes", {{"POSITION", pos}}}, {"indices", idx}, {"mode", 5}});
  const int fan = g.mesh("fan", {{"attributes", {{"POSITION", pos}}}, {"indices", idx}, {"mode", 6}});
  const int strip_flat = g.mesh("strip_flat", {{"attributes", {{"POSITION", pos}}}, {"mode", 5}});
  g.node({{"mesh", strip}});
  g.node({{"mesh", fan}});
  g.node({{"mesh", strip_flat}});
  const Scene s = load_gltf(g.write_gltf(dir, "topology"));
  ASSERT_EQ(s.submeshes.size(), 3u);
  // glTF 2.0: strip triangle i = {i, i+1+i%2, i+2-i%2}; fan triangle i = {i+1, i+2, 0}.
  EXPECT_EQ(s.submeshes[0].indices, (std::vector<std::uint32_t>{0, 1, 2, 1, 3, 2, 2, 3, 4, 3, 5, 4}));
  EXPECT_EQ(s.submeshes[1].indices, (std::vector<std::uint32_t>{1, 2, 0, 2, 3, 0, 3, 4, 0, 4, 5, 0}));
  EXPECT_EQ(s.submeshes[2].indices, s.submeshes[0].indices);
  EXPECT_EQ(s.submeshes[2].index_bytes, 0u);
  EXPECT_EQ(s.triangle_count(), 12u);
}

TEST(GltfLoad, PointsAndLinesAreSkippedWithAWarning) {
  TempDir dir;
  GltfBuilder g;
  const int pos = g.vec3(quad_positions);
  g.doc()["meshes"].push_back({{"name", "Mixed"},
                               {"primitives",
                                {{{"attributes", {{"POSITION", pos}}}, {"mode", 1}},
                                 {{"attributes", {{"POSITION", pos}}}, {"mode", 6}},
                                 {{"attributes", {{"POSITION", pos}}}, {"mode", 0}}}}});
  g.node({{"mesh", 0}});
  const Scene s = load_gltf(g.write_gltf(dir, "mixed"));
  ASSERT_EQ(s.submeshes.size(), 1u);
  EXPECT_EQ(s.triangle_count(), 2u);
  EXPECT_TRUE(has_warning(s, "mesh 0 'Mixed' primitive 0: mode LINES skipped")) << s.warnings.size();
  EXPECT_TRUE(has_warning(s, "primitive 2: mode POINTS skipped"));
}

TEST(GltfLoad, NodeHierarchyTrsAndMatrixFlattenedSharedMeshInstanced) {
  TempDir dir;
  GltfBuilder g;
  const int pos = g.vec3(quad_positions);
  const int idx = g.indices16({0, 1, 2, 0, 2, 3});
  const int m = g.mesh("Quad", {{"attributes", {{"POSITION", pos}}}, {"indices", idx}});
  // Child placed by a matrix (translate x+10), parent by TRS (scale 2, translate y+5).
  const int child = g.node({{"mesh", m}, {"name", "child"},
                            {"matrix", {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 10, 0, 0, 1}}}, false);
  g.node({{"mesh", m}, {"name", "parent"}, {"children", {child}}, {"translation", {0, 5, 0}}, {"scale", {2, 2, 2}}});
  // 90 degrees about z: (1,0,0) -> (0,1,0).
  const float h = std::sqrt(0.5f);
  g.node({{"mesh", m}, {"name", "rotated"}, {"rotation", {0, 0, h, h}}, {"translation", {-3, 0, 0}}});
  const Scene s = load_gltf(g.write_gltf(dir, "hierarchy"));
  ASSERT_EQ(s.submeshes.size(), 1u);  // one mesh, one primitive
  ASSERT_EQ(s.instances.size(), 3u);  // placed three times
  EXPECT_EQ(s.triangle_count(), 6u);
  const glm::mat4& pw = s.instances[0].world;
  EXPECT_EQ(s.instances[0].node, "parent");
  EXPECT_FLOAT_EQ((pw * glm::vec4(1, 1, 0, 1)).y, 7.0f);
  EXPECT_EQ(s.instances[1].node, "child");
  const glm::vec4 c = s.instances[1].world * glm::vec4(1, 0, 0, 1);
  EXPECT_FLOAT_EQ(c.x, 22.0f);  // (1 + 10) * 2
  EXPECT_FLOAT_EQ(c.y, 5.0f);
  const glm::vec4 r = s.instances[2].world * glm::vec4(1, 0, 0, 1);
  EXPECT_NEAR(r.x, -3.0f, 1e-6f);
  EXPECT_NEAR(r.y, 1.0f, 1e-6f);
  EXPECT_FLOAT_EQ(s.bounds.max.x, 22.0f);
  EXPECT_FLOAT_EQ(s.bounds.max.y, 7.0f);
}

TEST(GltfLoad, GlbLoadsLikeGltfAndHashesTheFile) {
  TempDir dir;
  GltfBuilder g = quad_corners("Quad", {0, 1, 2, 0, 2, 3});
  const std::string glb = g.write_glb(dir, "quad");
  const Scene s = load_scene(glb);
  EXPECT_EQ(s.triangle_count(), 2u);
  EXPECT_EQ(s.content_hash, hash_file_hex(glb));  // no external resources
}

TEST(GltfLoad, ContentHashFoldsInExternalBuffers) {
  TempDir dir;
  GltfBuilder g;
  const int pos = g.vec3(quad_positions);
  g.node({{"mesh", g.mesh("Quad", {{"attributes", {{"POSITION", pos}}}})}});
  const std::string path = g.write_gltf(dir, "hashed");
  const Scene s = load_gltf(path);
  std::ifstream a(path, std::ios::binary), b(dir.path("hashed.bin"), std::ios::binary);
  std::stringstream sa, sb;
  sa << a.rdbuf();
  sb << b.rdbuf();
  Fnv1a64 h;
  h.update(sa.str());
  h.update(sb.str());
  EXPECT_EQ(s.content_hash, h.hex());
  EXPECT_NE(s.content_hash, hash_file_hex(path));
}

TEST(GltfLoad, SparseAccessorIsApplied) {
  TempDir dir;
  GltfBuilder g;
  const int pos = g.vec3(quad_positions);
  const std::vector<std::uint16_t> sparse_idx = {2};
  const std::vector<float> sparse_val = {5, 6, 0};
  const int iv = g.view(sparse_idx.data(), 2);
  const int vv = g.view(sparse_val.data(), 12);
  g.doc()["accessors"][pos]["sparse"] = {{"count", 1},
                                         {"indices", {{"bufferView", iv}, {"componentType", 5123}}},
                                         {"values", {{"bufferView", vv}}}};
  g.node({{"mesh", g.mesh("Quad", {{"attributes", {{"POSITION", pos}}}})}});
  const Scene s = load_gltf(g.write_gltf(dir, "sparse"));
  ASSERT_EQ(s.submeshes.size(), 1u);
  EXPECT_EQ(s.submeshes[0].positions[2], glm::vec3(5, 6, 0));
  EXPECT_EQ(s.submeshes[0].positions[1], glm::vec3(1, 0, 0));
}

TEST(GltfLoad, MissingTextureFileIsAWarning) {
  TempDir dir;
  GltfBuilder g;
  const int pos = g.vec3(quad_positions);
  g.doc()["images"] = {{{"uri", "nothere.png"}}};
  g.doc()["textures"] = {{{"source", 0}}};
  g.doc()["materials"] = {{{"name", "Painted"}, {"pbrMetallicRoughness", {{"baseColorTexture", {{"index", 0}}}}}}};
  const int idx = g.indices16({0, 1, 2, 0, 2, 3});
  g.node({{"mesh", g.mesh("Quad", {{"attributes", {{"POSITION", pos}}}, {"indices", idx}, {"material", 0}})}});
  const Scene s = load_gltf(g.write_gltf(dir, "notex"));
  ASSERT_EQ(s.textures.size(), 1u);
  EXPECT_TRUE(s.textures[0].missing);
  EXPECT_EQ(s.textures[0].gpu_bytes(), 0u);
  EXPECT_EQ(s.materials[0].base_color_texture, 0);
  EXPECT_TRUE(has_warning(s, "image 0 'nothere.png': file not found"));
  EXPECT_EQ(s.triangle_count(), 2u);
}

TEST(GltfLoad, MaskMaterialDecodesAlphaAndBlendOpaqueDoNot) {
  TempDir dir;
  // 4x2 RGBA: left half transparent (alpha 0), right half opaque (alpha 255).
  std::vector<std::uint8_t> px(4 * 2 * 4, 200);
  for (int y = 0; y < 2; ++y)
    for (int x = 0; x < 4; ++x) px[(y * 4 + x) * 4 + 3] = x < 2 ? 0 : 255;
  ASSERT_NE(stbi_write_png(dir.path("cut.png").c_str(), 4, 2, 4, px.data(), 16), 0);
  std::vector<std::uint8_t> rgb(3 * 3 * 3, 90);
  ASSERT_NE(stbi_write_png(dir.path("rgb.png").c_str(), 3, 3, 3, rgb.data(), 9), 0);

  GltfBuilder g;
  const int pos = g.vec3(quad_positions);
  const int uv = g.vec2({0, 0, 1, 0, 1, 1, 0, 1});
  g.doc()["images"] = {{{"uri", "cut.png"}}, {{"uri", "rgb.png"}}};
  g.doc()["textures"] = {{{"source", 0}}, {{"source", 1}}};
  g.doc()["materials"] = {
      {{"name", "Cut"}, {"alphaMode", "MASK"}, {"alphaCutoff", 0.3}, {"doubleSided", true},
       {"pbrMetallicRoughness", {{"baseColorTexture", {{"index", 0}}}, {"baseColorFactor", {1, 0.5, 0.25, 0.8}}}}},
      {{"name", "Glass"}, {"alphaMode", "BLEND"}, {"pbrMetallicRoughness", {{"baseColorTexture", {{"index", 0}}}}}},
      {{"name", "NoAlpha"}, {"alphaMode", "MASK"}, {"pbrMetallicRoughness", {{"baseColorTexture", {{"index", 1}}}}}},
      {{"name", "FactorOnly"}, {"alphaMode", "MASK"}, {"pbrMetallicRoughness", {{"baseColorFactor", {1, 1, 1, 0.2}}}}},
      {{"name", "Plain"}}};
  for (int m = 0; m < 5; ++m) {
    g.node({{"mesh", g.mesh("M" + std::to_string(m),
                            {{"attributes", {{"POSITION", pos}, {"TEXCOORD_0", uv}}}, {"material", m}})}});
  }
  const Scene s = load_gltf(g.write_gltf(dir, "alpha"));
  ASSERT_EQ(s.materials.size(), 5u);
  const Material& cut = s.materials[0];
  EXPECT_EQ(cut.alpha_mode, AlphaMode::PunchThrough);
  EXPECT_FLOAT_EQ(cut.alpha_cutoff, 0.3f);
  EXPECT_TRUE(cut.double_sided);
  EXPECT_FLOAT_EQ(cut.base_color.y, 0.5f);
  ASSERT_EQ(s.alpha_masks.size(), 1u);  // only the MASK material with an alpha texture
  ASSERT_EQ(cut.alpha_mask, 0);
  const AlphaMask& mask = s.alpha_masks[0];
  EXPECT_EQ(mask.width, 4);
  EXPECT_EQ(mask.height, 2);
  EXPECT_FLOAT_EQ(mask.sample({0.1f, 0.5f}), 0.0f);
  EXPECT_FLOAT_EQ(mask.sample({0.9f, 0.5f}), 1.0f);
  EXPECT_FLOAT_EQ(mask.sample({1.9f, -0.5f}), 1.0f);  // repeat wrapping
  EXPECT_FLOAT_EQ(cut.base_color.w, 0.8f);  // a fragment's alpha: base_color.w x mask
  // Every textured material's image is decoded once for the albedo: cut.png and rgb.png.
  ASSERT_EQ(s.base_color_texels.size(), 2u);
  EXPECT_EQ(cut.base_color_texels, s.materials[1].base_color_texels);
  EXPECT_NE(s.materials[2].base_color_texels, -1);
  EXPECT_EQ(s.materials[3].base_color_texels, -1);
  EXPECT_EQ(s.base_color_texels[static_cast<std::size_t>(s.materials[2].base_color_texels)].rgba[0], 90);
  EXPECT_EQ(s.materials[1].alpha_mode, AlphaMode::Translucent);
  EXPECT_EQ(s.materials[1].alpha_mask, -1);
  EXPECT_EQ(s.materials[2].alpha_mask, -1);  // texture without alpha
  EXPECT_EQ(s.materials[3].alpha_mask, -1);
  EXPECT_FLOAT_EQ(s.materials[3].base_color.w, 0.2f);
  EXPECT_EQ(s.materials[4].alpha_mode, AlphaMode::Opaque);
  ASSERT_EQ(s.textures.size(), 2u);
  EXPECT_EQ(s.textures[0].format, "png");
  EXPECT_EQ(s.textures[0].width, 4);
  EXPECT_EQ(s.textures[0].channels, 4);
  EXPECT_EQ(s.textures[1].channels, 3);
  EXPECT_EQ(s.submeshes[0].vertex_stride_bytes, 20u);  // POSITION 12 + TEXCOORD_0 8
  EXPECT_EQ(s.submeshes[0].uvs[2], glm::vec2(1, 1));
}

TEST(GltfImageHeader, PngJpegAndGarbage) {
  TempDir dir;
  std::vector<std::uint8_t> px(5 * 7 * 3, 128);
  ASSERT_NE(stbi_write_jpg(dir.path("a.jpg").c_str(), 5, 7, 3, px.data(), 90), 0);
  ASSERT_NE(stbi_write_png(dir.path("a.png").c_str(), 5, 7, 3, px.data(), 15), 0);
  auto read = [&](const std::string& name) {
    std::ifstream in(dir.path(name), std::ios::binary);
    return std::vector<std::uint8_t>(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  };
  const auto jpg = read("a.jpg");
  const auto h = parse_image_header(jpg.data(), jpg.size());
  ASSERT_TRUE(h.has_value());
  EXPECT_EQ(h->format, "jpeg");
  EXPECT_EQ(h->width, 5);
  EXPECT_EQ(h->height, 7);
  EXPECT_EQ(h->channels, 3);
  const auto png = read("a.png");
  const auto p = parse_image_header(png.data(), png.size());
  ASSERT_TRUE(p.has_value());
  EXPECT_EQ(p->format, "png");
  EXPECT_EQ(p->width, 5);
  EXPECT_EQ(p->height, 7);
  EXPECT_EQ(p->channels, 3);
  const std::uint8_t junk[] = {1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16};
  EXPECT_FALSE(parse_image_header(junk, sizeof junk).has_value());
  EXPECT_FALSE(parse_image_header(png.data(), 20).has_value());  // truncated IHDR
}

// ---------------------------------------------------------------------------------------------
// Fixtures: what fails, and how the message names the culprit

TEST(GltfErrors, OutOfRangeIndexNamesTheAccessor) {
  TempDir dir;
  GltfBuilder g;
  const int pos = g.vec3(quad_positions);
  const int idx = g.indices16({0, 1, 2, 0, 2, 40});
  g.node({{"mesh", g.mesh("Quad", {{"attributes", {{"POSITION", pos}}}, {"indices", idx}})}});
  const std::string path = g.write_gltf(dir, "badindex");
  const std::string e = load_error(path);
  EXPECT_NE(e.find(path + ": accessor 1 (indices of mesh 0 'Quad' primitive 0): index 40 at position 5 is out of "
                          "range (4 vertices)"),
            std::string::npos)
      << e;
}

TEST(GltfErrors, MissingBinNamesTheBufferAndFile) {
  TempDir dir;
  GltfBuilder g;
  const int pos = g.vec3(quad_positions);
  g.node({{"mesh", g.mesh("Quad", {{"attributes", {{"POSITION", pos}}}})}});
  const std::string path = g.write_gltf(dir, "nobin", "");
  const std::string e = load_error(path);
  EXPECT_NE(e.find(path), std::string::npos) << e;
  EXPECT_NE(e.find("buffer 0 'geometry'"), std::string::npos) << e;
  EXPECT_NE(e.find("nobin.bin"), std::string::npos) << e;
  EXPECT_NE(e.find("not found"), std::string::npos) << e;
}

TEST(GltfErrors, ShortBinNamesTheBuffer) {
  TempDir dir;
  GltfBuilder g;
  const int pos = g.vec3(quad_positions);
  g.node({{"mesh", g.mesh("Quad", {{"attributes", {{"POSITION", pos}}}})}});
  const std::string path = g.write_gltf(dir, "shortbin", "");
  dir.write("shortbin.bin", "1234");
  const std::string e = load_error(path);
  EXPECT_NE(e.find("buffer 0 'geometry'"), std::string::npos) << e;
  EXPECT_NE(e.find("is 4 bytes but byteLength is 48"), std::string::npos) << e;
}

TEST(GltfErrors, NanPositionNamesTheVertex) {
  TempDir dir;
  GltfBuilder g;
  std::vector<float> p = quad_positions;
  p[7] = std::numeric_limits<float>::quiet_NaN();
  const int pos = g.vec3(p);
  g.node({{"mesh", g.mesh("Quad", {{"attributes", {{"POSITION", pos}}}})}});
  const std::string e = load_error(g.write_gltf(dir, "nan"));
  EXPECT_NE(e.find("accessor 0 (POSITION of mesh 0 'Quad' primitive 0): vertex 2 has a non-finite coordinate"),
            std::string::npos)
      << e;
}

TEST(GltfErrors, InfinitePositionIsRejected) {
  TempDir dir;
  GltfBuilder g;
  std::vector<float> p = quad_positions;
  p[0] = std::numeric_limits<float>::infinity();
  g.node({{"mesh", g.mesh("Quad", {{"attributes", {{"POSITION", g.vec3(p)}}}})}});
  EXPECT_NE(load_error(g.write_gltf(dir, "inf")).find("vertex 0 has a non-finite coordinate"), std::string::npos);
}

TEST(GltfErrors, NodeCycleIsRejected) {
  TempDir dir;
  GltfBuilder g;
  const int pos = g.vec3(quad_positions);
  const int m = g.mesh("Quad", {{"attributes", {{"POSITION", pos}}}});
  g.node({{"mesh", m}, {"name", "root"}, {"children", {1}}});
  g.node({{"name", "a"}, {"children", {2}}}, false);
  g.node({{"name", "b"}, {"children", {1}}}, false);
  const std::string e = load_error(g.write_gltf(dir, "cycle"));
  // Node 1 is a child of both 0 and 2: reported as not-a-tree before the cycle walk.
  EXPECT_NE(e.find("node 1 'a'"), std::string::npos) << e;

  TempDir dir2;
  GltfBuilder g2;
  const int pos2 = g2.vec3(quad_positions);
  const int m2 = g2.mesh("Quad", {{"attributes", {{"POSITION", pos2}}}});
  g2.node({{"mesh", m2}, {"name", "root"}});
  g2.node({{"name", "a"}, {"children", {2}}}, false);
  g2.node({{"name", "b"}, {"children", {1}}}, false);
  const std::string e2 = load_error(g2.write_gltf(dir2, "cycle2"));
  EXPECT_NE(e2.find("node graph cycle"), std::string::npos) << e2;

  TempDir dir3;
  GltfBuilder g3;
  g3.node({{"name", "self"}, {"children", {0}}});
  EXPECT_NE(load_error(g3.write_gltf(dir3, "self")).find("node 0 'self': is its own child"), std::string::npos);
}

TEST(GltfErrors, OutOfRangeReferencesNameTheOwner) {
  struct Case {
    const char* what;
    std::function<void(GltfBuilder&, int pos)> edit;
    const char* expect;
  };
  const std::vector<Case> cases = {
      {"node mesh", [](GltfBuilder& g, int) { g.doc()["nodes"][0]["mesh"] = 5; },
       "node 0 'n': refers to mesh 5, but the file has 1"},
      {"child", [](GltfBuilder& g, int) { g.doc()["nodes"][0]["children"] = {9}; },
       "node 0 'n' children: refers to node 9, but the file has 1"},
      {"material", [](GltfBuilder& g, int) { g.doc()["meshes"][0]["primitives"][0]["material"] = 3; },
       "mesh 0 'Quad' primitive 0: refers to material 3, but the file has 0"},
      {"texture",
       [](GltfBuilder& g, int) {
         g.doc()["materials"] = {{{"name", "m"}, {"pbrMetallicRoughness", {{"baseColorTexture", {{"index", 2}}}}}}};
       },
       "material 0 'm' baseColorTexture: refers to texture 2, but the file has 0"},
      {"image",
       [](GltfBuilder& g, int) {
         g.doc()["textures"] = {{{"source", 4}}};
         g.doc()["materials"] = {{{"name", "m"}, {"pbrMetallicRoughness", {{"baseColorTexture", {{"index", 0}}}}}}};
       },
       "texture 0: refers to image 4, but the file has 0"},
      {"accessor type", [](GltfBuilder& g, int pos) { g.doc()["accessors"][pos]["type"] = "VEC2"; },
       "POSITION must be VEC3 FLOAT, found VEC2 FLOAT"},
      {"byte range", [](GltfBuilder& g, int pos) { g.doc()["accessors"][pos]["count"] = 5; },
       "accessor 0 (POSITION of mesh 0 'Quad' primitive 0): 5 elements of 12 bytes (stride 12) from byte 0 need 60 "
       "bytes, but bufferView 0 has 48"},
      {"view outside buffer", [](GltfBuilder& g, int) { g.doc()["bufferViews"][0]["byteLength"] = 480; },
       "bufferView 0: bytes [0, 480) lie outside buffer 0"},
      {"view buffer index", [](GltfBuilder& g, int) { g.doc()["bufferViews"][0]["buffer"] = 2; },
       "bufferView 0: refers to buffer 2, but the file has 1 buffers"},
  };
  for (const Case& c : cases) {
    TempDir dir;
    GltfBuilder g;
    const int pos = g.vec3(quad_positions);
    g.node({{"mesh", g.mesh("Quad", {{"attributes", {{"POSITION", pos}}}})}, {"name", "n"}});
    c.edit(g, pos);
    const std::string e = load_error(g.write_gltf(dir, "ref"));
    EXPECT_NE(e.find(c.expect), std::string::npos) << c.what << ": " << e;
  }
}

TEST(GltfErrors, AttributeAndIndexTypesAndCounts) {
  {
    TempDir dir;
    GltfBuilder g;
    const int pos = g.vec3(quad_positions);
    const int nrm = g.vec3({0, 0, 1, 0, 0, 1, 0, 0, 1});  // 3 normals for 4 positions
    g.node({{"mesh", g.mesh("Quad", {{"attributes", {{"POSITION", pos}, {"NORMAL", nrm}}}})}});
    const std::string e = load_error(g.write_gltf(dir, "counts"));
    EXPECT_NE(e.find("accessor 1 (NORMAL of mesh 0 'Quad' primitive 0): has 3 elements but POSITION (accessor 0) has 4"),
              std::string::npos)
        << e;
  }
  {
    TempDir dir;
    GltfBuilder g;
    const int pos = g.vec3(quad_positions);
    const std::vector<float> fidx = {0, 1, 2};
    const int idx = g.accessor(g.view(fidx.data(), 12), 5126, 3, "SCALAR");
    g.node({{"mesh", g.mesh("Quad", {{"attributes", {{"POSITION", pos}}}, {"indices", idx}})}});
    const std::string e = load_error(g.write_gltf(dir, "findex"));
    EXPECT_NE(e.find("indices must be SCALAR UNSIGNED_BYTE/UNSIGNED_SHORT/UNSIGNED_INT, found SCALAR FLOAT"),
              std::string::npos)
        << e;
  }
  {
    TempDir dir;
    GltfBuilder g;
    const int pos = g.vec3(quad_positions);
    g.node({{"mesh", g.mesh("Quad", {{"attributes", {{"NORMAL", pos}}}})}});
    EXPECT_NE(load_error(g.write_gltf(dir, "nopos")).find("has no POSITION attribute"), std::string::npos);
  }
  {
    TempDir dir;
    GltfBuilder g;
    const int pos = g.vec3(quad_positions);
    const std::vector<std::uint16_t> bad_sparse = {7};
    const std::vector<float> val = {0, 0, 0};
    const int iv = g.view(bad_sparse.data(), 2);
    const int vv = g.view(val.data(), 12);
    g.doc()["accessors"][pos]["sparse"] = {
        {"count", 1}, {"indices", {{"bufferView", iv}, {"componentType", 5123}}}, {"values", {{"bufferView", vv}}}};
    g.node({{"mesh", g.mesh("Quad", {{"attributes", {{"POSITION", pos}}}})}});
    const std::string e = load_error(g.write_gltf(dir, "badsparse"));
    EXPECT_NE(e.find("sparse indices: index 7 at position 0"), std::string::npos) << e;
  }
}

TEST(GltfErrors, SpecsAndFilesThatAreNotScenes) {
  EXPECT_THROW(load_scene("/nonexistent/dir/x.gltf"), InputError);
  EXPECT_THROW(load_scene("model.obj"), InputError);
  TempDir dir;
  dir.write("broken.gltf", "{ not json");
  const std::string e = load_error(dir.path("broken.gltf"));
  EXPECT_NE(e.find("broken.gltf"), std::string::npos) << e;
}

// ---------------------------------------------------------------------------------------------
// The sample models in shared/scenes

std::string model_path(const std::string& name) {
  return std::string(TBDRSIM_SCENES_DIR) + "/" + name + "/glTF/" + name + ".gltf";
}

#define LOAD_MODEL_OR_SKIP(var, name)                                                    \
  if (!fs::exists(model_path(name))) GTEST_SKIP() << "sample model absent: " << model_path(name); \
  const Scene var = load_scene(model_path(name))

std::size_t count_mode(const Scene& s, AlphaMode m) {
  return static_cast<std::size_t>(
      std::count_if(s.materials.begin(), s.materials.end(), [&](const Material& x) { return x.alpha_mode == m; }));
}

TEST(GltfModels, Box) {
  LOAD_MODEL_OR_SKIP(s, "Box");
  EXPECT_EQ(s.name, "Box");
  EXPECT_EQ(s.triangle_count(), 12u);
  EXPECT_EQ(s.vertex_count(), 24u);
  ASSERT_EQ(s.submeshes.size(), 1u);
  EXPECT_EQ(s.instances.size(), 1u);
  EXPECT_EQ(s.submeshes[0].index_bytes, 2u);
  EXPECT_EQ(s.submeshes[0].vertex_stride_bytes, 24u);  // POSITION + NORMAL
  EXPECT_EQ(count_mode(s, AlphaMode::Opaque), 1u);
  EXPECT_NEAR(s.bounds.min.x, -0.5f, 1e-5f);
  EXPECT_NEAR(s.bounds.max.y, 0.5f, 1e-5f);
  EXPECT_TRUE(s.warnings.empty());
  EXPECT_EQ(s.content_hash.size(), 16u);
  std::ostringstream os;
  print_scene_info(s, os);
  EXPECT_NE(os.str().find("triangles     12\n"), std::string::npos) << os.str();
  EXPECT_NE(os.str().find("opaque        1 materials, 12 triangles"), std::string::npos) << os.str();
}

TEST(GltfModels, BoxTextured) {
  LOAD_MODEL_OR_SKIP(s, "BoxTextured");
  EXPECT_EQ(s.triangle_count(), 12u);
  ASSERT_EQ(s.textures.size(), 1u);
  EXPECT_EQ(s.textures[0].format, "png");
  EXPECT_EQ(s.textures[0].width, 256);
  EXPECT_EQ(s.textures[0].height, 256);
  EXPECT_EQ(s.textures[0].gpu_bytes(), 349524u);  // 256^2 * 4 with the full mip chain
  EXPECT_EQ(s.submeshes[0].vertex_stride_bytes, 32u);  // POSITION + NORMAL + TEXCOORD_0
  EXPECT_EQ(s.materials[0].base_color_texture, 0);
}

TEST(GltfModels, Duck) {
  LOAD_MODEL_OR_SKIP(s, "Duck");
  EXPECT_EQ(s.triangle_count(), 4212u);
  ASSERT_EQ(s.textures.size(), 1u);
  EXPECT_EQ(s.textures[0].width, 512);
  EXPECT_FALSE(s.textures[0].missing);
}

TEST(GltfModels, DamagedHelmet) {
  LOAD_MODEL_OR_SKIP(s, "DamagedHelmet");
  EXPECT_EQ(s.triangle_count(), 15452u);
  ASSERT_EQ(s.textures.size(), 5u);
  for (const TextureInfo& t : s.textures) {
    EXPECT_EQ(t.format, "jpeg");
    EXPECT_EQ(t.width, 2048);
    EXPECT_EQ(t.height, 2048);
    EXPECT_FALSE(t.missing);
  }
  EXPECT_TRUE(s.warnings.empty());
}

TEST(GltfModels, SciFiHelmetWithMissingTextures) {
  LOAD_MODEL_OR_SKIP(s, "SciFiHelmet");
  EXPECT_EQ(s.triangle_count(), 23358u);
  EXPECT_EQ(s.textures.size(), 4u);
  const auto missing = std::count_if(s.textures.begin(), s.textures.end(), [](const TextureInfo& t) { return t.missing; });
  EXPECT_EQ(static_cast<std::size_t>(missing), 3u);  // this copy ships only the occlusion map
  EXPECT_TRUE(has_warning(s, "SciFiHelmet_BaseColor.png': file not found"));
}

TEST(GltfModels, FlightHelmet) {
  LOAD_MODEL_OR_SKIP(s, "FlightHelmet");
  EXPECT_EQ(s.triangle_count(), 94722u);
  EXPECT_EQ(s.submeshes.size(), 5u);
  EXPECT_EQ(s.instances.size(), 5u);
  EXPECT_EQ(count_mode(s, AlphaMode::Translucent), 1u);
  EXPECT_EQ(s.textures.size(), 15u);
}

TEST(GltfModels, AlphaBlendModeTest) {
  LOAD_MODEL_OR_SKIP(s, "AlphaBlendModeTest");
  EXPECT_EQ(s.triangle_count(), 61u);
  EXPECT_EQ(count_mode(s, AlphaMode::PunchThrough), 3u);
  EXPECT_EQ(count_mode(s, AlphaMode::Translucent), 1u);
  EXPECT_EQ(count_mode(s, AlphaMode::Opaque), 2u);
  std::vector<float> cutoffs;
  int mask = -2;
  for (const Material& m : s.materials) {
    if (m.alpha_mode != AlphaMode::PunchThrough) continue;
    cutoffs.push_back(m.alpha_cutoff);
    if (mask == -2) mask = m.alpha_mask;
    EXPECT_EQ(m.alpha_mask, mask);  // the three share one decoded image
  }
  std::sort(cutoffs.begin(), cutoffs.end());
  EXPECT_EQ(cutoffs, (std::vector<float>{0.25f, 0.5f, 0.75f}));
  ASSERT_EQ(s.alpha_masks.size(), 1u);
  ASSERT_EQ(mask, 0);
  const AlphaMask& am = s.alpha_masks[0];
  EXPECT_EQ(am.width, 1024);
  EXPECT_EQ(am.height, 1024);
  EXPECT_NE(std::find(am.alpha.begin(), am.alpha.end(), 0), am.alpha.end());
  EXPECT_NE(std::find(am.alpha.begin(), am.alpha.end(), 255), am.alpha.end());
  // The bed's base color is a 2048^2 progressive JPEG: its SOF2 header gives the size.
  bool found_jpeg = false;
  for (const TextureInfo& t : s.textures)
    if (t.name == "MatBed_baseColor.jpg") {
      found_jpeg = true;
      EXPECT_EQ(t.format, "jpeg");
      EXPECT_EQ(t.width, 2048);
    }
  EXPECT_TRUE(found_jpeg);
}

TEST(GltfModels, LanternWithMissingBaseColor) {
  LOAD_MODEL_OR_SKIP(s, "Lantern");
  EXPECT_EQ(s.triangle_count(), 5394u);
  EXPECT_EQ(s.instances.size(), 3u);
  EXPECT_TRUE(has_warning(s, "Lantern_baseColor.png': file not found"));
}

TEST(GltfModels, BrainStem) {
  LOAD_MODEL_OR_SKIP(s, "BrainStem");
  EXPECT_EQ(s.triangle_count(), 61666u);
  EXPECT_EQ(s.submeshes.size(), 59u);  // one sub-mesh per primitive
}

TEST(GltfModels, CesiumMilkTruckSharesTheWheelMesh) {
  LOAD_MODEL_OR_SKIP(s, "CesiumMilkTruck");
  EXPECT_EQ(s.submeshes.size(), 4u);  // truck body: 3 primitives, wheels: 1
  EXPECT_EQ(s.instances.size(), 5u);  // the wheel sub-mesh is placed by two nodes
  std::uint64_t unique = 0;
  for (const SubMesh& sm : s.submeshes) unique += sm.triangle_count();
  EXPECT_EQ(unique, 2856u);
  EXPECT_EQ(s.triangle_count(), 3624u);
}

TEST(GltfModels, MetalRoughSpheresNoTextures) {
  LOAD_MODEL_OR_SKIP(s, "MetalRoughSpheresNoTextures");
  EXPECT_EQ(s.triangle_count(), 1040409u);
  EXPECT_TRUE(s.textures.empty());
}

TEST(GltfModels, Suzanne) {
  LOAD_MODEL_OR_SKIP(s, "Suzanne");
  EXPECT_EQ(s.triangle_count(), 3936u);
  EXPECT_EQ(s.textures.size(), 2u);
  const Camera cam = framing_camera(s);
  // The framing camera looks down -z at the bounds' center, with the whole scene between near and far.
  EXPECT_NEAR(cam.target.x, s.bounds.center().x, 1e-5f);
  EXPECT_GT(cam.eye.z, s.bounds.max.z);
  EXPECT_LT(cam.near_plane, cam.eye.z - s.bounds.max.z);
  EXPECT_GT(cam.far_plane, cam.eye.z - s.bounds.min.z);
}

}  // namespace
}  // namespace tbdr

// ---- node animation (scene/animation.hpp) ----------------------------------------------------------

namespace tbdr {
namespace {

/// A quad placed by `child` under `parent` (translation 0, 5, 0); animation 0 moves the child
/// along x, LINEAR from (0, 0, 0) at 0 s to (10, 0, 0) at 1 s, and turns the parent about z, STEP:
/// no turn from 0 s, 90 degrees from 0.5 s.
GltfBuilder animated_quad() {
  GltfBuilder g;
  const int pos = g.vec3(quad_positions);
  const int idx = g.indices16({0, 1, 2, 0, 2, 3});
  const int m = g.mesh("Quad", {{"attributes", {{"POSITION", pos}}}, {"indices", idx}});
  const int child = g.node({{"mesh", m}, {"name", "child"}}, false);
  g.node({{"name", "parent"}, {"children", {child}}, {"translation", {0, 5, 0}}});
  const std::vector<float> times{0.0f, 1.0f};
  const int t_in = g.accessor(g.view(times.data(), 8), 5126, 2, "SCALAR");
  const int t_out = g.vec3({0, 0, 0, 10, 0, 0});
  const std::vector<float> step_times{0.0f, 0.5f};
  const int r_in = g.accessor(g.view(step_times.data(), 8), 5126, 2, "SCALAR");
  const float h = std::sqrt(0.5f);
  const std::vector<float> quats{0, 0, 0, 1, 0, 0, h, h};
  const int r_out = g.accessor(g.view(quats.data(), quats.size() * 4), 5126, 2, "VEC4");
  g.doc()["animations"] = json::array({json{
      {"name", "slide"},
      {"channels", json::array({json{{"sampler", 0}, {"target", {{"node", child}, {"path", "translation"}}}},
                                json{{"sampler", 1}, {"target", {{"node", 1}, {"path", "rotation"}}}}})},
      {"samplers", json::array({json{{"input", t_in}, {"output", t_out}},
                                json{{"input", r_in}, {"output", r_out}, {"interpolation", "STEP"}}})}}});
  return g;
}

TEST(GltfAnimation, PosesTheInstancesAtATimeThroughTheirParents) {
  TempDir dir;
  Scene s = load_gltf(animated_quad().write_gltf(dir, "slide"));
  ASSERT_EQ(s.animation.animations.size(), 1u);
  const Animation& a = s.animation.animations[0];
  EXPECT_EQ(a.name, "slide");
  ASSERT_EQ(a.channels.size(), 2u);
  EXPECT_FLOAT_EQ(a.duration_s, 1.0f);
  ASSERT_EQ(s.instances.size(), 1u);
  // Rest: (1, 1, 0) of the quad at (1, 6, 0).
  EXPECT_NEAR((s.instances[0].world * glm::vec4(1, 1, 0, 1)).y, 6.0f, 1e-6f);
  // 0.25 s: the child 2.5 along x, the parent not turned: (1 + 2.5, 1 + 5, 0).
  pose_scene(s, 0, 0.25);
  glm::vec4 p = s.instances[0].world * glm::vec4(1, 1, 0, 1);
  EXPECT_NEAR(p.x, 3.5f, 1e-5f);
  EXPECT_NEAR(p.y, 6.0f, 1e-5f);
  EXPECT_NEAR(s.bounds.max.x, 3.5f, 1e-5f);  // the bounds follow the pose
  // 0.75 s: the child 7.5 along x, (8.5, 1, 0) in the parent, turned 90 degrees about z: (-1, 8.5),
  // then up 5: (-1, 13.5, 0).
  pose_scene(s, 0, 0.75);
  p = s.instances[0].world * glm::vec4(1, 1, 0, 1);
  EXPECT_NEAR(p.x, -1.0f, 1e-5f);
  EXPECT_NEAR(p.y, 13.5f, 1e-5f);
  // Past the last key: the last value.
  pose_scene(s, 0, 5.0);
  EXPECT_NEAR((s.instances[0].world * glm::vec4(0, 0, 0, 1)).y, 15.0f, 1e-5f);
  EXPECT_THROW(pose_scene(s, 1, 0.0), std::out_of_range);
}

TEST(GltfAnimation, ChannelsInterpolateLinearlyStepwiseAndAsCubicSplines) {
  AnimationChannel c;
  c.path = AnimationPath::Translation;
  c.times = {0.0f, 2.0f};
  c.values = {glm::vec4(0.0f), glm::vec4(10.0f, 0, 0, 0)};
  EXPECT_FLOAT_EQ(sample_channel(c, 0.5f).x, 2.5f);
  EXPECT_FLOAT_EQ(sample_channel(c, -1.0f).x, 0.0f);
  c.interpolation = AnimationInterpolation::Step;
  EXPECT_FLOAT_EQ(sample_channel(c, 1.9f).x, 0.0f);
  EXPECT_FLOAT_EQ(sample_channel(c, 2.0f).x, 10.0f);
  // Cubic spline with zero tangents: 10 (3u^2 - 2u^3); at u = 0.25: 10 x (0.1875 - 0.03125) = 1.5625.
  c.interpolation = AnimationInterpolation::CubicSpline;
  c.values = {glm::vec4(0.0f), glm::vec4(0.0f), glm::vec4(0.0f), glm::vec4(0.0f), glm::vec4(10.0f, 0, 0, 0), glm::vec4(0.0f)};
  EXPECT_FLOAT_EQ(sample_channel(c, 0.5f).x, 1.5625f);
  // Rotations slerp: halfway from none to 90 degrees about y is 45 degrees.
  AnimationChannel r;
  r.path = AnimationPath::Rotation;
  r.times = {0.0f, 1.0f};
  const float h = std::sqrt(0.5f);
  r.values = {glm::vec4(0, 0, 0, 1), glm::vec4(0, h, 0, h)};
  const glm::vec4 q = sample_channel(r, 0.5f);
  EXPECT_NEAR(q.y, std::sin(glm::radians(22.5f)), 1e-6f);
  EXPECT_NEAR(q.w, std::cos(glm::radians(22.5f)), 1e-6f);
}

TEST(GltfAnimation, BadChannelsAreRefusedNamingThem) {
  TempDir dir;
  {
    GltfBuilder g = animated_quad();
    g.doc()["animations"][0]["samplers"][0]["interpolation"] = "BOUNCE";
    const std::string path = g.write_gltf(dir, "interp");
    try {
      load_gltf(path);
      ADD_FAILURE() << "loaded";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("animation 0 'slide' sampler 0: interpolation 'BOUNCE'"), std::string::npos) << e.what();
    }
  }
  {
    GltfBuilder g = animated_quad();
    g.doc()["animations"][0]["channels"][1]["target"]["path"] = "rotation";
    g.doc()["animations"][0]["channels"][1]["sampler"] = 0;  // VEC3 values for a rotation
    EXPECT_THROW(load_gltf(g.write_gltf(dir, "output")), InputError);
  }
  {
    GltfBuilder g = animated_quad();
    g.doc()["nodes"][1]["matrix"] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 5, 0, 1};
    g.doc()["nodes"][1].erase("translation");
    EXPECT_THROW(load_gltf(g.write_gltf(dir, "matrix")), InputError);  // animated nodes use TRS
  }
  {
    GltfBuilder g = animated_quad();
    g.doc()["animations"][0]["channels"][0]["target"]["path"] = "weights";
    const Scene s = load_gltf(g.write_gltf(dir, "weights"));
    EXPECT_EQ(s.animation.animations[0].channels.size(), 1u);
    EXPECT_TRUE(std::any_of(s.warnings.begin(), s.warnings.end(), [](const std::string& w) { return w.find("weights") != std::string::npos; }));
  }
}

}  // namespace
}  // namespace tbdr
