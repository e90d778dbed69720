#include "models/command_processor.hpp"

#include <algorithm>
#include <exception>
#include <numeric>
#include <map>
#include <memory>
#include <set>
#include <stdexcept>
#include <unordered_map>

#include "models/compute_unit.hpp"
#include "models/geometry_unit.hpp"
#include "models/hardware_checks.hpp"
#include "models/light_lists.hpp"
#include "models/isp.hpp"
#include "models/texture_unit.hpp"
#include "models/tile_memory.hpp"
#include "models/tiler.hpp"
#include "models/tsp.hpp"
#include "models/pass_renderer.hpp"
#include "kernel/errors.hpp"
#include "kernel/thread_pool.hpp"

namespace tbdr {

namespace {


/// The attachments whose stored surfaces (AttachmentImage::surface) some command of `trace` reads
/// without colours: every image a dispatch reads (its kernels read the surfaces' sites), and the
/// G-buffer or visibility attachments a draw of generated geometry fetches or reads when its
/// shader reads the stored surface (reads_stored_surface). Conservative: any such command, before
/// or after the writer. The others keep only their written marks (AttachmentImage::keeps_surface).
std::set<std::string> stored_surface_readers(const Trace& trace) {
  std::set<std::string> names;
  for (const auto& cmd : trace.commands) {
    if (const auto* d = std::get_if<DispatchCmd>(&cmd)) {
      names.insert(d->reads.begin(), d->reads.end());
      continue;
    }
    const auto* pass = std::get_if<PassDesc>(&cmd);
    if (!pass) continue;
    const auto targets = pass->color_targets();
    for (const DrawCmd& draw : pass->draws) {
      if (draw.geometry == GeometryKind::Scene) continue;
      const PipelineState* pipeline = trace.find_pipeline(draw.pipeline);
      const ShaderDesc* sh = pipeline ? trace.find_shader(pipeline->shader) : nullptr;
      if (!sh) continue;  // refused when the draw is replayed
      bool writes_surface_target = false;
      for (std::uint32_t o = 0; o < sh->color_outputs && o < targets.size(); ++o) {
        if (targets[o]->usage != AttachmentUsage::Color) writes_surface_target = true;
      }
      if (!reads_stored_surface(*sh, writes_surface_target)) continue;
      names.insert(draw.fetch.begin(), draw.fetch.end());
      names.insert(draw.reads.begin(), draw.reads.end());
    }
  }
  return names;
}

/// The helpers' niceness when the timing model runs on its own thread beside the frame
/// (FrameOptions::feed): at --threads N there are N + 1 busy threads on N cores, and the timing
/// model, whose schedule waits for the functional run's pieces, and the caller's thread (geometry,
/// binning, the serial steps) are the critical path; the helpers take what they leave idle.
/// nice 10 gives a helper a tenth of a core against a nice-0 thread (CFS weights 110 / 1024).
/// Measured at 1080p, 1024 lights, 2 threads on 2 cores, wall seconds, median of 5 interleaved
/// (nice 5 / 10 / 19), once tiles were published outside the merge lock (before, a helper preempted
/// while holding it stalled the caller's thread, and nice 5 measured best): plain_forward 0.24 /
/// 0.22 / 0.22, forward_plus 0.34 / 0.33 / 0.32, light_prepass 0.86 / 0.85 / 0.85,
/// visibility_buffer 0.46 / 0.45 / 0.45, forward_light_stack 0.56 / 0.57 / 0.57, the other seven
/// equal. 10 rather than more, so that the helpers still get a part of a core shared with other
/// users' processes.
constexpr int kHelperNicenessBesideTiming = 10;

class FrameSimulator {
 public:
  FrameSimulator(const Trace& trace, const std::string& path, const Scene& scene, const HwConfig& hw, const FrameOptions& options)
      : trace_(trace), path_(path), scene_(scene), hw_(hw), options_(options),
        pool_(options.threads == 0 ? default_thread_count() : options.threads,
              options.feed != nullptr ? kHelperNicenessBesideTiming : 0) {}

