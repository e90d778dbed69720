#include "workloads/technique.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <optional>
#include <sstream>
#include <stdexcept>

#include "sim/errors.hpp"
#include "sim/hash.hpp"

namespace tbdr {

// The registry: one line per technique. Each X(name) needs `TechniqueInfo technique_name();`
// defined in workloads/techniques/name.cpp.
#define TBDR_TECHNIQUE_LIST(X) \
  X(plain_forward)

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
