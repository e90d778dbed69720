#include "app/sweep.hpp"

#include <fcntl.h>
#include <glob.h>
#include <poll.h>
#include <signal.h>
#include <sqlite3.h>
#include <sys/prctl.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <map>
#include <ostream>
#include <set>
#include <sstream>

#include <boost/program_options/options_description.hpp>
#include <boost/program_options/parsers.hpp>

#include "analysis/report.hpp"
#include "models/hw_config.hpp"
#include "kernel/errors.hpp"
#include "analysis/results_db.hpp"
#include "trace/trace.hpp"
#include "tbdrsim_version.hpp"

namespace tbdr {

namespace fs = std::filesystem;

namespace {

std::string trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t\r\n");
  if (b == std::string::npos) return {};
  const auto e = s.find_last_not_of(" \t\r\n");
  return s.substr(b, e - b + 1);
}

std::vector<std::string> split_commas(const std::string& text) {
  std::vector<std::string> out;
  std::string cur;
  std::istringstream in(text);
  while (std::getline(in, cur, ',')) out.push_back(trim(cur));
  if (!text.empty() && text.back() == ',') out.push_back("");
  return out;
}

/// The message of an InputError without its "where: " prefix.
std::string bare_message(const InputError& e) {
  const std::string what = e.what();
  const std::string& where = e.where();
  if (!where.empty() && what.rfind(where + ": ", 0) == 0) return what.substr(where.size() + 2);
  return what;
}

/// A path written in the sweep file, relative to the sweep file's folder (absolute stays absolute).
std::string relative_to(const fs::path& base_dir, const std::string& p) {
  const fs::path path(p);
  if (path.is_absolute()) return path.lexically_normal().string();
  return (base_dir / path).lexically_normal().string();
}

bool has_glob_chars(const std::string& s) { return s.find_first_of("*?[") != std::string::npos; }

// ---------------------------------------------------------------------------------------------
// Ranges

bool is_integer_text(const std::string& s) {
  if (s.empty()) return false;
  std::size_t i = (s[0] == '-' || s[0] == '+') ? 1 : 0;
  if (i == s.size()) return false;
  for (; i < s.size(); ++i) {
    if (s[i] < '0' || s[i] > '9') return false;
  }
  return true;
}

bool parse_double(const std::string& s, double& v) {
  const std::string t = trim(s);
  if (t.empty()) return false;
  const char* b = t.data() + (t[0] == '+' ? 1 : 0);
  auto r = std::from_chars(b, t.data() + t.size(), v);
  return r.ec == std::errc{} && r.ptr == t.data() + t.size() && std::isfinite(v);
}

std::string format_number(double v, bool integer) {
  if (integer) return std::to_string(static_cast<long long>(std::llround(v)));
  // Round away accumulated binary noise (0.1 * 3 = 0.30000000000000004) before printing.
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.12g", v);
  double clean = 0;
  parse_double(buf, clean);
  auto r = std::to_chars(buf, buf + sizeof buf, clean);
  return std::string(buf, r.ptr);
}

constexpr std::size_t kMaxRangeValues = 100000;

std::vector<std::string> expand_range(const std::string& text, const std::string& where) {
  const auto dots = text.find("..");
  const std::string lo_text = trim(text.substr(0, dots));
  std::string rest = trim(text.substr(dots + 2));
  std::string hi_text = rest, op, by_text;
  // "A..B", "A..B step S", "A..B x F", "A..B *F"
  if (auto p = rest.find("step"); p != std::string::npos) {
    hi_text = trim(rest.substr(0, p));
    op = "step";
    by_text = trim(rest.substr(p + 4));
  } else if (auto q = rest.find_first_of("x*"); q != std::string::npos) {
    hi_text = trim(rest.substr(0, q));
    op = "x";
    by_text = trim(rest.substr(q + 1));
  }
  const std::string syntax = "expected a range A..B, A..B step S or A..B x F (geometric), e.g. 16..64 step 16 or 1..8 x 2";
  double lo = 0, hi = 0, by = op == "x" ? 2 : 1;
  if (!parse_double(lo_text, lo) || !parse_double(hi_text, hi) || (!op.empty() && !parse_double(by_text, by))) {
    throw InputError(where, "bad range '" + text + "': " + syntax);
  }
  if (hi < lo) throw InputError(where, "bad range '" + text + "': the end is below the start");
  if (op != "x" && by <= 0) throw InputError(where, "bad range '" + text + "': the step must be positive");
  if (op == "x" && (by <= 1 || lo <= 0)) {
    throw InputError(where, "bad range '" + text + "': a geometric range needs a start > 0 and a factor > 1");
  }
  const bool integer = is_integer_text(lo_text) && is_integer_text(hi_text) && (op.empty() || is_integer_text(by_text));
  std::vector<std::string> out;
  const double eps = 1e-9 * std::max({std::fabs(lo), std::fabs(hi), 1.0});
  for (std::size_t i = 0;; ++i) {
    const double v = op == "x" ? lo * std::pow(by, static_cast<double>(i)) : lo + static_cast<double>(i) * by;
    if (v > hi + eps) break;
    if (out.size() >= kMaxRangeValues) {
      throw InputError(where, "range '" + text + "' has more than " + std::to_string(kMaxRangeValues) + " values");
    }
    out.push_back(format_number(v, integer));
  }
  return out;
}

// ---------------------------------------------------------------------------------------------
// The sweep file

/// One "key = value" line of the sweep file with its section and line number.
struct SweepLine {
  std::string section;
  std::string name;   ///< the key within its section
  std::string full;   ///< section + "." + name, as Boost.Program_options reports it
  std::string value;
  long line = 0;
};

/// Scans the file like Boost.Program_options reads it ('#' comments, [section], key = value) to
/// keep line numbers; sections must be sweep, set, vary or zip.NAME.
std::vector<SweepLine> scan_sweep_file(const std::string& path, std::istream& in, std::map<std::string, long>& section_lines) {
  std::vector<SweepLine> out;
  std::map<std::string, long> seen;
  std::string line, section;
  long n = 0;
  while (std::getline(in, line)) {
    ++n;
    if (auto hash = line.find('#'); hash != std::string::npos) line.resize(hash);
    const std::string s = trim(line);
    if (s.empty()) continue;
    if (s.front() == '[') {
      if (s.back() != ']') throw InputError(path, n, "malformed section header '" + s + "' (expected [name])");
      section = trim(s.substr(1, s.size() - 2));
      const bool zip = section.rfind("zip.", 0) == 0 && section.size() > 4;
      if (section != "sweep" && section != "set" && section != "vary" && !zip) {
        throw InputError(path, n, "unknown section [" + section + "] (known: [sweep], [set], [vary], [zip.NAME])");
      }
      if (section_lines.count(section)) {
        throw InputError(path, n, "section [" + section + "] appears twice (first at line " +
                                      std::to_string(section_lines[section]) + ")");
      }
      section_lines[section] = n;
      continue;
    }
    const auto eq = s.find('=');
    if (eq == std::string::npos) throw InputError(path, n, "expected 'key = value' or '[section]', found '" + s + "'");
    if (section.empty()) throw InputError(path, n, "'" + s + "' is outside any section (start with [sweep])");
    const std::string name = trim(s.substr(0, eq));
    if (name.empty()) throw InputError(path, n, "missing key before '='");
    const std::string full = section + "." + name;
    const bool repeatable = section == "sweep" && (name == "config" || name == "trace");
    if (auto it = seen.find(full); it != seen.end() && !repeatable) {
      throw InputError(path, n, "key '" + name + "' set twice in [" + section + "] (first at line " +
                                    std::to_string(it->second) + ")");
    }
    seen[full] = n;
    out.push_back({section, name, full, trim(s.substr(eq + 1)), n});
  }
  return out;
}

/// Checks that `key` is a hardware parameter and `value` a valid value for it.
void check_param_value(const std::string& key, const std::string& value, const std::string& where) {
  const ParamTable& table = hw_params().table();
  ResolvedParams p = table.defaults();
  try {
    table.apply_override(p, key + "=" + value);
  } catch (const InputError& e) {
    throw InputError(where, bare_message(e));
  }
}

std::vector<std::string> expand_traces(const std::string& pattern, const fs::path& base_dir, const std::string& where) {
  const std::string p = relative_to(base_dir, pattern);
  if (!has_glob_chars(pattern)) {
    if (!fs::is_regular_file(p)) throw InputError(where, "trace file '" + p + "' not found");
    return {p};
  }
  glob_t g{};
  const int rc = ::glob(p.c_str(), 0, nullptr, &g);
  std::vector<std::string> out;
  if (rc == 0) {
    for (std::size_t i = 0; i < g.gl_pathc; ++i) {
      if (fs::is_regular_file(g.gl_pathv[i])) out.push_back(g.gl_pathv[i]);
    }
  }
  globfree(&g);
  if (out.empty()) throw InputError(where, "trace pattern '" + p + "' matches no file");
  return out;
}

}  // namespace

