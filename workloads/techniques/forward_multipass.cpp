// Forward multi-pass: the scene is drawn once per batch of lights, each geometry pass adding its
// batch's contribution with additive blending (CMU 15-769 "Deferred Shading" lecture: "for each
// light: render scene with additive blending", z buffer initialised by a z pre-pass).
// Billeter's table (not listed there; by the same criteria): off-chip buffers = color only (every
// pass is a draw of one render pass, so depth and color stay on chip); geometry passes =
// ceil(lights / lights_per_pass) (+1 with PreZ; bounded to what each batch's lights reach);
// overshading no with PreZ (equal test); MSAA yes;
// blending yes (translucent geometry is drawn once, after the additive passes).
//
// Render pass `main`: color rgba8 (clear, store; MSAA resolves on chip) and depth d24s8 (transient).
// Draws, in order:
//   prez=yes: depth-only opaque + masked (alpha test) draws; every lighting pass then tests equal.
//   lighting pass 0: opaque + masked, blend off: ambient + lights of batch 0 (lights=0-(n-1)).
//     Without PreZ it writes depth (less) and the masked draw runs the alpha test.
//   lighting pass b > 0: opaque + masked, depth equal, no write, blend add: the batch's light
//     contributions only (docs/kernels.md: blend=add leaves the ambient term out). Punch-through
//     geometry is forced opaque there: its discarded samples fail the equal test.
//     With light_bounds=yes (the default) each such pass is drawn as a multi-pass renderer draws
//     a light: a scissor rectangle around the screen rectangle of the batch's light spheres (the
//     whole frame when one reaches the near plane) and only the objects whose bounds touch the
//     union of the spheres' boxes (the application's object culling: trace keys scissor=,
//     cull_min=, cull_max=, version 3); a batch that reaches no visible pixel is not drawn.
//     Lights add exactly 0 beyond their radius, so the image is the same as light_bounds=no,
//     which draws the whole scene over the whole frame in every pass. Pass 0 writes the ambient
//     term of every pixel, so it stays whole.
//   translucent (BLEND) geometry: once, lights from the per-object lists, alpha blending (additive
//     multi-pass cannot alpha-blend a surface lit in several passes).
//
// Shader cost (technique.hpp constants): forward_lit = kForwardLitAluOps 20 ALU (surface 12,
// ambient 3, output 5), 2 fetches, 8 varyings, light_source=all over the draw's batch, 12 ALU per
// light; forward_add is the same shader writing light contributions only (it still evaluates the
// surface: the redundant per-pass work the lecture lists as the method's overhead);
// forward_lit_masked +1 ALU alpha test; depth_only 0 ALU; depth_only_masked 1 ALU + 1 fetch.
#include <algorithm>

#include "techniques/technique.hpp"