  FrameResult run() {
    check_trace_on_hardware(trace_, hw_, path_);  // what this GPU cannot run is refused before any command runs
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
    // The per-pixel counters' fresh pages (4 ms at 1080p) are touched on one thread while the
    // light bins are built on another: both serial steps before the first pass.
    const std::size_t pixels = static_cast<std::size_t>(f.width) * static_cast<std::size_t>(f.height);
    pool_.for_each(2, [&](std::size_t item, unsigned) {
      if (item == 0) {
        result_.images.counters.resize(pixels, options_.colour);
      } else {
        light_bins_ = LightScreenBins::build(trace_.lights, camera_, viewport_);
      }
    });
    inputs_ = FrameInputs{.hw = &hw_, .scene = &scene_, .lights = &trace_.lights, .camera = camera_,
                          .viewport = viewport_, .frustum = &frustum_, .light_bins = &light_bins_, .colour = options_.colour,
                          .reference_loops = options_.reference_loops, .tile_signatures = options_.tile_signatures};
    if (options_.tile_signatures != nullptr) options_.tile_signatures->begin_frame();
    result_.images.width = f.width;
    result_.images.height = f.height;

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
    result_.work.immediate = hw_.gpu.mode == GpuMode::Imr;
    result_.work.frames = options_.sequence_frames;
    if (result_.work.immediate) {
      rop_ = std::make_unique<RenderOutputUnit>(hw_, f.width, f.height);
      // Every image gets its place before the first pass runs: the framebuffer's size is known
      // before any command is timed (FrameAddressMap).
      for (const auto& cmd : trace_.commands) {
        if (const auto* pass = std::get_if<PassDesc>(&cmd)) rop_->place_pass(*pass);
      }
      result_.work.framebuffer_bytes = rop_->framebuffer_bytes();
    }
    if (options_.feed && options_.sequence_frame == 0) {
      options_.feed->begin(result_.work, options_.sequence_frames > 1 ? options_.sequence_commands : timed_command_count(trace_));
    }
    surface_readers_ = stored_surface_readers(trace_);
    int pass_index = 0;
    std::uint64_t dispatches = 0;
    const auto& commands = trace_.commands;
    for (std::size_t i = 0; i < commands.size(); ++i) {
      if (const auto* pass = std::get_if<PassDesc>(&commands[i])) {
        run_pass(*pass, pass_index++);
      } else if (const auto* d = std::get_if<DispatchCmd>(&commands[i])) {
        // Bin-ahead past dispatches: the pass after them is set up and binned before the pass
        // binned ahead renders its tiles, then those tiles, the dispatches and the rest of its
        // set-up run (run_pass with `past`), as the hardware bins it into its second parameter
        // buffer while the earlier work runs.
        if (const std::size_t next = pass_after_dispatches(i); next != 0) {
          std::vector<PastDispatch> past;
          for (std::size_t k = i; k < next; ++k) {
            if (const auto* dk = std::get_if<DispatchCmd>(&commands[k])) past.push_back({dk, static_cast<int>(dispatches++)});
          }
          run_pass(std::get<PassDesc>(commands[next]), pass_index++, past);
          i = next;
          continue;
        }
        finish_pending_pass();
        run_dispatch_cmd(*d, static_cast<int>(dispatches++));
      }
      // Barriers order work; in the functional model every command completes before the next
      // (a pass's tiles, binned ahead of the next pass's, before that pass's tiles).
    }
    finish_pending_pass();
    // The frame's shape (its totals are summed in result_.totals as the commands complete).
    FrameShapeStats& shape = result_.shape;
    shape.width.set(f.width);
    shape.height.set(f.height);
    shape.samples_per_pixel.set(f.samples);
    shape.lights.set(static_cast<double>(trace_.lights.size()));
    shape.passes.set(static_cast<std::uint64_t>(pass_index));
    shape.dispatches.set(static_cast<std::uint64_t>(dispatches));
    shape.scene_triangles.set(static_cast<std::uint64_t>(scene_.triangle_count()));
    shape.geometry_passes.set(static_cast<std::uint64_t>(geometry_passes_));
    std::uint64_t covered = 0;
    for (auto v : result_.images.counters.shaded) covered += v > 0 ? 1 : 0;
    shape.covered_pixels.set(covered);
    return std::move(result_);
  }

