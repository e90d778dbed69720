#include "techniques/technique.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <limits>
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

// ---- starting a trace ----------------------------------------------------------------------------

namespace {

bool is_hash16(const std::string& h) {
  return h.size() == 16 &&
         std::all_of(h.begin(), h.end(), [](char c) { return (c >= '0' && c <= '9') || (c >= 'a' && c <= 'f'); });
}

}  // namespace

TraceScene trace_scene_for(const TraceSetup& setup) {
  const std::string spec = !setup.scene_spec.empty() ? setup.scene_spec : (setup.scene ? setup.scene->source : "");
  if (spec.empty()) throw InputError("scene", "no scene given (neither a scene spec nor a loaded scene)");
  TraceScene s;
  if (const auto atrium = parse_atrium_spec(spec)) {
    s.kind = SceneKind::Atrium;
    std::optional<int> detail = atrium->detail;
    if (setup.scene) {  // the loaded scene knows the detail a plain "atrium" stands for
      const auto loaded = parse_atrium_spec(setup.scene->source);
      if (loaded && loaded->detail) detail = loaded->detail;
    }
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

Trace begin_trace(const TraceSetup& setup, const std::string& technique, const TechniqueOptions& options,
                  const TechniqueLimits& limits) {
  if (!limits.no_msaa.empty() && setup.samples > 1)
    throw InputError("samples", "technique " + technique + " does not support MSAA (samples=" +
                                    std::to_string(setup.samples) + "): " + limits.no_msaa + "; use samples=1");
  if (limits.needs_lights && setup.lights.lights.empty())
    throw InputError("lights", "technique " + technique +
                                   " needs at least one light (its kernels cull the light array into lists)");
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

std::string add_light_buffer(Trace& trace) {
  if (trace.lights.empty()) return "";
  return add_buffer(trace, "lights", kLightBufferBytesPerLight * trace.lights.size(), DramClass::LightData,
                    BufferContent::Lights, true);
}

// ---- shaders ---------------------------------------------------------------------------------------

ShaderDesc make_shader(const std::string& name, std::uint32_t alu_ops, std::uint32_t tex_fetches,
                       std::uint32_t varyings, std::uint32_t light_alu_ops, LightSource source,
                       std::uint32_t color_outputs, PlsAccess pls, bool discard) {
  return ShaderDesc{.name = name,
                    .alu_ops = alu_ops,
                    .tex_fetches = tex_fetches,
                    .varyings = varyings,
                    .light_alu_ops = source == LightSource::None ? 0 : light_alu_ops,
                    .light_source = source,
                    .color_outputs = color_outputs,
                    .pls = pls,
                    .discard = discard,
                    .vertex_alu_ops = std::nullopt};
}

ShaderDesc masked_variant(const ShaderDesc& s, std::uint32_t alpha_fetches, std::uint32_t uv_varyings) {
  ShaderDesc m = s;
  m.name = s.name + "_masked";
  m.alu_ops += kAlphaTestAluOps;
  m.tex_fetches += alpha_fetches;
  m.varyings += uv_varyings;
  m.discard = true;
  return m;
}

ShaderDesc gbuffer_shader(const std::string& name, std::uint32_t extra_targets, std::uint32_t color_outputs,
                          PlsAccess pls) {
  return make_shader(name, kSurfaceAluOps + kGbufferEncodeAluOps + kGbufferExtraTargetAluOps * extra_targets,
                     kSurfaceTexFetches, kSurfaceVaryings, 0, LightSource::None, color_outputs, pls);
}

ShaderDesc light_volume_shader(const std::string& name, std::uint32_t fetches, std::uint32_t extra_targets,
                               std::uint32_t color_outputs, PlsAccess pls) {
  return make_shader(name,
                     kGbufferDecodeAluOps + kGbufferExtraTargetAluOps * extra_targets + kPositionReconstructAluOps +
                         kOutputAluOps,
                     fetches, kProxyVaryings, kLightAluOps, LightSource::Proxy, color_outputs, pls);
}

// ---- pipeline states -------------------------------------------------------------------------------

namespace {

PipelineState make_pipeline(const std::string& name, const std::string& shader, bool depth_test, bool depth_write,
                            CompareOp compare, BlendMode blend, CullMode cull,
                            AlphaOverride alpha = AlphaOverride::Material) {
  return PipelineState{.name = name, .shader = shader, .depth_test = depth_test, .depth_write = depth_write,
                       .depth_compare = compare, .blend = blend, .cull = cull, .alpha = alpha};
}

}  // namespace

PipelineState depth_writing_pipeline(const std::string& name, const std::string& shader) {
  return make_pipeline(name, shader, true, true, CompareOp::Less, BlendMode::Off, CullMode::Back);
}

PipelineState depth_equal_pipeline(const std::string& name, const std::string& shader, BlendMode blend) {
  return make_pipeline(name, shader, true, false, CompareOp::Equal, blend, CullMode::Back, AlphaOverride::Opaque);
}

PipelineState blended_pipeline(const std::string& name, const std::string& shader) {
  return make_pipeline(name, shader, true, false, CompareOp::Less, BlendMode::Alpha, CullMode::Back);
}

PipelineState light_volume_pipeline(const std::string& name, const std::string& shader, BlendMode blend) {
  return make_pipeline(name, shader, true, false, CompareOp::GreaterEqual, blend, CullMode::Front);
}

PipelineState fullscreen_pipeline(const std::string& name, const std::string& shader) {
  return make_pipeline(name, shader, false, false, CompareOp::Always, BlendMode::Off, CullMode::None);
}

// ---- attachments and buffers -----------------------------------------------------------------------

Attachment make_attachment(const std::string& name, Format format, std::uint32_t samples, LoadOp load, StoreOp store,
                           AttachmentUsage usage, bool transient) {
  return Attachment{.name = name, .format = format, .samples = samples, .load = load, .store = store,
                    .transient = transient, .usage = usage, .resolve = {}};
}

Attachment depth_attachment(std::uint32_t samples, LoadOp load, StoreOp store, const std::string& name) {
  const bool transient = load != LoadOp::Load && store == StoreOp::DontCare;
  return make_attachment(name, Format::D24s8, samples, load, store, AttachmentUsage::Depth, transient);
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

PassDesc color_pass(const std::string& name, std::uint32_t samples, LoadOp depth_load, const std::string& depth) {
  PassDesc pass;
  pass.name = name;
  add_color_target(pass, "color", samples);
  pass.attachments.push_back(depth_attachment(samples, depth_load, StoreOp::DontCare, depth));
  return pass;
}

std::string add_buffer(Trace& trace, const std::string& name, std::uint64_t bytes, DramClass traffic,
                       BufferContent content, bool upload) {
  trace.buffers.push_back(
      BufferDesc{.name = name, .bytes = bytes, .traffic = traffic, .content = content, .upload = upload});
  return name;
}

std::string add_frame_buffer(Trace& trace, const TraceSetup& setup) {
  return add_buffer(trace, "color", std::uint64_t(setup.width) * std::uint64_t(setup.height) * 4, DramClass::Color,
                    BufferContent::Image);
}

// ---- commands --------------------------------------------------------------------------------------

namespace {

std::vector<std::string> non_empty(const std::vector<std::string>& names) {
  std::vector<std::string> out;
  for (const auto& n : names)
    if (!n.empty()) out.push_back(n);
  return out;
}

}  // namespace

LightReach light_reach(const Light& light, const Camera& camera, int width, int height) {
  LightReach out;
  const float r = light.radius;
  const glm::vec3 c = light.position;
  const float pad = r * kLightBoxMarginRadius +
                    (std::max({std::fabs(c.x), std::fabs(c.y), std::fabs(c.z)}) + r) * kLightBoxMarginCoordinate;
  out.box = CullBox{c - glm::vec3(r + pad), c + glm::vec3(r + pad)};
  const ScissorRect frame{0, 0, static_cast<std::uint32_t>(width), static_cast<std::uint32_t>(height)};
  // View space looks down -z; visible points have z < -near (as the simulator's camera transform).
  const glm::vec3 v = glm::vec3(camera.view() * glm::vec4(c, 1.0f));
  if (v.z - r >= -camera.near_plane) return out;  // wholly behind the near plane: reaches no visible point
  out.visible = true;
  if (v.z + r > -camera.near_plane) {  // crosses the near plane or holds the eye: every pixel
    out.full_frame = true;
    out.rect = frame;
    return out;
  }
  const glm::mat4 proj = camera.projection(static_cast<float>(width) / static_cast<float>(height));
  float x0 = std::numeric_limits<float>::max(), y0 = x0, x1 = -x0, y1 = -x0;
  for (int i = 0; i < 8; ++i) {
    const glm::vec4 clip = proj * glm::vec4(v.x + ((i & 1) ? r : -r), v.y + ((i & 2) ? r : -r), v.z + ((i & 4) ? r : -r), 1.0f);
    // Pixel coordinates, y down from the top-left pixel (the rasteriser's viewport transform).
    const float px = (clip.x / clip.w * 0.5f + 0.5f) * static_cast<float>(width);
    const float py = (0.5f - clip.y / clip.w * 0.5f) * static_cast<float>(height);
    x0 = std::min(x0, px);
    x1 = std::max(x1, px);
    y0 = std::min(y0, py);
    y1 = std::max(y1, py);
  }
  const auto clamp_px = [](float p, int size) {
    return static_cast<std::uint32_t>(std::clamp(p, 0.0f, static_cast<float>(size)));
  };
  out.rect = ScissorRect{clamp_px(std::floor(x0) - kLightRectMarginPx, width), clamp_px(std::floor(y0) - kLightRectMarginPx, height),
                         clamp_px(std::ceil(x1) + kLightRectMarginPx, width), clamp_px(std::ceil(y1) + kLightRectMarginPx, height)};
  out.visible = out.rect.x0 < out.rect.x1 && out.rect.y0 < out.rect.y1;  // off the frame: no pixel
  return out;
}

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

void add_scene_draws(PassDesc& pass, const std::string& opaque, const std::string& masked,
                     const std::vector<std::string>& reads) {
  pass.draws.push_back(scene_draw(SceneSubset::Opaque, opaque, reads));
  pass.draws.push_back(scene_draw(SceneSubset::Masked, masked, reads));
}

void add_scene_shading(Trace& trace, PassDesc& pass, const std::string& pipeline, const ShaderDesc& shader,
                       const ShaderDesc& masked, const std::vector<std::string>& reads) {
  const std::string masked_pipeline = pipeline + "_masked";
  trace.shaders.push_back(shader);
  trace.shaders.push_back(masked);
  trace.pipelines.push_back(depth_writing_pipeline(pipeline, shader.name));
  trace.pipelines.push_back(depth_writing_pipeline(masked_pipeline, masked.name));
  add_scene_draws(pass, pipeline, masked_pipeline, reads);
}

DispatchCmd make_dispatch(ComputeKernel kernel, std::uint32_t groups_x, std::uint32_t groups_y,
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

// ---- options -----------------------------------------------------------------------------------------

std::uint32_t tiles_for(int pixels, std::uint32_t tile_px) {
  const auto p = static_cast<std::uint32_t>(std::max(pixels, 1));
  return (p + tile_px - 1) / tile_px;
}

std::uint32_t kernel_group_edge(std::uint32_t tile_px) { return std::min(tile_px, kKernelGroupEdge); }

std::uint32_t index_bytes_option(const TechniqueOptions& options, const std::string& key, std::size_t light_count) {
  const std::string& v = options.get(key);
  if (v == "auto") return light_count <= 256 ? 1 : light_count <= 65536 ? 2 : 4;
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

bool translucent_forward_option(const TechniqueOptions& options) {
  const std::string& v = options.get("translucent");
  if (v == "forward") return true;
  if (v == "skip") return false;
  throw InputError("option translucent=" + v, "expected forward or skip, got '" + v + "'");
}

TechniqueOption translucent_pass_declaration() {
  return {"translucent", "forward",
          "BLEND materials cannot live in the G-buffer: forward = draw them in a render pass that loads the "
          "kernel-written frame as its color and tests the stored depth (per-object light lists; 1 sample only), "
          "skip = leave them out"};
}

TechniqueOption sphere_subdivisions_declaration() {
  return {"sphere_subdivisions", "1", "icosphere level of the light proxies: 20 x 4^n triangles per light"};
}

std::uint32_t sphere_subdivisions_option(const TechniqueOptions& options) {
  return static_cast<std::uint32_t>(options.get_int("sphere_subdivisions", 0, 6));
}

std::size_t scene_material_count(const TraceSetup& setup) {
  if (setup.scene) return setup.scene->materials.size();
  return load_scene(setup.scene_spec).materials.size();
}

// ---- passes shared by several techniques -----------------------------------------------------------

void add_prez(Trace& trace, PassDesc& pass) {
  // Punch-through materials must run the alpha test even in a depth-only pass: uv, the base color
  // alpha fetch and the compare.
  const ShaderDesc depth_only = make_shader("depth_only", 0, 0, 0, 0, LightSource::None, 0);
  add_scene_shading(trace, pass, "prez", depth_only, masked_variant(depth_only, 1, kUvVaryings));
}

void add_translucent_state(Trace& trace) {
  trace.shaders.push_back(make_shader("forward_translucent", kForwardLitAluOps, kSurfaceTexFetches, kSurfaceVaryings,
                                      kLightAluOps, LightSource::ObjectList, 1));
  trace.pipelines.push_back(blended_pipeline("translucent", "forward_translucent"));
}

void add_translucent_draw(PassDesc& pass, const std::string& lights) {
  pass.draws.push_back(scene_draw(SceneSubset::Blended, "translucent", {lights}));
}

void add_translucent_pass(Trace& trace, const TraceSetup& setup, const TechniqueOptions& options,
                          const std::string& frame, const std::string& lights, const std::string& depth) {
  if (!translucent_forward_option(options) || setup.samples > 1) return;
  trace.commands.emplace_back(make_barrier({frame}));
  PassDesc pass;
  pass.name = "translucent";
  pass.attachments.push_back(make_attachment(frame, Format::Rgba8, 1, LoadOp::Load, StoreOp::Store, AttachmentUsage::Color));
  pass.attachments.push_back(depth_attachment(1, LoadOp::Load, StoreOp::DontCare, depth));
  add_translucent_state(trace);
  add_translucent_draw(pass, lights);
  trace.commands.emplace_back(std::move(pass));
}

void add_ambient(Trace& trace, PassDesc& pass, const std::string& source) {
  trace.shaders.push_back(make_shader("ambient", kAmbientAluOps + kOutputAluOps, 1, 0, 0, LightSource::None, 1));
  trace.pipelines.push_back(fullscreen_pipeline("ambient", "ambient"));
  pass.draws.push_back(make_draw(GeometryKind::Fullscreen, "ambient", {source}));
}

void add_light_volumes(PassDesc& pass, const std::string& pipeline, const std::string& lights,
                       std::uint32_t subdivisions, std::vector<std::string> reads,
                       const std::vector<std::string>& fetch) {
  if (lights.empty()) return;
  reads.push_back(lights);
  DrawCmd volumes = make_draw(GeometryKind::LightSpheres, pipeline, reads, fetch);
  volumes.subdivisions = subdivisions;
  pass.draws.push_back(volumes);
}

void add_forward_lit(Trace& trace, PassDesc& pass, const ForwardLitSpec& spec) {
  LightSource source = spec.source;
  if (trace.lights.empty() && (source == LightSource::All || source == LightSource::ObjectList))
    source = LightSource::None;  // nothing to evaluate: the reader rejects a per-light cost without a source
  const ShaderDesc lit = make_shader(spec.shader, kForwardLitAluOps + spec.extra_alu_ops, kSurfaceTexFetches,
                                     kSurfaceVaryings, kLightAluOps, source, 1, spec.pls);
  if (spec.depth_primed) {
    // The pre-pass resolved visibility (and ran the alpha test): shade exactly the stored depth.
    const std::string p = spec.shader + "_equal";
    trace.shaders.push_back(lit);
    trace.pipelines.push_back(depth_equal_pipeline(p, spec.shader));
    add_scene_draws(pass, p, p, spec.reads);
    return;
  }
  add_scene_shading(trace, pass, spec.shader, lit, masked_variant(lit), spec.reads);
}

PassDesc make_gbuffer_pass(Trace& trace, const GbufferLayout& layout, const std::string& name) {
  PassDesc pass;
  pass.name = name;
  for (std::size_t i = 0; i < layout.formats.size(); ++i)
    pass.attachments.push_back(make_attachment(layout.names[i], layout.formats[i], 1, LoadOp::Clear, StoreOp::Store,
                                               AttachmentUsage::Gbuffer));
  pass.attachments.push_back(depth_attachment(1, LoadOp::Clear, StoreOp::Store));
  const ShaderDesc gbuffer =
      gbuffer_shader("gbuffer", layout.extra_targets(), static_cast<std::uint32_t>(layout.formats.size()));
  add_scene_shading(trace, pass, "gbuffer", gbuffer, masked_variant(gbuffer));
  return pass;
}

ComputeDeferred begin_compute_deferred(const TraceSetup& setup, const std::string& technique,
                                       const TechniqueOptions& options) {
  ComputeDeferred c;
  c.trace = begin_trace(setup, technique, options, {.no_msaa = kGbufferNoMsaa, .needs_lights = true});
  c.lights = add_light_buffer(c.trace);
  c.layout = gbuffer_layout_option(options, "gbuffer");
  return c;
}

ShadedGbuffer add_compute_gbuffer(Trace& trace, const TraceSetup& setup, const GbufferLayout& layout,
                                  const std::string& shader, std::uint32_t lookup_alu_ops, LightSource source) {
  ShadedGbuffer out;
  out.frame = add_frame_buffer(trace, setup);
  PassDesc gbuffer = make_gbuffer_pass(trace, layout);
  const auto targets = static_cast<std::uint32_t>(layout.formats.size());
  trace.shaders.push_back(make_shader(shader,
                                      kGbufferDecodeAluOps + kGbufferExtraTargetAluOps * layout.extra_targets() +
                                          kPositionReconstructAluOps + lookup_alu_ops + kAmbientAluOps +
                                          kOutputAluOps,
                                      targets + 1, 0, kLightAluOps, source, 1));
  out.stored = layout.names;
  out.stored.push_back("depth");
  trace.commands.emplace_back(std::move(gbuffer));
  trace.commands.emplace_back(make_barrier(out.stored));
  return out;
}

Trace finish_compute_deferred(ComputeDeferred& c, const ShadedGbuffer& g, const TraceSetup& setup,
                              const TechniqueOptions& options, ComputeKernel kernel, const std::string& shader,
                              std::uint32_t tile_px, const std::vector<std::string>& extra_reads,
                              std::map<std::string, std::string> params) {
  std::vector<std::string> reads = g.stored;
  reads.push_back(c.lights);
  reads.insert(reads.end(), extra_reads.begin(), extra_reads.end());
  c.trace.commands.emplace_back(shading_dispatch(kernel, shader, setup, tile_px, reads, g.frame, std::move(params)));
  add_translucent_pass(c.trace, setup, options, g.frame, c.lights);
  return std::move(c.trace);
}

// ---- light lists ---------------------------------------------------------------------------------------

namespace {

std::string float_text(float v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

}  // namespace

std::uint64_t LightGrid::cells() const {
  return std::uint64_t{tiles_x()} * tiles_y() * (clusters ? slices : 1);
}

std::uint32_t LightGrid::group_edge() const { return kernel_group_edge(tile_px); }

std::map<std::string, std::string> LightGrid::cluster_params() const {
  std::map<std::string, std::string> params = {
      {"tile_px", std::to_string(tile_px)}, {"slices", std::to_string(slices)}, {"slicing", cubical ? "cubical" : "log"}};
  if (cubical) params["min_depth"] = float_text(min_depth);
  return params;
}

namespace {

// Number of depth slices of a cubical cluster grid (docs/kernels.md, Billeter 2015): as many as
// reach the far plane from `min_depth` with tiles of `tile_px`, at most `max_slices`. The same
// formula the cluster kernels use, so buffer sizes match their grids.
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

// The cubical grid's min_depth and slices options (GridOptions::CubicalClusters), into `g`.
void cubical_slices_option(const TraceSetup& setup, const TechniqueOptions& options, LightGrid& g) {
  const Camera& cam = setup.camera;
  g.cubical = true;
  if (options.get("min_depth") == "auto") {
    g.min_depth = std::min(10.0f * cam.near_plane, 0.5f * cam.far_plane);
  } else {
    g.min_depth = options.get_float("min_depth", 0.0f, 1e30f);
    if (!(g.min_depth > cam.near_plane && g.min_depth < cam.far_plane))
      throw InputError("option min_depth=" + options.get("min_depth"),
                       "must lie between the camera's near and far planes");
  }
  const std::uint32_t max_slices =
      options.get("slices") == "auto" ? 4096u : static_cast<std::uint32_t>(options.get_int("slices", 1, 4096));
  g.slices = cubical_slice_count(cam, setup.height, g.tile_px, g.min_depth, max_slices);
}

}  // namespace

LightGrid light_grid_option(const TraceSetup& setup, const TechniqueOptions& options, GridOptions form) {
  const std::size_t light_count = setup.lights.lights.size();
  LightGrid g;
  g.clusters = form != GridOptions::Tiles;
  g.width = setup.width;
  g.height = setup.height;
  g.tile_px = static_cast<std::uint32_t>(options.get_int("tile_px", 4, g.clusters ? 1024 : 256));
  if (form == GridOptions::LogClusters) g.slices = static_cast<std::uint32_t>(options.get_int("slices", 1, 1024));
  if (form == GridOptions::CubicalClusters) cubical_slices_option(setup, options, g);
  g.max_lights = list_cap_option(options, g.clusters ? "max_lights_per_cluster" : "max_lights_per_tile", light_count);
  g.index_bytes = index_bytes_option(options, "index_bytes", light_count);
  return g;
}

void add_light_grid_buffers(Trace& trace, const LightGrid& grid) {
  add_buffer(trace, grid.grid_buffer(), grid.cells() * kGridEntryBytes, DramClass::LightLists,
             grid.clusters ? BufferContent::ClusterGrid : BufferContent::TileGrid);
  add_buffer(trace, kLightIndexBuffer, grid.cells() * grid.max_lights * grid.index_bytes, DramClass::LightLists,
             BufferContent::LightIndexList);
}

std::string add_used_clusters_buffer(Trace& trace, const LightGrid& grid) {
  return add_buffer(trace, "used_clusters", 4 + grid.cells() * kUsedClusterEntryBytes, DramClass::LightLists,
                    BufferContent::UsedClusters);
}

DispatchCmd tile_light_cull_dispatch(const LightGrid& grid, const std::string& lights) {
  const std::uint32_t edge = grid.group_edge();
  return make_dispatch(ComputeKernel::TileLightCull, grid.tiles_x(), grid.tiles_y(), 1, edge, edge, 1, {"depth", lights},
                       {grid.grid_buffer(), kLightIndexBuffer},
                       {{"tile_px", std::to_string(grid.tile_px)},
                        {"max_lights_per_tile", std::to_string(grid.max_lights)}});
}

namespace {

// One workgroup per cluster of the grid, its threads looping over the lights (with `used`, the
// kernel skips the clusters missing from the used list).
DispatchCmd cluster_light_assign(const LightGrid& grid, const std::string& lights, const std::string& used) {
  auto params = grid.cluster_params();
  params["dense"] = used.empty() ? "yes" : "no";
  return make_dispatch(ComputeKernel::ClusterLightAssign, grid.tiles_x() * grid.tiles_y(), grid.slices, 1, kAssignGroupThreads,
                       1, 1, {lights, used}, {grid.grid_buffer(), kLightIndexBuffer}, params);
}

}  // namespace

void add_sparse_cluster_assignment(Trace& trace, const LightGrid& grid, const std::string& lights,
                                   const std::string& used) {
  const std::uint32_t edge = grid.group_edge();
  trace.commands.emplace_back(make_dispatch(ComputeKernel::ClusterFlag, grid.tiles_x(), grid.tiles_y(), 1, edge, edge, 1,
                                            {"depth"}, {used}, grid.cluster_params()));
  trace.commands.emplace_back(make_barrier({used}));
  trace.commands.emplace_back(cluster_light_assign(grid, lights, used));
}

DispatchCmd dense_cluster_assignment(const LightGrid& grid, const std::string& lights) {
  return cluster_light_assign(grid, lights, "");
}

DispatchCmd shading_dispatch(ComputeKernel kernel, const std::string& shader, const TraceSetup& setup,
                             std::uint32_t tile_px, const std::vector<std::string>& reads, const std::string& frame,
                             std::map<std::string, std::string> params) {
  params["shader"] = shader;
  params["tile_px"] = std::to_string(tile_px);
  const std::uint32_t edge = kernel_group_edge(tile_px);
  return make_dispatch(kernel, tiles_for(setup.width, tile_px), tiles_for(setup.height, tile_px), 1, edge, edge, 1,
                       reads, {frame}, params);
}

Trace generate_light_grid_forward(const TraceSetup& setup, const TechniqueOptions& options, const LightGridConfig& c) {
  using Kind = LightGridConfig::Kind;
  Trace t = begin_trace(setup, c.technique, options, {.needs_lights = true});
  const std::string lights = add_light_buffer(t);
  const auto samples = static_cast<std::uint32_t>(setup.samples);
  const LightGrid& grid = c.grid;
  const bool tiles = c.kind == Kind::Tiles;
  add_light_grid_buffers(t, grid);
  std::string used;
  if (c.kind == Kind::SparseClusters) used = add_used_clusters_buffer(t, grid);

  const bool stored_prepass = c.kind != Kind::DenseClusters;
  if (stored_prepass) {
    // The depth pre-pass leaves the chip: the culling kernels read it as a texture (Billeter: "Depth"
    // is clustered forward's off-chip buffer).
    PassDesc prepass;
    prepass.name = "prepass";
    prepass.attachments.push_back(depth_attachment(samples, LoadOp::Clear, StoreOp::Store));
    add_prez(t, prepass);
    t.commands.emplace_back(std::move(prepass));
    t.commands.emplace_back(make_barrier({"depth"}));
    if (tiles)
      t.commands.emplace_back(tile_light_cull_dispatch(grid, lights));
    else
      add_sparse_cluster_assignment(t, grid, lights, used);
  } else {
    t.commands.emplace_back(dense_cluster_assignment(grid, lights));
  }
  t.commands.emplace_back(make_barrier({grid.grid_buffer(), kLightIndexBuffer}));

  // The forward pass reloads the pre-pass depth (and tests equal) or renders a fresh on-chip depth.
  const bool reload = stored_prepass && c.depth_reload;
  PassDesc pass = color_pass(stored_prepass ? "forward" : "main", samples, reload ? LoadOp::Load : LoadOp::Clear,
                             stored_prepass && !reload ? "forward_depth" : "depth");
  bool primed = reload;
  if (!stored_prepass && c.prez) {
    add_prez(t, pass);
    primed = true;
  }
  ForwardLitSpec lit;
  lit.source = tiles ? LightSource::TileList : LightSource::ClusterList;
  lit.extra_alu_ops = tiles ? kTileLookupAluOps : kClusterLookupAluOps;
  lit.depth_primed = primed;
  lit.reads = {lights, grid.grid_buffer(), kLightIndexBuffer};
  add_forward_lit(t, pass, lit);
  if (c.kind == Kind::DenseClusters) {
    // The dense grid covers the whole frustum, so translucent surfaces use their cluster lists too.
    t.pipelines.push_back(blended_pipeline("translucent", lit.shader));
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

std::vector<Trace> generate_sequence(const std::string& technique, const TraceSetup& setup, const SequenceMotion& motion) {
  if (motion.frames < 1 || motion.frames > kMaxSequenceFrames)
    throw InputError("--frames " + std::to_string(motion.frames), "expected 1.." + std::to_string(kMaxSequenceFrames) + " frames");
  if (!motion.cameras.empty() && motion.cameras.size() < static_cast<std::size_t>(motion.frames)) {
    throw InputError("--frames " + std::to_string(motion.frames), "the camera path file holds " + std::to_string(motion.cameras.size()) +
                                                                      " cameras, fewer than the frames asked for");
  }
  if (motion.animation >= 0) {
    const std::size_t have = setup.scene != nullptr ? setup.scene->animation.animations.size() : 0;
    if (static_cast<std::size_t>(motion.animation) >= have) {
      throw InputError("--animation " + std::to_string(motion.animation),
                       "scene " + setup.scene_spec + " has " + std::to_string(have) + " animation(s)");
    }
    if (!(motion.animation_fps > 0 && motion.animation_fps <= 1000)) {
      throw InputError("--animation-fps", "expected more than 0 and at most 1000 frames per second");
    }
  }
  std::vector<Trace> frames;
  frames.reserve(static_cast<std::size_t>(motion.frames));
  for (int k = 0; k < motion.frames; ++k) {
    TraceSetup at = setup;
    at.camera = motion.cameras.empty() ? camera_on_path(setup.camera, motion.camera, k) : motion.cameras[static_cast<std::size_t>(k)];
    at.lights = lights_in_motion(setup.lights, motion.lights, k);
    frames.push_back(generate_trace(technique, at));
    if (motion.animation >= 0) frames.back().pose = Trace::Pose{motion.animation, k / motion.animation_fps, 0};
  }
  // One allocation per buffer for the whole sequence: the largest any frame needs.
  for (std::size_t k = 1; k < frames.size(); ++k) {
    if (frames[k].buffers.size() != frames[0].buffers.size())
      throw std::logic_error("generate_sequence: frame " + std::to_string(k) + " of " + technique + " declares another set of buffers");
    for (std::size_t b = 0; b < frames[0].buffers.size(); ++b) {
      if (frames[k].buffers[b].name != frames[0].buffers[b].name)
        throw std::logic_error("generate_sequence: frame " + std::to_string(k) + " of " + technique + " declares buffer '" +
                               frames[k].buffers[b].name + "' where the first declares '" + frames[0].buffers[b].name + "'");
      frames[0].buffers[b].bytes = std::max(frames[0].buffers[b].bytes, frames[k].buffers[b].bytes);
    }
  }
  for (auto& f : frames) f.buffers = frames[0].buffers;
  std::stringstream text;
  try {
    write_trace_frames(frames, text);
  } catch (const std::invalid_argument& e) {
    throw std::logic_error(std::string("generate_sequence of ") + technique + ": " + e.what());
  }
  return parse_trace_frames(text, "<generated " + technique + " sequence>");
}

}  // namespace tbdr