std::vector<std::string> expand_value_list(const std::string& text, const std::string& where) {
  if (trim(text).empty()) throw InputError(where, "empty value list");
  std::vector<std::string> out;
  for (const auto& item : split_commas(text)) {
    if (item.empty()) throw InputError(where, "empty item in the list '" + text + "'");
    if (item.find("..") != std::string::npos) {
      const auto r = expand_range(item, where);
      out.insert(out.end(), r.begin(), r.end());
    } else {
      out.push_back(item);
    }
  }
  std::set<std::string> seen;
  for (const auto& v : out) {
    if (!seen.insert(v).second) throw InputError(where, "value '" + v + "' listed twice in '" + text + "'");
  }
  return out;
}

SweepSpec parse_sweep_file(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InputError(path, "cannot open sweep file");
  std::map<std::string, long> section_lines;
  const std::vector<SweepLine> lines = scan_sweep_file(path, in, section_lines);

  // Boost.Program_options reads the values; the scan supplies line numbers and strictness.
  const std::vector<IniEntry> parsed = read_ini_entries(path, "sweep file", lines.size());

  SweepSpec spec;
  spec.path = path;
  spec.name = fs::path(path).stem().string();
  const fs::path base_dir = fs::path(path).parent_path();
  std::map<std::string, std::string> key_where;  // every key set or swept, for conflicts
  std::map<std::string, std::size_t> zip_axis;   // zip group -> axis index
  bool have_reps = false;
  for (std::size_t i = 0; i < lines.size(); ++i) {
    const SweepLine& l = lines[i];
    const std::string where = path + ":" + std::to_string(l.line);
    if (parsed[i].key != l.full) throw InputError(where, "sweep file parse mismatch at key '" + l.name + "'");
    const std::string value = trim(parsed[i].value);

    if (l.section == "sweep") {
      if (l.name == "name") {
        if (value.empty()) throw InputError(where, "empty name");
        spec.name = value;
      } else if (l.name == "config") {
        for (const auto& item : split_commas(value)) {
          if (item.empty()) throw InputError(where, "empty config file name");
          const std::string p = relative_to(base_dir, item);
          if (!fs::is_regular_file(p)) throw InputError(where, "config file '" + p + "' not found");
          spec.base_configs.push_back(p);
        }
      } else if (l.name == "trace") {
        for (const auto& item : split_commas(value)) {
          if (item.empty()) throw InputError(where, "empty trace name");
          const auto t = expand_traces(item, base_dir, where);
          spec.traces.insert(spec.traces.end(), t.begin(), t.end());
        }
      } else if (l.name == "repetitions") {
        int reps = 0;
        auto r = std::from_chars(value.data(), value.data() + value.size(), reps);
        if (value.empty() || r.ec != std::errc{} || r.ptr != value.data() + value.size() || reps < 1 || reps > 1000) {
          throw InputError(where, "repetitions = '" + value + "': expected an integer in [1, 1000]");
        }
        spec.repetitions = reps;
        have_reps = true;
      } else {
        throw InputError(where, "unknown key '" + l.name + "' in [sweep] (known: name, config, trace, repetitions)");
      }
      continue;
    }

    // [set], [vary], [zip.NAME]: the key is a parameter, or "config" (a config file axis).
    if (auto it = key_where.find(l.name); it != key_where.end()) {
      throw InputError(where, "'" + l.name + "' is already set or swept at " + it->second);
    }
    key_where[l.name] = where;
    if (l.section == "set") {
      if (l.name == "config") throw InputError(where, "config files go in [sweep] (config = FILE) or [vary] (config = A, B)");
      check_param_value(l.name, value, where);
      spec.sets.push_back(l.name + "=" + value);
      spec.set_where.push_back(where);
      continue;
    }
    // Config file lists are plain lists (paths may contain ".."); parameters take ranges too.
    std::vector<std::string> values = l.name == "config" ? split_commas(value) : expand_value_list(value, where);
    if (l.name == "config") {
      std::set<std::string> seen;
      for (const auto& v : values) {
        if (v.empty()) throw InputError(where, "empty config file name in '" + value + "'");
        if (!seen.insert(v).second) throw InputError(where, "config file '" + v + "' listed twice");
      }
    }
    for (auto& v : values) {
      if (l.name == "config") {
        v = relative_to(base_dir, v);
        if (!fs::is_regular_file(v)) throw InputError(where, "config file '" + v + "' not found");
      } else {
        check_param_value(l.name, v, where);
      }
    }
    if (l.section == "vary") {
      SweepAxis axis;
      axis.name = l.name;
      axis.keys = {l.name};
      for (auto& v : values) axis.values.push_back({v});
      axis.where = {where};
      spec.axes.push_back(std::move(axis));
      continue;
    }
    // zip group
    auto z = zip_axis.find(l.section);
    if (z == zip_axis.end()) {
      SweepAxis axis;
      axis.name = l.section;
      axis.values.resize(values.size());
      z = zip_axis.emplace(l.section, spec.axes.size()).first;
      spec.axes.push_back(std::move(axis));
    }
    SweepAxis& axis = spec.axes[z->second];
    if (values.size() != axis.values.size()) {
      throw InputError(where, "[" + l.section + "] '" + l.name + "' has " + std::to_string(values.size()) +
                                  " values but '" + axis.keys.front() + "' (" + axis.where.front() + ") has " +
                                  std::to_string(axis.values.size()) + "; zipped keys need lists of equal length");
    }
    axis.keys.push_back(l.name);
    axis.where.push_back(where);
    for (std::size_t v = 0; v < values.size(); ++v) axis.values[v].push_back(values[v]);
  }
  (void)have_reps;
  if (!section_lines.count("sweep")) throw InputError(path, "no [sweep] section (it names the traces)");
  if (spec.traces.empty()) {
    throw InputError(path, section_lines["sweep"], "[sweep] names no trace (trace = FILE or GLOB, repeatable)");
  }
  for (const auto& [sec, line] : section_lines) {
    if (sec.rfind("zip.", 0) == 0 && !zip_axis.count(sec)) throw InputError(path, line, "[" + sec + "] is empty");
  }
  return spec;
}

