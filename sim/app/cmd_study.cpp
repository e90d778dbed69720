// `tbdrsim study`: the README's main job. Every technique on the built-in atrium at 1920x1080
// with 256 and 1024 lights on one configuration, in parallel worker processes, into one results
// database; prints the comparison table and the measured method table (Billeter's columns), and
// writes images, heat maps and plots into a folder.
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <cstdio>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <map>
#include <sstream>

#include <boost/program_options.hpp>
#include <sqlite3.h>

#include "app/cli.hpp"
#include "app/commands.hpp"
#include "kernel/errors.hpp"
#include "app/image_output.hpp"
#include "analysis/results_db.hpp"
#include "app/run_driver.hpp"
#include "scene/camera.hpp"
#include "scene/lights.hpp"
#include "scene/scene_library.hpp"
#include "techniques/technique.hpp"

namespace tbdr {

namespace po = boost::program_options;

namespace {

/// Lights per additive pass of forward_multipass in the study.
constexpr int kMultipassBatch = 64;

/// One point of the study: a technique at a light count.
struct StudyPoint {
  std::string technique;
  int lights = 0;
  std::string trace_path;
  std::string images_dir;
};

double query_double(sqlite3* db, const std::string& sql) {
  sqlite3_stmt* s = nullptr;
  double v = 0;
  if (sqlite3_prepare_v2(db, sql.c_str(), -1, &s, nullptr) == SQLITE_OK && sqlite3_step(s) == SQLITE_ROW) {
    v = sqlite3_column_double(s, 0);
  }
  sqlite3_finalize(s);
  return v;
}

std::string fmt(double v, int decimals) {
  std::ostringstream o;
  o << std::fixed << std::setprecision(decimals) << v;
  return o.str();
}

/// Share of pixels whose color differs from the reference by more than 1/255 in a channel (1 when
/// the sizes differ or an image is missing).
double differing_pixels(const std::string& a, const std::string& b) {
  try {
    const ImageRGB8 x = read_png(a), y = read_png(b);
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

/// Lit surface invocations (scene geometry evaluating lights, or pixels lit by a kernel) per
/// visible pixel: above 1, lighting was computed for samples that ended up hidden.
double overshading_of(double lit, double compute, double covered) { return (lit + compute) / std::max(1.0, covered); }

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

}  // namespace

int cmd_study(const std::vector<std::string>& args, std::ostream& out, std::ostream& err) {
  po::options_description desc("study options");
  add_config_options(desc);
  desc.add_options()("out,o", po::value<std::string>()->default_value("study"), "output folder (database, traces, images, plots)")(
      "jobs,j", po::value<int>()->default_value(2), "worker processes")(
      "scene", po::value<std::string>()->default_value("atrium:" + std::to_string(default_atrium_detail)), "scene")(
      "resolution", po::value<std::string>()->default_value("1920x1080"), "WIDTHxHEIGHT")(
      "lights", po::value<std::vector<int>>()->multitoken(), "light counts (default 256 1024)")(
      "technique", po::value<std::vector<std::string>>()->multitoken(), "techniques (default: all)")(
      "images", po::value<std::string>()->default_value("largest"), "write images for: none | largest (light count) | all");
  po::variables_map vm;
  if (!parse_command_options("study", args, desc, nullptr, vm, out)) return 0;
  namespace fs = std::filesystem;
  const std::string dir = vm["out"].as<std::string>();
  const int jobs = vm["jobs"].as<int>();
  if (jobs < 1 || jobs > 64) throw InputError("--jobs " + std::to_string(jobs), "expected 1..64 worker processes");
  const std::vector<int> light_counts = vm.count("lights") ? vm["lights"].as<std::vector<int>>() : std::vector<int>{256, 1024};
  const std::vector<std::string> names = vm.count("technique") ? vm["technique"].as<std::vector<std::string>>() : technique_names();
  for (const auto& n : names) find_technique(n);  // InputError for an unknown name
  const std::string image_mode = vm["images"].as<std::string>();
  if (image_mode != "none" && image_mode != "largest" && image_mode != "all") {
    throw InputError("--images " + image_mode, "expected none, largest or all");
  }
  const ResolvedConfig config = config_from_options(vm);
  std::error_code ec;
  fs::create_directories(fs::path(dir) / "traces", ec);
  fs::create_directories(fs::path(dir) / "images", ec);
  if (ec) throw InputError(dir, "cannot create the study folder: " + ec.message());
  const std::string db_path = (fs::path(dir) / "study.db").string();
  { ResultsDb db(db_path); }  // create or migrate before the workers start

  // Traces: generated once here (cheap), replayed by the workers.
  out << "study: " << names.size() << " techniques x " << light_counts.size() << " light counts on "
      << vm["scene"].as<std::string>() << " at " << vm["resolution"].as<std::string>() << ", configuration '"
      << config.params.config_name << "', " << jobs << " workers" << std::endl;
  std::vector<StudyPoint> points;
  const int max_lights = *std::max_element(light_counts.begin(), light_counts.end());
  {
    std::vector<std::string> trace_args = {"--scene", vm["scene"].as<std::string>(), "--resolution", vm["resolution"].as<std::string>()};
    for (int n : light_counts) {
      for (const auto& t : names) {
        StudyPoint p;
        p.technique = t;
        p.lights = n;
        p.trace_path = (fs::path(dir) / "traces" / (t + "_" + std::to_string(n) + ".trace")).string();
        if (image_mode == "all" || (image_mode == "largest" && n == max_lights)) {
          p.images_dir = (fs::path(dir) / "images" / (t + "_" + std::to_string(n))).string();
        }
        std::vector<std::string> a = {"trace", "--technique", t, "--lights", std::to_string(n), "--out", p.trace_path};
        a.insert(a.end(), trace_args.begin(), trace_args.end());
        // One additive pass per light would replay the scene 1024 times: the study batches lights
        // (the issue allows "one additive pass per light or per light batch").
        if (t == "forward_multipass") a.insert(a.end(), {"--option", "lights_per_pass=" + std::to_string(kMultipassBatch)});
        std::ostringstream sink, errs;
        if (cli_main(a, sink, errs) != 0) throw InputError("study", "generating " + t + ": " + errs.str());
        points.push_back(p);
      }
    }
  }

  // Workers: point i goes to worker i % jobs; each run is written at once (one transaction).
  const auto t0 = std::chrono::steady_clock::now();
  std::vector<pid_t> workers;
  for (int w = 0; w < jobs; ++w) {
    const pid_t pid = fork();
    if (pid < 0) throw std::runtime_error("fork failed");
    if (pid == 0) {
      int rc = 0;
      for (std::size_t i = static_cast<std::size_t>(w); i < points.size(); i += static_cast<std::size_t>(jobs)) {
        try {
          RunRequest req;
          req.config = config;
          req.trace_path = points[i].trace_path;
          req.db_path = db_path;
          req.images_dir = points[i].images_dir;
          req.command_line = invocation_command_line() + " [point " + std::to_string(i) + "]";
          run_one(req);
        } catch (const std::exception& e) {
          std::cerr << "study: " << points[i].technique << " with " << points[i].lights << " lights failed: " << e.what() << "\n";
          rc = 1;
        }
      }
      _exit(rc);
    }
    workers.push_back(pid);
  }
  const bool tty = isatty(STDOUT_FILENO) != 0 && &out == &std::cout;
  sqlite3* db = nullptr;
  sqlite3_open_v2(db_path.c_str(), &db, SQLITE_OPEN_READONLY, nullptr);
  sqlite3_busy_timeout(db, 10000);
  const double runs_before = query_double(db, "SELECT count(*) FROM runs");
  std::size_t alive = workers.size();
  int failures = 0;
  std::size_t last_done = static_cast<std::size_t>(-1);
  while (alive > 0) {
    int status = 0;
    const pid_t pid = waitpid(-1, &status, WNOHANG);
    if (pid > 0) {
      --alive;
      if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) ++failures;
      continue;
    }
    const auto done = static_cast<std::size_t>(query_double(db, "SELECT count(*) FROM runs") - runs_before);
    if (done != last_done || tty) {
      draw_progress(out, std::min(done, points.size()), points.size(),
                    std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), tty);
      last_done = done;
    }
    usleep(tty ? 200000 : 1000000);
  }
  draw_progress(out, points.size(), points.size(), std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), tty);
  if (tty) out << "\n";
  if (failures > 0) err << "study: " << failures << " worker(s) reported failed runs (see above)\n";

