#include "kernel/params.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>

#include <cerrno>
#include <climits>
#include <system_error>
#include <unistd.h>

#include <boost/program_options/options_description.hpp>
#include <boost/program_options/parsers.hpp>

#include "kernel/errors.hpp"
#include "kernel/hash.hpp"
#include "kernel/text_escape.hpp"

namespace tbdr {

std::string trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t\r\n");
  if (b == std::string::npos) return {};
  const auto e = s.find_last_not_of(" \t\r\n");
  return s.substr(b, e - b + 1);
}

namespace {

std::string format_real(double v) {
  char buf[64];
  auto r = std::to_chars(buf, buf + sizeof buf, v);
  std::string s(buf, r.ptr);
  return s;
}

std::string format_bound(double v, ParamType t) {
  if (std::isinf(v)) return v < 0 ? "-inf" : "inf";
  if (t == ParamType::Int) return std::to_string(static_cast<long long>(v));
  return format_real(v);
}

}  // namespace

const char* to_string(ParamType t) {
  switch (t) {
    case ParamType::Int: return "int";
    case ParamType::Real: return "real";
    case ParamType::Bool: return "bool";
    case ParamType::Text: return "text";
    case ParamType::Choice: return "choice";
  }
  return "?";
}

std::string format_param_value(const ParamValue& v) {
  if (auto* i = std::get_if<std::int64_t>(&v)) return std::to_string(*i);
  if (auto* d = std::get_if<double>(&v)) return format_real(*d);
  if (auto* b = std::get_if<bool>(&v)) return *b ? "true" : "false";
  return std::get<std::string>(v);
}

std::string ParamDecl::section() const {
  const auto dot = key.rfind('.');
  return dot == std::string::npos ? std::string{} : key.substr(0, dot);
}

std::string ParamDecl::range_text() const {
  switch (type) {
    case ParamType::Int:
    case ParamType::Real:
      return "[" + format_bound(min, type) + ", " + format_bound(max, type) + "]";
    case ParamType::Bool: return "true|false";
    case ParamType::Text: return "any text";
    case ParamType::Choice: {
      std::string s = "one of ";
      for (std::size_t i = 0; i < choices.size(); ++i) s += (i ? "|" : "") + choices[i];
      return s;
    }
  }
  return {};
}

bool ParamDecl::parse(const std::string& raw, ParamValue& out, std::string& why) const {
  const std::string text = trim(raw);
  switch (type) {
    case ParamType::Int: {
      std::int64_t v = 0;
      const char* b = text.data();
      const char* e = b + text.size();
      auto r = std::from_chars(b, e, v);
      if (text.empty() || r.ec != std::errc{} || r.ptr != e) {
        why = "an integer in " + range_text();
        return false;
      }
      if (static_cast<double>(v) < min || static_cast<double>(v) > max) {
        why = "an integer in " + range_text();
        return false;
      }
      out = v;
      return true;
    }
    case ParamType::Real: {
      double v = 0;
      const char* b = text.data();
      const char* e = b + text.size();
      auto r = std::from_chars(b, e, v);
      if (text.empty() || r.ec != std::errc{} || r.ptr != e || !std::isfinite(v)) {
        why = "a finite number in " + range_text();
        return false;
      }
      if (v < min || v > max) {
        why = "a number in " + range_text();
        return false;
      }
      out = v;
      return true;
    }
    case ParamType::Bool: {
      std::string t = text;
      std::transform(t.begin(), t.end(), t.begin(), [](unsigned char c) { return std::tolower(c); });
      if (t == "true" || t == "1" || t == "on" || t == "yes") { out = true; return true; }
      if (t == "false" || t == "0" || t == "off" || t == "no") { out = false; return true; }
      why = "true|false (also 1|0, on|off, yes|no)";
      return false;
    }
    case ParamType::Text:
      out = text;
      return true;
    case ParamType::Choice:
      if (std::find(choices.begin(), choices.end(), text) == choices.end()) {
        why = range_text();
        return false;
      }
      out = text;
      return true;
  }
  return false;
}

