#include "app/sweep.hpp"

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <algorithm>
#include <chrono>
#include <cstring>
#include <filesystem>
#include <iomanip>
#include <map>
#include <optional>
#include <ostream>
#include <set>
#include <sstream>

#include "analysis/results_db.hpp"
#include "analysis/sql.hpp"
#include "app/commands.hpp"
#include "app/run_driver.hpp"
#include "app/worker_pool.hpp"
#include "kernel/errors.hpp"
#include "models/config_checks.hpp"
#include "models/hw_config.hpp"
#include "tbdrsim_version.hpp"
#include "techniques/technique.hpp"
#include "trace/trace.hpp"

namespace tbdr {

namespace {

/// What the parent knows of a trace without simulating it.
struct TraceInfo {
  std::string hash;
  std::string technique;
  std::string scene;
  std::size_t scene_draws = 0;  ///< `draw scene` commands: what a point's replay time grows with
};

/// A trace that draws the scene at least this many times is announced as slow before the sweep
/// runs. The single-pass and deferred techniques draw it 1 to 3 times (depth pre-pass, G-buffer or
/// shading pass, blended geometry); replaying a frame walks the scene's triangles through geometry,
/// tiling and hidden-surface removal once per draw, so 8 draws is several times the usual point.
constexpr std::size_t kSlowSceneDraws = 8;

/// Reads a trace (every frame of a sequence) for its hash, technique, scene and scene draws.
TraceInfo read_trace_info(const std::string& path) {
  const std::vector<Trace> frames = read_trace_frames(path);
  const Trace& trace = frames.front();
  TraceInfo info;
  info.hash = trace_hash(frames);
  info.technique = trace.technique.empty() ? "custom" : trace.technique;
  info.scene = trace.scene.kind == SceneKind::Atrium ? "atrium:" + std::to_string(trace.scene.detail) : trace.scene.path;
  for (const Trace& frame : frames) {
    for (const auto& c : frame.commands) {
      if (const auto* pass = std::get_if<PassDesc>(&c)) {
        for (const auto& d : pass->draws) info.scene_draws += d.geometry == GeometryKind::Scene ? 1 : 0;
      }
    }
  }
  return info;
}

/// Announces the traces that draw the scene kSlowSceneDraws times or more, with their points and
/// how many times the scene they draw compared with the sweep's lightest trace. `infos` and
/// `points_per_trace` are indexed like SweepPoints::traces(); traces not read (empty hash) are left out.
void warn_slow_traces(const SweepPoints& points, const std::vector<TraceInfo>& infos,
                      const std::vector<std::size_t>& points_per_trace, std::ostream& out) {
  // By path (one path may be listed twice), in path order.
  std::map<std::string, std::pair<const TraceInfo*, std::size_t>> traces;
  for (std::size_t t = 0; t < infos.size(); ++t) {
    if (infos[t].hash.empty()) continue;
    auto& [info, n] = traces[points.traces()[t]];
    info = &infos[t];
    n += points_per_trace[t];
  }
  std::size_t lightest = 0;
  for (const auto& [path, entry] : traces) {
    const std::size_t draws = entry.first->scene_draws;
    if (draws > 0 && (lightest == 0 || draws < lightest)) lightest = draws;
  }
  for (const auto& [path, entry] : traces) {
    const auto& [info, n] = entry;
    if (info->scene_draws < kSlowSceneDraws) continue;
    out << "slow: " << n << " point(s) replay " << path << " (" << info->technique << "), which draws the scene "
        << info->scene_draws << " times";
    if (lightest > 0 && lightest < info->scene_draws) {
      out << ", " << lightest << " in this sweep's lightest trace";
    }
    out << ": replay time grows with each draw, so these points take the longest; leave the trace out with "
           "--trace or a narrower glob\n";
  }
  out << std::flush;
}

/// The labels of the points' configurations (ParamTable::label: the preset and the parameters
/// whose values differ from it, as the database and `plot --config` name them), resolved per
/// combination when asked and the last one kept: a dry run lists them point by point, and points
/// of one combination are consecutive for every trace and repetition.
class SweepConfigLabels {
 public:
  const std::string& operator()(const SweepPoint& p, std::size_t combination) {
    if (combination == last_ && !label_.empty()) return label_;
    const auto& table = hw_params().table();
    auto it = bases_.find(p.configs);
    if (it == bases_.end()) {
      // Per list of config files, once: the resolved base, and the base's and the preset's
      // values formatted as the label writes them.
      Base b;
      b.params = table.resolve(p.configs, {});
      b.base = b.params;
      const ResolvedParams preset = table.preset(p.configs);
      for (std::size_t i = 0; i < table.decls().size(); ++i) {
        b.base_text.push_back(format_param_value(b.params.values[i]));
        b.preset_text.push_back(format_param_value(preset.values[i]));
      }
      it = bases_.emplace(p.configs, std::move(b)).first;
    }
    Base& b = it->second;
    // The base's parameters the point sets take the point's values (restored after): the label
    // is ParamTable::label of the resolved point, computed from the keys that differ only.
    std::vector<std::size_t> touched;
    for (const auto& set : p.sets) {
      table.apply_override(b.params, set);
      const int i = table.find(set.substr(0, set.find('=')));
      if (i >= 0) touched.push_back(static_cast<std::size_t>(i));
    }
    std::vector<std::pair<std::string, std::string>> differ;  // key, value
    for (std::size_t i = 0; i < b.base_text.size(); ++i) {
      const bool set_here = std::find(touched.begin(), touched.end(), i) != touched.end();
      const std::string& v = set_here ? (b.scratch = format_param_value(b.params.values[i])) : b.base_text[i];
      if (v != b.preset_text[i]) differ.emplace_back(table.decls()[i].key, v);
    }
    std::sort(differ.begin(), differ.end());
    label_ = b.params.config_name;
    for (const auto& [k, v] : differ) label_ += " " + k + "=" + v;
    // Back to the base for the next point (only the keys the point set changed).
    for (std::size_t i : touched) {
      b.params.values[i] = b.base.values[i];
      b.params.origins[i] = b.base.origins[i];
    }
    last_ = combination;
    return label_;
  }

