#include "app/run_driver.hpp"
#include "app/run_stats.hpp"
#include "app/stat_rows.hpp"
#include "app/sampled_run.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <ctime>
#include <time.h>
#include <filesystem>

#include <unistd.h>
#include <functional>
#include <future>
#include <iomanip>
#include <map>
#include <optional>
#include <ostream>
#include <sstream>

#include "kernel/errors.hpp"
#include "kernel/params.hpp"
#include "kernel/thread_pool.hpp"
#include "models/work_feed.hpp"
#include "models/frame_signature.hpp"
#include "app/host_speed.hpp"
#include "app/image_output.hpp"
#include "analysis/results_db.hpp"
#include "trace/trace.hpp"
#include "tbdrsim_version.hpp"
#include "scene/scene_library.hpp"

namespace tbdr {

namespace {

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

/// CPU time of this process, seconds (less sensitive than wall time to other load on the host).
double cpu_seconds() { return static_cast<double>(std::clock()) / CLOCKS_PER_SEC; }

/// CPU seconds of the calling thread alone (the timing model's, while images are written beside it).
double thread_cpu_seconds() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + static_cast<double>(t.tv_nsec) * 1e-9;
}

/// The scene a trace references: the atrium at its detail, or the glTF path relative to the
/// trace file first, then to the working directory.
std::shared_ptr<const Scene> load_trace_scene(const Trace& trace, const std::string& trace_path, const SceneLoadOptions& options) {
  if (trace.scene.kind == SceneKind::Atrium) return shared_scene("atrium:" + std::to_string(trace.scene.detail), options);
  namespace fs = std::filesystem;
  const fs::path rel = fs::path(trace_path).parent_path() / trace.scene.path;
  const std::string path = fs::exists(rel) ? rel.string() : trace.scene.path;
  std::error_code ec;
  if (fs::status(path, ec).type() == fs::file_type::not_found) {
    throw InputError(trace_path, trace.scene.line, "scene file '" + trace.scene.path + "' not found (looked in " +
                                                       rel.string() + " and the working directory)");
  }
  try {
    check_input_file(path, "scene file");  // a folder (path=.), permission denied, a symlink loop
  } catch (const InputError& e) {
    throw InputError(trace_path, trace.scene.line, std::string("scene ") + e.what());
  }
  return shared_scene(path, options);
}

std::string stat_text(double v) {
  std::ostringstream s;
  s << std::fixed << std::setprecision(2) << v;
  return s.str();
}


}  // namespace

RunParam config_label_param(const std::string& label) { return {"config.label", label, "config"}; }

std::vector<RunParam> trace_run_params(const Trace& trace, const std::string& trace_path) {
  std::vector<RunParam> params;
  for (const auto& [k, v] : trace.options) {
    params.push_back({"technique." + k, v, "trace " + trace_path + ":" + std::to_string(trace.technique_line)});
  }
  if (!trace.camera_name.empty()) {
    params.push_back({"trace.camera", trace.camera_name, "trace " + trace_path + ":" + std::to_string(trace.camera_line)});
  }
  return params;
}

namespace {

/// The image of a G-buffer or visibility attachment: what its data stands for, from the surfaces
/// the frame stored (the first G-buffer target a shader writes keeps them for its siblings;
/// FormatPrecision::surface has applied each target's format). `albedo` shows the stored base
/// colour, `normal` the normal as n/2 + 1/2, a visibility attachment its triangle ids (as
/// triangle_id.png); sample 0 of each pixel, black where none was written. Other G-buffer targets
/// hold nothing the model keeps: no image.
std::optional<ImageRGB8> surface_image(const FrameImages& images, const std::string& name, const AttachmentImage& img) {
  const AttachmentImage* store = img.surface.empty() ? nullptr : &img;
  for (const auto& [other, o] : images.attachments) {
    if (!store && o.usage == img.usage && !o.surface.empty() && o.samples == img.samples) store = &o;
  }
  const bool albedo = name == "albedo", normal = name == "normal", ids = img.usage == AttachmentUsage::Visibility;
  if (!store || !(albedo || normal || ids)) return std::nullopt;
  const int w = images.width, h = images.height;
  const std::size_t pixels = static_cast<std::size_t>(w) * static_cast<std::size_t>(h);
  const std::size_t S = store->samples;
  auto written = [&](std::size_t p) { return store->surface_valid[p * S] != 0; };
  if (ids) {
    std::vector<std::uint32_t> id(pixels, 0);
    for (std::size_t p = 0; p < pixels; ++p) {
      if (written(p)) id[p] = store->surface.site(p * S).triangle + 1;
    }
    return ids_to_image(id, w, h, 0);
  }
  // (Looks are kept: surface stores keep them with colours, which images imply.)
  if (albedo) {  // linear colour, shown in sRGB as color_to_image shows it (black: sRGB of 0)
    ImageRGB8 out(w, h);
    for (std::size_t p = 0; p < pixels; ++p) {
      if (!written(p)) continue;
      const Rgb8 c = linear_to_srgb8(store->surface.look(p * S).albedo);
      out.rgb[3 * p] = c.r;
      out.rgb[3 * p + 1] = c.g;
      out.rgb[3 * p + 2] = c.b;
    }
    return out;
  }
  // A normal map's usual picture: n/2 + 1/2 as 8-bit unorm, not a colour (no sRGB curve).
  ImageRGB8 out(w, h);
  auto unorm8 = [](float v) { return static_cast<std::uint8_t>(lround_nonnegative(std::clamp(v * 0.5f + 0.5f, 0.0f, 1.0f) * 255.0f)); };
  for (std::size_t p = 0; p < pixels; ++p) {
    if (!written(p)) continue;
    const glm::vec3 n = store->surface.look(p * S).normal;
    out.rgb[3 * p] = unorm8(n.x);
    out.rgb[3 * p + 1] = unorm8(n.y);
    out.rgb[3 * p + 2] = unorm8(n.z);
  }
  return out;
}

}  // namespace

