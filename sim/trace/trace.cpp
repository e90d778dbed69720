#include "trace/trace.hpp"

#include <algorithm>
#include <array>
#include <sstream>

#include "kernel/hash.hpp"

namespace tbdr {

namespace {

// Spellings, indexed by enum value. One table per enum gives both to_string and parse.
constexpr std::array kFormatNames = {"r8",     "rg8",    "rgba8",  "rgb10a2", "r11g11b10f", "r16f",
                                     "rg16f",  "rgba16f", "r32f",  "rg32f",   "rgba32f",    "r32ui",
                                     "rg32ui", "rgba32ui", "d16",  "d24s8",   "d32f",       "d32fs8"};
constexpr std::array<std::uint32_t, kFormatNames.size()> kFormatBytes = {1, 2, 4, 4, 4, 2, 4, 8, 4,
                                                                         8, 16, 4, 8, 16, 2, 4, 4, 5};
constexpr std::array kLoadOpNames = {"clear", "load", "dont_care"};
constexpr std::array kStoreOpNames = {"store", "dont_care"};
constexpr std::array kUsageNames = {"color", "depth", "gbuffer", "visibility"};
constexpr std::array kLightSourceNames = {"none",     "all",          "object_list", "proxy",
                                          "tile_list", "cluster_list", "pls_stack"};
constexpr std::array kPlsAccessNames = {"none", "read", "write", "read_write"};
constexpr std::array kCompareNames = {"never",     "less",          "equal", "less_equal",
                                      "greater",   "not_equal",     "greater_equal", "always"};
constexpr std::array kStencilOpNames = {"keep", "zero", "replace", "incr", "decr", "invert", "incr_wrap", "decr_wrap"};
constexpr std::array kBlendNames = {"off", "add", "alpha"};
constexpr std::array kCullNames = {"none", "back", "front"};
constexpr std::array kAlphaNames = {"material", "opaque", "punch_through", "translucent"};
constexpr std::array kGeometryNames = {"scene", "fullscreen", "light_spheres", "light_quads"};
constexpr std::array kSubsetNames = {"all", "opaque", "masked", "blended"};
/// The DRAM classes a trace buffer may be booked to, with their trace spellings ("depth" is the
/// database's depth_stencil).
struct BufferTraffic {
  DramClass cls;
  const char* name;
};
constexpr std::array kBufferTraffic = {
    BufferTraffic{DramClass::LightData, "light_data"}, BufferTraffic{DramClass::LightLists, "light_lists"},
    BufferTraffic{DramClass::Gbuffer, "gbuffer"},       BufferTraffic{DramClass::Color, "color"},
    BufferTraffic{DramClass::DepthStencil, "depth"},    BufferTraffic{DramClass::Visibility, "visibility"},
    BufferTraffic{DramClass::WorkLists, "work_lists"},  BufferTraffic{DramClass::Other, "other"}};
constexpr std::array kContentNames = {"lights",       "light_index_list", "tile_grid",  "cluster_grid",
                                      "used_clusters", "depth_bounds",    "work_lists", "image",
                                      "other"};
constexpr std::array kSceneKindNames = {"atrium", "gltf"};
constexpr std::array kComputeKernelNames = {"depth_bounds",   "tile_light_cull",      "cluster_flag",
                                            "cluster_light_assign", "deferred_shade", "tiled_deferred_shade",
                                            "vbuffer_worklists", "vbuffer_shade"};
static_assert(kComputeKernelNames.size() == kComputeKernelCount);

template <typename E, std::size_t N>
const char* name_of(const std::array<const char*, N>& names, E v) {
  const auto i = static_cast<std::size_t>(v);
  return i < N ? names[i] : "?";
}

template <typename E, std::size_t N>
std::optional<E> parse_of(const std::array<const char*, N>& names, std::string_view s) {
  for (std::size_t i = 0; i < N; ++i)
    if (s == names[i]) return static_cast<E>(i);
  return std::nullopt;
}

}  // namespace

std::uint32_t bytes_per_sample(Format f) { return kFormatBytes.at(static_cast<std::size_t>(f)); }
bool is_depth_format(Format f) {
  return f == Format::D16 || f == Format::D24s8 || f == Format::D32f || f == Format::D32fs8;
}
bool has_stencil(Format f) { return f == Format::D24s8 || f == Format::D32fs8; }

const char* to_string(Format v) { return name_of(kFormatNames, v); }
const char* to_string(LoadOp v) { return name_of(kLoadOpNames, v); }
const char* to_string(StoreOp v) { return name_of(kStoreOpNames, v); }
const char* to_string(AttachmentUsage v) { return name_of(kUsageNames, v); }
const char* to_string(LightSource v) { return name_of(kLightSourceNames, v); }
const char* to_string(PlsAccess v) { return name_of(kPlsAccessNames, v); }
const char* to_string(CompareOp v) { return name_of(kCompareNames, v); }
const char* to_string(StencilOp v) { return name_of(kStencilOpNames, v); }
const char* to_string(BlendMode v) { return name_of(kBlendNames, v); }
const char* to_string(CullMode v) { return name_of(kCullNames, v); }
const char* to_string(AlphaOverride v) { return name_of(kAlphaNames, v); }
const char* to_string(GeometryKind v) { return name_of(kGeometryNames, v); }
const char* to_string(SceneSubset v) { return name_of(kSubsetNames, v); }
const char* to_string(BufferContent v) { return name_of(kContentNames, v); }
const char* to_string(SceneKind v) { return name_of(kSceneKindNames, v); }
const char* to_string(ComputeKernel v) { return name_of(kComputeKernelNames, v); }

std::string compute_kernel_list() {
  std::string s;
  for (const char* n : kComputeKernelNames) s += (s.empty() ? "" : ", ") + std::string(n);
  return s;
}

std::optional<Format> parse_format(std::string_view s) { return parse_of<Format>(kFormatNames, s); }
std::optional<LoadOp> parse_load_op(std::string_view s) { return parse_of<LoadOp>(kLoadOpNames, s); }
std::optional<StoreOp> parse_store_op(std::string_view s) { return parse_of<StoreOp>(kStoreOpNames, s); }
std::optional<AttachmentUsage> parse_attachment_usage(std::string_view s) {
  return parse_of<AttachmentUsage>(kUsageNames, s);
}
std::optional<LightSource> parse_light_source(std::string_view s) {
  return parse_of<LightSource>(kLightSourceNames, s);
}
std::optional<PlsAccess> parse_pls_access(std::string_view s) { return parse_of<PlsAccess>(kPlsAccessNames, s); }
std::optional<CompareOp> parse_compare_op(std::string_view s) { return parse_of<CompareOp>(kCompareNames, s); }
std::optional<StencilOp> parse_stencil_op(std::string_view s) { return parse_of<StencilOp>(kStencilOpNames, s); }
std::optional<BlendMode> parse_blend_mode(std::string_view s) { return parse_of<BlendMode>(kBlendNames, s); }
std::optional<CullMode> parse_cull_mode(std::string_view s) { return parse_of<CullMode>(kCullNames, s); }
std::optional<AlphaOverride> parse_alpha_override(std::string_view s) {
  return parse_of<AlphaOverride>(kAlphaNames, s);
}
std::optional<GeometryKind> parse_geometry_kind(std::string_view s) {
  return parse_of<GeometryKind>(kGeometryNames, s);
}
std::optional<SceneSubset> parse_scene_subset(std::string_view s) { return parse_of<SceneSubset>(kSubsetNames, s); }
std::optional<DramClass> parse_buffer_traffic(std::string_view s) {
  for (const auto& t : kBufferTraffic)
    if (s == t.name) return t.cls;
  return std::nullopt;
}
const char* buffer_traffic_name(DramClass c) {
  for (const auto& t : kBufferTraffic)
    if (c == t.cls) return t.name;
  return to_string(c);
}
std::optional<BufferContent> parse_buffer_content(std::string_view s) {
  return parse_of<BufferContent>(kContentNames, s);
}
std::optional<SceneKind> parse_scene_kind(std::string_view s) { return parse_of<SceneKind>(kSceneKindNames, s); }
std::optional<ComputeKernel> parse_compute_kernel(std::string_view s) {
  return parse_of<ComputeKernel>(kComputeKernelNames, s);
}

std::uint64_t LightSelection::count(std::uint64_t light_count) const {
  if (all) return light_count;
  std::uint64_t n = 0;
  for (const auto& [first, last] : ranges) {
    if (first >= light_count) continue;
    const std::uint64_t end = std::min<std::uint64_t>(std::uint64_t{last} + 1, light_count);
    n += end - first;
  }
  return n;
}

bool LightSelection::contains(std::uint32_t index) const {
  if (all) return true;
  for (const auto& [first, last] : ranges)
    if (index >= first && index <= last) return true;
  return false;
}

std::uint32_t PassDesc::pls_bytes_per_pixel() const {
  std::uint32_t bytes = 0;
  for (const auto& v : pls) bytes += bytes_per_sample(v.format);
  return bytes;
}

const Attachment* PassDesc::depth_attachment() const {
  for (const auto& a : attachments)
    if (a.usage == AttachmentUsage::Depth) return &a;
  return nullptr;
}

const Attachment* PassDesc::find_attachment(std::string_view name) const {
  for (const auto& a : attachments)
    if (a.name == name) return &a;
  return nullptr;
}

std::vector<const Attachment*> PassDesc::color_targets() const {
  std::vector<const Attachment*> out;
  for (const auto& a : attachments) {
    if (a.usage == AttachmentUsage::Depth) continue;
    if (!is_resolve_target(a)) out.push_back(&a);
  }
  return out;
}

bool PassDesc::is_resolve_target(const Attachment& a) const {
  return std::any_of(attachments.begin(), attachments.end(), [&](const Attachment& b) { return b.resolve == a.name; });
}

namespace {
template <typename T>
const T* find_named(const std::vector<T>& v, std::string_view name) {
  for (const auto& x : v)
    if (x.name == name) return &x;
  return nullptr;
}
}  // namespace

const ShaderDesc* Trace::find_shader(std::string_view name) const { return find_named(shaders, name); }
const PipelineState* Trace::find_pipeline(std::string_view name) const { return find_named(pipelines, name); }
const BufferDesc* Trace::find_buffer(std::string_view name) const { return find_named(buffers, name); }

std::string trace_text(const Trace& trace) {
  std::ostringstream out;
  write_trace(trace, out);
  return out.str();
}

std::string trace_hash(const Trace& trace) { return fnv1a_hex(trace_text(trace)); }

}  // namespace tbdr