void ParamTable::check_default(const ParamDecl& d) const {
  std::string why;
  ParamValue v;
  if (!d.parse(format_param_value(d.default_value), v, why)) {
    throw std::logic_error("parameter " + d.key + ": default " + format_param_value(d.default_value) +
                           " is not " + why);
  }
}

ParamTable::Builder ParamTable::declare(std::string key, ParamType type, ParamValue default_value) {
  if (find(key) >= 0) throw std::logic_error("parameter declared twice: " + key);
  ParamDecl d;
  d.key = std::move(key);
  d.type = type;
  d.default_value = std::move(default_value);
  decls_.push_back(std::move(d));
  return Builder(decls_.back());
}

void ParamTable::section(std::string name, std::string doc) {
  sections_.emplace_back(std::move(name), std::move(doc));
}

void ParamTable::retire(std::string key, std::string replacement) {
  if (find(key) >= 0) throw std::logic_error("parameter retired while still declared: " + key);
  retired_.emplace_back(std::move(key), std::move(replacement));
}

const std::string* ParamTable::retired(const std::string& key) const {
  for (const auto& r : retired_) {
    if (r.first == key) return &r.second;
  }
  return nullptr;
}

int ParamTable::find(const std::string& key) const {
  for (std::size_t i = 0; i < decls_.size(); ++i) {
    if (decls_[i].key == key) return static_cast<int>(i);
  }
  return -1;
}

bool ParamTable::has_section(const std::string& name) const {
  for (const auto& s : sections_) {
    if (s.first == name) return true;
  }
  for (const auto& d : decls_) {
    if (d.section() == name) return true;
  }
  return false;
}

ResolvedParams ParamTable::defaults() const {
  for (const auto& d : decls_) check_default(d);
  ResolvedParams p;
  p.config_name = defaults_name_;
  for (const auto& d : decls_) {
    p.values.push_back(d.default_value);
    p.origins.push_back(ParamOrigin{});
  }
  return p;
}

namespace {

std::string closest_key(const ParamTable& table, const std::string& key) {
  // Suggest a declared key of the same section, or with the same name, when one is close.
  const auto dot = key.rfind('.');
  const std::string name = dot == std::string::npos ? key : key.substr(dot + 1);
  const std::string sec = dot == std::string::npos ? "" : key.substr(0, dot);
  auto distance = [](const std::string& a, const std::string& b) {
    std::vector<std::size_t> prev(b.size() + 1), cur(b.size() + 1);
    for (std::size_t j = 0; j <= b.size(); ++j) prev[j] = j;
    for (std::size_t i = 1; i <= a.size(); ++i) {
      cur[0] = i;
      for (std::size_t j = 1; j <= b.size(); ++j) {
        cur[j] = std::min({prev[j] + 1, cur[j - 1] + 1, prev[j - 1] + (a[i - 1] == b[j - 1] ? 0 : 1)});
      }
      std::swap(prev, cur);
    }
    return prev[b.size()];
  };
  std::string best;
  std::size_t best_d = 4;
  for (const auto& d : table.decls()) {
    if (d.section() != sec) continue;
    const std::string dn = d.key.substr(d.key.rfind('.') + 1);
    const std::size_t dist = distance(name, dn);
    if (dist < best_d) {
      best_d = dist;
      best = d.key;
    }
  }
  return best;
}

void apply_one(const ParamTable& table, ResolvedParams& p, const std::string& where, const std::string& key,
               const std::string& value) {
  const int idx = table.find(key);
  if (idx < 0) {
    if (const std::string* instead = table.retired(key)) {
      throw InputError(where, "parameter '" + key + "' was removed: " + *instead);
    }
    std::string msg = "unknown parameter '" + key + "'";
    const std::string guess = closest_key(table, key);
    if (!guess.empty()) msg += " (did you mean '" + guess + "'?)";
    msg += "; `tbdrsim params` lists every parameter";
    throw InputError(where, escape_for_message(msg));
  }
  const ParamDecl& d = table.decls()[static_cast<std::size_t>(idx)];
  std::string why;
  ParamValue v;
  if (!d.parse(value, v, why)) {
    throw InputError(where, "parameter '" + escape_for_message(key) + "' = '" + escape_for_message(value) + "': expected " + why +
                                (d.unit.empty() ? "" : " (" + d.unit + ")"));
  }
  p.values[static_cast<std::size_t>(idx)] = std::move(v);
  p.origins[static_cast<std::size_t>(idx)].text = where;
}

}  // namespace