std::vector<SweepPoint> expand_sweep(const SweepSpec& spec) {
  std::size_t combos = 1;
  for (const auto& a : spec.axes) combos *= a.values.size();
  std::vector<SweepPoint> points;
  points.reserve(combos * spec.traces.size() * static_cast<std::size_t>(spec.repetitions));
  std::vector<std::size_t> digit(spec.axes.size(), 0);
  std::size_t group = 0;
  for (std::size_t c = 0; c < combos; ++c) {
    // Mixed-radix decode, the last axis fastest.
    std::size_t rest = c;
    for (std::size_t a = spec.axes.size(); a-- > 0;) {
      digit[a] = rest % spec.axes[a].values.size();
      rest /= spec.axes[a].values.size();
    }
    std::vector<std::string> configs = spec.base_configs;
    std::vector<std::string> sets = spec.sets;
    std::string label;
    for (std::size_t a = 0; a < spec.axes.size(); ++a) {
      const auto& axis = spec.axes[a];
      for (std::size_t k = 0; k < axis.keys.size(); ++k) {
        const std::string& v = axis.values[digit[a]][k];
        if (axis.keys[k] == "config") {
          configs.push_back(v);
          label += (label.empty() ? "" : " ") + std::string("config=") + fs::path(v).filename().string();
        } else {
          sets.push_back(axis.keys[k] + "=" + v);
          label += (label.empty() ? "" : " ") + axis.keys[k] + "=" + v;
        }
      }
    }
    for (const auto& trace : spec.traces) {
      for (int r = 0; r < spec.repetitions; ++r) {
        SweepPoint p;
        p.index = points.size();
        p.group = group;
        p.repetition = r;
        p.configs = configs;
        p.sets = sets;
        p.trace = trace;
        p.label = (label.empty() ? "" : label + " | ") + fs::path(trace).filename().string();
        if (spec.repetitions > 1) p.label += " #" + std::to_string(r + 1);
        points.push_back(std::move(p));
      }
      ++group;
    }
  }
  return points;
}

