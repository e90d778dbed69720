#include "models/tsp.hpp"

#include <algorithm>
#include <bit>

#include "models/shading.hpp"

namespace tbdr {

Tsp::Tsp(RenderContext& ctx) : ctx_(ctx) {}

namespace {

/// Lights a fragment of this primitive evaluates, per its shader's light source.
std::uint64_t lights_per_fragment(const RenderContext& ctx, const Primitive& p, const DrawContext& d) {
  switch (d.shader->light_source) {
    case LightSource::None: return 0;
    case LightSource::All: return d.lights.size();
    case LightSource::ObjectList: return ctx.object_lights[p.object].size();
    case LightSource::Proxy: return p.proxy_light >= 0 ? 1 : 0;
    case LightSource::TileList:
    case LightSource::ClusterList:
    case LightSource::PlsStack: break;
  }
  return 0;
}

}  // namespace

void Tsp::shade(std::uint32_t prim_index, std::span<const ShadePixel> pixels, std::vector<std::uint32_t>* alive,
                TspStats& stats) {
  if (pixels.empty()) return;
  const Primitive& p = ctx_.prims[prim_index];
  const DrawContext& d = ctx_.draws[p.draw];
  const ShaderDesc& sh = *d.shader;
  const HwConfig& hw = *ctx_.hw;

  // Quads: 2x2 pixel blocks aligned to even coordinates; every lane of a launched quad runs.
  quad_seen_.clear();
  for (const auto& px : pixels) {
    quad_seen_.push_back((static_cast<std::uint64_t>(static_cast<std::uint32_t>(px.y >> 1)) << 32) |
                         static_cast<std::uint32_t>(px.x >> 1));
  }
  std::sort(quad_seen_.begin(), quad_seen_.end());
  const auto quads = static_cast<std::uint64_t>(std::unique(quad_seen_.begin(), quad_seen_.end()) - quad_seen_.begin());
  const std::uint64_t lanes = quads * 4;
  const std::uint64_t n_lights = lights_per_fragment(ctx_, p, d);
  stats.invocations += pixels.size();
  stats.quads += quads;
  stats.helper_lanes += lanes - pixels.size();
  stats.alu_ops += lanes * (sh.alu_ops + std::uint64_t{sh.light_alu_ops} * n_lights);
  stats.texture_fetches += lanes * sh.tex_fetches;
  stats.texels += lanes * sh.tex_fetches * static_cast<std::uint64_t>(hw.texture.texels_per_fetch);
  stats.light_evaluations += pixels.size() * n_lights;

  const bool has_surface = p.material != kNoMaterial && ctx_.scene != nullptr;
  const Material* mat = has_surface ? &ctx_.scene->materials[p.material] : nullptr;
  const AlphaMask* mask_tex =
      (mat && mat->alpha_mask >= 0) ? &ctx_.scene->alpha_masks[static_cast<std::size_t>(mat->alpha_mask)] : nullptr;
  const int bits = p.setup.subpixel_bits;
  const std::int64_t half = std::int64_t{1} << (bits - 1);
  const std::uint32_t outputs = std::min<std::uint32_t>(sh.color_outputs, static_cast<std::uint32_t>(ctx_.color_targets.size()));
  std::uint32_t out_bytes_per_sample = 0;
  for (std::uint32_t o = 0; o < outputs; ++o) out_bytes_per_sample += bytes_per_sample(ctx_.color_targets[o]->format);
  AttachmentImage* target = outputs > 0 ? ctx_.color_targets[0] : nullptr;
  const BlendMode blend = d.pipeline->blend;
  const auto& lights = *ctx_.lights;
  const int W = ctx_.viewport.width_px;
  const int S = ctx_.pattern.count;
  if (alive) alive->assign(pixels.size(), 0);

  for (std::size_t i = 0; i < pixels.size(); ++i) {
    const ShadePixel& px = pixels[i];
    std::uint32_t write_mask = px.mask;
    SurfacePoint s;
    if (has_surface) {
      const glm::vec3 b = perspective_barycentrics(p.setup, (std::int64_t{px.x} << bits) + half, (std::int64_t{px.y} << bits) + half);
      s.position = p.world[0] * b.x + p.world[1] * b.y + p.world[2] * b.z;
      glm::vec3 n = p.normal[0] * b.x + p.normal[1] * b.y + p.normal[2] * b.z;
      const float len = glm::length(n);
      n = len > 0.0f ? n / len : glm::vec3(0.0f, 1.0f, 0.0f);
      if (!p.setup.front_facing) n = -n;
      s.normal = n;
      s.albedo = glm::vec3(mat->base_color);
      s.alpha = mat->base_color.w;
      if (p.hsr == HsrClass::PunchThrough) {
        const glm::vec2 uv = p.uv[0] * b.x + p.uv[1] * b.y + p.uv[2] * b.z;
        const float a = s.alpha * (mask_tex ? mask_tex->sample(uv) : 1.0f);
        if (a < mat->alpha_cutoff) {
          stats.alpha_killed += static_cast<std::uint64_t>(std::popcount(write_mask));
          write_mask = 0;
        }
      }
    }
    if (alive) (*alive)[i] = write_mask;
    const std::size_t pixel = static_cast<std::size_t>(px.y) * static_cast<std::size_t>(W) + static_cast<std::size_t>(px.x);
    ctx_.images->counters.shaded[pixel] += 1;
    ctx_.images->counters.lights_evaluated[pixel] += static_cast<std::uint32_t>(n_lights);
    if (write_mask == 0 || target == nullptr) continue;
    ctx_.images->counters.triangle_id[pixel] = prim_index + 1;

    glm::vec3 color(0.0f);
    if (has_surface) {
      color = ShadingModel::ambient(s);
      const glm::vec3 eye = ctx_.camera.eye;
      switch (sh.light_source) {
        case LightSource::All: {
          const auto& cand = ctx_.light_tiles[static_cast<std::size_t>((px.y / ctx_.light_tile_px) * ctx_.light_tiles_x +
                                                                       px.x / ctx_.light_tile_px)];
          for (std::uint32_t l : cand) {
            if (d.light_selected[l]) color += ShadingModel::light_contribution(s, eye, lights[l]);
          }
          break;
        }
        case LightSource::ObjectList:
          for (std::uint32_t l : ctx_.object_lights[p.object]) color += ShadingModel::light_contribution(s, eye, lights[l]);
          break;
        case LightSource::Proxy:
          if (p.proxy_light >= 0) color += ShadingModel::light_contribution(s, eye, lights[static_cast<std::size_t>(p.proxy_light)]);
          break;
        default: break;
      }
    }
    const glm::vec4 src(color, s.alpha);
    const auto written = static_cast<std::uint64_t>(std::popcount(write_mask));
    stats.shaded_samples += written;
    stats.tile_buffer_write_bytes += written * out_bytes_per_sample;
    if (blend != BlendMode::Off) {
      stats.blended_samples += written;
      stats.tile_buffer_read_bytes += written * out_bytes_per_sample;
    }
    glm::vec4* dst = target->color.data() + pixel * static_cast<std::size_t>(S);
    for (int smp = 0; smp < S; ++smp) {
      if (!(write_mask & (1u << smp))) continue;
      switch (blend) {
        case BlendMode::Off: dst[smp] = src; break;
        case BlendMode::Add: dst[smp] += glm::vec4(glm::vec3(src), 0.0f); break;
        case BlendMode::Alpha:
          dst[smp] = glm::vec4(glm::vec3(src) * src.w + glm::vec3(dst[smp]) * (1.0f - src.w), src.w + dst[smp].w * (1.0f - src.w));
          break;
      }
    }
  }
}

}  // namespace tbdr