void ParamTable::apply_config_file(ResolvedParams& p, const std::string& path) const {
  IniRules rules;
  rules.what = "config file";
  rules.known_section = [this](const std::string& section) { return has_section(section); };
  for (const auto& sec : sections()) rules.known_sections += (rules.known_sections.empty() ? "" : ", ") + sec.first;
  for (const IniLine& l : read_ini_file(path, rules)) apply_one(*this, p, path + ":" + std::to_string(l.line), l.key, l.value);
  p.config_name = std::filesystem::path(path).stem().string();
}

void check_path_length(const std::string& path, const std::string& what) {
  namespace fs = std::filesystem;
  // The nearest folder that exists answers pathconf for the file system the path lands on. Found
  // by cutting the path at its slashes from the end (a fs::path's parent_path() re-splits the
  // whole path each time: a path of thousands of components took seconds under the sanitizers).
  std::error_code ec;
  std::string probe = ".";
  for (std::size_t cut = path.find_last_of('/'); cut != std::string::npos; cut = cut == 0 ? std::string::npos : path.find_last_of('/', cut - 1)) {
    const std::string dir = cut == 0 ? std::string("/") : path.substr(0, cut);
    if (dir.size() < PATH_MAX && fs::is_directory(dir, ec)) {
      probe = dir;
      break;
    }
  }
  auto conf = [&](int name, long fallback) {
    const long v = probe.size() < PATH_MAX ? ::pathconf(probe.c_str(), name) : -1;
    return v > 0 ? v : fallback;
  };
  const long path_max = conf(_PC_PATH_MAX, PATH_MAX);
  const long name_max = conf(_PC_NAME_MAX, NAME_MAX);
  auto head = [&] { return path.size() > 60 ? path.substr(0, 60) + "..." : path; };
  if (path.size() >= static_cast<std::size_t>(path_max)) {
    throw InputError(head(), what + " path is " + std::to_string(path.size()) + " bytes long; the file system allows " +
                                 std::to_string(path_max - 1) + " (pathconf _PC_PATH_MAX)");
  }
  for (const auto& part : fs::path(path)) {
    if (part.native().size() > static_cast<std::size_t>(name_max)) {
      throw InputError(head(), what + " path has a component of " + std::to_string(part.native().size()) +
                                   " bytes; the file system allows " + std::to_string(name_max) +
                                   " (pathconf _PC_NAME_MAX)");
    }
  }
}

void check_input_file(const std::string& path, const std::string& what, bool allow_special) {
  namespace fs = std::filesystem;
  check_path_length(path, what);
  std::error_code ec;
  const fs::file_status st = fs::status(path, ec);
  const auto why = [](const std::error_code& e) -> std::string {
    if (e == std::errc::permission_denied || e == std::errc::operation_not_permitted) {
      return "permission denied (the file, or a folder on its path, is not readable)";
    }
    if (e == std::errc::too_many_symbolic_link_levels) return "too many levels of symbolic links (a symlink loop)";
    if (e == std::errc::no_such_file_or_directory) return "not found";
    if (e == std::errc::not_a_directory) return "not found (a part of its path is not a folder)";
    return e.message();
  };
  if (ec) throw InputError(path, "cannot read " + what + ": " + why(ec));
  if (st.type() == fs::file_type::not_found) throw InputError(path, "cannot read " + what + ": not found");
  if (st.type() == fs::file_type::directory) throw InputError(path, "cannot read " + what + ": it is a folder, not a file");
  if (st.type() != fs::file_type::regular && !allow_special) {
    throw InputError(path, "cannot read " + what + ": not a regular file (a device, FIFO or socket)");
  }
  if (::access(path.c_str(), R_OK) != 0) {
    throw InputError(path, "cannot read " + what + ": " + why(std::error_code(errno, std::generic_category())));
  }
}

