#include "app/stats_export.hpp"

#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <sstream>
#include <string_view>
#include <vector>

#include "analysis/results_db.hpp"
#include "analysis/sql.hpp"
#include "app/run_stats.hpp"
#include "kernel/errors.hpp"
#include "kernel/output_file.hpp"

namespace tbdr {

namespace fs = std::filesystem;

namespace {

/// A JSON string literal (RFC 8259: quote, backslash and control characters escaped).
std::string json_string(const std::string& s) {
  std::string o = "\"";
  for (const char ch : s) {
    const auto c = static_cast<unsigned char>(ch);
    if (c == '"') {
      o += "\\\"";
    } else if (c == '\\') {
      o += "\\\\";
    } else if (c == '\n') {
      o += "\\n";
    } else if (c < 0x20) {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\u%04x", c);
      o += buf;
    } else {
      o += ch;
    }
  }
  return o + "\"";
}

/// A JSON number that reads back to the same double (17 significant digits); null for NaN and
/// infinities, which JSON cannot hold.
std::string json_number(double v) {
  if (!std::isfinite(v)) return "null";
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

/// A value as gem5's stats.txt prints it: integers without decimals, others with six.
std::string text_number(double v) {
  char buf[40];
  if (std::fabs(v) < 1e15 && v == std::floor(v)) {
    std::snprintf(buf, sizeof buf, "%.0f", v);
  } else {
    std::snprintf(buf, sizeof buf, "%.6f", v);
  }
  return buf;
}

/// Writes `text` to `path` (InputError naming it when that fails).
void write_file(const std::string& path, const std::string& text) {
  write_output_file(path, "the file", text);  // whole or not at all (kernel/output_file.hpp)
}

/// Who the run is: the columns of runs and its configuration's label.
struct RunIdentity {
  std::vector<std::pair<std::string, std::string>> fields;  ///< name, value, in order
  std::string technique, config_label, status;
};

RunIdentity run_identity(const ResultsDb& db, std::int64_t run_id) {
  SqlStatement q(db.sql(),
                 "SELECT r.technique, r.scene, r.config_name, l.config_label, r.config_hash, r.trace_path, "
                 "r.trace_hash, r.tool_version, r.started_at, r.host, r.status FROM runs r "
                 "JOIN v_config_label l ON l.run_id = r.id WHERE r.id = ?", run_id);
  if (!q.step()) throw InputError(db.path(), "no run " + std::to_string(run_id) + " in the results database");
  RunIdentity id;
  const char* names[] = {"technique", "scene",        "config_name", "config_label", "config_hash", "trace_path",
                         "trace_hash", "tool_version", "started_at",  "host",         "status"};
  id.fields.push_back({"run_id", std::to_string(run_id)});
  for (int c = 0; c < 11; ++c) id.fields.push_back({names[c], q.text(c)});
  id.technique = q.text(0);
  id.config_label = q.text(3);
  id.status = q.text(10);
  return id;
}

/// One figure of the file: a statistic (scope/name) or a derived figure (derived/metric).
struct Figure {
  std::string scope, name;
  double value = 0;
  std::string unit, description;
};

std::vector<Figure> run_figures(const ResultsDb& db, std::int64_t run_id) {
  std::vector<Figure> figures;
  for (StatRecord& r : db.run_stats(run_id)) {
    figures.push_back({std::move(r.scope), std::move(r.name), r.value, std::move(r.unit), std::move(r.description)});
  }
  {
    // The derived figures (names without a dot: the raw statistics are in v_metric as unit.name too).
    SqlStatement q(db.sql(),
                   "SELECT m.metric, m.value, m.unit, coalesce(d.description, '') FROM v_metric m "
                   "LEFT JOIN v_metric_def d ON d.metric = m.metric "
                   "WHERE m.run_id = ? AND m.metric NOT GLOB '*.*' AND m.value IS NOT NULL", run_id);
    while (q.step()) {
      std::string description = q.text(3);
      const std::string metric = q.text(0);
      if (description.empty() && metric.rfind("requested_", 0) == 0) {
        description = "Bytes of this traffic class the units requested before the caches, read + written, 1e6 bytes";
      } else if (description.empty() && metric.rfind("dram_", 0) == 0) {
        description = "Bytes of this traffic class read from and written to the DRAM devices (after the caches), 1e6 bytes";
      } else if (description.empty() && metric.rfind("energy_", 0) == 0) {
        description = "Energy of this component";
      }
      figures.push_back({"derived", metric, q.real(1), q.text(2), description});
    }
  }
  return figures;
}

/// The run's parameters (hardware, technique options, trace identity): key -> value, origin.
std::vector<std::array<std::string, 3>> run_parameters(const ResultsDb& db, std::int64_t run_id) {
  std::vector<std::array<std::string, 3>> params;
  SqlStatement q(db.sql(), "SELECT key, value, origin FROM run_params WHERE run_id = ? ORDER BY rowid", run_id);
  while (q.step()) params.push_back({q.text(0), q.text(1), q.text(2)});
  return params;
}

/// "frame/tsp" + "shaded_samples" -> "frame.tsp.shaded_samples" (gem5 names are dotted paths).
std::string dotted_name(const Figure& f) {
  std::string s = f.scope + "." + f.name;
  for (char& c : s) {
    if (c == '/') c = '.';
  }
  return s;
}

std::string stats_text(const RunIdentity& id, const std::vector<Figure>& figures,
                       const std::vector<std::array<std::string, 3>>& params) {
  std::ostringstream o;
  o << "# tbdrsim statistics of one run (the layout of gem5's stats.txt): name value # description (unit)\n";
  for (const auto& [k, v] : id.fields) o << "# " << k << ": " << v << "\n";
  o << "\n---------- Begin Simulation Statistics ----------\n";
  std::size_t width = 40;
  for (const auto& f : figures) width = std::max(width, dotted_name(f).size() + 2);
  for (const auto& f : figures) {
    const std::string name = dotted_name(f);
    const std::string value = text_number(f.value);
    o << name << std::string(width - name.size(), ' ') << std::string(value.size() < 20 ? 20 - value.size() : 1, ' ')
      << value << "  # " << f.description << (f.unit.empty() ? "" : " (" + f.unit + ")") << "\n";
  }
  o << "---------- End Simulation Statistics   ----------\n";
  o << "\n# parameters: key = value  # origin\n";
  for (const auto& p : params) o << "# " << p[0] << " = " << p[1] << "  # " << p[2] << "\n";
  return o.str();
}

std::string stats_json(const RunIdentity& id, const std::vector<Figure>& figures,
                       const std::vector<std::array<std::string, 3>>& params) {
  std::ostringstream o;
  o << "{\n  \"format\": \"tbdrsim-stats 1\",\n  \"run\": {";
  for (std::size_t i = 0; i < id.fields.size(); ++i) {
    o << (i ? ", " : "") << json_string(id.fields[i].first) << ": ";
    o << (id.fields[i].first == "run_id" ? id.fields[i].second : json_string(id.fields[i].second));
  }
  o << "},\n  \"parameters\": {";
  for (std::size_t i = 0; i < params.size(); ++i) {
    o << (i ? ",\n" : "\n") << "    " << json_string(params[i][0]) << ": {\"value\": " << json_string(params[i][1])
      << ", \"origin\": " << json_string(params[i][2]) << "}";
  }
  o << "\n  },\n  \"stats\": {";
  // Grouped by scope, in the order the run stored them; derived figures last, under "derived".
  std::vector<std::string> scopes;
  std::map<std::string, std::vector<const Figure*>> by_scope;
  for (const auto& f : figures) {
    if (!by_scope.count(f.scope)) scopes.push_back(f.scope);
    by_scope[f.scope].push_back(&f);
  }
  for (std::size_t s = 0; s < scopes.size(); ++s) {
    o << (s ? ",\n" : "\n") << "    " << json_string(scopes[s]) << ": {";
    const auto& list = by_scope[scopes[s]];
    for (std::size_t i = 0; i < list.size(); ++i) {
      const Figure& f = *list[i];
      o << (i ? ",\n" : "\n") << "      " << json_string(f.name) << ": {\"value\": " << json_number(f.value)
        << ", \"unit\": " << json_string(f.unit) << ", \"description\": " << json_string(f.description) << "}";
    }
    o << "\n    }";
  }
  o << "\n  }\n}\n";
  return o.str();
}

/// One pass or dispatch of a run on the timeline: its name and its first, binning-end and last cycle.
struct CommandSpan {
  std::string name;
  double start = 0, binning_end = 0, end = 0;
};

/// The run's passes and dispatches (the stats scopes "<command>/timing"), in the order it stored them.
std::vector<CommandSpan> command_spans(const ResultsDb& db, std::int64_t run_id) {
  const std::string_view kTimingSuffix = CommandTimingStats::kScopeSuffix;
  std::vector<CommandSpan> commands;
  std::map<std::string, std::size_t> index;
  SqlStatement q(db.sql(),
                 "SELECT scope, name, value FROM stats WHERE run_id = ? AND scope GLOB '*/timing' "
                 "AND scope <> 'frame/timing' ORDER BY rowid", run_id);
  while (q.step()) {
    const std::string scope = q.text(0);
    const std::string command = scope.substr(0, scope.size() - kTimingSuffix.size());
    auto [it, fresh] = index.try_emplace(command, commands.size());
    if (fresh) commands.push_back({command});
    CommandSpan& c = commands[it->second];
    const std::string name = q.text(1);
    if (name == stat_name(&CommandTimingStats::start_cycle)) c.start = q.real(2);
    if (name == stat_name(&CommandTimingStats::binning_end_cycle)) c.binning_end = q.real(2);
    if (name == stat_name(&CommandTimingStats::end_cycle)) c.end = q.real(2);
  }
  return commands;
}

/// One timed unit's busy, stalled and idle cycles over the frame (v_unit).
struct UnitCycles {
  std::string name;
  double busy = 0, stalled = 0, idle = 0;
};

std::vector<UnitCycles> unit_cycles(const ResultsDb& db, std::int64_t run_id) {
  std::vector<UnitCycles> units;
  SqlStatement q(db.sql(),
                 "SELECT unit, coalesce(busy_cycles, 0), coalesce(stalled_cycles, 0), coalesce(idle_cycles, 0) "
                 "FROM v_unit WHERE run_id = ? ORDER BY unit", run_id);
  while (q.step()) units.push_back({q.text(0), q.real(1), q.real(2), q.real(3)});
  return units;
}

}  // namespace

void check_output_file(const std::string& option, const std::string& path) {
  std::error_code ec;
  if (path.empty()) throw InputError(option, "empty file name");
  if (fs::is_directory(path, ec)) throw InputError(option + " " + path, "is a folder, not a file");
  const fs::path folder = fs::path(path).has_parent_path() ? fs::path(path).parent_path() : fs::path(".");
  if (!fs::is_directory(folder, ec)) {
    throw InputError(option + " " + path, "folder '" + folder.string() + "' does not exist");
  }
  if (access(folder.c_str(), W_OK | X_OK) != 0) {
    throw InputError(option + " " + path, "folder '" + folder.string() + "' is not writable");
  }
}

void write_stats_file(const ResultsDb& db, std::int64_t run_id, const std::string& path) {
  const RunIdentity id = run_identity(db, run_id);
  const std::vector<Figure> figures = run_figures(db, run_id);
  const auto params = run_parameters(db, run_id);
  const bool json = fs::path(path).extension() == ".json";
  write_file(path, json ? stats_json(id, figures, params) : stats_text(id, figures, params));
}

void write_timeline_file(const ResultsDb& db, std::int64_t run_id, const TimingResult& timing, const std::string& path) {
  const RunIdentity id = run_identity(db, run_id);
  double frame_cycles = 0, frame_ms = 0;
  {
    SqlStatement q(db.sql(), "SELECT cycles, frame_time_ms FROM v_run_summary WHERE run_id = ?", run_id);
    if (!q.step() || q.is_null(0) || q.is_null(1) || q.real(0) <= 0) {
      throw InputError(db.path(), "run " + std::to_string(run_id) + " has no timing figures for a timeline");
    }
    frame_cycles = q.real(0);
    frame_ms = q.real(1);
  }
  // Simulated microseconds per core clock cycle, from the frame's own figures.
  const double us_per_cycle = frame_ms * 1e3 / frame_cycles;
  const std::vector<CommandSpan> commands = command_spans(db, run_id);
  const std::vector<UnitCycles> units = unit_cycles(db, run_id);

  std::ostringstream o;
  std::vector<std::string> events;
  auto meta = [&](const char* what, int pid, int tid, const std::string& name) {
    events.push_back(std::string("{\"ph\": \"M\", \"name\": \"") + what + "\", \"pid\": " + std::to_string(pid) +
                     ", \"tid\": " + std::to_string(tid) + ", \"args\": {\"name\": " + json_string(name) + "}}");
  };
  auto sort_index = [&](int pid, int tid, int index) {
    events.push_back("{\"ph\": \"M\", \"name\": \"thread_sort_index\", \"pid\": " + std::to_string(pid) +
                     ", \"tid\": " + std::to_string(tid) + ", \"args\": {\"sort_index\": " + std::to_string(index) + "}}");
  };
  auto slice = [&](int pid, int tid, const std::string& name, double from, double to, const std::string& args) {
    events.push_back("{\"ph\": \"X\", \"name\": " + json_string(name) + ", \"cat\": \"gpu\", \"pid\": " +
                     std::to_string(pid) + ", \"tid\": " + std::to_string(tid) + ", \"ts\": " +
                     json_number(from * us_per_cycle) + ", \"dur\": " + json_number((to - from) * us_per_cycle) +
                     ", \"args\": {" + args + "}}");
  };
  auto cycles_args = [&](double from, double to) {
    return "\"start_cycle\": " + json_number(from) + ", \"end_cycle\": " + json_number(to) +
           ", \"cycles\": " + json_number(to - from);
  };
  // Process 1: the frame and one track per command (binning, then its tiles or compute work).
  meta("process_name", 1, 0, "run " + std::to_string(run_id) + ": " + id.technique + " on " + id.config_label);
  meta("thread_name", 1, 1, "frame");
  sort_index(1, 1, 0);
  slice(1, 1, "frame", 0, frame_cycles, cycles_args(0, frame_cycles));
  for (std::size_t i = 0; i < commands.size(); ++i) {
    const CommandSpan& c = commands[i];
    const int tid = static_cast<int>(i) + 2;
    meta("thread_name", 1, tid, c.name);
    sort_index(1, tid, tid);
    const bool dispatch = c.name.rfind("dispatch", 0) == 0;
    const double work_start = std::max(c.start, c.binning_end);
    if (!dispatch && c.binning_end > c.start) {
      slice(1, tid, "binning", c.start, c.binning_end, cycles_args(c.start, c.binning_end));
    }
    if (c.end > work_start) {
      slice(1, tid, dispatch ? "compute" : "tiles", work_start, c.end, cycles_args(work_start, c.end));
    }
  }
  // Process 2: each unit's share of the frame. The timing model reports busy and stalled cycles
  // per unit over the frame, not their intervals: one slice per unit spans the frame and carries
  // them, and a counter track shows the unit's busy, stalled and idle percentages (their sum is
  // 100: stalled is time waiting while not busy, docs/queries.md).
  meta("process_name", 2, 0, "units: busy / stalled / idle over the frame (totals, not intervals; they add up to 100 %)");
  for (std::size_t i = 0; i < units.size(); ++i) {
    const UnitCycles& u = units[i];
    const int tid = static_cast<int>(i) + 1;
    meta("thread_name", 2, tid, u.name);
    sort_index(2, tid, tid);
    const double busy_pct = 100.0 * u.busy / frame_cycles, stalled_pct = 100.0 * u.stalled / frame_cycles;
    const double idle_pct = 100.0 * u.idle / frame_cycles;
    char label[128];
    std::snprintf(label, sizeof label, "%s busy %.1f %%, stalled %.1f %%, idle %.1f %%", u.name.c_str(), busy_pct,
                  stalled_pct, idle_pct);
    slice(2, tid, label, 0, frame_cycles,
          "\"busy_cycles\": " + json_number(u.busy) + ", \"stalled_cycles\": " + json_number(u.stalled) +
              ", \"idle_cycles\": " + json_number(u.idle));
    for (const double at : {0.0, frame_cycles}) {
      events.push_back("{\"ph\": \"C\", \"name\": " + json_string(u.name + " %") + ", \"pid\": 2, \"tid\": " +
                       std::to_string(tid) + ", \"ts\": " + json_number(at * us_per_cycle) + ", \"args\": {\"busy\": " +
                       json_number(busy_pct) + ", \"stalled\": " + json_number(stalled_pct) +
                       ", \"idle\": " + json_number(idle_pct) + "}}");
    }
  }
  // Processes 3..: one per unit of the timing model, a track per pass or dispatch it worked for
  // (the tids of process 1), a slice per busy interval (merged and bounded: models/busy_intervals.hpp).
  for (std::size_t u = 0; u < timing.units.size(); ++u) {
    const int pid = static_cast<int>(u) + 3;
    const std::string& unit = timing.units[u].name;
    meta("process_name", pid, 0, "unit " + unit + ": busy intervals per pass");
    events.push_back("{\"ph\": \"M\", \"name\": \"process_sort_index\", \"pid\": " + std::to_string(pid) +
                     ", \"tid\": 0, \"args\": {\"sort_index\": " + std::to_string(pid) + "}}");
    for (std::size_t c = 0; c < timing.commands.size(); ++c) {
      const CommandTime& cmd = timing.commands[c];
      const auto busy = std::find_if(cmd.unit_busy.begin(), cmd.unit_busy.end(), [&](const UnitBusy& b) { return b.unit == unit; });
      if (busy == cmd.unit_busy.end()) continue;
      const int tid = static_cast<int>(c) + 2;
      meta("thread_name", pid, tid, cmd.name);
      sort_index(pid, tid, tid);
      for (const BusyInterval& i : busy->intervals) {
        slice(pid, tid, unit + " " + cmd.name, i.start_cycle, i.end_cycle,
              cycles_args(i.start_cycle, i.end_cycle) + ", \"busy_cycles\": " + json_number(i.busy_cycles) +
                  ", \"unit\": " + json_string(unit) + ", \"command\": " + json_string(cmd.name));
      }
    }
  }
  // The DRAM: one process, a track per channel, a slice per stretch of data-bus transfers over the
  // frame (the DRAM serves every unit and command at once, so it is not split by pass).
  if (!timing.dram_bus.empty()) {
    const int pid = static_cast<int>(timing.units.size()) + 3;
    meta("process_name", pid, 0, "dram: data bus busy per channel (frame)");
    events.push_back("{\"ph\": \"M\", \"name\": \"process_sort_index\", \"pid\": " + std::to_string(pid) +
                     ", \"tid\": 0, \"args\": {\"sort_index\": " + std::to_string(pid) + "}}");
    for (std::size_t ch = 0; ch < timing.dram_bus.size(); ++ch) {
      const UnitBusy& bus = timing.dram_bus[ch];
      const int tid = static_cast<int>(ch) + 1;
      meta("thread_name", pid, tid, bus.unit);
      sort_index(pid, tid, tid);
      for (const BusyInterval& i : bus.intervals) {
        slice(pid, tid, bus.unit, i.start_cycle, i.end_cycle,
              cycles_args(i.start_cycle, i.end_cycle) + ", \"busy_cycles\": " + json_number(i.busy_cycles) +
                  ", \"unit\": " + json_string(bus.unit));
      }
    }
  }
  // Trace-event timestamps and durations are microseconds (the format's one unit); displayTimeUnit
  // only says how the viewer shows them: milliseconds, the scale of a frame.
  o << "{\n  \"displayTimeUnit\": \"ms\",\n  \"otherData\": {";
  for (std::size_t i = 0; i < id.fields.size(); ++i) {
    o << (i ? ", " : "") << json_string(id.fields[i].first) << ": " << json_string(id.fields[i].second);
  }
  o << ", \"frame_cycles\": " << json_string(json_number(frame_cycles)) << ", \"us_per_cycle\": "
    << json_string(json_number(us_per_cycle)) << "},\n  \"traceEvents\": [\n";
  for (std::size_t i = 0; i < events.size(); ++i) o << "    " << events[i] << (i + 1 < events.size() ? ",\n" : "\n");
  o << "  ]\n}\n";
  write_file(path, o.str());
}

}  // namespace tbdr