SweepSlice parse_slice(const std::string& text) {
  const auto slash = text.find('/');
  SweepSlice s;
  auto num = [](const std::string& t, int& v) {
    auto r = std::from_chars(t.data(), t.data() + t.size(), v);
    return !t.empty() && r.ec == std::errc{} && r.ptr == t.data() + t.size();
  };
  if (slash == std::string::npos || !num(text.substr(0, slash), s.index) || !num(text.substr(slash + 1), s.count) ||
      s.count < 1 || s.index < 0 || s.index >= s.count) {
    throw InputError("--slice " + text, "expected i/K with 0 <= i < K, e.g. 0/4");
  }
  return s;
}

std::vector<SweepPoint> slice_points(const std::vector<SweepPoint>& points, SweepSlice slice) {
  std::vector<SweepPoint> out;
  for (const auto& p : points) {
    if (p.group % static_cast<std::size_t>(slice.count) == static_cast<std::size_t>(slice.index)) out.push_back(p);
  }
  return out;
}

std::string self_executable() {
  std::error_code ec;
  const fs::path p = fs::read_symlink("/proc/self/exe", ec);
  return ec ? std::string("tbdrsim") : p.string();
}

// ---------------------------------------------------------------------------------------------
// Running a sweep

namespace {

volatile sig_atomic_t g_interrupts = 0;
volatile sig_atomic_t g_terminate = 0;

extern "C" void on_sigint(int) { g_interrupts = g_interrupts + 1; }
extern "C" void on_sigterm(int) { g_terminate = 1; }

/// Installs the sweep's SIGINT/SIGTERM handlers for its lifetime and restores the old ones.
class SignalScope {
 public:
  SignalScope() {
    g_interrupts = 0;
    g_terminate = 0;
    struct sigaction sa {};
    sa.sa_handler = on_sigint;
    sigemptyset(&sa.sa_mask);
    sa.sa_flags = 0;  // no SA_RESTART: poll() returns EINTR at once
    sigaction(SIGINT, &sa, &old_int_);
    sa.sa_handler = on_sigterm;
    sigaction(SIGTERM, &sa, &old_term_);
  }
  ~SignalScope() {
    sigaction(SIGINT, &old_int_, nullptr);
    sigaction(SIGTERM, &old_term_, nullptr);
  }
  SignalScope(const SignalScope&) = delete;
  SignalScope& operator=(const SignalScope&) = delete;

 private:
  struct sigaction old_int_ {};
  struct sigaction old_term_ {};
};

/// The resolved configuration of a point (shared by the points of one configuration).
struct PointConfig {
  ResolvedConfig config;
};

/// What the parent knows of a trace without simulating it.
struct TraceInfo {
  std::string hash;
  std::string technique;
  std::string scene;
};

/// A running worker process.
struct Worker {
  pid_t pid = -1;
  int err_fd = -1;
  std::string err_text;
  const SweepPoint* point = nullptr;
  const PointConfig* config = nullptr;
  const TraceInfo* trace = nullptr;
  std::string command_line;
  std::string started_at;
  std::chrono::steady_clock::time_point start;
  bool killed = false;
};

std::string config_key(const SweepPoint& p) {
  std::string k;
  for (const auto& c : p.configs) k += "c:" + c + "\n";
  for (const auto& s : p.sets) k += "s:" + s + "\n";
  return k;
}

std::string format_duration(double s) {
  if (!std::isfinite(s) || s < 0) return "?";
  const long t = std::lround(s);
  char buf[32];
  if (t >= 3600) {
    std::snprintf(buf, sizeof buf, "%ld:%02ld:%02ld", t / 3600, (t / 60) % 60, t % 60);
  } else {
    std::snprintf(buf, sizeof buf, "%ld:%02ld", t / 60, t % 60);
  }
  return buf;
}

std::string signal_text(int sig) {
  const char* d = strsignal(sig);
  return "killed by signal " + std::to_string(sig) + (d ? std::string(" (") + d + ")" : std::string());
}

/// Number of finished runs of this configuration and trace already in the database.
std::int64_t count_ok_runs(SqlQuery& q, const std::string& config_hash, const std::string& trace_hash) {
  q.reset();
  q.bind(1, config_hash).bind(2, trace_hash);
  const std::int64_t n = q.step() ? q.int64(0) : 0;
  q.reset();
  return n;
}

/// Starts `tbdrsim run` for one point: its own process group (a terminal Ctrl-C reaches only the
/// sweep, which decides), killed if the sweep dies, stdout to /dev/null, stderr to a pipe.
Worker spawn_worker(const std::vector<std::string>& argv_strings) {
  int fds[2];
  if (pipe2(fds, O_CLOEXEC) != 0) throw std::runtime_error(std::string("pipe: ") + std::strerror(errno));
  std::vector<char*> argv;
  for (const auto& a : argv_strings) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  const pid_t parent = getpid();
  const pid_t pid = fork();
  if (pid < 0) {
    close(fds[0]);
    close(fds[1]);
    throw std::runtime_error(std::string("fork: ") + std::strerror(errno));
  }
  if (pid == 0) {
    // Child: only async-signal-safe calls until exec.
    setpgid(0, 0);
    prctl(PR_SET_PDEATHSIG, SIGKILL);
    if (getppid() != parent) _exit(127);
    signal(SIGINT, SIG_DFL);
    signal(SIGTERM, SIG_DFL);
    const int devnull = open("/dev/null", O_RDWR);
    if (devnull >= 0) {
      dup2(devnull, STDIN_FILENO);
      dup2(devnull, STDOUT_FILENO);
    }
    dup2(fds[1], STDERR_FILENO);
    execv(argv[0], argv.data());
    const char msg[] = "cannot execute the tbdrsim binary\n";
    (void)!write(STDERR_FILENO, msg, sizeof msg - 1);
    _exit(127);
  }
  close(fds[1]);
  fcntl(fds[0], F_SETFL, fcntl(fds[0], F_GETFL) | O_NONBLOCK);
  Worker w;
  w.pid = pid;
  w.err_fd = fds[0];
  return w;
}

/// Reads what is available on a worker's stderr; false at end of file.
bool drain(Worker& w) {
  char buf[4096];
  for (;;) {
    const ssize_t n = read(w.err_fd, buf, sizeof buf);
    if (n > 0) {
      w.err_text.append(buf, static_cast<std::size_t>(n));
      if (w.err_text.size() > 64 * 1024) w.err_text.erase(0, w.err_text.size() - 64 * 1024);
      continue;
    }
    if (n == 0) return false;
    if (errno == EINTR) continue;
    return true;  // EAGAIN
  }
}

std::string shell_quote(const std::string& s) {
  if (!s.empty() && s.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_-./=:,+@%") ==
                        std::string::npos) {
    return s;
  }
  std::string q = "'";
  for (char c : s) {
    if (c == '\'') {
      q += "'\\''";
    } else {
      q += c;
    }
  }
  return q + "'";
}

/// Shows progress: a redrawn bar on a terminal, one line per finished point otherwise.
class Progress {
 public:
  Progress(SweepProgress mode, std::ostream& out, std::size_t total, std::size_t skipped)
      : mode_(mode), out_(out), total_(total), done_(skipped), start_(std::chrono::steady_clock::now()) {}

