// `tbdrsim report`: comparison tables over the analysis views (v_run_summary, v_param, v_metric).
#include "analysis/report.hpp"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <ostream>
#include <set>
#include <sstream>

#include "analysis/results_db.hpp"
#include "analysis/sql.hpp"
#include "kernel/errors.hpp"

namespace tbdr {

// ---------------------------------------------------------------------------------------------
// Report

std::string canonical_group_key(const std::string& key) {
  if (key == "technique") return "trace.technique";
  if (key == "scene") return "trace.scene";
  if (key == "config" || key == "config_label") return "config.label";
  if (key == "config_name") return "config.name";
  if (key == "lights") return "trace.lights";
  if (key == "camera") return "trace.camera";
  if (key == "resolution") return "trace.resolution";
  if (key == "trace" || key == "trace_path") return "trace.path";
  if (key == "trace_hash") return "trace.hash";
  if (key == "mode") return "gpu.mode";
  return key;
}

ReportFormat parse_report_format(const std::string& text) {
  if (text == "table") return ReportFormat::Table;
  if (text == "csv") return ReportFormat::Csv;
  if (text == "markdown" || text == "md") return ReportFormat::Markdown;
  throw InputError("--format " + text, "expected table, csv or markdown");
}

std::vector<std::string> report_group_key_names(const ResultsDb& db) {
  std::vector<std::string> names = {"technique", "scene", "config", "lights"};
  SqlStatement q(db.sql(), "SELECT DISTINCT key FROM v_param ORDER BY key");
  while (q.step()) names.push_back(q.text(0));
  return names;
}

std::vector<std::string> report_metric_names(const ResultsDb& db) {
  std::vector<std::string> names;
  SqlStatement q(db.sql(), "SELECT DISTINCT metric FROM v_metric ORDER BY metric");
  while (q.step()) names.push_back(q.text(0));
  return names;
}

namespace {

/// The traffic classes in the order the simulator declares them (others follow, sorted).
const char* const kDramClassOrder[] = {"parameter_buffer", "vertices", "indices",    "textures", "color",
                                       "depth_stencil",    "gbuffer",  "visibility", "light_data",
                                       "light_lists",      "work_lists", "spill",    "other"};

bool parse_number(const std::string& s, double& v) {
  if (s.empty()) return false;
  auto r = std::from_chars(s.data(), s.data() + s.size(), v);
  return r.ec == std::errc{} && r.ptr == s.data() + s.size();
}

/// Numbers sort numerically, text alphabetically, numbers before text.
bool key_less(const std::string& a, const std::string& b) {
  double x = 0, y = 0;
  const bool na = parse_number(a, x), nb = parse_number(b, y);
  if (na && nb) return x < y;
  if (na != nb) return na;
  return a < b;
}

/// Derived figures carry their unit in their name; raw statistics ('tsp.shaded_samples') get it added.
std::string header_text(const std::string& metric, const std::string& unit) {
  if (unit.empty() || metric.find('.') == std::string::npos) return metric;
  return metric + " (" + unit + ")";
}

bool starts_ends(const std::string& s, const std::string& pre, const std::string& suf) {
  return s.size() > pre.size() + suf.size() && s.rfind(pre, 0) == 0 &&
         s.compare(s.size() - suf.size(), suf.size(), suf) == 0;
}

/// The default report's three tables: frame figures, DRAM MB per class, energy mJ per component.
std::vector<ReportTable::Section> default_sections(const std::vector<std::string>& metrics) {
  ReportTable::Section frame{"per run (a sequence: the sum of its frames; its figures per frame: --metric steady_interval_ms, steady_fps, ...)", {}, {}};
  ReportTable::Section dram{"DRAM MB per traffic class (read + written at the DRAM devices, after the caches; "
                            "requested = what the units asked for before them)", {}, {}};
  ReportTable::Section energy{"energy mJ per component", {}, {}};
  std::optional<std::size_t> dram_total, requested_total, energy_total;
  for (std::size_t i = 0; i < metrics.size(); ++i) {
    const std::string& m = metrics[i];
    if (m == metric::kDramTotalMb) dram_total = i;
    if (m == metric::kRequestedTotalMb) requested_total = i;
    if (m == metric::kEnergyTotalMj) energy_total = i;
    if (m != metric::kDramTotalMb && starts_ends(m, "dram_", "_mb") && m != metric::kDramReadMb && m != metric::kDramWriteMb) {
      dram.metrics.push_back(i);
      dram.headers.push_back(m.substr(5, m.size() - 8));
    } else if (m != metric::kEnergyTotalMj && starts_ends(m, "energy_", "_mj")) {
      energy.metrics.push_back(i);
      energy.headers.push_back(m.substr(7, m.size() - 10));
    } else {
      frame.metrics.push_back(i);
      frame.headers.push_back(m);
    }
  }
  if (!dram.metrics.empty() && dram_total) {
    dram.metrics.push_back(*dram_total);
    dram.headers.push_back("total");
  }
  if (!dram.metrics.empty() && requested_total) {
    dram.metrics.push_back(*requested_total);
    dram.headers.push_back("requested");
  }
  if (!energy.metrics.empty() && energy_total) {
    energy.metrics.push_back(*energy_total);
    energy.headers.push_back("total");
  }
  std::vector<ReportTable::Section> out;
  for (auto* sec : {&frame, &dram, &energy}) {
    if (!sec->metrics.empty()) out.push_back(*sec);
  }
  return out;
}

std::string format_value(double v) {
  char buf[64];
  if (std::fabs(v) < 1e15 && v == std::floor(v)) {
    std::snprintf(buf, sizeof buf, "%.0f", v);
  } else if (std::fabs(v) >= 1e4) {
    std::snprintf(buf, sizeof buf, "%.0f", v);
  } else {
    std::snprintf(buf, sizeof buf, "%.4g", v);
  }
  return buf;
}

std::string format_csv_value(double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.10g", v);
  return buf;
}

std::string csv_field(const std::string& s) {
  if (s.find_first_of(",\"\n") == std::string::npos) return s;
  std::string q = "\"";
  for (char c : s) {
    if (c == '"') q += '"';
    q += c;
  }
  return q + "\"";
}

std::string md_field(const std::string& s) {
  std::string r;
  for (char c : s) {
    if (c == '|') r += '\\';
    r += c;
  }
  return r;
}

bool is_optional_default(const std::string& metric) {
  return metric.rfind("dram_", 0) == 0 || metric.rfind("requested_", 0) == 0 || metric.rfind("energy_", 0) == 0 || metric == metric::kFrameTimeMs ||
         metric == metric::kCycles;
}

/// The default metrics, in column order (figures absent from every run are dropped later).
std::vector<std::string> default_report_metrics(const SqlConnection& db) {
  std::vector<std::string> m = {metric::kFrameTimeMs, metric::kCycles, metric::kDramTotalMb, metric::kRequestedTotalMb};
  std::set<std::string> classes;
  {
    SqlStatement q(db, "SELECT DISTINCT substr(scope, 12) FROM stats WHERE scope GLOB 'frame/dram.*'");
    while (q.step()) classes.insert(q.text(0));
  }
  for (const char* c : kDramClassOrder) {
    if (classes.erase(c)) m.push_back(std::string("dram_") + c + "_mb");
  }
  for (const auto& c : classes) m.push_back("dram_" + c + "_mb");
  m.push_back(metric::kEnergyTotalMj);
  {
    SqlStatement q(db,
                   "SELECT DISTINCT substr(name, 1, length(name) - 3) FROM stats WHERE scope = 'frame/energy' "
                   "AND substr(name, 1, length(name) - 3) IN (SELECT component FROM v_energy_component) ORDER BY rowid");
    while (q.step()) m.push_back("energy_" + q.text(0) + "_mj");
  }
  m.push_back(metric::kShadedFragmentsPerPixel);
  m.push_back(metric::kOvershading);
  m.push_back(metric::kLightsPerPixel);
  return m;
}

/// The finished runs passing the user's filter, with their inputs ("config hash/trace hash").
struct SelectedRuns {
  std::vector<std::int64_t> ok;              ///< ascending
  std::map<std::int64_t, std::string> inputs;
  std::int64_t failed = 0;                   ///< failed runs passing the filter
  std::map<std::string, std::int64_t> failed_reasons;  ///< reason -> runs
};

/// A failed run's error as a reason shared by the runs it stopped: without the "FILE:LINE: " of
/// the trace it names (each point has its own), "(no error recorded)" when empty.
std::string failure_reason(const std::string& error) {
  if (error.empty()) return "(no error recorded)";
  std::string prefix, rest = error;
  if (rest.rfind("refused: ", 0) == 0) {
    prefix = "refused: ";
    rest = rest.substr(prefix.size());
  }
  // "path/x.trace:12: pass 'lighting' ...": drop up to the ": " after the first ":<digits>".
  for (std::size_t colon = rest.find(':'); colon != std::string::npos; colon = rest.find(':', colon + 1)) {
    std::size_t d = colon + 1;
    while (d < rest.size() && std::isdigit(static_cast<unsigned char>(rest[d]))) ++d;
    if (d > colon + 1 && rest.compare(d, 2, ": ") == 0) {
      rest = rest.substr(d + 2);
      break;
    }
  }
  return prefix + rest;
}

/// The keys of v_param: every stored parameter key and the pseudo-keys of the view.
std::vector<std::string> param_keys(const SqlConnection& db) {
  std::vector<std::string> keys = {"trace.technique", "trace.scene", "trace.lights",    "trace.width",
                                   "trace.height",    "trace.samples", "trace.resolution", "trace.path",
                                   "trace.hash",      "config.name",  "config.label"};
  SqlStatement q(db, "SELECT DISTINCT key FROM run_params");
  while (q.step()) keys.push_back(q.text(0));
  return keys;
}

bool ident_char(char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_'; }

/// Quotes, in an SQL condition, every dotted v_param key written as a bare word outside string
/// literals (gpu.mode -> "gpu.mode", which SQL would read as table.column) and returns the keys the
/// condition names, quoted or not, so that they can be made columns.
std::string quote_param_keys(const std::string& where, const std::vector<std::string>& keys,
                             std::vector<std::string>& used) {
  std::vector<std::string> dotted;
  for (const auto& k : keys) {
    if (k.find('.') != std::string::npos) dotted.push_back(k);
  }
  // Longest first, so that a key never matches inside a longer one.
  std::sort(dotted.begin(), dotted.end(), [](const std::string& a, const std::string& b) { return a.size() > b.size(); });
  std::string out;
  std::set<std::string> seen;
  char quote = 0;  // inside '...' or "..."
  for (std::size_t i = 0; i < where.size();) {
    const char c = where[i];
    if (quote) {
      out += c;
      if (c == quote) quote = 0;
      ++i;
      continue;
    }
    if (c == '\'' || c == '"') {
      if (c == '"') {  // an identifier already quoted: note it when it is a key
        const auto end = where.find('"', i + 1);
        if (end != std::string::npos) {
          const std::string id = where.substr(i + 1, end - i - 1);
          if (std::find(dotted.begin(), dotted.end(), id) != dotted.end()) seen.insert(id);
        }
      }
      quote = c;
      out += c;
      ++i;
      continue;
    }
    bool matched = false;
    if (i == 0 || !(ident_char(where[i - 1]) || where[i - 1] == '.')) {
      for (const auto& k : dotted) {
        if (where.compare(i, k.size(), k) == 0 && (i + k.size() == where.size() || !ident_char(where[i + k.size()]))) {
          out += "\"" + k + "\"";
          seen.insert(k);
          i += k.size();
          matched = true;
          break;
        }
      }
    }
    if (!matched) {
      out += c;
      ++i;
    }
  }
  used.assign(seen.begin(), seen.end());
  return out;
}

SelectedRuns select_runs(const SqlConnection& db, const std::string& where) {
  SelectedRuns r;
  try {
    // --where is an SQL condition by design, the only text spliced into a statement here; the
    // statement holds one statement only (SqlStatement refuses "1; DROP TABLE runs"). Keys of
    // v_param it names become columns of a per-run pivot (their names bound as values).
    std::vector<std::string> used;
    const std::string cond = where.empty() ? std::string("1") : quote_param_keys(where, param_keys(db), used);
    std::string pivot;
    if (!used.empty()) {
      std::string cols, in;
      for (std::size_t i = 0; i < used.size(); ++i) {
        cols += ", max(CASE WHEN key = ? THEN coalesce(value_num, value) END) AS \"" + used[i] + "\"";
        in += i ? ",?" : "?";
      }
      pivot = "WITH p AS (SELECT run_id AS p_run_id" + cols + " FROM v_param WHERE key IN (" + in +
              ") GROUP BY run_id) ";
    }
    SqlStatement q(db, pivot + "SELECT run_id, status, config_hash, trace_hash, coalesce(error, '') FROM v_run_summary" +
                           (used.empty() ? "" : " LEFT JOIN p ON p.p_run_id = run_id") + " WHERE (" + cond +
                           ") ORDER BY run_id");
    int b = 1;
    for (const auto& k : used) q.bind(b++, k);
    for (const auto& k : used) q.bind(b++, k);
    while (q.step()) {
      if (q.text(1) == "ok") {
        r.ok.push_back(q.int64(0));
        r.inputs[q.int64(0)] = q.text(2) + "/" + q.text(3);
      } else {
        ++r.failed;
        ++r.failed_reasons[failure_reason(q.text(4))];
      }
    }
  } catch (const InputError& e) {
    throw InputError("--where " + where, std::string(e.what()) +
                                             " (the condition is on v_run_summary's columns and v_param keys)");
  }
  return r;
}

/// The group key values of every selected run ("(none)" where a run has no such key).
std::map<std::int64_t, std::vector<std::string>> group_keys_of(const SqlConnection& db,
                                                               const std::vector<std::string>& keys,
                                                               const std::vector<std::string>& typed,
                                                               const std::set<std::int64_t>& selected) {
  std::map<std::int64_t, std::vector<std::string>> run_keys;
  for (std::size_t k = 0; k < keys.size(); ++k) {
    SqlStatement exists(db, "SELECT 1 FROM v_param WHERE key = ? LIMIT 1");
    exists.bind(1, keys[k]);
    if (!exists.step()) {
      std::string why = "no run has this key; use technique, scene, config, lights, camera, resolution, trace, "
                        "trace.width, trace.height, trace.samples, technique.<option> (the trace's technique "
                        "options) or a parameter key (`tbdrsim params` lists them)";
      if (keys[k].rfind("technique.", 0) == 0) {
        why += "; runs stored before tbdrsim recorded technique options (results database schema 3 and older) "
               "have none: `tbdrsim trace --list` shows each technique's options";
      }
      throw InputError("--by " + typed[k], why);
    }
    SqlStatement q(db, "SELECT run_id, value FROM v_param WHERE key = ?");
    q.bind(1, keys[k]);
    while (q.step()) {
      const std::int64_t id = q.int64(0);
      if (!selected.count(id)) continue;
      auto& v = run_keys[id];
      v.resize(keys.size(), "(none)");
      v[k] = q.text(1);
    }
  }
  for (const auto id : selected) run_keys[id].resize(keys.size(), "(none)");
  return run_keys;
}

/// Sums of one group's runs, per metric.
struct GroupSums {
  std::vector<double> sum;
  std::vector<std::int64_t> n;
  std::set<std::int64_t> runs;
  std::set<std::string> inputs;
};

/// Which metrics some selected run recorded (and with a non-zero value), and their units.
struct MetricsSeen {
  std::vector<bool> seen, nonzero;
  std::vector<std::string> units;
};

/// Adds every selected run's value of each metric to its group's sums.
MetricsSeen sum_metrics(const SqlConnection& db, const std::vector<std::string>& metrics,
                        const std::set<std::int64_t>& selected,
                        std::map<std::int64_t, std::vector<std::string>>& run_keys,
                        std::map<std::vector<std::string>, GroupSums>& groups) {
  MetricsSeen s{std::vector<bool>(metrics.size(), false), std::vector<bool>(metrics.size(), false),
                std::vector<std::string>(metrics.size())};
  if (selected.empty()) return s;
  std::map<std::string, std::size_t> metric_index;
  for (std::size_t i = 0; i < metrics.size(); ++i) metric_index[metrics[i]] = i;
  // One placeholder per metric: only "?" marks are spliced in, the names are bound.
  std::string in;
  for (std::size_t i = 0; i < metrics.size(); ++i) in += (i ? ",?" : "?");
  SqlStatement q(db, "SELECT run_id, metric, value, unit FROM v_metric WHERE metric IN (" + in + ")");
  for (std::size_t i = 0; i < metrics.size(); ++i) q.bind(static_cast<int>(i + 1), metrics[i]);
  while (q.step()) {
    const std::int64_t id = q.int64(0);
    if (!selected.count(id)) continue;
    const std::size_t m = metric_index.at(q.text(1));
    if (s.units[m].empty()) s.units[m] = q.text(3);
    if (q.is_null(2)) continue;
    const double v = q.real(2);
    auto& acc = groups[run_keys[id]];
    acc.sum[m] += v;
    acc.n[m] += 1;
    s.seen[m] = true;
    if (v != 0) s.nonzero[m] = true;
  }
  return s;
}

/// Two key values name the same thing: equal text, or equal numbers ("128" and "128.0").
bool key_equal(const std::string& a, const std::string& b) {
  double x = 0, y = 0;
  return a == b || (parse_number(a, x) && parse_number(b, y) && x == y);
}

/// Ranks the rows by `metric` among the rows sharing every group key but the last (all rows with
/// one key): 1 = least (or largest, t.rank_largest_first); equal values share a rank; rows without
/// the figure get 0 and sort last. Rows are then ordered by those keys and the rank; with `best`,
/// only the rows ranked 1 stay.
void apply_rank(ReportTable& t, const std::string& metric, bool best) {
  const std::size_t m = static_cast<std::size_t>(std::find(t.metrics.begin(), t.metrics.end(), metric) - t.metrics.begin());
  t.rank_metric = m;
  const std::size_t shared = t.group_keys.empty() ? 0 : t.group_keys.size() - 1;
  auto same_group = [&](const ReportTable::Row& a, const ReportTable::Row& b) {
    for (std::size_t k = 0; k < shared; ++k) {
      if (a.keys[k] != b.keys[k]) return false;
    }
    return true;
  };
  auto better = [&](double a, double b) { return t.rank_largest_first ? a > b : a < b; };
  std::vector<int> ranks(t.rows.size(), 0);
  for (std::size_t i = 0; i < t.rows.size(); ++i) {
    const auto& v = t.rows[i].values[m];
    if (!v) continue;
    ranks[i] = 1;
    for (std::size_t j = 0; j < t.rows.size(); ++j) {
      const auto& w = t.rows[j].values[m];
      if (j != i && w && same_group(t.rows[i], t.rows[j]) && better(*w, *v)) ++ranks[i];
    }
  }
  std::vector<std::size_t> order(t.rows.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    for (std::size_t k = 0; k < shared; ++k) {
      if (t.rows[a].keys[k] != t.rows[b].keys[k]) return key_less(t.rows[a].keys[k], t.rows[b].keys[k]);
    }
    const int ra = ranks[a] == 0 ? std::numeric_limits<int>::max() : ranks[a];
    const int rb = ranks[b] == 0 ? std::numeric_limits<int>::max() : ranks[b];
    return ra < rb;
  });
  std::vector<ReportTable::Row> rows;
  for (std::size_t i : order) {
    if (best && ranks[i] != 1) continue;
    rows.push_back(std::move(t.rows[i]));
    t.ranks.push_back(ranks[i]);
  }
  t.rows = std::move(rows);
}

/// Finds, for every row, the row that differs from it only in the baseline key, where that key
/// has the baseline value, and keeps that row's values beside it.
void apply_baseline(ReportTable& t, const std::string& typed_key, const std::string& typed) {
  const std::size_t kb = *t.baseline_key;
  std::set<std::string, decltype(&key_less)> present(&key_less);
  std::optional<std::string> stored;  // the baseline value as the database spells it
  for (const auto& r : t.rows) {
    present.insert(r.keys[kb]);
    if (key_equal(r.keys[kb], t.baseline_value)) stored = r.keys[kb];
  }
  if (!stored) {
    std::string values;
    for (const auto& v : present) values += (values.empty() ? "" : ", ") + v;
    throw InputError("--baseline " + typed, "no selected run has " + typed_key + " = " + t.baseline_value +
                                                (values.empty() ? std::string(" (no runs selected)") : "; its values: " + values));
  }
  t.baseline_value = *stored;
  std::map<std::vector<std::string>, std::size_t> index;
  for (std::size_t i = 0; i < t.rows.size(); ++i) index[t.rows[i].keys] = i;
  for (const auto& r : t.rows) {
    std::vector<std::string> k = r.keys;
    k[kb] = *stored;
    const auto it = index.find(k);
    if (it == index.end()) {
      t.baseline_values.emplace_back(r.values.size());
      ++t.rows_without_baseline;
    } else {
      t.baseline_values.push_back(t.rows[it->second].values);
    }
  }
}

}  // namespace

ReportTable build_report(const ResultsDb& db, const ReportOptions& opt) {
  const SqlConnection& sql = db.sql();
  ReportTable t;
  std::vector<std::string> keys;
  for (const auto& k : opt.by.empty() ? std::vector<std::string>{"technique"} : opt.by) {
    keys.push_back(canonical_group_key(k));
    t.group_keys.push_back(k);
  }
  std::string baseline_key_typed;
  if (!opt.baseline.empty()) {
    const auto eq = opt.baseline.find('=');
    if (eq == std::string::npos || eq == 0 || eq + 1 == opt.baseline.size()) {
      throw InputError("--baseline " + opt.baseline, "expected KEY=VALUE, e.g. pls.tile_buffer_bits_per_pixel=128 or technique=deferred");
    }
    baseline_key_typed = opt.baseline.substr(0, eq);
    t.baseline_value = opt.baseline.substr(eq + 1);
    const std::string key = canonical_group_key(baseline_key_typed);
    const auto it = std::find(keys.begin(), keys.end(), key);
    if (it == keys.end()) {
      keys.push_back(key);
      t.group_keys.push_back(baseline_key_typed);
      t.baseline_key = keys.size() - 1;
    } else {
      t.baseline_key = static_cast<std::size_t>(it - keys.begin());
    }
  }
  const SelectedRuns runs = select_runs(sql, opt.where);
  t.runs_failed = runs.failed;
  for (const auto& [reason, n] : runs.failed_reasons) t.failed_reasons.emplace_back(reason, n);
  std::stable_sort(t.failed_reasons.begin(), t.failed_reasons.end(),
                   [](const auto& a, const auto& b) { return a.second > b.second; });
  t.runs_used = static_cast<std::int64_t>(runs.ok.size());
  const std::set<std::int64_t> selected(runs.ok.begin(), runs.ok.end());
  auto run_keys = group_keys_of(sql, keys, t.group_keys, selected);

  const bool defaults = opt.metrics.empty();
  t.metrics = defaults ? default_report_metrics(sql) : opt.metrics;
  std::string rank_name = opt.rank;
  if (!rank_name.empty()) {
    const auto colon = rank_name.rfind(':');
    if (colon != std::string::npos) {
      const std::string order = rank_name.substr(colon + 1);
      if (order != "max" && order != "min") {
        throw InputError("--rank " + opt.rank, "expected METRIC, METRIC:min (least first, the default) or METRIC:max");
      }
      t.rank_largest_first = order == "max";
      rank_name = rank_name.substr(0, colon);
    }
    if (std::find(t.metrics.begin(), t.metrics.end(), rank_name) == t.metrics.end()) t.metrics.push_back(rank_name);
  } else if (opt.best) {
    throw InputError("--best", "needs --rank METRIC: the figure that says which row is best");
  }
  std::map<std::vector<std::string>, GroupSums> groups;
  for (const auto id : runs.ok) {
    auto& acc = groups[run_keys[id]];
    acc.sum.resize(t.metrics.size(), 0.0);
    acc.n.resize(t.metrics.size(), 0);
    acc.runs.insert(id);
    acc.inputs.insert(runs.inputs.at(id));
  }
  const MetricsSeen seen = sum_metrics(sql, t.metrics, selected, run_keys, groups);
  t.units = seen.units;
  if ((!defaults || !rank_name.empty()) && !runs.ok.empty()) {
    for (std::size_t m = 0; m < t.metrics.size(); ++m) {
      if (seen.seen[m] || (defaults && t.metrics[m] != rank_name)) continue;
      SqlStatement any(sql, "SELECT 1 FROM v_metric WHERE metric = ? LIMIT 1");
      any.bind(1, t.metrics[m]);
      if (!any.step()) {
        const bool only_ranked = t.metrics[m] == rank_name &&
                                 std::find(opt.metrics.begin(), opt.metrics.end(), rank_name) == opt.metrics.end();
        throw InputError((only_ranked ? "--rank " : "--metric ") + t.metrics[m],
                         "no run has this figure; see docs/queries.md or `SELECT DISTINCT metric FROM v_metric`");
      }
    }
  }
  // Keep the default metrics some run recorded (traffic classes and energy components only when
  // some run has a non-zero value).
  std::vector<std::size_t> keep;
  for (std::size_t m = 0; m < t.metrics.size(); ++m) {
    if (!defaults || t.metrics[m] == rank_name ||
        (seen.seen[m] && (seen.nonzero[m] || !is_optional_default(t.metrics[m])))) {
      keep.push_back(m);
    }
  }
  std::vector<std::string> metrics, units;
  for (auto m : keep) {
    metrics.push_back(t.metrics[m]);
    units.push_back(t.units[m]);
  }
  for (auto& [k, acc] : groups) {
    if (acc.inputs.size() > 1) ++t.mixed_groups;
    ReportTable::Row row;
    row.keys = k;
    row.runs = static_cast<std::int64_t>(acc.runs.size());
    for (auto m : keep) {
      if (acc.n[m] > 0) {
        row.values.push_back(acc.sum[m] / static_cast<double>(acc.n[m]));
      } else {
        row.values.push_back(std::nullopt);
      }
    }
    t.rows.push_back(std::move(row));
  }
  t.metrics = std::move(metrics);
  t.units = std::move(units);
  if (defaults) {
    t.sections = default_sections(t.metrics);
  } else {
    ReportTable::Section all;
    for (std::size_t m = 0; m < t.metrics.size(); ++m) {
      all.metrics.push_back(m);
      all.headers.push_back(header_text(t.metrics[m], t.units[m]));
    }
    t.sections.push_back(std::move(all));
  }
  std::sort(t.rows.begin(), t.rows.end(), [](const ReportTable::Row& a, const ReportTable::Row& b) {
    for (std::size_t i = 0; i < a.keys.size(); ++i) {
      if (a.keys[i] != b.keys[i]) return key_less(a.keys[i], b.keys[i]);
    }
    return false;
  });
  if (!rank_name.empty()) apply_rank(t, rank_name, opt.best);
  if (t.baseline_key) apply_baseline(t, baseline_key_typed, opt.baseline);
  return t;
}

namespace {

/// Prints one grid: the first `label_cols` columns left-aligned, the others right-aligned.
void print_grid(const std::vector<std::vector<std::string>>& grid, std::size_t label_cols, ReportFormat format,
                std::ostream& out) {
  std::vector<std::size_t> width(grid.front().size(), 0);
  for (const auto& line : grid) {
    for (std::size_t c = 0; c < line.size(); ++c) width[c] = std::max(width[c], line[c].size());
  }
  if (format == ReportFormat::Markdown) {
    for (std::size_t i = 0; i < grid.size(); ++i) {
      out << "|";
      for (std::size_t c = 0; c < grid[i].size(); ++c) {
        const std::string cell = md_field(grid[i][c]);
        const std::size_t w = std::max<std::size_t>(width[c], 3);
        const std::size_t pad = w > grid[i][c].size() ? w - grid[i][c].size() : 0;
        out << " " << (c < label_cols ? cell + std::string(pad, ' ') : std::string(pad, ' ') + cell) << " |";
      }
      out << "\n";
      if (i == 0) {
        out << "|";
        for (std::size_t c = 0; c < grid[0].size(); ++c) {
          const std::size_t w = std::max<std::size_t>(width[c], 3);
          out << (c < label_cols ? " " + std::string(w, '-') + " |" : " " + std::string(w - 1, '-') + ": |");
        }
        out << "\n";
      }
    }
    return;
  }
  for (std::size_t i = 0; i < grid.size(); ++i) {
    std::string line;
    for (std::size_t c = 0; c < grid[i].size(); ++c) {
      const std::string& cell = grid[i][c];
      const std::size_t pad = width[c] - cell.size();
      if (c) line += "  ";
      line += c < label_cols ? cell + std::string(pad, ' ') : std::string(pad, ' ') + cell;
    }
    out << line << "\n";
    if (i == 0) {
      std::string rule;
      for (std::size_t c = 0; c < width.size(); ++c) rule += (c ? "  " : "") + std::string(width[c], '-');
      out << rule << "\n";
    }
  }
}

}  // namespace

void print_report(const ReportTable& t, ReportFormat format, bool transpose, std::ostream& out) {
  const bool csv = format == ReportFormat::Csv;
  auto value_text = [&](const std::optional<double>& v) {
    if (!v) return csv ? std::string() : std::string("-");
    return csv ? format_csv_value(*v) : format_value(*v);
  };
  const bool compare = t.baseline_key.has_value();
  const bool ranked = t.rank_metric.has_value();
  const std::string rank_header =
      ranked ? (csv ? std::string("rank") : "rank (" + t.metrics[*t.rank_metric] + (t.rank_largest_first ? ", largest" : ", least") + " first)")
             : std::string();
  // One printed column per metric, or three with a baseline: the value, its difference from the
  // baseline group's and their ratio.
  struct Column {
    std::string header;
    std::size_t metric = 0;
    int kind = 0;  ///< 0 value, 1 difference, 2 ratio
  };
  auto cell = [&](const Column& c, std::size_t row) -> std::string {
    const std::optional<double>& v = t.rows[row].values[c.metric];
    if (c.kind == 0) return value_text(v);
    const std::optional<double>& b = t.baseline_values[row][c.metric];
    if (!v || !b) return csv ? std::string() : std::string("-");
    char buf[64];
    if (c.kind == 1) {
      if (csv) return format_csv_value(*v - *b);
      const std::string d = format_value(*v - *b);
      return (*v - *b > 0 ? "+" : "") + d;
    }
    if (*b == 0) return csv ? std::string() : std::string("-");
    std::snprintf(buf, sizeof buf, csv ? "%.10g" : "%.3f", *v / *b);
    return buf;
  };
  // CSV: one flat table with the full metric names.
  std::vector<ReportTable::Section> sections = t.sections;
  if (csv || sections.empty()) {
    ReportTable::Section all;
    for (std::size_t m = 0; m < t.metrics.size(); ++m) {
      all.metrics.push_back(m);
      all.headers.push_back(csv ? t.metrics[m] : header_text(t.metrics[m], t.units[m]));
    }
    sections = {all};
  }
  if (!csv) {
    out << t.runs_used << " finished run(s)";
    if (t.runs_failed) out << " (" << t.runs_failed << " failed run(s) left out)";
    out << ", grouped by ";
    for (std::size_t k = 0; k < t.group_keys.size(); ++k) out << (k ? " x " : "") << t.group_keys[k];
    out << "; the runs of a group averaged\n";
    if (t.runs_failed) {
      // Which runs did not finish, and why (a study's refused points, a sweep's failed ones).
      constexpr std::size_t kReasonsShown = 5;
      out << "left out: " << t.runs_failed << " failed run(s), status failed, by reason:\n";
      for (std::size_t i = 0; i < t.failed_reasons.size() && i < kReasonsShown; ++i) {
        out << "  " << t.failed_reasons[i].second << " x " << t.failed_reasons[i].first << "\n";
      }
      if (t.failed_reasons.size() > kReasonsShown) {
        out << "  (" << t.failed_reasons.size() - kReasonsShown << " other reason(s): "
            << "`SELECT run_id, technique, error FROM v_run_summary WHERE status <> 'ok'` lists every one)\n";
      }
    }
    if (ranked) {
      out << "ranked by " << t.metrics[*t.rank_metric] << (t.rank_largest_first ? " (largest first)" : " (least first)");
      if (t.group_keys.size() > 1) {
        out << " among the rows of equal ";
        for (std::size_t k = 0; k + 1 < t.group_keys.size(); ++k) out << (k ? ", " : "") << t.group_keys[k];
      }
      out << "\n";
    }
    if (compare) {
      out << "baseline: " << t.group_keys[*t.baseline_key] << " = " << t.baseline_value
          << " (each group against the one that differs only in " << t.group_keys[*t.baseline_key]
          << "; -base: difference, /base: ratio)\n";
      if (t.rows_without_baseline) {
        out << "note: " << t.rows_without_baseline << " group(s) have no baseline group to compare with (shown as -)\n";
      }
    }
    if (t.mixed_groups) {
      out << "note: " << t.mixed_groups
          << " group(s) average runs of different configurations or traces; separate them with more --by keys "
             "(config, lights, a parameter key) or --where\n";
    }
    if (t.rows.empty()) {
      out << "(no finished runs match)\n";
      return;
    }
  }
  for (std::size_t s = 0; s < sections.size(); ++s) {
    const auto& sec = sections[s];
    std::vector<Column> cols;
    for (std::size_t i = 0; i < sec.metrics.size(); ++i) {
      cols.push_back({sec.headers[i], sec.metrics[i], 0});
      if (compare) {
        cols.push_back({sec.headers[i] + (csv ? "_delta" : " -base"), sec.metrics[i], 1});
        cols.push_back({sec.headers[i] + (csv ? "_ratio" : " /base"), sec.metrics[i], 2});
      }
    }
    std::vector<std::vector<std::string>> grid;
    std::size_t label_cols = 0;
    if (!transpose) {
      std::vector<std::string> head = t.group_keys;
      head.push_back("runs");
      if (ranked) head.push_back(rank_header);
      for (const auto& c : cols) head.push_back(c.header);
      grid.push_back(head);
      for (std::size_t r = 0; r < t.rows.size(); ++r) {
        std::vector<std::string> line = t.rows[r].keys;
        line.push_back(std::to_string(t.rows[r].runs));
        if (ranked) line.push_back(t.ranks[r] ? std::to_string(t.ranks[r]) : std::string(csv ? "" : "-"));
        for (const auto& c : cols) line.push_back(cell(c, r));
        grid.push_back(line);
      }
      label_cols = t.group_keys.size();
    } else {
      std::string corner;
      for (std::size_t k = 0; k < t.group_keys.size(); ++k) corner += (k ? " / " : "") + t.group_keys[k];
      std::vector<std::string> head = {"metric \\ " + corner};
      for (const auto& r : t.rows) {
        std::string label;
        for (std::size_t k = 0; k < r.keys.size(); ++k) label += (k ? " / " : "") + r.keys[k];
        head.push_back(label);
      }
      grid.push_back(head);
      std::vector<std::string> runs = {"runs"};
      for (const auto& r : t.rows) runs.push_back(std::to_string(r.runs));
      grid.push_back(runs);
      if (ranked) {
        std::vector<std::string> rank_line = {rank_header};
        for (std::size_t r = 0; r < t.rows.size(); ++r) {
          rank_line.push_back(t.ranks[r] ? std::to_string(t.ranks[r]) : std::string(csv ? "" : "-"));
        }
        grid.push_back(rank_line);
      }
      for (const auto& c : cols) {
        std::vector<std::string> line = {c.header};
        for (std::size_t r = 0; r < t.rows.size(); ++r) line.push_back(cell(c, r));
        grid.push_back(line);
      }
      label_cols = 1;
    }
    if (csv) {
      for (const auto& line : grid) {
        for (std::size_t c = 0; c < line.size(); ++c) out << (c ? "," : "") << csv_field(line[c]);
        out << "\n";
      }
      continue;
    }
    if (!sec.title.empty()) {
      out << "\n" << (format == ReportFormat::Markdown ? "### " : "") << sec.title << "\n";
      if (format == ReportFormat::Markdown) out << "\n";
    } else if (format == ReportFormat::Markdown) {
      out << "\n";
    }
    print_grid(grid, label_cols, format, out);
  }
}

DerivedFigures read_derived_figures(const ResultsDb& db, std::int64_t run_id) {
  SqlStatement q(db.sql(),
                 "SELECT frame_time_ms, cycles, dram_total_mb, requested_total_mb, energy_total_mj, "
                 "shaded_fragments_per_pixel, overshading, lights_per_pixel, lights_per_fragment, config_label "
                 "FROM v_run_summary WHERE run_id = ?", run_id);
  if (!q.step()) throw InputError(db.path(), "no run " + std::to_string(run_id));
  auto get = [&](int c) -> std::optional<double> {
    if (q.is_null(c)) return std::nullopt;
    return q.real(c);
  };
  DerivedFigures d;
  d.frame_time_ms = get(0);
  d.cycles = get(1);
  d.dram_total_mb = get(2);
  d.requested_total_mb = get(3);
  d.energy_total_mj = get(4);
  d.shaded_fragments_per_pixel = get(5);
  d.overshading = get(6);
  d.lights_per_pixel = get(7);
  d.lights_per_fragment = get(8);
  d.config_label = q.text(9);
  return d;
}

}  // namespace tbdr
