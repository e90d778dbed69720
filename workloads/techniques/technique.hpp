#pragma once
// Technique generators: one per many-light rendering technique, each turning a scene, camera,
// light set and frame size into the command trace an application would submit (trace/trace.hpp).
//
// Adding a technique: write workloads/techniques/<name>.cpp defining
//   TechniqueInfo technique_<name>();
// (name, summary, options with defaults and docs, generator function) and add one line
// X(<name>) to TBDR_TECHNIQUE_LIST in workloads/techniques/technique.cpp. The generators share the
// building blocks below: the same pipeline states, attachments, shader costs, light lists and
// passes are written once here.
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

/// How a frame sequence's camera and lights move (`tbdrsim trace --frames`).
struct SequenceMotion {
  int frames = 1;                         ///< frames in the sequence, 1..kMaxSequenceFrames
  CameraPath camera = CameraPath::Static;
  LightMotion lights = LightMotion::Static;
  /// Frame k's camera, when given (a camera path file: read_camera_path_file), instead of `camera`'s path.
  std::vector<Camera> cameras;
  /// The scene's glTF animation to play (-1: none): frame k is posed at k / animation_fps seconds
  /// (the trace's `pose` line).
  int animation = -1;
  double animation_fps = kDefaultAnimationFps;
  /// Frames per second of the animation's clock: a 60 Hz display's.
  static constexpr double kDefaultAnimationFps = 60.0;
};
/// The most frames `tbdrsim trace --frames` writes: 10 s at 60 frames per second.
inline constexpr int kMaxSequenceFrames = 600;
/// Generates the frames of `technique` along `motion`: frame k is the technique's trace of `setup`
/// with the camera and lights moved to frame k, validated through the reader as one sequence.
/// A buffer whose size a generator derives from what the frame sees (its light lists) is
/// declared at the largest size any frame needs, as an application allocates it once; any other
/// declaration that differs between frames is a generator bug (std::logic_error).
std::vector<Trace> generate_sequence(const std::string& technique, const TraceSetup& setup, const SequenceMotion& motion);

// ---- starting a trace -----------------------------------------------------------------------------

/// What a technique cannot do, checked by begin_trace() before anything is written.
struct TechniqueLimits {
  std::string no_msaa = {};   ///< why the technique cannot use MSAA ("" when it can)
  bool needs_lights = false;  ///< its kernels cull the light array into lists: at least one light
};
/// Why a technique shading from a one-sample G-buffer cannot use MSAA (Billeter 2015: MSAA no).
inline constexpr const char* kGbufferNoMsaa = "its G-buffer holds one surface per pixel (Billeter 2015: MSAA no)";

/// The trace's scene line for the setup: atrium + detail, or glTF path + content hash.
TraceScene trace_scene_for(const TraceSetup& setup);
/// A trace with the header declarations filled in: technique and resolved options, scene,
/// frame, camera and lights. Generators add buffers, shaders, pipelines and commands. Throws
/// InputError naming the technique when the setup exceeds its `limits` (MSAA, no light).
Trace begin_trace(const TraceSetup& setup, const std::string& technique, const TechniqueOptions& options,
                  const TechniqueLimits& limits = {});
/// Declares the uploaded light array as buffer `lights` (traffic light_data) and returns its name,
/// or returns "" when the setup has no lights (nothing to read).
std::string add_light_buffer(Trace& trace);

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
/// Varyings of the texture coordinate alone (what the alpha test of a shader without uv adds).
inline constexpr std::uint32_t kUvVaryings = 2;
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
/// Threads of a cluster_light_assign workgroup, looping over the lights for one cluster.
inline constexpr std::uint32_t kAssignGroupThreads = 64;

// ---- shaders ---------------------------------------------------------------------------------------

