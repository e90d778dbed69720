#pragma once
// The command trace: what an application would have submitted for one frame, as technique
// generators (workloads/) write it and the simulator (sim/) replays it. The text format is
// specified in docs/trace-format.md; this header is its data model, the reader and the writer.
//
// A trace has declarations (scene, frame, camera, lights, buffers, shaders, pipelines) and an
// ordered list of commands (render passes with their attachments, pixel local storage and draws;
// compute dispatches; barriers). Every element keeps the line it was read from, so the
// simulator's errors can name file:line too (0 for elements built in memory).
#include <cstdint>
#include <iosfwd>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <variant>
#include <vector>

#include "scene/camera.hpp"
#include "trace/traffic.hpp"
#include "scene/lights.hpp"
#include "scene/scene.hpp"

namespace tbdr {

/// The trace format version this build reads and writes. See docs/trace-format.md for what bumps it.
inline constexpr int kTraceVersion = 5;
/// The version that lets an attachment name a `content=image` buffer (a pass loading the frame a
/// dispatch wrote); version 1 readers refuse the name as a duplicate.
inline constexpr int kImageAttachmentVersion = 2;
/// The version that gives a draw a scissor rectangle (`scissor=`) and an object-culling box
/// (`cull_min=`, `cull_max=`); version 2 readers refuse the keys as unknown.
inline constexpr int kDrawBoundsVersion = 3;
/// The version that lets a trace hold a sequence of frames (a `frame` line after the commands of
/// the one before starts the next); version 3 readers refuse the second `frame` line. A
/// single-frame trace is written as version 3, which every reader since then reads the same.
inline constexpr int kSequenceVersion = 4;
/// The version that gives a pass its own render area (`pass NAME area=x0,y0,x1,y1`: a shadow map,
/// a blur target or a post-processing pass at its own size); version 4 readers refuse the key.
inline constexpr int kPassAreaVersion = 5;
/// The version that gives a shader its vertex stage's cost (`shader ... vertex_alu_ops=N`).
inline constexpr int kVertexCostVersion = 5;

/// Bytes one light occupies in a GPU light buffer: 3 x vec4 (position+radius, color+intensity,
/// direction+cos_inner+cos_outer packed with std140 padding). A `content=lights` buffer holds at
/// least this times the trace's lights (the reader checks it).
inline constexpr std::uint64_t kLightBufferBytesPerLight = 48;

// ---------------------------------------------------------------------------------------------
// Declared limits (docs/limits.md). The reader refuses a trace beyond any of them with file:line,
// before any work, so memory and time follow what a trace asks the GPU to do, never a number it
// merely states. Each has its reason beside it.
// ---------------------------------------------------------------------------------------------

/// The largest trace file (bytes): 1,000,000 lights (the generator's --lights bound) take ~110 MB
/// of `light` lines; twice that leaves room for the rest. Checked before the file is read.
inline constexpr std::uint64_t kMaxTraceBytes = 256ull << 20;
/// The most passes, dispatches and barriers: every technique writes fewer than 20; 65,536 keeps a
/// file of nothing but `barrier` lines (200 MB of them held 2.76 GB before) to a few megabytes.
inline constexpr std::uint64_t kMaxTraceCommands = 65536;
/// The most draws in one trace: forward_multipass at lights_per_pass=1 with 1,000,000 lights
/// draws twice per light (opaque, masked) plus the translucent draw: 2,000,001 < 2^21.
inline constexpr std::uint64_t kMaxTraceDraws = 1ull << 21;
/// The most lights: the generator's bound (`tbdrsim trace --lights`, 0..1,000,000).
inline constexpr std::uint64_t kMaxTraceLights = 1'000'000;
/// The most frames a trace may hold (version 4 sequences): `tbdrsim trace --frames` writes at most
/// 600 (10 s at 60 Hz); 1,000 leaves room for a longer capture.
inline constexpr std::uint64_t kMaxTraceFrames = 1'000;
/// The most declarations (buffers, shaders, pipelines) summed over a sequence's frames: each frame
/// holds every declaration made before it (the reader copies them), so a file of many frames after
/// many declarations would hold frames x declarations of them; 2^20 (about 150 MB at worst) is 600
/// frames of 1,700 declarations, where the techniques declare fewer than 50.
inline constexpr std::uint64_t kMaxSequenceDeclarations = 1ull << 20;
/// The widest and tallest frame in pixels: 16384, the largest render target Vulkan drivers of
/// tile-based GPUs report (maxFramebufferWidth/Height; the Vulkan spec's required minimum is 4096).
inline constexpr std::uint32_t kMaxFrameSide = 16384;
/// The most samples a frame may hold (width x height x samples): 2^28, a 16384 x 16384 frame at
/// one sample or 8K UHD (7680 x 4320) at 8. The simulator keeps per-sample state of every
/// attachment, so this bounds its memory.
inline constexpr std::uint64_t kMaxFrameSamples = 1ull << 28;
/// The largest buffer (bytes): 16 GiB, above any light list a technique sizes for 1,000,000
/// lights at 1080p (cells x max lights x index bytes), far below what would exhaust the host when
/// a pass reads a CPU-filled buffer whole.
inline constexpr std::uint64_t kMaxBufferBytes = 16ull << 30;
/// The largest CPU-filled (`upload=yes`) buffer: a pass reads it whole at its start (one DRAM
/// request per line), so its size is work; 256 MiB holds 1,000,000 lights (48 MB) five times over.
inline constexpr std::uint64_t kMaxUploadBufferBytes = 256ull << 20;
/// Compute dispatch bounds, the Vulkan 1.3 required limits (spec table "Required Limits"):
/// maxComputeWorkGroupCount 65535 per dimension; maxComputeWorkGroupInvocations is at least 128
/// and 1024 on most drivers, the bound used here for group_size's product.
inline constexpr std::uint32_t kMaxDispatchGroups = 65535;
inline constexpr std::uint32_t kMaxWorkGroupInvocations = 1024;
/// Camera bounds that keep the projection finite in float32: a vertical field of view in
/// [0.01, 179] degrees (1/tan of half of it stays below 1.2e4 and above 8.7e-3); clip distances
/// in [1e-6, 1e9] world units (their product and squares stay inside float range) with far/near
/// at most 2^24, the resolution of a 24-bit depth buffer (beyond it the far half of the scene
/// falls on a handful of depth codes); and up at least 0.06 degrees from the view direction
/// (sine 1e-3), below which the camera basis is a float32 rounding error.
inline constexpr float kMinFovYDeg = 0.01f;
inline constexpr float kMaxFovYDeg = 179.0f;
inline constexpr float kMinClipDistance = 1e-6f;
inline constexpr float kMaxClipDistance = 1e9f;
inline constexpr float kMaxFarNearRatio = 16777216.0f;
/// Largest animation index a `pose` line may name: a bound on the reader's integers, far above any
/// file's count (the scene decides whether it has that animation).
inline constexpr int kMaxPoseAnimation = 65535;
/// Latest time a `pose` line may name, seconds (a day): keeps the key search in float range.
inline constexpr double kMaxPoseSeconds = 86400.0;
inline constexpr float kMinUpViewSine = 1e-3f;
/// The largest world coordinate (eye, target, light position and radius), 1e9 world units: the
/// same bound as the far plane, so squared distances stay inside float range.
inline constexpr float kMaxWorldCoordinate = 1e9f;

// ---------------------------------------------------------------------------------------------
// Enums. Each has to_string() giving the trace spelling and parse_<enum>() returning nullopt for
// an unknown spelling (the reader turns that into an InputError naming the token).
// ---------------------------------------------------------------------------------------------

/// Pixel format of an attachment, a pixel-local-storage variable or an image.
enum class Format : std::uint8_t {
  R8, Rg8, Rgba8, Rgb10a2, R11g11b10f, R16f, Rg16f, Rgba16f, R32f, Rg32f, Rgba32f,
  R32ui, Rg32ui, Rgba32ui, D16, D24s8, D32f, D32fs8,
};
/// Bytes one sample of this format occupies (d32fs8: 4 depth + 1 stencil = 5).
std::uint32_t bytes_per_sample(Format f);
/// True for the depth(/stencil) formats d16, d24s8, d32f, d32fs8.
bool is_depth_format(Format f);
/// True for the formats with a stencil component: d24s8, d32fs8.
bool has_stencil(Format f);

/// What a render pass does with an attachment's contents when it begins.
enum class LoadOp : std::uint8_t { Clear, Load, DontCare };
/// What a render pass does with an attachment's contents when it ends.
enum class StoreOp : std::uint8_t { Store, DontCare };
/// What an attachment or buffer holds, for classing its DRAM traffic.
enum class AttachmentUsage : std::uint8_t { Color, Depth, Gbuffer, Visibility };

/// Where the shader gets the lights it evaluates per fragment (the simulator counts them).
enum class LightSource : std::uint8_t {
  None,         ///< evaluates no light
  All,          ///< every light of the draw's light selection
  ObjectList,   ///< the lights whose spheres touch the drawn instance's bounds
  Proxy,        ///< the one light whose proxy geometry (sphere, quad) is being drawn
  TileList,     ///< the lights of the screen tile's list (built by a culling dispatch)
  ClusterList,  ///< the lights of the fragment's cluster list (built by an assignment dispatch)
  PlsStack,     ///< the lights stacked in the pixel's local storage (forward light stack)
};

/// How a shader touches the pass's pixel local storage.
enum class PlsAccess : std::uint8_t { None, Read, Write, ReadWrite };

/// Depth or stencil comparison.
enum class CompareOp : std::uint8_t { Never, Less, Equal, LessEqual, Greater, NotEqual, GreaterEqual, Always };
/// Stencil update operation.
enum class StencilOp : std::uint8_t { Keep, Zero, Replace, Incr, Decr, Invert, IncrWrap, DecrWrap };
/// Color blending of a pipeline: none, additive (src+dst), or alpha (src*a + dst*(1-a)).
enum class BlendMode : std::uint8_t { Off, Add, Alpha };
/// Face culling of a pipeline.
enum class CullMode : std::uint8_t { None, Back, Front };
/// How the ISP treats the drawn fragments for hidden-surface removal: as the material says, or forced.
enum class AlphaOverride : std::uint8_t { Material, Opaque, PunchThrough, Translucent };

/// What geometry a draw submits.
enum class GeometryKind : std::uint8_t {
  Scene,         ///< scene instances (a subset, a sub-mesh or a material)
  Fullscreen,    ///< one triangle covering the whole frame
  LightSpheres,  ///< one icosphere per selected light, enclosing the light's sphere
  LightQuads,    ///< one screen-space quad (2 triangles) per selected light, bounding its projection
};
/// Which scene instances a `draw scene` submits, by material alpha mode.
enum class SceneSubset : std::uint8_t { All, Opaque, Masked, Blended };

/// What a buffer holds (what the kernels and shaders that use it find there).
enum class BufferContent : std::uint8_t {
  Lights,          ///< the light array (positions, radii, colors, spot cones)
  LightIndexList,  ///< packed light indices referenced by a grid
  TileGrid,        ///< per screen tile: offset and count into a light index list
  ClusterGrid,     ///< per cluster: offset and count into a light index list
  UsedClusters,    ///< the compact list of clusters some pixel falls into
  DepthBounds,     ///< per-tile min/max depth
  WorkLists,       ///< per-material tile work lists (visibility buffer)
  Image,           ///< an image written by a compute kernel (e.g. the lit frame)
  Other,           ///< anything else
};

/// Name of the scene source kind.
enum class SceneKind : std::uint8_t { Atrium, Gltf };

/// A compute kernel the simulator implements (docs/kernels.md), as a `dispatch` line names it.
enum class ComputeKernel : std::uint8_t {
  DepthBounds,         ///< depth_bounds: per-tile min/max depth
  TileLightCull,       ///< tile_light_cull: per-tile light lists (Harada; Olsson & Assarsson)
  ClusterFlag,         ///< cluster_flag: the clusters holding visible samples (Olsson)
  ClusterLightAssign,  ///< cluster_light_assign: per-cluster light lists
  DeferredShade,       ///< deferred_shade: shading from G-buffer images
  TiledDeferredShade,  ///< tiled_deferred_shade: Andersson's single-pass tiled deferred shading
  VbufferWorklists,    ///< vbuffer_worklists: per-tile, per-material work lists (Burns & Hunt)
  VbufferShade,        ///< vbuffer_shade: shading from a visibility buffer
  Transfer,            ///< transfer: an application's blit, copy, resolve, clear or fill (memory traffic)
  CapturedCompute,     ///< captured_compute: an application's own compute shader, by its captured cost
};
inline constexpr std::size_t kComputeKernelCount = 10;

/// Every enum above as X(Type, spelling): each has `const char* to_string(Type)` and
/// `std::optional<Type> parse_<spelling>(std::string_view)`, both from one table of spellings
/// (`<spelling>_names` in trace.cpp).
#define TBDR_TRACE_ENUMS(X) \
  X(Format, format) \
  X(LoadOp, load_op) \
  X(StoreOp, store_op) \
  X(AttachmentUsage, attachment_usage) \
  X(LightSource, light_source) \
  X(PlsAccess, pls_access) \
  X(CompareOp, compare_op) \
  X(StencilOp, stencil_op) \
  X(BlendMode, blend_mode) \
  X(CullMode, cull_mode) \
  X(AlphaOverride, alpha_override) \
  X(GeometryKind, geometry_kind) \
  X(SceneSubset, scene_subset) \
  X(BufferContent, buffer_content) \
  X(SceneKind, scene_kind) \
  X(ComputeKernel, compute_kernel)

#define TBDR_DECLARE_TRACE_ENUM(Type, spelling) \
  const char* to_string(Type v);                  \
  std::optional<Type> parse_##spelling(std::string_view s);
TBDR_TRACE_ENUMS(TBDR_DECLARE_TRACE_ENUM)
#undef TBDR_DECLARE_TRACE_ENUM

/// Every kernel's spelling, comma-separated in enum order (for "known: ..." error messages).
std::string compute_kernel_list();
/// The DRAM class a `buffer ... traffic=T` line names; only the classes a buffer can hold
/// (light_data, light_lists, gbuffer, color, depth, visibility, work_lists, other).
std::optional<DramClass> parse_buffer_traffic(std::string_view s);
/// The trace's spelling of a buffer's DRAM class (the inverse of parse_buffer_traffic).
const char* buffer_traffic_name(DramClass c);

// ---------------------------------------------------------------------------------------------
// Declarations
// ---------------------------------------------------------------------------------------------

/// The scene the trace draws: referenced (built-in generator + detail, or glTF path + hash), not copied.
struct TraceScene {
  SceneKind kind = SceneKind::Atrium;
  int detail = 1;            ///< atrium only: the generator's detail level
  std::string path;          ///< gltf only: the file as the generator was given it
  std::string content_hash;  ///< 16 hex digits (fnv1a of the file / generator spec); required for gltf
  int line = 0;
};

/// Frame size and sample count the trace was generated for.
struct TraceFrame {
  int width = 0;    ///< pixels
  int height = 0;   ///< pixels
  int samples = 1;  ///< MSAA samples per pixel: 1, 2, 4 or 8
  int line = 0;
};

/// Which lights (indices into Trace::lights) a draw's shader sees or proxies: all, or ranges.
struct LightSelection {
  bool all = true;
  std::vector<std::pair<std::uint32_t, std::uint32_t>> ranges;  ///< inclusive [first, last], sorted, disjoint, non-adjacent
  bool empty() const { return !all && ranges.empty(); }
  /// Number of lights selected out of `light_count`.
  std::uint64_t count(std::uint64_t light_count) const;
  /// True if light `index` is selected.
  bool contains(std::uint32_t index) const;
};

/// Declared cost and behaviour of a fragment shader. Cost is declared, not executed.
struct ShaderDesc {
  std::string name;
  std::uint32_t alu_ops = 0;        ///< FP32 ALU operations per fragment, excluding lights
  std::uint32_t tex_fetches = 0;    ///< bilinear texture fetches per fragment
  std::uint32_t varyings = 0;       ///< 32-bit components interpolated per fragment
  std::uint32_t light_alu_ops = 0;  ///< FP32 ALU operations per light the fragment evaluates
  LightSource light_source = LightSource::None;
  std::uint32_t color_outputs = 0;  ///< color attachments written (0..8), in declaration order
  PlsAccess pls = PlsAccess::None;
  bool discard = false;             ///< may discard fragments (alpha test): punch-through behaviour
  /// FP32 ALU operations per vertex of the vertex shader the draws with this shader run (version
  /// 5, `vertex_alu_ops=`: a captured vertex shader's cost); none: the hardware parameter
  /// geometry.vertex_shader_alu_ops.
  std::optional<std::uint32_t> vertex_alu_ops;
  int line = 0;
};

/// Fixed-function state and shader of a draw, declared once and referenced by name.
struct PipelineState {
  std::string name;
  std::string shader;                   ///< a ShaderDesc name
  bool depth_test = true;
  bool depth_write = true;
  CompareOp depth_compare = CompareOp::Less;
  bool stencil_test = false;
  CompareOp stencil_compare = CompareOp::Always;
  StencilOp stencil_fail_op = StencilOp::Keep;        ///< stencil test failed
  StencilOp stencil_depth_fail_op = StencilOp::Keep;  ///< stencil passed, depth failed
  StencilOp stencil_pass_op = StencilOp::Keep;        ///< both passed
  std::uint32_t stencil_ref = 0;                      ///< reference value, 0..255
  BlendMode blend = BlendMode::Off;
  CullMode cull = CullMode::Back;
  AlphaOverride alpha = AlphaOverride::Material;
  int line = 0;
};

/// A buffer in DRAM: light data, light lists, grids, work lists.
struct BufferDesc {
  std::string name;
  std::uint64_t bytes = 0;
  DramClass traffic = DramClass::Other;
  BufferContent content = BufferContent::Other;
  bool upload = false;  ///< filled by the CPU before the frame (else a dispatch must write it first)
  int line = 0;
};

// ---------------------------------------------------------------------------------------------
// Commands
// ---------------------------------------------------------------------------------------------

/// A render-pass attachment: one image of frame size. The same name in a later pass is the same
/// image (same format, samples and usage); load=load there reads what an earlier pass stored.
struct Attachment {
  std::string name;
  Format format = Format::Rgba8;
  std::uint32_t samples = 1;  ///< per pixel
  LoadOp load = LoadOp::Clear;
  StoreOp store = StoreOp::Store;
  bool transient = false;     ///< memoryless / lazily allocated: never in DRAM
  AttachmentUsage usage = AttachmentUsage::Color;
  std::string resolve;        ///< name of a 1-sample attachment of the pass this one resolves into, or empty
  int line = 0;
  std::uint32_t bytes_per_pixel() const { return bytes_per_sample(format) * samples; }
};

/// One pixel-local-storage variable; the pass's variables in order make its per-pixel layout.
struct PlsVariable {
  std::string name;
  Format format = Format::Rgba8;
  int line = 0;
};

/// A draw's scissor rectangle (Vulkan vkCmdSetScissor): pixels [x0, x1) x [y0, y1), y down from the
/// top-left pixel. The simulator clamps it to the frame; samples outside it are discarded.
struct ScissorRect {
  std::uint32_t x0 = 0;
  std::uint32_t y0 = 0;
  std::uint32_t x1 = 0;
  std::uint32_t y1 = 0;
  friend bool operator==(const ScissorRect&, const ScissorRect&) = default;
};

/// The world-space box of an application's object culling (closed): a scene draw submits only the
/// instances whose world-space bounding box intersects it, as a renderer that culls its objects
/// against a light's volume before drawing them.
struct CullBox {
  glm::vec3 min{0.0f};  ///< world units, each component <= max's
  glm::vec3 max{0.0f};
  friend bool operator==(const CullBox&, const CullBox&) = default;
};

/// A draw inside a render pass.
struct DrawCmd {
  std::string pipeline;                    ///< a PipelineState name
  GeometryKind geometry = GeometryKind::Scene;
  SceneSubset subset = SceneSubset::All;   ///< scene draws, unless submesh or material is set
  std::string submesh;                     ///< scene draws: only this sub-mesh (by name)
  std::string material;                    ///< scene draws: only sub-meshes with this material (by name)
  LightSelection lights;                   ///< lights the shader sees (light_source=all) or that get proxies
  std::uint32_t subdivisions = 1;          ///< light_spheres: icosphere level (20 * 4^n triangles)
  std::vector<std::string> reads;          ///< buffers and stored images read as textures/buffers (DRAM)
  std::vector<std::string> fetch;          ///< attachments of this pass read at the same pixel, on chip
  std::optional<ScissorRect> scissor;      ///< the scissor rectangle (version 3); none: the whole frame
  std::optional<CullBox> cull;             ///< scene draws: the object-culling box (version 3); none: every instance
  int line = 0;
};

/// A render pass: attachments, pixel local storage layout and draws, replayed tile by tile.
struct PassDesc {
  std::string name;
  std::vector<Attachment> attachments;
  std::vector<PlsVariable> pls;
  std::vector<DrawCmd> draws;
  /// The render area (version 5, Vulkan's VkRenderPassBeginInfo::renderArea): the pass renders,
  /// loads, clears and stores only the pixels [x0, x1) x [y0, y1) of the frame's grid, and only
  /// the tiles that overlap it exist for it. Draws keep the frame's viewport (as in Vulkan, the
  /// area does not rescale them). None: the whole frame.
  std::optional<ScissorRect> area;
  int line = 0;      ///< the `pass` line
  int end_line = 0;  ///< the `end` line
  /// Bytes of pixel local storage per pixel (sum of the variables).
  std::uint32_t pls_bytes_per_pixel() const;
  /// The depth attachment, or nullptr.
  const Attachment* depth_attachment() const;
  /// The attachment of that name, or nullptr.
  const Attachment* find_attachment(std::string_view name) const;
  /// Attachments a shader's color outputs write, in order: non-depth ones that are not resolve targets.
  std::vector<const Attachment*> color_targets() const;
  /// Whether another attachment of the pass resolves into `a` (its MSAA resolve target).
  bool is_resolve_target(const Attachment& a) const;
};

/// A compute dispatch of one of the simulator's kernels. The reader refuses a kernel name that is
/// not a ComputeKernel (file:line); the simulator validates the kernel's parameters.
struct DispatchCmd {
  ComputeKernel kernel = ComputeKernel::DepthBounds;  ///< the kernel the dispatch runs
  std::uint32_t groups[3] = {1, 1, 1};      ///< workgroups in x, y, z
  std::uint32_t group_size[3] = {1, 1, 1};  ///< threads per workgroup in x, y, z
  std::vector<std::string> reads;           ///< buffers and stored images read
  std::vector<std::string> writes;          ///< buffers and images written
  std::map<std::string, std::string> params;  ///< kernel parameters, verbatim
  int line = 0;
  std::uint64_t group_count() const { return std::uint64_t{groups[0]} * groups[1] * groups[2]; }
};

/// A barrier: later work touching `resources` waits until earlier work writing them has finished.
struct BarrierCmd {
  bool all = false;                    ///< every resource (full drain)
  std::vector<std::string> resources;  ///< buffer or image names when not `all`
  int line = 0;
};

/// One step of the frame, in submission order.
using TraceCommand = std::variant<PassDesc, DispatchCmd, BarrierCmd>;

/// A whole frame's trace.
struct Trace {
  int version = kTraceVersion;
  std::string technique;                      ///< generator name, empty for hand-written traces
  std::map<std::string, std::string> options; ///< the generator's options, verbatim
  int technique_line = 0;
  TraceScene scene;
  TraceFrame frame;
  Camera camera;
  std::string camera_name;                    ///< viewpoint name, may be empty
  int camera_line = 0;
  std::vector<Light> lights;
  std::vector<int> light_lines;               ///< source line of each light (same size as lights, or empty)
  /// The frame's pose of an animated glTF scene (`pose animation=I time=S`): its glTF animation I
  /// at S seconds (scene/animation.hpp pose_scene); absent: the scene as the file places it.
  struct Pose {
    int animation = 0;
    double time_s = 0.0;
    int line = 0;
  };
  std::optional<Pose> pose;
  std::vector<BufferDesc> buffers;
  std::vector<ShaderDesc> shaders;
  std::vector<PipelineState> pipelines;
  std::vector<TraceCommand> commands;

