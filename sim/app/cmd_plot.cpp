// `tbdrsim plot KIND --db DB [--out FILE] [options]`: draws one plot of a results database by
// running its script (analysis/plot_<kind>.py) with Debian's python3, which has pandas and
// matplotlib. The scripts check their own options and the database and answer bad input with one
// line and exit code 2 (docs/plots.md); this command finds them (installed or in the checkout),
// refuses an unknown kind, and passes their message and exit code through.
#include <fcntl.h>
#include <poll.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <optional>
#include <ostream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <boost/program_options/positional_options.hpp>  // commands.hpp names it without including it

#include "app/commands.hpp"
#include "app/worker_pool.hpp"
#include "kernel/errors.hpp"

namespace tbdr {

namespace {

namespace fs = std::filesystem;

/// One kind of plot: its name on the command line, its script in analysis/, what it draws.
struct PlotKind {
  const char* name;
  const char* script;
  const char* summary;
};

constexpr PlotKind kPlotKinds[] = {
    {"techniques", "plot_techniques.py", "a figure (--metric) per technique, a panel per configuration and light count"},
    {"dram", "plot_dram.py", "DRAM MB per technique stacked by traffic class, for one configuration"},
    {"energy", "plot_energy.py", "energy per technique stacked by component (DRAM, caches, tile buffer, ALU, ...)"},
    {"passes", "plot_passes.py", "time by pass (timeline of binning, tile work, dispatches) and unit (busy, stalled)"},
    {"scaling", "plot_scaling.py", "a figure against the light count, a line per technique"},
    {"sensitivity", "plot_sensitivity.py", "a figure against hardware parameters (--param), a line per technique"},
    {"delta", "plot_delta.py", "change of a figure against a baseline (--baseline KEY=VALUE), per technique"},
    {"tiles", "plot_tiles.py", "per-tile heat maps (cycles, samples, DRAM bytes), one per technique"},
    {"sequence", "plot_sequence.py", "a sequence's frames: interval, DRAM and energy per frame, a line per technique"},
};

/// The interpreter: Debian's, which has pandas and matplotlib (scripts/install_deps.sh installs
/// python3-pandas and python3-matplotlib); the first python3 on PATH may be another without them.
/// TBDRSIM_PYTHON overrides it.
constexpr const char* kDebianPython = "/usr/bin/python3";

std::string env_or(const char* name, const std::string& fallback) {
  const char* v = std::getenv(name);
  return v && *v ? std::string(v) : fallback;
}

/// The folders searched for the scripts, in order: $TBDRSIM_ANALYSIS_DIR, the installed layout
/// (<prefix>/bin/tbdrsim -> <prefix>/share/tbdrsim/analysis), the checkout this binary was built
/// from (TBDRSIM_SOURCE_DIR/analysis).
std::vector<fs::path> script_dirs() {
  std::vector<fs::path> dirs;
  if (const char* d = std::getenv("TBDRSIM_ANALYSIS_DIR"); d && *d) dirs.emplace_back(d);
  dirs.push_back(fs::path(self_executable()).parent_path().parent_path() / "share" / "tbdrsim" / "analysis");
  dirs.push_back(fs::path(TBDRSIM_SOURCE_DIR) / "analysis");
  return dirs;
}

void print_kinds(std::ostream& os) {
  for (const auto& k : kPlotKinds) {
    os << "  " << k.name << std::string(13 - std::string(k.name).size(), ' ') << k.summary << "\n";
  }
}

std::string usage() {
  std::ostringstream os;
  os << "usage: tbdrsim plot KIND --db DB [--out FILE.png] [options]\n"
     << "       tbdrsim plot KIND --help      (the options of one kind)\n\nkinds:\n";
  print_kinds(os);
  os << "\nEvery kind takes --db, --out, --where, --config (a label it lists, or a preset name), --lights, --technique, "
        "--scene, --fix KEY=VALUE and --independent-y; "
        "docs/plots.md shows each plot.\n"
     << "Scripts: $TBDRSIM_ANALYSIS_DIR, <prefix>/share/tbdrsim/analysis or the checkout's analysis/; "
        "interpreter: $TBDRSIM_PYTHON or " << kDebianPython << ".\n";
  return os.str();
}

/// Runs `argv` (argv[0] a path) with its stdout and stderr copied to `out` and `err` as they come,
/// TBDRSIM_PLOT_PROG = `prog` in its environment (the name its messages start with); returns the
/// waitpid status.
int run_captured(const std::vector<std::string>& argv, const std::string& prog, std::ostream& out, std::ostream& err) {
  int pipes[2][2];
  if (pipe2(pipes[0], O_CLOEXEC) != 0 || pipe2(pipes[1], O_CLOEXEC) != 0) {
    throw std::runtime_error(std::string("pipe: ") + std::strerror(errno));
  }
  std::vector<char*> cargv;
  for (const auto& a : argv) cargv.push_back(const_cast<char*>(a.c_str()));
  cargv.push_back(nullptr);
  out.flush();
  err.flush();
  const pid_t pid = fork();
  if (pid < 0) throw std::runtime_error(std::string("fork: ") + std::strerror(errno));
  if (pid == 0) {
    dup2(pipes[0][1], STDOUT_FILENO);
    dup2(pipes[1][1], STDERR_FILENO);
    setenv("TBDRSIM_PLOT_PROG", prog.c_str(), 1);
    execv(cargv[0], cargv.data());
    const std::string msg = "tbdrsim plot: cannot execute " + argv[0] + ": " + std::strerror(errno) + "\n";
    (void)!write(STDERR_FILENO, msg.data(), msg.size());
    _exit(127);
  }
  close(pipes[0][1]);
  close(pipes[1][1]);
  pollfd fds[2] = {{pipes[0][0], POLLIN, 0}, {pipes[1][0], POLLIN, 0}};
  std::ostream* sinks[2] = {&out, &err};
  int open_fds = 2;
  char buf[4096];
  while (open_fds > 0) {
    if (poll(fds, 2, -1) < 0) {
      if (errno == EINTR) continue;
      break;
    }
    for (int i = 0; i < 2; ++i) {
      if (fds[i].fd < 0 || !(fds[i].revents & (POLLIN | POLLHUP | POLLERR))) continue;
      const ssize_t n = read(fds[i].fd, buf, sizeof buf);
      if (n > 0) {
        sinks[i]->write(buf, n);
        sinks[i]->flush();
      } else if (n == 0 || errno != EINTR) {
        close(fds[i].fd);
        fds[i].fd = -1;
        --open_fds;
      }
    }
  }
  int status = 0;
  while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  return status;
}

}  // namespace

int cmd_plot(const std::vector<std::string>& args, std::ostream& out, std::ostream& err) {
  if (args.empty()) throw UsageError("tbdrsim plot: which plot? (a KIND)\n\n" + usage());
  const std::string& kind = args.front();
  if (kind == "--help" || kind == "-h" || kind == "help") {
    out << usage();
    return 0;
  }
  const PlotKind* chosen = nullptr;
  for (const auto& k : kPlotKinds) {
    if (kind == k.name) chosen = &k;
  }
  if (!chosen) throw UsageError("tbdrsim plot: unknown plot kind '" + kind + "'\n\n" + usage());

  std::optional<fs::path> script;
  std::string searched;
  for (const auto& dir : script_dirs()) {
    std::error_code ec;
    if (fs::is_regular_file(dir / chosen->script, ec)) {
      script = dir / chosen->script;
      break;
    }
    searched += (searched.empty() ? "" : ", ") + dir.string();
  }
  if (!script) throw InputError(chosen->script, "plot script not found (looked in " + searched + "; set TBDRSIM_ANALYSIS_DIR)");
  const std::string python = env_or("TBDRSIM_PYTHON", kDebianPython);
  {
    std::error_code ec;
    if (!fs::exists(python, ec)) {
      throw InputError(python, "no Python interpreter here (install python3, python3-pandas and python3-matplotlib: "
                               "scripts/install_deps.sh; or set TBDRSIM_PYTHON)");
    }
  }

  std::vector<std::string> argv = {python, script->string()};
  argv.insert(argv.end(), args.begin() + 1, args.end());
  const int status = run_captured(argv, std::string("tbdrsim plot ") + chosen->name, out, err);
  if (WIFEXITED(status)) return WEXITSTATUS(status);
  err << "tbdrsim plot: " << chosen->script << " ended by signal " << WTERMSIG(status) << "\n";
  return 1;
}

}  // namespace tbdr