/// A fragment shader declaration in one call.
ShaderDesc make_shader(const std::string& name, std::uint32_t alu_ops, std::uint32_t tex_fetches,
                       std::uint32_t varyings, std::uint32_t light_alu_ops, LightSource source,
                       std::uint32_t color_outputs, PlsAccess pls = PlsAccess::None, bool discard = false);
/// The punch-through (MASK) variant of scene shader `s`: named `<name>_masked`, + kAlphaTestAluOps,
/// may discard. A shader that does not sample the base color adds its alpha fetch (`alpha_fetches`)
/// and, without a uv, the uv varyings (`uv_varyings`).
ShaderDesc masked_variant(const ShaderDesc& s, std::uint32_t alpha_fetches = 0, std::uint32_t uv_varyings = 0);
/// The G-buffer writing shader `name`: surface + encode (+ kGbufferExtraTargetAluOps per extra
/// target), kSurfaceTexFetches, kSurfaceVaryings, `color_outputs` targets (0 when it writes PLS).
ShaderDesc gbuffer_shader(const std::string& name, std::uint32_t extra_targets, std::uint32_t color_outputs,
                          PlsAccess pls = PlsAccess::None);
/// A light proxy's shader `name` (the light-volume techniques): decode the surface (+1 per extra
/// target), reconstruct the position from depth and output (17 ALU with no extra target),
/// `fetches` G-buffer reads, the view ray (kProxyVaryings) and kLightAluOps for its light.
ShaderDesc light_volume_shader(const std::string& name, std::uint32_t fetches, std::uint32_t extra_targets,
                               std::uint32_t color_outputs, PlsAccess pls = PlsAccess::None);

// ---- pipeline states -------------------------------------------------------------------------------

/// Opaque scene geometry: depth test less with write, no blending, back faces culled.
PipelineState depth_writing_pipeline(const std::string& name, const std::string& shader);
/// Shading exactly the depth a pre-pass stored (PreZ or reloaded): test equal without write, `blend`;
/// punch-through geometry is forced opaque (its discarded samples fail the equal test anyway).
PipelineState depth_equal_pipeline(const std::string& name, const std::string& shader,
                                   BlendMode blend = BlendMode::Off);
/// Translucent geometry over the opaque frame: depth test less without write, alpha blending.
PipelineState blended_pipeline(const std::string& name, const std::string& shader);
/// Light proxies: back faces (cull=front) that pass depth greater_equal reach the surfaces inside
/// the volume; no depth write, `blend`.
PipelineState light_volume_pipeline(const std::string& name, const std::string& shader, BlendMode blend);
/// A fullscreen draw: no depth test, no culling, no blending.
PipelineState fullscreen_pipeline(const std::string& name, const std::string& shader);

// ---- attachments and buffers -----------------------------------------------------------------------

/// An attachment in one call.
Attachment make_attachment(const std::string& name, Format format, std::uint32_t samples, LoadOp load, StoreOp store,
                           AttachmentUsage usage, bool transient = false);
/// The frame's D24S8 depth attachment `name` with `samples` samples; transient (never in DRAM) when
/// it is neither loaded nor stored.
Attachment depth_attachment(std::uint32_t samples, LoadOp load, StoreOp store, const std::string& name = "depth");
/// Adds the frame's color target `name` (stored): 1-sample, or with MSAA a transient multisampled
/// `<name>_ms` that resolves into it on chip (only the resolved color leaves the chip).
void add_color_target(PassDesc& pass, const std::string& name, std::uint32_t samples, Format format = Format::Rgba8);
/// A render pass `name` that clears and stores the frame's color (add_color_target) over the depth
/// `depth`: cleared and transient (never in DRAM), or loaded (`depth_load`, a stored pre-pass depth)
/// and not stored again.
PassDesc color_pass(const std::string& name, std::uint32_t samples, LoadOp depth_load = LoadOp::Clear,
                    const std::string& depth = "depth");
