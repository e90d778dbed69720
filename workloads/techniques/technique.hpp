#pragma once
// Technique generators: one per many-light rendering technique, each turning a scene, camera,
// light set and frame size into the command trace an application would submit (sim/trace.hpp).
//
// Adding a technique: write workloads/techniques/<name>.cpp defining
//   TechniqueInfo technique_<name>();
// (name, summary, options with defaults and docs, generator function) and add one line
// X(<name>) to TBDR_TECHNIQUE_LIST in workloads/technique.cpp.
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "trace/trace.hpp"
#include "scene/camera.hpp"
#include "scene/lights.hpp"
#include "scene/scene.hpp"

namespace tbdr {

/// Everything a technique generator needs to write one frame's trace.
struct TraceSetup {
  const Scene* scene = nullptr;  ///< the loaded scene (sub-mesh/material names, bounds, hash); may be null for atrium
  std::string scene_spec;        ///< as the user gave it: "atrium", "atrium:2" or a glTF path
  Camera camera;
  std::string camera_name;       ///< viewpoint name, may be empty
  LightSet lights;
  int width = 1280;              ///< pixels
  int height = 720;              ///< pixels
  int samples = 1;               ///< MSAA samples per pixel: 1, 2, 4 (or 8)
  std::map<std::string, std::string> options;  ///< technique options, key=value, validated against TechniqueInfo
};

/// One option a technique accepts: its key, default value (as text) and what it means, declared once.
struct TechniqueOption {
  std::string key;
  std::string default_value;
  std::string doc;
};

struct TechniqueInfo;

/// A technique's options for one generate_trace() call: the given values over the declared defaults.
class TechniqueOptions {
 public:
  /// Throws InputError naming the option if a key is not declared by the technique.
  TechniqueOptions(const TechniqueInfo& info, const std::map<std::string, std::string>& given);
  /// The value as text (given or default).
  const std::string& get(const std::string& key) const;
  /// Integer in [min, max]; throws InputError naming the option if malformed or out of range.
  std::int64_t get_int(const std::string& key, std::int64_t min, std::int64_t max) const;
  /// Finite float in [min, max]; throws InputError naming the option if malformed or out of range.
  float get_float(const std::string& key, float min, float max) const;
  /// yes/no (also true/false, on/off, 1/0).
  bool get_bool(const std::string& key) const;
  /// Every declared option with its resolved value: what the trace records.
  const std::map<std::string, std::string>& resolved() const { return values_; }