std::vector<std::string> write_frame_images(const FrameResult& frame, const std::string& dir, unsigned threads,
                                            double* cpu_seconds) {
  namespace fs = std::filesystem;
  const int w = frame.images.width, h = frame.images.height;
  const std::size_t pixels = static_cast<std::size_t>(w) * static_cast<std::size_t>(h);
  auto out = [&](const std::string& name) { return (fs::path(dir) / name).string(); };
  // Every image is made and encoded on its own, from the frame only: the jobs run on `threads`
  // threads (PNG compression is most of an image's cost) and their files are listed in this order.
  struct Job {
    std::string file;
    std::function<std::optional<ImageRGB8>()> make;  ///< nothing: no image to write
  };
  std::vector<Job> jobs;
  for (const auto& [name, img_ref] : frame.images.attachments) {
    const AttachmentImage& img = img_ref;
    const std::string attachment = name;
    if (img.usage == AttachmentUsage::Depth) {
      jobs.push_back({"depth_" + name + ".png", [&img, pixels, w, h]() -> std::optional<ImageRGB8> {
                        std::vector<float> d(pixels);
                        for (std::size_t p = 0; p < pixels; ++p) d[p] = img.depth[p * img.samples];
                        return depth_to_image(d, w, h);
                      }});
    } else if (!img.color.empty() && img.samples == 1) {
      jobs.push_back({"attachment_" + name + ".png", [&img, w, h]() -> std::optional<ImageRGB8> { return color_to_image(img.color, w, h); }});
    } else if (img.usage == AttachmentUsage::Gbuffer || img.usage == AttachmentUsage::Visibility) {
      jobs.push_back({"attachment_" + name + ".png", [&frame, attachment, &img] { return surface_image(frame.images, attachment, img); }});
    }
  }
  const std::size_t attachment_jobs = jobs.size();
  // The final colour: its attachment's file copied when that was written above (not encoded twice).
  std::optional<std::string> color_copied_from;
  if (auto it = frame.images.attachments.find(frame.final_color); it != frame.images.attachments.end()) {
    if (!it->second.color.empty() && it->second.samples == 1) {
      color_copied_from = out("attachment_" + frame.final_color + ".png");
    } else {
      const AttachmentImage& img = it->second;
      jobs.push_back({"color.png", [&img, w, h]() -> std::optional<ImageRGB8> { return color_to_image(img.color, w, h); }});
    }
  } else if (auto ib = frame.images.image_buffers.find(frame.final_color); ib != frame.images.image_buffers.end()) {
    const auto& color = ib->second.color;
    jobs.push_back({"color.png", [&color, w, h]() -> std::optional<ImageRGB8> { return color_to_image(color, w, h); }});
  }
  jobs.push_back({"triangle_id.png", [&frame, w, h]() -> std::optional<ImageRGB8> { return ids_to_image(frame.images.counters.triangle_id, w, h, 0); }});
  auto heat = [&](const std::vector<std::uint32_t>& v, const std::string& file, const std::string& title, const std::string& unit) {
    jobs.push_back({file, [&v, title, unit, w, h]() -> std::optional<ImageRGB8> {
                      HeatmapSpec spec;
                      spec.title = title;
                      spec.unit = unit;
                      return heatmap_to_image(v, w, h, spec);
                    }});
  };
  heat(frame.images.counters.rasterised_samples, "heat_overdraw.png", "Overdraw", "samples rasterised per pixel");
  heat(frame.images.counters.shaded, "heat_shaded.png", "Shading", "shader invocations per pixel");
  heat(frame.images.counters.lights_evaluated, "heat_lights.png", "Lights evaluated", "lights per pixel");

  std::vector<char> made(jobs.size(), 0);
  std::vector<double> cpu(jobs.size(), 0.0);
  ThreadPool pool(std::max(1u, std::min<unsigned>(threads, static_cast<unsigned>(jobs.size()))));
  pool.for_each(jobs.size(), [&](std::size_t i, unsigned) {
    const double c = thread_cpu_seconds();
    if (const std::optional<ImageRGB8> image = jobs[i].make()) {
      write_png(out(jobs[i].file), *image);
      made[i] = 1;
    }
    cpu[i] = thread_cpu_seconds() - c;
  });
  // The files in the order they are listed: the attachments, the final colour, the rest.
  std::vector<std::string> written;
  for (std::size_t i = 0; i < jobs.size(); ++i) {
    if (i == attachment_jobs && color_copied_from) {
      std::error_code ec;
      fs::copy_file(*color_copied_from, out("color.png"), fs::copy_options::overwrite_existing, ec);
      if (ec) throw InputError(out("color.png"), "cannot write PNG image (" + ec.message() + ")");
      written.push_back(out("color.png"));
    }
    if (made[i]) written.push_back(out(jobs[i].file));
  }
  if (cpu_seconds != nullptr) {
    *cpu_seconds = 0;
    for (double c : cpu) *cpu_seconds += c;
  }
  return written;
}

void book_timing(const HwConfig& hw, const FrameResult& frame, const TimingResult& timing, EnergyBreakdown& energy) {
  energy = compute_energy(hw, frame.totals, timing.memory, timing.frame_time_ps,
                          std::max<int>(1, static_cast<int>(timing.frames.size())));
}