  // The comparison table: the latest run of each point.
  auto run_of = [&](const StudyPoint& p) {
    return query_double(db, "SELECT max(id) FROM runs WHERE status = 'ok' AND trace_path = '" + p.trace_path + "'");
  };
  auto metric = [&](double run, const std::string& scope, const std::string& name) {
    return query_double(db, "SELECT value FROM stats WHERE run_id = " + fmt(run, 0) + " AND scope = '" + scope + "' AND name = '" + name + "'");
  };
  out << "\nComparison (" << config.params.config_name << "): frame time, DRAM traffic requested by the units, energy"
      << " (forward_multipass: " << kMultipassBatch << " lights per pass)\n";
  out << std::left << std::setw(30) << "technique" << std::right << std::setw(7) << "lights" << std::setw(11) << "frame ms"
      << std::setw(11) << "DRAM MB" << std::setw(11) << "energy mJ" << std::setw(12) << "overshading" << std::setw(12)
      << "lights/px" << "\n";
  for (const auto& p : points) {
    const double run = run_of(p);
    if (run <= 0) {
      out << std::left << std::setw(30) << p.technique << std::right << std::setw(7) << p.lights << "   (failed)\n";
      continue;
    }
    const double dram = metric(run, "frame/dram", "read_bytes") + metric(run, "frame/dram", "write_bytes");
    const double covered = std::max(1.0, metric(run, "frame/frame", "covered_pixels"));
    const double overshading = overshading_of(metric(run, "frame/tsp", "lit_surface_invocations"),
                                              metric(run, "frame/compute", "compute_shaded_pixels"), covered);
    const double evals = metric(run, "frame/tsp", "light_evaluations") + metric(run, "frame/compute", "compute_light_evaluations");
    out << std::left << std::setw(30) << p.technique << std::right << std::setw(7) << p.lights << std::setw(11)
        << fmt(metric(run, "frame/timing", "frame_time_ms"), 2) << std::setw(11) << fmt(dram / 1e6, 1) << std::setw(11)
        << fmt(metric(run, "frame/energy", "total_mj"), 2) << std::setw(12) << fmt(overshading, 2) << std::setw(12)
        << fmt(evals / covered, 1) << "\n";
  }