 private:
  /// Creates the pass's attachments not made yet (an image buffer a dispatch wrote under its
  /// name is its content), checks them, and points the context at its targets. With
  /// `check_loads_later` (a pass set up before the dispatches ahead of it ran) the check that a
  /// loaded attachment was stored waits for check_loaded_attachments.
  void prepare_attachments(const PassDesc& pass, RenderContext& ctx, bool check_loads_later = false) {
    int samples = -1;
    for (const auto& a : pass.attachments) {
      if (pass.is_resolve_target(a)) {
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
        AttachmentImage img = AttachmentImage::cleared(a, pixels, options_.colour);
        img.keeps_surface = options_.colour || surface_readers_.contains(a.name);
        // An attachment named after an image buffer (trace version 2) is that image, as a dispatch wrote it.
        if (auto ib = result_.images.image_buffers.find(a.name); ib != result_.images.image_buffers.end()) {
          img.color = ib->second.color;
          img.defined = true;
        }
        it = result_.images.attachments.emplace(a.name, std::move(img)).first;
      } else if (it->second.format != a.format || it->second.samples != a.samples) {
        throw InputError(path_, a.line, "attachment '" + a.name + "' was declared earlier with another format or sample count");
      }
    }
    if (!check_loads_later) check_loaded_attachments(pass);
    for (const Attachment* a : pass.color_targets()) ctx.color_targets.push_back(&result_.images.attachments.at(a->name));
    if (const Attachment* d = pass.depth_attachment()) ctx.depth = &result_.images.attachments.at(d->name);
  }

  /// Refuses a pass loading an attachment no earlier command stored.
  void check_loaded_attachments(const PassDesc& pass) const {
    for (const auto& a : pass.attachments) {
      if (a.load == LoadOp::Load && !a.transient && !result_.images.attachments.at(a.name).defined) {
        throw InputError(path_, a.line, "attachment '" + a.name + "' is loaded but no earlier pass stored it");
      }
    }
  }