std::vector<EnergyBreakdown> sequence_frame_energy(const HwConfig& hw, const std::vector<FrameStats>& frames,
                                                   const TimingResult& timing) {
  std::vector<EnergyBreakdown> out;
  if (timing.frames.size() < 2 || frames.size() != timing.frames.size() || timing.frame_cycles <= 0) return out;
  const double ps_per_cycle = timing.frame_time_ps / timing.frame_cycles;
  for (std::size_t k = 0; k < frames.size(); ++k) {
    const FrameTime& f = timing.frames[k];
    const MemorySystemStats memory = k > 0 ? f.memory_at_end - timing.frames[k - 1].memory_at_end : f.memory_at_end;
    const double interval_ps = (f.end_cycle - (k > 0 ? timing.frames[k - 1].end_cycle : 0.0)) * ps_per_cycle;
    out.push_back(compute_energy(hw, frames[k], memory, interval_ps, 1));
  }
  return out;
}

void time_frame(const HwConfig& hw, const FrameResult& frame, TimingResult& timing, EnergyBreakdown& energy) {
  timing = run_timing(hw, frame.work);
  book_timing(hw, frame, timing, energy);
}

std::string write_tile_cycles_image(const FrameResult& frame, const TimingResult& timing, const std::string& dir) {
  const int tw = frame.work.tile_width, th = frame.work.tile_height;
  const int tx = (frame.images.width + tw - 1) / tw, ty = (frame.images.height + th - 1) / th;
  std::vector<double> cycles(static_cast<std::size_t>(tx) * static_cast<std::size_t>(ty), 0.0);
  for (const auto& t : timing.tiles) {
    if (t.tile_x < tx && t.tile_y < ty) cycles[static_cast<std::size_t>(t.tile_y * tx + t.tile_x)] += t.cycles;
  }
  HeatmapSpec spec;
  spec.title = "Tile cycles";
  spec.unit = "cycles per tile, summed over passes (fetch to writeback)";
  const std::string path = (std::filesystem::path(dir) / "heat_tile_cycles.png").string();
  write_png(path, heatmap_tiles_to_image(cycles, tx, ty, tw, th, frame.images.width, frame.images.height, spec));
  return path;
}

namespace {

/// The images folder of a run, and the folders above it the run creates: removed again unless
/// the run succeeds (a refused trace, a full disk), so a failed run leaves nothing behind.
class RunImagesFolder {
 public:
  /// Creates `dir` (nothing when empty).
  explicit RunImagesFolder(const std::string& dir) {
    namespace fs = std::filesystem;
    if (dir.empty()) return;
    std::error_code ec;
    fs::path outermost;
    for (fs::path p = fs::path(dir).lexically_normal(); !p.empty() && !fs::exists(p, ec); p = p.parent_path()) {
      outermost = p;
      if (p == p.parent_path()) break;
    }
    fs::create_directories(dir, ec);
    if (ec || !fs::is_directory(dir)) throw InputError(dir, "cannot create the images folder");
    created_ = outermost.string();
  }
  RunImagesFolder(const RunImagesFolder&) = delete;
  RunImagesFolder& operator=(const RunImagesFolder&) = delete;
  ~RunImagesFolder() {
    std::error_code ec;
    if (!created_.empty()) std::filesystem::remove_all(created_, ec);
  }
  /// The run is written: its images stay.
  void keep() { created_.clear(); }

 private:
  std::string created_;  ///< the outermost folder this run created; empty once kept
};

/// A run's results database. A new database is made beside its name with the run in it and
/// linked in at the end (ResultsDb::link_into_place), so a run that fails to write it (a full
/// disk) leaves no database at all; its errors name the database asked for.
class RunDatabase {
 public:
  explicit RunDatabase(const std::string& asked) : asked_(asked) {
    std::error_code ec;
    new_ = !std::filesystem::exists(asked, ec) && !ec;
    path_ = new_ ? asked + ".run-" + std::to_string(getpid()) : asked;
  }

 private:
  /// Runs `step`; an InputError about the new database's working file names the database asked for.
  template <class Step>
  auto as_asked(Step&& step) {
    if (!new_) return step();
    try {
      return step();
    } catch (const InputError& e) {
      auto named = [&](std::string text) {
        for (auto at = text.find(path_); at != std::string::npos; at = text.find(path_, at + asked_.size())) {
          text.replace(at, path_.size(), asked_);
        }
        return text;
      };
      const std::string where = named(e.where());
      std::string what = named(e.what());
      if (what.rfind(where + ": ", 0) == 0) what = what.substr(where.size() + 2);
      if (where == asked_ && what.rfind("cannot create the results database", 0) != 0) {
        what = "cannot create the results database: " + what + "; nothing written";
      }
      throw InputError(where, what);
    }
  }


 public:
  RunDatabase(const RunDatabase&) = delete;
  RunDatabase& operator=(const RunDatabase&) = delete;
  ~RunDatabase() {
    if (!new_) return;
    db_.reset();
    std::error_code ec;
    for (const char* suffix : {"", "-wal", "-shm", "-journal"}) std::filesystem::remove(path_ + suffix, ec);
  }

  /// Opens it (a new one created; its schema made in place: the working file is this process's alone).
  void open() {
    as_asked([&] { open_now(); });
  }

  /// Writes the run; reads its derived figures back into `derived` when given. Returns its id.
  std::int64_t write(const RunRecord& rec, DerivedFigures* derived) {
    std::int64_t id = 0;
    as_asked([&] {
      if (!db_) open_now();
      id = write_into(rec, derived);
      if (new_) db_.reset();  // closed: the write-ahead log is folded in
    });
    if (new_ && !as_asked([&] { return ResultsDb::link_into_place(path_, asked_); })) {
      // Another process created the database meanwhile: the run goes into theirs.
      db_.emplace(asked_);
      id = write_into(rec, derived);
    }
    return id;
  }