  void finished(const SweepPoint& p, bool ok, double seconds, const std::string& error) {
    ++done_;
    ++ran_;
    if (!ok) ++failed_;
    if (mode_ == SweepProgress::None) return;
    if (mode_ == SweepProgress::Bar) {
      if (!ok) {
        clear_bar();
        out_ << "FAILED " << p.label << ": " << first_line(error) << "\n";
      }
      draw(true);
      return;
    }
    char head[64];
    std::snprintf(head, sizeof head, "[%*zu/%zu] ", static_cast<int>(std::to_string(total_).size()), done_, total_);
    out_ << head << (ok ? "ok     " : "FAILED ") << std::fixed << std::setprecision(2) << seconds << " s  " << p.label;
    out_ << "  (" << rate_text() << ", ETA " << eta_text() << ")";
    if (!ok) out_ << "\n    " << first_line(error);
    out_ << "\n" << std::flush;
  }

  void skipped() {
    ++done_;
    draw(true);
  }

  void message(const std::string& text) {
    if (mode_ == SweepProgress::None) return;
    clear_bar();
    out_ << text << "\n";
    draw(true);
  }

  /// Redraws the bar at most ten times a second (or at once when forced).
  void set_running(std::size_t running) { running_ = running; }

  void draw(bool force) {
    if (mode_ != SweepProgress::Bar) return;
    const auto now = std::chrono::steady_clock::now();
    if (!force && now - last_draw_ < std::chrono::milliseconds(100)) return;
    last_draw_ = now;
    constexpr int kWidth = 30;
    const double frac = total_ ? static_cast<double>(done_) / static_cast<double>(total_) : 1.0;
    const int filled = static_cast<int>(frac * kWidth);
    std::string bar(static_cast<std::size_t>(filled), '#');
    bar += std::string(static_cast<std::size_t>(kWidth - filled), '.');
    out_ << "\r\033[K[" << bar << "] " << done_ << "/" << total_;
    if (failed_) out_ << "  " << failed_ << " failed";
    out_ << "  " << running_ << " running  " << rate_text() << "  ETA " << eta_text() << std::flush;
    drawn_ = true;
  }

  void end() {
    if (mode_ == SweepProgress::Bar && drawn_) {
      draw(true);
      out_ << "\n";
      drawn_ = false;
    }
  }

 private:
  static std::string first_line(const std::string& s) {
    std::string t = trim(s);
    const auto nl = t.find('\n');
    return nl == std::string::npos ? t : t.substr(0, nl) + " ...";
  }
  double elapsed() const { return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count(); }
  std::string rate_text() const {
    char buf[48];
    std::snprintf(buf, sizeof buf, "%.2f points/s", ran_ ? static_cast<double>(ran_) / elapsed() : 0.0);
    return buf;
  }
  std::string eta_text() const {
    if (!ran_) return "?";
    const double rate = static_cast<double>(ran_) / elapsed();
    return format_duration(static_cast<double>(total_ - done_) / rate);
  }
  void clear_bar() {
    if (mode_ == SweepProgress::Bar && drawn_) out_ << "\r\033[K";
  }

  SweepProgress mode_;
  std::ostream& out_;
  std::size_t total_, done_, ran_ = 0, failed_ = 0, running_ = 0;
  std::chrono::steady_clock::time_point start_, last_draw_{};
  bool drawn_ = false;
};

}  // namespace

namespace {

/// Kills and reaps the workers still running when run_sweep leaves by an exception.
class WorkerGuard {
 public:
  explicit WorkerGuard(std::vector<Worker>& running) : running_(running) {}
  ~WorkerGuard() {
    for (auto& w : running_) {
      kill(w.pid, SIGKILL);
      waitpid(w.pid, nullptr, 0);
      close(w.err_fd);
    }
  }
  WorkerGuard(const WorkerGuard&) = delete;
  WorkerGuard& operator=(const WorkerGuard&) = delete;

 private:
  std::vector<Worker>& running_;
};

}  // namespace