 private:
  std::string technique_;
  std::map<std::string, std::string> values_;
};

/// Signature of a technique generator.
using TraceGenerator = Trace (*)(const TraceSetup& setup, const TechniqueOptions& options);

/// A registered technique.
struct TechniqueInfo {
  std::string name;                      ///< identifier used on the command line and in the trace
  std::string summary;                   ///< one line: what it does and where it comes from
  std::vector<TechniqueOption> options;  ///< every option it reads, with defaults
  TraceGenerator generate = nullptr;
};

/// Every registered technique, in registry order.
const std::vector<TechniqueInfo>& techniques();
/// Names of the registered techniques, in registry order.
std::vector<std::string> technique_names();
/// The technique of that name; throws InputError listing the known techniques otherwise.
const TechniqueInfo& find_technique(const std::string& name);
/// Generates the trace of `technique` for `setup`, validated by writing and re-reading it (so
/// commands carry the line numbers of the canonical text). Throws InputError for an unknown
/// technique (listing the known ones), an unknown or malformed option, or an unusable setup.
Trace generate_trace(const std::string& technique, const TraceSetup& setup);

// ---- helpers shared by the generators ----------------------------------------------------------

/// Bytes one light occupies in a GPU light buffer: 3 x vec4 (position+radius, color+intensity,
/// direction+cos_inner+cos_outer packed with std140 padding).
inline constexpr std::uint64_t kLightBufferBytesPerLight = 48;

/// The trace's scene line for the setup: atrium + detail, or glTF path + content hash.
TraceScene trace_scene_for(const TraceSetup& setup);
/// A trace with the header declarations filled in: technique and resolved options, scene,
/// frame, camera and lights. Generators add buffers, shaders, pipelines and commands.
Trace begin_trace(const TraceSetup& setup, const std::string& technique, const TechniqueOptions& options);
/// Declares the uploaded light array as buffer `name` (traffic light_data) and returns its name,
/// or returns "" when the setup has no lights (nothing to read).
std::string add_light_buffer(Trace& trace, const std::string& name = "lights");

// ---- shader costs shared by every generator ------------------------------------------------------
//
// The same material and lighting math costs the same in every technique, so comparisons measure
// the techniques' structure, not different guesses. plain_forward's default lit shader is
// kSurfaceAluOps + kAmbientAluOps + kOutputAluOps = 20 ALU ops, 2 texture fetches, 8 varyings and
// kLightAluOps = 12 per light; every other technique builds its shaders from these pieces (see
// docs/techniques.md for each shader's sum).

/// Surface evaluation: renormalise the interpolated normal and apply the normal map (~6), base
/// color x texture x material factors (~6).
inline constexpr std::uint32_t kSurfaceAluOps = 12;
/// Texture fetches of the surface: base color (with alpha) and normal map.
inline constexpr std::uint32_t kSurfaceTexFetches = 2;
/// Varyings of a scene fragment: world position (3), normal (3), uv (2).
inline constexpr std::uint32_t kSurfaceVaryings = 8;
/// The normal part of the surface alone (light pre-pass geometry pass): renormalise + normal map.
inline constexpr std::uint32_t kNormalAluOps = 6;
/// Varyings of a normal-only scene fragment: normal (3), uv (2).
inline constexpr std::uint32_t kNormalVaryings = 5;
/// Ambient term: albedo x ambient constant (3 multiplies).
inline constexpr std::uint32_t kAmbientAluOps = 3;
/// Final color: sum, saturate and convert to the output format (~5).
inline constexpr std::uint32_t kOutputAluOps = 5;
/// Per light evaluated: vector to the light and distance (~5: sub, dot, rsqrt, mul), finite-radius
/// attenuation (1-(d/r)^2)^2 (~3), N.L clamp (~2), accumulate (~2).
inline constexpr std::uint32_t kLightAluOps = 12;
/// Alpha test of a punch-through (MASK) material: compare and discard.
inline constexpr std::uint32_t kAlphaTestAluOps = 1;
/// Writing albedo + normal to a G-buffer (or PLS): normal scale-bias to unsigned (3), packing (1).
inline constexpr std::uint32_t kGbufferEncodeAluOps = 4;
/// Reading albedo + normal back: unpack (1), normal bias-scale (3).
inline constexpr std::uint32_t kGbufferDecodeAluOps = 4;
/// Each G-buffer target beyond albedo and normal (specular, motion, ...): one pack or unpack.
inline constexpr std::uint32_t kGbufferExtraTargetAluOps = 1;
/// World position from the depth buffer and the pixel: NDC (2), view ray scale (3), to world (3).
inline constexpr std::uint32_t kPositionReconstructAluOps = 8;
/// Varyings of a light-volume fragment: the view ray used for position reconstruction.
inline constexpr std::uint32_t kProxyVaryings = 3;
/// Finding the fragment's screen tile in a tile grid: two scales and a multiply-add.
inline constexpr std::uint32_t kTileLookupAluOps = 3;
/// Finding the fragment's cluster: tile index (3), depth slice log/scale/floor/clamp (3).
inline constexpr std::uint32_t kClusterLookupAluOps = 6;
/// Reading the per-pixel light stack from PLS: unpack count, loop set-up.
inline constexpr std::uint32_t kPlsStackReadAluOps = 2;
/// Pushing a light index onto the PLS stack: read count, compare with capacity, write, increment.
inline constexpr std::uint32_t kPlsStackPushAluOps = 4;
/// Writing a visibility id: pack triangle id and instance id.
inline constexpr std::uint32_t kVisibilityIdAluOps = 2;
/// Rebuilding a surface from a visibility id (Burns & Hunt): transform the triangle's 3 vertices
/// (3 x 25: position mat4 16 + normal mat3 9), barycentrics with perspective correction (~20),
/// interpolate 8 attributes (~16), uv derivatives for the texture LOD (~9).
inline constexpr std::uint32_t kVisibilityReconstructAluOps = 120;

/// The lit forward shader's ALU ops per fragment, excluding lights (20, as plain_forward).
inline constexpr std::uint32_t kForwardLitAluOps = kSurfaceAluOps + kAmbientAluOps + kOutputAluOps;

// ---- list and grid formats ------------------------------------------------------------------------

/// Bytes of one grid entry (a tile's or a cluster's offset and count into the index list: 2 x u32).
inline constexpr std::uint64_t kGridEntryBytes = 8;
/// Bytes of one used-cluster entry (a cluster id, u32); the used list also has a 4-byte counter.
inline constexpr std::uint64_t kUsedClusterEntryBytes = 4;
/// Workgroup edge of the screen-space kernels (16 x 16 = 256 threads; bigger tiles loop).
inline constexpr std::uint32_t kKernelGroupEdge = 16;

// ---- building blocks for generators ---------------------------------------------------------------

/// A fragment shader declaration in one call.
ShaderDesc make_shader(const std::string& name, std::uint32_t alu_ops, std::uint32_t tex_fetches,
                       std::uint32_t varyings, std::uint32_t light_alu_ops, LightSource source,
                       std::uint32_t color_outputs, PlsAccess pls = PlsAccess::None, bool discard = false);
/// A pipeline declaration in one call (no stencil).
PipelineState make_pipeline(const std::string& name, const std::string& shader, bool depth_test, bool depth_write,
                            CompareOp compare, BlendMode blend, CullMode cull,
                            AlphaOverride alpha = AlphaOverride::Material);
/// An attachment in one call.
Attachment make_attachment(const std::string& name, Format format, std::uint32_t samples, LoadOp load, StoreOp store,
                           AttachmentUsage usage, bool transient = false);
/// Adds the frame's color target `name` (stored): 1-sample, or with MSAA a transient multisampled
/// `<name>_ms` that resolves into it on chip (only the resolved color leaves the chip).
void add_color_target(PassDesc& pass, const std::string& name, std::uint32_t samples, Format format = Format::Rgba8);
/// A draw; `reads` entries that are empty (e.g. no light buffer) are dropped.
DrawCmd make_draw(GeometryKind geometry, const std::string& pipeline, const std::vector<std::string>& reads = {},
                  const std::vector<std::string>& fetch = {});
/// A scene draw of one subset.
DrawCmd scene_draw(SceneSubset subset, const std::string& pipeline, const std::vector<std::string>& reads = {},
                   const std::vector<std::string>& fetch = {});
/// Declares a DRAM buffer written by a dispatch (upload=no) and returns its name.
std::string add_buffer(Trace& trace, const std::string& name, std::uint64_t bytes, TrafficClass traffic,
                       BufferContent content, bool upload = false);
/// A dispatch; `reads`/`writes` entries that are empty are dropped.
DispatchCmd make_dispatch(const std::string& kernel, std::uint32_t groups_x, std::uint32_t groups_y,
                          std::uint32_t groups_z, std::uint32_t size_x, std::uint32_t size_y, std::uint32_t size_z,
                          const std::vector<std::string>& reads, const std::vector<std::string>& writes,
                          const std::map<std::string, std::string>& params);
/// A barrier on the named resources.
BarrierCmd make_barrier(const std::vector<std::string>& resources);

/// Throws InputError naming the technique when the setup asks for MSAA (`why`: the reason).
void reject_msaa(const TraceSetup& setup, const std::string& technique, const std::string& why);
/// Throws InputError naming the technique when the setup has no light (its kernels need some).
void require_lights(const TraceSetup& setup, const std::string& technique);

/// Number of `tile_px` tiles covering `pixels` (rounded up).
std::uint32_t tiles_for(int pixels, std::uint32_t tile_px);
/// Smallest light index size that addresses every light: 1 byte up to 256 lights, 2 up to 65536, else 4.
std::uint32_t index_bytes_for(std::size_t light_count);
/// The `key` option as light index bytes: "auto" (index_bytes_for) or 1, 2, 4; InputError when too
/// small to address `light_count` lights.
std::uint32_t index_bytes_option(const TechniqueOptions& options, const std::string& key, std::size_t light_count);
/// The `key` option as a light-list cap: "all" (the light count, so no list can overflow and the
/// image stays exact) or a count in [1, 65535], never more than the light count.
std::uint32_t list_cap_option(const TechniqueOptions& options, const std::string& key, std::size_t light_count);
/// Number of depth slices of a cubical cluster grid (docs/kernels.md, Billeter 2015): as many as
/// reach the far plane from `min_depth` with tiles of `tile_px`, at most `max_slices`. The same
/// formula the cluster kernels use, so buffer sizes match their grids.
std::uint32_t cubical_slice_count(const Camera& camera, int height, std::uint32_t tile_px, float min_depth,
                                  std::uint32_t max_slices);

/// A G-buffer layout: the color targets of a G-buffer pass, albedo first, normal second, then
/// extra targets (specular, motion, ...) that only cost bandwidth and encode/decode work.
struct GbufferLayout {
  std::vector<std::string> names;  ///< albedo, normal, gbuffer2, gbuffer3, ...
  std::vector<Format> formats;
  std::uint32_t bytes_per_sample() const;  ///< sum of the targets, depth excluded
  std::uint32_t extra_targets() const { return names.size() > 2 ? static_cast<std::uint32_t>(names.size() - 2) : 0; }
};
/// Parses the `key` option: 2 to 8 comma-separated color formats (e.g. "rgba8,rgb10a2").
GbufferLayout gbuffer_layout_option(const TechniqueOptions& options, const std::string& key);
/// Parses the `key` option as one non-depth format.
Format color_format_option(const TechniqueOptions& options, const std::string& key);

/// Number of materials in the setup's scene (loads the scene when only a spec is given).
std::size_t scene_material_count(const TraceSetup& setup);

/// Declares the depth-only pre-pass shaders and pipelines (`prez`, `prez_masked`): 0 ALU for opaque;
/// the alpha test (kAlphaTestAluOps, 1 fetch, uv varyings) for punch-through materials.
void add_prez_state(Trace& trace);
/// Appends the pre-pass draws (opaque, then masked) to `pass`.
void add_prez_draws(PassDesc& pass);
/// Declares the forward shader and pipeline for translucent (BLEND) geometry drawn over a finished
/// opaque frame: lights from the per-object lists (Billeter's "assign lights per geometry batch"),
/// depth test without write, alpha blending. Returns the pipeline name (`translucent`).
std::string add_translucent_state(Trace& trace);
/// Appends the translucent draw (subset blended, pipeline `translucent`) to `pass`.
void add_translucent_draw(PassDesc& pass, const std::string& lights);
/// The `translucent` option of the deferred techniques: true for "forward" (draw BLEND materials
/// in a forward pass over the lit frame), false for "skip".
bool translucent_forward_option(const TechniqueOptions& options);

/// How a forward pass shades its opaque and punch-through geometry.
struct ForwardLitSpec {
  std::string shader = "forward_lit";      ///< shader name (masked variant: <shader>_masked)
  LightSource source = LightSource::All;   ///< where the lights come from
  std::uint32_t extra_alu_ops = 0;         ///< e.g. the light-list lookup
  PlsAccess pls = PlsAccess::None;
  bool depth_primed = false;  ///< depth already holds the final opaque depth (PreZ or reloaded): test
                              ///< equal without write and without alpha test (the pre-pass ran it)
  std::vector<std::string> reads;  ///< buffers the shader reads (empty names dropped)
};
/// Declares the lit forward shader(s) and pipeline(s) of `spec` and appends the opaque and masked
/// draws to `pass`. Cost: kForwardLitAluOps + extra, kSurfaceTexFetches, kSurfaceVaryings,
/// kLightAluOps per light; +kAlphaTestAluOps and discard for masked geometry unless depth_primed.
void add_forward_lit(Trace& trace, PassDesc& pass, const ForwardLitSpec& spec);

/// Declares the G-buffer shaders (`gbuffer`, `gbuffer_masked`: surface + encode, one color output
/// per target) and pipelines, and returns a pass `name` that clears and stores every target of
/// `layout` and a d24s8 depth, drawing the opaque and masked geometry. 1 sample (deferred).
PassDesc make_gbuffer_pass(Trace& trace, const GbufferLayout& layout, const std::string& name = "gbuffer");

/// The light-grid forward family: Forward+ (tiles), clustered forward (sparse clusters from a
/// stored depth pre-pass), practical and cascaded clustered forward (dense clusters assigned up front).
struct LightGridConfig {
  /// What the grid is and how it is built.
  enum class Kind : std::uint8_t {
    Tiles,           ///< depth pre-pass stored, tile_light_cull, forward pass with tile_list
    SparseClusters,  ///< depth pre-pass stored, cluster_flag, cluster_light_assign over used clusters
    DenseClusters,   ///< cluster_light_assign dense=yes before the frame's only render pass
  };
  std::string technique;
  Kind kind = Kind::Tiles;
  std::uint32_t tile_px = 16;
  std::uint32_t slices = 1;         ///< clusters: depth slices (cubical: the count that reaches far)
  bool cubical = false;             ///< clusters: slicing=cubical (else log)
  float min_depth = 0.0f;           ///< cubical: start of the first slice, world units
  std::uint32_t max_lights = 1;     ///< list cap: sizes the index list (and is tile_light_cull's cap)
  std::uint32_t index_bytes = 4;    ///< bytes per light index in the list
  bool prez = true;                 ///< dense: depth-only pre-pass in the same render pass
  bool depth_reload = true;         ///< tiles/sparse: forward pass loads the pre-pass depth, tests equal
};
/// Writes the trace of a light-grid forward technique (see LightGridConfig).
Trace generate_light_grid_forward(const TraceSetup& setup, const TechniqueOptions& options, const LightGridConfig& c);

}  // namespace tbdr