 private:
  void open_now() {
    if (new_) {
      db_.emplace(path_, ResultsDb::kSchemaVersion, ResultsDb::InPlace{});
    } else {
      db_.emplace(path_);
    }
  }
  std::int64_t write_into(const RunRecord& rec, DerivedFigures* derived) {
    const std::int64_t id = db_->write_run(rec);
    if (derived != nullptr) *derived = read_derived_figures(*db_, id);
    return id;
  }
  std::string asked_;  ///< the database the run was asked to write
  std::string path_;   ///< the file written: asked_, or its working name while new
  bool new_ = false;
  std::optional<ResultsDb> db_;
};

/// Whether the functional run computes colours for a frame: for the images (of the last frame,
/// `last`), and for transaction elimination's tile signatures (every frame).
bool needs_colours(const RunRequest& req, bool last) {
  return (!req.images_dir.empty() && last) || req.config.hw.writeback.transaction_elimination != 0;
}

/// A run's trace (its frames: one, or a sequence) and the scene it references.
struct RunInputs {
  std::vector<Trace> frames;
  std::shared_ptr<const Scene> scene;
  /// Per frame, the scene it draws: `scene`, or `scene` posed at the frame's `pose` (an animated
  /// glTF scene, one copy per distinct pose).
  std::vector<std::shared_ptr<const Scene>> frame_scenes;
  const Scene& scene_of(std::size_t k) const { return k < frame_scenes.size() ? *frame_scenes[k] : *scene; }
  /// The first frame: the technique, scene and options every frame shares.
  const Trace& trace() const { return frames.front(); }
};

/// Reads the trace and loads its scene; checks the trace's sub-mesh and material names, before any
/// work. Colours (and the texels they sample) are loaded only for the images that read them: the
/// statistics are the same either way (tests/test_speed_equivalence.cpp).
RunInputs load_run_inputs(const RunRequest& req) {
  RunInputs in{read_trace_frames(req.trace_path), nullptr, {}};
  in.scene = load_trace_scene(in.trace(), req.trace_path, SceneLoadOptions{.colour_texels = needs_colours(req, true)});
  for (const Trace& frame : in.frames) check_scene_references(frame, *in.scene, req.trace_path);
  std::map<std::pair<int, double>, std::shared_ptr<const Scene>> poses;
  for (const Trace& frame : in.frames) {
    if (!frame.pose) {
      in.frame_scenes.push_back(in.scene);
      continue;
    }
    auto& posed = poses[{frame.pose->animation, frame.pose->time_s}];
    if (!posed) {
      auto copy = std::make_shared<Scene>(*in.scene);
      pose_scene(*copy, static_cast<std::size_t>(frame.pose->animation), frame.pose->time_s);
      posed = std::move(copy);
    }
    in.frame_scenes.push_back(posed);
  }
  return in;
}

/// Without images nothing reads the frame's pixels again (the statistics are taken): their memory
/// (stored surfaces, depth, per-pixel counters: about 500 MB for deferred at 3840x2160) is given
/// back before the timing model builds its streams (its DMA streams there: about 300 MB), so the
/// two peaks do not add up (with more than one thread the timing model has run beside the
/// functional run: measured deferred at 3840x2160 228 MB at 2 threads, 166 MB at 1).
void release_pixels_without_images(const RunRequest& req, FrameResult& frame) {
  if (!req.images_dir.empty()) return;
  FrameImages kept;  // the frame's size, for the summary
  kept.width = frame.images.width;
  kept.height = frame.images.height;
  frame.images = std::move(kept);
}

/// The frame's images: with more than one thread written on their own threads while the timing
/// model runs (the images read FrameResult::images, the timing model FrameResult::work), else
/// after it.
class FrameImageJob {
 public:
  explicit FrameImageJob(const RunRequest& req) : req_(req) {}
  /// Starts writing beside the timing model, where the run has the threads for it.
  void start_beside(const FrameResult& frame) {
    if (!req_.images_dir.empty() && req_.threads > 1) {
      written_ = std::async(std::launch::async, [this, &frame] { return write_frame_images(frame, req_.images_dir, req_.threads, &cpu_seconds_); });
    }
  }
  /// Waits for the writer started beside the timing model (nothing if none was).
  void wait() {
    if (written_.valid()) written_.wait();
  }
  /// The files written (written now unless started beside): the frame's images, then the tile cycles.
  std::vector<std::string> finish(const FrameResult& frame, const TimingResult& timing) {
    std::vector<std::string> files = written_.valid() ? written_.get() : write_frame_images(frame, req_.images_dir, req_.threads, &cpu_seconds_);
    files.push_back(write_tile_cycles_image(frame, timing, req_.images_dir));
    return files;
  }
  /// CPU seconds the images took on all their threads.
  double cpu_seconds() const { return cpu_seconds_; }

