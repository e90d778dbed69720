#include "models/command_processor.hpp"

#include <algorithm>
#include <map>
#include <memory>
#include <set>
#include <stdexcept>

#include "models/compute_unit.hpp"
#include "models/geometry_unit.hpp"
#include "models/light_lists.hpp"
#include "models/isp.hpp"
#include "models/texture_unit.hpp"
#include "models/tile_memory.hpp"
#include "models/tiler.hpp"
#include "models/tsp.hpp"
#include "kernel/errors.hpp"

namespace tbdr {

namespace {


void collect_dram(const std::string& prefix, const DramTraffic& dram, std::vector<StatRecord>& out) {
  std::uint64_t r = 0, w = 0;
  for (std::size_t c = 0; c < kDramClassCount; ++c) {
    const std::string scope = prefix + "/dram." + to_string(static_cast<DramClass>(c));
    out.push_back({scope, "read_bytes", static_cast<double>(dram.read_bytes[c]), "bytes", "DRAM bytes read for this traffic class"});
    out.push_back({scope, "write_bytes", static_cast<double>(dram.write_bytes[c]), "bytes", "DRAM bytes written for this traffic class"});
    r += dram.read_bytes[c];
    w += dram.write_bytes[c];
  }
  out.push_back({prefix + "/dram", "read_bytes", static_cast<double>(r), "bytes", "DRAM bytes read, all classes"});
  out.push_back({prefix + "/dram", "write_bytes", static_cast<double>(w), "bytes", "DRAM bytes written, all classes"});
}

/// Tile indices in the configured dispatch order.
std::vector<int> tile_order(int tiles_x, int tiles_y, const std::string& order) {
  std::vector<int> out;
  out.reserve(static_cast<std::size_t>(tiles_x) * static_cast<std::size_t>(tiles_y));
  if (order == "morton") {
    std::vector<std::pair<std::uint64_t, int>> keyed;
    for (int ty = 0; ty < tiles_y; ++ty) {
      for (int tx = 0; tx < tiles_x; ++tx) {
        std::uint64_t key = 0;
        for (int b = 0; b < 16; ++b) {
          key |= (static_cast<std::uint64_t>((tx >> b) & 1) << (2 * b)) | (static_cast<std::uint64_t>((ty >> b) & 1) << (2 * b + 1));
        }
        keyed.push_back({key, ty * tiles_x + tx});
      }
    }
    std::sort(keyed.begin(), keyed.end());
    for (const auto& k : keyed) out.push_back(k.second);
  } else {
    for (int t = 0; t < tiles_x * tiles_y; ++t) out.push_back(t);
  }
  return out;
}

/// Builds the per-32px-tile light candidate lists used to compute colors quickly and exactly.
void build_light_tiles(RenderContext& ctx) {
  ctx.light_tile_px = 32;
  ctx.light_tiles_x = (ctx.viewport.width_px + ctx.light_tile_px - 1) / ctx.light_tile_px;
  const int ty_n = (ctx.viewport.height_px + ctx.light_tile_px - 1) / ctx.light_tile_px;
  ctx.light_tiles.assign(static_cast<std::size_t>(ctx.light_tiles_x) * static_cast<std::size_t>(ty_n), {});
  for (std::uint32_t l = 0; l < ctx.lights->size(); ++l) {
    const PixelRect r = light_screen_rect((*ctx.lights)[l], ctx.camera, ctx.viewport);
    if (r.empty()) continue;
    for (int ty = r.y0 / ctx.light_tile_px; ty <= (r.y1 - 1) / ctx.light_tile_px; ++ty) {
      for (int tx = r.x0 / ctx.light_tile_px; tx <= (r.x1 - 1) / ctx.light_tile_px; ++tx) {
        ctx.light_tiles[static_cast<std::size_t>(ty * ctx.light_tiles_x + tx)].push_back(l);
      }
    }
  }
}

bool is_resolve_target(const PassDesc& pass, const Attachment& a) {
  for (const auto& o : pass.attachments) {
    if (o.resolve == a.name) return true;
  }
  return false;
}

class FrameSimulator {
 public:
  FrameSimulator(const Trace& trace, const std::string& path, const Scene& scene, const HwConfig& hw)
      : trace_(trace), path_(path), scene_(scene), hw_(hw) {}

