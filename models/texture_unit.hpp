#pragma once
// The texture unit's addressing, functionally: where every texture a fragment shader samples lives
// in a "texture address space" (byte offsets from 0; the memory system places that space in DRAM),
// and which cache lines the bilinear fetches of one 2x2 quad touch. Nothing is sampled for real:
// only addresses are computed (the image uses the material's constant base colour).
//
// Layout (see docs/hardware-model.md, "Texture addresses"):
// - Fetch slot 0 of a material reads its base colour texture; slot k >= 1 reads a companion
//   texture of the same size (a normal map, ...) with its own storage. A material without a usable
//   texture (none, missing, or 0 texels) samples a 4x4 default texture per slot, shared by all such
//   materials.
// - Regions, in this order: every scene texture some material references as its base colour
//   (by texture index), then the default texture; each holds `slots` copies one after another
//   (slot 0, 1, ...), each copy a full mip chain down to 1x1.
// - A level of w x h texels is padded to powers of two (W2 x H2) and stored as W2*H2/m^2 square
//   blocks of m = min(W2, H2) texels side, each block in Morton (Z) order (x in the even bits,
//   y in the odd bits), blocks one after another along the longer side: PowerVR's twiddled layout.
// - Every level (so every copy and every texture) starts on a multiple of the texture cache line.
#include <array>
#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

namespace tbdr {

struct Scene;
struct HwConfig;

inline constexpr std::uint32_t kMaxTextureLevels = 32;

/// One mip level of a stored texture: its size in texels and where it starts.
struct TextureLevel {
  std::uint32_t width = 0;       ///< texels (w >> level, at least 1)
  std::uint32_t height = 0;      ///< texels
  std::uint32_t block_log2 = 0;  ///< log2 of the side of the Morton-ordered square blocks
  std::uint64_t offset = 0;      ///< bytes from the start of the copy (a multiple of the line size)
  std::uint64_t bytes = 0;       ///< bytes of the padded level (W2 x H2 texels)
  /// Line blocks: with power-of-two texel and line sizes and a power-of-two texture, a line holds
  /// an aligned block of 2^line_x_log2 x 2^line_y_log2 texels, line_cols x line_rows of them
  /// tile the level, and footprints are counted on that grid (QuadFootprint::blocks).
  bool line_blocks = false;
  std::uint32_t line_x_log2 = 0;
  std::uint32_t line_y_log2 = 0;
  std::uint32_t line_cols = 0;
  std::uint32_t line_rows = 0;
};

/// One texture as the texture unit stores it: `slots` copies of a full, twiddled mip chain.
struct TextureStorage {
  std::int32_t scene_texture = -1;  ///< index into Scene::textures, -1 for the default texture
  std::uint32_t width = 0;          ///< level 0 texels
  std::uint32_t height = 0;
  std::uint32_t levels = 0;         ///< down to 1x1 inclusive
  std::array<TextureLevel, kMaxTextureLevels> level{};
  std::uint64_t base = 0;           ///< texture-space offset of slot 0's copy
  std::uint64_t slot_bytes = 0;     ///< bytes of one copy (line aligned)

  /// Texture-space offset of the copy read by fetch slot `slot`.
  std::uint64_t slot_base(std::uint32_t slot) const { return base + std::uint64_t{slot} * slot_bytes; }
  /// Texel index of (x, y) within level `l` in twiddled order (byte offset / bytes per texel).
  std::uint64_t twiddled_index(std::uint32_t l, std::uint32_t x, std::uint32_t y) const;
};

/// The distinct texture lines one quad's bilinear fetches from one copy touch (at most 16).
/// Block form (`blocks`): bit c + 8r of `mask` stands for line block ((base_x + c) mod line_cols,
/// (base_y + r) mod line_rows) of the level, and `lines` is filled only on request
/// (TextureLayout::block_lines); otherwise `lines` holds the lines.
struct QuadFootprint {
  std::array<std::uint64_t, 16> lines{};  ///< texture-space line offsets (no particular order)
  std::uint32_t count = 0;                ///< distinct lines
  std::uint32_t level = 0;                ///< mip level sampled
  bool blocks = false;
  std::uint64_t mask = 0;
  std::uint32_t base_x = 0;
  std::uint32_t base_y = 0;
};

/// The texture address space of a frame: every texture's storage and the quad footprints.
class TextureLayout {
 public:
  static constexpr std::uint32_t kDefaultTextureSize = 4;  ///< side of the default texture