 private:
  const RunRequest& req_;
  std::future<std::vector<std::string>> written_;
  double cpu_seconds_ = 0;
};

/// Adds `next`, a later frame of a sequence, to `sum`, the frames before it: the unit statistics,
/// each command's (by name: a sequence's pass figures are its frames' sums), the traffic and the
/// shape's counts; the images become the latest frame's.
void add_sequence_frame(FrameResult& sum, FrameResult&& next) {
  sum.totals.render += next.totals.render;
  sum.totals.compute += next.totals.compute;
  for (CommandStats& c : next.commands) {
    auto it = std::find_if(sum.commands.begin(), sum.commands.end(), [&](const CommandStats& s) { return s.name == c.name; });
    if (it == sum.commands.end()) {
      sum.commands.push_back(std::move(c));
      continue;
    }
    if (it->pass && c.pass) *it->pass += *c.pass;
    if (it->compute && c.compute) *it->compute += *c.compute;
    it->requested += c.requested;
  }
  for (PassSummary& p : next.passes) sum.passes.push_back(std::move(p));
  sum.dram += next.dram;
  // Counts add up over the frames (covered pixels too: per-pixel figures stay per frame); sizes stay.
  sum.shape.passes += next.shape.passes;
  sum.shape.dispatches += next.shape.dispatches;
  sum.shape.geometry_passes += next.shape.geometry_passes;
  sum.shape.covered_pixels.set(sum.shape.covered_pixels.value() + next.shape.covered_pixels.value());
  sum.images = std::move(next.images);
  sum.final_color = std::move(next.final_color);
  sum.host_tile_seconds += next.host_tile_seconds;
}

/// Simulates the run's frames functionally: one frame as simulate_frame does; a sequence frame by
/// frame into `feed` (which it needs), one feed for all (the first frame begins it, the last
/// closes it; each command carries its frame), their results added up (add_sequence_frame), each
/// frame's unit statistics kept in `frame_totals` (a sequence only). Colours are computed where
/// needs_colours says: the last frame's for its images, every frame's for transaction elimination
/// (whose tile signatures this function keeps from one frame to the next).
FrameResult simulate_frames(const RunRequest& req, const RunInputs& in, WorkFeed* feed, std::vector<FrameStats>& frame_totals) {
  const int n = static_cast<int>(in.frames.size());
  FrameOptions options{.colour = needs_colours(req, true), .threads = req.threads, .feed = feed};
  TileSignatures signatures;  // writeback.transaction_elimination: from one frame to the next
  if (req.config.hw.writeback.transaction_elimination != 0) options.tile_signatures = &signatures;
  if (n == 1) return simulate_frame(in.trace(), req.trace_path, in.scene_of(0), req.config.hw, options);
  if (feed == nullptr) throw std::logic_error("simulate_frames: a sequence needs a feed");
  options.sequence_frames = n;
  for (const Trace& t : in.frames) options.sequence_commands += timed_command_count(t);
  FrameResult sum;
  for (int k = 0; k < n; ++k) {
    options.sequence_frame = k;
    options.colour = needs_colours(req, k == n - 1);
    FrameResult frame = simulate_frame(in.frames[static_cast<std::size_t>(k)], req.trace_path, in.scene_of(static_cast<std::size_t>(k)),
                                       req.config.hw, options);
    frame_totals.push_back(frame.totals);
    if (k == 0) {
      sum = std::move(frame);
    } else {
      add_sequence_frame(sum, std::move(frame));
    }
  }
  return sum;
}

/// The functional run and the timing model one after the other, on the caller's thread (a
/// sequence's frames into a feed, which the timing model then reads whole).
void simulate_serially(const RunRequest& req, const RunInputs& in, RunOutcome& o,
                       const std::vector<AddressRegion>* address_layout = nullptr) {
  const auto t_sim = std::chrono::steady_clock::now();
  const double c_sim = cpu_seconds();
  WorkFeed feed;
  const bool sequence = in.frames.size() > 1;
  o.frame = simulate_frames(req, in, sequence ? &feed : nullptr, o.sequence.totals);
  if (sequence) o.frame.work = feed.take();
  if (address_layout != nullptr) o.frame.work.address_layout = *address_layout;
  o.wall_seconds = seconds_since(t_sim);
  o.cpu_seconds = cpu_seconds() - c_sim;
  release_pixels_without_images(req, o.frame);
  const auto t_timing = std::chrono::steady_clock::now();
  const double c_timing = thread_cpu_seconds();
  o.timing = run_timing(req.config.hw, o.frame.work, req.dram_observer);
  o.timing_seconds = seconds_since(t_timing);
  o.timing_cpu_seconds = thread_cpu_seconds() - c_timing;
}

/// The timing model on its own thread beside the functional run, taking each command as soon as
/// the functional run has completed it (models/work_feed.hpp): the same results, as it waits for
/// whatever its schedule needs next. Meanwhile the images start (`images`) and the database is
/// opened (a new one created: the functional run has read every input by now, so an input it
/// refuses has written nothing).
void simulate_pipelined(const RunRequest& req, const RunInputs& in, RunOutcome& o, FrameImageJob& images, RunDatabase& db) {
  const auto t_sim = std::chrono::steady_clock::now();
  const double c_sim = cpu_seconds();
  WorkFeed feed;
  double timing_thread_cpu = 0;
  // The caller's thread and the timing model's on different CPUs while the frame runs (host speed
  // only: app/host_speed.hpp).
  CriticalThreadPlacement placement(req.threads);
  std::future<TimingResult> timed = std::async(std::launch::async, [&req, &feed, &timing_thread_cpu, &placement] {
    const double c = thread_cpu_seconds();
    feed.frame();  // the frame has begun: its tile helpers exist, with every CPU the caller had
    placement.keep_apart();
    TimingResult r = run_timing(req.config.hw, feed, req.dram_observer);
    timing_thread_cpu = thread_cpu_seconds() - c;
    return r;
  });
  try {
    o.frame = simulate_frames(req, in, &feed, o.sequence.totals);
  } catch (...) {
    placement.restore();
    // The feed is closed (simulate_frame closes it; again here, whatever failed): the timing
    // model ends with what it was given; its result is dropped.
    feed.close();
    try {
      timed.get();
    } catch (...) {
    }
    throw;
  }
  placement.restore();  // before the image writers start (threads inherit the caller's CPUs)
  o.wall_seconds = seconds_since(t_sim);
  release_pixels_without_images(req, o.frame);
  images.start_beside(o.frame);
  const double c_db = thread_cpu_seconds();
  db.open();
  const double db_open_cpu = thread_cpu_seconds() - c_db;
  o.timing = timed.get();
  o.frame.work = feed.take();
  o.timing_seconds = seconds_since(t_sim);  // (it ran from the start, beside the functional run)
  o.timing_cpu_seconds = timing_thread_cpu;
  o.timing_wait_seconds = feed.consumer_wait_seconds();
  // The functional run's CPU: the process's since it started less the timing thread's and the
  // image writer's (finished first: the main thread does nothing else meanwhile).
  images.wait();
  o.cpu_seconds = std::max(0.0, cpu_seconds() - c_sim - timing_thread_cpu - images.cpu_seconds() - db_open_cpu);
}

/// Sampled simulation (RunRequest::sample_frames): every frame's signature, the groups and their
/// representatives, then each window of frames around the representatives simulated as a sequence
/// of its own, from cold (simulate_serially; its work released before the next window), and each
/// representative's figures taken as its window ran it.
void simulate_sampled(const RunRequest& req, const RunInputs& in, RunOutcome& o) {
  const auto t_sim = std::chrono::steady_clock::now();
  const double c_sim = cpu_seconds();
  const std::size_t n = in.frames.size();
  SampledSequence sampled;
  std::vector<std::vector<double>> rows;
  for (std::size_t k = 0; k < n; ++k) {
    const Trace& frame = in.frames[k];
    sampled.signatures.push_back(frame_signature(frame, in.scene_of(k)));
    rows.push_back(sampled.signatures.back().values());
  }
  sampled.plan = plan_sampling(rows, req.sample_frames);
  sampled.windows = sample_windows(sampled.plan, n, req.sample_warmup_frames);
  sampled.measured.resize(sampled.plan.groups());
  RunRequest window_req = req;
  window_req.images_dir.clear();
  double timing_cpu = 0;
  std::vector<AddressRegion> first_layout;
  for (const SampleWindow& w : sampled.windows) {
    const auto first = in.frames.begin() + static_cast<std::ptrdiff_t>(w.first);
    const auto first_scene = in.frame_scenes.begin() + static_cast<std::ptrdiff_t>(w.first);
    RunInputs window{std::vector<Trace>(first, first + static_cast<std::ptrdiff_t>(w.frames())), in.scene,
                     {first_scene, first_scene + static_cast<std::ptrdiff_t>(w.frames())}};
    const bool last_is_representative = std::find(sampled.plan.representative.begin(), sampled.plan.representative.end(),
                                                  w.last) != sampled.plan.representative.end();
    if (!last_is_representative) window.frames.back() = frame_after_representative(window.frames.back());
    RunOutcome run;
    // Later windows place their data where the sequence's first frames did (the first window, from
    // frame 0, is the sequence's own beginning): a frame's DRAM timing depends on its addresses.
    simulate_serially(window_req, window, run, w.first == 0 ? nullptr : &first_layout);
    if (w.first == 0) first_layout = run.timing.address_layout;
    timing_cpu += run.timing_cpu_seconds;
    run.frame.work.commands = {};
    SequenceFrames frames{std::move(run.sequence.totals), {}};
    frames.energy = sequence_frame_energy(req.config.hw, frames.totals, run.timing);
    sampled.ms_per_cycle = run.timing.frame_time_ps * 1e-9 / run.timing.frame_cycles;
    for (std::size_t g = 0; g < sampled.plan.groups(); ++g) {
      const std::size_t r = sampled.plan.representative[g];
      if (r >= w.first && r <= w.last) sampled.measured[g] = sequence_frame_stats(run.timing, frames, r - w.first);
    }
  }
  o.wall_seconds = seconds_since(t_sim);
  o.timing_seconds = 0;
  o.timing_cpu_seconds = timing_cpu;
  o.cpu_seconds = std::max(0.0, cpu_seconds() - c_sim - timing_cpu);
  const SamplingSummaryStats estimate = summarize_sampled(sampled);
  o.sampled = SampledOutcome{estimate, summarize_sampled_sequence(sampled, estimate)};
  o.stats = sampled_rows(sampled, o.sampled->estimate, o.sampled->sequence);
}

/// Appends the run's host figures (scope frame/host): no simulated figure depends on them.
void collect_host_stats(const RunOutcome& o, std::vector<StatRecord>& rows) {
  HostRunStats host;
  host.load_wall_seconds.set(o.load_seconds);
  host.simulation_wall_seconds.set(o.wall_seconds);
  host.timing_wall_seconds.set(o.timing_seconds);
  host.simulation_cpu_seconds.set(o.cpu_seconds);
  host.timing_cpu_seconds.set(o.timing_cpu_seconds);
  host.timing_wait_seconds.set(o.timing_wait_seconds);
  host.image_cpu_seconds.set(o.image_cpu_seconds);
  host.tile_render_wall_seconds.set(o.frame.host_tile_seconds);
  host.simulation_threads.set(static_cast<double>(o.threads));
  // Host timings of runs with and without huge pages, on hosts that take freed memory back or not, differ.
  const HostSpeedFacts facts = host_speed_facts();
  host.allocator_huge_pages.set(facts.allocator_huge_pages ? 1.0 : 0.0);
  host.host_free_page_reporting.set(facts.host_free_page_reporting ? 1.0 : 0.0);
  append_host_rows(host, rows);
}

/// The run as the results database stores it: identity, every parameter with its origin, the
/// frame's statistics and host figures, the tiles.
RunRecord run_record(const RunRequest& req, const RunInputs& in, const RunOutcome& o, const std::string& started) {
  RunRecord rec;
  rec.started_at = started;
  rec.finished_at = utc_now_iso8601();
  rec.tool_version = kToolVersion;
  rec.host = host_name();
  rec.command_line = req.command_line;
  rec.config_name = req.config.params.config_name;
  rec.config_hash = req.config.hash;
  rec.trace_path = req.trace_path;
  rec.trace_hash = trace_hash(in.frames);
  rec.scene = in.scene->source;
  rec.technique = o.technique;
  rec.status = "ok";
  const auto& table = hw_params().table();
  for (std::size_t i = 0; i < table.decls().size(); ++i) {
    rec.params.push_back({table.decls()[i].key, format_param_value(req.config.params.values[i]), req.config.params.origins[i].text});
  }
  // A sampled run's label says so: its figures are estimates, grouped apart from full runs.
  rec.params.push_back(config_label_param(req.sample_frames > 0 ? req.config.label + " run.sample=" + std::to_string(req.sample_frames)
                                                                : req.config.label));
  for (auto& p : trace_run_params(in.trace(), req.trace_path)) rec.params.push_back(std::move(p));
  if (req.sample_frames > 0) {
    rec.params.push_back({"run.sample", std::to_string(req.sample_frames), "command line"});
    rec.params.push_back({"run.sample_warmup", std::to_string(req.sample_warmup_frames), "command line"});
    // No frame/frame rows (nothing simulated the whole sequence): the trace's size and lights, as
    // v_param derives them from those rows for other runs.
    const TraceFrame& f = in.trace().frame;
    rec.params.push_back({"trace.width", std::to_string(f.width), "trace"});
    rec.params.push_back({"trace.height", std::to_string(f.height), "trace"});
    rec.params.push_back({"trace.samples", std::to_string(f.samples), "trace"});
    rec.params.push_back({"trace.lights", std::to_string(in.trace().lights.size()), "trace"});
    rec.params.push_back({"trace.resolution", std::to_string(f.width) + "x" + std::to_string(f.height), "trace"});
  }
  rec.stats = o.stats;
  collect_host_stats(o, rec.stats);
  rec.tiles = o.timing.tiles;
  return rec;
}

}  // namespace