  FrameResult run() {
    const auto& f = trace_.frame;
    viewport_ = Viewport{f.width, f.height, static_cast<int>(hw_.geometry.subpixel_bits)};
    try {
      validate_viewport(viewport_);
    } catch (const std::invalid_argument& e) {
      throw InputError(path_, f.line, e.what());
    }
    if (!trace_.scene.content_hash.empty() && trace_.scene.content_hash != scene_.content_hash) {
      throw InputError(path_, trace_.scene.line,
                       "scene content hash " + trace_.scene.content_hash + " does not match the loaded scene '" +
                           scene_.source + "' (" + scene_.content_hash + "); regenerate the trace for this scene");
    }
    camera_ = CameraXform::from(trace_.camera, static_cast<float>(f.width) / static_cast<float>(f.height));
    frustum_ = ViewFrustum::from(trace_.camera, f.width, f.height);
    result_.images.width = f.width;
    result_.images.height = f.height;
    result_.images.counters.resize(static_cast<std::size_t>(f.width) * static_cast<std::size_t>(f.height));

    result_.work.width = f.width;
    result_.work.height = f.height;
    result_.work.tile_width = static_cast<int>(hw_.tiling.tile_width);
    result_.work.tile_height = static_cast<int>(hw_.tiling.tile_height);
    result_.work.tiles_x = (f.width + result_.work.tile_width - 1) / result_.work.tile_width;
    // The texture address space: every fetch slot any shader of the trace uses gets its copies.
    std::uint32_t slots = 1;
    for (const auto& sh : trace_.shaders) slots = std::max(slots, sh.tex_fetches);
    textures_ = std::make_unique<TextureLayout>(&scene_, hw_, slots);
    result_.work.texture_bytes = textures_->total_bytes();
    int pass_index = 0;
    std::uint64_t dispatches = 0;
    for (const auto& cmd : trace_.commands) {
      if (const auto* pass = std::get_if<PassDesc>(&cmd)) {
        run_pass(*pass, pass_index++);
      } else if (const auto* d = std::get_if<DispatchCmd>(&cmd)) {
        run_dispatch_cmd(*d, static_cast<int>(dispatches++));
      }
      // Barriers order work; in the functional model every command completes before the next.
    }
    // Frame totals: every unit's statistics summed over the passes (gauges: the largest level).
    if (pass_index > 0) result_.totals.render.collect("frame", result_.stats);
    if (dispatches > 0) collect_stats(result_.totals.compute, "frame/compute", result_.stats);
    collect_dram("frame", result_.dram, result_.stats);
    auto frame_stat = [&](const char* name, double v, const char* unit, const char* desc) {
      result_.stats.push_back({"frame/frame", name, v, unit, desc});
    };
    frame_stat("width", f.width, "pixels", "Frame width");
    frame_stat("height", f.height, "pixels", "Frame height");
    frame_stat("samples_per_pixel", f.samples, "samples", "MSAA samples per pixel of the trace");
    frame_stat("lights", static_cast<double>(trace_.lights.size()), "lights", "Lights in the trace");
    frame_stat("passes", pass_index, "passes", "Render passes replayed");
    frame_stat("dispatches", static_cast<double>(dispatches), "dispatches", "Compute dispatches replayed");
    frame_stat("scene_triangles", static_cast<double>(scene_.triangle_count()), "triangles", "Triangles in the scene");
    frame_stat("geometry_passes", geometry_passes_, "passes", "Submissions of the scene's opaque geometry");
    std::uint64_t covered = 0;
    for (auto v : result_.images.counters.shaded) covered += v > 0 ? 1 : 0;
    frame_stat("covered_pixels", static_cast<double>(covered), "pixels", "Pixels shaded at least once (the visible surface)");
    return std::move(result_);
  }

