// `tbdrsim params`: the parameter reference (declarations) or a resolved configuration.
#include <algorithm>
#include <iomanip>
#include <ostream>
#include <sstream>
#include <string>
#include <vector>

#include <boost/program_options.hpp>

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

void print_table(const ParamTable& table, const ResolvedParams& p, bool resolved, std::ostream& out) {
  std::size_t key_w = 0, val_w = 0, unit_w = 0;
  for (std::size_t i = 0; i < table.decls().size(); ++i) {
    const auto& d = table.decls()[i];
    key_w = std::max(key_w, d.key.size());
    val_w = std::max(val_w, format_param_value(p.values[i]).size());
    unit_w = std::max(unit_w, d.unit.size());
  }
  std::string section = "\x01";
  for (std::size_t i = 0; i < table.decls().size(); ++i) {
    const auto& d = table.decls()[i];
    if (d.section() != section) {
      section = d.section();
      std::string doc;
      for (const auto& s : table.sections()) {
        if (s.first == section) doc = s.second;
      }
      out << "\n[" << section << "]  " << doc << "\n";
    }
    out << "  " << std::left << std::setw(static_cast<int>(key_w)) << d.key << "  "
        << std::setw(static_cast<int>(val_w)) << format_param_value(p.values[i]) << "  "
        << std::setw(static_cast<int>(unit_w)) << d.unit << "  ";
    if (resolved) {
      out << p.origins[i].text << "\n";
    } else {
      out << d.range_text() << "  " << d.doc << "  (source: " << d.source << ")\n";
    }
  }
}

void print_markdown(const ParamTable& table, const ResolvedParams& p, bool resolved, std::ostream& out) {
  if (resolved) {
    out << "| parameter | value | unit | from |\n|---|---|---|---|\n";
  } else {
    out << "| parameter | default | unit | range | description | source |\n|---|---|---|---|---|---|\n";
  }
  for (std::size_t i = 0; i < table.decls().size(); ++i) {
    const auto& d = table.decls()[i];
    out << "| `" << d.key << "` | " << md_escape(format_param_value(p.values[i])) << " | " << d.unit << " | ";
    if (resolved) {
      out << md_escape(p.origins[i].text) << " |\n";
    } else {
      out << md_escape(d.range_text()) << " | " << md_escape(d.doc) << " | " << md_escape(d.source) << " |\n";
    }
  }
}

void print_ini(const ParamTable& table, const ResolvedParams& p, std::ostream& out) {
  out << "# tbdrsim configuration: every parameter, resolved. `tbdrsim params` documents each.\n";
  std::string section = "\x01";
  for (std::size_t i = 0; i < table.decls().size(); ++i) {
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
                     "table | markdown | ini (a complete config file of the resolved values)");
  po::variables_map vm;
  if (!parse_command_options("params", args, desc, nullptr, vm, out)) return 0;
  const std::string format = vm["format"].as<std::string>();
  if (format != "table" && format != "markdown" && format != "ini") {
    throw UsageError("tbdrsim params: --format must be table, markdown or ini (got '" + format + "')");
  }
  const ResolvedConfig rc = config_from_options(vm);
  const bool resolved = vm.count("config") || vm.count("set");
  const ParamTable& table = hw_params().table();
  const std::vector<std::string> derived = derived_lines(rc.hw);
  if (format == "markdown") {
    print_markdown(table, rc.params, resolved, out);
    out << "\nDerived (not parameters):\n\n";
    for (const auto& l : derived) out << "- " << l << "\n";
  } else if (format == "ini") {
    print_ini(table, rc.params, out);
    out << "\n# Derived (not parameters):\n";
    for (const auto& l : derived) out << "# " << l << "\n";
  } else {
    out << table.decls().size() << " parameters";
    if (resolved) out << ", configuration '" << rc.params.config_name << "', hash " << rc.hash;
    out << "\n";
    print_table(table, rc.params, resolved, out);
    out << "\nDerived (not parameters):\n";
    for (const auto& l : derived) out << "  " << l << "\n";
  }
  return 0;
}

}  // namespace tbdr