 private:
  /// One list of config files: its resolved parameters (the working copy a point's keys are set
  /// in, then restored from `base`), and its and its preset's values as the label writes them.
  struct Base {
    ResolvedParams params, base;
    std::vector<std::string> base_text, preset_text;
    std::string scratch;
  };
  std::map<std::vector<std::string>, Base> bases_;  // by config file list
  std::size_t last_ = 0;
  std::string label_;
};

/// The hash shown for a generated trace that a dry run has not generated: no run has it.
constexpr const char* kNotGenerated = "(to generate)";

/// The [generate] requests by the path of their trace.
std::map<std::string, const TraceRequest*> generated_by_path(const SweepSpec& spec) {
  std::map<std::string, const TraceRequest*> out;
  for (const auto& g : spec.generate) out.emplace(generated_trace_path(spec, g), &g);
  return out;
}

/// What is known of a generated trace that does not exist yet (a dry run): its technique.
TraceInfo ungenerated_info(const TraceRequest& r) {
  TraceInfo info;
  info.hash = kNotGenerated;
  info.technique = r.technique;
  return info;
}

/// The file:line a failed generation is due to: the [generate] key of the option `tbdrsim trace`
/// names in its error ("--lights 5x: ..." or "option pls_bytes=7: ..."), else the section.
std::string generation_error_where(const TraceRequest& r, const InputError& e) {
  const std::string& w = e.where();
  for (std::size_t i = 0; i + 1 < r.args.size(); i += 2) {
    const std::string& flag = r.args[i];
    const std::string& value = r.args[i + 1];
    const bool hit = flag == "--option" ? w.rfind("option " + value.substr(0, value.find('=') + 1), 0) == 0
                                        : w.rfind(flag + " ", 0) == 0 || w == flag || w == value;
    if (hit) return r.arg_where[i / 2];
  }
  return r.where;
}

/// The message of an InputError without its "where: " prefix.
std::string bare_message(const InputError& e) {
  const std::string what = e.what();
  if (!e.where().empty() && what.rfind(e.where() + ": ", 0) == 0) return what.substr(e.where().size() + 2);
  return what;
}

/// Generates the [generate] traces the points replay that are not in spec.generated_dir yet, with
/// `tbdrsim trace` (cmd_trace, the same code path). All of them are written into a staging folder
/// first and moved in only when every one succeeded, so a bad option value leaves nothing behind
/// (InputError naming the [generate] line). Returns how many it generated.
std::size_t generate_traces(const SweepSpec& spec, const SweepPoints& points, std::ostream& out) {
  namespace fs = std::filesystem;
  const auto by_path = generated_by_path(spec);
  std::vector<const TraceRequest*> missing;
  std::set<std::string> seen;
  std::size_t present = 0;
  const std::vector<bool> used = points.traces_used();
  for (std::size_t t = 0; t < used.size(); ++t) {
    const std::string& path = points.traces()[t];
    const auto it = by_path.find(path);
    if (!used[t] || it == by_path.end() || !seen.insert(path).second) continue;
    if (fs::is_regular_file(path)) {
      ++present;
    } else {
      missing.push_back(it->second);
    }
  }
  if (missing.empty()) {
    if (present) out << "generate: " << present << " trace(s) already in " << spec.generated_dir << "\n" << std::flush;
    return 0;
  }
  const fs::path dir(spec.generated_dir);
  const bool made_dir = !fs::exists(dir);
  const fs::path staging = dir / (".staging-" + std::to_string(getpid()));
  // Removes the staging folder (and the folder, when this call made it) unless every trace is in.
  struct Cleanup {
    fs::path staging, dir;
    bool made_dir, done = false;
    ~Cleanup() {
      std::error_code ec;
      fs::remove_all(staging, ec);
      if (!done && made_dir) fs::remove(dir, ec);
    }
  } cleanup{staging, dir, made_dir};
  try {
    fs::create_directories(staging);
  } catch (const fs::filesystem_error& e) {
    throw InputError(spec.generated_dir, std::string("cannot create the folder of generated traces: ") + e.code().message());
  }
  out << "generate: " << missing.size() << " trace(s) into " << spec.generated_dir;
  if (present) out << " (" << present << " already there)";
  out << "\n" << std::flush;
  for (const TraceRequest* r : missing) {
    std::vector<std::string> args = r->args;
    const fs::path final_path = generated_trace_path(spec, *r);
    args.insert(args.end(), {"--out", (staging / final_path.filename()).string()});
    std::ostringstream sink;
    try {
      cmd_trace(args, sink, sink);
    } catch (const InputError& e) {
      throw InputError(generation_error_where(*r, e), "generating the trace '" + r->label + "': " + bare_message(e));
    } catch (const UsageError& e) {
      // Boost's message ("tbdrsim trace: the argument ('x') for option '--lights' is invalid") without
      // the usage text after it, at the line of the key it names.
      std::string what = e.what();
      what = what.substr(0, what.find('\n'));
      if (what.rfind("tbdrsim trace: ", 0) == 0) what = what.substr(15);
      std::string where = r->where;
      for (std::size_t i = 0; i + 1 < r->args.size(); i += 2) {
        if (what.find("'" + r->args[i] + "'") != std::string::npos) where = r->arg_where[i / 2];
      }
      throw InputError(where, "generating the trace '" + r->label + "': " + what);
    }
    out << "  " << r->label << " -> " << final_path.filename().string() << "\n" << std::flush;
  }
  for (const TraceRequest* r : missing) {
    const fs::path final_path = generated_trace_path(spec, *r);
    fs::rename(staging / final_path.filename(), final_path);
  }
  cleanup.done = true;
  return missing.size();
}

/// Reads every trace the points replay (bad input stops the sweep before anything runs; the
/// hashes identify points already in the database), indexed like points.traces(); a trace no point
/// replays is left empty. A generated trace that is not there yet (a dry run) is known by its
/// request only.
std::vector<TraceInfo> read_traces(const SweepSpec& spec, const SweepPoints& points) {
  const auto generated = generated_by_path(spec);
  const std::vector<bool> used = points.traces_used();
  std::vector<TraceInfo> infos(used.size());
  std::map<std::string, std::size_t> read;  // path -> the index it was read for
  for (std::size_t t = 0; t < used.size(); ++t) {
    if (!used[t]) continue;
    const std::string& path = points.traces()[t];
    if (const auto it = read.find(path); it != read.end()) {
      infos[t] = infos[it->second];
      continue;
    }
    const auto g = generated.find(path);
    const bool absent = g != generated.end() && !std::filesystem::exists(path);
    infos[t] = absent ? ungenerated_info(*g->second) : read_trace_info(path);
    read.emplace(path, t);
  }
  return infos;
}

/// The command line of one point's worker: `tbdrsim run` with its configs, overrides, trace and
/// threads.
std::vector<std::string> run_args(const std::string& binary, const SweepPoint& p, const std::string& db_path,
                                  int threads) {
  std::vector<std::string> args = {binary, "run"};
  for (const auto& c : p.configs) {
    args.push_back("--config");
    args.push_back(c);
  }
  for (const auto& s : p.sets) {
    args.push_back("--set");
    args.push_back(s);
  }
  args.insert(args.end(), {"--trace", p.trace, "--db", db_path, "--threads", std::to_string(threads), "--quiet"});
  return args;
}

std::string signal_text(int sig) {
  const char* d = strsignal(sig);
  return "killed by signal " + std::to_string(sig) + (d ? std::string(" (") + d + ")" : std::string());
}

/// Why a worker failed: its last words on stderr (without "error: "), the signal that killed it,
/// or its exit code.
std::string failure_text(const WorkerEnd& end) {
  std::string error = trim(end.stderr_text);
  if (WIFSIGNALED(end.status)) {
    error = signal_text(WTERMSIG(end.status)) + (error.empty() ? "" : ": " + error);
  } else if (error.empty()) {
    error = "tbdrsim run exited with code " + std::to_string(WEXITSTATUS(end.status));
  }
  if (error.rfind("error: ", 0) == 0) error = error.substr(7);
  return error;
}

/// A started point: its command line and start time, for the row of a failed run.
struct Launch {
  std::string command_line;
  std::string started_at;
};

/// The row of a failed point: its inputs and resolved parameters, status failed, no statistics.
RunRecord failed_run(const SweepPoint& p, const TraceInfo& trace, const Launch& launch, const std::string& error) {
  const ResolvedConfig config = resolve_config(p.configs, p.sets);  // resolved at read time: cannot fail now
  RunRecord rec;
  rec.started_at = launch.started_at;
  rec.finished_at = utc_now_iso8601();
  rec.tool_version = kToolVersion;
  rec.host = host_name();
  rec.command_line = launch.command_line;
  rec.config_name = config.params.config_name;
  rec.config_hash = config.hash;
  rec.trace_path = p.trace;
  rec.trace_hash = trace.hash;
  rec.scene = trace.scene;
  rec.technique = trace.technique;
  rec.status = "failed";
  rec.error = error;
  const auto& table = hw_params().table();
  for (std::size_t i = 0; i < table.decls().size(); ++i) {
    rec.params.push_back({table.decls()[i].key, format_param_value(config.params.values[i]), config.params.origins[i].text});
  }
  rec.params.push_back(config_label_param(config.label));
  return rec;
}

/// Tells whether a point is already in the database: it holds more finished runs of the point's
/// configuration and trace than the point's repetition number.
class DoneCheck {
 public:
  explicit DoneCheck(const ResultsDb& db)
      : count_(db.sql(), "SELECT count(*) FROM runs WHERE config_hash = ? AND trace_hash = ? AND status = 'ok'") {}
  bool operator()(const std::string& config_hash, const std::string& trace_hash, int repetition) {
    count_.bind(1, config_hash).bind(2, trace_hash);
    const std::int64_t n = count_.step() ? count_.int64(0) : 0;
    count_.reset();
    return n > repetition;
  }

