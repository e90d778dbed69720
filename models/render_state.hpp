#pragma once
// State shared by the units of one render: the resolved draws, the primitives the geometry unit
// produced (what the parameter buffer holds), and the frame's attachment images. Each unit owns
// its own logic; these are the data that flow between them.
#include <cstdint>
#include <limits>
#include <map>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "models/hw_config.hpp"
#include "models/rasterizer.hpp"
#include "sim/trace.hpp"
#include "workloads/camera.hpp"
#include "workloads/scene.hpp"

namespace tbdr {

/// The camera as the units use it: matrices and the eye position.
struct CameraXform {
  glm::mat4 view{1.0f};
  glm::mat4 proj{1.0f};
  glm::mat4 view_proj{1.0f};
  glm::vec3 eye{0.0f};
  float near_plane = 0.1f;
  static CameraXform from(const Camera& camera, float aspect);
};

/// How hidden-surface removal treats a primitive's fragments.
enum class HsrClass : std::uint8_t {
  Opaque,        ///< depth known at rasterisation: tags overwrite tags, shading deferred
  PunchThrough,  ///< alpha-tested / discard: shaded before its depth can be written
  Translucent,   ///< blended: what is beneath must be shaded first; never hides anything
};
const char* to_string(HsrClass c);

inline constexpr std::uint32_t kNoMaterial = std::numeric_limits<std::uint32_t>::max();

/// A draw resolved against the trace and the scene: what every unit needs to know about it.
struct DrawContext {
  const DrawCmd* cmd = nullptr;
  const PipelineState* pipeline = nullptr;
  const ShaderDesc* shader = nullptr;
  std::vector<std::uint32_t> lights;  ///< indices of the lights the draw selects
  std::vector<std::uint8_t> light_selected;  ///< per light of the trace: 1 when selected
  std::uint32_t pass_draw_index = 0;  ///< position of the draw in its pass
};

/// One primitive after the geometry unit: rasteriser setup plus the original triangle's
/// attributes for the shader (perspective-correct barycentrics weight these).
struct Primitive {
  TriangleSetup setup;
  std::uint32_t draw = 0;          ///< index into the render's DrawContext table
  std::uint32_t object = 0;        ///< index into the render's object table (object light lists)
  std::uint32_t material = kNoMaterial;
  std::int32_t proxy_light = -1;   ///< the light a proxy primitive stands for
  HsrClass hsr = HsrClass::Opaque;
  std::uint32_t varyings = 0;      ///< 32-bit varyings stored per vertex in the parameter buffer
  std::array<glm::vec3, 3> world{};   ///< original triangle, world space
  std::array<glm::vec3, 3> normal{};  ///< original triangle, world space
  std::array<glm::vec2, 3> uv{};      ///< original triangle
  std::array<std::uint64_t, 3> vertex_key{};  ///< identity of each vertex (re-use within a primitive block)
};

/// An attachment's contents for the whole frame (kept across passes by name).
struct AttachmentImage {
  Format format = Format::Rgba8;
  std::uint32_t samples = 1;
  AttachmentUsage usage = AttachmentUsage::Color;
  bool defined = false;               ///< holds stored contents a later pass may load
  std::vector<glm::vec4> color;       ///< width*height*samples, color-like formats
  std::vector<float> depth;           ///< width*height*samples, depth formats
  std::vector<std::uint8_t> stencil;  ///< width*height*samples, depth formats
};

/// Per-pixel observations for the images written with --images.
struct PixelCounters {
  std::vector<std::uint32_t> rasterised_samples;  ///< overdraw: depth-tested samples per pixel
  std::vector<std::uint32_t> shaded;               ///< shader invocations per pixel (helpers excluded)
  std::vector<std::uint32_t> lights_evaluated;     ///< lights evaluated per pixel, all invocations
  std::vector<std::uint32_t> triangle_id;          ///< last primitive shaded at the pixel (+1, 0 none)
  void resize(std::size_t pixels);
};

/// The frame's images and per-pixel counters.
struct FrameImages {
  int width = 0;
  int height = 0;
  std::map<std::string, AttachmentImage> attachments;
  PixelCounters counters;
};

}  // namespace tbdr

namespace tbdr {

/// Everything the fragment units (ISP, TSP, tile memory) read while rendering one pass's tiles.
struct RenderContext {
  const HwConfig* hw = nullptr;
  const Scene* scene = nullptr;
  const std::vector<Light>* lights = nullptr;
  CameraXform camera;
  Viewport viewport;
  SamplePattern pattern;
  const PassDesc* pass = nullptr;
  FrameImages* images = nullptr;
  bool defer_shading = true;                  ///< tbdr: tag buffer HSR; tbr/imr: shade at early-Z
  bool framebuffer_in_dram = false;           ///< imr: attachments live in DRAM, no tile memory
  std::vector<DrawContext> draws;             ///< the pass's draws, resolved
  std::vector<std::vector<std::uint32_t>> object_lights;  ///< per object: lights touching it
  std::vector<Primitive> prims;               ///< the render's primitives (parameter buffer contents)
  std::vector<AttachmentImage*> color_targets;  ///< images the shaders' color outputs write, in order
  AttachmentImage* depth = nullptr;           ///< the pass's depth attachment image, or nullptr
  /// Lights whose screen rectangle overlaps each shading tile (an exact-result acceleration of
  /// the image computation only; what a technique is charged for comes from its light source).
  int light_tile_px = 32;
  int light_tiles_x = 0;
  std::vector<std::vector<std::uint32_t>> light_tiles;
};

}  // namespace tbdr
