#pragma once
// The scene data model every loader produces (glTF files, the built-in atrium) and every later
// stage consumes (trace generators, the geometry unit). Geometry is kept in object space per
// sub-mesh and placed by instances, as a glTF node hierarchy places meshes.
#include <cstdint>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "scene/animation.hpp"

namespace tbdr {

/// How a material's fragments interact with hidden-surface removal.
enum class AlphaMode : std::uint8_t {
  Opaque,        ///< glTF OPAQUE: writes depth, HSR may discard hidden samples before shading
  PunchThrough,  ///< glTF MASK: alpha-tested; depth known only after the shader ran
  Translucent,   ///< glTF BLEND: blended over what is behind, never hides anything
};
const char* to_string(AlphaMode m);

/// A decoded single-channel alpha mask (8 bits per texel), kept only for punch-through
/// materials so that which samples an alpha test discards is computed, not estimated.
struct AlphaMask {
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> alpha;  ///< row-major, width*height texels
  /// Alpha in [0,1] at texture coordinate uv, nearest texel, repeat wrapping.
  float sample(glm::vec2 uv) const;
};

/// A decoded base colour image (RGBA8, sRGB-encoded colour as glTF stores it), kept so the shader
/// samples the albedo it is charged for fetching.
struct ColorTexels {
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> rgba;  ///< row-major, width*height*4
  /// Linear RGB at texture coordinate uv: the nearest texel at the base level with repeat
  /// wrapping (AlphaMask::sample's convention), its sRGB colour decoded (glTF 2.0: "The base
  /// color texture MUST contain 8-bit values encoded with the sRGB opto-electronic transfer function").
  glm::vec3 sample_linear_rgb(glm::vec2 uv) const;
  /// Whether all width x height texels are held (else only the size: SceneLoadOptions).
  bool decoded() const { return width > 0 && height > 0 && rgba.size() >= static_cast<std::size_t>(width) * static_cast<std::size_t>(height) * 4; }
  /// The RGBA8 texel sample_linear_rgb(uv) reads, or nullptr where it reads none (not decoded, uv
  /// not finite): where not null, sample_linear_rgb(uv) == linear_rgb(texel_at(uv)).
  const std::uint8_t* texel_at(glm::vec2 uv) const;
  /// Linear RGB of an RGBA8 texel's sRGB codes.
  static glm::vec3 linear_rgb(const std::uint8_t* texel);
};

/// A texture as the GPU would hold it: size and format read from the image header.
struct TextureInfo {
  std::string name;      ///< uri or image name
  std::string format;    ///< container format: "png", "jpeg", "procedural", ...
  int width = 0;
  int height = 0;
  int channels = 0;
  bool missing = false;  ///< file absent: counted with 0 bytes and a warning
  /// Bytes resident in GPU memory: RGBA8 (4 bytes per texel) with a full mip chain, the exact
  /// sum over levels down to 1x1 (about x4/3 of the base level); 0 when missing.
  std::uint64_t gpu_bytes() const;
};

/// A glTF material reduced to what the simulator needs.
struct Material {
  std::string name;
  AlphaMode alpha_mode = AlphaMode::Opaque;
  float alpha_cutoff = 0.5f;            ///< punch-through threshold (glTF default 0.5)
  bool double_sided = false;            ///< disables back-face culling
  glm::vec4 base_color{1.0f};           ///< linear RGBA base color factor
  int base_color_texture = -1;          ///< index into Scene::textures, -1 for none
  int alpha_mask = -1;                  ///< index into Scene::alpha_masks (punch-through only)
  int base_color_texels = -1;           ///< index into Scene::base_color_texels, -1 when not decoded
};

/// A triangle list with one material: the unit a draw call submits.
struct SubMesh {
  std::string name;
  std::uint32_t material = 0;           ///< index into Scene::materials
  std::vector<glm::vec3> positions;     ///< object space
  /// Clip-space positions (x, y, z, w; OpenGL convention: -w <= x, y, z <= w inside, y up) that a
  /// captured vertex shader already computed (glTF attribute `_CLIP_POSITION`, docs/capture-import.md).
  /// When present (same count as positions) the geometry unit takes them as they are: no instance
  /// or camera transform. Empty for ordinary meshes.
  std::vector<glm::vec4> clip_positions;
  std::vector<glm::vec3> normals;       ///< object space, same count as positions (generated if absent)
  std::vector<glm::vec2> uvs;           ///< same count as positions (zeros if absent)
  std::vector<std::uint32_t> indices;   ///< triangle list, 3 per triangle, all < positions.size()
  std::uint32_t vertex_stride_bytes = 32;  ///< bytes the vertex fetch reads per vertex (attribute layout)
  std::uint32_t index_bytes = 4;        ///< bytes per index in the source buffer (1, 2 or 4); 0 for a
                                        ///< non-indexed draw (indices are then generated 0..n-1)
  std::uint32_t triangle_count() const { return static_cast<std::uint32_t>(indices.size() / 3); }
};

/// A placement of a sub-mesh in the world (a flattened glTF node).
struct Instance {
  std::uint32_t submesh = 0;            ///< index into Scene::submeshes
  glm::mat4 world{1.0f};                ///< object to world
  std::string node;                     ///< name of the node it came from
};

/// World-space axis-aligned bounds.
struct Bounds {
  glm::vec3 min{0.0f};
  glm::vec3 max{0.0f};
  glm::vec3 center() const { return (min + max) * 0.5f; }
  glm::vec3 extent() const { return max - min; }
};

/// A loaded scene: what a trace's `scene` line refers to.
struct Scene {
  std::string name;                     ///< "atrium" or the file's stem
  std::string source;                   ///< "atrium:2" or the path it was loaded from
  std::string content_hash;             ///< fnv1a of the file bytes (or of the generator's spec)
  std::vector<Material> materials;
  std::vector<TextureInfo> textures;
  std::vector<AlphaMask> alpha_masks;
  std::vector<ColorTexels> base_color_texels;  ///< decoded base colour images (Material::base_color_texels)
  std::vector<SubMesh> submeshes;
  std::vector<Instance> instances;
  Bounds bounds;                        ///< world-space bounds of all instances
  std::vector<std::string> warnings;    ///< non-fatal problems (missing textures, skipped lines/points)
  SceneAnimation animation;             ///< node hierarchy and glTF animations (pose_scene)

  std::uint64_t triangle_count() const; ///< over instances
  std::uint64_t vertex_count() const;   ///< over instances
};

/// Recomputes scene.bounds from every instance's transformed vertices (zero bounds when empty).
void update_bounds(Scene& scene);

}  // namespace tbdr