SweepSummary run_sweep(const SweepSpec& spec, const SweepOptions& opt, std::ostream& out) {
  const auto t0 = std::chrono::steady_clock::now();
  SweepSummary summary;
  const std::vector<SweepPoint> all = expand_sweep(spec);
  const std::vector<SweepPoint> points = slice_points(all, opt.slice);
  summary.points = points.size();
  if (opt.jobs < 1 || opt.jobs > 1024) throw InputError("-j " + std::to_string(opt.jobs), "expected 1..1024 worker processes");
  const std::string binary = opt.binary.empty() ? self_executable() : opt.binary;
  if (!opt.dry_run && access(binary.c_str(), X_OK) != 0) {
    throw InputError(binary, "the tbdrsim binary for the workers is not executable");
  }

  // Resolve every configuration and read every trace first: bad input stops the sweep before
  // anything runs, and the hashes identify points already in the database.
  std::map<std::string, PointConfig> configs;
  std::map<std::string, TraceInfo> traces;
  std::vector<const PointConfig*> point_config(points.size());
  std::vector<const TraceInfo*> point_trace(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    const SweepPoint& p = points[i];
    const std::string key = config_key(p);
    auto it = configs.find(key);
    if (it == configs.end()) {
      PointConfig pc;
      try {
        pc.config = resolve_config(p.configs, p.sets);
      } catch (const InputError& e) {
        throw InputError(spec.path, "point '" + p.label + "': " + std::string(e.what()));
      }
      it = configs.emplace(key, std::move(pc)).first;
    }
    point_config[i] = &it->second;
    auto tt = traces.find(p.trace);
    if (tt == traces.end()) {
      const Trace trace = read_trace(p.trace);
      TraceInfo info;
      info.hash = trace_hash(trace);
      info.technique = trace.technique.empty() ? "custom" : trace.technique;
      info.scene = trace.scene.kind == SceneKind::Atrium ? "atrium:" + std::to_string(trace.scene.detail) : trace.scene.path;
      tt = traces.emplace(p.trace, std::move(info)).first;
    }
    point_trace[i] = &tt->second;
  }

  ResultsDb db(opt.db_path);
  SqlQuery count_q(db.handle(), db.path(),
                   "SELECT count(*) FROM runs WHERE config_hash = ? AND trace_hash = ? AND status = 'ok'");
  auto already_done = [&](std::size_t i) {
    return count_ok_runs(count_q, point_config[i]->config.hash, point_trace[i]->hash) > points[i].repetition;
  };
  std::vector<std::size_t> todo;
  std::vector<bool> done_before(points.size(), false);
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (already_done(i)) {
      ++summary.skipped;
      done_before[i] = true;
    } else {
      todo.push_back(i);
    }
  }
  const std::size_t distinct_configs = configs.size();
  out << "sweep " << spec.name << ": " << points.size() << " point(s)";
  if (opt.slice.count > 1) out << " in slice " << opt.slice.index << "/" << opt.slice.count << " (of " << all.size() << ")";
  out << " (" << distinct_configs << " configuration(s) x " << traces.size() << " trace(s)";
  if (spec.repetitions > 1) out << " x " << spec.repetitions << " repetitions";
  out << "), " << summary.skipped << " already in " << opt.db_path << ", " << todo.size() << " to run";
  if (!opt.dry_run) out << " with " << opt.jobs << " worker(s)";
  out << "\n" << std::flush;

  if (opt.dry_run) {
    for (std::size_t i = 0; i < points.size(); ++i) {
      const bool done = done_before[i];
      out << "  " << std::setw(5) << points[i].index << "  " << (done ? "done  " : "to run") << "  "
          << points[i].label << "  (config " << point_config[i]->config.hash << ", trace " << point_trace[i]->hash << ")\n";
    }
    summary.not_run = todo.size();
    return summary;
  }

  SignalScope signals;
  Progress progress(opt.progress, out, points.size(), summary.skipped);
  std::vector<Worker> running;
  WorkerGuard guard(running);
  std::size_t next = 0;
  bool stopping = false, killing = false;
  int announced_interrupts = 0;

  auto kill_all = [&]() {
    for (auto& w : running) {
      if (!w.killed) {
        kill(w.pid, SIGKILL);
        w.killed = true;
      }
    }
  };

  auto finish = [&](Worker& w, int status) {
    while (drain(w)) {
    }
    close(w.err_fd);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - w.start).count();
    if (w.killed) {
      ++summary.not_run;
      return;
    }
    const bool ok = WIFEXITED(status) && WEXITSTATUS(status) == 0;
    std::string error;
    if (!ok) {
      error = trim(w.err_text);
      if (WIFSIGNALED(status)) {
        error = signal_text(WTERMSIG(status)) + (error.empty() ? "" : ": " + error);
      } else if (error.empty()) {
        error = "tbdrsim run exited with code " + std::to_string(WEXITSTATUS(status));
      }
      if (error.rfind("error: ", 0) == 0) error = error.substr(7);
      RunRecord rec;
      rec.started_at = w.started_at;
      rec.finished_at = utc_now_iso8601();
      rec.tool_version = kToolVersion;
      rec.host = host_name();
      rec.command_line = w.command_line;
      rec.config_name = w.config->config.params.config_name;
      rec.config_hash = w.config->config.hash;
      rec.trace_path = w.point->trace;
      rec.trace_hash = w.trace->hash;
      rec.scene = w.trace->scene;
      rec.technique = w.trace->technique;
      rec.status = "failed";
      rec.error = error;
      const auto& table = hw_params().table();
      for (std::size_t i = 0; i < table.decls().size(); ++i) {
        rec.params.push_back({table.decls()[i].key, format_param_value(w.config->config.params.values[i]),
                              w.config->config.params.origins[i].text});
      }
      db.write_run(rec);
      ++summary.failed;
    } else {
      ++summary.ok;
    }
    progress.finished(*w.point, ok, seconds, error);
  };

  while (true) {
    if (g_terminate || g_interrupts >= 2) {
      if (!killing) {
        killing = true;
        stopping = true;
        progress.message("stopping: killing " + std::to_string(running.size()) + " running point(s); finished runs are kept");
      }
      kill_all();
    } else if (g_interrupts >= 1 && announced_interrupts == 0) {
      announced_interrupts = 1;
      stopping = true;
      progress.message("stopping: waiting for " + std::to_string(running.size()) +
                       " running point(s) to finish (Ctrl-C again to kill them)");
    }
    // Launch.
    while (!stopping && running.size() < static_cast<std::size_t>(opt.jobs) && next < todo.size()) {
      const std::size_t i = todo[next++];
      if (already_done(i)) {  // another sweep on the same database finished it meanwhile
        ++summary.skipped;
        progress.skipped();
        continue;
      }
      const SweepPoint& p = points[i];
      std::vector<std::string> args = {binary, "run"};
      for (const auto& c : p.configs) {
        args.push_back("--config");
        args.push_back(c);
      }
      for (const auto& s : p.sets) {
        args.push_back("--set");
        args.push_back(s);
      }
      args.insert(args.end(), {"--trace", p.trace, "--db", opt.db_path, "--quiet"});
      Worker w = spawn_worker(args);
      w.point = &p;
      w.config = point_config[i];
      w.trace = point_trace[i];
      for (std::size_t a = 0; a < args.size(); ++a) w.command_line += (a ? " " : "") + shell_quote(args[a]);
      w.started_at = utc_now_iso8601();
      w.start = std::chrono::steady_clock::now();
      running.push_back(std::move(w));
    }
    progress.set_running(running.size());
    if (running.empty()) break;
    progress.draw(false);

    std::vector<pollfd> fds;
    for (const auto& w : running) fds.push_back({w.err_fd, POLLIN, 0});
    const int rc = poll(fds.data(), fds.size(), 100);
    if (rc > 0) {
      for (std::size_t k = 0; k < running.size(); ++k) {
        if (fds[k].revents) drain(running[k]);
      }
    }
    // Reap.
    for (std::size_t k = 0; k < running.size();) {
      int status = 0;
      const pid_t r = waitpid(running[k].pid, &status, WNOHANG);
      if (r == running[k].pid) {
        Worker done = std::move(running[k]);  // reaped: no longer the guard's to kill
        running.erase(running.begin() + static_cast<std::ptrdiff_t>(k));
        progress.set_running(running.size());
        finish(done, status);
      } else {
        ++k;
      }
    }
  }
  summary.not_run += todo.size() - next;
  summary.interrupted = g_interrupts > 0 || g_terminate;
  summary.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  progress.end();
  const std::size_t ran = summary.ok + summary.failed;
  out << "sweep " << spec.name << ": " << summary.ok << " ok, " << summary.failed << " failed, " << summary.skipped
      << " already done";
  if (summary.not_run) out << ", " << summary.not_run << " not run";
  out << " in " << std::fixed << std::setprecision(1) << summary.seconds << " s";
  if (ran) out << " (" << std::setprecision(2) << static_cast<double>(ran) / summary.seconds << " points/s)";
  out << (summary.interrupted ? "; interrupted: run the same command again to finish" : "") << "\n";
  out.unsetf(std::ios::floatfield);
  return summary;
}

