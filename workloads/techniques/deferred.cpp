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
#include "techniques/technique.hpp"

namespace tbdr {

namespace {

Trace generate_deferred(const TraceSetup& setup, const TechniqueOptions& options) {
  Trace t = begin_trace(setup, "deferred", options,
                        {.no_msaa = "its G-buffer holds one surface per pixel and the light volumes read it as textures"});
  const std::string lights = add_light_buffer(t);
  const GbufferLayout layout = gbuffer_layout_option(options, "gbuffer");
  const std::uint32_t subdivisions = sphere_subdivisions_option(options);
  const bool translucent = translucent_forward_option(options);

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
           sphere_subdivisions_declaration(),
           {"translucent", "forward",
            "BLEND materials cannot live in the G-buffer (Billeter: blending no): forward = draw them in a "
            "forward pass over the lit frame (per-object light lists), skip = leave them out"}},
          &generate_deferred};
}

}  // namespace tbdr