  const ShaderDesc* find_shader(std::string_view name) const;
  const PipelineState* find_pipeline(std::string_view name) const;
  const BufferDesc* find_buffer(std::string_view name) const;
};

// ---------------------------------------------------------------------------------------------
// Reading, writing, hashing
// ---------------------------------------------------------------------------------------------

/// Reads and validates a trace file of one frame; every error is an InputError naming path:line
/// and the token. A trace holding a sequence of frames is refused at its second `frame` line
/// (read_trace_frames reads those).
Trace read_trace(const std::string& path);
/// Same, from a stream; `name` is used in error messages in place of the file name. A stream
/// longer than kMaxTraceBytes is refused when the reader gets there.
Trace parse_trace(std::istream& in, const std::string& name);
/// Reads every frame of a trace file, in order (version 4 may hold several, docs/trace-format.md
/// "Sequences"): each a complete Trace with the header lines and every declaration made before
/// its commands (declarations are made once and stay visible in the frames after).
std::vector<Trace> read_trace_frames(const std::string& path);
/// Same, from a stream.
std::vector<Trace> parse_trace_frames(std::istream& in, const std::string& name);
/// Checks what a trace names in its scene, once the scene is loaded and before any work: every
/// draw's `submesh=` and `material=` must name a sub-mesh or material the scene has. InputError
/// naming path:line of the draw, the name and some of the names the scene has.
void check_scene_references(const Trace& trace, const Scene& scene, const std::string& path);
/// Writes the canonical text of a trace (parse_trace of it gives a trace that writes identically).
void write_trace(const Trace& trace, std::ostream& out);
/// Writes the canonical text of a sequence of frames (parse_trace_frames gives them back): the
/// first frame as write_trace does, then per later frame its `frame`, `camera` and `light` lines,
/// the declarations it adds and its commands. The frames share technique, scene and frame size;
/// a declaration of a later frame must equal the earlier one of that name. One frame: write_trace.
void write_trace_frames(const std::vector<Trace>& frames, std::ostream& out);
/// Writes a sequence's canonical text to a file (whole or not at all).
void write_trace_frames_file(const std::vector<Trace>& frames, const std::string& path);
/// Hash of a sequence's canonical text (one frame: trace_hash of it).
std::string trace_hash(const std::vector<Trace>& frames);
/// The canonical text as a string.
std::string trace_text(const Trace& trace);
/// Writes the canonical text to a file; throws InputError if the file cannot be written.
void write_trace_file(const Trace& trace, const std::string& path);
/// Hash of the canonical text, 16 hex digits: identifies a trace in the results database.
std::string trace_hash(const Trace& trace);

}  // namespace tbdr