RunOutcome run_one(const RunRequest& req) {
  RunOutcome outcome;
  const auto t_load = std::chrono::steady_clock::now();
  const std::string started = utc_now_iso8601();
  check_results_db_target(req.db_path);  // a bad --db is reported now, not after the simulation
  // Declared before the image writer, so that the folder is removed (on failure) after the writer
  // has finished; the database likewise.
  RunImagesFolder images_folder(req.images_dir);
  const RunInputs in = load_run_inputs(req);
  outcome.load_seconds = seconds_since(t_load);
  outcome.threads = req.threads;
  RunDatabase db(req.db_path);
  if (req.sample_frames > 0) {
    if (in.frames.size() < 2) throw InputError(req.trace_path, "--sample needs a sequence (a trace of more than one frame); this trace holds one");
    if (!req.images_dir.empty()) throw InputError("--images", "a sampled run (--sample) simulates no whole sequence to draw; run without --sample for images");
    simulate_sampled(req, in, outcome);
    outcome.technique = in.trace().technique.empty() ? "custom" : in.trace().technique;
    outcome.scene = in.scene->source;
    outcome.run_id = db.write(run_record(req, in, outcome, started), nullptr);
    images_folder.keep();
    return outcome;
  }
  FrameImageJob images(req);
  if (req.threads > 1) {
    simulate_pipelined(req, in, outcome, images, db);
  } else {
    simulate_serially(req, in, outcome);
  }
  // Timed: nothing reads the frame's commands again (RunOutcome). Their tiles' work is tens of
  // thousands of blocks (freeing them took 2.5-4 ms of the serial end at 1080p): with more than
  // one thread they are freed on another thread while the results are written.
  std::future<void> released;
  if (req.threads > 1) {
    released = std::async(std::launch::async, [commands = std::move(outcome.frame.work.commands)]() mutable { commands = {}; });
  }
  outcome.frame.work.commands = {};  // (freed here at one thread; moved from, at more)
  book_timing(req.config.hw, outcome.frame, outcome.timing, outcome.energy);
  outcome.sequence.energy = sequence_frame_energy(req.config.hw, outcome.sequence.totals, outcome.timing);
  outcome.stats = run_rows(outcome.frame, outcome.timing, outcome.energy, outcome.sequence);
  outcome.technique = in.trace().technique.empty() ? "custom" : in.trace().technique;
  outcome.scene = in.scene->source;
  if (!req.images_dir.empty()) {
    outcome.images_written = images.finish(outcome.frame, outcome.timing);
    outcome.image_cpu_seconds = images.cpu_seconds();
  }
  outcome.run_id = db.write(run_record(req, in, outcome, started), req.summary_figures ? &outcome.derived : nullptr);
  if (released.valid()) released.get();
  images_folder.keep();
  return outcome;
}

