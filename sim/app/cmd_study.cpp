// `tbdrsim study`: the README's main job. Every technique on the built-in atrium at 1920x1080
// with 256 and 1024 lights on one configuration, in parallel worker processes (the worker pool),
// into one results database; prints the comparison table and the measured method table
// (Billeter's columns), and writes images, heat maps and plots into a folder.
#include <unistd.h>

#include <algorithm>
#include <limits>
#include <cctype>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <future>
#include <iomanip>
#include <iostream>
#include <map>
#include <numeric>
#include <optional>
#include <set>
#include <sstream>
#include <tuple>
#include <variant>

#include <boost/program_options.hpp>

#include "analysis/report.hpp"
#include "analysis/results_db.hpp"
#include "analysis/sql.hpp"
#include "app/cli.hpp"
#include "app/commands.hpp"
#include "app/image_output.hpp"
#include "app/run_driver.hpp"
#include "app/run_stats.hpp"
#include "app/worker_pool.hpp"
#include "kernel/errors.hpp"
#include "models/hardware_checks.hpp"
#include "scene/scene_library.hpp"
#include "tbdrsim_version.hpp"
#include "techniques/technique.hpp"
#include "trace/trace.hpp"

namespace tbdr {

namespace po = boost::program_options;
namespace fs = std::filesystem;

namespace {

/// What the study runs, from its command line.
struct StudyPlan {
  std::string dir;
  std::string db_path;
  std::string scene;
  std::string resolution;
  std::string image_mode;  ///< none | largest | all
  int jobs = 2;
  unsigned threads = 1;  ///< threads inside each run (--threads; default: cores / jobs)
  std::vector<int> light_counts;
  std::vector<std::string> techniques;
  int max_lights = 0;
  /// The GPU modes compared (--modes), empty: the configuration's own mode only.
  std::vector<std::string> modes;
  /// One configuration per mode (the given one with gpu.mode set), or the given one.
  std::vector<ResolvedConfig> configs;
  std::string config_label;  ///< the configuration's label (preset and what is set on top of it)
  /// Technique options given with --option TECHNIQUE:KEY=VALUE: technique -> "KEY=VALUE" list.
  std::map<std::string, std::vector<std::string>> options;
  /// Frames of each trace (--frames; 1: one cold frame), the camera moving along camera_path and
  /// the lights orbiting (docs/sequences.md).
  int frames = 1;
  std::string camera_path = "orbit";
};

/// One point of the study: a technique at a light count, on one of the configurations (modes).
struct StudyPoint {
  std::string technique;
  int lights = 0;
  std::size_t config = 0;  ///< index into StudyPlan::configs
  std::string mode;        ///< gpu.mode of that configuration
  std::string trace_path;
  std::string images_dir;
  /// Draws of the scene's geometry in the trace: each sends (the part inside its cull box of) the
  /// scene through the geometry unit, the tiler and the ISP, the replay's dominant unit of work.
  std::size_t scene_draws = 0;
  /// Why the configuration refuses the trace, before any work (check_trace_on_hardware: PLS on an
  /// immediate-mode GPU or past its limit, a sample count the sub-pixel grid cannot place; each
  /// documented in docs/hardware-model.md): such a point is recorded as refused, not run. Empty:
  /// the point runs.
  std::string refusal;
};

/// The `error` text of a refused point's row ("refused: " and the refusal): `report` counts the
/// runs left out by it.
constexpr const char* kRefusedPrefix = "refused: ";

/// Writes the row of a point that did not run (status failed, its error, the configuration's
/// parameters, no statistics), so that the database and `tbdrsim report` count it with its reason.
void record_failed_point(const std::string& db_path, const ResolvedConfig& config, const StudyPoint& p,
                         const std::string& error, const std::string& command_line) {
  RunRecord rec;
  rec.started_at = rec.finished_at = utc_now_iso8601();
  rec.tool_version = kToolVersion;
  rec.host = host_name();
  rec.command_line = command_line;
  rec.config_name = config.params.config_name;
  rec.config_hash = config.hash;
  rec.trace_path = p.trace_path;
  rec.technique = p.technique;
  try {
    const Trace trace = read_trace(p.trace_path);
    rec.trace_hash = trace_hash(trace);
    rec.scene = trace.scene.kind == SceneKind::Atrium ? "atrium:" + std::to_string(trace.scene.detail) : trace.scene.path;
    for (auto& tp : trace_run_params(trace, p.trace_path)) rec.params.push_back(std::move(tp));
  } catch (const std::exception&) {
    // (an unreadable trace: the row keeps its path and the error says why)
  }
  rec.status = "failed";
  rec.error = error;
  const auto& table = hw_params().table();
  for (std::size_t i = 0; i < table.decls().size(); ++i) {
    rec.params.push_back({table.decls()[i].key, format_param_value(config.params.values[i]), config.params.origins[i].text});
  }
  ResultsDb db(db_path);
  db.write_run(rec);
}

std::string fmt(double v, int decimals) {
  std::ostringstream o;
  o << std::fixed << std::setprecision(decimals) << v;
  return o.str();
}

/// Share of pixels whose color differs from the reference `x` (decoded once for every
/// technique) by more than 1/255 in a channel (1 when the sizes differ or the image is missing).
double differing_pixels(const ImageRGB8& x, const std::string& b) {
  try {
    const ImageRGB8 y = read_png(b);
    if (x.rgb.size() != y.rgb.size() || x.rgb.empty()) return 1.0;
    std::size_t n = 0;
    for (std::size_t p = 0; p < x.rgb.size(); p += 3) {
      bool d = false;
      for (std::size_t c = 0; c < 3; ++c) d = d || std::abs(int(x.rgb[p + c]) - int(y.rgb[p + c])) > 1;
      n += d ? 1 : 0;
    }
    return static_cast<double>(n) / static_cast<double>(x.rgb.size() / 3);
  } catch (const InputError&) {
    return 1.0;
  }
}

void draw_progress(std::ostream& out, std::size_t done, std::size_t total, double seconds, bool tty) {
  const double rate = seconds > 0 ? static_cast<double>(done) / seconds : 0;
  const double eta = rate > 0 ? static_cast<double>(total - done) / rate : 0;
  if (tty) {
    const int width = 30;
    const int filled = total ? static_cast<int>(width * done / total) : width;
    out << "\r  [" << std::string(static_cast<std::size_t>(filled), '#') << std::string(static_cast<std::size_t>(width - filled), '.')
        << "] " << done << "/" << total << "  " << fmt(rate * 60, 1) << " runs/min  ETA " << fmt(eta, 0) << " s   " << std::flush;
  } else {
    out << "  progress: " << done << "/" << total << " runs, " << fmt(rate * 60, 1) << " runs/min, ETA " << fmt(eta, 0) << " s"
        << std::endl;
  }
}

/// The most lights a study point may have: the trace generator's limit (`trace --lights`).
constexpr int kMaxStudyLights = 1000000;

StudyPlan plan_from_options(const po::variables_map& vm) {
  StudyPlan plan;
  plan.dir = vm["out"].as<std::string>();
  plan.jobs = vm["jobs"].as<int>();
  if (plan.jobs < 1 || plan.jobs > 64) throw InputError("--jobs " + std::to_string(plan.jobs), "expected 1..64 worker processes");
  plan.threads = threads_option(vm, threads_per_worker(plan.jobs));
  plan.light_counts = vm.count("lights") ? vm["lights"].as<std::vector<int>>() : std::vector<int>{256, 1024};
  for (const int n : plan.light_counts) {
    // A study compares how techniques light: a frame without lights (`trace --lights 0`, the unlit
    // frame validate's probes use) has nothing to compare, and the light-culling techniques refuse it.
    if (n < 1 || n > kMaxStudyLights) {
      throw InputError("--lights " + std::to_string(n), "a study compares lighting: expected light counts in [1, " +
                                                            std::to_string(kMaxStudyLights) + "]");
    }
  }
  plan.techniques = vm.count("technique") ? vm["technique"].as<std::vector<std::string>>() : technique_names();
  for (const auto& n : plan.techniques) find_technique(n);  // InputError for an unknown name
  plan.image_mode = vm["images"].as<std::string>();
  if (plan.image_mode != "none" && plan.image_mode != "largest" && plan.image_mode != "all") {
    throw InputError("--images " + plan.image_mode, "expected none, largest or all");
  }
  std::vector<std::string> files, sets;
  if (vm.count("config")) {
    // Names and paths found as every command finds them (cli.hpp: find_data_file).
    for (const auto& f : vm["config"].as<std::vector<std::string>>()) files.push_back(find_data_file(f, DataFolder::Configs));
  }
  if (vm.count("set")) sets = vm["set"].as<std::vector<std::string>>();
  if (vm.count("modes")) plan.modes = vm["modes"].as<std::vector<std::string>>();
  if (plan.modes.empty()) {
    plan.configs.push_back(resolve_config(files, sets));
  } else {
    for (const auto& m : plan.modes) {
      std::vector<std::string> with_mode = sets;
      with_mode.push_back("gpu.mode=" + m);  // InputError naming it when it is not a mode
      plan.configs.push_back(resolve_config(files, with_mode));
    }
  }
  // What the modes share, labelled as the runs are (ResolvedConfig::label).
  plan.config_label = plan.modes.empty() ? plan.configs.front().label : resolve_config(files, sets).label;
  plan.scene = vm["scene"].as<std::string>();
  plan.resolution = vm["resolution"].as<std::string>();
  if (vm.count("option")) {
    for (const auto& o : vm["option"].as<std::vector<std::string>>()) {
      const auto colon = o.find(':');
      const auto eq = o.find('=', colon == std::string::npos ? 0 : colon);
      if (colon == std::string::npos || colon == 0 || eq == std::string::npos || eq == colon + 1) {
        throw InputError("--option " + o, "expected TECHNIQUE:KEY=VALUE, e.g. forward_light_stack:pls_bytes=32");
      }
      const std::string technique = o.substr(0, colon);
      find_technique(technique);  // InputError for an unknown name
      if (std::find(plan.techniques.begin(), plan.techniques.end(), technique) == plan.techniques.end()) {
        throw InputError("--option " + o, "technique '" + technique + "' is not in this study (--technique)");
      }
      plan.options[technique].push_back(o.substr(colon + 1));
    }
  }
  plan.frames = vm["frames"].as<int>();
  if (plan.frames < 1 || plan.frames > kMaxSequenceFrames) {
    throw InputError("--frames " + std::to_string(plan.frames), "expected 1.." + std::to_string(kMaxSequenceFrames) + " frames");
  }
  plan.camera_path = vm["camera-path"].as<std::string>();
  // A path's name, or a camera path file (the generators read it: an error names its line).
  if (!camera_path_named(plan.camera_path) && !fs::is_regular_file(plan.camera_path)) parse_camera_path(plan.camera_path);
  plan.max_lights = *std::max_element(plan.light_counts.begin(), plan.light_counts.end());
  plan.db_path = (fs::path(plan.dir) / "study.db").string();
  return plan;
}

/// The gpu.mode value of a configuration.
std::string mode_of(const ResolvedConfig& c) {
  const auto& table = hw_params().table();
  return format_param_value(c.params.values[static_cast<std::size_t>(table.find("gpu.mode"))]);
}

/// Generates every point's trace (a fraction of a second each, on the worker pool: one child
/// process per trace, plan.jobs at once), one point per configuration (mode) replaying it.
std::vector<StudyPoint> generate_traces(const StudyPlan& plan) {
  std::vector<StudyPoint> points;
  std::vector<StudyPoint> traces;                  // one point per trace, in the study's order
  std::vector<std::vector<std::string>> generate;  // its `tbdrsim trace` arguments
  std::vector<std::string> trace_args = {"--scene", plan.scene, "--resolution", plan.resolution};
  if (plan.frames > 1) {
    trace_args.insert(trace_args.end(), {"--frames", std::to_string(plan.frames), "--camera-path", plan.camera_path,
                                         "--light-motion", "orbit"});
  }
  for (int n : plan.light_counts) {
    for (const auto& t : plan.techniques) {
      StudyPoint p;
      p.technique = t;
      p.lights = n;
      // The trace's name carries its options, so that studies with other options into the same
      // folder keep each trace (and the runs that name it) apart.
      std::string stem = t + "_" + std::to_string(n);
      if (plan.frames > 1) {  // a sequence's trace apart: its path (a file's stem) and frames
        std::string path = camera_path_named(plan.camera_path) ? plan.camera_path : fs::path(plan.camera_path).stem().string();
        for (char& c : path) {
          if (!std::isalnum(static_cast<unsigned char>(c))) c = '-';
        }
        stem += "_" + path + std::to_string(plan.frames);
      }
      const auto given = plan.options.find(t);
      if (given != plan.options.end()) {
        for (const auto& kv : given->second) {
          std::string part = kv;
          for (char& c : part) {
            if (!std::isalnum(static_cast<unsigned char>(c)) && c != '_' && c != '.') c = '-';
          }
          stem += "_" + part;
        }
      }
      p.trace_path = (fs::path(plan.dir) / "traces" / (stem + ".trace")).string();
      if (plan.image_mode == "all" || (plan.image_mode == "largest" && n == plan.max_lights)) {
        p.images_dir = (fs::path(plan.dir) / "images" / (t + "_" + std::to_string(n))).string();
      }
      std::vector<std::string> a = {"trace", "--technique", t, "--lights", std::to_string(n), "--out", p.trace_path};
      a.insert(a.end(), trace_args.begin(), trace_args.end());
      // forward_multipass runs in its textbook form, one additive pass per light, each bounded by
      // its light's scissor and cull box (its light_bounds option; docs/techniques.md).
      if (given != plan.options.end()) {
        for (const auto& kv : given->second) a.insert(a.end(), {"--option", kv});  // the last one given wins
      }
      traces.push_back(p);
      generate.push_back(std::move(a));
    }
  }
  // The generators run in forked children; a failure's message (what the generator wrote to its
  // stderr) names the technique.
  std::vector<bool> existed;
  std::vector<WorkerJob> jobs;
  for (std::size_t i = 0; i < traces.size(); ++i) {
    existed.push_back(fs::exists(traces[i].trace_path));
    WorkerJob job;
    job.function = [&generate, i] {
      std::ostringstream sink;
      return cli_main(generate[i], sink, std::cerr);
    };
    jobs.push_back(std::move(job));
  }
  std::string failed;
  for (const WorkerEnd& end : run_worker_jobs(plan.jobs, std::move(jobs))) {
    if (!end.ok() && failed.empty()) failed = "generating " + traces[end.id].technique + ": " + end.stderr_text;
  }
  if (!failed.empty()) {
    for (std::size_t i = 0; i < traces.size(); ++i) {
      std::error_code ec;
      if (!existed[i]) fs::remove(traces[i].trace_path, ec);
    }
    throw InputError("study", failed);
  }
  for (StudyPoint& p : traces) {
    const std::vector<Trace> frames = read_trace_frames(p.trace_path);
    const Trace& trace = frames.front();
    for (const Trace& frame : frames) {
      for (const TraceCommand& c : frame.commands) {
        if (const auto* pass = std::get_if<PassDesc>(&c)) {
          for (const DrawCmd& d : pass->draws) p.scene_draws += d.geometry == GeometryKind::Scene ? 1 : 0;
        }
      }
    }
    for (std::size_t c = 0; c < plan.configs.size(); ++c) {
      StudyPoint q = p;
      q.config = c;
      q.mode = mode_of(plan.configs[c]);
      if (c > 0) q.images_dir.clear();  // images of the first configuration only
      try {
        check_trace_on_hardware(trace, plan.configs[c].hw, p.trace_path);  // what `run` would refuse first
      } catch (const InputError& e) {
        q.refusal = e.what();
        q.images_dir.clear();
      }
      points.push_back(q);
    }
  }
  return points;
}

/// Runs every point on the worker pool, one simulation per child process, each run written at once
/// (one transaction); a failed point's message goes to `err` and its row (status failed, the error)
/// to the database. A refused point is not run: its row is written here. Returns the number of
/// failed points (refused ones not counted).
int run_points(const StudyPlan& plan, const std::vector<StudyPoint>& points, std::ostream& out, std::ostream& err) {
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (points[i].refusal.empty()) continue;
    record_failed_point(plan.db_path, plan.configs[points[i].config], points[i], kRefusedPrefix + points[i].refusal,
                        invocation_command_line() + " [point " + std::to_string(i) + "]");
  }
  const auto t0 = std::chrono::steady_clock::now();
  auto seconds = [&] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(); };
  const bool tty = isatty(STDOUT_FILENO) != 0 && &out == &std::cout;
  std::size_t next = 0, done = 0, drawn = 0;
  int failures = 0;
  // Redrawn five times a second on a terminal; in a log, a line a second at most, when it moved.
  const auto interval = std::chrono::milliseconds(tty ? 200 : 1000);
  auto last_draw = std::chrono::steady_clock::now();
  draw_progress(out, 0, points.size(), seconds(), tty);
  // Longest first, so that the last run to end is a short one: most scene draws first
  // (forward_multipass draws the scene once per light, about a third of the study's CPU time at
  // 1024 lights), then most lights. Ties keep the points' order.
  std::vector<std::size_t> order;
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (points[i].refusal.empty()) order.push_back(i);
  }
  done = points.size() - order.size();  // the refused points are done: recorded above
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return std::tie(points[b].scene_draws, points[b].lights) < std::tie(points[a].scene_draws, points[a].lights);
  });
  WorkerPoolHooks hooks;
  hooks.next = [&]() -> std::optional<WorkerJob> {
    if (next == order.size()) return std::nullopt;
    const std::size_t i = order[next++];
    WorkerJob job;
    job.id = i;
    job.function = [&plan, &points, i] {
      try {
        RunRequest req;
        req.config = plan.configs[points[i].config];
        req.trace_path = points[i].trace_path;
        req.db_path = plan.db_path;
        req.images_dir = points[i].images_dir;
        req.threads = plan.threads;
        req.command_line = invocation_command_line() + " [point " + std::to_string(i) + "]";
        run_one(req);
        return 0;
      } catch (const std::exception& e) {
        std::cerr << "study: " << points[i].technique << " with " << points[i].lights << " lights on " << points[i].mode
                  << " failed: " << e.what() << "\n";
        try {
          record_failed_point(plan.db_path, plan.configs[points[i].config], points[i], e.what(),
                              invocation_command_line() + " [point " + std::to_string(i) + "]");
        } catch (const std::exception& w) {
          std::cerr << "study: its row could not be written: " << w.what() << "\n";
        }
        return 1;
      }
    };
    return job;
  };
  hooks.ended = [&](const WorkerEnd& end) {
    err << end.stderr_text;
    if (!end.ok()) ++failures;
    ++done;
  };
  hooks.tick = [&] {
    if (std::chrono::steady_clock::now() - last_draw < interval || (!tty && done == drawn)) return;
    draw_progress(out, done, points.size(), seconds(), tty);
    last_draw = std::chrono::steady_clock::now();
    drawn = done;
  };
  run_worker_pool({plan.jobs, false}, hooks);
  draw_progress(out, points.size(), points.size(), seconds(), tty);
  if (tty) out << "\n";
  return failures;
}