 private:
  SqlStatement count_;
};

/// How long a point's claim holds without renewal. A sweep renews its claims every
/// kClaimRenewSeconds, so a claim lapses only when its sweep stopped renewing (died, or hung for
/// minutes); 120 s leaves room for a renewal that waits out SQLite's 60 s busy timeout.
constexpr double kClaimLeaseSeconds = 120;
/// How often a sweep renews its claims: a sixth of the lease, so several renewals may fail or wait.
constexpr double kClaimRenewSeconds = 20;

/// Wall-clock time in Unix seconds (claims are compared across processes).
double unix_seconds() {
  return std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
}

/// The claims this sweep holds on points in the database (table sweep_claims), so that sweeps
/// sharing a database run each point once. A point is claimed in the same write transaction that
/// finds it neither done nor claimed by a live sweep; the claim is released when its run ends. A
/// claim is dead, and taken over, when its lease has lapsed or when its process no longer exists
/// on this host (a killed sweep's points are taken over at once by a sweep on the same host).
class PointClaims {
 public:
  /// What claim() found.
  enum class Result { Ours, Done, Elsewhere };

  explicit PointClaims(const ResultsDb& db)
      : db_(db),
        host_(host_name()),
        pid_(getpid()),
        owner_(host_ + "/" + std::to_string(pid_) + "/" + std::to_string(unix_seconds())),
        last_renewal_(unix_seconds()) {}
  ~PointClaims() {
    try {
      SqlStatement s(db_.sql(), "DELETE FROM sweep_claims WHERE owner = ?");
      s.bind(1, owner_);
      retry_while_busy([&] { s.run(); });
    } catch (const SqlError&) {  // leaving anyway: the leases lapse
    }
  }
  PointClaims(const PointClaims&) = delete;
  PointClaims& operator=(const PointClaims&) = delete;