 private:
  void prepare_attachments(const PassDesc& pass, RenderContext& ctx) {
    int samples = -1;
    for (const auto& a : pass.attachments) {
      if (is_resolve_target(pass, a)) {
        if (a.samples != 1) throw InputError(path_, a.line, "resolve target '" + a.name + "' must have 1 sample");
        continue;
      }
      if (samples < 0) samples = static_cast<int>(a.samples);
      if (static_cast<int>(a.samples) != samples) {
        throw InputError(path_, a.line, "attachment '" + a.name + "' has " + std::to_string(a.samples) +
                                            " samples but the pass's other attachments have " + std::to_string(samples));
      }
    }
    if (samples < 0) samples = trace_.frame.samples;
    try {
      ctx.pattern = standard_sample_pattern(samples, viewport_.subpixel_bits);
    } catch (const std::invalid_argument& e) {
      throw InputError(path_, pass.line, e.what());
    }
    const std::size_t pixels = static_cast<std::size_t>(viewport_.width_px) * static_cast<std::size_t>(viewport_.height_px);
    for (const auto& a : pass.attachments) {
      auto it = result_.images.attachments.find(a.name);
      if (it == result_.images.attachments.end()) {
        AttachmentImage img;
        img.format = a.format;
        img.samples = a.samples;
        img.usage = a.usage;
        if (is_depth_format(a.format)) {
          img.depth.assign(pixels * a.samples, 1.0f);
          img.stencil.assign(pixels * a.samples, 0);
        } else {
          img.color.assign(pixels * a.samples, glm::vec4(0.0f));
        }
        it = result_.images.attachments.emplace(a.name, std::move(img)).first;
      } else if (it->second.format != a.format || it->second.samples != a.samples) {
        throw InputError(path_, a.line, "attachment '" + a.name + "' was declared earlier with another format or sample count");
      }
      if (a.load == LoadOp::Load && !a.transient && !it->second.defined) {
        throw InputError(path_, a.line, "attachment '" + a.name + "' is loaded but no earlier pass stored it");
      }
    }
    for (const Attachment* a : pass.color_targets()) ctx.color_targets.push_back(&result_.images.attachments.at(a->name));
    if (const Attachment* d = pass.depth_attachment()) ctx.depth = &result_.images.attachments.at(d->name);
  }

  void resolve_draws(const PassDesc& pass, RenderContext& ctx) {
    const auto n_lights = static_cast<std::uint32_t>(trace_.lights.size());
    for (std::size_t i = 0; i < pass.draws.size(); ++i) {
      const DrawCmd& cmd = pass.draws[i];
      DrawContext d;
      d.cmd = &cmd;
      d.pass_draw_index = static_cast<std::uint32_t>(i);
      d.pipeline = trace_.find_pipeline(cmd.pipeline);
      if (!d.pipeline) throw InputError(path_, cmd.line, "unknown pipeline '" + cmd.pipeline + "'");
      d.shader = trace_.find_shader(d.pipeline->shader);
      if (!d.shader) throw InputError(path_, d.pipeline->line, "unknown shader '" + d.pipeline->shader + "'");
      resolve_draw_inputs(pass, cmd, d);
      if (d.shader->color_outputs > ctx.color_targets.size()) {
        throw InputError(path_, cmd.line, "shader '" + d.shader->name + "' writes " + std::to_string(d.shader->color_outputs) +
                                              " color outputs but pass '" + pass.name + "' has " +
                                              std::to_string(ctx.color_targets.size()) + " color attachments");
      }
      d.light_selected.assign(n_lights, 0);
      for (std::uint32_t l = 0; l < n_lights; ++l) {
        if (cmd.lights.contains(l)) {
          d.lights.push_back(l);
          d.light_selected[l] = 1;
        }
      }
      ctx.draws.push_back(std::move(d));
    }
  }