/// The figures of the study's runs, read back from its database: the derived figures from
/// v_run_summary (their one definition, analysis/views.sql), raw statistics with bound queries.
class StudyResults {
 public:
  StudyResults(const ResultsDb& db, const StudyPlan& plan)
      : db_(db),
        plan_(plan),
        run_(db.sql(), "SELECT max(id) FROM runs WHERE status = 'ok' AND trace_path = ? AND config_hash = ?"),
        stat_(db.sql(), "SELECT value FROM stats WHERE run_id = ? AND scope = ? AND name = ?") {}

  /// The latest finished run of a point, if any.
  std::optional<std::int64_t> run_of(const StudyPoint& p) {
    run_.bind(1, p.trace_path).bind(2, plan_.configs[p.config].hash);
    std::optional<std::int64_t> id;
    if (run_.step() && !run_.is_null(0)) id = run_.int64(0);
    run_.reset();
    return id;
  }

  /// One statistic of a run. A unit with no work in a frame records no row (frame/compute of a
  /// technique without a compute pass): an absent statistic is zero.
  double stat(std::int64_t run, const std::string& scope, const std::string& name) {
    stat_.bind(1, run).bind(2, scope).bind(3, name);
    const double v = stat_.step() ? stat_.real(0) : 0.0;
    stat_.reset();
    return v;
  }