namespace {
/// A sampled run's summary: its estimate of the whole sequence and how it was sampled.
void print_sampled_summary(const RunOutcome& o, std::ostream& out) {
  const SamplingSummaryStats& e = o.sampled->estimate;
  const SequenceSummaryStats& q = o.sampled->sequence;
  out << "run " << o.run_id << ": " << o.technique << " on " << o.scene << ", " << e.frames.value()
      << " frames sampled: " << e.groups.value() << " groups, " << e.frames_simulated.value() << " frames simulated in "
      << e.windows.value() << (e.windows.value() == 1 ? " window, " : " windows, ") << stat_text(o.wall_seconds) << " s\n";
  out << "  estimated sequence: " << stat_text(e.total_cycles.value()) << " cycles (+-" << stat_text(e.total_cycles_error_pct.value())
      << " %), " << stat_text(e.total_ms.value()) << " ms; DRAM " << stat_text(e.dram_bytes.value() / 1e6) << " MB at the devices (+-"
      << stat_text(e.dram_bytes_error_pct.value()) << " %); energy " << stat_text(e.energy_mj.value()) << " mJ (+-"
      << stat_text(e.energy_error_pct.value()) << " %)\n";
  out << "  estimated frames: steady " << stat_text(q.steady_interval_ms.value()) << " ms per frame (p95 "
      << stat_text(q.p95_interval_ms.value()) << ", " << stat_text(q.steady_fps.value()) << " fps), DRAM "
      << stat_text(q.steady_dram_mb_per_frame.value()) << " MB (at the devices) and " << stat_text(q.steady_energy_per_frame_mj.value())
      << " mJ per steady frame\n";
  out << "  (+-: two standard errors had each group's frame been drawn at random from it, its spread predicted from the signatures; "
         "rows sampling/summary and sampling/frame<k>)\n";
}
}  // namespace