  // The measured method table (Billeter's columns) at the largest light count.
  out << "\nMethod table, measured at " << max_lights << " lights (off-chip: classes with DRAM traffic besides the "
      << "parameter buffer, vertices, indices, textures and light data)\n";
  out << std::left << std::setw(30) << "technique" << std::setw(56) << "off-chip buffers" << std::right << std::setw(9) << "geo pass"
      << std::setw(14) << "overshading" << std::setw(6) << "MSAA" << std::setw(10) << "blending" << "\n";
  out << "  (overshading: lit surface invocations per visible pixel, yes above 1.10 (translucent layers add about 5 %); blending: the image with the translucent glass\n"
      << "   equals plain forward's; MSAA: the generator produces a 4x trace)\n";
  std::string reference_color;
  for (const auto& p : points) {
    if (p.lights == max_lights && p.technique == "plain_forward" && !p.images_dir.empty()) {
      reference_color = (fs::path(p.images_dir) / "color.png").string();
    }
  }
  for (const auto& p : points) {
    if (p.lights != max_lights) continue;
    const double run = run_of(p);
    if (run <= 0) continue;
    std::string offchip;
    for (const char* cls : {"color", "depth_stencil", "gbuffer", "visibility", "light_lists", "work_lists", "spill"}) {
      const double b = metric(run, std::string("frame/dram.") + cls, "read_bytes") + metric(run, std::string("frame/dram.") + cls, "write_bytes");
      if (b > 0) offchip += (offchip.empty() ? "" : ",") + std::string(cls);
    }
    const double covered = std::max(1.0, metric(run, "frame/frame", "covered_pixels"));
    const double overshading = overshading_of(metric(run, "frame/tsp", "lit_surface_invocations"),
                                              metric(run, "frame/compute", "compute_shaded_pixels"), covered);
    // MSAA: does the technique's generator produce a 4x trace?
    bool msaa = true;
    {
      std::ostringstream sink, errs;
      msaa = cli_main({"trace", "--technique", p.technique, "--lights", "1", "--resolution", "64x36", "--samples", "4", "--out",
                       (fs::path(dir) / "traces" / "msaa_probe.trace").string()},
                      sink, errs) == 0;
    }
    // Blending: does its image, translucent glass included, equal plain forward's?
    std::string blending = "n/a";
    if (!reference_color.empty() && !p.images_dir.empty()) {
      // The atrium has a few exactly coplanar faces (z-fighting, about 0.02 % of the pixels) whose
      // visible one depends on the depth test; more than 0.1 % of differing pixels is real.
      blending = differing_pixels(reference_color, (fs::path(p.images_dir) / "color.png").string()) <= 0.001 ? "yes" : "no";
    }
    out << std::left << std::setw(30) << p.technique << std::setw(56) << offchip << std::right << std::setw(9)
        << fmt(metric(run, "frame/frame", "geometry_passes"), 0) << std::setw(12)
        << std::setw(14) << (fmt(overshading, 2) + (overshading > 1.10 ? " yes" : " no")) << std::setw(6)
        << (msaa ? "yes" : "no") << std::setw(10) << blending << "\n";
  }
  sqlite3_close(db);

  // Plots, when the analysis scripts and Debian's python3 with pandas and matplotlib are present.
  const fs::path plots = fs::path(dir) / "plots";
  fs::create_directories(plots, ec);
  int plotted = 0;
  for (const char* script : {"plot_techniques.py", "plot_scaling.py"}) {
    const fs::path s = fs::path(TBDRSIM_SOURCE_DIR) / "analysis" / script;
    if (!fs::exists(s) || !fs::exists("/usr/bin/python3")) continue;
    const std::string png = (plots / (std::string(script).substr(0, std::string(script).size() - 3) + ".png")).string();
    const std::string cmd = "/usr/bin/python3 " + s.string() + " --db " + db_path + " --out " + png + " > /dev/null 2>&1";
    if (std::system(cmd.c_str()) == 0) ++plotted;
  }
  out << "\nresults: " << db_path << " (" << points.size() << " runs), traces in " << (fs::path(dir) / "traces").string()
      << ", images and heat maps in " << (fs::path(dir) / "images").string() << ", " << plotted << " plots in " << plots.string()
      << "\n";
  return failures > 0 ? 1 : 0;
}

}  // namespace tbdr