  /// A statistic named by its declaration (kernel/stats.hpp stat_name).
  template <StatSet S, class M>
  double stat(std::int64_t run, const std::string& scope, M S::*member) {
    return stat(run, scope, std::string(stat_name(member)));
  }

  /// Bytes the units requested to read and write in a scope ("frame/dram", "frame/dram.color").
  double requested_bytes(std::int64_t run, const std::string& scope) {
    return stat(run, scope, &TrafficStats::read_bytes) + stat(run, scope, &TrafficStats::write_bytes);
  }

  /// The derived figures of a run (views.sql).
  DerivedFigures derived(std::int64_t run) { return read_derived_figures(db_, run); }

 private:
  const ResultsDb& db_;
  const StudyPlan& plan_;
  SqlStatement run_, stat_;
};

std::string fig(const std::optional<double>& v, int decimals) { return v ? fmt(*v, decimals) : std::string("-"); }

/// With --frames above 1: each point's cold first frame beside its steady state (sequence/frame0,
/// sequence/summary), in the comparison table's order of points.
void print_sequence_table(const StudyPlan& plan, const std::vector<StudyPoint>& points, StudyResults& results,
                          std::ostream& out) {
  if (plan.frames <= 1) return;
  const bool modes = plan.configs.size() > 1;
  out << "\nSequences (" << plan.frames << " frames, camera " << plan.camera_path << ", lights orbiting, "
      << plan.config_label << "): the comparison above sums the frames; here the cold first frame beside the steady "
      << "frames (after the first, before the last; docs/sequences.md)\n";
  out << std::left << std::setw(30) << "technique" << std::right << std::setw(7) << "lights";
  if (modes) out << std::setw(6) << "mode";
  out << std::setw(11) << "cold ms" << std::setw(11) << "steady ms" << std::setw(9) << "p95 ms" << std::setw(9) << "fps"
      << std::setw(12) << "DRAM MB/f" << std::setw(10) << "mJ/f" << std::setw(11) << "cold mJ" << "\n";
  const std::string summary = SequenceSummaryStats::kScope;
  const std::string first = SequenceFrameStats::kScopePrefix + std::string("0");
  for (const StudyPoint& p : points) {
    const std::optional<std::int64_t> run = results.run_of(p);
    if (!run) continue;
    out << std::left << std::setw(30) << p.technique << std::right << std::setw(7) << p.lights;
    if (modes) out << std::setw(6) << p.mode;
    out << std::setw(11) << fmt(results.stat(*run, first, &SequenceFrameStats::interval_ms), 3)
        << std::setw(11) << fmt(results.stat(*run, summary, &SequenceSummaryStats::steady_interval_ms), 3)
        << std::setw(9) << fmt(results.stat(*run, summary, &SequenceSummaryStats::p95_interval_ms), 3)
        << std::setw(9) << fmt(results.stat(*run, summary, &SequenceSummaryStats::steady_fps), 1)
        << std::setw(12) << fmt(results.stat(*run, summary, &SequenceSummaryStats::steady_dram_mb_per_frame), 2)
        << std::setw(10) << fmt(results.stat(*run, summary, &SequenceSummaryStats::steady_energy_per_frame_mj), 3)
        << std::setw(11) << fmt(results.stat(*run, first, &SequenceFrameStats::energy_mj), 3) << "\n";
  }
}

