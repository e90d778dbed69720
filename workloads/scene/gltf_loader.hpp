#pragma once
// glTF 2.0 loading (.gltf with external or embedded buffers, and .glb) into the Scene data model,
// with the validation tinygltf does not do: byte ranges, attribute types, index ranges, NaNs,
// node cycles and dangling indices. Every failure is an InputError naming the file and the
// accessor, mesh, node or buffer at fault.
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>

#include "scene/scene.hpp"

namespace tbdr {

/// The application-specific glTF attribute (glTF 2.0 section 3.7.2.1: names starting with `_`)
/// holding clip-space positions a captured vertex shader wrote (SubMesh::clip_positions).
inline constexpr const char* kClipPositionAttribute = "_CLIP_POSITION";

/// What an image file's header says, read without decoding the pixels.
struct ImageHeader {
  std::string format;   ///< "png", "jpeg", "gif", "bmp", "ktx2"
  int width = 0;
  int height = 0;
  int channels = 0;     ///< components in the file (PNG palette with tRNS counts as 4)
};

/// Parses the header of a PNG (IHDR), JPEG (first SOFn), GIF, BMP or KTX2 image; nullopt when the
/// bytes are none of these or are truncated.
std::optional<ImageHeader> parse_image_header(const std::uint8_t* data, std::size_t size);

/// Loads a .gltf or .glb file (detected by its magic bytes). Throws InputError on invalid input;
/// non-fatal problems (missing textures, skipped line/point primitives) go to Scene::warnings.
Scene load_gltf(const std::string& path);

}  // namespace tbdr