  /// Claims the point of this configuration, trace and repetition unless it is done or a live
  /// sweep holds it.
  Result claim(const std::string& config, const std::string& trace, int repetition) {
    Result result = Result::Ours;
    retry_while_busy([&] {
      SqlTransaction tx(db_.sql());
      result = claim_in_transaction(config, trace, repetition);
      tx.commit();
    });
    return result;
  }

  /// Releases a point (its run ended).
  void release(const std::string& config, const std::string& trace, int repetition) {
    SqlStatement s(db_.sql(),
                   "DELETE FROM sweep_claims WHERE config_hash = ? AND trace_hash = ? AND repetition = ? AND owner = ?");
    s.bind(1, config).bind(2, trace).bind(3, static_cast<std::int64_t>(repetition)).bind(4, owner_);
    retry_while_busy([&] { s.run(); });
  }

  /// Extends the lease of every claim held, when kClaimRenewSeconds have passed since the last time.
  void renew_if_due() {
    const double now = unix_seconds();
    if (now - last_renewal_ < kClaimRenewSeconds) return;
    SqlStatement s(db_.sql(), "UPDATE sweep_claims SET lease_until = ? WHERE owner = ?");
    s.bind(1, now + kClaimLeaseSeconds).bind(2, owner_);
    retry_while_busy([&] { s.run(); });
    last_renewal_ = now;
  }