/// The comparison table: the latest run of each point.
void print_comparison(const StudyPlan& plan, const std::vector<StudyPoint>& points, StudyResults& results,
                      std::ostream& out) {
  const bool modes = plan.configs.size() > 1;
  // The technique options the study set (--option; the techniques' defaults otherwise).
  std::string options;
  for (const auto& t : plan.techniques) {
    std::vector<std::string> kv;
    if (const auto it = plan.options.find(t); it != plan.options.end()) kv.insert(kv.end(), it->second.begin(), it->second.end());
    if (kv.empty()) continue;
    options += (options.empty() ? "" : "; ") + t;
    for (const auto& o : kv) options += " " + o;
  }
  out << "\nComparison (" << plan.config_label << "): frame time, DRAM traffic at the devices (after the caches), energy"
      << " (technique options: " << (options.empty() ? "the techniques' defaults" : options) << "); per light count"
      << (modes ? " and mode" : "") << ", least DRAM traffic first\n";
  out << std::left << std::setw(30) << "technique" << std::right << std::setw(7) << "lights";
  if (modes) out << std::setw(6) << "mode";
  out << std::setw(11) << "frame ms" << std::setw(11) << "DRAM MB" << std::setw(6) << "rank" << std::setw(10) << "req MB"
      << std::setw(11) << "energy mJ" << std::setw(10) << "frags/px" << std::setw(12) << "overshading" << std::setw(11)
      << "lights/px" << std::setw(13) << "stack ovf %" << "\n";
  // The rows of each light count (and mode), ordered and ranked by the bytes that reached DRAM.
  struct Row {
    const StudyPoint* point;
    std::optional<std::int64_t> run;
    DerivedFigures d;
    double overflow = 0;
    int rank = 0;
  };
  std::vector<Row> rows;
  std::vector<std::string> overflowed;
  for (const auto& p : points) {
    Row row{&p, results.run_of(p), {}, 0.0, 0};
    if (row.run) {
      row.d = results.derived(*row.run);
      // A PLS light stack that overflows falls back to every light: its frame time is then the
      // overflow's cost, not the technique's; the share of lit fragments that overflowed says so.
      const double lit = std::max(1.0, results.stat(*row.run, "frame/tsp", &TspStats::lit_surface_invocations));
      row.overflow = 100.0 * results.stat(*row.run, "frame/tsp", &TspStats::light_stack_overflow_fragments) / lit;
      if (row.overflow > 0) {
        overflowed.push_back(p.technique + " at " + std::to_string(p.lights) + " lights" + (modes ? " on " + p.mode : "") +
                             ": " + fmt(row.overflow, 1) + " %");
      }
    }
    rows.push_back(std::move(row));
  }
  // Failed runs and runs without a device figure last, in the plan's order.
  const auto dram_key = [](const Row& r) {
    return r.d.dram_total_mb.value_or(std::numeric_limits<double>::infinity());
  };
  std::stable_sort(rows.begin(), rows.end(), [&](const Row& a, const Row& b) {
    if (a.point->lights != b.point->lights) return a.point->lights < b.point->lights;
    if (a.point->config != b.point->config) return a.point->config < b.point->config;
    return dram_key(a) < dram_key(b);
  });
  for (auto& r : rows) {
    if (!r.run || !r.d.dram_total_mb) continue;
    r.rank = 1;
    for (const auto& o : rows) {
      if (o.point->lights == r.point->lights && o.point->config == r.point->config && o.d.dram_total_mb &&
          *o.d.dram_total_mb < *r.d.dram_total_mb) {
        ++r.rank;
      }
    }
  }
  for (const auto& r : rows) {
    const StudyPoint& p = *r.point;
    out << std::left << std::setw(30) << p.technique << std::right << std::setw(7) << p.lights;
    if (modes) out << std::setw(6) << p.mode;
    if (!r.run) {
      out << (p.refusal.empty() ? "   (failed)\n" : "   (refused: the configuration cannot run it; below)\n");
      continue;
    }
    const DerivedFigures& d = r.d;
    out << std::setw(11) << fig(d.frame_time_ms, 2) << std::setw(11) << fig(d.dram_total_mb, 1) << std::setw(6)
        << (r.rank > 0 ? std::to_string(r.rank) : std::string("-")) << std::setw(10) << fig(d.requested_total_mb, 1)
        << std::setw(11) << fig(d.energy_total_mj, 2) << std::setw(10) << fig(d.shaded_fragments_per_pixel, 2)
        << std::setw(12) << fig(d.overshading, 2) << std::setw(11) << fig(d.lights_per_pixel, 1) << std::setw(13)
        << fmt(r.overflow, 1) << "\n";
  }
  out << "  (DRAM MB: bytes read and written at the DRAM devices, after the texture, vertex and system level caches;\n"
      << "   rank: 1 = least DRAM traffic at this light count; req MB: what the units requested before the caches;\n";
  out << "   frags/px: fragment shader invocations per pixel, every pass; overshading: light evaluations spent on surfaces\n"
      << "   that are not in the final image, per covered pixel (0 = only the final surface is lit); lights/px: light\n"
      << "   evaluations per pixel; definitions: docs/queries.md)\n";
  for (const auto& o : overflowed) {
    out << "  note: " << o << " of the lit fragments overflowed the PLS light stack and evaluated every light: that "
        << "frame time measures the overflow (raise -o pls_bytes with pls.max_pls_bytes_per_pixel), not the technique\n";
  }
}

