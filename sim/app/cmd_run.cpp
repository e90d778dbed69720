// `tbdrsim scene`, `tbdrsim trace` and `tbdrsim run`: inspect scenes, generate technique traces,
// replay a trace and write the run to the results database.
#include <cstdio>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <sstream>

#include <boost/program_options.hpp>

#include "app/cli.hpp"
#include "app/commands.hpp"
#include "kernel/errors.hpp"
#include "kernel/thread_pool.hpp"
#include "models/command_processor.hpp"
#include "app/image_output.hpp"
#include "analysis/results_db.hpp"
#include "app/run_driver.hpp"
#include "app/stats_export.hpp"
#include "app/memory_trace_options.hpp"
#include "models/dram_trace_export.hpp"
#include "tbdrsim_version.hpp"
#include "scene/camera.hpp"
#include "scene/lights.hpp"
#include "scene/scene_library.hpp"
#include "techniques/technique.hpp"

namespace tbdr {

namespace po = boost::program_options;

int cmd_scene(const std::vector<std::string>& args, std::ostream& out, std::ostream&) {
  po::options_description desc("scene options");
  desc.add_options()("action", po::value<std::string>()->required(), "info")(
      "scene", po::value<std::string>()->required(), "atrium[:detail] or a .gltf/.glb file");
  po::positional_options_description pos;
  pos.add("action", 1).add("scene", 1);
  po::variables_map vm;
  if (!parse_command_options("scene", args, desc, &pos, vm, out)) return 0;
  if (vm["action"].as<std::string>() != "info") {
    throw UsageError("tbdrsim scene: unknown action '" + vm["action"].as<std::string>() + "' (expected: info)");
  }
  const Scene scene = load_scene(vm["scene"].as<std::string>());
  print_scene_info(scene, out);
  return 0;
}

namespace {

void parse_resolution(const std::string& text, int& w, int& h) {
  const auto x = text.find('x');
  try {
    std::size_t a = 0, b = 0;
    if (x == std::string::npos) throw std::invalid_argument("no x");
    w = std::stoi(text.substr(0, x), &a);
    h = std::stoi(text.substr(x + 1), &b);
    if (a != x || b != text.size() - x - 1 || w <= 0 || h <= 0 || w > 16384 || h > 16384) throw std::invalid_argument("range");
  } catch (const std::exception&) {
    throw InputError("--resolution " + text, "expected WIDTHxHEIGHT with both in [1, 16384], e.g. 1920x1080");
  }
}

}  // namespace

/// The setup `tbdrsim trace` generates from; `scene_ptr` keeps the scene it points to (the
/// generators read geometry, materials and texture sizes, never the colour texels).
TraceSetup trace_setup_from_options(const po::variables_map& vm, std::shared_ptr<const Scene>& scene_ptr) {
  TraceSetup setup;
  setup.scene_spec = vm["scene"].as<std::string>();
  scene_ptr = shared_scene(setup.scene_spec, SceneLoadOptions{.colour_texels = false});
  const Scene& scene_storage = *scene_ptr;
  setup.scene = &scene_storage;
  parse_resolution(vm["resolution"].as<std::string>(), setup.width, setup.height);
  setup.samples = vm["samples"].as<int>();
  const std::string camera = vm["camera"].as<std::string>();
  if (scene_storage.name == "atrium") {
    setup.camera_name = camera.empty() ? "entrance" : camera;
    setup.camera = atrium_viewpoint(setup.camera_name, scene_storage);
  } else {
    if (!camera.empty() && camera != "framing") {
      throw InputError("--camera " + camera, "glTF scenes have one viewpoint, 'framing'");
    }
    setup.camera_name = "framing";
    setup.camera = framing_camera(scene_storage);
  }
  if (vm.count("light-file")) {
    setup.lights = read_light_file(vm["light-file"].as<std::string>());
  } else {
    LightSetSpec spec;
    const int n = vm["lights"].as<int>();
    if (n < 0 || n > 1000000) throw InputError("--lights " + std::to_string(n), "expected a count in [0, 1000000]");
    spec.count = static_cast<std::uint32_t>(n);
    spec.seed = vm["light-seed"].as<std::uint64_t>();
    setup.lights = generate_lights(scene_storage, spec);
  }
  if (vm.count("option")) {
    for (const auto& kv : vm["option"].as<std::vector<std::string>>()) {
      const auto eq = kv.find('=');
      if (eq == std::string::npos) throw InputError("--option " + kv, "expected key=value");
      setup.options[kv.substr(0, eq)] = kv.substr(eq + 1);
    }
  }
  return setup;
}

void add_trace_setup_options(po::options_description& desc) {
  desc.add_options()
      ("scene", po::value<std::string>()->default_value("atrium:" + std::to_string(default_atrium_detail)),
       "atrium[:detail] (detail 1..5, default 3) or a .gltf/.glb file")
      ("lights", po::value<int>()->default_value(256),
       "number of generated lights, 0 to 1000000; 0: none, the surfaces shaded unlit (validate's ALU- and "
       "texture-bound probes; techniques that cull a light array refuse it)")
      ("light-seed", po::value<std::uint64_t>()->default_value(1), "seed of the light placement")
      ("light-file", po::value<std::string>(), "read the lights from this file instead of generating them")
      ("camera", po::value<std::string>()->default_value(""), "atrium viewpoint (entrance, gallery, top, ...); glTF: framing")
      ("resolution", po::value<std::string>()->default_value("1920x1080"), "WIDTHxHEIGHT in pixels")
      ("samples", po::value<int>()->default_value(1), "MSAA samples per pixel: 1, 2, 4 or 8")
      ("option,o", po::value<std::vector<std::string>>()->composing(), "technique option key=value (repeatable)");
}

int cmd_trace(const std::vector<std::string>& args, std::ostream& out, std::ostream&) {
  po::options_description desc("trace options");
  add_trace_setup_options(desc);
  desc.add_options()("technique,t", po::value<std::string>()->default_value("plain_forward"),
                     "technique generator (see --list)")("out", po::value<std::string>(), "output trace file")(
      "frames", po::value<int>()->default_value(1),
      ("frames of a sequence, 1.." + std::to_string(kMaxSequenceFrames) + " (docs/trace-format.md, Sequences)").c_str())(
      "camera-path", po::value<std::string>()->default_value("static"),
      "how the camera moves over the frames: static, orbit (1 degree per frame about the target's vertical axis), "
      "flythrough (1 % of the eye-target distance per frame along the view), or a camera path file (one camera per "
      "frame: docs/sequences.md)")(
      "light-motion", po::value<std::string>()->default_value("static"),
      "how the lights move over the frames: static, orbit (each circles its place at half its range, 6 degrees per frame)")(
      "animation", po::value<int>(),
      "play the glTF scene's animation I over the frames: frame k is posed at k / --animation-fps seconds (docs/sequences.md)")(
      "animation-fps", po::value<double>()->default_value(SequenceMotion::kDefaultAnimationFps),
      "frames per second of the animation's clock")(
      "list", "list the techniques and their options");
  po::variables_map vm;
  if (!parse_command_options("trace", args, desc, nullptr, vm, out)) return 0;
  if (vm.count("list")) {
    for (const auto& t : techniques()) {
      out << t.name << ": " << t.summary << "\n";
      for (const auto& o : t.options) out << "    " << o.key << " = " << o.default_value << "  " << o.doc << "\n";
    }
    return 0;
  }
  if (!vm.count("out")) throw UsageError("tbdrsim trace: --out FILE is required");
  std::shared_ptr<const Scene> scene;
  const TraceSetup setup = trace_setup_from_options(vm, scene);
  SequenceMotion motion;
  motion.frames = vm["frames"].as<int>();
  const std::string camera_path = vm["camera-path"].as<std::string>();
  if (const auto named = camera_path_named(camera_path)) {
    motion.camera = *named;
  } else if (std::filesystem::is_regular_file(camera_path)) {
    motion.cameras = read_camera_path_file(camera_path, setup.camera);  // (InputError naming file:line)
  } else {
    throw InputError("--camera-path " + camera_path, "neither a camera path (static, orbit, flythrough) nor a camera path file");
  }
  motion.lights = parse_light_motion(vm["light-motion"].as<std::string>());
  if (vm.count("animation")) {
    motion.animation = vm["animation"].as<int>();
    if (motion.animation < 0) throw InputError("--animation", "expected an animation index, 0 or more");
    motion.animation_fps = vm["animation-fps"].as<double>();
  }
  const std::vector<Trace> frames = generate_sequence(vm["technique"].as<std::string>(), setup, motion);
  write_trace_frames_file(frames, vm["out"].as<std::string>());
  const Trace& trace = frames.front();
  out << "wrote " << vm["out"].as<std::string>() << ": technique " << trace.technique << ", " << trace.lights.size()
      << " lights, " << trace.commands.size() << " commands";
  if (frames.size() > 1) {
    out << " per frame, " << frames.size() << " frames (camera " << (motion.cameras.empty() ? to_string(motion.camera) : camera_path)
        << ", lights " << to_string(motion.lights);
    if (motion.animation >= 0) out << ", animation " << motion.animation << " at " << motion.animation_fps << " fps";
    out << ")";
  }
  out << ", hash " << trace_hash(frames) << "\n";
  return 0;
}

int cmd_run(const std::vector<std::string>& args, std::ostream& out, std::ostream&) {
  po::options_description desc("run options");
  add_config_options(desc);
  desc.add_options()("trace,t", po::value<std::string>()->required(), "command trace to replay")(
      "db,d", po::value<std::string>()->required(), "results database (created if absent)")(
      "images,i", po::value<std::string>(),
      "write the frame's images and heat maps into this folder (created; 'none': no images, as without the option)")(
      "stats", po::value<std::vector<std::string>>()->composing(),
      "write the run's statistics to FILE (gem5 stats.txt text; JSON with units and descriptions when FILE ends "
      ".json); repeatable: one run, several files (--stats s.txt --stats s.json)")(
      "timeline", po::value<std::string>(), "write the run's timeline to FILE (Chrome/Perfetto trace-event JSON)")(
      "sample", po::value<std::size_t>(),
      "sampled simulation of a sequence: simulate K frames, each standing for a group of frames with similar "
      "signatures, and estimate the sequence's totals with an error estimate (docs/sequences.md)")(
      "sample-warmup", po::value<std::size_t>()->default_value(1),
      "with --sample: frames simulated before each representative frame, from cold, to warm the caches and fill the pipeline")(
      "quiet,q", "print nothing but errors");
  add_memory_trace_options(desc);
  add_threads_option(desc, "the cores this process may use, " + std::to_string(default_thread_count()) + " here");
  po::variables_map vm;
  if (!parse_command_options("run", args, desc, nullptr, vm, out)) return 0;
  RunRequest req;
  req.config = config_from_options(vm);
  req.trace_path = vm["trace"].as<std::string>();
  req.db_path = vm["db"].as<std::string>();
  // "none" means no images, as `study --images none` does (a folder named none: --images ./none).
  if (vm.count("images") && vm["images"].as<std::string>() != "none") req.images_dir = vm["images"].as<std::string>();
  req.command_line = invocation_command_line();
  req.threads = threads_option(vm, default_thread_count());
  req.summary_figures = !vm.count("quiet");  // only the summary reads them (1 ms of the serial end)
  if (vm.count("sample")) {
    req.sample_frames = vm["sample"].as<std::size_t>();
    req.sample_warmup_frames = vm["sample-warmup"].as<std::size_t>();
    if (req.sample_frames < 2) throw InputError("--sample", "must be at least 2 (the cold first frame and one more group)");
    for (const char* option : {"images", "timeline", "memory-trace"}) {
      if (vm.count(option) && !(std::string(option) == "images" && req.images_dir.empty())) {
        throw InputError("--sample", std::string("a sampled run simulates no whole sequence: --") + option + " needs a run without --sample");
      }
    }
  }
  const std::vector<std::string> stats_files =
      vm.count("stats") ? vm["stats"].as<std::vector<std::string>>() : std::vector<std::string>{};
  for (std::size_t i = 0; i < stats_files.size(); ++i) {
    check_output_file("--stats", stats_files[i]);  // before the run
    for (std::size_t j = 0; j < i; ++j) {
      if (std::filesystem::path(stats_files[j]).lexically_normal() == std::filesystem::path(stats_files[i]).lexically_normal()) {
        throw InputError("--stats " + stats_files[i], "given twice: each --stats names another file");
      }
    }
  }
  if (vm.count("timeline")) check_output_file("--timeline", vm["timeline"].as<std::string>());
  std::unique_ptr<DramTraceExport> memory_trace = memory_trace_from_options(vm);  // checked before the run
  req.dram_observer = memory_trace.get();
  // A run that fails leaves no images folder behind that it created (it is made before the run).
  std::error_code ec;
  const bool images_existed = req.images_dir.empty() || std::filesystem::exists(req.images_dir, ec);
  RunOutcome outcome;
  try {
    outcome = run_one(req);
  } catch (...) {
    if (!images_existed) std::filesystem::remove_all(req.images_dir, ec);
    throw;
  }
  if (memory_trace) memory_trace->write(vm["memory-trace"].as<std::string>());
  if (!stats_files.empty() || vm.count("timeline")) {
    const ResultsDb db(req.db_path, ResultsDb::QueryOnly{});
    for (const auto& f : stats_files) write_stats_file(db, outcome.run_id, f);
    if (vm.count("timeline")) write_timeline_file(db, outcome.run_id, outcome.timing, vm["timeline"].as<std::string>());
  }
  if (!vm.count("quiet")) print_run_summary(outcome, out);
  return 0;
}

}  // namespace tbdr
