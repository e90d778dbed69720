#pragma once
// One entry point for every scene a run can name: the built-in atrium or a glTF file, and a
// human-readable summary of a loaded scene (what `tbdrsim scene-info` prints).
#include <memory>
#include <optional>
#include <ostream>
#include <string>

#include "scene/scene.hpp"

namespace tbdr {

/// Detail level of a plain "atrium" spec.
inline constexpr int default_atrium_detail = 3;

/// An atrium scene spec: "atrium" or "atrium:N".
struct AtriumSpec {
  std::optional<int> detail;  ///< N of "atrium:N"; none for a plain "atrium" (default_atrium_detail)
};
/// The atrium spec `spec` names, or nullopt when it names something else; throws InputError naming
/// the spec when N is not a non-negative integer (make_atrium checks the range 1..5).
std::optional<AtriumSpec> parse_atrium_spec(const std::string& spec);

/// What of a scene to build beyond what the statistics read.
struct SceneLoadOptions {
  /// The atrium's procedural base colour texels (ColorTexels::rgba), which only the colour of
  /// images reads; without them the textures keep their sizes and every statistic is the same.
  /// A glTF file's images are decoded either way (their alpha makes the masks the tests read).
  bool colour_texels = true;
};

/// Loads a scene from a spec: "atrium" (detail 3), "atrium:N" (N in 1..5), or a path ending in
/// .gltf or .glb. Throws InputError naming the spec (or the file) when it cannot.
Scene load_scene(const std::string& spec, const SceneLoadOptions& options = {});

/// load_scene, shared: the procedural atrium is built once per process for each detail and set
/// of options, and later calls share it; a process forked after the first call (tbdrsim study's
/// trace generators and runs) inherits it instead of building it again (about 70 ms of CPU for
/// atrium:3). A glTF file is loaded afresh on every call (the file may change between calls).
std::shared_ptr<const Scene> shared_scene(const std::string& spec, const SceneLoadOptions& options = {});

/// Prints name, source, content hash, triangle/vertex/sub-mesh/instance counts, materials by alpha
/// mode (count and triangles), bounds, textures (count and GPU bytes) and warnings.
void print_scene_info(const Scene& scene, std::ostream& out);

}  // namespace tbdr
