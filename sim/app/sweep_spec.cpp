#include "app/sweep_spec.hpp"

#include <glob.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

#include "kernel/errors.hpp"
#include "kernel/hash.hpp"
#include "models/config_checks.hpp"
#include "models/hw_config.hpp"

namespace tbdr {

namespace fs = std::filesystem;

namespace {

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

/// `p` (a path the sweep file names at `where`) checked against the file system's length limits,
/// so a test for its existence cannot throw a filesystem_error; InputError naming `where` if not.
const std::string& checked_length(const std::string& p, const std::string& what, const std::string& where) {
  try {
    check_path_length(p, what);
  } catch (const InputError& e) {
    throw InputError(where, bare_message(e));
  }
  return p;
}

ConfigNameLookup g_config_lookup = nullptr;  ///< set_sweep_config_lookup

/// A config value written in the sweep file: the file beside the sweep file (or the path as
/// written when absolute), else, for a bare name, the preset the lookup finds (as --config would).
std::string sweep_config_path(const fs::path& base_dir, const std::string& item, const std::string& where) {
  const std::string p = checked_length(relative_to(base_dir, item), "config file", where);
  std::error_code ec;
  if (g_config_lookup == nullptr || fs::symlink_status(p, ec).type() != fs::file_type::not_found ||
      fs::path(item).has_parent_path()) {
    return p;
  }
  try {
    return g_config_lookup(item);
  } catch (const InputError& e) {
    throw InputError(where, "config file '" + p + "' not found, nor a preset of that name: " + bare_message(e));
  }
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

/// Checks that `key` is a hardware parameter and `value` a valid value for it; returns the value's
/// canonical text (format_param_value: "1.0" and "1" of a real are both "1"), so two spellings of
/// one value are seen as one.
std::string check_param_value(const std::string& key, const std::string& value, const std::string& where) {
  const ParamTable& table = hw_params().table();
  ResolvedParams p = table.defaults();
  try {
    table.apply_override(p, key + "=" + value);
  } catch (const InputError& e) {
    throw InputError(where, bare_message(e));
  }
  return format_param_value(p.values[static_cast<std::size_t>(table.find(key))]);
}

/// check_input_file for a file a sweep names at `where`: the error is located at the sweep's line.
void check_named_file(const std::string& p, const std::string& what, const std::string& where, bool allow_special) {
  try {
    check_input_file(p, what, allow_special);
  } catch (const InputError& e) {
    throw InputError(where, what + " '" + p + "': " + bare_message(e));
  }
}

std::vector<std::string> expand_traces(const std::string& pattern, const fs::path& base_dir, const std::string& where) {
  const std::string p = checked_length(relative_to(base_dir, pattern), "trace", where);
  if (!has_glob_chars(pattern)) {
    check_named_file(p, "trace file", where, false);
    return {p};
  }
  glob_t g{};
  const int rc = ::glob(p.c_str(), 0, nullptr, &g);
  std::vector<std::string> out;
  if (rc == 0) {
    for (std::size_t i = 0; i < g.gl_pathc; ++i) {
      // A match that cannot be examined (permission denied, a symlink loop) is refused by name;
      // folders, devices and the like are not traces and are passed over.
      const std::string m = g.gl_pathv[i];
      std::error_code ec;
      const fs::file_status st = fs::status(m, ec);
      if ((ec && st.type() != fs::file_type::not_found) || st.type() == fs::file_type::regular) {
        try {
          check_input_file(m, "trace file");
        } catch (const InputError& e) {
          globfree(&g);
          throw InputError(where, "trace pattern '" + p + "' matches '" + m + "': " + bare_message(e));
        }
        out.push_back(m);
      }
    }
  }
  globfree(&g);
  if (out.empty()) throw InputError(where, "trace pattern '" + p + "' matches no file");
  return out;
}

/// Checks, at read time, the constraints between parameters (models/config_checks.hpp) of every
/// configuration the sweep's points resolve to. Only the axes that set a constrained parameter or
/// a config file can change the outcome, so only their combinations are resolved (a sweep of a
/// million points over unconstrained parameters resolves one). `key_where`: the file:line of
/// every key the sweep file sets or sweeps. InputError at the line of the first involved key the
/// sweep sets (else the sweep file), naming the point and where each involved value came from.
void check_point_configs(const SweepSpec& spec, const std::map<std::string, std::string>& key_where) {
  const auto& constrained = constrained_param_keys();
  const std::set<std::string> ckeys(constrained.begin(), constrained.end());
  std::vector<std::size_t> relevant;
  for (std::size_t a = 0; a < spec.axes.size(); ++a) {
    for (const auto& k : spec.axes[a].keys) {
      if (k == "config" || ckeys.count(k)) {
        relevant.push_back(a);
        break;
      }
    }
  }
  std::size_t combos = 1;  // <= kMaxSweepPoints: check_sweep_size ran first
  for (std::size_t a : relevant) combos *= spec.axes[a].values.size();
  const auto& reg = hw_params();
  const ParamTable& table = reg.table();
  std::map<std::vector<std::string>, ResolvedParams> bases;
  for (std::size_t c = 0; c < combos; ++c) {
    std::vector<std::string> configs = spec.base_configs;
    std::vector<std::string> sets = spec.sets;
    std::string label;
    std::size_t rest = c;
    std::vector<std::size_t> digit(relevant.size());
    for (std::size_t r = relevant.size(); r-- > 0;) {
      digit[r] = rest % spec.axes[relevant[r]].values.size();
      rest /= spec.axes[relevant[r]].values.size();
    }
    for (std::size_t r = 0; r < relevant.size(); ++r) {
      const SweepAxis& axis = spec.axes[relevant[r]];
      for (std::size_t k = 0; k < axis.keys.size(); ++k) {
        const std::string& val = axis.values[digit[r]][k];
        (axis.keys[k] == "config" ? configs : sets).push_back(axis.keys[k] == "config" ? val : axis.keys[k] + "=" + val);
        label += (label.empty() ? "" : " ") + axis.keys[k] + "=" + val;
      }
    }
    ResolvedParams params;
    try {
      // Config files are read once per list of them; each combination is a copy with its overrides.
      auto base = bases.find(configs);
      if (base == bases.end()) base = bases.emplace(configs, table.resolve(configs, {})).first;
      params = base->second;
      for (const auto& set : sets) table.apply_override(params, set);
    } catch (const InputError& e) {
      throw InputError(e.where().rfind("--set ", 0) == 0 ? spec.path : e.where(),
                       (label.empty() ? "" : "the point " + label + ": ") + bare_message(e));
    }
    const auto bad = first_constraint_violation(reg.build(params));
    if (!bad) continue;
    std::string where;
    std::string origins;
    for (const auto& key : bad->keys) {
      const auto it = key_where.find(key);
      const int i = table.find(key);
      const std::string origin = it != key_where.end() ? it->second
                                 : i < 0            ? "default"
                                                    : params.origins[static_cast<std::size_t>(i)].text;
      if (where.empty() && origin != "default") where = origin;
      origins += (origins.empty() ? "" : "; ") + key + " from " + origin;
    }
    throw InputError(where.empty() ? spec.path : where,
                     (label.empty() ? "every point" : "the point " + label) + ": " + bad->message + " [" + origins +
                         "]; docs/sweeps.md");
  }
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

namespace {

/// Applies one [sweep] line: name, config (base files), trace (files or globs), repetitions.
void apply_sweep_key(SweepSpec& spec, const IniLine& l, const std::string& value, const std::string& where,
                     const fs::path& base_dir) {
  if (l.name == "name") {
    if (value.empty()) throw InputError(where, "empty name");
    spec.name = value;
  } else if (l.name == "config") {
    for (const auto& item : split_commas(value)) {
      if (item.empty()) throw InputError(where, "empty config file name");
      const std::string p = sweep_config_path(base_dir, item, where);
      check_named_file(p, "config file", where, false);
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
  } else {
    throw InputError(where, "unknown key '" + l.name + "' in [sweep] (known: name, config, trace, repetitions)");
  }
}

/// The checked values of one [vary] or [zip.NAME] line: config files (a plain list, paths may
/// contain "..", made relative to the working directory) or parameter values (ranges expanded).
std::vector<std::string> axis_values(const IniLine& l, const std::string& value, const std::string& where,
                                     const fs::path& base_dir) {
  if (l.name != "config") {
    std::vector<std::string> values = expand_value_list(value, where);
    std::map<std::string, std::string> canonical;  // canonical text -> the spelling met first
    for (const auto& v : values) {
      const auto [it, fresh] = canonical.emplace(check_param_value(l.name, v, where), v);
      if (!fresh) {
        throw InputError(where, "'" + v + "' and '" + it->second + "' are the same value of " + l.name + " (" +
                                    it->first + "); each point would run twice");
      }
    }
    return values;
  }
  std::vector<std::string> values = split_commas(value);
  std::set<std::string> seen;
  for (const auto& v : values) {
    if (v.empty()) throw InputError(where, "empty config file name in '" + value + "'");
    if (!seen.insert(v).second) throw InputError(where, "config file '" + v + "' listed twice");
  }
  for (auto& v : values) {
    v = sweep_config_path(base_dir, v, where);
    check_named_file(v, "config file", where, false);
  }
  return values;
}

/// Adds one key of a zip group to its axis (created at the group's first key).
void add_zip_key(SweepSpec& spec, std::map<std::string, std::size_t>& zip_axis, const IniLine& l,
                 const std::vector<std::string>& values, const std::string& where) {
  auto z = zip_axis.find(l.section);
  if (z == zip_axis.end()) {
    SweepAxis axis;
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

// ---------------------------------------------------------------------------------------------
// [generate]: traces made by `tbdrsim trace` for every combination of the section's lists

/// The [generate] keys that are `tbdrsim trace` options of the same name (besides option.KEY).
constexpr const char* kGenerateKeys[] = {"technique", "scene", "camera", "resolution", "lights", "light-seed", "samples", "light-file"};

/// One [generate] key with its values (ranges expanded), in file order.
struct GenerateKey {
  std::string name;                 ///< "lights", "option.pls_bytes", ...
  std::vector<std::string> values;  ///< paths already relative to the working folder
  std::string where;
};

/// A scene value: atrium[:detail] stays as written; anything else is a glTF file relative to the
/// sweep file, which must exist.
bool is_atrium_scene(const std::string& v) { return v == "atrium" || v.rfind("atrium:", 0) == 0; }

/// The values of one [generate] line, checked as far as they can be without generating: files
/// that exist (technique names and option keys: expand_generate); the rest (light counts,
/// resolutions, option values) `tbdrsim trace` checks when the sweep generates the trace.
GenerateKey generate_key(const IniLine& l, const std::string& value, const std::string& where, const fs::path& base_dir) {
  const bool option = l.name.rfind("option.", 0) == 0 && l.name.size() > 7;
  if (!option && std::find(std::begin(kGenerateKeys), std::end(kGenerateKeys), l.name) == std::end(kGenerateKeys)) {
    std::string known;
    for (const char* k : kGenerateKeys) known += std::string(known.empty() ? "" : ", ") + k;
    throw InputError(where, "unknown key '" + l.name + "' in [generate] (known: " + known +
                                ", option.KEY for a technique option; `tbdrsim trace --list` lists them)");
  }
  GenerateKey key{l.name, {}, where};
  if (l.name == "scene" || l.name == "light-file") {
    for (const auto& v : split_commas(value)) {
      if (v.empty()) throw InputError(where, "empty item in the list '" + value + "'");
      if (l.name == "scene" && is_atrium_scene(v)) {
        key.values.push_back(v);
        continue;
      }
      const std::string p = checked_length(relative_to(base_dir, v), l.name, where);
      if (!fs::is_regular_file(p)) throw InputError(where, l.name + " '" + p + "' not found");
      key.values.push_back(p);
    }
    std::set<std::string> seen;
    for (const auto& v : key.values) {
      if (!seen.insert(v).second) throw InputError(where, "'" + v + "' listed twice");
    }
  } else {
    key.values = expand_value_list(value, where);
  }
  return key;
}

/// The option keys technique `t` reads; InputError naming `where` and the known techniques when
/// `t` is not one of `generators`.
const std::vector<std::string>& technique_options(const TraceGenerators& generators, const std::string& t,
                                                  const std::string& where) {
  for (const auto& [name, options] : generators.techniques) {
    if (name == t) return options;
  }
  std::string known;
  for (const auto& [name, options] : generators.techniques) known += (known.empty() ? "" : ", ") + name;
  throw InputError(where, "unknown technique '" + t + "' (known: " + known + ")");
}

/// Whether technique `t` reads option `key` (without the "option." prefix).
bool technique_has_option(const TraceGenerators& generators, const std::string& t, const std::string& key) {
  const auto& options = technique_options(generators, t, "");
  return std::find(options.begin(), options.end(), key) != options.end();
}

/// The requests of a [generate] section: per technique (in order), the cartesian product of the
/// keys that apply to it (every key but the options it does not read), the last key fastest.
std::vector<TraceRequest> expand_generate(const std::vector<GenerateKey>& keys, const TraceGenerators& generators,
                                         const std::string& path, long line) {
  const std::string where = path + ":" + std::to_string(line);
  const auto tech = std::find_if(keys.begin(), keys.end(), [](const GenerateKey& k) { return k.name == "technique"; });
  if (tech == keys.end()) throw InputError(where, "[generate] names no technique (technique = NAME, or a list)");
  for (const auto& t : tech->values) technique_options(generators, t, tech->where);
  auto has_option = [&](const std::string& t, const std::string& key) { return technique_has_option(generators, t, key); };
  for (const auto& k : keys) {
    if (k.name.rfind("option.", 0) != 0) continue;
    const std::string opt = k.name.substr(7);
    if (std::none_of(tech->values.begin(), tech->values.end(), [&](const std::string& t) { return has_option(t, opt); })) {
      std::string known;
      for (const auto& t : tech->values) {
        for (const auto& o : technique_options(generators, t, tech->where)) known += (known.empty() ? "" : ", ") + o;
      }
      throw InputError(k.where, "no technique of this [generate] has the option '" + opt + "'" +
                                    (known.empty() ? " (they take none)" : " (theirs: " + known + ")"));
    }
  }
  // Counted before any request is made, with a cap, so a typing error cannot allocate millions.
  std::uint64_t total = 0;
  for (const auto& t : tech->values) {
    std::uint64_t n = 1;
    for (const auto& k : keys) {
      if (&k == &*tech || (k.name.rfind("option.", 0) == 0 && !has_option(t, k.name.substr(7)))) continue;
      n = n > kMaxSweepPoints / k.values.size() ? kMaxSweepPoints + 1 : n * k.values.size();
    }
    total = std::min<std::uint64_t>(total + n, kMaxSweepPoints + 1);
  }
  if (total > kMaxSweepPoints) {
    throw InputError(where, "[generate] makes more than " + std::to_string(kMaxSweepPoints) +
                                " traces; split it into several sweeps (docs/limits.md)");
  }
  std::vector<TraceRequest> out;
  for (const auto& t : tech->values) {
    std::vector<const GenerateKey*> used;
    for (const auto& k : keys) {
      if (&k == &*tech || (k.name.rfind("option.", 0) == 0 && !has_option(t, k.name.substr(7)))) continue;
      used.push_back(&k);
    }
    std::vector<std::size_t> digit(used.size(), 0);
    while (true) {
      TraceRequest r;
      r.technique = t;
      r.where = where;
      r.args = {"--technique", t};
      r.arg_where = {tech->where};
      r.label = t;
      Fnv1a64 id;
      id.update("tbdrsim " + generators.version + "\ntechnique=" + t + "\n");
      for (std::size_t u = 0; u < used.size(); ++u) {
        const GenerateKey& k = *used[u];
        const std::string& v = k.values[digit[u]];
        const bool option = k.name.rfind("option.", 0) == 0;
        const std::string shown = option ? k.name.substr(7) : k.name;
        if (option) {
          r.args.insert(r.args.end(), {"--option", shown + "=" + v});
        } else {
          r.args.insert(r.args.end(), {"--" + k.name, v});
        }
        r.arg_where.push_back(k.where);
        const bool file = k.name == "light-file" || (k.name == "scene" && !is_atrium_scene(v));
        if (k.values.size() > 1) r.label += " " + shown + "=" + (file ? fs::path(v).filename().string() : v);
        // Files by content, so a sweep run from another folder (another relative path) finds them.
        id.update(k.name + "=" + (file ? "file:" + hash_file_hex(v) : v) + "\n");
      }
      r.id = id.hex();
      out.push_back(std::move(r));
      std::size_t u = used.size();
      while (u > 0 && ++digit[u - 1] == used[u - 1]->values.size()) digit[--u] = 0;
      if (u == 0) break;
    }
  }
  return out;
}

}  // namespace

std::string generated_trace_dir(const std::string& db_path) {
  const fs::path db(db_path);
  return (db.parent_path() / (db.stem().string() + ".traces")).string();
}

std::string generated_trace_path(const SweepSpec& spec, const TraceRequest& request) {
  return (fs::path(spec.generated_dir) / (request.technique + "-" + request.id + ".trace")).string();
}

void set_sweep_config_lookup(ConfigNameLookup lookup) { g_config_lookup = lookup; }

SweepSpec parse_sweep_file(const std::string& path, const std::vector<std::string>& traces, const std::string& db_path,
                           const TraceGenerators& generators) {
  IniRules rules;
  rules.what = "sweep file";
  rules.known_section = [](const std::string& section) {
    return section == "sweep" || section == "set" || section == "vary" || section == "generate" ||
           (section.rfind("zip.", 0) == 0 && section.size() > 4);
  };
  rules.known_sections = "sweep, set, vary, zip.NAME, generate";
  rules.keys_need_section = true;
  rules.sections_once = true;
  rules.may_repeat = [](const IniLine& l) { return l.section == "sweep" && (l.name == "config" || l.name == "trace"); };
  std::map<std::string, long> section_lines;
  const std::vector<IniLine> lines = read_ini_file(path, rules, &section_lines);

  SweepSpec spec;
  spec.path = path;
  spec.name = fs::path(path).stem().string();
  spec.generated_dir = generated_trace_dir(db_path.empty() ? spec.name + ".db" : db_path);
  const fs::path base_dir = fs::path(path).parent_path();
  std::vector<GenerateKey> generate_keys;
  std::map<std::string, std::string> key_where;  // every key set or swept, for conflicts
  std::map<std::string, std::size_t> zip_axis;   // zip group -> axis index
  for (std::size_t i = 0; i < lines.size(); ++i) {
    const IniLine& l = lines[i];
    const std::string where = path + ":" + std::to_string(l.line);
    const std::string value = trim(l.value);
    if (l.section == "sweep") {
      if (l.name == "trace" && !traces.empty()) continue;  // replaced by the command line's
      apply_sweep_key(spec, l, value, where, base_dir);
      continue;
    }
    if (l.section == "generate") {
      generate_keys.push_back(generate_key(l, value, where, base_dir));
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
    } else if (l.section == "vary") {
      SweepAxis axis;
      axis.keys = {l.name};
      for (auto& v : axis_values(l, value, where, base_dir)) axis.values.push_back({v});
      axis.where = {where};
      spec.axes.push_back(std::move(axis));
    } else {
      add_zip_key(spec, zip_axis, l, axis_values(l, value, where, base_dir), where);
    }
  }
  for (const auto& t : traces) {
    const auto found = expand_traces(t, fs::path(), "--trace " + t);
    spec.traces.insert(spec.traces.end(), found.begin(), found.end());
  }
  if (section_lines.count("generate")) spec.generate = expand_generate(generate_keys, generators, path, section_lines["generate"]);
  if (!section_lines.count("sweep")) throw InputError(path, "no [sweep] section (it names the traces)");
  if (spec.traces.empty() && spec.generate.empty()) {
    throw InputError(path, section_lines["sweep"],
                     "[sweep] names no trace (trace = FILE or GLOB, repeatable) and there is no [generate] section");
  }
  for (const auto& [sec, line] : section_lines) {
    if (sec.rfind("zip.", 0) == 0 && !zip_axis.count(sec)) throw InputError(path, line, "[" + sec + "] is empty");
  }
  check_sweep_size(spec);
  check_point_configs(spec, key_where);
  return spec;
}

void check_sweep_size(const SweepSpec& spec) {
  // Multiplied with a check at each step, so 10^9 points (or an overflow) are refused, never allocated.
  std::uint64_t points = static_cast<std::uint64_t>(std::max(spec.repetitions, 1));
  std::string product = std::to_string(points) + " repetitions";
  auto times = [&](std::uint64_t n, const std::string& what) {
    product += " x " + std::to_string(n) + " " + what;
    points = n != 0 && points > kMaxSweepPoints / n ? kMaxSweepPoints + 1 : points * n;
  };
  times(spec.traces.size() + spec.generate.size(), "traces");
  for (const auto& a : spec.axes) times(a.values.size(), a.keys.front() + (a.keys.size() > 1 ? " (zip)" : ""));
  if (points > kMaxSweepPoints) {
    throw InputError(spec.path, "the sweep has more than " + std::to_string(kMaxSweepPoints) + " points (" + product +
                                    "); split it into several sweeps (docs/limits.md)");
  }
}

SweepPoints::SweepPoints(const SweepSpec& spec, SweepSlice slice) : spec_(&spec) {
  check_sweep_size(spec);  // so every product below fits (at most kMaxSweepPoints)
  for (const auto& a : spec.axes) combos_ *= a.values.size();
  for (const auto& t : spec.traces) {
    trace_paths_.push_back(t);
    trace_labels_.push_back(fs::path(t).filename().string());
  }
  for (const auto& g : spec.generate) {
    trace_paths_.push_back(generated_trace_path(spec, g));
    trace_labels_.push_back(g.label);
  }
  reps_ = static_cast<std::size_t>(std::max(spec.repetitions, 1));
  groups_ = combos_ * trace_paths_.size();
  slice_step_ = static_cast<std::size_t>(std::max(slice.count, 1));
  slice_first_ = static_cast<std::size_t>(std::max(slice.index, 0));
  const std::size_t slice_groups = groups_ > slice_first_ ? (groups_ - slice_first_ + slice_step_ - 1) / slice_step_ : 0;
  size_ = slice_groups * reps_;
}

void SweepPoints::digits(std::size_t c, std::vector<std::size_t>& digits) const {
  digits.resize(spec_->axes.size());
  for (std::size_t a = spec_->axes.size(); a-- > 0;) {  // the last axis fastest
    digits[a] = c % spec_->axes[a].values.size();
    c /= spec_->axes[a].values.size();
  }
}

SweepPoint SweepPoints::operator[](std::size_t i) const {
  SweepPoint p;
  p.index = index(i);
  p.group = group(i);
  p.repetition = repetition(i);
  p.configs = spec_->base_configs;
  p.sets = spec_->sets;
  std::vector<std::size_t> digit;
  digits(combination(i), digit);
  std::string label;
  for (std::size_t a = 0; a < spec_->axes.size(); ++a) {
    const auto& axis = spec_->axes[a];
    for (std::size_t k = 0; k < axis.keys.size(); ++k) {
      const std::string& v = axis.values[digit[a]][k];
      if (!label.empty()) label += ' ';
      if (axis.keys[k] == "config") {
        p.configs.push_back(v);
        label += "config=" + fs::path(v).filename().string();
      } else {
        p.sets.push_back(axis.keys[k] + "=" + v);
        label += axis.keys[k] + "=" + v;
      }
    }
  }
  const std::size_t t = trace(i);
  p.trace = trace_paths_[t];
  p.label = (label.empty() ? "" : label + " | ") + trace_labels_[t];
  if (reps_ > 1) p.label += " #" + std::to_string(p.repetition + 1);
  return p;
}

std::size_t SweepPoints::configurations_in_slice() const {
  // The slice's groups in order have non-decreasing configurations: count the changes.
  std::size_t n = 0;
  std::size_t last = SIZE_MAX;
  for (std::size_t i = 0; i < size_; i += reps_) {
    const std::size_t c = combination(i);
    n += c != last ? 1 : 0;
    last = c;
  }
  return n;
}

std::vector<bool> SweepPoints::traces_used() const {
  std::vector<bool> used(trace_paths_.size(), false);
  std::size_t found = 0;
  for (std::size_t i = 0; i < size_ && found < used.size(); i += reps_) {
    if (!used[trace(i)]) {
      used[trace(i)] = true;
      ++found;
    }
  }
  return used;
}

std::size_t SweepPoints::traces_in_slice() const {
  const auto used = traces_used();
  return static_cast<std::size_t>(std::count(used.begin(), used.end(), true));
}

std::vector<SweepPoint> expand_sweep(const SweepSpec& spec) {
  const SweepPoints lazy(spec);
  std::vector<SweepPoint> points;
  points.reserve(lazy.size());
  for (std::size_t i = 0; i < lazy.size(); ++i) points.push_back(lazy[i]);
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

}  // namespace tbdr
