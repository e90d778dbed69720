// Deferred shading with tile storage (Martin et al. 2013, "Challenges with high quality mobile
// graphics"; Bjørge, GPU Pro 5; Billeter 2015 "Deferred Tile Store"): one render pass whose
// G-buffer lives in pixel local storage (EXT_shader_pixel_local_storage): the scene writes the
// surface into PLS, light volumes (depth tested, no depth write) accumulate their light into a PLS
// accumulator reading depth through framebuffer fetch, and a fullscreen resolve writes the color.
// Only color leaves the chip.
// Billeter's table: off-chip buffers = color; 1 geometry pass; overshading no; MSAA no (PLS is
// not usable with MSAA); blending no (with translucent=forward, BLEND geometry is drawn after the
// resolve as a forward pass in the same render pass: writing color ends the PLS, which is done).
//
// Pass `main`: color rgba8 (clear, store), depth d24s8 (transient); PLS albedo r11g11b10f,
//   normal rgb10a2, light_accum r11g11b10f (12 B/px, options).
//   1. opaque + masked, `gbuffer_pls` (pls=write, no color output): surface 12 + encode 4 ALU,
//      2 fetches, 8 varyings (masked +1 ALU, discard).
//   2. light_spheres `light_volume_pls`: cull=front, depth greater_equal, no write,
//      light_source=proxy, pls=read_write, fetch=depth: decode 4 + position 8 + accumulate/pack 5
//      = 17 ALU, no fetch, 3 varyings, 12 per light.
//   3. fullscreen `resolve` (pls=read, 1 color output): decode 4 + ambient 3 + output 5 = 12 ALU;
//      docs/kernels.md: writes ambient + accumulator.
//   4. translucent=forward: BLEND geometry, per-object light lists, alpha blend.
#include "techniques/technique.hpp"

namespace tbdr {

namespace {

Trace generate_deferred_tile_store(const TraceSetup& setup, const TechniqueOptions& options) {
  Trace t = begin_trace(setup, "deferred_tile_store", options,
                        {.no_msaa = "its G-buffer lives in pixel local storage, which is not usable with MSAA"});
  const std::string lights = add_light_buffer(t);
  const Format albedo = color_format_option(options, "pls_albedo_format");
  const Format normal = color_format_option(options, "pls_normal_format");
  const Format accum = color_format_option(options, "pls_accum_format");
  const std::uint32_t subdivisions = sphere_subdivisions_option(options);
  const bool translucent = translucent_forward_option(options);

  PassDesc pass = color_pass("main", 1);
  pass.pls = {{"albedo", albedo, 0}, {"normal", normal, 0}, {"light_accum", accum, 0}};
  const ShaderDesc gbuffer = gbuffer_shader("gbuffer_pls", 0, 0, PlsAccess::Write);
  add_scene_shading(t, pass, "gbuffer_pls", gbuffer, masked_variant(gbuffer));
  t.shaders.push_back(light_volume_shader("light_volume_pls", 0, 0, 0, PlsAccess::ReadWrite));
  t.pipelines.push_back(light_volume_pipeline("light_volume_pls", "light_volume_pls", BlendMode::Off));
  add_light_volumes(pass, "light_volume_pls", lights, subdivisions, {}, {"depth"});
  t.shaders.push_back(make_shader("resolve", kGbufferDecodeAluOps + kAmbientAluOps + kOutputAluOps, 0, 0, 0,
                                  LightSource::None, 1, PlsAccess::Read));
  t.pipelines.push_back(fullscreen_pipeline("resolve", "resolve"));
  pass.draws.push_back(make_draw(GeometryKind::Fullscreen, "resolve"));
  if (translucent) {
    add_translucent_state(t);
    add_translucent_draw(pass, lights);
  }
  t.commands.emplace_back(std::move(pass));
  return t;
}

}  // namespace

TechniqueInfo technique_deferred_tile_store() {
  return {"deferred_tile_store",
          "G-buffer in pixel local storage, light volumes accumulating in PLS, fullscreen resolve; only color "
          "leaves the chip (Martin et al. 2013; Billeter 2015)",
          {{"pls_albedo_format", "r11g11b10f",
            "PLS variable holding the albedo (Martin et al. 2013 / Bjørge GPU Pro 5: color r11g11b10f, 4 B)"},
           {"pls_normal_format", "rgb10a2", "PLS variable holding the normal (Martin et al. 2013: rgb10a2, 4 B)"},
           {"pls_accum_format", "r11g11b10f",
            "PLS light accumulator (Martin et al. 2013: r11g11b10f, 4 B; 12 B/px in all, depth read through "
            "framebuffer fetch; the extension guarantees 16 B)"},
           sphere_subdivisions_declaration(),
           {"translucent", "forward",
            "BLEND materials cannot live in the PLS G-buffer: forward = draw them after the resolve with "
            "per-object light lists and alpha blending, skip = leave them out"}},
          &generate_deferred_tile_store};
}

}  // namespace tbdr
