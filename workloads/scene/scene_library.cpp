#include "scene/scene_library.hpp"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cstdio>
#include <map>
#include <mutex>
#include <utility>

#include "kernel/errors.hpp"
#include "scene/atrium.hpp"
#include "scene/gltf_loader.hpp"

namespace tbdr {

namespace {

bool ends_with_ci(const std::string& s, const std::string& suffix) {
  if (s.size() < suffix.size()) return false;
  for (std::size_t i = 0; i < suffix.size(); ++i) {
    if (std::tolower(static_cast<unsigned char>(s[s.size() - suffix.size() + i])) != suffix[i]) return false;
  }
  return true;
}

std::string fmt_vec(const glm::vec3& v) {
  char buf[96];
  std::snprintf(buf, sizeof buf, "(%.4g, %.4g, %.4g)", static_cast<double>(v.x), static_cast<double>(v.y),
                static_cast<double>(v.z));
  return buf;
}

std::string fmt_bytes(std::uint64_t b) {
  char buf[64];
  if (b >= (1ull << 20))
    std::snprintf(buf, sizeof buf, "%llu bytes (%.1f MiB)", static_cast<unsigned long long>(b),
                  static_cast<double>(b) / (1024.0 * 1024.0));
  else
    std::snprintf(buf, sizeof buf, "%llu bytes", static_cast<unsigned long long>(b));
  return buf;
}

}  // namespace

std::optional<AtriumSpec> parse_atrium_spec(const std::string& spec) {
  if (spec == "atrium") return AtriumSpec{};
  if (spec.rfind("atrium:", 0) != 0) return std::nullopt;
  const std::string n = spec.substr(7);
  int detail = 0;
  const auto [ptr, ec] = std::from_chars(n.data(), n.data() + n.size(), detail);
  if (n.empty() || ec != std::errc() || ptr != n.data() + n.size() || detail < 0) {
    throw InputError(spec, "atrium detail must be an integer in 1..5, got '" + n + "'");
  }
  return AtriumSpec{detail};
}

Scene load_scene(const std::string& spec, const SceneLoadOptions& options) {
  if (const auto atrium = parse_atrium_spec(spec)) {
    return make_atrium(atrium->detail.value_or(default_atrium_detail), options.colour_texels);
  }
  if (ends_with_ci(spec, ".gltf") || ends_with_ci(spec, ".glb")) return load_gltf(spec);
  throw InputError(spec, "unknown scene: expected 'atrium', 'atrium:N' (N in 1..5) or a .gltf/.glb file");
}

std::shared_ptr<const Scene> shared_scene(const std::string& spec, const SceneLoadOptions& options) {
  const auto atrium = parse_atrium_spec(spec);
  if (!atrium) return std::make_shared<const Scene>(load_scene(spec, options));
  const int detail = atrium->detail.value_or(default_atrium_detail);
  // Built scenes by (detail, colour texels); kept for the process's life (a few per process).
  static std::mutex mutex;
  static std::map<std::pair<int, bool>, std::shared_ptr<const Scene>> built;
  const std::lock_guard<std::mutex> lock(mutex);
  std::shared_ptr<const Scene>& scene = built[{detail, options.colour_texels}];
  if (!scene) scene = std::make_shared<const Scene>(make_atrium(detail, options.colour_texels));
  return scene;
}

void print_scene_info(const Scene& scene, std::ostream& out) {
  struct ModeStats {
    std::uint64_t materials = 0, triangles = 0;
  };
  ModeStats modes[3];
  for (const Material& m : scene.materials) modes[static_cast<int>(m.alpha_mode)].materials++;
  for (const Instance& inst : scene.instances) {
    if (inst.submesh >= scene.submeshes.size()) continue;
    const SubMesh& sm = scene.submeshes[inst.submesh];
    if (sm.material >= scene.materials.size()) continue;
    modes[static_cast<int>(scene.materials[sm.material].alpha_mode)].triangles += sm.triangle_count();
  }
  std::uint64_t tex_bytes = 0;
  std::size_t missing = 0;
  for (const TextureInfo& t : scene.textures) {
    tex_bytes += t.gpu_bytes();
    missing += t.missing ? 1 : 0;
  }

  out << "scene         " << scene.name << "\n";
  out << "source        " << scene.source << "\n";
  out << "content hash  " << scene.content_hash << "\n";
  out << "triangles     " << scene.triangle_count() << "\n";
  out << "vertices      " << scene.vertex_count() << "\n";
  out << "sub-meshes    " << scene.submeshes.size() << "\n";
  out << "instances     " << scene.instances.size() << "\n";
  out << "materials     " << scene.materials.size() << "\n";
  const AlphaMode order[3] = {AlphaMode::Opaque, AlphaMode::PunchThrough, AlphaMode::Translucent};
  for (AlphaMode m : order) {
    const ModeStats& s = modes[static_cast<int>(m)];
    char line[128];
    std::snprintf(line, sizeof line, "  %-13s %llu materials, %llu triangles\n", to_string(m),
                  static_cast<unsigned long long>(s.materials), static_cast<unsigned long long>(s.triangles));
    out << line;
  }
  out << "bounds        min " << fmt_vec(scene.bounds.min) << " max " << fmt_vec(scene.bounds.max) << " size "
      << fmt_vec(scene.bounds.extent()) << "\n";
  out << "textures      " << scene.textures.size();
  if (missing) out << " (" << missing << " missing)";
  out << ", " << fmt_bytes(tex_bytes) << " with mip chains\n";
  out << "alpha masks   " << scene.alpha_masks.size() << "\n";
  out << "warnings      " << scene.warnings.size() << "\n";
  for (const std::string& w : scene.warnings) out << "  " << w << "\n";
}

}  // namespace tbdr