/// With several modes: technique x mode at each light count, through the report (the same
/// grouping as `tbdrsim report --by technique --by gpu.mode`), one column per mode and figure.
void print_mode_table(const StudyPlan& plan, const std::vector<StudyPoint>& points, StudyResults& results,
                      const ResultsDb& db, std::ostream& out) {
  if (plan.configs.size() < 2) return;
  for (int lights : plan.light_counts) {
    std::string ids;
    for (const auto& p : points) {
      if (p.lights != lights) continue;
      if (const auto run = results.run_of(p)) ids += (ids.empty() ? "" : ",") + std::to_string(*run);
    }
    if (ids.empty()) continue;
    ReportOptions opt;
    opt.by = {"technique", "gpu.mode"};
    opt.metrics = {metric::kFrameTimeMs, metric::kDramTotalMb, metric::kEnergyTotalMj, metric::kShadedFragmentsPerPixel};
    opt.where = "run_id IN (" + ids + ")";  // the study's own runs: integers only
    const ReportTable t = build_report(db, opt);
    out << "\nTechnique x GPU mode at " << lights << " lights (" << plan.config_label
        << "; the same trace on each mode; `tbdrsim report --db " << plan.db_path
        << " --by technique --by gpu.mode --baseline gpu.mode=" << plan.modes.front() << "` prints ratios)\n";
    const char* titles[] = {"frame ms", "DRAM MB", "energy mJ", "frags/px"};
    constexpr int kModeColumn = 16;  // the longest title ("energy mJ tbdr") and two spaces
    const int decimals[] = {2, 1, 2, 2};
    out << std::left << std::setw(30) << "technique" << std::right;
    for (std::size_t m = 0; m < opt.metrics.size(); ++m) {
      for (const auto& mode : plan.modes) out << std::setw(kModeColumn) << (std::string(titles[m]) + " " + mode);
    }
    out << "\n";
    std::map<std::string, std::map<std::string, const ReportTable::Row*>> cells;
    for (const auto& r : t.rows) cells[r.keys[0]][r.keys[1]] = &r;
    for (const auto& tech : plan.techniques) {
      out << std::left << std::setw(30) << tech << std::right;
      for (std::size_t m = 0; m < opt.metrics.size(); ++m) {
        for (const auto& mode : plan.modes) {
          const auto it = cells[tech].find(mode);
          std::string text = "failed";
          for (const auto& p : points) {
            if (p.lights == lights && p.technique == tech && p.mode == mode && !p.refusal.empty()) text = "refused";
          }
          if (it != cells[tech].end()) {
            const auto& values = it->second->values;
            text = m < values.size() && values[m].has_value() ? fmt(values[m].value(), decimals[m]) : std::string("-");
          }
          out << std::setw(kModeColumn) << text;
        }
      }
      out << "\n";
    }
  }
}

