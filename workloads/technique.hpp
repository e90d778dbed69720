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

#include "sim/trace.hpp"
#include "workloads/camera.hpp"
#include "workloads/lights.hpp"
#include "workloads/scene.hpp"

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

}  // namespace tbdr
