#include "app/sweep.hpp"

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
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

/// Reads a trace for its hash, technique, scene and scene draws.
TraceInfo read_trace_info(const std::string& path) {
  const Trace trace = read_trace(path);
  TraceInfo info;
  info.hash = trace_hash(trace);
  info.technique = trace.technique.empty() ? "custom" : trace.technique;
  info.scene = trace.scene.kind == SceneKind::Atrium ? "atrium:" + std::to_string(trace.scene.detail) : trace.scene.path;
  for (const auto& c : trace.commands) {
    if (const auto* pass = std::get_if<PassDesc>(&c)) {
      for (const auto& d : pass->draws) info.scene_draws += d.geometry == GeometryKind::Scene ? 1 : 0;
    }
  }
  return info;
}

/// Announces the traces that draw the scene kSlowSceneDraws times or more, with their points and
/// how many times the scene they draw compared with the sweep's lightest trace.
void warn_slow_traces(const std::map<std::string, TraceInfo>& traces, const std::vector<SweepPoint>& points,
                      std::ostream& out, const std::vector<std::size_t>* only = nullptr) {
  std::size_t lightest = 0;
  for (const auto& [path, info] : traces) {
    if (info.scene_draws > 0 && (lightest == 0 || info.scene_draws < lightest)) lightest = info.scene_draws;
  }
  for (const auto& [path, info] : traces) {
    if (info.scene_draws < kSlowSceneDraws) continue;
    std::size_t n = 0;
    if (only) {
      for (const std::size_t i : *only) n += points[i].trace == path ? 1 : 0;
    } else {
      for (const auto& p : points) n += p.trace == path ? 1 : 0;
    }
    out << "slow: " << n << " point(s) replay " << path << " (" << info.technique << "), which draws the scene "
        << info.scene_draws << " times";
    if (lightest > 0 && lightest < info.scene_draws) {
      out << ", " << lightest << " in this sweep's lightest trace";
    }
    out << ": replay time grows with each draw, so these points take the longest; leave the trace out with "
           "--trace or a narrower glob\n";
  }
  out << std::flush;
}

/// What a sweep keeps of one resolved configuration: its hash. The resolved parameters (about
/// 11 KB: a value and an origin per parameter) are resolved again for the rare point that fails,
/// so a sweep of a million configurations holds a million hashes, not 11 GB.
struct PointConfig {
  std::string hash;   ///< hw_params().table().hash() of the resolved parameters
  std::string label;  ///< hw_params().table().label(): what the database and the dry run call it
};

/// Every point's resolved configuration and trace, read once before anything runs (points of one
/// configuration or one trace share them).
struct PointInputs {
  std::map<std::string, PointConfig> configs;  ///< by config_key()
  std::map<std::string, TraceInfo> traces;     ///< by trace path
  std::vector<const PointConfig*> config;      ///< per point
  std::vector<const TraceInfo*> trace;         ///< per point
};