/// The method table's "overshading: yes" threshold, in light evaluations on hidden surfaces per
/// covered pixel: a hundredth of a light per pixel; the atrium's few exactly coplanar faces, whose
/// second face replaces the first at equal depth, give about 1e-5.
constexpr double kOvershadingYes = 0.01;

/// The measured method table (Billeter's columns) at the largest light count, first configuration.
void print_method_table(const StudyPlan& plan, const std::vector<StudyPoint>& points, StudyResults& results,
                        std::ostream& out) {
  out << "\nMethod table, measured at " << plan.max_lights << " lights" << (plan.configs.size() > 1 ? " on " + points.front().mode : "")
      << " (off-chip: classes with DRAM traffic besides the parameter buffer, vertices, indices, textures and light data)\n";
  out << std::left << std::setw(30) << "technique" << std::setw(56) << "off-chip buffers" << std::right << std::setw(9) << "geo pass"
      << std::setw(14) << "overshading" << std::setw(6) << "MSAA" << std::setw(10) << "blending" << "\n";
  out << "  (overshading: light evaluations spent on hidden surfaces per covered pixel (views.sql), yes above "
      << kOvershadingYes << " (exactly coplanar faces give a few samples);\n"
      << "   blending: the image with the translucent glass equals plain forward's; MSAA: the generator produces a 4x trace)\n";
  // MSAA: does the technique's generator produce a 4x trace? Probed with a one-light 64x36 trace
  // per technique on the default atrium, here: a few milliseconds each once this process has
  // built that scene (shared_scene), where a worker process per probe built it again.
  std::set<std::string> msaa_techniques;
  for (const auto& p : points) {
    if (p.lights != plan.max_lights || p.config != 0) continue;
    const std::string probe = (fs::path(plan.dir) / "traces" / ("msaa_probe_" + p.technique + ".trace")).string();
    std::ostringstream sink, errs;
    const int rc = cli_main({"trace", "--technique", p.technique, "--lights", "1", "--resolution", "64x36", "--samples", "4", "--out", probe},
                            sink, errs);
    std::error_code ec;
    fs::remove(probe, ec);
    if (rc == 0) msaa_techniques.insert(p.technique);
  }
  std::optional<ImageRGB8> reference_color;  // plain forward's image, when there is one
  for (const auto& p : points) {
    if (p.lights == plan.max_lights && p.technique == "plain_forward" && !p.images_dir.empty()) {
      try {
        reference_color = read_png((fs::path(p.images_dir) / "color.png").string());
      } catch (const InputError&) {
        reference_color.reset();  // its run failed: no blending column
      }
    }
  }
  for (const auto& p : points) {
    if (p.lights != plan.max_lights || p.config != 0) continue;
    const std::optional<std::int64_t> run = results.run_of(p);
    if (!run) continue;
    std::string offchip;
    for (const char* cls : {"color", "depth_stencil", "gbuffer", "visibility", "light_lists", "work_lists", "spill"}) {
      if (results.requested_bytes(*run, std::string("frame/dram.") + cls) > 0) offchip += (offchip.empty() ? "" : ",") + std::string(cls);
    }
    const std::optional<double> overshading = results.derived(*run).overshading;
    const bool msaa = msaa_techniques.count(p.technique) > 0;
    // Blending: does its image, translucent glass included, equal plain forward's?
    std::string blending = "n/a";
    if (reference_color && !p.images_dir.empty()) {
      // The atrium has a few exactly coplanar faces (z-fighting, about 0.02 % of the pixels) whose
      // visible one depends on the depth test; more than 0.1 % of differing pixels is real.
      blending = differing_pixels(*reference_color, (fs::path(p.images_dir) / "color.png").string()) <= 0.001 ? "yes" : "no";
    }
    out << std::left << std::setw(30) << p.technique << std::setw(56) << offchip << std::right << std::setw(9)
        << fmt(results.stat(*run, FrameShapeStats::kScope, &FrameShapeStats::geometry_passes) / plan.frames, 0)  // per frame
        << std::setw(14)
        << (fig(overshading, 2) + (overshading && *overshading > kOvershadingYes ? " yes" : " no")) << std::setw(6)
        << (msaa ? "yes" : "no") << std::setw(10) << blending << "\n";
  }
}

