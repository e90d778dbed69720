// Tests of the technique generators (workloads/techniques/): every technique writes a trace that
// reads back and re-writes identically, for a tiny hand-built scene and for the atrium; MSAA is
// accepted or refused with the technique's name; buffer sizes follow the documented formulas;
// every option is documented and its default parses; the structure matches the expected rows of
// Billeter's table in docs/techniques.md; the same shading math costs the same everywhere.
// (Simulation results are not tested here.)
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <numbers>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "kernel/errors.hpp"
#include "trace/trace.hpp"
#include "scene/camera.hpp"
#include "scene/lights.hpp"
#include "scene/scene_library.hpp"
#include "techniques/technique.hpp"
#include "atrium_trace_setup.hpp"

namespace tbdr {
namespace {

const std::vector<std::string> kAllTechniques = {
    "plain_forward",   "forward_multipass",           "deferred",
    "tiled_deferred",  "clustered_deferred",          "forward_plus",
    "clustered_forward", "practical_clustered_forward", "cascaded_clustered_forward",
    "deferred_tile_store", "forward_light_stack",     "visibility_buffer",
    "light_prepass"};

const std::set<std::string> kMsaaTechniques = {"plain_forward",     "forward_multipass",
                                               "forward_plus",      "clustered_forward",
                                               "practical_clustered_forward", "cascaded_clustered_forward",
                                               "visibility_buffer"};

// A tiny scene: a floor quad (opaque), a masked card and a translucent pane, one instance each.
Scene tiny_scene() {
  Scene s;
  s.name = "tiny";
  s.source = "tiny.gltf";
  s.content_hash = "0123456789abcdef";
  const AlphaMode modes[] = {AlphaMode::Opaque, AlphaMode::PunchThrough, AlphaMode::Translucent};
  const char* names[] = {"floor", "card", "pane"};
  for (int i = 0; i < 3; ++i) {
    Material m;
    m.name = names[i];
    m.alpha_mode = modes[i];
    if (modes[i] == AlphaMode::Translucent) m.base_color.w = 0.4f;
    s.materials.push_back(m);
    SubMesh sm;
    sm.name = names[i];
    sm.material = static_cast<std::uint32_t>(i);
    const float z = -static_cast<float>(i);
    sm.positions = {{-1, -1, z}, {1, -1, z}, {1, 1, z}, {-1, 1, z}};
    sm.normals.assign(4, {0, 0, 1});
    sm.uvs = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
    sm.indices = {0, 1, 2, 0, 2, 3};
    s.submeshes.push_back(sm);
    Instance inst;
    inst.submesh = static_cast<std::uint32_t>(i);
    s.instances.push_back(inst);
  }
  update_bounds(s);
  return s;
}

TraceSetup tiny_setup(const Scene& scene, int samples = 1, int lights = 16, int width = 160, int height = 90) {
  TraceSetup setup;
  setup.scene = &scene;
  setup.scene_spec = "tiny.gltf";
  setup.camera.eye = {0.0f, 0.0f, 4.0f};
  setup.camera.target = {0.0f, 0.0f, 0.0f};
  setup.camera.near_plane = 0.1f;
  setup.camera.far_plane = 20.0f;
  setup.camera_name = "front";
  for (int i = 0; i < lights; ++i) {
    Light l;
    l.position = {-1.0f + 0.125f * static_cast<float>(i), 0.25f, 0.5f};
    l.radius = 1.5f;
    l.color = {1.0f, 0.9f, 0.8f};
    setup.lights.lights.push_back(l);
  }
  if (lights > 2) {
    setup.lights.lights[2].type = Light::Type::Spot;
    setup.lights.lights[2].cos_inner = 0.95f;
    setup.lights.lights[2].cos_outer = 0.7f;
  }
  setup.width = width;
  setup.height = height;
  setup.samples = samples;
  return setup;
}

std::string text_of(const Trace& t) { return trace_text(t); }

Trace parse_text(const std::string& text) {
  std::istringstream in(text);
  return parse_trace(in, "regenerated.trace");
}

void expect_round_trip(const Trace& t, const std::string& what) {
  const std::string once = text_of(t);
  const std::string twice = text_of(parse_text(once));
  EXPECT_EQ(once, twice) << what;
  EXPECT_EQ(trace_hash(t), trace_hash(parse_text(once))) << what;
}

const BufferDesc& buffer(const Trace& t, const std::string& name) {
  const BufferDesc* b = t.find_buffer(name);
  if (!b) throw std::runtime_error("no buffer " + name);
  return *b;
}

const DispatchCmd* find_dispatch(const Trace& t, const std::string& kernel) {
  for (const auto& c : t.commands)
    if (const auto* d = std::get_if<DispatchCmd>(&c); d && to_string(d->kernel) == kernel) return d;
  return nullptr;
}

const PassDesc* find_pass(const Trace& t, const std::string& name) {
  for (const auto& c : t.commands)
    if (const auto* p = std::get_if<PassDesc>(&c); p && p->name == name) return p;
  return nullptr;
}

// What leaves the chip: the usages of stored attachments plus the traffic classes of images
// written by kernels (light lists and data excluded: Billeter's column lists framebuffer-like buffers).
std::set<std::string> off_chip(const Trace& t) {
  std::set<std::string> out;
  for (const auto& c : t.commands) {
    if (const auto* p = std::get_if<PassDesc>(&c)) {
      for (const auto& a : p->attachments)
        if (a.store == StoreOp::Store) out.insert(to_string(a.usage));
    } else if (const auto* d = std::get_if<DispatchCmd>(&c)) {
      for (const auto& w : d->writes)
        if (const BufferDesc* b = t.find_buffer(w); b && b->content == BufferContent::Image)
          out.insert(to_string(b->traffic));
    }
  }
  return out;
}

// Geometry passes: how many times the opaque scene subset is drawn.
int geometry_passes(const Trace& t) {
  int n = 0;
  for (const auto& c : t.commands)
    if (const auto* p = std::get_if<PassDesc>(&c))
      for (const auto& d : p->draws)
        if (d.geometry == GeometryKind::Scene && d.subset == SceneSubset::Opaque) ++n;
  return n;
}

bool draws_blended(const Trace& t) {
  for (const auto& c : t.commands)
    if (const auto* p = std::get_if<PassDesc>(&c))
      for (const auto& d : p->draws)
        if (d.geometry == GeometryKind::Scene && d.subset == SceneSubset::Blended) {
          const PipelineState* ps = t.find_pipeline(d.pipeline);
          if (ps && ps->blend == BlendMode::Alpha) return true;
        }
  return false;
}

// ---- registry and options ----------------------------------------------------------------------------

TEST(TechniqueRegistry, EveryTechniqueIsRegisteredOnce) {
  const auto names = technique_names();
  EXPECT_EQ(names.front(), "plain_forward");
  for (const auto& n : kAllTechniques) EXPECT_EQ(std::count(names.begin(), names.end(), n), 1) << n;
  EXPECT_EQ(names.size(), kAllTechniques.size());
  for (const auto& info : techniques()) {
    EXPECT_FALSE(info.summary.empty()) << info.name;
    EXPECT_NE(info.generate, nullptr) << info.name;
  }
}

TEST(TechniqueOptions, EveryOptionHasADocAndItsDefaultParses) {
  const Scene scene = tiny_scene();
  for (const auto& info : techniques()) {
    std::set<std::string> keys;
    TraceSetup setup = tiny_setup(scene);
    const std::string defaults = text_of(generate_trace(info.name, setup));
    for (const auto& o : info.options) {
      EXPECT_TRUE(keys.insert(o.key).second) << info.name << ": duplicate option " << o.key;
      EXPECT_GE(o.doc.size(), 20u) << info.name << "." << o.key << " needs a doc string";
      EXPECT_FALSE(o.default_value.empty()) << info.name << "." << o.key;
      setup.options[o.key] = o.default_value;  // explicitly given default == implicit default
    }
    const Trace t = generate_trace(info.name, setup);
    EXPECT_EQ(text_of(t), defaults) << info.name;
    for (const auto& o : info.options) EXPECT_EQ(t.options.at(o.key), o.default_value) << info.name << "." << o.key;
  }
}

TEST(TechniqueOptions, MalformedOrOutOfRangeOptionsNameTheOption) {
  const Scene scene = tiny_scene();
  struct Case {
    std::string technique, key, value;
  };
  const Case cases[] = {
      {"forward_plus", "tile_px", "sixteen"},        {"forward_plus", "index_bytes", "3"},
      {"clustered_forward", "slices", "0"},          {"deferred", "gbuffer", "rgba8"},
      {"deferred", "gbuffer", "rgba8,d24s8"},        {"deferred", "translucent", "maybe"},
      {"deferred_tile_store", "pls_albedo_format", "d16"},
      {"forward_light_stack", "pls_bytes", "18"},    {"visibility_buffer", "id_bytes", "6"},
      {"cascaded_clustered_forward", "min_depth", "500"},
      {"forward_multipass", "lights_per_pass", "0"}, {"light_prepass", "light_buffer_format", "bogus"},
  };
  for (const auto& c : cases) {
    TraceSetup setup = tiny_setup(scene);
    setup.options[c.key] = c.value;
    try {
      generate_trace(c.technique, setup);
      ADD_FAILURE() << c.technique << " accepted " << c.key << "=" << c.value;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(c.key), std::string::npos) << e.what();
    }
  }
}

TEST(TechniqueOptions, IndexBytesMustAddressEveryLight) {
  const Scene scene = tiny_scene();
  TraceSetup setup = tiny_setup(scene, 1, 300);
  setup.options["index_bytes"] = "1";
  EXPECT_THROW(generate_trace("clustered_forward", setup), InputError);
  setup.options["index_bytes"] = "auto";
  const Trace t = generate_trace("clustered_forward", setup);
  const std::uint64_t clusters = 2 * 1 * 16;  // 160x90 in 128 px tiles x 16 slices
  EXPECT_EQ(buffer(t, "light_index").bytes, clusters * 300 * 2);  // auto: 2-byte indices for 300 lights
}

// ---- every technique generates and round-trips -----------------------------------------------------------

TEST(TechniqueGeneration, TinySceneTracesRoundTrip) {
  const Scene scene = tiny_scene();
  for (const auto& name : kAllTechniques) {
    const Trace t = generate_trace(name, tiny_setup(scene));
    EXPECT_EQ(t.technique, name);
    EXPECT_EQ(t.lights.size(), 16u) << name;
    EXPECT_EQ(t.frame.width, 160) << name;
    EXPECT_FALSE(t.commands.empty()) << name;
    expect_round_trip(t, name);
  }
}

TEST(TechniqueGeneration, AtriumTracesRoundTrip) {
  const Scene scene = load_scene("atrium:1");
  const TraceSetup setup = testing_support::atrium_entrance_setup(scene, 16, 160, 90);
  for (const auto& name : kAllTechniques) {
    const Trace t = generate_trace(name, setup);
    EXPECT_EQ(t.scene.kind, SceneKind::Atrium) << name;
    EXPECT_EQ(t.scene.detail, 1) << name;
    expect_round_trip(t, name);
  }
  // The visibility buffer sizes its work lists by the scene's materials.
  const Trace vb = generate_trace("visibility_buffer", setup);
  const std::uint64_t tiles = 10 * 6;
  const std::uint64_t materials = scene.materials.size();
  EXPECT_EQ(buffer(vb, "work_lists").bytes, tiles * materials * 12 + materials * 8);
}

TEST(TechniqueGeneration, TechniquesWithoutKernelsNeedNoLights) {
  const Scene scene = tiny_scene();
  for (const auto& name : {"forward_multipass", "deferred", "deferred_tile_store", "forward_light_stack",
                           "light_prepass"}) {
    const Trace t = generate_trace(name, tiny_setup(scene, 1, 0));
    EXPECT_TRUE(t.buffers.empty()) << name;
    expect_round_trip(t, name);
  }
  for (const auto& name : {"tiled_deferred", "clustered_deferred", "forward_plus", "clustered_forward",
                           "practical_clustered_forward", "cascaded_clustered_forward", "visibility_buffer"}) {
    try {
      generate_trace(name, tiny_setup(scene, 1, 0));
      ADD_FAILURE() << name << " accepted zero lights";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
    }
  }
}

TEST(TechniqueGeneration, OptionVariantsRoundTrip) {
  const Scene scene = tiny_scene();
  const std::vector<std::pair<std::string, std::map<std::string, std::string>>> variants = {
      {"forward_multipass", {{"prez", "no"}, {"lights_per_pass", "5"}}},
      {"deferred", {{"gbuffer", "rgba8,rgb10a2,rgba8,rg16f"}, {"sphere_subdivisions", "3"}}},
      {"deferred", {{"translucent", "skip"}}},
      {"tiled_deferred", {{"gbuffer", "rgba8,rgb10a2"}, {"tile_px", "32"}, {"max_lights_per_tile", "8"}}},
      {"clustered_deferred", {{"tile_px", "32"}, {"slices", "24"}, {"index_bytes", "2"}}},
      {"forward_plus", {{"depth_reload", "no"}, {"index_bytes", "auto"}}},
      {"clustered_forward", {{"depth_reload", "no"}, {"max_lights_per_cluster", "4"}}},
      {"practical_clustered_forward", {{"prez", "yes"}, {"tile_px", "32"}}},
      {"cascaded_clustered_forward", {{"dense", "no"}, {"min_depth", "2.5"}, {"slices", "6"}}},
      {"cascaded_clustered_forward", {{"prez", "no"}}},
      {"deferred_tile_store", {{"pls_albedo_format", "rgba8"}, {"translucent", "skip"}}},
      {"forward_light_stack", {{"pls_bytes", "8"}, {"sphere_subdivisions", "0"}}},
      {"visibility_buffer", {{"id_bytes", "8"}, {"tile_px", "8"}}},
      {"light_prepass", {{"normal_format", "rgb10a2"}, {"light_buffer_format", "r11g11b10f"}}},
  };
  for (const auto& [name, options] : variants) {
    for (int samples : {1, 4}) {
      if (samples > 1 && !kMsaaTechniques.count(name)) continue;
      TraceSetup setup = tiny_setup(scene, samples);
      setup.options = options;
      const Trace t = generate_trace(name, setup);
      for (const auto& [k, v] : options) EXPECT_EQ(t.options.at(k), v) << name;
      expect_round_trip(t, name);
    }
  }
  // cascaded dense=no is Olsson's sparse pipeline on cubical clusters; it needs its pre-pass.
  TraceSetup sparse = tiny_setup(scene);
  sparse.options = {{"dense", "no"}};
  const Trace t = generate_trace("cascaded_clustered_forward", sparse);
  EXPECT_NE(find_dispatch(t, "cluster_flag"), nullptr);
  EXPECT_EQ(find_dispatch(t, "cluster_flag")->params.at("slicing"), "cubical");
  sparse.options["prez"] = "no";
  EXPECT_THROW(generate_trace("cascaded_clustered_forward", sparse), InputError);
}

// ---- docs/techniques.md ------------------------------------------------------------------------------

TEST(TechniqueDocs, EveryTechniqueAndOptionIsDocumented) {
  const std::string path = std::string(TBDRSIM_SOURCE_DIR) + "/docs/techniques.md";
  std::ifstream in(path);
  ASSERT_TRUE(in) << path;
  std::stringstream buf;
  buf << in.rdbuf();
  const std::string doc = buf.str();
  for (const auto& info : techniques()) {
    const std::string heading = "### " + info.name + "\n";
    const auto at = doc.find(heading);
    ASSERT_NE(at, std::string::npos) << "docs/techniques.md has no section " << heading;
    const auto end = doc.find("\n### ", at + heading.size());
    const std::string section = doc.substr(at, end == std::string::npos ? std::string::npos : end - at);
    for (const auto& o : info.options) {
      EXPECT_NE(section.find("`" + o.key + "` = " + o.default_value), std::string::npos)
          << info.name << ": section does not give option " << o.key << " = " << o.default_value;
    }
    EXPECT_NE(doc.find("| " + info.name + " |"), std::string::npos) << info.name << " missing from the table";
  }
}

// ---- MSAA ------------------------------------------------------------------------------------------------

TEST(TechniqueMsaa, SupportedTechniquesResolveOnChipOthersNameThemselves) {
  const Scene scene = tiny_scene();
  for (const auto& name : kAllTechniques) {
    for (int samples : {2, 4}) {
      if (kMsaaTechniques.count(name)) {
        const Trace t = generate_trace(name, tiny_setup(scene, samples));
        expect_round_trip(t, name + " x" + std::to_string(samples));
        for (const auto& c : t.commands) {
          const auto* p = std::get_if<PassDesc>(&c);
          if (!p) continue;
          for (const auto& a : p->attachments) {
            if (!a.resolve.empty()) continue;
            if (a.usage == AttachmentUsage::Color && a.samples == 1) {
              EXPECT_TRUE(std::any_of(p->attachments.begin(), p->attachments.end(),
                                      [&](const Attachment& m) { return m.resolve == a.name; }))
                  << name << ": 1-sample color " << a.name << " is not a resolve target";
            } else {
              EXPECT_EQ(a.samples, static_cast<std::uint32_t>(samples)) << name << ": " << a.name;
            }
          }
        }
      } else {
        try {
          generate_trace(name, tiny_setup(scene, samples));
          ADD_FAILURE() << name << " accepted samples=" << samples;
        } catch (const InputError& e) {
          const std::string what = e.what();
          EXPECT_NE(what.find("technique " + name), std::string::npos) << what;
          EXPECT_NE(what.find("MSAA"), std::string::npos) << what;
        }
      }
    }
  }
}

// ---- buffer sizes --------------------------------------------------------------------------------------

TEST(TechniqueBuffers, TileListsScaleWithResolutionAndLights) {
  const Scene scene = tiny_scene();
  for (const auto& [w, h, lights] : {std::tuple{160, 90, 16}, std::tuple{320, 180, 16}, std::tuple{320, 180, 64},
                                     std::tuple{1920, 1080, 256}}) {
    const Trace t = generate_trace("forward_plus", tiny_setup(scene, 1, lights, w, h));
    const std::uint64_t tiles = std::uint64_t((w + 15) / 16) * ((h + 15) / 16);
    EXPECT_EQ(buffer(t, "tile_grid").bytes, tiles * kGridEntryBytes);
    EXPECT_EQ(buffer(t, "light_index").bytes, tiles * static_cast<std::uint64_t>(lights) * 4);
    EXPECT_EQ(buffer(t, "lights").bytes, kLightBufferBytesPerLight * static_cast<std::uint64_t>(lights));
    const DispatchCmd* cull = find_dispatch(t, "tile_light_cull");
    ASSERT_NE(cull, nullptr);
    EXPECT_EQ(cull->group_count(), tiles);
    EXPECT_EQ(cull->params.at("max_lights_per_tile"), std::to_string(lights));
  }
  const Scene s = tiny_scene();
  TraceSetup setup = tiny_setup(s, 1, 64);
  setup.options["max_lights_per_tile"] = "8";
  setup.options["index_bytes"] = "2";
  setup.options["tile_px"] = "32";
  const Trace t = generate_trace("forward_plus", setup);
  EXPECT_EQ(buffer(t, "light_index").bytes, std::uint64_t(5 * 3) * 8 * 2);
}

TEST(TechniqueBuffers, ClusterGridsScaleWithTilesSlicesAndLights) {
  const Scene scene = tiny_scene();
  for (const auto& [w, h, lights] : {std::tuple{160, 90, 16}, std::tuple{1280, 720, 16}, std::tuple{1280, 720, 300}}) {
    const std::uint64_t index_bytes = lights <= 256 ? 1 : 2;
    const Trace cf = generate_trace("clustered_forward", tiny_setup(scene, 1, lights, w, h));
    const std::uint64_t c128 = std::uint64_t((w + 127) / 128) * ((h + 127) / 128) * 16;
    EXPECT_EQ(buffer(cf, "cluster_grid").bytes, c128 * kGridEntryBytes);
    EXPECT_EQ(buffer(cf, "used_clusters").bytes, 4 + c128 * kUsedClusterEntryBytes);
    EXPECT_EQ(buffer(cf, "light_index").bytes, c128 * static_cast<std::uint64_t>(lights) * index_bytes);
    const Trace cd = generate_trace("clustered_deferred", tiny_setup(scene, 1, lights, w, h));
    EXPECT_EQ(buffer(cd, "cluster_grid").bytes, c128 * kGridEntryBytes);
    EXPECT_EQ(buffer(cd, "color").bytes, std::uint64_t(w) * h * 4);

    const Trace pf = generate_trace("practical_clustered_forward", tiny_setup(scene, 1, lights, w, h));
    const std::uint64_t c64 = std::uint64_t((w + 63) / 64) * ((h + 63) / 64) * 16;
    EXPECT_EQ(buffer(pf, "cluster_grid").bytes, c64 * kGridEntryBytes);
    EXPECT_EQ(buffer(pf, "light_index").bytes, c64 * static_cast<std::uint64_t>(lights) * index_bytes);
    EXPECT_EQ(pf.find_buffer("used_clusters"), nullptr);
    const DispatchCmd* assign = find_dispatch(pf, "cluster_light_assign");
    ASSERT_NE(assign, nullptr);
    EXPECT_EQ(assign->params.at("dense"), "yes");
    EXPECT_EQ(assign->group_count(), c64);
  }
}

TEST(TechniqueBuffers, CascadedSlicesReachTheFarPlane) {
  const Scene scene = tiny_scene();
  for (const auto& [w, h] : {std::pair{160, 90}, std::pair{1920, 1080}}) {
    const TraceSetup setup = tiny_setup(scene, 1, 16, w, h);
    const Trace t = generate_trace("cascaded_clustered_forward", setup);
    const DispatchCmd* assign = find_dispatch(t, "cluster_light_assign");
    ASSERT_NE(assign, nullptr);
    EXPECT_EQ(assign->params.at("slicing"), "cubical");
    const int slices = std::stoi(assign->params.at("slices"));
    const float min_depth = std::stof(assign->params.at("min_depth"));
    EXPECT_FLOAT_EQ(min_depth, 1.0f);  // auto: 10 x near
    const double ratio = 1.0 + 2.0 * std::tan(60.0 * std::numbers::pi / 360.0) * 64.0 / h;
    // The last slice starts before the far plane, the one before it ends short of it.
    EXPECT_GE(min_depth * std::pow(ratio, slices - 1), setup.camera.far_plane * 0.999) << w;
    EXPECT_LT(min_depth * std::pow(ratio, slices - 2), setup.camera.far_plane) << w;
    const std::uint64_t clusters = std::uint64_t((w + 63) / 64) * ((h + 63) / 64) * slices;
    EXPECT_EQ(buffer(t, "cluster_grid").bytes, clusters * kGridEntryBytes);
  }
  TraceSetup capped = tiny_setup(scene, 1, 16, 1920, 1080);
  capped.options["slices"] = "12";
  EXPECT_EQ(find_dispatch(generate_trace("cascaded_clustered_forward", capped), "cluster_light_assign")->params.at("slices"),
            "12");
}

TEST(TechniqueBuffers, GbufferAndVisibilityBytesFollowTheLayout) {
  const Scene scene = tiny_scene();
  const Trace d = generate_trace("deferred", tiny_setup(scene));
  const PassDesc* g = find_pass(d, "gbuffer");
  ASSERT_NE(g, nullptr);
  std::uint32_t bytes = 0;
  for (const auto& a : g->attachments) bytes += a.bytes_per_pixel();
  EXPECT_EQ(bytes, 4u + 4u + 4u);  // albedo rgba8 + normal rgb10a2 + d24s8
  const Trace td = generate_trace("tiled_deferred", tiny_setup(scene));
  bytes = 0;
  for (const auto& a : find_pass(td, "gbuffer")->attachments) bytes += a.bytes_per_pixel();
  EXPECT_EQ(bytes, 20u);  // Andersson: 4 x RGBA8 + D24S8

  TraceSetup setup = tiny_setup(scene, 4);
  setup.options["id_bytes"] = "8";
  const Trace vb = generate_trace("visibility_buffer", setup);
  const Attachment* ids = find_pass(vb, "visibility")->find_attachment("visibility");
  ASSERT_NE(ids, nullptr);
  EXPECT_EQ(ids->format, Format::Rg32ui);
  EXPECT_EQ(ids->bytes_per_pixel(), 32u);  // 8 B x 4 samples

  const Trace ts = generate_trace("deferred_tile_store", tiny_setup(scene));
  EXPECT_EQ(find_pass(ts, "main")->pls_bytes_per_pixel(), 12u);
  TraceSetup stack = tiny_setup(scene);
  stack.options["pls_bytes"] = "32";
  EXPECT_EQ(find_pass(generate_trace("forward_light_stack", stack), "main")->pls_bytes_per_pixel(), 32u);
  EXPECT_EQ(find_pass(generate_trace("forward_light_stack", tiny_setup(scene)), "main")->pls_bytes_per_pixel(), 16u);
}

// ---- structure: Billeter's table ---------------------------------------------------------------------------

TEST(TechniqueStructure, MatchesTheExpectedBilleterRows) {
  struct Row {
    std::string technique;
    std::set<std::string> off_chip;
    int geometry_passes;
    bool blending;
  };
  // 16 lights; forward_multipass: PreZ + 16 one-light passes. See docs/techniques.md.
  const Row rows[] = {
      {"plain_forward", {"color"}, 1, true},
      {"forward_multipass", {"color"}, 17, true},
      {"deferred", {"gbuffer", "depth", "color"}, 1, true},
      {"tiled_deferred", {"gbuffer", "depth", "color"}, 1, true},
      {"clustered_deferred", {"gbuffer", "depth", "color"}, 1, true},
      {"forward_plus", {"depth", "color"}, 2, true},
      {"clustered_forward", {"depth", "color"}, 2, true},
      {"practical_clustered_forward", {"color"}, 1, true},
      {"cascaded_clustered_forward", {"color"}, 2, true},
      {"deferred_tile_store", {"color"}, 1, true},
      {"forward_light_stack", {"color"}, 2, true},
      {"visibility_buffer", {"visibility", "depth", "color"}, 1, true},
      {"light_prepass", {"gbuffer", "depth", "color"}, 2, true},
  };
  const Scene scene = tiny_scene();
  for (const auto& r : rows) {
    const Trace t = generate_trace(r.technique, tiny_setup(scene));
    EXPECT_EQ(off_chip(t), r.off_chip) << r.technique;
    EXPECT_EQ(geometry_passes(t), r.geometry_passes) << r.technique;
    EXPECT_EQ(draws_blended(t), r.blending) << r.technique;
  }
  TraceSetup prez = tiny_setup(scene);
  prez.options["prez"] = "yes";
  EXPECT_EQ(geometry_passes(generate_trace("practical_clustered_forward", prez)), 2);
  prez.options["prez"] = "no";
  EXPECT_EQ(geometry_passes(generate_trace("forward_multipass", prez)), 16);
  TraceSetup skip = tiny_setup(scene);
  skip.options["translucent"] = "skip";
  for (const auto& name : {"deferred", "deferred_tile_store", "light_prepass", "tiled_deferred", "clustered_deferred",
                           "visibility_buffer"})
    EXPECT_FALSE(draws_blended(generate_trace(name, skip))) << name;
}

TEST(TechniqueStructure, ComputeLitFramesGetATranslucentPass) {
  // After the shading dispatch wrote the lit frame `color` (an image buffer): a barrier on it, then
  // pass `translucent` whose color attachment is that image (rgba8, 1 sample, loaded and stored
  // again) over the stored depth (loaded, not stored), drawing the blended subset alpha-blended
  // without depth writes. The last command of the frame.
  const Scene scene = tiny_scene();
  for (const auto& name : {"tiled_deferred", "clustered_deferred", "visibility_buffer"}) {
    SCOPED_TRACE(name);
    const Trace t = generate_trace(name, tiny_setup(scene));
    ASSERT_GE(t.commands.size(), 3u);
    const auto* shade = std::get_if<DispatchCmd>(&t.commands[t.commands.size() - 3]);
    ASSERT_NE(shade, nullptr);
    EXPECT_EQ(shade->writes, std::vector<std::string>{"color"});
    EXPECT_EQ(buffer(t, "color").content, BufferContent::Image);
    const auto* barrier = std::get_if<BarrierCmd>(&t.commands[t.commands.size() - 2]);
    ASSERT_NE(barrier, nullptr);
    EXPECT_EQ(barrier->resources, std::vector<std::string>{"color"});
    const auto* pass = std::get_if<PassDesc>(&t.commands.back());
    ASSERT_NE(pass, nullptr);
    EXPECT_EQ(pass->name, "translucent");
    ASSERT_EQ(pass->attachments.size(), 2u);
    const Attachment& color = pass->attachments[0];
    EXPECT_EQ(color.name, "color");
    EXPECT_EQ(color.format, Format::Rgba8);
    EXPECT_EQ(color.samples, 1u);
    EXPECT_EQ(color.load, LoadOp::Load);
    EXPECT_EQ(color.store, StoreOp::Store);
    EXPECT_EQ(color.usage, AttachmentUsage::Color);
    const Attachment& depth = pass->attachments[1];
    EXPECT_EQ(depth.name, "depth");
    EXPECT_EQ(depth.load, LoadOp::Load);
    EXPECT_EQ(depth.store, StoreOp::DontCare);
    ASSERT_EQ(pass->draws.size(), 1u);
    EXPECT_EQ(pass->draws[0].subset, SceneSubset::Blended);
    const PipelineState* ps = t.find_pipeline(pass->draws[0].pipeline);
    ASSERT_NE(ps, nullptr);
    EXPECT_EQ(ps->blend, BlendMode::Alpha);
    EXPECT_TRUE(ps->depth_test);
    EXPECT_FALSE(ps->depth_write);
  }
  // With MSAA (the visibility buffer) the stored depth is multisampled and the frame is not: no pass.
  EXPECT_EQ(find_pass(generate_trace("visibility_buffer", tiny_setup(scene, 4)), "translucent"), nullptr);
}

TEST(TechniqueStructure, MultipassBatchesCoverEveryLightOnce) {
  const Scene scene = tiny_scene();
  for (int per_pass : {1, 3, 16, 40}) {
    TraceSetup setup = tiny_setup(scene);
    setup.options["lights_per_pass"] = std::to_string(per_pass);
    const Trace t = generate_trace("forward_multipass", setup);
    std::vector<int> seen(16, 0);
    int lit_passes = 0;
    for (const auto& d : std::get<PassDesc>(t.commands[0]).draws) {
      if (d.subset != SceneSubset::Opaque || d.pipeline == "prez") continue;
      ++lit_passes;
      const PipelineState* p = t.find_pipeline(d.pipeline);
      EXPECT_EQ(p->blend, lit_passes == 1 ? BlendMode::Off : BlendMode::Add);
      EXPECT_EQ(p->depth_compare, CompareOp::Equal);
      for (std::uint32_t l = 0; l < 16; ++l) seen[l] += d.lights.contains(l);
    }
    EXPECT_EQ(lit_passes, (16 + per_pass - 1) / per_pass);
    for (int s : seen) EXPECT_EQ(s, 1) << "lights_per_pass=" << per_pass;
  }
}

TEST(TechniqueStructure, DeferredLightVolumesAndPls) {
  const Scene scene = tiny_scene();
  const Trace d = generate_trace("deferred", tiny_setup(scene));
  const PassDesc* lighting = find_pass(d, "lighting");
  ASSERT_NE(lighting, nullptr);
  EXPECT_EQ(lighting->depth_attachment()->load, LoadOp::Load);
  const DrawCmd& ambient = lighting->draws.at(0);
  EXPECT_EQ(ambient.geometry, GeometryKind::Fullscreen);
  EXPECT_EQ(d.find_shader(d.find_pipeline(ambient.pipeline)->shader)->light_source, LightSource::None);
  const DrawCmd& volumes = lighting->draws.at(1);
  EXPECT_EQ(volumes.geometry, GeometryKind::LightSpheres);
  const PipelineState* vp = d.find_pipeline(volumes.pipeline);
  EXPECT_EQ(vp->cull, CullMode::Front);
  EXPECT_EQ(vp->depth_compare, CompareOp::GreaterEqual);
  EXPECT_FALSE(vp->depth_write);
  EXPECT_EQ(vp->blend, BlendMode::Add);
  EXPECT_EQ(d.find_shader(vp->shader)->light_source, LightSource::Proxy);
  EXPECT_EQ(volumes.fetch, std::vector<std::string>{"depth"});

  const Trace ts = generate_trace("deferred_tile_store", tiny_setup(scene));
  ASSERT_EQ(ts.commands.size(), 1u);
  const PassDesc& main = std::get<PassDesc>(ts.commands[0]);
  EXPECT_TRUE(main.depth_attachment()->transient);
  const ShaderDesc* accum = ts.find_shader("light_volume_pls");
  EXPECT_EQ(accum->pls, PlsAccess::ReadWrite);
  EXPECT_EQ(accum->color_outputs, 0u);
  EXPECT_EQ(ts.find_shader("resolve")->pls, PlsAccess::Read);

  const Trace ls = generate_trace("forward_light_stack", tiny_setup(scene));
  const ShaderDesc* splat = ls.find_shader("light_splat");
  EXPECT_EQ(splat->light_source, LightSource::None);
  EXPECT_EQ(splat->pls, PlsAccess::ReadWrite);
  EXPECT_EQ(ls.find_shader("forward_lit")->light_source, LightSource::PlsStack);
}

// ---- costs -----------------------------------------------------------------------------------------------

TEST(TechniqueCosts, SameMathCostsTheSameEverywhere) {
  EXPECT_EQ(kForwardLitAluOps, 20u);  // plain_forward's default alu_ops
  const Scene scene = tiny_scene();
  for (const auto& name : kAllTechniques) {
    const Trace t = generate_trace(name, tiny_setup(scene));
    for (const auto& s : t.shaders) {
      if (s.light_source != LightSource::None) {
        EXPECT_EQ(s.light_alu_ops, kLightAluOps) << name << ": " << s.name;
      }
      if (s.name == "forward_lit" || s.name == "forward_translucent") {
        std::uint32_t lookup = 0;
        if (s.light_source == LightSource::TileList) lookup = kTileLookupAluOps;
        if (s.light_source == LightSource::ClusterList) lookup = kClusterLookupAluOps;
        if (s.light_source == LightSource::PlsStack) lookup = kPlsStackReadAluOps;
        EXPECT_EQ(s.alu_ops, kForwardLitAluOps + lookup) << name << ": " << s.name;
        EXPECT_EQ(s.tex_fetches, kSurfaceTexFetches) << name;
        EXPECT_EQ(s.varyings, kSurfaceVaryings) << name;
      }
      if (s.name == "gbuffer") {
        EXPECT_GE(s.alu_ops, kSurfaceAluOps + kGbufferEncodeAluOps) << name;
      }
    }
  }
}

}  // namespace
}  // namespace tbdr
