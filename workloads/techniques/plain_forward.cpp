// Plain forward shading: one render pass, one geometry pass, every fragment evaluates every light.
// Billeter's table: off-chip buffers = color only; 1 geometry pass; overshading yes (HSR on a TBDR
// removes most of it for opaque geometry); MSAA yes; blending yes.
//
// Pass `main`: color rgba8 (clear, store) and depth d24s8 (clear, dont_care, transient: on a TBDR
// GPU depth never leaves the chip). With MSAA, a multisampled transient color attachment resolves
// on chip into the single-sample color that is stored. Draw order: opaque (depth test + write),
// masked / punch-through (alpha test, depth test + write), blended / translucent (depth test, no
// depth write, alpha blend), as an application would submit them.
//
// Declared shader cost (options, so a sweep can vary them):
//   alu_ops = 20        base per fragment: normal renormalise (~6), base color x texture and
//                       material factors (~6), ambient + output conversion (~8)
//   tex_fetches = 2     base color and normal map
//   light_alu_ops = 12  per light: vector to light and distance (~5: sub, dot, rsqrt, mul),
//                       finite-radius attenuation (1-(d/r)^2)^2 (~3), N.L clamp (~2), accumulate (~2)
//   varyings = 8        world position (3), normal (3), uv (2)
// The masked shader adds 1 ALU op for the alpha test and may discard.
// draw_order = submesh: one draw per sub-mesh in scene order (opaque after punch-through and
// blended geometry), the workload of bench/tag_buffers.sh. draw_order = near_to_far / far_to_near:
// opaque, then masked sub-meshes sorted by camera distance, then the blended geometry: the best and
// worst submission orders for a TBR's per-tile early-Z (bench/hsr_anchor.sh).
#include "techniques/technique.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "kernel/errors.hpp"

namespace tbdr {

namespace {

Trace generate_plain_forward(const TraceSetup& setup, const TechniqueOptions& options) {
  Trace t = begin_trace(setup, "plain_forward", options);
  const std::string lights = add_light_buffer(t);
  const auto alu_ops = static_cast<std::uint32_t>(options.get_int("alu_ops", 0, 100000));
  const auto tex_fetches = static_cast<std::uint32_t>(options.get_int("tex_fetches", 0, 64));
  const auto light_alu_ops = static_cast<std::uint32_t>(options.get_int("light_alu_ops", 0, 100000));
  // No light to evaluate: no light source (the reader rejects a per-light cost with no source).
  const LightSource source = t.lights.empty() ? LightSource::None : LightSource::All;
  const ShaderDesc lit = make_shader("forward_lit", alu_ops, tex_fetches, kSurfaceVaryings, light_alu_ops, source, 1);
  const ShaderDesc masked = masked_variant(lit);
  t.shaders = {lit, masked};
  // Double-sided materials disable back-face culling per material.
  t.pipelines = {depth_writing_pipeline("opaque", lit.name), depth_writing_pipeline("masked", masked.name),
                 blended_pipeline("blended", lit.name)};

  PassDesc pass = color_pass("main", static_cast<std::uint32_t>(setup.samples));
  const std::string& order = options.get("draw_order");
  if (order == "pass") {
    add_scene_draws(pass, "opaque", "masked", {lights});
    pass.draws.push_back(scene_draw(SceneSubset::Blended, "blended", {lights}));
  } else if (order == "submesh" && setup.scene) {
    // One draw per sub-mesh in the scene's order, with its material's pipeline: opaque sub-meshes
    // declared after punch-through or blended ones are drawn after them.
    for (const SubMesh& sm : setup.scene->submeshes) {
      const AlphaMode mode = setup.scene->materials[sm.material].alpha_mode;
      DrawCmd d = scene_draw(SceneSubset::All, mode == AlphaMode::Opaque ? "opaque" : mode == AlphaMode::PunchThrough ? "masked" : "blended",
                             {lights});
      d.submesh = sm.name;
      pass.draws.push_back(std::move(d));
    }
  } else if ((order == "near_to_far" || order == "far_to_near") && setup.scene) {
    // Opaque, then masked sub-meshes, each sorted by the camera distance of their nearest
    // instance's bounds centre (near_to_far: what an engine sorting for early-Z submits;
    // far_to_near: a painter's order, early-Z's worst case), then the blended geometry.
    for (const AlphaMode mode : {AlphaMode::Opaque, AlphaMode::PunchThrough}) {
      std::vector<std::pair<float, const SubMesh*>> sorted;
      for (std::size_t m = 0; m < setup.scene->submeshes.size(); ++m) {
        const SubMesh& sm = setup.scene->submeshes[m];
        if (setup.scene->materials[sm.material].alpha_mode != mode) continue;
        Bounds local{glm::vec3(std::numeric_limits<float>::infinity()), glm::vec3(-std::numeric_limits<float>::infinity())};
        for (const glm::vec3& v : sm.positions) {
          local.min = glm::min(local.min, v);
          local.max = glm::max(local.max, v);
        }
        float nearest = std::numeric_limits<float>::infinity();
        for (const Instance& inst : setup.scene->instances) {
          if (inst.submesh != m || sm.positions.empty()) continue;
          const glm::vec3 centre = glm::vec3(inst.world * glm::vec4(local.center(), 1.0f));
          nearest = std::min(nearest, glm::length(centre - setup.camera.eye));
        }
        if (std::isfinite(nearest)) sorted.emplace_back(order == "near_to_far" ? nearest : -nearest, &sm);
      }
      std::stable_sort(sorted.begin(), sorted.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
      for (const auto& [key, sm] : sorted) {
        DrawCmd d = scene_draw(SceneSubset::All, mode == AlphaMode::Opaque ? "opaque" : "masked", {lights});
        d.submesh = sm->name;
        pass.draws.push_back(std::move(d));
      }
    }
    pass.draws.push_back(scene_draw(SceneSubset::Blended, "blended", {lights}));
  } else {
    throw InputError("option draw_order=" + order, order != "pass" ? "needs the loaded scene" : "expected pass, submesh, near_to_far or far_to_near, got '" + order + "'");
  }
  t.commands.emplace_back(std::move(pass));
  return t;
}

}  // namespace

TechniqueInfo technique_plain_forward() {
  return {"plain_forward",
          "one pass, every fragment evaluates every light; only color leaves the chip (Billeter 2015)",
          {{"alu_ops", "20", "FP32 ALU ops per fragment, excluding lights"},
           {"tex_fetches", "2", "bilinear texture fetches per fragment (base color, normal map)"},
           {"light_alu_ops", "12", "FP32 ALU ops per light evaluated per fragment"},
           {"draw_order", "pass",
            "pass: opaque, then masked, then blended draws (as sorted engines submit); submesh: one draw per sub-mesh "
            "in the scene's order, so opaque geometry follows punch-through and blended geometry (an unsorted "
            "engine walking its scene; shows what the ISP's tag buffers do); near_to_far / far_to_near: opaque "
            "then masked sub-meshes sorted by camera distance (an engine sorting for early-Z; a painter's "
            "order, early-Z's worst case), then the blended geometry (the range a TBR's early-Z spans)"}},
          &generate_plain_forward};
}

}  // namespace tbdr
