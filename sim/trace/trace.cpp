#include "trace/trace.hpp"

#include <algorithm>
#include <array>
#include <sstream>

#include "kernel/errors.hpp"
#include "kernel/hash.hpp"

namespace tbdr {

namespace {

// Spellings, indexed by enum value, named <spelling>_names after TBDR_TRACE_ENUMS. One table per
// enum gives both to_string and parse.
constexpr std::array format_names = {"r8",     "rg8",    "rgba8",  "rgb10a2", "r11g11b10f", "r16f",
                                     "rg16f",  "rgba16f", "r32f",  "rg32f",   "rgba32f",    "r32ui",
                                     "rg32ui", "rgba32ui", "d16",  "d24s8",   "d32f",       "d32fs8"};
constexpr std::array<std::uint32_t, format_names.size()> kFormatBytes = {1, 2, 4, 4, 4, 2, 4, 8, 4,
                                                                         8, 16, 4, 8, 16, 2, 4, 4, 5};
constexpr std::array load_op_names = {"clear", "load", "dont_care"};
constexpr std::array store_op_names = {"store", "dont_care"};
constexpr std::array attachment_usage_names = {"color", "depth", "gbuffer", "visibility"};
constexpr std::array light_source_names = {"none",     "all",          "object_list", "proxy",
                                          "tile_list", "cluster_list", "pls_stack"};
constexpr std::array pls_access_names = {"none", "read", "write", "read_write"};
constexpr std::array compare_op_names = {"never",     "less",          "equal", "less_equal",
                                      "greater",   "not_equal",     "greater_equal", "always"};
constexpr std::array stencil_op_names = {"keep", "zero", "replace", "incr", "decr", "invert", "incr_wrap", "decr_wrap"};
constexpr std::array blend_mode_names = {"off", "add", "alpha"};
constexpr std::array cull_mode_names = {"none", "back", "front"};
constexpr std::array alpha_override_names = {"material", "opaque", "punch_through", "translucent"};
constexpr std::array geometry_kind_names = {"scene", "fullscreen", "light_spheres", "light_quads"};
constexpr std::array scene_subset_names = {"all", "opaque", "masked", "blended"};
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
constexpr std::array buffer_content_names = {"lights",       "light_index_list", "tile_grid",  "cluster_grid",
                                      "used_clusters", "depth_bounds",    "work_lists", "image",
                                      "other"};
constexpr std::array scene_kind_names = {"atrium", "gltf"};
constexpr std::array compute_kernel_names = {"depth_bounds",   "tile_light_cull",      "cluster_flag",
                                            "cluster_light_assign", "deferred_shade", "tiled_deferred_shade",
                                            "vbuffer_worklists", "vbuffer_shade", "transfer", "captured_compute"};
static_assert(compute_kernel_names.size() == kComputeKernelCount);

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

#define TBDR_DEFINE_TRACE_ENUM(Type, spelling)                                                 \
  const char* to_string(Type v) { return name_of(spelling##_names, v); }                     \
  std::optional<Type> parse_##spelling(std::string_view s) { return parse_of<Type>(spelling##_names, s); }
TBDR_TRACE_ENUMS(TBDR_DEFINE_TRACE_ENUM)
#undef TBDR_DEFINE_TRACE_ENUM

std::string compute_kernel_list() {
  std::string s;
  for (const char* n : compute_kernel_names) s += (s.empty() ? "" : ", ") + std::string(n);
  return s;
}

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

std::string trace_hash(const std::vector<Trace>& frames) {
  std::ostringstream out;
  write_trace_frames(frames, out);
  return fnv1a_hex(out.str());
}

namespace {

/// "'a', 'b', 'c' (and 12 more)": the first few names of a list, for an error message.
std::string some_names(const std::vector<std::string>& names) {
  constexpr std::size_t kShown = 8;  // enough to spot a typo, short enough for one line
  std::string out;
  for (std::size_t i = 0; i < names.size() && i < kShown; ++i) out += (i ? ", '" : "'") + names[i] + "'";
  if (names.size() > kShown) out += " (and " + std::to_string(names.size() - kShown) + " more)";
  return names.empty() ? "none" : out;
}

}  // namespace

void check_scene_references(const Trace& trace, const Scene& scene, const std::string& path) {
  if (trace.pose && static_cast<std::size_t>(trace.pose->animation) >= scene.animation.animations.size()) {
    throw InputError(path, trace.pose->line,
                     "pose animation " + std::to_string(trace.pose->animation) + ": scene " + scene.source + " has " +
                         std::to_string(scene.animation.animations.size()) + " animation(s)");
  }
  std::vector<std::string> submeshes, materials;
  for (const auto& sm : scene.submeshes) submeshes.push_back(sm.name);
  for (const auto& m : scene.materials) materials.push_back(m.name);
  auto has = [](const std::vector<std::string>& v, const std::string& n) {
    return std::find(v.begin(), v.end(), n) != v.end();
  };
  for (const auto& cmd : trace.commands) {
    const auto* pass = std::get_if<PassDesc>(&cmd);
    if (!pass) continue;
    for (const auto& d : pass->draws) {
      if (!d.submesh.empty() && !has(submeshes, d.submesh)) {
        throw InputError(path, d.line, "draw names submesh='" + d.submesh + "', which scene '" + scene.source +
                                           "' does not have (its sub-meshes: " + some_names(submeshes) + ")");
      }
      if (!d.material.empty() && !has(materials, d.material)) {
        throw InputError(path, d.line, "draw names material='" + d.material + "', which scene '" + scene.source +
                                           "' does not have (its materials: " + some_names(materials) + ")");
      }
    }
  }
}

}  // namespace tbdr
