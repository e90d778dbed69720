#include "techniques/technique.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <optional>
#include <sstream>
#include <stdexcept>

#include "kernel/errors.hpp"
#include "kernel/hash.hpp"
#include "scene/scene_library.hpp"

namespace tbdr {

// The registry: one line per technique. Each X(name) needs `TechniqueInfo technique_name();`
// defined in workloads/techniques/name.cpp.
#define TBDR_TECHNIQUE_LIST(X) \
  X(plain_forward)                 \
  X(forward_multipass)             \
  X(deferred)                      \
  X(tiled_deferred)                \
  X(clustered_deferred)            \
  X(forward_plus)                  \
  X(clustered_forward)             \
  X(practical_clustered_forward)   \
  X(cascaded_clustered_forward)    \
  X(deferred_tile_store)           \
  X(forward_light_stack)           \
  X(visibility_buffer)             \
  X(light_prepass)

#define TBDR_DECLARE_TECHNIQUE(name) TechniqueInfo technique_##name();
TBDR_TECHNIQUE_LIST(TBDR_DECLARE_TECHNIQUE)
#undef TBDR_DECLARE_TECHNIQUE

const std::vector<TechniqueInfo>& techniques() {
#define TBDR_TECHNIQUE_ENTRY(name) technique_##name(),
  static const std::vector<TechniqueInfo> registry = {TBDR_TECHNIQUE_LIST(TBDR_TECHNIQUE_ENTRY)};
#undef TBDR_TECHNIQUE_ENTRY
  return registry;
}

std::vector<std::string> technique_names() {
  std::vector<std::string> names;
  for (const auto& t : techniques()) names.push_back(t.name);
  return names;
}

const TechniqueInfo& find_technique(const std::string& name) {
  for (const auto& t : techniques())
    if (t.name == name) return t;
  std::string known;
  for (const auto& n : technique_names()) known += (known.empty() ? "" : ", ") + n;
  throw InputError("technique " + name, "unknown technique '" + name + "' (known: " + known + ")");
}

// ---- options -------------------------------------------------------------------------------------

TechniqueOptions::TechniqueOptions(const TechniqueInfo& info, const std::map<std::string, std::string>& given)
    : technique_(info.name) {
  for (const auto& o : info.options) values_[o.key] = o.default_value;
  for (const auto& [key, value] : given) {
    if (!values_.count(key)) {
      std::string known;
      for (const auto& o : info.options) known += (known.empty() ? "" : ", ") + o.key;
      throw InputError("option " + key + "=" + value,
                       "technique " + info.name + " has no option '" + key + "'" +
                           (known.empty() ? " (it takes none)" : " (known: " + known + ")"));
    }
    values_[key] = value;
  }
}

const std::string& TechniqueOptions::get(const std::string& key) const {
  auto it = values_.find(key);
  if (it == values_.end())  // a generator reading an option it did not declare: a programming error
    throw std::logic_error("technique " + technique_ + " reads undeclared option '" + key + "'");
  return it->second;
}

std::int64_t TechniqueOptions::get_int(const std::string& key, std::int64_t min, std::int64_t max) const {
  const std::string& v = get(key);
  std::int64_t out = 0;
  const auto r = std::from_chars(v.data(), v.data() + v.size(), out);
  if (r.ec != std::errc() || r.ptr != v.data() + v.size())
    throw InputError("option " + key + "=" + v, "malformed integer '" + v + "'");
  if (out < min || out > max)
    throw InputError("option " + key + "=" + v,
                     "value out of range [" + std::to_string(min) + ", " + std::to_string(max) + "]");
  return out;
}

float TechniqueOptions::get_float(const std::string& key, float min, float max) const {
  const std::string& v = get(key);
  float out = 0.0f;
  const auto r = std::from_chars(v.data(), v.data() + v.size(), out);
  if (r.ec != std::errc() || r.ptr != v.data() + v.size() || !std::isfinite(out))
    throw InputError("option " + key + "=" + v, "malformed number '" + v + "'");
  if (out < min || out > max) {
    std::ostringstream range;
    range << "value out of range [" << min << ", " << max << "]";
    throw InputError("option " + key + "=" + v, range.str());
  }
  return out;
}

bool TechniqueOptions::get_bool(const std::string& key) const {
  const std::string& v = get(key);
  if (v == "yes" || v == "true" || v == "on" || v == "1") return true;
  if (v == "no" || v == "false" || v == "off" || v == "0") return false;
  throw InputError("option " + key + "=" + v, "expected yes or no, got '" + v + "'");
}

// ---- generation ----------------------------------------------------------------------------------

namespace {

bool is_hash16(const std::string& h) {
  return h.size() == 16 &&
         std::all_of(h.begin(), h.end(), [](char c) { return (c >= '0' && c <= '9') || (c >= 'a' && c <= 'f'); });
}

// "atrium" -> nullopt detail; "atrium:3" -> 3; anything else -> not an atrium spec.
bool atrium_spec(const std::string& spec, std::optional<int>& detail) {
  detail.reset();
  if (spec == "atrium") return true;
  if (spec.rfind("atrium:", 0) != 0) return false;
  const std::string d = spec.substr(7);
  int v = 0;
  const auto r = std::from_chars(d.data(), d.data() + d.size(), v);
  if (r.ec != std::errc() || r.ptr != d.data() + d.size() || v < 0)
    throw InputError("scene " + spec, "malformed atrium detail level '" + d + "'");
  detail = v;
  return true;
}

}  // namespace

TraceScene trace_scene_for(const TraceSetup& setup) {
  const std::string spec = !setup.scene_spec.empty() ? setup.scene_spec : (setup.scene ? setup.scene->source : "");
  if (spec.empty()) throw InputError("scene", "no scene given (neither a scene spec nor a loaded scene)");
  TraceScene s;
  std::optional<int> detail;
  if (atrium_spec(spec, detail)) {
    s.kind = SceneKind::Atrium;
    std::optional<int> loaded_detail;
    if (setup.scene && atrium_spec(setup.scene->source, loaded_detail) && loaded_detail) detail = loaded_detail;
    if (!detail) throw InputError("scene " + spec, "atrium detail level unknown (give atrium:<detail>)");
    s.detail = *detail;
    if (setup.scene && is_hash16(setup.scene->content_hash)) s.content_hash = setup.scene->content_hash;
  } else {
    s.kind = SceneKind::Gltf;
    s.path = spec;
    s.content_hash = setup.scene && is_hash16(setup.scene->content_hash) ? setup.scene->content_hash
                                                                          : hash_file_hex(spec);
  }
  return s;
}

Trace begin_trace(const TraceSetup& setup, const std::string& technique, const TechniqueOptions& options) {
  Trace t;
  t.technique = technique;
  t.options = options.resolved();
  t.scene = trace_scene_for(setup);
  t.frame.width = setup.width;
  t.frame.height = setup.height;
  t.frame.samples = setup.samples;
  t.camera = setup.camera;
  t.camera_name = setup.camera_name;
  t.lights = setup.lights.lights;
  return t;
}

std::string add_light_buffer(Trace& trace, const std::string& name) {
  if (trace.lights.empty()) return "";
  BufferDesc b;
  b.name = name;
  b.bytes = kLightBufferBytesPerLight * trace.lights.size();
  b.traffic = TrafficClass::LightData;
  b.content = BufferContent::Lights;
  b.upload = true;
  trace.buffers.push_back(b);
  return name;
}

// ---- building blocks ------------------------------------------------------------------------------

ShaderDesc make_shader(const std::string& name, std::uint32_t alu_ops, std::uint32_t tex_fetches,
                       std::uint32_t varyings, std::uint32_t light_alu_ops, LightSource source,
                       std::uint32_t color_outputs, PlsAccess pls, bool discard) {
  ShaderDesc s;
  s.name = name;
  s.alu_ops = alu_ops;
  s.tex_fetches = tex_fetches;
  s.varyings = varyings;
  s.light_alu_ops = source == LightSource::None ? 0 : light_alu_ops;
  s.light_source = source;
  s.color_outputs = color_outputs;
  s.pls = pls;
  s.discard = discard;
  return s;
}

PipelineState make_pipeline(const std::string& name, const std::string& shader, bool depth_test, bool depth_write,
                            CompareOp compare, BlendMode blend, CullMode cull, AlphaOverride alpha) {
  PipelineState p;
  p.name = name;
  p.shader = shader;
  p.depth_test = depth_test;
  p.depth_write = depth_write;
  p.depth_compare = compare;
  p.blend = blend;
  p.cull = cull;
  p.alpha = alpha;
  return p;
}

Attachment make_attachment(const std::string& name, Format format, std::uint32_t samples, LoadOp load, StoreOp store,
                           AttachmentUsage usage, bool transient) {
  Attachment a;
  a.name = name;
  a.format = format;
  a.samples = samples;
  a.load = load;
  a.store = store;
  a.usage = usage;
  a.transient = transient;
  return a;
}

void add_color_target(PassDesc& pass, const std::string& name, std::uint32_t samples, Format format) {
  Attachment color = make_attachment(name, format, 1, LoadOp::Clear, StoreOp::Store, AttachmentUsage::Color);
  if (samples > 1) {
    Attachment ms = make_attachment(name + "_ms", format, samples, LoadOp::Clear, StoreOp::DontCare,
                                    AttachmentUsage::Color, true);
    ms.resolve = name;
    color.load = LoadOp::DontCare;  // fully overwritten by the resolve
    pass.attachments.push_back(ms);
  }
  pass.attachments.push_back(color);
}

namespace {

std::vector<std::string> non_empty(const std::vector<std::string>& names) {
  std::vector<std::string> out;
  for (const auto& n : names)
    if (!n.empty()) out.push_back(n);
  return out;
}

}  // namespace

DrawCmd make_draw(GeometryKind geometry, const std::string& pipeline, const std::vector<std::string>& reads,
                  const std::vector<std::string>& fetch) {
  DrawCmd d;
  d.geometry = geometry;
  d.pipeline = pipeline;
  d.reads = non_empty(reads);
  d.fetch = non_empty(fetch);
  return d;
}

DrawCmd scene_draw(SceneSubset subset, const std::string& pipeline, const std::vector<std::string>& reads,
                   const std::vector<std::string>& fetch) {
  DrawCmd d = make_draw(GeometryKind::Scene, pipeline, reads, fetch);
  d.subset = subset;
  return d;
}

std::string add_buffer(Trace& trace, const std::string& name, std::uint64_t bytes, TrafficClass traffic,
                       BufferContent content, bool upload) {
  BufferDesc b;
  b.name = name;
  b.bytes = bytes;
  b.traffic = traffic;
  b.content = content;
  b.upload = upload;
  trace.buffers.push_back(b);
  return name;
}

DispatchCmd make_dispatch(const std::string& kernel, std::uint32_t groups_x, std::uint32_t groups_y,
                          std::uint32_t groups_z, std::uint32_t size_x, std::uint32_t size_y, std::uint32_t size_z,
                          const std::vector<std::string>& reads, const std::vector<std::string>& writes,
                          const std::map<std::string, std::string>& params) {
  DispatchCmd d;
  d.kernel = kernel;
  d.groups[0] = std::max<std::uint32_t>(1, groups_x);
  d.groups[1] = std::max<std::uint32_t>(1, groups_y);
  d.groups[2] = std::max<std::uint32_t>(1, groups_z);
  d.group_size[0] = std::max<std::uint32_t>(1, size_x);
  d.group_size[1] = std::max<std::uint32_t>(1, size_y);
  d.group_size[2] = std::max<std::uint32_t>(1, size_z);
  d.reads = non_empty(reads);
  d.writes = non_empty(writes);
  d.params = params;
  return d;
}

BarrierCmd make_barrier(const std::vector<std::string>& resources) {
  BarrierCmd b;
  b.resources = non_empty(resources);
  b.all = b.resources.empty();
  return b;
}

void reject_msaa(const TraceSetup& setup, const std::string& technique, const std::string& why) {
  if (setup.samples <= 1) return;
  throw InputError("samples", "technique " + technique + " does not support MSAA (samples=" +
                                  std::to_string(setup.samples) + "): " + why + "; use samples=1");
}

void require_lights(const TraceSetup& setup, const std::string& technique) {
  if (!setup.lights.lights.empty()) return;
  throw InputError("lights", "technique " + technique +
                                 " needs at least one light (its kernels cull the light array into lists)");
}

std::uint32_t tiles_for(int pixels, std::uint32_t tile_px) {
  const auto p = static_cast<std::uint32_t>(std::max(pixels, 1));
  return (p + tile_px - 1) / tile_px;
}

std::uint32_t index_bytes_for(std::size_t light_count) {
  if (light_count <= 256) return 1;
  if (light_count <= 65536) return 2;
  return 4;
}

std::uint32_t index_bytes_option(const TechniqueOptions& options, const std::string& key, std::size_t light_count) {
  const std::string& v = options.get(key);
  if (v == "auto") return index_bytes_for(light_count);
  const auto bytes = static_cast<std::uint32_t>(options.get_int(key, 1, 4));
  if (bytes == 3) throw InputError("option " + key + "=" + v, "light index size must be 1, 2 or 4 bytes (or auto)");
  if (bytes < 4 && light_count > (std::size_t{1} << (8 * bytes)))
    throw InputError("option " + key + "=" + v, std::to_string(bytes) + "-byte light indices cannot address " +
                                                    std::to_string(light_count) + " lights (use auto or a larger size)");
  return bytes;
}

std::uint32_t list_cap_option(const TechniqueOptions& options, const std::string& key, std::size_t light_count) {
  const auto all = static_cast<std::uint32_t>(std::max<std::size_t>(light_count, 1));
  if (options.get(key) == "all") return all;
  return std::min(all, static_cast<std::uint32_t>(options.get_int(key, 1, 65535)));
}

std::uint32_t cubical_slice_count(const Camera& camera, int height, std::uint32_t tile_px, float min_depth,
                                  std::uint32_t max_slices) {
  // As docs/kernels.md: slice k+1 starts at z_k * (1 + 2 tan(fov_y/2) * tile_px / height); the first
  // slice ends at min_depth (never nearer than the near plane); the last reaches the far plane.
  const float tan_half_y = std::tan(camera.fov_y_deg * 3.14159265358979f / 360.0f);
  const float ratio = 1.0f + 2.0f * tan_half_y * static_cast<float>(tile_px) / static_cast<float>(std::max(height, 1));
  const float start = std::max(min_depth, camera.near_plane);
  const int needed = 1 + static_cast<int>(std::ceil(std::log(camera.far_plane / start) / std::log(ratio)));
  return static_cast<std::uint32_t>(std::max(1, std::min(static_cast<int>(max_slices), needed)));
}

std::uint32_t GbufferLayout::bytes_per_sample() const {
  std::uint32_t sum = 0;
  for (Format f : formats) sum += tbdr::bytes_per_sample(f);
  return sum;
}

namespace {

Format parse_color_format(const std::string& key, const std::string& value, const std::string& token) {
  const auto f = parse_format(token);
  if (!f) throw InputError("option " + key + "=" + value, "unknown format '" + token + "'");
  if (is_depth_format(*f))
    throw InputError("option " + key + "=" + value, "'" + token + "' is a depth format (a color format is needed)");
  return *f;
}

}  // namespace

GbufferLayout gbuffer_layout_option(const TechniqueOptions& options, const std::string& key) {
  const std::string& v = options.get(key);
  GbufferLayout layout;
  std::size_t start = 0;
  while (start <= v.size()) {
    const std::size_t comma = v.find(',', start);
    const std::string token = v.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
    layout.formats.push_back(parse_color_format(key, v, token));
    const std::size_t i = layout.formats.size() - 1;
    layout.names.push_back(i == 0 ? "albedo" : i == 1 ? "normal" : "gbuffer" + std::to_string(i));
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  if (layout.formats.size() < 2 || layout.formats.size() > 8)
    throw InputError("option " + key + "=" + v,
                     "a G-buffer needs 2 to 8 color targets (albedo, normal, extras), got " +
                         std::to_string(layout.formats.size()));
  return layout;
}

Format color_format_option(const TechniqueOptions& options, const std::string& key) {
  const std::string& v = options.get(key);
  return parse_color_format(key, v, v);
}

std::size_t scene_material_count(const TraceSetup& setup) {
  if (setup.scene) return setup.scene->materials.size();
  return load_scene(setup.scene_spec).materials.size();
}

void add_prez_state(Trace& trace) {
  trace.shaders.push_back(make_shader("depth_only", 0, 0, 0, 0, LightSource::None, 0));
  // Punch-through materials must run the alpha test even in a depth-only pass: uv (2 varyings),
  // the base color alpha fetch and the compare.
  trace.shaders.push_back(make_shader("depth_only_masked", kAlphaTestAluOps, 1, 2, 0, LightSource::None, 0,
                                      PlsAccess::None, true));
  trace.pipelines.push_back(
      make_pipeline("prez", "depth_only", true, true, CompareOp::Less, BlendMode::Off, CullMode::Back));
  trace.pipelines.push_back(
      make_pipeline("prez_masked", "depth_only_masked", true, true, CompareOp::Less, BlendMode::Off, CullMode::Back));
}

void add_prez_draws(PassDesc& pass) {
  pass.draws.push_back(scene_draw(SceneSubset::Opaque, "prez"));
  pass.draws.push_back(scene_draw(SceneSubset::Masked, "prez_masked"));
}

std::string add_translucent_state(Trace& trace) {
  trace.shaders.push_back(make_shader("forward_translucent", kForwardLitAluOps, kSurfaceTexFetches, kSurfaceVaryings,
                                      kLightAluOps, LightSource::ObjectList, 1));
  trace.pipelines.push_back(make_pipeline("translucent", "forward_translucent", true, false, CompareOp::Less,
                                          BlendMode::Alpha, CullMode::Back));
  return "translucent";
}

void add_translucent_draw(PassDesc& pass, const std::string& lights) {
  pass.draws.push_back(scene_draw(SceneSubset::Blended, "translucent", {lights}));
}

bool translucent_forward_option(const TechniqueOptions& options) {
  const std::string& v = options.get("translucent");
  if (v == "forward") return true;
  if (v == "skip") return false;
  throw InputError("option translucent=" + v, "expected forward or skip, got '" + v + "'");
}

void add_forward_lit(Trace& trace, PassDesc& pass, const ForwardLitSpec& spec) {
  LightSource source = spec.source;
  if (trace.lights.empty() && (source == LightSource::All || source == LightSource::ObjectList))
    source = LightSource::None;  // nothing to evaluate: the reader rejects a per-light cost without a source
  const std::uint32_t alu = kForwardLitAluOps + spec.extra_alu_ops;
  trace.shaders.push_back(make_shader(spec.shader, alu, kSurfaceTexFetches, kSurfaceVaryings, kLightAluOps, source, 1,
                                      spec.pls));
  if (spec.depth_primed) {
    // The pre-pass resolved visibility (and ran the alpha test): shade exactly the stored depth.
    // Punch-through geometry is forced opaque: its discarded samples fail the equal test anyway.
    const std::string p = spec.shader + "_equal";
    trace.pipelines.push_back(make_pipeline(p, spec.shader, true, false, CompareOp::Equal, BlendMode::Off,
                                            CullMode::Back, AlphaOverride::Opaque));
    pass.draws.push_back(scene_draw(SceneSubset::Opaque, p, spec.reads));
    pass.draws.push_back(scene_draw(SceneSubset::Masked, p, spec.reads));
    return;
  }
  const std::string masked = spec.shader + "_masked";
  trace.shaders.push_back(make_shader(masked, alu + kAlphaTestAluOps, kSurfaceTexFetches, kSurfaceVaryings,
                                      kLightAluOps, source, 1, spec.pls, true));
  trace.pipelines.push_back(
      make_pipeline(spec.shader, spec.shader, true, true, CompareOp::Less, BlendMode::Off, CullMode::Back));
  trace.pipelines.push_back(make_pipeline(masked, masked, true, true, CompareOp::Less, BlendMode::Off, CullMode::Back));
  pass.draws.push_back(scene_draw(SceneSubset::Opaque, spec.shader, spec.reads));
  pass.draws.push_back(scene_draw(SceneSubset::Masked, masked, spec.reads));
}

PassDesc make_gbuffer_pass(Trace& trace, const GbufferLayout& layout, const std::string& name) {
  const auto targets = static_cast<std::uint32_t>(layout.formats.size());
  const std::uint32_t alu = kSurfaceAluOps + kGbufferEncodeAluOps + kGbufferExtraTargetAluOps * layout.extra_targets();
  trace.shaders.push_back(
      make_shader("gbuffer", alu, kSurfaceTexFetches, kSurfaceVaryings, 0, LightSource::None, targets));
  trace.shaders.push_back(make_shader("gbuffer_masked", alu + kAlphaTestAluOps, kSurfaceTexFetches, kSurfaceVaryings,
                                      0, LightSource::None, targets, PlsAccess::None, true));
  trace.pipelines.push_back(
      make_pipeline("gbuffer", "gbuffer", true, true, CompareOp::Less, BlendMode::Off, CullMode::Back));
  trace.pipelines.push_back(
      make_pipeline("gbuffer_masked", "gbuffer_masked", true, true, CompareOp::Less, BlendMode::Off, CullMode::Back));
  PassDesc pass;
  pass.name = name;
  for (std::size_t i = 0; i < layout.formats.size(); ++i)
    pass.attachments.push_back(make_attachment(layout.names[i], layout.formats[i], 1, LoadOp::Clear, StoreOp::Store,
                                               AttachmentUsage::Gbuffer));
  pass.attachments.push_back(
      make_attachment("depth", Format::D24s8, 1, LoadOp::Clear, StoreOp::Store, AttachmentUsage::Depth));
  pass.draws.push_back(scene_draw(SceneSubset::Opaque, "gbuffer"));
  pass.draws.push_back(scene_draw(SceneSubset::Masked, "gbuffer_masked"));
  return pass;
}

namespace {

std::string float_text(float v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

}  // namespace

Trace generate_light_grid_forward(const TraceSetup& setup, const TechniqueOptions& options, const LightGridConfig& c) {
  using Kind = LightGridConfig::Kind;
  require_lights(setup, c.technique);
  Trace t = begin_trace(setup, c.technique, options);
  const std::string lights = add_light_buffer(t);
  const auto samples = static_cast<std::uint32_t>(setup.samples);
  const std::uint32_t tiles_x = tiles_for(setup.width, c.tile_px);
  const std::uint32_t tiles_y = tiles_for(setup.height, c.tile_px);
  const std::uint32_t slices = c.kind == Kind::Tiles ? 1 : c.slices;
  const std::uint64_t cells = std::uint64_t{tiles_x} * tiles_y * slices;
  const std::uint32_t edge = std::min(c.tile_px, kKernelGroupEdge);

  const bool tiles = c.kind == Kind::Tiles;
  const std::string grid = tiles ? "tile_grid" : "cluster_grid";
  add_buffer(t, grid, cells * kGridEntryBytes, TrafficClass::LightLists,
             tiles ? BufferContent::TileGrid : BufferContent::ClusterGrid);
  const std::string index = add_buffer(t, "light_index", cells * c.max_lights * c.index_bytes,
                                       TrafficClass::LightLists, BufferContent::LightIndexList);
  std::string used;
  if (c.kind == Kind::SparseClusters)
    used = add_buffer(t, "used_clusters", 4 + cells * kUsedClusterEntryBytes, TrafficClass::LightLists,
                      BufferContent::UsedClusters);

  std::map<std::string, std::string> cluster_params = {{"tile_px", std::to_string(c.tile_px)},
                                                       {"slices", std::to_string(slices)},
                                                       {"slicing", c.cubical ? "cubical" : "log"}};
  if (c.cubical) cluster_params["min_depth"] = float_text(c.min_depth);

  const bool stored_prepass = c.kind != Kind::DenseClusters;
  if (stored_prepass || c.prez) add_prez_state(t);
  if (stored_prepass) {
    // The depth pre-pass leaves the chip: the culling kernels read it as a texture (Billeter: "Depth"
    // is clustered forward's off-chip buffer).
    PassDesc prepass;
    prepass.name = "prepass";
    prepass.attachments.push_back(
        make_attachment("depth", Format::D24s8, samples, LoadOp::Clear, StoreOp::Store, AttachmentUsage::Depth));
    add_prez_draws(prepass);
    t.commands.emplace_back(std::move(prepass));
    t.commands.emplace_back(make_barrier({"depth"}));
    if (tiles) {
      t.commands.emplace_back(make_dispatch("tile_light_cull", tiles_x, tiles_y, 1, edge, edge, 1, {"depth", lights},
                                            {grid, index},
                                            {{"tile_px", std::to_string(c.tile_px)},
                                             {"max_lights_per_tile", std::to_string(c.max_lights)}}));
    } else {
      t.commands.emplace_back(
          make_dispatch("cluster_flag", tiles_x, tiles_y, 1, edge, edge, 1, {"depth"}, {used}, cluster_params));
      t.commands.emplace_back(make_barrier({used}));
      auto params = cluster_params;
      params["dense"] = "no";
      // One workgroup per cluster of the grid, its threads looping over the lights (the kernel
      // skips clusters missing from the used list).
      t.commands.emplace_back(make_dispatch("cluster_light_assign", tiles_x * tiles_y, slices, 1, 64, 1, 1,
                                            {lights, used}, {grid, index}, params));
    }
  } else {
    auto params = cluster_params;
    params["dense"] = "yes";
    t.commands.emplace_back(make_dispatch("cluster_light_assign", tiles_x * tiles_y, slices, 1, 64, 1, 1, {lights},
                                          {grid, index}, params));
  }
  t.commands.emplace_back(make_barrier({grid, index}));

  PassDesc pass;
  pass.name = stored_prepass ? "forward" : "main";
  add_color_target(pass, "color", samples);
  bool primed = false;
  if (stored_prepass && c.depth_reload) {
    pass.attachments.push_back(
        make_attachment("depth", Format::D24s8, samples, LoadOp::Load, StoreOp::DontCare, AttachmentUsage::Depth));
    primed = true;
  } else {
    pass.attachments.push_back(make_attachment(stored_prepass ? "forward_depth" : "depth", Format::D24s8, samples,
                                               LoadOp::Clear, StoreOp::DontCare, AttachmentUsage::Depth, true));
    if (!stored_prepass && c.prez) {
      add_prez_draws(pass);
      primed = true;
    }
  }
  ForwardLitSpec lit;
  lit.source = tiles ? LightSource::TileList : LightSource::ClusterList;
  lit.extra_alu_ops = tiles ? kTileLookupAluOps : kClusterLookupAluOps;
  lit.depth_primed = primed;
  lit.reads = {lights, grid, index};
  add_forward_lit(t, pass, lit);
  if (c.kind == Kind::DenseClusters) {
    // The dense grid covers the whole frustum, so translucent surfaces use their cluster lists too.
    t.pipelines.push_back(make_pipeline("translucent", lit.shader, true, false, CompareOp::Less, BlendMode::Alpha,
                                        CullMode::Back));
    pass.draws.push_back(scene_draw(SceneSubset::Blended, "translucent", lit.reads));
  } else {
    // Lists exist only where the pre-pass depth put samples: translucent surfaces in front of it
    // take the per-object light lists instead (Billeter's "yes*").
    add_translucent_state(t);
    add_translucent_draw(pass, lights);
  }
  t.commands.emplace_back(std::move(pass));
  return t;
}

Trace generate_trace(const std::string& technique, const TraceSetup& setup) {
  const TechniqueInfo& info = find_technique(technique);
  const TechniqueOptions options(info, setup.options);
  if (setup.width < 1 || setup.height < 1 || setup.width > 16384 || setup.height > 16384)
    throw InputError("resolution", "frame size " + std::to_string(setup.width) + "x" + std::to_string(setup.height) +
                                       " out of range (1..16384)");
  if (setup.samples != 1 && setup.samples != 2 && setup.samples != 4 && setup.samples != 8)
    throw InputError("samples", "sample count " + std::to_string(setup.samples) + " must be 1, 2, 4 or 8");

  const Trace generated = info.generate(setup, options);
  // Validate through the reader: a generator bug surfaces as an error naming the line of the
  // canonical text, and the returned trace carries those line numbers.
  std::stringstream text;
  write_trace(generated, text);
  return parse_trace(text, "<generated " + technique + ">");
}

}  // namespace tbdr