 private:
  Result claim_in_transaction(const std::string& config, const std::string& trace, int repetition) {
    const auto rep = static_cast<std::int64_t>(repetition);
    {
      SqlStatement done(db_.sql(), "SELECT count(*) FROM runs WHERE config_hash = ? AND trace_hash = ? AND status = 'ok'");
      done.bind(1, config).bind(2, trace);
      if (done.step() && done.int64(0) > rep) return Result::Done;
    }
    const double now = unix_seconds();
    {
      SqlStatement held(db_.sql(),
                        "SELECT owner, host, pid, lease_until FROM sweep_claims "
                        "WHERE config_hash = ? AND trace_hash = ? AND repetition = ?");
      held.bind(1, config).bind(2, trace).bind(3, rep);
      if (held.step() && held.text(0) != owner_ && held.real(3) > now &&
          (held.text(1) != host_ || process_exists(held.int64(2)))) {
        return Result::Elsewhere;
      }
    }
    SqlStatement take(db_.sql(),
                      "INSERT OR REPLACE INTO sweep_claims(config_hash, trace_hash, repetition, owner, host, pid, "
                      "lease_until) VALUES(?,?,?,?,?,?,?)");
    take.bind(1, config).bind(2, trace).bind(3, rep).bind(4, owner_).bind(5, host_);
    take.bind(6, static_cast<std::int64_t>(pid_)).bind(7, now + kClaimLeaseSeconds);
    take.run();
    return Result::Ours;
  }

  /// True when a process with this id exists on this host (signal 0 tests without sending).
  static bool process_exists(std::int64_t pid) {
    return pid > 0 && (kill(static_cast<pid_t>(pid), 0) == 0 || errno == EPERM);
  }