  /// The pass's draws: pipeline, shader, inputs (resolve_draw_inputs; with `grids_later`, the
  /// light grids wait for resolve_light_grids), selected lights.
  void resolve_draws(const PassDesc& pass, RenderContext& ctx, bool grids_later = false) {
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
      resolve_draw_inputs(pass, cmd, d, grids_later);
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

  static constexpr const char* kNoStoredSurface =
      "the G-buffer or visibility attachment this draw reads holds no surface: no shader wrote it";

  /// The G-buffer and visibility attachments of `pass` that `cmd` fetches (earlier draws of the
  /// pass write them): their surfaces are stored as they shade, so their stores exist from now.
  void allocate_fetched_surfaces(const PassDesc& pass, const DrawCmd& cmd) {
    for (const auto& n : cmd.fetch) {
      const Attachment* a = pass.find_attachment(n);
      if (!a || is_depth_format(a->format)) continue;
      AttachmentImage& img = result_.images.attachments.at(n);
      if (img.surface_valid.empty() && (img.usage == AttachmentUsage::Gbuffer || img.usage == AttachmentUsage::Visibility)) {
        if (img.keeps_surface) img.surface.assign(img.sample_count, options_.colour);
        img.surface_valid.assign(img.sample_count, 0);
      }
    }
  }

  /// Where a draw's shader finds its surface, its light lists and what it samples from DRAM.
  void resolve_draw_inputs(const PassDesc& pass, const DrawCmd& cmd, DrawContext& d, bool grids_later = false) {
    auto surfaces_of = [&](const std::string& n) -> const AttachmentImage* {
      auto it = result_.images.attachments.find(n);
      if (it == result_.images.attachments.end()) return nullptr;
      const auto u = it->second.usage;
      return (u == AttachmentUsage::Gbuffer || u == AttachmentUsage::Visibility) ? &it->second : nullptr;
    };
    for (const auto& n : cmd.fetch) {
      const Attachment* a = pass.find_attachment(n);
      if (!a || is_depth_format(a->format)) continue;
      d.fetch_bytes += a->bytes_per_pixel();
    }
    allocate_fetched_surfaces(pass, cmd);
    if (cmd.geometry != GeometryKind::Scene) {
      for (const auto& n : cmd.fetch) {
        if (!d.surface_source) d.surface_source = surfaces_of(n);
      }
      for (const auto& n : cmd.reads) {
        if (!d.surface_source) d.surface_source = surfaces_of(n);
      }
      if (d.surface_source && d.surface_source->surface_valid.empty()) {
        throw InputError(path_, cmd.line, kNoStoredSurface);
      }
    }
    if (!grids_later) resolve_light_grids(cmd, d);
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

  /// The tile or cluster light grid a draw's shader reads its light lists from (a dispatch
  /// before the pass wrote it).
  void resolve_light_grids(const DrawCmd& cmd, DrawContext& d) const {
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
  }

  /// What the timing model knows of a dispatch before it runs: its name and kind (its content
  /// follows once it has run).
  CommandWork dispatch_header(const DispatchCmd& d, int index) const {
    CommandWork cw;
    cw.name = "dispatch" + std::to_string(index) + "." + to_string(d.kernel);
    cw.frame = options_.sequence_frame;
    cw.is_dispatch = true;
    cw.depends_on_previous = true;  // a dispatch follows a barrier on what it reads
    return cw;
  }

  /// A dispatch that has run: its work for the timing model, summary and traffic, not yet handed on.
  struct DispatchRun {
    CommandWork cw;
    PassSummary summary;
    DramTraffic dram;
  };

  /// Runs a dispatch now and hands its work on.
  void run_dispatch_cmd(const DispatchCmd& d, int index) {
    DispatchRun run = run_dispatch_work(d, index, nullptr);
    finish_command(run.cw.name, &run.cw, std::move(run.summary), run.dram);
  }

  /// Runs a dispatch: its statistics and image, its work for the timing model. The attachment
  /// named after the image it wrote is dropped (a later pass that loads it starts from what the
  /// dispatch wrote), unless it is one of `binned_past`'s, the pass set up before it ran, which
  /// holds it: that pass resets it (reset_replaced_attachments), and `replaced` gets its name.
  DispatchRun run_dispatch_work(const DispatchCmd& d, int index, const PassDesc* binned_past,
                                std::vector<std::string>* replaced = nullptr) {
    CommandWork cw = dispatch_header(d, index);
    const std::string prefix = cw.name;
    ComputeStats stats;
    DramTraffic dram;
    ComputeContext cc;
    static_cast<FrameInputs&>(cc) = inputs_;
    cc.trace = &trace_;
    cc.trace_path = &path_;
    cc.images = &result_.images;
    std::vector<std::uint64_t> texture_lines;
    cc.textures = textures_.get();
    cc.texture_lines = &texture_lines;
    cc.pool = &pool_;
    std::string image;
    run_dispatch(cc, d, stats, dram, image);
    cw.compute_alu_ops = stats.compute_alu_ops.value();
    cw.compute_threads = stats.threads.value();
    cw.compute_texels = stats.compute_texture_fetches.value() * static_cast<std::uint64_t>(hw_.texture.filtered_texels_per_fetch);
    cw.read_bytes = dram.read_bytes;
    cw.write_bytes = dram.write_bytes;
    // Material texture lines go through the texture cache, not as a plain read stream.
    cw.read_bytes[static_cast<std::size_t>(DramClass::Textures)] = 0;
    cw.texture_lines = std::move(texture_lines);
    cw.texture_line_accesses = stats.compute_texture_line_accesses.value();
    if (!image.empty()) {
      result_.final_color = image;
      if (binned_past && binned_past->find_attachment(image)) {
        replaced->push_back(image);
      } else {
        result_.images.attachments.erase(image);  // a later pass that loads it starts from what the dispatch wrote
      }
    }
    command_stats(prefix).compute = stats;
    result_.totals.compute += stats;
    DispatchRun run;
    run.summary.name = prefix;
    run.cw = std::move(cw);
    run.dram = dram;
    return run;
  }

  /// A dispatch after the pass binned ahead, before the pass set up past it (run_pass).
  struct PastDispatch {
    const DispatchCmd* cmd;
    int index;  ///< its dispatch index (its name)
  };

  /// The index of the pass that the dispatches from trace command `i` on (with barriers between
  /// them) lead to, when it can be set up and binned before they run, or 0: a pass binned ahead
  /// is pending, and setting the next pass up early changes nothing those dispatches read and
  /// points at nothing they replace. Early set-up makes the pass's attachments that do not exist
  /// yet (a dispatch must not read one), points its draws at the attachments they read or fetch
  /// (a dispatch must not replace one by an image, unless it is the pass's own: that one is reset
  /// in place) and gives the G-buffers they fetch their surface stores (a dispatch must not read
  /// one).
  std::size_t pass_after_dispatches(std::size_t i) const {
    // Only with the timing model beside the frame (FrameOptions::feed): on one thread nothing
    // runs beside the binning, and two primitive stores alive instead of one cost memory and
    // fresh pages (forward_plus at atrium:5, 1080p: 329 -> 479 MB, 5-7 % more CPU). The results
    // are the same either way (tests/test_threads.cpp compares the two at 1 and 2 threads).
    if (!options_.feed || !pending_ || rop_) return 0;
    const auto& commands = trace_.commands;
    std::vector<const DispatchCmd*> dispatches;
    std::size_t k = i;
    for (; k < commands.size(); ++k) {
      if (const auto* d = std::get_if<DispatchCmd>(&commands[k])) {
        dispatches.push_back(d);
      } else if (!std::holds_alternative<BarrierCmd>(commands[k])) {
        break;
      }
    }
    if (k == commands.size() || !std::holds_alternative<PassDesc>(commands[k])) return 0;
    const PassDesc& next = std::get<PassDesc>(commands[k]);
    const auto& attachments = result_.images.attachments;
    auto names = [](const std::vector<std::string>& list, const std::string& n) { return std::find(list.begin(), list.end(), n) != list.end(); };
    for (const DispatchCmd* d : dispatches) {
      for (const auto& a : next.attachments) {
        if (!attachments.contains(a.name) && names(d->reads, a.name)) return 0;
      }
      for (const auto& dc : next.draws) {
        for (const auto& n : dc.reads) {
          if (attachments.contains(n) && names(d->writes, n) && !next.find_attachment(n)) return 0;
        }
        for (const auto& n : dc.fetch) {
          if (names(d->reads, n) || (names(d->writes, n) && !next.find_attachment(n))) return 0;
        }
      }
    }
    return k;
  }

  /// A pass being replayed: what its renderer works with, kept from its binning to its end.
  struct PassRun {
    const PassDesc* pass = nullptr;
    std::string prefix;
    std::unique_ptr<PassStats> ps = std::make_unique<PassStats>();
    DramTraffic dram;
    RenderContext ctx;
    CommandWork cw;
    std::unique_ptr<PassRenderer> renderer;
    bool live = false;  ///< published to the feed as it goes
  };

  /// Replays a pass: its set-up and binning now; its last render's tiles after the next pass is
  /// binned, when it can be (bin-ahead below), else now. A pass reads what earlier passes wrote
  /// only in its tiles (loads, stored surfaces, PLS) and its binning none of it, so the results
  /// are those of passes replayed one after another; with the timing model beside the frame
  /// (FrameOptions::feed) it gets the next pass's binning while this one's tiles render, as the
  /// hardware bins the next render into its second parameter buffer meanwhile.
  ///
  /// With `past` (pass_after_dispatches: the dispatches between the pass binned ahead and this
  /// one, not run yet) it is binned before them too, and what it reads of them waits for its
  /// catch-up (catch_up_past, before its first tile): the pending pass's tiles, the dispatches,
  /// then the rest of its set-up (the images they wrote as its attachments, the load checks, the
  /// light grids, the once-read buffers at the bytes they wrote, the stored-surface checks). With
  /// the feed, each dispatch is opened with its header before this pass, and closed once run.
  void run_pass(const PassDesc& pass, int index, const std::vector<PastDispatch>& past = {}) {
    const bool early = !past.empty();
    auto run = std::make_unique<PassRun>();
    run->pass = &pass;
    run->prefix = "pass" + std::to_string(index) + "." + pass.name;
    RenderContext& ctx = run->ctx;
    static_cast<FrameInputs&>(ctx) = inputs_;
    ctx.pass = &pass;
    ctx.render_area = pass.area ? PixelRect{static_cast<int>(pass.area->x0), static_cast<int>(pass.area->y0),
                                            static_cast<int>(pass.area->x1), static_cast<int>(pass.area->y1)}
                                : PixelRect{0, 0, viewport_.width_px, viewport_.height_px};
    ctx.images = &result_.images;
    ctx.defer_shading = hw_.gpu.mode == GpuMode::Tbdr;
    ctx.framebuffer_in_dram = hw_.gpu.mode == GpuMode::Imr;
    if (rop_) {
      ctx.rop = rop_.get();
      rop_->bind_pass(pass, run->ps->rop);
    }
    prepare_attachments(pass, ctx, early);
    resolve_draws(pass, ctx, early);
    count_geometry_passes(pass);
    ctx.dram = &run->dram;
    ctx.frame_prim_base = prim_base_;
    ctx.textures = textures_.get();
    CommandWork& cw = run->cw;
    cw.name = run->prefix;
    cw.frame = options_.sequence_frame;
    if (!early) cw.read_bytes = book_buffer_reads(pass, run->dram).read_bytes;  // buffers read once per pass, at its start
    cw.depends_on_previous = reads_earlier_results(pass);

    // The dispatches before it, opened in the feed in trace order before it (their content
    // follows once they have run).
    std::vector<std::size_t> past_feed;
    std::vector<CommandWork*> past_open;
    if (early && options_.feed) {
      for (const PastDispatch& pd : past) {
        past_open.push_back(&options_.feed->open(dispatch_header(*pd.cmd, pd.index)));
        past_feed.push_back(options_.feed->last_opened());
      }
    }

    // The render's primitive records live in stores kept across the frame's passes (two: a pass
    // binned ahead and the one before it): each pass touches the pages its largest render needs,
    // which earlier passes faulted in already.
    ctx.prims = take_prims_buffer();
    run->renderer = std::make_unique<PassRenderer>(ctx, hw_, *run->ps, run->dram, cw, pool_);
    PassRenderer& renderer = *run->renderer;
    // With a feed, a pass whose layout is known before its tiles render is handed to the timing
    // model as it goes (each render when binned, each tile as merged); others when complete.
    const bool known_layout = renderer.layout_known_at_start();
    run->live = options_.feed && known_layout;
    if (run->live) renderer.publish_to(*options_.feed);
    // Tiles of this pass render only after the pass before it (and the dispatches past which it
    // was binned) ended.
    bool caught_up = false;
    auto catch_up = [&, r = run.get()] {
      if (caught_up) return;
      caught_up = true;
      if (!early) {
        if (finish_pending_pass()) recheck_stored_surfaces(*r);
        return;
      }
      catch_up_past(*r, past, past_open, past_feed);
    };
    renderer.before_tiles(catch_up);
    // The pass binned before it renders its tiles on the pool's helpers while this one is binned
    // here (the hardware bins into its second parameter buffer meanwhile); a partial render of
    // this pass ends that pass first (before_tiles), and so does everything after the binning.
    if (pending_ && !rop_) pending_->renderer->start_finish();
    renderer.bin();
    prim_base_ = ctx.frame_prim_base;
    // The pass before it (and the dispatches before it): binned before this one, rendered now
    // (or already, by a partial render of this one).
    if (early) catch_up();
    // What it stores is defined for the commands after it (their loads read it in their tiles).
    for (const auto& a : pass.attachments) {
      AttachmentImage& img = result_.images.attachments.at(a.name);
      img.defined = a.store == StoreOp::Store && !a.transient;
      if (img.defined && a.usage == AttachmentUsage::Color) result_.final_color = a.name;
    }
    if (!early) catch_up();
    renderer.before_tiles(nullptr);
    // Bin-ahead: the next pass is binned before this one's last render's tiles, when this pass's
    // layout is known now (a spilling pass is published complete at its end, after the next
    // pass would have opened) and it has no imr batches. Any command but a pass finishes it first.
    if (known_layout && !rop_) {
      pending_ = std::move(run);
    } else {
      end_pass(*run);
    }
  }

  /// A pass set up and binned before the dispatches past it ran (run_pass with `past`), before
  /// its first tile: the pending pass's tiles, the dispatches (each handed on as it ends, the last
  /// after this pass's header is complete: the timing model reads that after the last
  /// dispatch), then the rest of its set-up, as run_pass makes it for a pass set up after them.
  void catch_up_past(PassRun& run, const std::vector<PastDispatch>& past, const std::vector<CommandWork*>& open,
                     const std::vector<std::size_t>& feed_index) {
    if (finish_pending_pass()) recheck_stored_surfaces(run);
    std::vector<std::string> replaced;
    for (std::size_t k = 0; k < past.size(); ++k) {
      DispatchRun d = run_dispatch_work(*past[k].cmd, past[k].index, run.pass, &replaced);
      const bool last = k + 1 == past.size();
      if (last) complete_set_up(run, replaced);
      if (open.empty()) {
        finish_command(d.cw.name, &d.cw, std::move(d.summary), d.dram);
      } else {
        open[k]->take_dispatch_content(std::move(d.cw));
        finish_command(open[k]->name, nullptr, std::move(d.summary), d.dram, feed_index[k]);
      }
    }
  }

  /// The set-up of a pass binned before the dispatches past it ran, after they ran: the
  /// attachments named after the images they wrote reset to those images (as prepare_attachments
  /// makes an attachment from an image buffer), the load checks, the light grids, the buffers
  /// read once at the bytes written, the stored-surface checks.
  void complete_set_up(PassRun& run, const std::vector<std::string>& replaced) {
    const PassDesc& pass = *run.pass;
    const std::size_t pixels = static_cast<std::size_t>(viewport_.width_px) * static_cast<std::size_t>(viewport_.height_px);
    for (const auto& name : replaced) {
      const Attachment& a = *pass.find_attachment(name);
      AttachmentImage img = AttachmentImage::cleared(a, pixels, options_.colour);
      img.keeps_surface = options_.colour || surface_readers_.contains(a.name);
      img.color = result_.images.image_buffers.at(name).color;
      img.defined = true;
      result_.images.attachments.at(name) = std::move(img);  // in place: the pass's context points at it
    }
    check_loaded_attachments(pass);
    for (DrawContext& d : run.ctx.draws) resolve_light_grids(*d.cmd, d);
    run.renderer->work().read_bytes = book_buffer_reads(pass, run.dram).read_bytes;
    recheck_stored_surfaces(run);
  }

  /// Renders the tiles of the pass binned ahead (if any) and ends it; whether there was one.
  bool finish_pending_pass() {
    if (!pending_) return false;
    std::unique_ptr<PassRun> run = std::move(pending_);
    end_pass(*run);
    return true;
  }

  /// A pass binned before the pass before it ended read that pass's stored surfaces before its
  /// tiles wrote them: what resolve_draws would have found after it. A G-buffer target the pass
  /// fetches gets its surface store if the pass before released it (no tile wrote one), and a
  /// draw that reads a stored surface no shader wrote is refused, as resolve_draw_inputs does.
  void recheck_stored_surfaces(PassRun& run) {
    for (const DrawCmd& cmd : run.pass->draws) allocate_fetched_surfaces(*run.pass, cmd);
    for (const DrawContext& d : run.ctx.draws) {
      if (d.surface_source && d.surface_source->surface_valid.empty()) {
        throw InputError(path_, d.cmd->line, kNoStoredSurface);
      }
    }
  }

  /// The last render's tiles, the pass's statistics and its command.
  void end_pass(PassRun& run) {
    run.renderer->finish();
    give_back_prims_buffer(std::move(run.ctx.prims));
    result_.host_tile_seconds += run.renderer->tile_seconds();
    command_stats(run.prefix).pass = *run.ps;
    result_.totals.render += *run.ps;
    PassSummary summary;
    summary.name = run.pass->name;
    summary.primitives = run.ps->geometry.primitives_out.value();
    summary.shaded_samples = run.ps->tsp.shaded_samples.value();
    summary.partial_renders = run.ps->tiler.partial_renders.value();
    const std::size_t feed_command = run.live ? run.renderer->feed_command() : 0;
    run.renderer.reset();
    finish_command(run.prefix, run.live ? nullptr : &run.cw, std::move(summary), run.dram, feed_command);
  }

  /// The statistics record of command `name` (made when first asked for: in completion order).
  CommandStats& command_stats(const std::string& name) {
    const auto [it, added] = command_index_.try_emplace(name, result_.commands.size());
    if (added) {
      CommandStats& s = result_.commands.emplace_back();
      s.name = name;
    }
    return result_.commands[it->second];
  }

  PrimitiveStore take_prims_buffer() {
    if (prims_buffers_.empty()) return {};
    PrimitiveStore p = std::move(prims_buffers_.back());
    prims_buffers_.pop_back();
    return p;
  }
  void give_back_prims_buffer(PrimitiveStore&& p) {
    p.clear();
    prims_buffers_.push_back(std::move(p));
  }

  /// What every pass and dispatch ends with, after its unit statistics: its work for the timing
  /// model (`cw`, or nullptr when the feed holds it open: closed now), its DRAM rows (under its
  /// work's name), its summary with its traffic, the frame's traffic.
  void finish_command(const std::string& name, CommandWork* cw, PassSummary summary, const DramTraffic& dram,
                      std::size_t feed_command = 0) {
    command_stats(name).requested = dram;
    if (cw == nullptr) {
      options_.feed->close_command(feed_command);
    } else if (options_.feed) {
      options_.feed->publish(std::move(*cw));
    } else {
      result_.work.commands.push_back(std::move(*cw));
    }
    summary.dram = dram;
    result_.passes.push_back(std::move(summary));
    result_.dram += dram;
  }

  /// Geometry passes: submissions of the scene's opaque geometry (a PreZ, a G-buffer pass, each
  /// additive pass of a multi-pass technique, the forward pass).
  void count_geometry_passes(const PassDesc& pass) {
    for (const auto& dc : pass.draws) {
      if (dc.geometry == GeometryKind::Scene && dc.submesh.empty() && dc.material.empty() &&
          (dc.subset == SceneSubset::All || dc.subset == SceneSubset::Opaque)) {
        ++geometry_passes_;
      }
    }
  }

  /// Buffers the draws read (lights, light lists): booked once per pass (re-reads hit on chip).
  DramTraffic book_buffer_reads(const PassDesc& pass, DramTraffic& dram) const {
    DramTraffic reads;
    std::set<std::string> seen;
    for (const auto& dc : pass.draws) {
      for (const auto& n : dc.reads) {
        const BufferDesc* b = trace_.find_buffer(n);
        if (!b || !seen.insert(n).second) continue;
        auto w = result_.images.buffer_bytes_written.find(n);
        const std::uint64_t bytes = w == result_.images.buffer_bytes_written.end() ? b->bytes : w->second;
        reads.read(b->traffic, bytes);
      }
    }
    dram += reads;
    return reads;
  }

  /// Whether the pass must wait for earlier commands: it loads a stored attachment or reads a buffer.
  static bool reads_earlier_results(const PassDesc& pass) {
    for (const auto& a : pass.attachments) {
      if (a.load == LoadOp::Load && !a.transient) return true;
    }
    for (const auto& dc : pass.draws) {
      if (!dc.reads.empty()) return true;
    }
    return false;
  }

  const Trace& trace_;
  const std::string& path_;
  const Scene& scene_;
  const HwConfig& hw_;
  FrameOptions options_;
  Viewport viewport_;
  CameraXform camera_;
  ViewFrustum frustum_;
  LightScreenBins light_bins_;  ///< candidate lights per screen bin, for the frame's images
  FrameInputs inputs_;          ///< what every pass and dispatch reads of the frame
  std::uint32_t prim_base_ = 0;
  int geometry_passes_ = 0;
  std::unique_ptr<TextureLayout> textures_;  ///< the frame's texture address space
  std::unique_ptr<RenderOutputUnit> rop_;    ///< gpu.mode=imr: the ROP caches, kept across the frame's passes
  std::set<std::string> surface_readers_;    ///< stored_surface_readers of the trace
  std::vector<PrimitiveStore> prims_buffers_;  ///< RenderContext::prims between passes (their chunks kept)
  std::unique_ptr<PassRun> pending_;           ///< a pass binned, its last render's tiles not rendered yet
  ThreadPool pool_;                          ///< the threads the passes' tiles render on
  FrameResult result_;
  std::unordered_map<std::string, std::size_t> command_index_;  ///< result_.commands by name
};

}  // namespace

std::size_t timed_command_count(const Trace& trace) {
  std::size_t commands = 0;
  for (const auto& cmd : trace.commands) {
    commands += std::holds_alternative<PassDesc>(cmd) || std::holds_alternative<DispatchCmd>(cmd) ? 1 : 0;
  }
  return commands;
}

FrameResult simulate_frame(const Trace& trace, const std::string& trace_path, const Scene& scene, const HwConfig& hw,
                           const FrameOptions& options) {
  // The feed is closed however the simulation ends (after a sequence's last frame, or when a
  // frame fails): a timing model waiting on it stops waiting.
  struct CloseFeed {
    WorkFeed* feed;
    bool last;
    ~CloseFeed() {
      if (feed && (last || std::uncaught_exceptions() > 0)) feed->close();
    }
  } close_feed{options.feed, options.sequence_frame + 1 >= options.sequence_frames};
  if (options.colour) {
    // Colours sample the base colour texels: a scene loaded without them (SceneLoadOptions)
    // would shade every textured surface untextured.
    for (const ColorTexels& t : scene.base_color_texels) {
      if (t.width > 0 && t.height > 0 && !t.decoded()) {
        throw std::logic_error("simulate_frame: colours asked of a scene loaded without its colour texels");
      }
    }
  }
  FrameSimulator sim(trace, trace_path, scene, hw, options);
  return sim.run();
}

}  // namespace tbdr