// ---------------------------------------------------------------------------------------------
// Slurm

std::string write_slurm_job(const SweepSpec& spec, const std::string& dir, int slices, int jobs, const std::string& binary) {
  if (slices < 1 || slices > 100000) throw InputError("--slices " + std::to_string(slices), "expected 1..100000");
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (!fs::is_directory(dir)) throw InputError(dir, "cannot create the Slurm job folder");
  const std::string adir = fs::absolute(dir).lexically_normal().string();
  const std::string asweep = fs::absolute(spec.path).lexically_normal().string();
  const std::string abin = fs::absolute(binary.empty() ? self_executable() : binary).lexically_normal().string();
  std::string safe_name;
  for (char c : spec.name) safe_name += std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_' ? c : '_';
  const std::string script = (fs::path(adir) / (safe_name + ".sbatch")).string();
  const std::string merge = shell_quote(abin) + " merge " + shell_quote(adir + "/merged.db") + " " +
                            shell_quote(adir) + "/shard_*.db";
  const std::size_t points = expand_sweep(spec).size();
  std::ofstream f(script);
  f << "#!/bin/bash\n"
    << "# tbdrsim sweep '" << spec.name << "' (" << points << " points) as a Slurm job array of " << slices
    << " tasks.\n"
    << "# Array task i runs every " << slices << "-th point group from offset i (tbdrsim sweep --slice i/" << slices
    << ")\n"
    << "# into its own database " << adir << "/shard_i.db; a task that is re-run skips what its shard holds.\n"
    << "# Submit:            sbatch " << shell_quote(script) << "\n"
    << "# When all are done: " << merge << "\n"
    << "#SBATCH --job-name=tbdrsim-" << safe_name << "\n"
    << "#SBATCH --array=0-" << slices - 1 << "\n"
    << "#SBATCH --cpus-per-task=" << jobs << "\n"
    << "#SBATCH --output=" << adir << "/slurm-%A_%a.out\n"
    << "set -euo pipefail\n"
    << "TBDRSIM=${TBDRSIM:-" << shell_quote(abin) << "}\n"
    << "TASK=${SLURM_ARRAY_TASK_ID:?run this script with sbatch (it is a job array)}\n"
    << "exec \"$TBDRSIM\" sweep " << shell_quote(asweep) << " --slice \"${TASK}/" << slices << "\" \\\n"
    << "  --db " << shell_quote(adir) << "/shard_\"${TASK}\".db -j \"${SLURM_CPUS_PER_TASK:-" << jobs
    << "}\" --progress lines\n";
  f.close();
  if (!f) throw InputError(script, "cannot write the Slurm script");
  fs::permissions(script, fs::perms::owner_exec | fs::perms::group_exec | fs::perms::others_exec, fs::perm_options::add, ec);
  std::ofstream readme(fs::path(adir) / "README.md");
  readme << "# Slurm job for the tbdrsim sweep '" << spec.name << "'\n\n"
         << "Submit: `sbatch " << script << "` (" << slices << " array tasks; task i writes `shard_i.db` here).\n\n"
         << "Merge the shards when every task has finished (re-running a task resumes it):\n\n"
         << "    " << merge << "\n";
  return script;
}