  const ResultsDb& db_;
  std::string host_;
  pid_t pid_;
  std::string owner_;
  double last_renewal_;
};

/// The sweep's first line: its points, configurations, traces, what is done and what will run.
void print_plan(const SweepSpec& spec, const SweepOptions& opt, const SweepPoints& points, std::size_t skipped,
                std::size_t to_run, std::ostream& out) {
  out << "sweep " << spec.name << ": " << points.size() << " point(s)";
  if (opt.slice.count > 1) out << " in slice " << opt.slice.index << "/" << opt.slice.count << " (of " << points.total() << ")";
  std::set<std::string> traces;  // distinct paths
  const std::vector<bool> used = points.traces_used();
  for (std::size_t t = 0; t < used.size(); ++t) {
    if (used[t]) traces.insert(points.traces()[t]);
  }
  out << " (" << points.configurations_in_slice() << " configuration(s) x " << traces.size() << " trace(s)";
  if (spec.repetitions > 1) out << " x " << spec.repetitions << " repetitions";
  out << "), " << skipped << " already in " << opt.db_path << ", " << to_run << " to run";
  if (!opt.dry_run) out << " with " << opt.jobs << " worker(s) x " << opt.threads << " thread(s)";
  out << "\n" << std::flush;
}

void print_summary(const SweepSpec& spec, const SweepSummary& summary, std::ostream& out) {
  const std::size_t ran = summary.ok + summary.failed;
  out << "sweep " << spec.name << ": " << summary.ok << " ok, " << summary.failed << " failed, " << summary.skipped
      << " already done";
  if (summary.elsewhere) out << ", " << summary.elsewhere << " being run by another sweep";
  if (summary.not_run) out << ", " << summary.not_run << " not run";
  out << " in " << std::fixed << std::setprecision(1) << summary.seconds << " s";
  if (ran) out << " (" << std::setprecision(2) << static_cast<double>(ran) / summary.seconds << " points/s)";
  out << (summary.interrupted ? "; interrupted: run the same command again to finish" : "") << "\n";
  out.unsetf(std::ios::floatfield);
}

}  // namespace

TraceGenerators trace_generators() {
  TraceGenerators g;
  for (const auto& t : techniques()) {
    std::vector<std::string> options;
    for (const auto& o : t.options) options.push_back(o.key);
    g.techniques.emplace_back(t.name, std::move(options));
  }
  g.version = kToolVersion;
  return g;
}

SweepConfigHashes::SweepConfigHashes(const SweepSpec& spec) : spec_(spec) {
  const ParamTable& table = hw_params().table();
  const auto& decls = table.decls();
  // The canonical line of every value of every swept parameter (an override sets the whole value,
  // so it does not depend on the configuration it lands on).
  ResolvedParams scratch = table.defaults();
  lines_.resize(spec.axes.size());
  for (std::size_t a = 0; a < spec.axes.size(); ++a) {
    const SweepAxis& axis = spec.axes[a];
    lines_[a].assign(axis.values.size(), std::vector<std::string>(axis.keys.size()));
    for (std::size_t k = 0; k < axis.keys.size(); ++k) {
      const std::string& key = axis.keys[k];
      if (key == "config") {
        config_axis_ = a;
        config_key_ = k;
        continue;
      }
      const int d = table.find(key);
      if (d < 0) throw InputError(spec.path, "unknown parameter '" + key + "'; `tbdrsim params` lists every parameter");
      varying_.push_back({static_cast<std::size_t>(d), a, k});
      for (std::size_t v = 0; v < axis.values.size(); ++v) {
        try {
          table.apply_override(scratch, key + "=" + axis.values[v][k]);
        } catch (const InputError& e) {
          throw InputError(spec.path, "point '" + key + "=" + axis.values[v][k] + "': " + std::string(e.what()));
        }
        lines_[a][v][k] = key + "=" + format_param_value(scratch.values[static_cast<std::size_t>(d)]) + "\n";
      }
    }
  }
  std::sort(varying_.begin(), varying_.end(), [](const Varying& x, const Varying& y) { return x.decl < y.decl; });
  // Every config file list, with the fixed overrides (ParamTable::resolve's order: files, then
  // overrides; the axes' overrides come last and set parameters no fixed one sets).
  const std::size_t bases = config_axis_ == SIZE_MAX ? 1 : spec.axes[config_axis_].values.size();
  for (std::size_t b = 0; b < bases; ++b) {
    std::vector<std::string> configs = spec.base_configs;
    std::string label = "(every point)";
    if (config_axis_ != SIZE_MAX) {
      configs.push_back(spec.axes[config_axis_].values[b][config_key_]);
      label = "config=" + std::filesystem::path(configs.back()).filename().string();
    }
    ResolvedParams params;
    try {
      params = table.resolve(configs, spec.sets);
    } catch (const InputError& e) {
      throw InputError(spec.path, "point '" + label + "': " + std::string(e.what()));
    }
    Base base;
    base.segments.resize(varying_.size() + 1);
    std::size_t k = 0;
    for (std::size_t d = 0; d < decls.size(); ++d) {
      if (k < varying_.size() && varying_[k].decl == d) {
        ++k;
        continue;
      }
      base.segments[k] += decls[d].key + "=" + format_param_value(params.values[d]) + "\n";
    }
    bases_.push_back(std::move(base));
  }
  digits_.resize(spec.axes.size());
  value_at_.assign(varying_.size(), SIZE_MAX);
  before_.resize(varying_.size() + 1);
}

const std::string& SweepConfigHashes::operator()(std::size_t c) {
  if (c == last_) return hash_;
  std::size_t rest = c;
  for (std::size_t a = spec_.axes.size(); a-- > 0;) {  // the last axis fastest (SweepPoints::digits)
    digits_[a] = rest % spec_.axes[a].values.size();
    rest /= spec_.axes[a].values.size();
  }
  const std::size_t b = config_axis_ == SIZE_MAX ? 0 : digits_[config_axis_];
  const Base& base = bases_[b];
  // The first varying parameter whose value differs from the last configuration's: the hash state
  // before it is still right (all of it when the config files differ).
  std::size_t from = 0;
  if (b != base_) {
    base_ = b;
    before_[0] = Fnv1a64{};
    before_[0].update(base.segments[0]);
  } else {
    while (from < varying_.size() && value_at_[from] == digits_[varying_[from].axis]) ++from;
  }
  Fnv1a64 h = before_[from];
  for (std::size_t k = from; k < varying_.size(); ++k) {
    const Varying& v = varying_[k];
    value_at_[k] = digits_[v.axis];
    h.update(lines_[v.axis][value_at_[k]][v.key]);
    h.update(base.segments[k + 1]);
    before_[k + 1] = h;
  }
  hash_ = before_[varying_.size()].hex();
  last_ = c;
  return hash_;
}

void print_slow_points(const SweepSpec& spec, std::ostream& out) {
  const SweepPoints points(spec);
  std::vector<TraceInfo> infos(points.traces().size());
  std::vector<std::size_t> counts(points.traces().size(), 0);
  for (std::size_t t = 0; t < points.traces().size(); ++t) {
    const std::string& path = points.traces()[t];
    if (t >= spec.traces.size() && !std::filesystem::is_regular_file(path)) continue;  // known once generated
    infos[t] = read_trace_info(path);
    counts[t] = points.combinations() * static_cast<std::size_t>(std::max(spec.repetitions, 1));
  }
  warn_slow_traces(points, infos, counts, out);
}

SweepSummary run_sweep(const SweepSpec& spec, const SweepOptions& opt, std::ostream& out) {
  const auto t0 = std::chrono::steady_clock::now();
  SweepSummary summary;
  // The points of the slice, each made from its index when needed: nothing is kept per point but
  // one bit (whether it was done before this sweep started).
  const SweepPoints points(spec, opt.slice);
  summary.points = points.size();
  if (opt.jobs < 1 || opt.jobs > 1024) throw InputError("-j " + std::to_string(opt.jobs), "expected 1..1024 worker processes");
  if (opt.threads < 1 || opt.threads > 1024) throw InputError("--threads " + std::to_string(opt.threads), "expected 1..1024 threads per run");
  const std::string binary = opt.binary.empty() ? self_executable() : opt.binary;
  if (!opt.dry_run && access(binary.c_str(), X_OK) != 0) {
    throw InputError(binary, "the tbdrsim binary for the workers is not executable");
  }
  if (!opt.dry_run) generate_traces(spec, points, out);
  // Every trace is read and every config file list resolved before anything runs (the values of
  // the axes and the constraints between parameters were checked when the sweep file was read).
  const std::vector<TraceInfo> traces = read_traces(spec, points);
  SweepConfigHashes config_hash(spec);
  SweepConfigLabels config_label;
  auto trace_hash = [&](std::size_t i) -> const std::string& { return traces[points.trace(i)].hash; };

  // A dry run writes nothing: it reads the database when there is one, and creates none.
  std::optional<ResultsDb> db;
  if (!opt.dry_run) {
    db.emplace(opt.db_path);
  } else if (std::filesystem::exists(opt.db_path)) {
    db.emplace(opt.db_path, ResultsDb::QueryOnly{});
  }
  std::vector<bool> done_before(points.size(), false);
  if (db) {
    DoneCheck done(*db);
    for (std::size_t i = 0; i < points.size(); ++i) {
      done_before[i] = done(config_hash(points.combination(i)), trace_hash(i), points.repetition(i));
      summary.skipped += done_before[i] ? 1 : 0;
    }
  }
  const std::size_t to_run = points.size() - summary.skipped;
  print_plan(spec, opt, points, summary.skipped, to_run, out);
  std::vector<std::size_t> points_per_trace(traces.size(), 0);  // of those to run (a dry run: all)
  for (std::size_t i = 0; i < points.size(); ++i) points_per_trace[points.trace(i)] += opt.dry_run || !done_before[i] ? 1 : 0;

  if (opt.dry_run) {
    std::set<std::string> to_generate;
    const std::vector<bool> used = points.traces_used();
    for (std::size_t t = 0; t < traces.size(); ++t) {
      if (used[t] && traces[t].hash == kNotGenerated) to_generate.insert(points.traces()[t]);
    }
    if (!to_generate.empty()) {
      out << "dry run: would generate " << to_generate.size() << " trace(s) into " << spec.generated_dir
          << "; generated none\n";
    }
    warn_slow_traces(points, traces, points_per_trace, out);
    // Streamed: one line per point, made when it is written.
    for (std::size_t i = 0; i < points.size(); ++i) {
      const SweepPoint p = points[i];
      out << "  " << std::setw(5) << p.index << "  " << (done_before[i] ? "done  " : "to run") << "  " << p.label
          << "  (config " << config_label(p, points.combination(i)) << " [" << config_hash(points.combination(i)) << "], trace "
          << trace_hash(i) << ")\n";
    }
    summary.not_run = to_run;
    return summary;
  }
  warn_slow_traces(points, traces, points_per_trace, out);

  SweepProgressDisplay progress(opt.progress, out, points.size(), summary.skipped);
  // The points being run, by index: their launch (for the row of a failed run) and hashes.
  struct Running {
    Launch launch;
    std::string config_hash;
  };
  std::map<std::size_t, Running> running;
  std::size_t next = 0;     // the next point to consider
  std::size_t visited = 0;  // points not done before that next() has taken (launched or skipped)
  WorkerPoolHooks hooks;
  PointClaims claims(*db);
  hooks.next = [&]() -> std::optional<WorkerJob> {
    while (next < points.size()) {
      const std::size_t i = next++;
      if (done_before[i]) continue;
      ++visited;
      const std::string config = config_hash(points.combination(i));
      const PointClaims::Result claim = claims.claim(config, trace_hash(i), points.repetition(i));
      if (claim != PointClaims::Result::Ours) {  // another sweep on the same database finished it or runs it
        ++(claim == PointClaims::Result::Done ? summary.skipped : summary.elsewhere);
        progress.skipped();
        continue;
      }
      WorkerJob job;
      job.id = i;
      job.argv = run_args(binary, points[i], opt.db_path, opt.threads);
      running[i] = {{shell_command_line(job.argv), utc_now_iso8601()}, config};
      return job;
    }
    return std::nullopt;
  };
  hooks.ended = [&](const WorkerEnd& end) {
    const std::size_t i = end.id;
    const auto it = running.find(i);
    const Running run = it->second;
    running.erase(it);
    if (end.killed) {
      claims.release(run.config_hash, trace_hash(i), points.repetition(i));
      ++summary.not_run;
      return;
    }
    const SweepPoint p = points[i];
    std::string error;
    if (end.ok()) {
      ++summary.ok;
    } else {
      error = failure_text(end);
      db->write_run(failed_run(p, traces[points.trace(i)], run.launch, error));
      ++summary.failed;
    }
    claims.release(run.config_hash, trace_hash(i), points.repetition(i));
    progress.finished(p, end.ok(), end.seconds, error);
  };
  hooks.running = [&](std::size_t n) { progress.set_running(n); };
  hooks.tick = [&] {
    claims.renew_if_due();
    progress.draw(false);
  };
  hooks.stopping = [&](bool kill, std::size_t n) {
    progress.message(kill ? "stopping: killing " + std::to_string(n) + " running point(s); finished runs are kept"
                          : "stopping: waiting for " + std::to_string(n) +
                                " running point(s) to finish (Ctrl-C again to kill them)");
  };
  summary.interrupted = run_worker_pool({opt.jobs, true}, hooks);
  summary.not_run += to_run - visited;
  summary.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  progress.end();
  print_summary(spec, summary, out);
  return summary;
}

}  // namespace tbdr