std::string_view strip_utf8_bom(std::string_view text) {
  if (text.size() >= 3 && text.substr(0, 3) == "\xEF\xBB\xBF") text.remove_prefix(3);
  return text;
}

std::string read_text_input(const std::string& path, const std::string& what, std::uint64_t max_bytes) {
  check_input_file(path, what, /*allow_special=*/false);
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, "cannot open " + what);
  in.seekg(0, std::ios::end);
  const std::streamoff size = in.tellg();
  if (size < 0) throw InputError(path, "cannot read " + what + " (not a regular file?)");
  if (static_cast<std::uint64_t>(size) > max_bytes) {
    throw InputError(path, what + " is " + std::to_string(size) + " bytes; the largest accepted is " +
                               std::to_string(max_bytes) + " (docs/limits.md)");
  }
  in.seekg(0);
  std::string text(static_cast<std::size_t>(size), '\0');
  in.read(text.data(), size);
  if (in.gcount() != size) throw InputError(path, "read error in " + what);
  const std::size_t bom = text.size() - strip_utf8_bom(text).size();
  text.erase(0, bom);
  return text;
}

namespace {

/// The line scan of read_ini_file: every `key = value` line with its section and line number
/// (Boost.Program_options reports neither), refusing what `rules` do not allow.
std::vector<IniLine> scan_ini_lines(const std::string& path, std::istream& in, const IniRules& rules,
                                    std::map<std::string, long>& section_lines) {
  std::vector<IniLine> out;
  std::map<std::string, long> seen;
  std::string line, section;
  long n = 0;
  while (std::getline(in, line)) {
    ++n;
    if (auto hash = line.find('#'); hash != std::string::npos) line.resize(hash);
    const std::string s = trim(line);
    if (s.empty()) continue;
    if (s.front() == '[') {
      if (s.back() != ']') throw InputError(path, n, "malformed section header '" + escape_for_message(s) + "' (expected [name])");
      section = trim(s.substr(1, s.size() - 2));
      if (!rules.known_section(section)) {
        throw InputError(path, n, "unknown section [" + escape_for_message(section) + "] (known sections: " + rules.known_sections + ")");
      }
      if (auto it = section_lines.find(section); it != section_lines.end() && rules.sections_once) {
        throw InputError(path, n, "section [" + section + "] appears twice (first at line " + std::to_string(it->second) + ")");
      }
      section_lines.emplace(section, n);
      continue;
    }
    const auto eq = s.find('=');
    if (eq == std::string::npos) throw InputError(path, n, "expected 'key = value' or '[section]', found '" + escape_for_message(s) + "'");
    if (section.empty() && rules.keys_need_section) {
      throw InputError(path, n, "'" + escape_for_message(s) + "' is outside any section (known sections: " + rules.known_sections + ")");
    }
    IniLine l;
    l.section = section;
    l.name = trim(s.substr(0, eq));
    if (l.name.empty()) throw InputError(path, n, "missing key before '='");
    l.key = section.empty() ? l.name : section + "." + l.name;
    l.line = n;
    if (auto it = seen.find(l.key); it != seen.end() && !(rules.may_repeat && rules.may_repeat(l))) {
      throw InputError(path, n, "key '" + l.key + "' set twice in one file (first at line " + std::to_string(it->second) + ")");
    }
    seen.emplace(l.key, n);
    out.push_back(std::move(l));
  }
  return out;
}

}  // namespace