// ---------------------------------------------------------------------------------------------
// Merging shards

std::vector<MergeShardResult> merge_databases(const std::string& out_path, const std::vector<std::string>& shards) {
  if (shards.empty()) throw InputError("merge", "no shard databases given");
  std::vector<MergeShardResult> results;
  ResultsDb out(out_path);
  sqlite3* h = out.handle();
  for (const auto& shard : shards) {
    if (!fs::is_regular_file(shard)) throw InputError(shard, "no such shard database");
    std::error_code ec;
    if (fs::equivalent(shard, out_path, ec)) throw InputError(shard, "is the output database itself");
    { ResultsDb check(shard); }  // a tbdrsim database (migrated to this version), or an InputError
    MergeShardResult res;
    res.shard = shard;
    {
      SqlQuery attach(h, out_path, "ATTACH DATABASE ? AS shard");
      attach.bind(1, shard);
      attach.step();
    }
    try {
      out.exec("BEGIN IMMEDIATE");
      try {
        // Finished runs already in the output, per (config_hash, trace_hash).
        std::map<std::pair<std::string, std::string>, std::int64_t> have_ok;
        {
          SqlQuery q(h, out_path, "SELECT config_hash, trace_hash, count(*) FROM main.runs WHERE status = 'ok' GROUP BY 1, 2");
          while (q.step()) have_ok[{q.text(0), q.text(1)}] = q.int64(2);
        }
        SqlQuery same(h, out_path,
                      "SELECT 1 FROM main.runs WHERE config_hash = ? AND trace_hash = ? AND status = ? AND "
                      "started_at = ? AND host = ? AND error = ? LIMIT 1");
        SqlQuery copy_run(h, out_path,
                          "INSERT INTO main.runs(started_at, finished_at, tool_version, host, command_line, "
                          "config_name, config_hash, trace_path, trace_hash, scene, technique, status, error) "
                          "SELECT started_at, finished_at, tool_version, host, command_line, config_name, config_hash, "
                          "trace_path, trace_hash, scene, technique, status, error FROM shard.runs WHERE id = ?");
        SqlQuery copy_params(h, out_path,
                             "INSERT INTO main.run_params(run_id, key, value, origin) SELECT ?, key, value, origin "
                             "FROM shard.run_params WHERE run_id = ? ORDER BY rowid");
        SqlQuery copy_stats(h, out_path,
                            "INSERT INTO main.stats(run_id, scope, name, value, unit) SELECT ?, scope, name, value, unit "
                            "FROM shard.stats WHERE run_id = ? ORDER BY rowid");
        SqlQuery copy_tiles(h, out_path,
                            "INSERT INTO main.tile_stats(run_id, pass, tile_x, tile_y, cycles, samples, dram_bytes) "
                            "SELECT ?, pass, tile_x, tile_y, cycles, samples, dram_bytes FROM shard.tile_stats "
                            "WHERE run_id = ? ORDER BY rowid");
        SqlQuery runs(h, out_path,
                      "SELECT id, config_hash, trace_hash, status, started_at, host, error FROM shard.runs ORDER BY id");
        while (runs.step()) {
          const std::int64_t id = runs.int64(0);
          const std::pair<std::string, std::string> key{runs.text(1), runs.text(2)};
          const std::string status = runs.text(3);
          bool duplicate = false;
          if (status == "ok") {
            auto& n = have_ok[key];
            if (n > 0) {
              --n;
              duplicate = true;
            }
          } else {
            same.reset();
            same.bind(1, key.first).bind(2, key.second).bind(3, status).bind(4, runs.text(4)).bind(5, runs.text(5));
            same.bind(6, runs.text(6));
            duplicate = same.step();
          }
          if (duplicate) {
            ++res.duplicates;
            continue;
          }
          copy_run.reset();
          copy_run.bind(1, id);
          copy_run.step();
          const std::int64_t new_id = sqlite3_last_insert_rowid(h);
          for (SqlQuery* q : {&copy_params, &copy_stats, &copy_tiles}) {
            q->reset();
            q->bind(1, new_id).bind(2, id);
            q->step();
          }
          ++res.copied;
        }
        out.exec(
            "INSERT INTO main.stat_defs(name, unit, description) SELECT name, unit, description FROM shard.stat_defs "
            "WHERE true ON CONFLICT(name) DO NOTHING");
        out.exec("COMMIT");
      } catch (...) {
        sqlite3_exec(h, "ROLLBACK", nullptr, nullptr, nullptr);
        throw;
      }
    } catch (...) {
      sqlite3_exec(h, "DETACH DATABASE shard", nullptr, nullptr, nullptr);
      throw;
    }
    out.exec("DETACH DATABASE shard");
    results.push_back(res);
  }
  return results;
}

}  // namespace tbdr
