// `tbdrsim params`: the parameter reference (declarations) or a resolved configuration.
#include <algorithm>
#include <iomanip>
#include <ostream>
#include <sstream>
#include <string>
#include <vector>

#include <fnmatch.h>

#include <boost/program_options.hpp>

#include "app/cli.hpp"
#include "app/commands.hpp"
#include "kernel/errors.hpp"

namespace tbdr {

namespace po = boost::program_options;

namespace {

std::string md_escape(const std::string& s) {
  std::string o;
  for (char c : s) {
    if (c == '|') o += "\\|";
    else o += c;
  }
  return o;
}

/// The table's line width: a description longer than the line is wrapped to it (a word longer
/// than the line, a URL, gets a line of its own).
constexpr std::size_t kTableLineChars = 100;

/// The widest value column of the table; longer values push their unit right.
constexpr std::size_t kValueColumnChars = 16;

/// `text` wrapped to kTableLineChars, every line starting with `indent` spaces.
std::string wrapped(const std::string& text, std::size_t indent) {
  std::string outp, line(indent, ' ');
  std::istringstream words(text);
  std::string w;
  bool first = true;
  while (words >> w) {
    if (!first && line.size() + 1 + w.size() > kTableLineChars) {
      outp += line + "\n";
      line = std::string(indent, ' ') + w;
    } else {
      line += (first ? "" : " ") + w;
    }
    first = false;
  }
  return outp + line + "\n";
}

/// Whether a parameter key matches the command's PATTERN: a glob (fnmatch, with * or ? or [) or a
/// case-insensitive part of the key; every key matches an empty pattern.
bool key_matches(const std::string& key, const std::string& pattern) {
  if (pattern.empty()) return true;
  if (pattern.find_first_of("*?[") != std::string::npos) return fnmatch(pattern.c_str(), key.c_str(), 0) == 0;
  auto lower = [](std::string s) {
    for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    return s;
  };
  return lower(key).find(lower(pattern)) != std::string::npos;
}

void print_table(const ParamTable& table, const ResolvedParams& p, bool resolved, const std::vector<std::size_t>& shown,
                 std::ostream& out) {
  std::size_t key_w = 0, val_w = 0, unit_w = 0;
  for (const std::size_t i : shown) {
    const auto& d = table.decls()[i];
    key_w = std::max(key_w, d.key.size());
    // (a long value, a mapping name, does not widen every line's value column)
    val_w = std::max(val_w, std::min(format_param_value(p.values[i]).size(), kValueColumnChars));
    unit_w = std::max(unit_w, d.unit.size());
  }
  std::string section = "\x01";
  for (const std::size_t i : shown) {
    const auto& d = table.decls()[i];
    if (d.section() != section) {
      section = d.section();
      std::string doc;
      for (const auto& s : table.sections()) {
        if (s.first == section) doc = s.second;
      }
      out << "\n" << wrapped("[" + section + "]  " + doc, 0);
    }
    std::ostringstream head;
    head << "  " << std::left << std::setw(static_cast<int>(key_w)) << d.key << "  "
         << std::setw(static_cast<int>(val_w)) << format_param_value(p.values[i]) << "  "
         << std::setw(static_cast<int>(unit_w)) << d.unit;
    if (resolved) {
      out << head.str() << "  " << p.origins[i].text << "\n";
    } else {
      // The key, value and unit on one line; the range, the description and its source below it.
      std::string line = head.str();
      while (!line.empty() && line.back() == ' ') line.pop_back();
      out << line << "\n" << wrapped((d.range_text().rfind('[', 0) == 0 || d.range_text().rfind('(', 0) == 0 ? "range " : "") + d.range_text() + ". " + d.doc + " (source: " + d.source + ")", 6);
    }
  }
}

void print_markdown(const ParamTable& table, const ResolvedParams& p, bool resolved, const std::vector<std::size_t>& shown,
                    std::ostream& out) {
  if (resolved) {
    out << "| parameter | value | unit | from |\n|---|---|---|---|\n";
  } else {
    out << "| parameter | default | unit | range | description | source |\n|---|---|---|---|---|---|\n";
  }
  for (const std::size_t i : shown) {
    const auto& d = table.decls()[i];
    out << "| `" << d.key << "` | " << md_escape(format_param_value(p.values[i])) << " | " << d.unit << " | ";
    if (resolved) {
      out << md_escape(p.origins[i].text) << " |\n";
    } else {
      out << md_escape(d.range_text()) << " | " << md_escape(d.doc) << " | " << md_escape(d.source) << " |\n";
    }
  }
}

void print_ini(const ParamTable& table, const ResolvedParams& p, const std::vector<std::size_t>& shown, std::ostream& out) {
  out << "# tbdrsim configuration: " << (shown.size() == table.decls().size() ? "every parameter" : "the parameters listed")
      << ", resolved. `tbdrsim params` documents each.\n";
  std::string section = "\x01";
  for (const std::size_t i : shown) {
    const auto& d = table.decls()[i];
    if (d.section() != section) {
      section = d.section();
      out << "\n[" << section << "]\n";
    }
    out << d.key.substr(d.key.rfind('.') + 1) << " = " << format_param_value(p.values[i]);
    if (!d.unit.empty()) out << "  # " << d.unit;
    out << "\n";
  }
}

/// The figures derived from the parameters (not parameters themselves), one line each:
/// name, value, unit, and the formula with this configuration's numbers.
std::vector<std::string> derived_lines(const HwConfig& hw) {
  const DramParams& d = hw.dram;
  std::ostringstream bw;
  bw << "dram peak bandwidth  " << format_param_value(d.peak_bandwidth_gbps()) << " GB/s  = dram.clock_mhz x "
     << "transfers_per_clock x bus_width_bits / 8 x channels = " << format_param_value(d.clock_mhz) << " MHz x "
     << format_param_value(d.transfers_per_clock) << " x " << d.bus_width_bits << " / 8 x " << d.channels << " ("
     << format_param_value(d.data_rate_mtps()) << " MT/s per pin)";
  return {bw.str()};
}

}  // namespace

int cmd_params(const std::vector<std::string>& args, std::ostream& out, std::ostream&) {
  po::options_description desc("params options");
  add_config_options(desc);
  desc.add_options()("format,f", po::value<std::string>()->default_value("table"),
                     "table | markdown | ini (a complete config file of the resolved values)")(
      "pattern", po::value<std::string>(),
      "PATTERN (the argument): only the parameters whose key contains it (case-insensitive: tile, dram.) or "
      "matches it as a glob (\"isp.*\", \"*_bytes\")");
  po::positional_options_description pos;
  pos.add("pattern", 1);
  po::variables_map vm;
  if (!parse_command_options("params", args, desc, &pos, vm, out)) return 0;
  const std::string format = vm["format"].as<std::string>();
  if (format != "table" && format != "markdown" && format != "ini") {
    throw UsageError("tbdrsim params: --format must be table, markdown or ini (got '" + format + "')");
  }
  const ResolvedConfig rc = config_from_options(vm);
  const bool resolved = vm.count("config") || vm.count("set");
  const ParamTable& table = hw_params().table();
  const std::string pattern = vm.count("pattern") ? vm["pattern"].as<std::string>() : std::string();
  std::vector<std::size_t> shown;
  std::vector<std::string> keys;
  for (std::size_t i = 0; i < table.decls().size(); ++i) {
    keys.push_back(table.decls()[i].key);
    if (key_matches(keys.back(), pattern)) shown.push_back(i);
  }
  if (shown.empty()) {
    const std::string guess = did_you_mean(pattern, keys);
    throw InputError("tbdrsim params " + pattern, "no parameter key contains or matches it" +
                                                      (guess.empty() ? std::string("; `tbdrsim params` lists them all") : "; " + guess));
  }
  // The derived figures (the DRAM's peak bandwidth) with the full list, or a pattern naming dram.
  const std::vector<std::string> derived = key_matches("dram.", pattern) || key_matches("dram.peak_bandwidth", pattern)
                                               ? derived_lines(rc.hw)
                                               : std::vector<std::string>{};
  if (format == "markdown") {
    print_markdown(table, rc.params, resolved, shown, out);
    if (!derived.empty()) out << "\nDerived (not parameters):\n\n";
    for (const auto& l : derived) out << "- " << l << "\n";
  } else if (format == "ini") {
    print_ini(table, rc.params, shown, out);
    if (!derived.empty()) out << "\n# Derived (not parameters):\n";
    for (const auto& l : derived) out << "# " << l << "\n";
  } else {
    if (shown.size() == table.decls().size()) {
      out << table.decls().size() << " parameters";
    } else {
      out << shown.size() << " of " << table.decls().size() << " parameters (matching '" << pattern << "')";
    }
    if (resolved) out << ", configuration '" << rc.params.config_name << "', hash " << rc.hash;
    out << "\n";
    print_table(table, rc.params, resolved, shown, out);
    if (!derived.empty()) out << "\nDerived (not parameters):\n";
    for (const auto& l : derived) {
      // "name  value  = formula = numbers": each "= ..." on a line of its own (the lines stay short).
      std::size_t start = 0;
      for (bool first = true;; first = false) {
        const std::size_t eq = l.find(" = ", start);
        std::string part = l.substr(start, eq == std::string::npos ? std::string::npos : eq - start);
        while (!part.empty() && part.back() == ' ') part.pop_back();
        out << (first ? "  " : "      = ") << part << "\n";
        if (eq == std::string::npos) break;
        start = eq + 3;
      }
    }
  }
  return 0;
}

}  // namespace tbdr
