// Light pre-pass / deferred lighting (Engel 2008; summarised in the Burns & Hunt notes in
// reference/: a z-only pass that also stores normals and the specular lobe, a pass computing
// diffuse and specular irradiance into a light buffer, and a second geometry pass that re-renders
// the scene combining the light buffer with the materials).
// Billeter's table (not listed; by the same criteria): off-chip buffers = normals + depth + light
// buffer; 2 geometry passes; overshading no (the second pass tests depth equal); MSAA no; blending
// no (with translucent=forward, BLEND geometry is forward-lit over the light buffer).
//
// Mapping onto docs/kernels.md (which cannot express it exactly):
//   Pass `normals` (geometry pass 1): normal (option normal_format, usage gbuffer) and depth d24s8,
//     cleared and stored. Shader `normals`: normal part of the surface 6 + encode 4 ALU, 1 fetch
//     (normal map), 5 varyings (masked: +1 ALU, +1 fetch for alpha, discard).
//   Pass `lighting`: light_buffer (option light_buffer_format, usage color; clear, store), depth
//     (load, for the depth-tested volumes; store again: the final pass reloads it).
//     1. fullscreen `ambient` (reads=normal): the ambient term (3 + 5 ALU, 1 fetch).
//     2. light_spheres `light_volume` (cull=front, greater_equal, no write, blend=add,
//        light_source=proxy, reads=normal, fetch=depth): decode 4 + position 8 + output 5 ALU,
//        1 fetch, 3 varyings, 12 per light. The simulator's contribution is the full one (albedo
//        included) where Engel's light buffer holds irradiance; the image is the same.
//     3. translucent=forward: BLEND geometry, per-object light lists, alpha blend onto it.
//   Pass `final` (geometry pass 2): depth (load; equal, no write); opaque + masked with `combine`
//     (reads=light_buffer; surface 12 + ambient 3 + output 5 ALU, 2 material fetches + 1 light
//     buffer fetch, 8 varyings, light_source=none) and NO color output: a shader with
//     light_source=none writes only the ambient term, and none can add a texel of an image, so the
//     frame is the light buffer the lighting pass completed (ambient + lights). Compared with
//     Engel the trace lacks the final rgba8 color write (4 B/px) and stores the frame in the light
//     buffer's format; the cost of the second geometry pass and of reading the light buffer is kept.
#include "techniques/technique.hpp"

namespace tbdr {

namespace {

Trace generate_light_prepass(const TraceSetup& setup, const TechniqueOptions& options) {
  Trace t = begin_trace(setup, "light_prepass", options,
                        {.no_msaa = "its normal buffer holds one surface per pixel and is read back as a texture"});
  const std::string lights = add_light_buffer(t);
  const Format normal_format = color_format_option(options, "normal_format");
  const Format light_format = color_format_option(options, "light_buffer_format");
  const std::uint32_t subdivisions = sphere_subdivisions_option(options);
  const bool translucent = translucent_forward_option(options);

  PassDesc normals;
  normals.name = "normals";
  normals.attachments.push_back(
      make_attachment("normal", normal_format, 1, LoadOp::Clear, StoreOp::Store, AttachmentUsage::Gbuffer));
  normals.attachments.push_back(depth_attachment(1, LoadOp::Clear, StoreOp::Store));
  const ShaderDesc normal =
      make_shader("normals", kNormalAluOps + kGbufferEncodeAluOps, 1, kNormalVaryings, 0, LightSource::None, 1);
  add_scene_shading(t, normals, "normals", normal, masked_variant(normal, 1));  // + the base color alpha fetch

  PassDesc lighting;
  lighting.name = "lighting";
  add_color_target(lighting, "light_buffer", 1, light_format);
  // Stored again although unchanged: the final pass reloads it, and the trace format has no
  // store op that keeps the DRAM copy without writing (Vulkan's STORE_OP_NONE): 4 B/px.
  lighting.attachments.push_back(depth_attachment(1, LoadOp::Load, StoreOp::Store));
  add_ambient(t, lighting, "normal");
  t.shaders.push_back(light_volume_shader("light_volume", 1, 0, 1));
  t.pipelines.push_back(light_volume_pipeline("light_volume", "light_volume", BlendMode::Add));
  add_light_volumes(lighting, "light_volume", lights, subdivisions, {"normal"}, {"depth"});

  t.shaders.push_back(make_shader("combine", kForwardLitAluOps, kSurfaceTexFetches + 1, kSurfaceVaryings, 0,
                                  LightSource::None, 0));
  t.pipelines.push_back(depth_equal_pipeline("combine", "combine"));
  PassDesc final_pass;
  final_pass.name = "final";
  final_pass.attachments.push_back(depth_attachment(1, LoadOp::Load, StoreOp::DontCare));
  add_scene_draws(final_pass, "combine", "combine", {"light_buffer"});

  if (translucent) {  // declared after combine, drawn in the lighting pass
    add_translucent_state(t);
    add_translucent_draw(lighting, lights);
  }

  t.commands.emplace_back(std::move(normals));
  t.commands.emplace_back(std::move(lighting));
  t.commands.emplace_back(std::move(final_pass));
  return t;
}

}  // namespace

TechniqueInfo technique_light_prepass() {
  return {"light_prepass",
          "normals + depth pass, light volumes accumulating into a light buffer, a second geometry pass "
          "combining it with the materials (Engel 2008, deferred lighting)",
          {{"normal_format", "rgba8",
            "format of the normal buffer written by the first geometry pass (Engel 2008: normal + specular power "
            "in one 32-bit target)"},
           {"light_buffer_format", "rgba16f",
            "format of the light buffer the light volumes accumulate into (HDR diffuse RGB + specular)"},
           sphere_subdivisions_declaration(),
           {"translucent", "forward",
            "BLEND materials have no normal-buffer entry: forward = draw them over the light buffer with "
            "per-object light lists and alpha blending, skip = leave them out"}},
          &generate_light_prepass};
}

}  // namespace tbdr