/// Declares a DRAM buffer written by a dispatch (upload=no) and returns its name.
std::string add_buffer(Trace& trace, const std::string& name, std::uint64_t bytes, DramClass traffic,
                       BufferContent content, bool upload = false);
/// Declares the lit frame a shading kernel writes: buffer `color`, rgba8 (W x H x 4 bytes), content
/// image; returns its name.
std::string add_frame_buffer(Trace& trace, const TraceSetup& setup);

// ---- commands --------------------------------------------------------------------------------------

/// A draw; `reads` entries that are empty (e.g. no light buffer) are dropped.
DrawCmd make_draw(GeometryKind geometry, const std::string& pipeline, const std::vector<std::string>& reads = {},
                  const std::vector<std::string>& fetch = {});
/// A scene draw of one subset.
DrawCmd scene_draw(SceneSubset subset, const std::string& pipeline, const std::vector<std::string>& reads = {},
                   const std::vector<std::string>& fetch = {});
/// Appends the opaque scene draw with pipeline `opaque` and the punch-through one with `masked`.
void add_scene_draws(PassDesc& pass, const std::string& opaque, const std::string& masked,
                     const std::vector<std::string>& reads = {});
/// Declares scene shader `shader` and its punch-through variant `masked`, their depth-writing
/// pipelines `pipeline` and `<pipeline>_masked`, and appends the opaque and masked draws to `pass`.
void add_scene_shading(Trace& trace, PassDesc& pass, const std::string& pipeline, const ShaderDesc& shader,
                       const ShaderDesc& masked, const std::vector<std::string>& reads = {});
/// A dispatch; `reads`/`writes` entries that are empty are dropped.
DispatchCmd make_dispatch(ComputeKernel kernel, std::uint32_t groups_x, std::uint32_t groups_y,
                          std::uint32_t groups_z, std::uint32_t size_x, std::uint32_t size_y, std::uint32_t size_z,
                          const std::vector<std::string>& reads, const std::vector<std::string>& writes,
                          const std::map<std::string, std::string>& params);
/// A barrier on the named resources.
BarrierCmd make_barrier(const std::vector<std::string>& resources);

// ---- what one light reaches ---------------------------------------------------------------------------

/// What one light can reach, as a renderer that draws per light sets up the light's draws: the
/// screen rectangle of its sphere (the scissor, Vulkan vkCmdSetScissor) and the sphere's world box
/// (the object culling). Lights contribute exactly 0 at and beyond their radius
/// (scene/lights.hpp), so a draw limited to both shades every non-zero contribution.
struct LightReach {
  bool visible = false;  ///< some pixel of the frame may see a point inside the sphere
  bool full_frame = false;  ///< the sphere reaches the near plane (or holds the eye): every pixel
  ScissorRect rect;      ///< the pixels the sphere can cover (the frame when full_frame), if visible
  CullBox box;           ///< the sphere's world-space bounding box, padded by kLightBoxMargin*
};
/// The padding of a light's culling box: kLightBoxMarginRadius of its radius plus
/// kLightBoxMarginCoordinate of its largest coordinate. Float rounding of centre +- radius and of
/// interpolated surface positions is a few ulps (2^-23 relative) of the coordinates: 2^-20 of them
/// (8 ulps) and 2^-10 of the radius keep every point the shading's radius test accepts inside.
inline constexpr float kLightBoxMarginRadius = 1.0f / 1024.0f;
inline constexpr float kLightBoxMarginCoordinate = 1.0f / 1048576.0f;
/// Pixels of margin around a sphere's projected rectangle: float rounding of the projection stays
/// far below a pixel (the same margin as the simulator's light_screen_rect).
inline constexpr int kLightRectMarginPx = 1;
/// What `light` reaches seen by `camera` in a `width` x `height` frame: the view-space box of the
/// sphere projected (its 8 corners; the projection of a convex box in front of the camera is the
/// hull of its corners' projections) and widened by kLightRectMarginPx. A sphere wholly behind the
/// near plane or off the frame is not visible.
LightReach light_reach(const Light& light, const Camera& camera, int width, int height);

