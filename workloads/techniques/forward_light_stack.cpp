// Forward shading with a per-pixel light stack (Martin et al. 2013, "Challenges with high quality
// mobile graphics"; Billeter 2015 "Forward Light Stack"): one render pass with pixel local storage:
// a depth-only pre-pass primes the on-chip depth, light proxies drawn against it push their light
// index onto the pixel's stack in PLS, then the forward pass shades each pixel with the lights of
// its stack. Only color leaves the chip.
// Billeter's table: off-chip buffers = color; 2 geometry passes; overshading PreZ (no); MSAA no
// (PLS is not usable with MSAA); blending yes (Martin blends "by hand" in PLS; here BLEND geometry
// is drawn after the forward pass with per-object light lists and hardware alpha blending: writing
// color ends the PLS, whose stacks are no longer needed).
//
// Pass `main`: color rgba8 (clear, store), depth d24s8 (transient); PLS `stack0..` r32ui,
//   pls_bytes in all (docs/kernels.md: a 4-byte count, then (pls_bytes - 4) / 2 16-bit indices;
//   an overflowing pixel falls back to every light, counted).
//   1. depth-only opaque + masked (alpha test).
//   2. light_spheres `light_splat`: cull=front, depth greater_equal, no write, light_source=none,
//      pls=read_write, no color output: pushes the light index (4 ALU, no fetch, no varying).
//   3. opaque + masked `forward_lit` (depth equal, no write; light_source=pls_stack, pls=read;
//      20 + 2 stack read ALU, 2 fetches, 8 varyings, 12 per light).
//   4. BLEND geometry, per-object light lists, alpha blend.
#include "kernel/errors.hpp"
#include "techniques/technique.hpp"

namespace tbdr {

namespace {

Trace generate_forward_light_stack(const TraceSetup& setup, const TechniqueOptions& options) {
  Trace t = begin_trace(setup, "forward_light_stack", options,
                        {.no_msaa = "its light stacks live in pixel local storage, which is not usable with MSAA"});
  const std::string lights = add_light_buffer(t);
  const auto pls_bytes = static_cast<std::uint32_t>(options.get_int("pls_bytes", 8, 128));
  if (pls_bytes % 4 != 0)
    throw InputError("option pls_bytes=" + options.get("pls_bytes"),
                     "pixel local storage comes in 4-byte variables: give a multiple of 4");
  const std::uint32_t subdivisions = sphere_subdivisions_option(options);

  PassDesc pass = color_pass("main", 1);
  for (std::uint32_t i = 0; i < pls_bytes / 4; ++i) pass.pls.push_back({"stack" + std::to_string(i), Format::R32ui, 0});
  add_prez(t, pass);
  t.shaders.push_back(make_shader("light_splat", kPlsStackPushAluOps, 0, 0, 0, LightSource::None, 0,
                                  PlsAccess::ReadWrite));
  t.pipelines.push_back(light_volume_pipeline("light_splat", "light_splat", BlendMode::Off));
  add_light_volumes(pass, "light_splat", lights, subdivisions);
  add_translucent_state(t);  // declared before the lit shader, drawn after it
  ForwardLitSpec lit;
  lit.source = LightSource::PlsStack;
  lit.extra_alu_ops = kPlsStackReadAluOps;
  lit.pls = PlsAccess::Read;
  lit.depth_primed = true;
  lit.reads = {lights};
  add_forward_lit(t, pass, lit);
  add_translucent_draw(pass, lights);
  t.commands.emplace_back(std::move(pass));
  return t;
}

}  // namespace

TechniqueInfo technique_forward_light_stack() {
  return {"forward_light_stack",
          "PreZ, light proxies push their index onto per-pixel stacks in pixel local storage, forward pass over "
          "the stacks; only color leaves the chip (Martin et al. 2013; Billeter 2015)",
          {{"pls_bytes", "16",
            "pixel local storage per pixel for the light stack, a multiple of 4: a 4-byte count plus (bytes-4)/2 "
            "16-bit indices (Billeter: about 16 bytes on ARM Mali T6xx, so 6 lights)"},
           sphere_subdivisions_declaration()},
          &generate_forward_light_stack};
}

}  // namespace tbdr