namespace tbdr {

namespace {

/// What the lights of one batch reach together: the union of their screen rectangles and of their
/// culling boxes (light_reach), over the lights that reach a visible pixel.
struct BatchReach {
  bool visible = false;     ///< some light of the batch reaches a visible pixel
  bool full_frame = false;  ///< one of them reaches every pixel (it crosses the near plane)
  ScissorRect rect;
  CullBox box;
};

/// The reach of lights [first, end) of the trace, seen by its camera in its frame.
BatchReach batch_reach(const Trace& t, std::uint32_t first, std::uint32_t end) {
  BatchReach out;
  for (std::uint32_t l = first; l < end; ++l) {
    const LightReach r = light_reach(t.lights[l], t.camera, t.frame.width, t.frame.height);
    if (!r.visible) continue;
    if (!out.visible) {
      out.visible = true;
      out.rect = r.rect;
      out.box = r.box;
    } else {
      out.rect = {std::min(out.rect.x0, r.rect.x0), std::min(out.rect.y0, r.rect.y0), std::max(out.rect.x1, r.rect.x1),
                  std::max(out.rect.y1, r.rect.y1)};
      out.box = {glm::min(out.box.min, r.box.min), glm::max(out.box.max, r.box.max)};
    }
    out.full_frame = out.full_frame || r.full_frame;
  }
  return out;
}

Trace generate_forward_multipass(const TraceSetup& setup, const TechniqueOptions& options) {
  Trace t = begin_trace(setup, "forward_multipass", options);
  const std::string lights = add_light_buffer(t);
  const auto per_pass = static_cast<std::uint32_t>(options.get_int("lights_per_pass", 1, 1 << 20));
  const bool prez = options.get_bool("prez");
  const bool light_bounds = options.get_bool("light_bounds");
  const auto samples = static_cast<std::uint32_t>(setup.samples);
  const auto light_count = static_cast<std::uint32_t>(t.lights.size());
  const LightSource source = light_count > 0 ? LightSource::All : LightSource::None;

  const ShaderDesc lit =
      make_shader("forward_lit", kForwardLitAluOps, kSurfaceTexFetches, kSurfaceVaryings, kLightAluOps, source, 1);
  const ShaderDesc lit_masked = masked_variant(lit);
  t.shaders.push_back(lit);
  t.shaders.push_back(lit_masked);

  PassDesc pass = color_pass("main", samples);
  if (prez) {
    add_prez(t, pass);
    t.pipelines.push_back(depth_equal_pipeline("first_equal", lit.name));
  } else {
    t.pipelines.push_back(depth_writing_pipeline("first", lit.name));
    t.pipelines.push_back(depth_writing_pipeline("first_masked", lit_masked.name));
  }
  if (light_count > per_pass) t.pipelines.push_back(depth_equal_pipeline("additive", lit.name, BlendMode::Add));
  add_translucent_state(t);

  const std::uint32_t batches = light_count == 0 ? 1 : (light_count + per_pass - 1) / per_pass;
  for (std::uint32_t b = 0; b < batches; ++b) {
    LightSelection sel;
    const std::uint32_t first_light = b * per_pass, end_light = std::min(light_count, (b + 1) * per_pass);
    if (light_count > 0) {
      sel.all = false;
      sel.ranges.push_back({first_light, end_light - 1});
    }
    const bool first = b == 0;
    const std::string opaque = first ? (prez ? "first_equal" : "first") : "additive";
    const std::string masked = first ? (prez ? "first_equal" : "first_masked") : "additive";
    DrawCmd o = scene_draw(SceneSubset::Opaque, opaque, {lights});
    DrawCmd m = scene_draw(SceneSubset::Masked, masked, {lights});
    if (light_count > 0) o.lights = m.lights = sel;
    // An additive pass adds only its lights' contributions, which are exactly 0 beyond their
    // radii: it draws the objects their spheres touch inside their screen rectangle, or nothing
    // when no light of the batch reaches a visible pixel. Pass 0 writes the ambient term of every
    // pixel (and the depth without PreZ): the whole frame, every object.
    if (!first && light_bounds) {
      const BatchReach reach = batch_reach(t, first_light, end_light);
      if (!reach.visible) continue;
      o.cull = m.cull = reach.box;
      if (!reach.full_frame) o.scissor = m.scissor = reach.rect;
    }
    pass.draws.push_back(o);
    pass.draws.push_back(m);
  }
  add_translucent_draw(pass, lights);
  t.commands.emplace_back(std::move(pass));
  return t;
}

}  // namespace

TechniqueInfo technique_forward_multipass() {
  return {"forward_multipass",
          "one additive geometry pass per batch of lights after a depth pre-pass; color only leaves the chip "
          "(CMU 15-769 deferred shading lecture, multi-pass forward)",
          {{"lights_per_pass", "1",
            "lights evaluated per additive geometry pass; 1 is the lecture's 'for each light: render scene with "
            "additive blending', larger batches model shaders specialised for N lights"},
           {"light_bounds", "yes",
            "yes: each additive pass (after the first) draws with a scissor rectangle around its lights' screen "
            "bounds and culls the objects whose bounds miss their spheres, as multi-pass renderers do; no: every "
            "pass draws the whole scene over the whole frame. The image is the same (lights add exactly 0 beyond "
            "their radius)"},
           {"prez", "yes",
            "depth-only pre-pass first so every lighting pass tests depth equal (the lecture: 'assume z buffer is "
            "initialized using a z prepass'); no: the first lighting pass writes depth"}},
          &generate_forward_multipass};
}

}  // namespace tbdr
