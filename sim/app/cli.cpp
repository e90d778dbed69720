#include "app/cli.hpp"

#include <iostream>

#include <boost/program_options.hpp>

#include "app/commands.hpp"
#include "kernel/errors.hpp"
#include "tbdrsim_version.hpp"

namespace tbdr {

namespace po = boost::program_options;

const std::vector<CliCommand>& cli_commands() {
  static const std::vector<CliCommand> commands = {
      {"params", "List every hardware parameter (default, unit, range, doc), or the resolved values of a "
                 "configuration and where each came from",
       cmd_params},
      {"scene", "Describe a scene: scene info atrium[:detail] | FILE.gltf/.glb", cmd_scene},
      {"trace", "Generate the command trace of a technique for a scene, lights, camera and resolution", cmd_trace},
      {"run", "Replay a trace on a hardware configuration and write the run to a results database", cmd_run},
      {"study", "The main job: every technique on the atrium at 1920x1080 with 256 and 1024 lights, compared", cmd_study},
      {"sweep", "Run a sweep file's points in parallel worker processes into a results database, resumably "
                "(or emit a Slurm job array)", cmd_sweep},
      {"merge", "Merge shard databases (Slurm array tasks) into one without duplicates", cmd_merge},
      {"report", "Compare techniques or configurations in a results database: tables of time, DRAM, energy",
       cmd_report},
      {"plot", "Draw a results database as a PNG: techniques, dram, energy, passes, scaling, sensitivity, delta, "
               "tiles (python3 + matplotlib)", cmd_plot},
      {"validate", "Check the simulator against published figures (Bjørge, Burns & Hunt, Imagination's HSR and "
                   "on-chip memory figures, rooflines, Olsson et al., DRAM energy): published vs simulated",
       cmd_validate},
  };
  return commands;
}

std::string& invocation_command_line() {
  static std::string line;
  return line;
}

namespace {

void print_usage(std::ostream& os) {
  os << "tbdrsim " << kToolVersion
     << ": cycle-approximate simulator of a tile-based deferred rendering GPU\n\n"
     << "usage: tbdrsim <command> [options]\n"
     << "       tbdrsim <command> --help\n\ncommands:\n";
  for (const auto& c : cli_commands()) {
    os << "  " << c.name << std::string(c.name && std::string(c.name).size() < 10 ? 10 - std::string(c.name).size() : 1, ' ')
       << c.summary << "\n";
  }
}

}  // namespace

void add_config_options(po::options_description& desc) {
  desc.add_options()
      ("config,c", po::value<std::vector<std::string>>()->composing(),
       "hardware config file (INI); repeatable, later files win")
      ("set,s", po::value<std::vector<std::string>>()->composing(),
       "override one parameter, section.key=value; repeatable, wins over files");
}

ResolvedConfig config_from_options(const po::variables_map& vm) {
  std::vector<std::string> files;
  std::vector<std::string> sets;
  if (vm.count("config")) files = vm["config"].as<std::vector<std::string>>();
  if (vm.count("set")) sets = vm["set"].as<std::vector<std::string>>();
  return resolve_config(files, sets);
}

bool parse_command_options(const std::string& command, const std::vector<std::string>& args,
                           const po::options_description& desc,
                           const po::positional_options_description* positional, po::variables_map& vm,
                           std::ostream& out) {
  po::options_description all(desc);
  all.add_options()("help,h", "show this help");
  try {
    po::command_line_parser parser(args);
    parser.options(all);
    if (positional) parser.positional(*positional);
    po::store(parser.run(), vm);
    if (vm.count("help")) {
      out << "usage: tbdrsim " << command << " [options]\n\n" << all << "\n";
      return false;
    }
    po::notify(vm);
  } catch (const po::error& e) {
    std::ostringstream help;
    help << all;
    throw UsageError("tbdrsim " + command + ": " + e.what() + "\n\nusage: tbdrsim " + command +
                     " [options]\n\n" + help.str());
  }
  return true;
}

int cli_main(const std::vector<std::string>& args, std::ostream& out, std::ostream& err) {
  try {
    if (args.empty()) {
      print_usage(err);
      return 2;
    }
    const std::string& name = args.front();
    if (name == "--help" || name == "-h" || name == "help") {
      print_usage(out);
      return 0;
    }
    if (name == "--version") {
      out << "tbdrsim " << kToolVersion << "\n";
      return 0;
    }
    for (const auto& c : cli_commands()) {
      if (name == c.name) return c.run(std::vector<std::string>(args.begin() + 1, args.end()), out, err);
    }
    err << "tbdrsim: unknown command '" << name << "'\n\n";
    print_usage(err);
    return 2;
  } catch (const UsageError& e) {
    err << e.what() << "\n";
    return 2;
  } catch (const InputError& e) {
    err << "error: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    err << "internal error: " << e.what() << "\n";
    return 1;
  }
}

}  // namespace tbdr