// ---- sizes and options ---------------------------------------------------------------------------------

/// Number of `tile_px` tiles covering `pixels` (rounded up).
std::uint32_t tiles_for(int pixels, std::uint32_t tile_px);
/// Workgroup edge of a per-tile kernel: the tile, at most kKernelGroupEdge (bigger tiles loop).
std::uint32_t kernel_group_edge(std::uint32_t tile_px);
/// The `key` option as light index bytes: "auto" (the smallest size that addresses every light: 1
/// byte up to 256 lights, 2 up to 65536, else 4) or 1, 2, 4; InputError when too small to address
/// `light_count` lights.
std::uint32_t index_bytes_option(const TechniqueOptions& options, const std::string& key, std::size_t light_count);
/// The `key` option as a light-list cap: "all" (the light count, so no list can overflow and the
/// image stays exact) or a count in [1, 65535], never more than the light count.
std::uint32_t list_cap_option(const TechniqueOptions& options, const std::string& key, std::size_t light_count);

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
/// The `translucent` option of the deferred techniques: true for "forward" (draw BLEND materials
/// in a forward pass over the lit frame), false for "skip".
bool translucent_forward_option(const TechniqueOptions& options);
/// The `translucent` option of the compute-shaded techniques (add_translucent_pass), declared once.
TechniqueOption translucent_pass_declaration();
/// The `sphere_subdivisions` option of the light-volume techniques, declared once.
TechniqueOption sphere_subdivisions_declaration();
/// The `sphere_subdivisions` option's value: the icosphere level of the light proxies, 0..6.
std::uint32_t sphere_subdivisions_option(const TechniqueOptions& options);

/// Number of materials in the setup's scene (loads the scene when only a spec is given).
std::size_t scene_material_count(const TraceSetup& setup);

// ---- passes shared by several techniques -----------------------------------------------------------

/// Declares the depth-only pre-pass shaders and pipelines (`prez`, `prez_masked`: 0 ALU for opaque;
/// the alpha test, one fetch and the uv for punch-through materials) and appends their draws
/// (opaque, then masked) to `pass`.
void add_prez(Trace& trace, PassDesc& pass);
/// Declares the forward shader and pipeline for translucent (BLEND) geometry drawn over a finished
/// opaque frame: lights from the per-object lists (Billeter's "assign lights per geometry batch"),
/// depth test without write, alpha blending: pipeline `translucent`.
void add_translucent_state(Trace& trace);
/// Appends the translucent draw (subset blended, pipeline `translucent`) to `pass`.
void add_translucent_draw(PassDesc& pass, const std::string& lights);
/// The transparency pass of the compute-shaded techniques (tiled and clustered deferred, the
/// visibility buffer), as engines composite transparency over a compute-lit frame: when option
/// `translucent` is forward and the frame has 1 sample, a barrier on the lit frame `frame` (the
/// image buffer the shading kernel wrote), then pass `translucent` whose color attachment is that
/// image (rgba8, loaded and stored again) over the stored depth `depth` (loaded, not stored),
/// drawing the BLEND geometry as add_translucent_state / add_translucent_draw. With MSAA the stored
/// depth is multisampled and the frame is not: nothing is added.
void add_translucent_pass(Trace& trace, const TraceSetup& setup, const TechniqueOptions& options,
                          const std::string& frame, const std::string& lights, const std::string& depth = "depth");
/// Declares the fullscreen `ambient` shader and pipeline (ambient + output, one fetch) and appends
/// its draw, reading `source` (the albedo or normal buffer), to `pass`: the ambient term once per
/// pixel before the light volumes add theirs.
void add_ambient(Trace& trace, PassDesc& pass, const std::string& source);
/// Appends the light proxies (one icosphere of `subdivisions` per light) drawn with `pipeline` to
/// `pass`, reading `reads` and the light buffer and fetching `fetch` on chip; none without lights.
void add_light_volumes(PassDesc& pass, const std::string& pipeline, const std::string& lights,
                       std::uint32_t subdivisions, std::vector<std::string> reads = {},
                       const std::vector<std::string>& fetch = {});

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

