// `tbdrsim import CAPTURE --out FRAME.trace`: a captured frame of a real application as a trace
// (docs/capture-import.md). CAPTURE is a RenderDoc capture (.rdc, exported first by
// scripts/capture/rdc_export.py with Debian's python3-renderdoc) or an already exported capture
// intermediate (frame.json, or the folder holding it). Writes FRAME.trace, FRAME.glb (the draws'
// clip-space geometry and textures), FRAME.import.txt (the summary) and, when the capture has it,
// FRAME.reference.png (the application's own frame); on any error nothing.
#include "app/capture_convert.hpp"

#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>

#include <boost/program_options.hpp>

#include "app/commands.hpp"
#include "app/worker_pool.hpp"
#include "kernel/errors.hpp"
#include "scene/gltf_loader.hpp"

extern char** environ;

namespace tbdr {

namespace fs = std::filesystem;

namespace {

/// Runs argv (argv[0] a path) with the tool's stdout and stderr; returns its exit code (128+signal).
int run_program(const std::vector<std::string>& argv) {
  std::vector<char*> cargv;
  for (const auto& a : argv) cargv.push_back(const_cast<char*>(a.c_str()));
  cargv.push_back(nullptr);
  std::cout.flush();
  std::cerr.flush();
  pid_t pid = 0;
  if (const int e = posix_spawn(&pid, cargv[0], nullptr, nullptr, cargv.data(), environ); e != 0) {
    throw InputError(argv[0], std::string("cannot run: ") + std::strerror(e));
  }
  int status = 0;
  while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

/// The exporter script: $TBDRSIM_CAPTURE_DIR, <prefix>/share/tbdrsim/capture, the checkout's scripts/capture.
fs::path exporter_script() {
  std::vector<fs::path> dirs;
  if (const char* d = std::getenv("TBDRSIM_CAPTURE_DIR"); d && *d) dirs.emplace_back(d);
  dirs.push_back(fs::path(self_executable()).parent_path().parent_path() / "share" / "tbdrsim" / "capture");
  dirs.push_back(fs::path(TBDRSIM_SOURCE_DIR) / "scripts" / "capture");
  std::string searched;
  for (const auto& dir : dirs) {
    std::error_code ec;
    if (fs::is_regular_file(dir / "rdc_export.py", ec)) return dir / "rdc_export.py";
    searched += (searched.empty() ? "" : ", ") + dir.string();
  }
  throw InputError("rdc_export.py", "capture exporter not found (looked in " + searched + "; set TBDRSIM_CAPTURE_DIR)");
}

void write_file(const fs::path& p, const void* data, std::size_t size) {
  std::ofstream f(p, std::ios::binary);
  f.write(static_cast<const char*>(data), static_cast<std::streamsize>(size));
  if (!f) throw InputError(p.string(), "cannot write file");
}

/// The intermediate (frame.json) a capture argument names: the folder's frame.json, the file
/// itself, or an .rdc exported first into `exported` by rdc_export.py. False: the export failed
/// (its message is on stderr).
bool intermediate_of(const fs::path& input, const fs::path& exported, unsigned history_samples, fs::path& frame_json) {
  std::error_code ec;
  if (fs::is_directory(input, ec)) {
    frame_json = input / "frame.json";
  } else if (input.extension() == ".rdc") {
    const std::string python = std::getenv("TBDRSIM_PYTHON") && *std::getenv("TBDRSIM_PYTHON") ? std::getenv("TBDRSIM_PYTHON")
                                                                                                 : "/usr/bin/python3";
    const int rc = run_program({python, exporter_script().string(), input.string(), exported.string(), "--history-samples",
                                std::to_string(history_samples)});
    if (rc != 0) return false;
    frame_json = exported / "frame.json";
  } else {
    frame_json = input;
  }
  return true;
}

}  // namespace

int cmd_import(const std::vector<std::string>& args, std::ostream& out, std::ostream& err) {
  namespace po = boost::program_options;
  po::options_description desc("import options");
  desc.add_options()("capture", po::value<std::vector<std::string>>()->required(),
                     "a RenderDoc capture (.rdc, Vulkan), or an exported capture intermediate (frame.json or its folder); "
                     "several, in order: consecutive frames imported as one sequence")(
      "out,o", po::value<std::string>()->required(),
      "the trace to write (FRAME.trace); FRAME.glb, FRAME.import.txt and FRAME.reference.png go beside it")(
      "history-samples", po::value<unsigned>()->default_value(1200),
      "pixels whose triangle RenderDoc's pixel history records in the application's frame (for comparing "
      "images; .rdc only, 0 for none)");
  po::positional_options_description pos;
  pos.add("capture", -1);
  po::variables_map vm;
  if (!parse_command_options("import", args, desc, &pos, vm, out)) return 0;
  std::vector<fs::path> inputs;
  for (const auto& c : vm["capture"].as<std::vector<std::string>>()) inputs.emplace_back(c);
  const fs::path trace_path(vm["out"].as<std::string>());
  if (trace_path.extension() != ".trace") throw UsageError("tbdrsim import: --out must name a .trace file");
  std::error_code ec;
  for (const auto& input : inputs) {
    if (!fs::exists(input, ec)) throw InputError(input.string(), "capture not found");
  }
  fs::path out_dir = trace_path.parent_path();
  if (out_dir.empty()) out_dir = ".";
  if (!fs::is_directory(out_dir, ec)) throw InputError(out_dir.string(), "output folder does not exist");

  // Everything is made in a scratch folder beside the output and moved in at the end.
  fs::path scratch = out_dir / (".tbdrsim-import-" + std::to_string(getpid()));
  fs::remove_all(scratch, ec);
  fs::create_directories(scratch);
  struct Cleanup {
    fs::path p;
    ~Cleanup() {
      std::error_code e;
      fs::remove_all(p, e);
    }
  } cleanup{scratch};

  const bool sequence = inputs.size() > 1;
  std::vector<fs::path> frame_jsons(inputs.size());
  std::vector<std::string> json_paths;
  for (std::size_t k = 0; k < inputs.size(); ++k) {
    const fs::path exported = scratch / (sequence ? "export_" + std::to_string(k) : std::string("export"));
    if (!intermediate_of(inputs[k], exported, vm["history-samples"].as<unsigned>(), frame_jsons[k])) {
      err << "tbdrsim import: the RenderDoc export of " << inputs[k].string() << " failed (its message is above); nothing written\n";
      return 2;
    }
    json_paths.push_back(frame_jsons[k].string());
  }
  const std::string stem = trace_path.stem().string();
  const std::string glb_name = stem + ".glb";
  CaptureSequence seq = convert_captures(json_paths, glb_name);
  std::vector<Trace> traces;
  for (const auto& f : seq.frames) traces.push_back(f.trace);

  // Read back what is written through the same reader and loader the simulator uses.
  write_file(scratch / glb_name, seq.glb.data(), seq.glb.size());
  std::ostringstream text;
  write_trace_frames(traces, text);
  write_file(scratch / (stem + ".trace"), text.str().data(), text.str().size());
  {
    const Scene scene = load_gltf((scratch / glb_name).string());
    for (const Trace& back : read_trace_frames((scratch / (stem + ".trace")).string())) {
      check_scene_references(back, scene, trace_path.string());
    }
  }
  std::ostringstream summary;
  for (std::size_t k = 0; k < seq.frames.size(); ++k) {
    const CaptureImport& imp = seq.frames[k];
    summary << "tbdrsim import of " << inputs[k].string() << (sequence ? " (frame " + std::to_string(k) + ")" : "") << "\n";
    for (const auto& s : imp.summary) summary << "  " << s << "\n";
    summary << "not carried by the trace (" << imp.unsupported.size() << "):\n";
    for (const auto& s : imp.unsupported) summary << "  - " << s << "\n";
    if (imp.unsupported.empty()) summary << "  (nothing)\n";
  }
  const std::string st = summary.str();
  write_file(scratch / (stem + ".import.txt"), st.data(), st.size());
  std::vector<std::pair<fs::path, fs::path>> moves = {{scratch / glb_name, out_dir / glb_name},
                                                      {scratch / (stem + ".trace"), trace_path},
                                                      {scratch / (stem + ".import.txt"), out_dir / (stem + ".import.txt")}};
  // The application's own frame (a sequence's last) beside the trace.
  const fs::path ref = frame_jsons.back().parent_path() / "reference.png";
  if (fs::is_regular_file(ref, ec)) {
    check_png_file(ref, "the application's frame (copied to " + stem + ".reference.png)");
    fs::copy_file(ref, scratch / (stem + ".reference.png"), fs::copy_options::overwrite_existing);
    moves.push_back({scratch / (stem + ".reference.png"), out_dir / (stem + ".reference.png")});
  }
  // The intermediates, kept as STEM.capture/ (a sequence's as STEM.capture/frame<k>/): what
  // `tbdrsim import` reads without RenderDoc and compare_frame.py compares with; never the .rdc.
  const fs::path kept = scratch / (stem + ".capture");
  for (std::size_t k = 0; k < inputs.size(); ++k) {
    const fs::path to = sequence ? kept / ("frame" + std::to_string(k)) : kept;
    fs::create_directories(to.parent_path());
    if (inputs[k].extension() == ".rdc") {
      fs::rename(frame_jsons[k].parent_path(), to);
    } else {
      fs::create_directories(to);
      for (const auto& e : fs::directory_iterator(frame_jsons[k].parent_path())) {
        if (e.is_regular_file() && e.path().extension() != ".rdc") fs::copy_file(e.path(), to / e.path().filename());
      }
    }
  }
  fs::remove_all(out_dir / (stem + ".capture"), ec);
  moves.push_back({kept, out_dir / (stem + ".capture")});
  for (const auto& [from, to] : moves) fs::rename(from, to);
  out << st << "wrote " << trace_path.string() << " (scene " << glb_name << ", hash " << traces.front().scene.content_hash
      << (sequence ? ", " + std::to_string(traces.size()) + " frames" : std::string()) << ")\n";
  return 0;
}

}  // namespace tbdr