std::string config_key(const SweepPoint& p) {
  std::string k;
  for (const auto& c : p.configs) k += "c:" + c + "\n";
  for (const auto& s : p.sets) k += "s:" + s + "\n";
  return k;
}

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
std::size_t generate_traces(const SweepSpec& spec, const std::vector<SweepPoint>& points, std::ostream& out) {
  namespace fs = std::filesystem;
  const auto by_path = generated_by_path(spec);
  std::vector<const TraceRequest*> missing;
  std::set<std::string> seen;
  std::size_t present = 0;
  for (const auto& p : points) {
    const auto it = by_path.find(p.trace);
    if (it == by_path.end() || !seen.insert(p.trace).second) continue;
    if (fs::is_regular_file(p.trace)) {
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

/// Resolves every configuration and reads every trace: bad input stops the sweep before anything
/// runs, and the hashes identify points already in the database. A generated trace that is not
/// there yet (a dry run) is known by its request only.
PointInputs resolve_inputs(const SweepSpec& spec, const std::vector<SweepPoint>& points) {
  const auto generated = generated_by_path(spec);
  PointInputs in;
  in.config.resize(points.size());
  in.trace.resize(points.size());
  // The config files of a point are read once per list of files (not once per point): each
  // configuration is that base with the point's overrides, as resolve_config layers them.
  const auto& reg = hw_params();
  std::map<std::vector<std::string>, ResolvedParams> bases;
  std::map<std::vector<std::string>, ResolvedParams> presets;  // what the labels are relative to
  for (std::size_t i = 0; i < points.size(); ++i) {
    const SweepPoint& p = points[i];
    const std::string key = config_key(p);
    auto it = in.configs.find(key);
    if (it == in.configs.end()) {
      PointConfig config;
      try {
        auto base = bases.find(p.configs);
        if (base == bases.end()) base = bases.emplace(p.configs, reg.table().resolve(p.configs, {})).first;
        ResolvedParams params = base->second;
        for (const auto& set : p.sets) reg.table().apply_override(params, set);
        check_config_constraints(reg.build(params), params);
        config.hash = reg.table().hash(params);
        auto preset = presets.find(p.configs);
        if (preset == presets.end()) preset = presets.emplace(p.configs, reg.table().preset(p.configs)).first;
        config.label = reg.table().label(params, preset->second);
      } catch (const InputError& e) {
        throw InputError(spec.path, "point '" + p.label + "': " + std::string(e.what()));
      }
      it = in.configs.emplace(key, std::move(config)).first;
    }
    in.config[i] = &it->second;
    auto tt = in.traces.find(p.trace);
    if (tt == in.traces.end()) {
      const auto g = generated.find(p.trace);
      const bool absent = g != generated.end() && !std::filesystem::exists(p.trace);
      tt = in.traces.emplace(p.trace, absent ? ungenerated_info(*g->second) : read_trace_info(p.trace)).first;
    }
    in.trace[i] = &tt->second;
  }
  return in;
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
  DoneCheck(const ResultsDb& db, const PointInputs& inputs, const std::vector<SweepPoint>& points)
      : count_(db.sql(), "SELECT count(*) FROM runs WHERE config_hash = ? AND trace_hash = ? AND status = 'ok'"),
        inputs_(inputs),
        points_(points) {}
  bool operator()(std::size_t i) {
    count_.bind(1, inputs_.config[i]->hash).bind(2, inputs_.trace[i]->hash);
    const std::int64_t n = count_.step() ? count_.int64(0) : 0;
    count_.reset();
    return n > points_[i].repetition;
  }

 private:
  SqlStatement count_;
  const PointInputs& inputs_;
  const std::vector<SweepPoint>& points_;
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

  PointClaims(const ResultsDb& db, const PointInputs& inputs, const std::vector<SweepPoint>& points)
      : db_(db),
        inputs_(inputs),
        points_(points),
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

  /// Claims point i unless it is done or a live sweep holds it.
  Result claim(std::size_t i) {
    Result result = Result::Ours;
    retry_while_busy([&] {
      SqlTransaction tx(db_.sql());
      result = claim_in_transaction(i);
      tx.commit();
    });
    return result;
  }

  /// Releases point i (its run ended).
  void release(std::size_t i) {
    SqlStatement s(db_.sql(),
                   "DELETE FROM sweep_claims WHERE config_hash = ? AND trace_hash = ? AND repetition = ? AND owner = ?");
    s.bind(1, inputs_.config[i]->hash).bind(2, inputs_.trace[i]->hash).bind(3, static_cast<std::int64_t>(points_[i].repetition)).bind(4, owner_);
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
  Result claim_in_transaction(std::size_t i) {
    const std::string& config = inputs_.config[i]->hash;
    const std::string& trace = inputs_.trace[i]->hash;
    const auto rep = static_cast<std::int64_t>(points_[i].repetition);
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
  const PointInputs& inputs_;
  const std::vector<SweepPoint>& points_;
  std::string host_;
  pid_t pid_;
  std::string owner_;
  double last_renewal_;
};

/// The sweep's first line: its points, configurations, traces, what is done and what will run.
void print_plan(const SweepSpec& spec, const SweepOptions& opt, std::size_t points, std::size_t all,
                const PointInputs& inputs, std::size_t skipped, std::size_t to_run, std::ostream& out) {
  out << "sweep " << spec.name << ": " << points << " point(s)";
  if (opt.slice.count > 1) out << " in slice " << opt.slice.index << "/" << opt.slice.count << " (of " << all << ")";
  out << " (" << inputs.configs.size() << " configuration(s) x " << inputs.traces.size() << " trace(s)";
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

void print_slow_points(const SweepSpec& spec, std::ostream& out) {
  std::map<std::string, TraceInfo> traces;
  for (const auto& t : spec.traces) {
    if (!traces.count(t)) traces.emplace(t, read_trace_info(t));
  }
  for (const auto& g : spec.generate) {  // known once generated
    const std::string t = generated_trace_path(spec, g);
    if (!traces.count(t) && std::filesystem::is_regular_file(t)) traces.emplace(t, read_trace_info(t));
  }
  warn_slow_traces(traces, expand_sweep(spec), out);
}

SweepSummary run_sweep(const SweepSpec& spec, const SweepOptions& opt, std::ostream& out) {
  const auto t0 = std::chrono::steady_clock::now();
  SweepSummary summary;
  // One list of points (a slice keeps its own, never a second copy of the whole sweep).
  std::vector<SweepPoint> points = expand_sweep(spec);
  const std::size_t all_points = points.size();
  if (opt.slice.count > 1) points = slice_points(points, opt.slice);
  summary.points = points.size();
  if (opt.jobs < 1 || opt.jobs > 1024) throw InputError("-j " + std::to_string(opt.jobs), "expected 1..1024 worker processes");
  if (opt.threads < 1 || opt.threads > 1024) throw InputError("--threads " + std::to_string(opt.threads), "expected 1..1024 threads per run");
  const std::string binary = opt.binary.empty() ? self_executable() : opt.binary;
  if (!opt.dry_run && access(binary.c_str(), X_OK) != 0) {
    throw InputError(binary, "the tbdrsim binary for the workers is not executable");
  }
  if (!opt.dry_run) generate_traces(spec, points, out);
  const PointInputs inputs = resolve_inputs(spec, points);

  if (opt.dry_run) {
    // A dry run writes nothing: it reads the database when there is one, and creates none.
    std::optional<ResultsDb> existing;
    if (std::filesystem::exists(opt.db_path)) existing.emplace(opt.db_path, ResultsDb::QueryOnly{});
    std::optional<DoneCheck> done;
    if (existing) done.emplace(*existing, inputs, points);
    std::vector<bool> done_before(points.size(), false);
    for (std::size_t i = 0; i < points.size(); ++i) {
      done_before[i] = done && (*done)(i);
      if (done_before[i]) ++summary.skipped;
    }
    print_plan(spec, opt, points.size(), all_points, inputs, summary.skipped, points.size() - summary.skipped, out);
    std::size_t to_generate = 0;
    for (const auto& [path, info] : inputs.traces) to_generate += info.hash == kNotGenerated ? 1 : 0;
    if (to_generate) {
      out << "dry run: would generate " << to_generate << " trace(s) into " << spec.generated_dir << "; generated none\n";
    }
    warn_slow_traces(inputs.traces, points, out);
    for (std::size_t i = 0; i < points.size(); ++i) {
      out << "  " << std::setw(5) << points[i].index << "  " << (done_before[i] ? "done  " : "to run") << "  "
          << points[i].label << "  (config " << inputs.config[i]->label << " [" << inputs.config[i]->hash
          << "], trace " << inputs.trace[i]->hash << ")\n";
    }
    summary.not_run = points.size() - summary.skipped;
    return summary;
  }

  ResultsDb db(opt.db_path);
  DoneCheck already_done(db, inputs, points);
  std::vector<std::size_t> todo;
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (already_done(i)) {
      ++summary.skipped;
    } else {
      todo.push_back(i);
    }
  }
  print_plan(spec, opt, points.size(), all_points, inputs, summary.skipped, todo.size(), out);
  warn_slow_traces(inputs.traces, points, out, &todo);

  SweepProgressDisplay progress(opt.progress, out, points.size(), summary.skipped);
  std::vector<Launch> launches(points.size());
  std::size_t next = 0;
  WorkerPoolHooks hooks;
  PointClaims claims(db, inputs, points);
  hooks.next = [&]() -> std::optional<WorkerJob> {
    while (next < todo.size()) {
      const std::size_t i = todo[next++];
      const PointClaims::Result claim = claims.claim(i);
      if (claim != PointClaims::Result::Ours) {  // another sweep on the same database finished it or runs it
        ++(claim == PointClaims::Result::Done ? summary.skipped : summary.elsewhere);
        progress.skipped();
        continue;
      }
      WorkerJob job;
      job.id = i;
      job.argv = run_args(binary, points[i], opt.db_path, opt.threads);
      launches[i] = {shell_command_line(job.argv), utc_now_iso8601()};
      return job;
    }
    return std::nullopt;
  };
  hooks.ended = [&](const WorkerEnd& end) {
    const std::size_t i = end.id;
    if (end.killed) {
      claims.release(i);
      ++summary.not_run;
      return;
    }
    std::string error;
    if (end.ok()) {
      ++summary.ok;
    } else {
      error = failure_text(end);
      db.write_run(failed_run(points[i], *inputs.trace[i], launches[i], error));
      ++summary.failed;
    }
    claims.release(i);
    progress.finished(points[i], end.ok(), end.seconds, error);
  };
  hooks.running = [&](std::size_t n) { progress.set_running(n); };
  hooks.tick = [&] {
    claims.renew_if_due();
    progress.draw(false);
  };
  hooks.stopping = [&](bool kill, std::size_t running) {
    progress.message(kill ? "stopping: killing " + std::to_string(running) + " running point(s); finished runs are kept"
                          : "stopping: waiting for " + std::to_string(running) +
                                " running point(s) to finish (Ctrl-C again to kill them)");
  };
  summary.interrupted = run_worker_pool({opt.jobs, true}, hooks);
  summary.not_run += todo.size() - next;
  summary.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  progress.end();
  print_summary(spec, summary, out);
  return summary;
}

}  // namespace tbdr