/// Declares the G-buffer shaders (`gbuffer`, `gbuffer_masked`: gbuffer_shader with one color output
/// per target) and pipelines, and returns a pass `name` that clears and stores every target of
/// `layout` and a d24s8 depth, drawing the opaque and masked geometry. 1 sample (deferred).
PassDesc make_gbuffer_pass(Trace& trace, const GbufferLayout& layout, const std::string& name = "gbuffer");

/// A compute-shaded deferred technique's trace as it is built (tiled and clustered deferred): begun
/// (no MSAA: kGbufferNoMsaa; at least one light), with its light buffer and the G-buffer layout of
/// option `gbuffer`.
struct ComputeDeferred {
  Trace trace;
  std::string lights;    ///< the light buffer
  GbufferLayout layout;  ///< option `gbuffer`
};
/// Begins the trace of compute-shaded deferred technique `technique` (see ComputeDeferred).
ComputeDeferred begin_compute_deferred(const TraceSetup& setup, const std::string& technique,
                                       const TechniqueOptions& options);

/// What the shading kernel of a compute-shaded deferred technique reads and writes.
struct ShadedGbuffer {
  std::vector<std::string> stored;  ///< the G-buffer targets and depth, as the G-buffer pass stored them
  std::string frame;                ///< the lit frame buffer the kernel writes (add_frame_buffer)
};
/// The G-buffer half of the compute-shaded deferred techniques (tiled and clustered deferred):
/// declares the frame buffer and the shader `shader` whose cost the shading kernel charges per pixel
/// (decode (+1 per extra target) + position reconstruction + `lookup_alu_ops` + ambient + output;
/// one fetch per target and one for depth; kLightAluOps per light from `source`), then appends the
/// G-buffer pass of `layout` and a barrier on what it stored.
ShadedGbuffer add_compute_gbuffer(Trace& trace, const TraceSetup& setup, const GbufferLayout& layout,
                                  const std::string& shader, std::uint32_t lookup_alu_ops, LightSource source);
/// Ends a compute-shaded deferred trace: the shading dispatch `kernel` (shading_dispatch of shader
/// `shader`, `tile_px` and `params`) reading what the G-buffer pass stored, the lights and
/// `extra_reads` and writing the lit frame, then add_translucent_pass. Returns the trace.
Trace finish_compute_deferred(ComputeDeferred& c, const ShadedGbuffer& g, const TraceSetup& setup,
                              const TechniqueOptions& options, ComputeKernel kernel, const std::string& shader,
                              std::uint32_t tile_px, const std::vector<std::string>& extra_reads,
                              std::map<std::string, std::string> params = {});

// ---- light lists ---------------------------------------------------------------------------------------

/// A grid of light lists over the frame (docs/kernels.md): screen tiles, or clusters (tiles cut in
/// depth slices). Each cell has an (offset, count) entry in the grid buffer (`tile_grid` or
/// `cluster_grid`) and room for `max_lights` indices in `light_index`.
struct LightGrid {
  bool clusters = false;          ///< depth-sliced clusters (else screen tiles)
  int width = 1;                  ///< frame pixels covered
  int height = 1;
  std::uint32_t tile_px = 16;     ///< screen tile edge in pixels
  std::uint32_t slices = 1;       ///< clusters: depth slices
  bool cubical = false;           ///< clusters: slicing=cubical from min_depth (else log)
  float min_depth = 0.0f;         ///< cubical: start of the first slice, world units
  std::uint32_t max_lights = 1;   ///< list cap per cell: sizes the index list
  std::uint32_t index_bytes = 4;  ///< bytes per light index in the list

