#pragma once
// The sub-command entry points and the option helpers they share (see CliCommand in sim/app/cli.hpp).
#include <iosfwd>
#include <string>
#include <vector>

#include <boost/program_options/options_description.hpp>
#include <boost/program_options/positional_options.hpp>
#include <boost/program_options/variables_map.hpp>

#include "models/hw_config.hpp"

namespace tbdr {

int cmd_scene(const std::vector<std::string>& args, std::ostream& out, std::ostream& err);
int cmd_trace(const std::vector<std::string>& args, std::ostream& out, std::ostream& err);
int cmd_run(const std::vector<std::string>& args, std::ostream& out, std::ostream& err);
int cmd_study(const std::vector<std::string>& args, std::ostream& out, std::ostream& err);
int cmd_params(const std::vector<std::string>& args, std::ostream& out, std::ostream& err);
int cmd_sweep(const std::vector<std::string>& args, std::ostream& out, std::ostream& err);
int cmd_merge(const std::vector<std::string>& args, std::ostream& out, std::ostream& err);
int cmd_report(const std::vector<std::string>& args, std::ostream& out, std::ostream& err);
int cmd_validate(const std::vector<std::string>& args, std::ostream& out, std::ostream& err);
int cmd_dram_bench(const std::vector<std::string>& args, std::ostream& out, std::ostream& err);
int cmd_plot(const std::vector<std::string>& args, std::ostream& out, std::ostream& err);
int cmd_import(const std::vector<std::string>& args, std::ostream& out, std::ostream& err);

/// Adds the hardware configuration options every simulating command takes: --config, --set.
void add_config_options(boost::program_options::options_description& desc);
/// Resolves the configuration from those options (InputError on any bad input).
ResolvedConfig config_from_options(const boost::program_options::variables_map& vm);
/// The most threads one run takes (--threads): the bound the sweep puts on its worker processes
/// (-j 1..1024), there to catch a mistyped count.
inline constexpr int kMaxThreadsPerRun = 1024;
/// Adds --threads, the threads inside one run (tiles of a render on a pool of threads; every
/// figure is the same at any count), with `default_help` saying what it defaults to.
void add_threads_option(boost::program_options::options_description& desc, const std::string& default_help);
/// The --threads value, or `fallback` when it was not given (InputError outside 1..kMaxThreadsPerRun).
unsigned threads_option(const boost::program_options::variables_map& vm, unsigned fallback);
/// The threads per run when `workers` runs go at once: the cores this process may use divided
/// between them (at least 1), so that workers x threads <= cores.
unsigned threads_per_worker(int workers);
/// The data folders of the checkout that config and sweep file names are looked up in.
enum class DataFolder { Configs, Sweeps };
/// Finds a config or sweep file named on the command line: the path as given (from the working
/// folder), else the same relative path in the tbdrsim checkout, else a bare name (".ini" optional)
/// in the checkout's configs/ (configs/sweeps/ for sweeps). InputError naming every path tried,
/// with a suggestion, when none exists.
std::string find_data_file(const std::string& arg, DataFolder folder);
/// "did you mean 'a' or 'b'?" for the candidates spelled close to `token` (edit distance at most a
/// third of its length, or a dotted candidate ending in it); empty when none is close.
std::string did_you_mean(const std::string& token, const std::vector<std::string>& candidates);
/// Parses `args` against `desc` (unknown options and stray positionals are UsageErrors); returns
/// false when --help was given (help already printed to `out`).
bool parse_command_options(const std::string& command, const std::vector<std::string>& args,
                           const boost::program_options::options_description& desc,
                           const boost::program_options::positional_options_description* positional,
                           boost::program_options::variables_map& vm, std::ostream& out);

}  // namespace tbdr
