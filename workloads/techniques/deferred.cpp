// Traditional deferred shading: a G-buffer pass stores the surface (MRT) to DRAM; a lighting pass
// reloads depth, draws one proxy sphere per light that reads the G-buffer as textures and adds the
// light's contribution with blending (CMU 15-769 lecture "light volumes"; Billeter 2015
// "Traditional Deferred": "many reads from G-Buffer + many writes to framebuffer", "store G-buffer
// to RAM (and potentially restore depth to on-chip)").
// Billeter's table: off-chip buffers = G-buffers; 1 geometry pass; overshading no; MSAA no;
// blending no (BLEND materials cannot live in a G-buffer: with translucent=forward they are drawn
// afterwards in a forward pass over the lit frame, as deferred renderers do).
//
// Pass `gbuffer`: albedo rgba8 + normal rgb10a2 (option `gbuffer`) + depth d24s8, all cleared and
//   stored; opaque and masked geometry (shader gbuffer: surface 12 + encode 4 ALU, 2 fetches,
//   8 varyings, one output per target; +1 ALU per extra target; masked +1 ALU, discard).
// Pass `lighting`: color rgba8 (clear, store), depth (load: the light volumes are depth tested).
//   1. fullscreen `ambient` (reads=albedo): the ambient term once per pixel (docs/kernels.md: a
//      shader with light_source=none writes the ambient term). 3 + 5 ALU, 1 fetch.
//   2. light_spheres `light_volume`: cull=front, depth_compare=greater_equal, no depth write,
//      blend=add, light_source=proxy; reads the G-buffer from DRAM, fetches depth on chip.
//      decode 4 (+1 per extra target) + position reconstruction 8 + output 5 = 17 ALU,
//      one fetch per G-buffer target, 3 varyings (view ray), 12 ALU for its light.
//   3. translucent=forward: BLEND geometry, forward-lit from per-object light lists, alpha blend.
//
// gbuffer_storage=onchip: the same frame as one render pass with subpasses, as the PowerVR SDK's
// Deferred Shading example renders it (the workload of Imagination's "On-Chip Memory Performance"
// measurements, PowerVR Performance Recommendations): pass `main` holds color rgba8 (clear, store),
// the G-buffer targets (clear, store=dont_care, transient) and depth d24s8 (transient).
//   1. opaque + masked `gbuffer_onchip`: the gbuffer shader with one more output, the ambient term
//      into color (1 + targets outputs; the light volumes add onto it).
//   2. light_spheres `light_volume_onchip`: as above, but the G-buffer and depth are read on chip
//      (fetch=: framebuffer fetch / input attachments), no texture fetch.
//   3. translucent=forward as above.
// Over the on-chip budget the driver ends the render before the light volumes
// (pls.over_budget = split_render): the G-buffer goes to memory and is read back as images.
#include "techniques/technique.hpp"

#include "kernel/errors.hpp"

namespace tbdr {

namespace {

Trace generate_deferred(const TraceSetup& setup, const TechniqueOptions& options) {
  Trace t = begin_trace(setup, "deferred", options,
                        {.no_msaa = "its G-buffer holds one surface per pixel and the light volumes read it as textures"});
  const std::string lights = add_light_buffer(t);
  const GbufferLayout layout = gbuffer_layout_option(options, "gbuffer");
  const std::uint32_t subdivisions = sphere_subdivisions_option(options);
  const bool translucent = translucent_forward_option(options);

  const std::string& storage = options.get("gbuffer_storage");
  if (storage == "onchip") {
    const auto targets = static_cast<std::uint32_t>(layout.formats.size());
    PassDesc pass = color_pass("main", 1);
    for (std::size_t i = 0; i < layout.formats.size(); ++i)
      pass.attachments.insert(pass.attachments.end() - 1,
                              make_attachment(layout.names[i], layout.formats[i], 1, LoadOp::Clear, StoreOp::DontCare,
                                              AttachmentUsage::Gbuffer, true));
    const ShaderDesc gbuffer = gbuffer_shader("gbuffer_onchip", layout.extra_targets(), 1 + targets);
    add_scene_shading(t, pass, "gbuffer_onchip", gbuffer, masked_variant(gbuffer));
    t.shaders.push_back(light_volume_shader("light_volume_onchip", 0, layout.extra_targets(), 1));
    t.pipelines.push_back(light_volume_pipeline("light_volume_onchip", "light_volume_onchip", BlendMode::Add));
    std::vector<std::string> fetch = layout.names;
    fetch.push_back("depth");
    add_light_volumes(pass, "light_volume_onchip", lights, subdivisions, {}, fetch);
    if (translucent) {
      add_translucent_state(t);
      add_translucent_draw(pass, lights);
    }
    t.commands.emplace_back(std::move(pass));
    return t;
  }
  if (storage != "memory")
    throw InputError("option gbuffer_storage=" + storage, "expected memory or onchip, got '" + storage + "'");

  PassDesc gbuffer = make_gbuffer_pass(t, layout);

  PassDesc lighting = color_pass("lighting", 1, LoadOp::Load);  // the light volumes are depth tested
  add_ambient(t, lighting, "albedo");
  const auto targets = static_cast<std::uint32_t>(layout.formats.size());
  t.shaders.push_back(light_volume_shader("light_volume", targets, layout.extra_targets(), 1));
  t.pipelines.push_back(light_volume_pipeline("light_volume", "light_volume", BlendMode::Add));
  add_light_volumes(lighting, "light_volume", lights, subdivisions, layout.names, {"depth"});
  if (translucent) {
    add_translucent_state(t);
    add_translucent_draw(lighting, lights);
  }

  t.commands.emplace_back(std::move(gbuffer));
  t.commands.emplace_back(std::move(lighting));
  return t;
}

}  // namespace

TechniqueInfo technique_deferred() {
  return {"deferred",
          "traditional deferred: G-buffer MRT stored to DRAM, one blended proxy sphere per light reading it "
          "(Billeter 2015; CMU 15-769 light volumes)",
          {{"gbuffer", "rgba8,rgb10a2",
            "G-buffer color targets in order: albedo, normal, then extra targets (specular, motion, ...) that "
            "only cost bandwidth; default 8 B/px + 4 B depth (the 15-769 lecture's example layout is 4 x 32-bit "
            "targets + D24S8 = 20 B/px: rgba8,rgba8,rgba8,rgba8)"},
           {"gbuffer_storage", "memory",
            "memory = the G-buffer pass stores its targets and a lighting pass reads them as textures; onchip = "
            "one render pass with subpasses (the PowerVR SDK Deferred Shading example): transient G-buffer "
            "targets the light volumes read on chip (framebuffer fetch / input attachments)"},
           sphere_subdivisions_declaration(),
           {"translucent", "forward",
            "BLEND materials cannot live in the G-buffer (Billeter: blending no): forward = draw them in a "
            "forward pass over the lit frame (per-object light lists), skip = leave them out"}},
          &generate_deferred};
}

}  // namespace tbdr