/// Plots, when the analysis scripts and Debian's python3 with pandas and matplotlib are present
/// (the scripts run at once, up to `jobs` of them); returns how many were written.
int write_plots(const std::string& db_path, const fs::path& plots, int jobs) {
  std::error_code ec;
  fs::create_directories(plots, ec);
  std::vector<WorkerJob> scripts;
  for (const char* script : {"plot_techniques.py", "plot_scaling.py"}) {
    const fs::path s = fs::path(data_root()) / "analysis" / script;  // installed, else the checkout
    if (!fs::exists(s) || !fs::exists("/usr/bin/python3")) continue;
    const std::string png = (plots / (std::string(script).substr(0, std::string(script).size() - 3) + ".png")).string();
    WorkerJob job;
    job.argv = {"/usr/bin/python3", s.string(), "--db", db_path, "--out", png};
    scripts.push_back(std::move(job));
  }
  int plotted = 0;
  for (const WorkerEnd& end : run_worker_jobs(jobs, std::move(scripts))) plotted += end.ok() ? 1 : 0;
  return plotted;
}

}  // namespace

int cmd_study(const std::vector<std::string>& args, std::ostream& out, std::ostream& err) {
  po::options_description desc("study options");
  add_config_options(desc);
  desc.add_options()("out,o", po::value<std::string>()->default_value("study"), "output folder (database, traces, images, plots)")(
      "jobs,j", po::value<int>()->default_value(2), "worker processes")(
      "scene", po::value<std::string>()->default_value("atrium:" + std::to_string(default_atrium_detail)), "scene")(
      "resolution", po::value<std::string>()->default_value("1920x1080"), "WIDTHxHEIGHT")(
      "lights", po::value<std::vector<int>>()->multitoken(), "light counts, each 1 or more (default 256 1024)")(
      "technique", po::value<std::vector<std::string>>()->multitoken(), "techniques (default: all)")(
      "images", po::value<std::string>()->default_value("largest"), "write images for: none | largest (light count) | all")(
      "option", po::value<std::vector<std::string>>()->composing(),
      "TECHNIQUE:KEY=VALUE: a technique option for that technique's traces, e.g. forward_light_stack:pls_bytes=32 "
      "(repeatable; `tbdrsim trace --list` lists the options)")(
      "modes", po::value<std::vector<std::string>>()->multitoken(),
      "GPU modes to compare (gpu.mode values: tbdr tbr imr); each trace replays on each; default: the configuration's")(
      "frames", po::value<int>()->default_value(1),
      "frames per trace: 1 = one cold frame; more = a sequence (camera along --camera-path, lights orbiting), and a "
      "table of the steady frame time, frame rate, DRAM and energy per frame beside the cold first frame "
      "(docs/sequences.md)")(
      "camera-path", po::value<std::string>()->default_value("orbit"), "the sequences' camera path: static, orbit, flythrough, or a camera path file (docs/sequences.md)");
  add_threads_option(desc, "the cores this process may use divided between the --jobs workers, at least 1, so "
                           "that jobs x threads <= cores");
  po::variables_map vm;
  if (!parse_command_options("study", args, desc, nullptr, vm, out)) return 0;
  const StudyPlan plan = plan_from_options(vm);
  std::error_code ec;
  // A generator refusing its options (bad input) leaves nothing behind: generate_traces removes
  // the traces it wrote, and here a folder this study created; the database comes after the traces.
  const bool dir_existed = fs::exists(plan.dir);
  const bool traces_existed = fs::exists(fs::path(plan.dir) / "traces");
  fs::create_directories(fs::path(plan.dir) / "traces", ec);
  if (ec) throw InputError(plan.dir, "cannot create the study folder: " + ec.message());
  out << "study: " << plan.techniques.size() << " techniques x " << plan.light_counts.size() << " light counts on "
      << plan.scene << " at " << plan.resolution << ", configuration '" << plan.config_label << "'";
  if (!plan.modes.empty()) {
    out << ", modes";
    for (const auto& m : plan.modes) out << " " << m;
  }
  out << ", " << plan.jobs << " workers x " << plan.threads << (plan.threads == 1 ? " thread" : " threads") << std::endl;
  // The atrium is built here once, as the trace generators (without colour texels) and the runs
  // (with them where they write images) ask for it, so that every worker process forked below
  // inherits it instead of building it again (shared_scene): 65 builds of about 70 ms each at
  // the default study, 1.5-2 s of its wall time on two workers. A glTF scene is loaded by each.
  std::vector<StudyPoint> points;
  try {
    if (parse_atrium_spec(plan.scene)) {  // (a bad spec throws here, and leaves nothing written)
      shared_scene(plan.scene, SceneLoadOptions{.colour_texels = false});
      if (plan.image_mode != "none") shared_scene(plan.scene, SceneLoadOptions{.colour_texels = true});
    }
    points = generate_traces(plan);
  } catch (...) {
    if (!dir_existed) {
      fs::remove_all(plan.dir, ec);
    } else if (!traces_existed) {
      fs::remove(fs::path(plan.dir) / "traces", ec);  // empty again
    }
    throw;
  }
  if (plan.image_mode != "none") {
    fs::create_directories(fs::path(plan.dir) / "images", ec);
    if (ec) throw InputError(plan.dir, "cannot create the study folder: " + ec.message());
  }
  std::int64_t runs_before = 0;  // rows of earlier studies into this folder
  {
    ResultsDb db(plan.db_path);  // create or migrate before the workers start
    SqlStatement q(db.sql(), "SELECT count(*) FROM runs");
    if (q.step()) runs_before = q.int64(0);
  }
  const int failures = run_points(plan, points, out, err);
  if (failures > 0) err << "study: " << failures << " worker(s) reported failed runs (see above)\n";
  // Refusals are the configuration's documented limits (a technique with pixel local storage on an
  // immediate-mode GPU, ...): the study goes on, and says which and why.
  std::map<std::string, std::vector<std::string>> refused;  // reason -> the points
  std::size_t refused_count = 0;
  for (const auto& p : points) {
    if (p.refusal.empty()) continue;
    ++refused_count;
    std::string reason = p.refusal;
    // The reason without the trace's path and line, which differ between the points.
    if (const auto pass = reason.find(": pass '"); pass != std::string::npos) reason = reason.substr(pass + 2);
    refused[reason].push_back(p.technique + " at " + std::to_string(p.lights) + " lights on " + p.mode);
  }
  // The plot scripts (python, about a second each) draw while this process writes the tables
  // (about a second too: the database's queries and the blending column's image comparisons);
  // both only read the database, which every run has written by now.
  const fs::path plots = fs::path(plan.dir) / "plots";
  std::future<int> plotted_later = std::async(std::launch::async, [&] { return write_plots(plan.db_path, plots, plan.jobs); });
  {
    const ResultsDb db(plan.db_path);
    StudyResults results(db, plan);
    print_comparison(plan, points, results, out);
    print_sequence_table(plan, points, results, out);
    print_mode_table(plan, points, results, db, out);
    print_method_table(plan, points, results, out);
  }
  const int plotted = plotted_later.get();
  std::int64_t runs_after = 0, ok_after = 0;
  {
    const ResultsDb db(plan.db_path);
    SqlStatement q(db.sql(), "SELECT count(*), coalesce(sum(status = 'ok'), 0) FROM runs");
    if (q.step()) {
      runs_after = q.int64(0);
      ok_after = q.int64(1);
    }
  }
  close_results_db_cleanly(plan.db_path);  // the plot scripts read it: leave no -wal/-shm beside it
  if (refused_count > 0) {
    out << "\nrefused: " << refused_count << " of the " << points.size()
        << " points, as documented (docs/hardware-model.md; not failures: the exit code stays 0 for them):\n";
    for (const auto& [reason, which] : refused) {
      out << "  ";
      for (std::size_t i = 0; i < which.size(); ++i) out << (i ? ", " : "") << which[i];
      out << ": " << reason << "\n";
    }
  }
  const std::size_t ran = points.size() - refused_count - static_cast<std::size_t>(failures);
  out << "\nresults: " << plan.db_path << " (this study: " << ran << " finished run(s)";
  if (failures > 0) out << ", " << failures << " failed";
  if (refused_count > 0) out << ", " << refused_count << " refused";
  out << "; the database holds " << runs_after << " run(s), " << ok_after << " finished";
  if (runs_before > 0) {
    out << ", " << runs_before << " of them from earlier studies into " << plan.dir
        << " (the tables above read this study's latest run of each point)";
  }
  out << "), traces in " << (fs::path(plan.dir) / "traces").string();
  if (plan.image_mode != "none") out << ", images and heat maps in " << (fs::path(plan.dir) / "images").string();
  out << ", " << plotted << " plots in " << plots.string() << "\n";
  return failures > 0 ? 1 : 0;
}

}  // namespace tbdr