  /// Where a draw's shader finds its surface, its light lists and what it samples from DRAM.
  void resolve_draw_inputs(const PassDesc& pass, const DrawCmd& cmd, DrawContext& d) {
    auto surfaces_of = [&](const std::string& n) -> const AttachmentImage* {
      auto it = result_.images.attachments.find(n);
      if (it == result_.images.attachments.end()) return nullptr;
      const auto u = it->second.usage;
      return (u == AttachmentUsage::Gbuffer || u == AttachmentUsage::Visibility) ? &it->second : nullptr;
    };
    if (cmd.geometry != GeometryKind::Scene) {
      for (const auto& n : cmd.fetch) {
        if (!d.surface_source) d.surface_source = surfaces_of(n);
      }
      for (const auto& n : cmd.reads) {
        if (!d.surface_source) d.surface_source = surfaces_of(n);
      }
      if (d.surface_source && d.surface_source->surface.empty()) {
        throw InputError(path_, cmd.line, "the G-buffer or visibility attachment this draw reads holds no surface: no shader wrote it");
      }
    }
    auto find_grid = [&](BufferContent content) -> std::string {
      for (const auto& n : cmd.reads) {
        const BufferDesc* b = trace_.find_buffer(n);
        if (b && b->content == content) return n;
      }
      return {};
    };
    if (d.shader->light_source == LightSource::TileList) {
      auto it = result_.images.tile_grids.find(find_grid(BufferContent::TileGrid));
      if (it == result_.images.tile_grids.end()) {
        throw InputError(path_, cmd.line, "light_source=tile_list needs a tile_grid buffer written by tile_light_cull in reads=");
      }
      d.tile_grid = it->second.get();
    }
    if (d.shader->light_source == LightSource::ClusterList) {
      auto it = result_.images.cluster_grids.find(find_grid(BufferContent::ClusterGrid));
      if (it == result_.images.cluster_grids.end()) {
        throw InputError(path_, cmd.line, "light_source=cluster_list needs a cluster_grid buffer written by cluster_light_assign in reads=");
      }
      d.cluster_grid = it->second.get();
    }
    if (d.shader->light_source == LightSource::PlsStack && pass.pls.empty()) {
      throw InputError(path_, cmd.line, "light_source=pls_stack needs pixel local storage in pass '" + pass.name + "'");
    }
    // Stored images sampled at the shaded pixel: booked per invocation (texture reads).
    for (const auto& n : cmd.reads) {
      auto it = result_.images.attachments.find(n);
      if (it == result_.images.attachments.end()) continue;
      const AttachmentImage& img = it->second;
      const std::uint32_t bps = is_depth_format(img.format) ? static_cast<std::uint32_t>(hw_.isp.depth_stencil_bytes_per_sample)
                                                             : bytes_per_sample(img.format);
      d.per_pixel_reads.push_back({traffic_class_of(img.usage), bps * img.samples});
    }
  }

  void run_dispatch_cmd(const DispatchCmd& d, int index) {
    const std::string prefix = "dispatch" + std::to_string(index) + "." + d.kernel;
    ComputeStats stats;
    DramTraffic dram;
    ComputeContext cc;
    cc.hw = &hw_;
    cc.trace = &trace_;
    cc.trace_path = &path_;
    cc.scene = &scene_;
    cc.images = &result_.images;
    cc.frustum = frustum_;
    cc.camera = camera_;
    cc.viewport = viewport_;
    RenderContext tmp;
    tmp.lights = &trace_.lights;
    tmp.camera = camera_;
    tmp.viewport = viewport_;
    build_light_tiles(tmp);
    cc.light_tile_px = tmp.light_tile_px;
    cc.light_tiles_x = tmp.light_tiles_x;
    cc.light_tiles = &tmp.light_tiles;
    std::string image;
    run_dispatch(cc, d, stats, dram, image);
    CommandWork cw;
    cw.name = prefix;
    cw.is_dispatch = true;
    cw.depends_on_previous = true;  // a dispatch follows a barrier on what it reads
    cw.compute_alu_ops = stats.compute_alu_ops.value();
    cw.compute_threads = stats.threads.value();
    cw.compute_texels = stats.compute_texture_fetches.value() * static_cast<std::uint64_t>(hw_.texture.texels_per_fetch);
    cw.read_bytes = dram.read_bytes;
    cw.write_bytes = dram.write_bytes;
    result_.work.commands.push_back(std::move(cw));
    if (!image.empty()) result_.final_color = image;
    collect_stats(stats, prefix + "/compute", result_.stats);
    result_.totals.compute += stats;
    collect_dram(prefix, dram, result_.stats);
    PassSummary summary;
    summary.name = prefix;
    summary.dram = dram;
    result_.passes.push_back(summary);
    result_.dram += dram;
  }