std::vector<IniLine> read_ini_file(const std::string& path, const IniRules& rules, std::map<std::string, long>* section_lines) {
  namespace po = boost::program_options;
  std::map<std::string, long> own_section_lines;
  const std::string text = read_text_input(path, rules.what, kMaxIniFileBytes);
  std::istringstream scan(text);
  std::vector<IniLine> lines = scan_ini_lines(path, scan, rules, section_lines ? *section_lines : own_section_lines);

  std::istringstream in(text);
  po::options_description none;
  po::parsed_options parsed(&none);
  try {
    parsed = po::parse_config_file(in, none, /*allow_unregistered=*/true);
  } catch (const po::error& e) {
    throw InputError(path, std::string("cannot parse ") + rules.what + ": " + e.what());
  }
  if (parsed.options.size() != lines.size()) {
    throw InputError(path, std::string(rules.what) + " parse mismatch (" + std::to_string(parsed.options.size()) +
                               " entries read, " + std::to_string(lines.size()) + " expected)");
  }
  for (std::size_t i = 0; i < lines.size(); ++i) {
    const po::option& opt = parsed.options[i];
    if (opt.string_key != lines[i].key) {
      throw InputError(path, lines[i].line, std::string(rules.what) + " parse mismatch at key '" + lines[i].key + "'");
    }
    lines[i].value = opt.value.empty() ? std::string{} : opt.value.front();
  }
  return lines;
}

void ParamTable::apply_override(ResolvedParams& p, const std::string& assignment) const {
  const std::string where = "--set " + assignment;
  const auto eq = assignment.find('=');
  if (eq == std::string::npos) throw InputError(where, "expected section.key=value");
  const std::string key = trim(assignment.substr(0, eq));
  const std::string value = trim(assignment.substr(eq + 1));
  if (key.find('.') == std::string::npos) throw InputError(where, "expected section.key=value (no section in '" + key + "')");
  const auto dot = key.rfind('.');
  if (!has_section(key.substr(0, dot))) {
    throw InputError(where, "unknown section '" + key.substr(0, dot) + "'; `tbdrsim params` lists every parameter");
  }
  apply_one(*this, p, where, key, value);
}

ResolvedParams ParamTable::resolve(const std::vector<std::string>& config_files,
                                   const std::vector<std::string>& overrides) const {
  ResolvedParams p = defaults();
  for (const auto& f : config_files) apply_config_file(p, f);
  for (const auto& o : overrides) apply_override(p, o);
  return p;
}

ResolvedParams ParamTable::preset(const std::vector<std::string>& config_files) const {
  ResolvedParams p = defaults();
  if (!config_files.empty()) apply_config_file(p, config_files.back());
  return p;
}

std::string ParamTable::label(const ResolvedParams& p, const ResolvedParams& preset) const {
  std::vector<std::string> set;
  for (std::size_t i = 0; i < decls_.size(); ++i) {
    const std::string v = format_param_value(p.values[i]);
    if (v != format_param_value(preset.values[i])) set.push_back(decls_[i].key + "=" + v);
  }
  // By key (a key has no '='), as analysis/views.sql's v_config_label orders them.
  std::sort(set.begin(), set.end(), [](const std::string& a, const std::string& b) {
    return a.substr(0, a.find('=')) < b.substr(0, b.find('='));
  });
  std::string label = p.config_name;
  for (const auto& s : set) label += " " + s;
  return label;
}

std::string ParamTable::hash(const ResolvedParams& p) const {
  Fnv1a64 h;
  for (std::size_t i = 0; i < decls_.size(); ++i) {
    h.update(decls_[i].key);
    h.update("=");
    h.update(format_param_value(p.values[i]));
    h.update("\n");
  }
  return h.hex();
}

}  // namespace tbdr