  /// Lays out the textures `scene` references (may be null: default texture only) with `slots`
  /// fetch slots per texture (at least 1), `bytes_per_texel` and `line_bytes` (a power of two).
  TextureLayout(const Scene* scene, std::uint32_t slots, std::uint32_t bytes_per_texel, std::uint32_t line_bytes);
  /// The same from the hardware configuration (texture.bytes_per_texel, cache.texture.line_bytes).
  TextureLayout(const Scene* scene, const HwConfig& hw, std::uint32_t slots);

  /// The storage a material's fetches read (the default texture for an index out of range).
  const TextureStorage& of_material(std::uint32_t material) const {
    return material < material_storage_.size() ? storages_[material_storage_[material]] : storages_.back();
  }
  /// The shared default texture.
  const TextureStorage& default_texture() const { return storages_.back(); }
  /// Every stored texture in address order (the default texture last).
  const std::vector<TextureStorage>& storages() const { return storages_; }
  /// Bytes of the whole texture space (a multiple of the line size).
  std::uint64_t total_bytes() const { return total_bytes_; }
  std::uint32_t slots() const { return slots_; }
  std::uint32_t bytes_per_texel() const { return bytes_per_texel_; }
  std::uint32_t line_bytes() const { return line_bytes_; }

  /// The mip level a quad samples: rho = max(|dUV/dx|, |dUV/dy|) in level-0 texels (coarse
  /// derivatives: uv[1]-uv[0], uv[2]-uv[0]), level = round(log2(rho)) clamped to [0, levels-1].
  /// uv: the quad's pixels (x,y), (x+1,y), (x,y+1), (x+1,y+1).
  std::uint32_t quad_level(const TextureStorage& t, const std::array<glm::vec2, 4>& uv) const;
  /// The distinct lines of slot 0's copy that the bilinear footprints (2x2 texels around each of
  /// the 4 uv, texel centres at +0.5, repeat wrapping) touch at the quad's level. The lines of
  /// slot k are these plus k * t.slot_bytes (copies are line aligned).
  void quad_footprint(const TextureStorage& t, const std::array<glm::vec2, 4>& uv, QuadFootprint& out) const;
  /// The same with the lines left in block form where the level allows it (count, level and mask
  /// set; `lines` filled only for levels without line blocks or unusually spread quads).
  void quad_blocks(const TextureStorage& t, const std::array<glm::vec2, 4>& uv, QuadFootprint& out) const;
  /// Writes the lines of the blocks `bits` (a subset of fp.mask, block form) to `out`; returns how many.
  std::uint32_t block_lines(const TextureStorage& t, const QuadFootprint& fp, std::uint64_t bits,
                            std::uint64_t* out) const;
  /// The blocks of `cur` not among those of `prev` (both of texture t, block form): lines a quad
  /// adds to its neighbour's. All of cur.mask when they cannot be compared.
  std::uint64_t new_blocks(const TextureStorage& t, const QuadFootprint& prev, const QuadFootprint& cur) const;
  /// quad_footprint texel by texel (the reference; quad_footprint counts line blocks when the
  /// level has them and falls back to this otherwise).
  void footprint_by_texel(const TextureStorage& t, const std::array<glm::vec2, 4>& uv, QuadFootprint& out) const;
  /// Appends the distinct lines of slot `slot` to `lines`; returns how many.
  std::uint32_t append_quad_lines(const TextureStorage& t, std::uint32_t slot, const std::array<glm::vec2, 4>& uv,
                                  std::vector<std::uint64_t>& lines) const;

 private:
  void add_storage(std::int32_t scene_texture, std::uint32_t width, std::uint32_t height);
  /// Line offset of texel (x, y) of level `l` (wrapped coordinates).
  std::uint64_t line_of(const TextureStorage& t, std::uint32_t l, std::uint32_t x, std::uint32_t y) const;

  std::uint32_t slots_ = 1;
  std::uint32_t bytes_per_texel_ = 4;
  std::uint32_t line_bytes_ = 64;
  std::uint32_t line_shift_ = 6;
  std::uint32_t texel_shift_ = 2;  ///< log2 bytes per texel (used only when that is a power of two)
  bool line_pow2_ = true;
  std::uint64_t total_bytes_ = 0;
  std::vector<TextureStorage> storages_;          ///< address order, default texture last
  std::vector<std::uint32_t> material_storage_;   ///< per scene material: index into storages_
};

}  // namespace tbdr