  void run_pass(const PassDesc& pass, int index) {
    const std::string prefix = "pass" + std::to_string(index) + "." + pass.name;
    auto ps = std::make_unique<PassStats>();
    DramTraffic pass_dram;
    RenderContext ctx;
    ctx.hw = &hw_;
    ctx.scene = &scene_;
    ctx.lights = &trace_.lights;
    ctx.camera = camera_;
    ctx.viewport = viewport_;
    ctx.pass = &pass;
    ctx.images = &result_.images;
    ctx.defer_shading = hw_.gpu.mode == "tbdr";
    ctx.framebuffer_in_dram = hw_.gpu.mode == "imr";
    prepare_attachments(pass, ctx);
    resolve_draws(pass, ctx);
    // Geometry passes: submissions of the scene's opaque geometry (a PreZ, a G-buffer pass, each
    // additive pass of a multi-pass technique, the forward pass).
    for (const auto& dc : pass.draws) {
      if (dc.geometry == GeometryKind::Scene && dc.submesh.empty() && dc.material.empty() &&
          (dc.subset == SceneSubset::All || dc.subset == SceneSubset::Opaque)) {
        ++geometry_passes_;
      }
    }
    build_light_tiles(ctx);
    ctx.frustum = &frustum_;
    ctx.dram = &pass_dram;
    ctx.frame_prim_base = prim_base_;
    std::vector<std::uint64_t> tile_texture_lines;  // the current tile's texture lines, as the TSP appends them
    ctx.textures = textures_.get();
    ctx.texture_lines = &tile_texture_lines;
    PlsState pls;
    if (!pass.pls.empty()) {
      const std::size_t pixels = static_cast<std::size_t>(viewport_.width_px) * static_cast<std::size_t>(viewport_.height_px);
      const std::uint32_t bytes = pass.pls_bytes_per_pixel();
      pls.stack_capacity = bytes > 4 ? (bytes - 4) / 2 : 0;
      pls.surface.assign(pixels, SurfacePoint{});
      pls.valid.assign(pixels, 0);
      pls.accum.assign(pixels, glm::vec3(0.0f));
      pls.stack.assign(pixels * pls.stack_capacity, 0);
      pls.stack_count.assign(pixels, 0);
      pls.overflow.assign(pixels, 0);
      ctx.pls = &pls;
    }
    // Buffers the draws read (lights, light lists): booked once per pass (re-reads hit on chip).
    {
      std::set<std::string> seen;
      for (const auto& dc : pass.draws) {
        for (const auto& n : dc.reads) {
          const BufferDesc* b = trace_.find_buffer(n);
          if (!b || !seen.insert(n).second) continue;
          auto w = result_.images.buffer_bytes_written.find(n);
          const std::uint64_t bytes = w == result_.images.buffer_bytes_written.end() ? b->bytes : w->second;
          pass_dram.read(traffic_class_of(b->traffic), bytes);
        }
      }
    }
    const DramTraffic pass_buffer_reads = pass_dram;

    // imr has no binning: the whole frame is one "tile" and nothing goes through a parameter buffer.
    HwConfig hw = hw_;
    if (ctx.framebuffer_in_dram) {
      hw.tiling.tile_width = viewport_.width_px;
      hw.tiling.tile_height = viewport_.height_px;
      hw.tiling.pb_capacity_bytes = std::int64_t{1} << 62;
    }
    ctx.hw = &hw;
    GeometryUnit geometry(hw, &scene_, trace_.lights, camera_, viewport_);
    Tiler tiler(hw, viewport_, ctx.pattern);
    TileMemory tile_memory(ctx, ps->tile_memory);
    Tsp tsp(ctx);
    Isp isp(ctx, tsp);
    const std::vector<int> order = tile_order(tiler.tiles_x(), tiler.tiles_y(), hw.tiling.tile_order);
    std::vector<std::uint8_t> resumed(static_cast<std::size_t>(tiler.tile_count()), 0);
    DramTraffic& dram = pass_dram;

    CommandWork cw;
    cw.name = prefix;
    cw.read_bytes = pass_buffer_reads.read_bytes;  // buffers read once per pass, at its start
    for (const auto& a : pass.attachments) {
      if (a.load == LoadOp::Load && !a.transient) cw.depends_on_previous = true;
    }
    for (const auto& dc : pass.draws) {
      if (!dc.reads.empty()) cw.depends_on_previous = true;
    }
    // The geometry and tiler statistics at the start of the current render.
    GeometryStats geometry_base;
    TilerStats tiler_base;

    auto render = [&](bool partial) {
      RenderWork rw;
      rw.partial = partial;
      const GeometryStats g = ps->geometry - geometry_base;
      const TilerStats b = ps->tiler - tiler_base;
      rw.binning.vertices_shaded = g.vertices_shaded.value();
      rw.binning.vertex_alu_ops = g.vertex_alu_ops.value();
      rw.binning.vertex_fetch_bytes = g.vertex_fetch_bytes.value();
      rw.binning.index_fetch_bytes = g.index_fetch_bytes.value();
      rw.binning.primitives_in = g.primitives_in.value();
      rw.binning.primitives_binned = b.primitives_binned.value();
      rw.binning.tile_references = b.tile_references.value();
      geometry_base = ps->geometry;
      tiler_base = ps->tiler;
      DramTraffic pb;
      tiler.finish_render(ps->tiler, pb);
      if (!ctx.framebuffer_in_dram) {
        dram += pb;
        rw.binning.pb_write_bytes = pb.writes(DramClass::ParameterBuffer);
      }
      for (int t : order) {
        const auto& prims = tiler.tile_primitives(t);
        if (partial && prims.empty()) continue;  // untouched: nothing to render yet
        const std::uint64_t pb_read = prims.empty() ? 0 : tiler.tile_read_bytes(t);
        for (const PixelRect& r : tile_memory.strips(tiler.tile_rect(t))) {
          const DramTraffic before = dram;
          const IspStats isp0 = ps->isp;
          const TspStats tsp0 = ps->tsp;
          tile_texture_lines.clear();
          tile_memory.begin_tile(r, resumed[static_cast<std::size_t>(t)] != 0, dram);
          isp.render_tile(r, prims, ps->isp, ps->tsp);
          const IspStats tile_isp = ps->isp - isp0;
          const TspStats tile_tsp = ps->tsp - tsp0;
          tile_memory.spill(tile_tsp.tile_buffer_read_bytes.value(), tile_tsp.tile_buffer_write_bytes.value(), dram);
          tile_memory.end_tile(r, partial, dram);
          TileWork tw;
          tw.tile_x = t % tiler.tiles_x();
          tw.tile_y = t / tiler.tiles_x();
          tw.rect = r;
          for (std::size_t c = 0; c < kDramClassCount; ++c) {
            tw.load_bytes[c] = dram.read_bytes[c] - before.read_bytes[c];
            tw.store_bytes[c] = dram.write_bytes[c] - before.write_bytes[c];
          }
          tw.primitives = tile_isp.primitives_fetched.value();
          tw.samples = tile_isp.samples_rasterised.value();
          tw.invocations = tile_tsp.shader_invocations.value();
          tw.quads = tile_tsp.shaded_quads.value();
          tw.alu_ops = tile_tsp.fragment_alu_ops.value();
          tw.texels = tile_tsp.texels_filtered.value();
          tw.texture_line_accesses = tile_tsp.texture_line_accesses.value();
          std::sort(tile_texture_lines.begin(), tile_texture_lines.end());
          tw.texture_lines.assign(tile_texture_lines.begin(),
                                  std::unique(tile_texture_lines.begin(), tile_texture_lines.end()));
          ps->tsp.texture_tile_lines += tw.texture_lines.size();
          // The footprint is what the texture unit requests (before the texture cache), booked like
          // the parameter buffer reads: after the tile's loads and stores were taken from `dram`.
          dram.read(DramClass::Textures, tw.texture_lines.size() * static_cast<std::uint64_t>(hw_.cache.texture.line_bytes));
          tw.tile_buffer_bytes = tile_tsp.tile_buffer_read_bytes.value() + tile_tsp.tile_buffer_write_bytes.value();
          tw.tag_bytes = tile_isp.tag_buffer_read_bytes.value() + tile_isp.tag_buffer_write_bytes.value();
          tw.depth_bytes = tile_isp.depth_buffer_read_bytes.value() + tile_isp.depth_buffer_write_bytes.value();
          if (!ctx.framebuffer_in_dram) {
            ps->tiler.pb_bytes_read += pb_read;
            dram.read(DramClass::ParameterBuffer, pb_read);
            if (!prims.empty()) tw.pb_reads = tiler.tile_read_ranges(t);
          }
          rw.tiles.push_back(std::move(tw));
        }
        if (partial) resumed[static_cast<std::size_t>(t)] = 1;
      }
      cw.renders.push_back(std::move(rw));
      tiler.reset();
      ctx.frame_prim_base += static_cast<std::uint32_t>(ctx.prims.size());
      ctx.prims.clear();
    };

    std::vector<Primitive> staged;
    for (std::uint32_t i = 0; i < ctx.draws.size(); ++i) {
      staged.clear();
      geometry.run_draw(ctx.draws[i], i, staged, ctx.object_lights, ps->geometry, dram);
      for (const Primitive& p : staged) {
        ctx.prims.push_back(p);
        if (!tiler.bin(static_cast<std::uint32_t>(ctx.prims.size() - 1), ctx.prims.back(), ps->tiler)) {
          ctx.prims.pop_back();
          ++ps->tiler.partial_renders;
          render(true);
          ctx.prims.push_back(p);
          tiler.bin(0, ctx.prims.back(), ps->tiler);
        }
      }
    }
    render(false);
    prim_base_ = ctx.frame_prim_base;
    if (ctx.framebuffer_in_dram) {
      // The depth and color accesses of an immediate-mode GPU go to DRAM (caches come with the timing model).
      dram.read(DramClass::DepthStencil, ps->isp.depth_buffer_read_bytes.value());
      dram.write(DramClass::DepthStencil, ps->isp.depth_buffer_write_bytes.value());
      dram.read(DramClass::Color, ps->tsp.tile_buffer_read_bytes.value());
      dram.write(DramClass::Color, ps->tsp.tile_buffer_write_bytes.value());
    }
    for (const auto& a : pass.attachments) {
      AttachmentImage& img = result_.images.attachments.at(a.name);
      img.defined = a.store == StoreOp::Store && !a.transient;
      if (img.defined && a.usage == AttachmentUsage::Color) result_.final_color = a.name;
    }
    if (ctx.framebuffer_in_dram) {
      // imr: the framebuffer accesses happen during shading; book them on the one "tile".
      auto& tw = cw.renders.back().tiles.back();
      tw.load_bytes[static_cast<std::size_t>(DramClass::DepthStencil)] += ps->isp.depth_buffer_read_bytes.value();
      tw.store_bytes[static_cast<std::size_t>(DramClass::DepthStencil)] += ps->isp.depth_buffer_write_bytes.value();
      tw.load_bytes[static_cast<std::size_t>(DramClass::Color)] += ps->tsp.tile_buffer_read_bytes.value();
      tw.store_bytes[static_cast<std::size_t>(DramClass::Color)] += ps->tsp.tile_buffer_write_bytes.value();
    }
    result_.work.commands.push_back(std::move(cw));
    ps->collect(prefix, result_.stats);
    result_.totals.render += *ps;
    collect_dram(prefix, dram, result_.stats);
    PassSummary summary;
    summary.name = pass.name;
    summary.primitives = ps->geometry.primitives_out.value();
    summary.shaded_samples = ps->tsp.shaded_samples.value();
    summary.partial_renders = ps->tiler.partial_renders.value();
    summary.dram = dram;
    result_.passes.push_back(summary);
    result_.dram += dram;
  }

  const Trace& trace_;
  const std::string& path_;
  const Scene& scene_;
  const HwConfig& hw_;
  Viewport viewport_;
  CameraXform camera_;
  ViewFrustum frustum_;
  std::uint32_t prim_base_ = 0;
  int geometry_passes_ = 0;
  std::unique_ptr<TextureLayout> textures_;  ///< the frame's texture address space
  FrameResult result_;
};

}  // namespace

FrameResult simulate_frame(const Trace& trace, const std::string& trace_path, const Scene& scene, const HwConfig& hw) {
  FrameSimulator sim(trace, trace_path, scene, hw);
  return sim.run();
}

}  // namespace tbdr