  std::uint32_t tiles_x() const { return tiles_for(width, tile_px); }
  std::uint32_t tiles_y() const { return tiles_for(height, tile_px); }
  std::uint64_t cells() const;  ///< tiles x slices (tiles have one slice)
  std::uint32_t group_edge() const;  ///< kernel_group_edge(tile_px)
  /// Name of the grid buffer: `cluster_grid` or `tile_grid`.
  std::string grid_buffer() const { return clusters ? "cluster_grid" : "tile_grid"; }
  /// The cluster kernels' grid parameters: tile_px, slices, slicing (and min_depth when cubical).
  std::map<std::string, std::string> cluster_params() const;
};
/// Name of the light index list buffer of a LightGrid.
inline constexpr const char* kLightIndexBuffer = "light_index";
/// How a technique's options describe its light grid (each reads them in this order).
enum class GridOptions : std::uint8_t {
  Tiles,        ///< tile_px (4..256), max_lights_per_tile, index_bytes
  LogClusters,  ///< tile_px (4..1024), slices (1..1024, exponential), max_lights_per_cluster, index_bytes
  /// tile_px (4..1024), min_depth (auto: 10 x near, at most far/2), slices (auto or a maximum,
  /// 1..4096: as many near-cubical slices as reach the far plane, the formula of docs/kernels.md),
  /// max_lights_per_cluster, index_bytes
  CubicalClusters,
};
/// The light grid over the setup's frame as the technique's options give it (`form`); list caps
/// with list_cap_option, index sizes with index_bytes_option.
LightGrid light_grid_option(const TraceSetup& setup, const TechniqueOptions& options, GridOptions form);
/// Declares the grid buffer (kGridEntryBytes per cell) and `light_index` (max_lights x index_bytes
/// per cell), both written by kernels.
void add_light_grid_buffers(Trace& trace, const LightGrid& grid);
/// Declares `used_clusters` (a 4-byte counter and kUsedClusterEntryBytes per cluster) and returns its name.
std::string add_used_clusters_buffer(Trace& trace, const LightGrid& grid);
/// The tile_light_cull dispatch: one group per tile reads the stored depth and the lights and
/// writes the tile grid's lists (capped at max_lights).
DispatchCmd tile_light_cull_dispatch(const LightGrid& grid, const std::string& lights);
/// Appends cluster_flag (one group per tile: the clusters that hold a stored depth sample go to
/// `used`), a barrier on `used` and cluster_light_assign dense=no over the used clusters.
void add_sparse_cluster_assignment(Trace& trace, const LightGrid& grid, const std::string& lights,
                                   const std::string& used);
/// The cluster_light_assign dense=yes dispatch: every cluster of the grid, whatever the geometry.
DispatchCmd dense_cluster_assignment(const LightGrid& grid, const std::string& lights);

/// A shading kernel's dispatch over the frame (tiled_deferred_shade, deferred_shade, vbuffer_shade):
/// one group per `tile_px` tile (kernel_group_edge threads on a side), the
/// per-pixel cost of shader `shader`, reading `reads` and writing the lit frame `frame`; `params`
/// adds to shader and tile_px.
DispatchCmd shading_dispatch(ComputeKernel kernel, const std::string& shader, const TraceSetup& setup,
                             std::uint32_t tile_px, const std::vector<std::string>& reads, const std::string& frame,
                             std::map<std::string, std::string> params = {});

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
  LightGrid grid;             ///< clusters for the cluster kinds
  bool prez = true;           ///< dense: depth-only pre-pass in the same render pass
  bool depth_reload = true;   ///< tiles/sparse: forward pass loads the pre-pass depth, tests equal
};
/// Writes the trace of a light-grid forward technique (see LightGridConfig).
Trace generate_light_grid_forward(const TraceSetup& setup, const TechniqueOptions& options, const LightGridConfig& c);

}  // namespace tbdr
