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
#include "techniques/technique.hpp"

namespace tbdr {

namespace {

Trace generate_plain_forward(const TraceSetup& setup, const TechniqueOptions& options) {
  Trace t = begin_trace(setup, "plain_forward", options);
  const std::string lights = add_light_buffer(t);

  ShaderDesc lit;
  lit.name = "forward_lit";
  lit.alu_ops = static_cast<std::uint32_t>(options.get_int("alu_ops", 0, 100000));
  lit.tex_fetches = static_cast<std::uint32_t>(options.get_int("tex_fetches", 0, 64));
  lit.varyings = 8;
  lit.light_alu_ops = static_cast<std::uint32_t>(options.get_int("light_alu_ops", 0, 100000));
  lit.light_source = LightSource::All;
  lit.color_outputs = 1;
  if (t.lights.empty()) {  // no light to evaluate: the reader rejects a per-light cost with no source
    lit.light_source = LightSource::None;
    lit.light_alu_ops = 0;
  }
  ShaderDesc masked = lit;
  masked.name = "forward_lit_masked";
  masked.alu_ops += 1;  // alpha test
  masked.discard = true;
  t.shaders = {lit, masked};

  PipelineState opaque;
  opaque.name = "opaque";
  opaque.shader = lit.name;
  opaque.depth_test = true;
  opaque.depth_write = true;
  opaque.depth_compare = CompareOp::Less;
  opaque.blend = BlendMode::Off;
  opaque.cull = CullMode::Back;  // double-sided materials disable culling per material
  PipelineState punch = opaque;
  punch.name = "masked";
  punch.shader = masked.name;
  PipelineState blended = opaque;
  blended.name = "blended";
  blended.depth_write = false;
  blended.blend = BlendMode::Alpha;
  t.pipelines = {opaque, punch, blended};

  PassDesc pass;
  pass.name = "main";
  const auto samples = static_cast<std::uint32_t>(setup.samples);
  Attachment color;
  color.name = "color";
  color.format = Format::Rgba8;
  color.samples = 1;
  color.load = LoadOp::Clear;
  color.store = StoreOp::Store;
  color.usage = AttachmentUsage::Color;
  if (samples > 1) {
    Attachment color_ms = color;
    color_ms.name = "color_ms";
    color_ms.samples = samples;
    color_ms.store = StoreOp::DontCare;
    color_ms.transient = true;
    color_ms.resolve = color.name;
    color.load = LoadOp::DontCare;  // fully overwritten by the resolve
    pass.attachments.push_back(color_ms);
  }
  pass.attachments.push_back(color);
  Attachment depth;
  depth.name = "depth";
  depth.format = Format::D24s8;
  depth.samples = samples;
  depth.load = LoadOp::Clear;
  depth.store = StoreOp::DontCare;
  depth.transient = true;
  depth.usage = AttachmentUsage::Depth;
  pass.attachments.push_back(depth);

  const std::pair<SceneSubset, const char*> draws[] = {
      {SceneSubset::Opaque, "opaque"}, {SceneSubset::Masked, "masked"}, {SceneSubset::Blended, "blended"}};
  for (const auto& [subset, pipeline] : draws) {
    DrawCmd d;
    d.geometry = GeometryKind::Scene;
    d.subset = subset;
    d.pipeline = pipeline;
    if (!lights.empty()) d.reads = {lights};
    pass.draws.push_back(d);
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
           {"light_alu_ops", "12", "FP32 ALU ops per light evaluated per fragment"}},
          &generate_plain_forward};
}

}  // namespace tbdr