void print_run_summary(const RunOutcome& o, std::ostream& out) {
  if (o.sampled) {
    print_sampled_summary(o, out);
    return;
  }
  const FrameResult& f = o.frame;
  const GeometryStats& geometry = f.totals.render.geometry;
  const IspStats& isp = f.totals.render.isp;
  const TspStats& tsp = f.totals.render.tsp;
  const std::uint64_t shaded = tsp.shader_invocations.value();
  out << "run " << o.run_id << ": " << o.technique << " on " << o.scene << ", " << f.images.width << "x"
      << f.images.height << ", " << f.passes.size() << " pass(es), simulated in " << stat_text(o.wall_seconds) << " s on " << o.threads
      << (o.threads == 1 ? " thread\n" : " threads\n");
  out << "  primitives in/out:  " << geometry.primitives_in.value() << " / " << geometry.primitives_out.value()
      << "  (clipped " << geometry.primitives_clipped.value() << ", partial renders "
      << f.totals.render.tiler.partial_renders.value() << ")\n";
  out << "  samples rasterised: " << isp.samples_rasterised.value() << "  removed by HSR " << isp.hsr_removed_samples.value()
      << "  depth-test failed " << isp.depth_test_failed_samples.value() << "  tag flushes " << isp.tag_flushes.value() << "\n";
  auto figure = [](const std::optional<double>& v) { return v ? stat_text(*v) : std::string("-"); };
  out << "  shaded: " << shaded << " invocations (" << figure(o.derived.shaded_fragments_per_pixel)
      << " fragments per pixel, overshading " << figure(o.derived.overshading) << "), " << tsp.shaded_quads.value()
      << " quads, " << tsp.helper_lanes.value() << " helper lanes, " << tsp.light_evaluations.value()
      << " light evaluations (" << figure(o.derived.lights_per_pixel) << " per pixel)\n";
  out << "  frame: " << stat_text(o.timing.frame_cycles) << " cycles, " << stat_text(o.timing.frame_time_ps * 1e-9)
      << " ms, energy " << stat_text(o.energy.total_pj * 1e-9)
      << " mJ (timing model " << stat_text(o.timing_seconds) << " s)\n";
  if (o.timing.frames.size() > 1) {
    const SequenceSummaryStats seq = summarize_sequence(o.timing, o.energy.total_pj, o.sequence);
    out << "  sequence: " << o.timing.frames.size() << " frames (the figures above and below are their sums), steady "
        << stat_text(seq.steady_interval_ms.value()) << " ms per frame (p95 " << stat_text(seq.p95_interval_ms.value())
        << ", " << stat_text(seq.steady_fps.value()) << " fps), DRAM " << stat_text(seq.steady_dram_mb_per_frame.value())
        << " MB per steady frame, energy " << stat_text(seq.steady_energy_per_frame_mj.value()) << " mJ per steady frame\n";
  }
  // DRAM per class: what reached the devices (the timing model's memory system, after the caches),
  // beside what the units requested (the functional count at the chip boundary).
  const DramTraffic& device = o.timing.dram;
  out << "  DRAM MB per class          read   written   (requested by the units, before the caches: read, written)\n";
  for (std::size_t c = 0; c < kDramClassCount; ++c) {
    if (f.dram.read_bytes[c] == 0 && f.dram.write_bytes[c] == 0 && device.read_bytes[c] == 0 &&
        device.write_bytes[c] == 0) {
      continue;
    }
    out << "    " << std::left << std::setw(18) << to_string(static_cast<DramClass>(c)) << std::right << std::setw(10)
        << stat_text(device.read_bytes[c] / 1e6) << std::setw(10) << stat_text(device.write_bytes[c] / 1e6) << "   ("
        << stat_text(f.dram.read_bytes[c] / 1e6) << ", " << stat_text(f.dram.write_bytes[c] / 1e6) << ")\n";
  }
  out << "    " << std::left << std::setw(18) << "total" << std::right << std::setw(10) << stat_text(device.total_read() / 1e6)
      << std::setw(10) << stat_text(device.total_written() / 1e6) << "   (" << stat_text(f.dram.total_read() / 1e6) << ", "
      << stat_text(f.dram.total_written() / 1e6) << ")\n";
  // The device's side (after the caches) against its peak, which dram.clock_mhz sets.
  const DramStats& dram = o.timing.memory_units.dram.stats;
  out << "  DRAM bandwidth: " << stat_text(dram.achieved_bandwidth_gbps.value()) << " GB/s achieved of "
      << stat_text(dram.peak_bandwidth_gbps.value()) << " GB/s peak\n";
  if (!o.images_written.empty()) {
    out << "  images: " << o.images_written.size() << " files in "
        << std::filesystem::path(o.images_written.front()).parent_path().string() << "\n";
  }
}

}  // namespace tbdr
