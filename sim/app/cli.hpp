#pragma once
// The command-line tool: `tbdrsim <command> [options]`. Each command is a function registered in
// one table (sim/app/cli.cpp) with its summary; options are parsed with Boost.Program_options.
#include <iosfwd>
#include <string>
#include <vector>

namespace tbdr {

/// Runs the tool with the given arguments (argv[0] excluded) and returns the process exit code:
/// 0 success, 1 internal failure, 2 bad input or bad usage (the message names what is wrong).
int cli_main(const std::vector<std::string>& args, std::ostream& out, std::ostream& err);

/// One sub-command of the tool.
struct CliCommand {
  const char* name;
  const char* summary;
  /// Receives the arguments after the command name; throws UsageError / InputError on bad input.
  int (*run)(const std::vector<std::string>& args, std::ostream& out, std::ostream& err);
};

/// All commands, in the order `tbdrsim --help` lists them.
const std::vector<CliCommand>& cli_commands();

/// The command line that started this process, for the runs table.
std::string& invocation_command_line();

/// The folder that config and sweep names, `tbdrsim --checkout` and the scripts resolve against:
/// the installed data folder `<prefix>/share/tbdrsim` when this executable is `<prefix>/bin/tbdrsim`
/// of an installed tree (`cmake --install`; the folder holds configs/), else the checkout it was
/// built from (TBDRSIM_SOURCE_DIR). docs/install.md.
std::string data_root();

}  // namespace tbdr
