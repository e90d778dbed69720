#include "app/cli.hpp"

#include <algorithm>
#include <filesystem>
#include <iostream>
#include <sstream>

#include <boost/program_options.hpp>

#include "analysis/report.hpp"
#include "app/commands.hpp"
#include "app/worker_pool.hpp"
#include "kernel/thread_pool.hpp"
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
      {"import", "Import a captured frame of a real application (RenderDoc .rdc, Vulkan) as a trace and its "
                 "clip-space geometry (docs/capture-import.md)",
       cmd_import},
      {"run", "Replay a trace on a hardware configuration and write the run to a results database", cmd_run},
      {"study", "The main job: every technique on the atrium at 1920x1080 with 256 and 1024 lights, compared", cmd_study},
      {"sweep", "Run a sweep file's points in parallel worker processes into a results database, resumably "
                "(or emit a Slurm job array)", cmd_sweep},
      {"merge", "Merge shard databases (Slurm array tasks) into one without duplicates", cmd_merge},
      {"report", "Compare techniques or configurations in a results database: tables of time, DRAM, energy",
       cmd_report},
      {"plot", "Draw a results database as a PNG: techniques, dram, energy, passes, scaling, sensitivity, delta, "
               "tiles (python3 + matplotlib)", cmd_plot},
      {"dram-bench", "Run a DRAM microbenchmark (stream or random reads) and print its figures; --memory-trace exports it", cmd_dram_bench},
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

/// The installed data folder, relative to the installed executable (<prefix>/bin/tbdrsim).
constexpr const char* kInstalledDataFolder = "share/tbdrsim";

std::string data_root() {
  static const std::string root = [] {
    namespace fs = std::filesystem;
    std::error_code ec;
    const fs::path installed = fs::path(self_executable()).parent_path().parent_path() / kInstalledDataFolder;
    if (fs::is_directory(installed / "configs", ec)) return installed.lexically_normal().string();
    return std::string(TBDRSIM_SOURCE_DIR);
  }();
  return root;
}

namespace {

void print_usage(std::ostream& os) {
  os << "tbdrsim " << kToolVersion
     << ": cycle-approximate simulator of a tile-based deferred rendering GPU\n\n"
     << "usage: tbdrsim <command> [options]\n"
     << "       tbdrsim <command> --help\n"
     << "       tbdrsim --checkout   (prints the checkout, or the installed data folder: its configs/, configs/sweeps/ and analysis/ scripts)\n"
     << "       tbdrsim --views      (prints the SQL of the analysis views, analysis/views.sql, as this tbdrsim creates them:\n"
     << "                             `tbdrsim --views | sqlite3 results.db` adds them to a database by hand)\n\ncommands:\n";
  for (const auto& c : cli_commands()) {
    os << "  " << c.name << std::string(c.name && std::string(c.name).size() < 10 ? 10 - std::string(c.name).size() : 1, ' ')
       << c.summary << "\n";
  }
  os << "\npaths: file arguments are taken from the working folder. A config (--config) or sweep file that is\n"
     << "not there is looked up in the tbdrsim checkout " << data_root() << "\n"
     << "(an installed tbdrsim's is <prefix>/share/tbdrsim beside <prefix>/bin/tbdrsim), in this order:\n"
     << "  1. the path as given, from the working folder    configs/series6xt_gx6450.ini, ./mine.ini\n"
     << "  2. the same relative path inside the checkout     configs/series6xt_gx6450.ini\n"
     << "  3. a bare name in the checkout's configs/ (configs/sweeps/ for sweep files), .ini optional:\n"
     << "                                                    series6xt_gx6450, tile_size\n"
     << "Traces, scenes, databases and output folders are not looked up: they are relative to the working folder.\n";
}

}  // namespace

void add_config_options(po::options_description& desc) {
  desc.add_options()
      ("config,c", po::value<std::vector<std::string>>()->composing(),
       "hardware config: a file (INI) or a preset name (series6xt_gx6450, mobile_16x16_lpddr4x, ...); "
       "repeatable, later files win. Found as given (from the working folder), else in the tbdrsim "
       "data folder, installed or the checkout (configs/NAME or configs/NAME.ini; see `tbdrsim --help`)")
      ("set,s", po::value<std::vector<std::string>>()->composing(),
       "override one parameter, section.key=value; repeatable, wins over files");
}

void add_threads_option(po::options_description& desc, const std::string& default_help) {
  desc.add_options()("threads", po::value<int>(),
                     ("threads inside each run: the tiles of every render are shaded on this many threads, "
                      "with the same statistics, images and database rows at any count (default: " + default_help + ")").c_str());
}

unsigned threads_option(const po::variables_map& vm, unsigned fallback) {
  if (!vm.count("threads")) return fallback;
  const int n = vm["threads"].as<int>();
  if (n < 1 || n > kMaxThreadsPerRun) {
    throw InputError("--threads " + std::to_string(n), "expected 1.." + std::to_string(kMaxThreadsPerRun) + " threads per run");
  }
  return static_cast<unsigned>(n);
}

unsigned threads_per_worker(int workers) {
  return std::max(1u, default_thread_count() / static_cast<unsigned>(std::max(1, workers)));
}

ResolvedConfig config_from_options(const po::variables_map& vm) {
  std::vector<std::string> files;
  std::vector<std::string> sets;
  if (vm.count("config")) {
    for (const auto& f : vm["config"].as<std::vector<std::string>>()) files.push_back(find_data_file(f, DataFolder::Configs));
  }
  if (vm.count("set")) sets = vm["set"].as<std::vector<std::string>>();
  return resolve_config(files, sets);
}

namespace {

namespace fs = std::filesystem;

/// Where a data folder lives in the checkout the tool was built from.
fs::path data_folder_path(DataFolder folder) {
  const fs::path root(data_root());
  return folder == DataFolder::Configs ? root / "configs" : root / "configs" / "sweeps";
}

/// The .ini files of a data folder, by stem (for "did you mean" and the error's list).
std::vector<std::string> data_folder_names(DataFolder folder) {
  std::vector<std::string> names;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(data_folder_path(folder), ec)) {
    if (e.is_regular_file() && e.path().extension() == ".ini") names.push_back(e.path().stem().string());
  }
  std::sort(names.begin(), names.end());
  return names;
}

/// Case-insensitive edit distance counting a swap of two neighbouring letters as one edit
/// (optimal string alignment: "gx6540" is 1 from "gx6450", 2 from "gx6250").
std::size_t edit_distance(const std::string& a, const std::string& b) {
  auto lower = [](char c) { return static_cast<char>(std::tolower(static_cast<unsigned char>(c))); };
  std::vector<std::vector<std::size_t>> d(a.size() + 1, std::vector<std::size_t>(b.size() + 1));
  for (std::size_t i = 0; i <= a.size(); ++i) d[i][0] = i;
  for (std::size_t j = 0; j <= b.size(); ++j) d[0][j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t cost = lower(a[i - 1]) == lower(b[j - 1]) ? 0 : 1;
      d[i][j] = std::min({d[i - 1][j] + 1, d[i][j - 1] + 1, d[i - 1][j - 1] + cost});
      if (i > 1 && j > 1 && lower(a[i - 1]) == lower(b[j - 2]) && lower(a[i - 2]) == lower(b[j - 1])) {
        d[i][j] = std::min(d[i][j], d[i - 2][j - 2] + 1);
      }
    }
  }
  return d[a.size()][b.size()];
}

}  // namespace

std::string find_data_file(const std::string& arg, DataFolder folder) {
  const char* what = folder == DataFolder::Configs ? "config" : "sweep file";
  if (arg.empty()) throw InputError(std::string("empty ") + what + " name", "expected a file or a name");
  check_path_length(arg, what);  // longer than the OS allows: say so, not "no such file"
  std::error_code ec;
  const fs::path given(arg);
  std::vector<fs::path> tried = {given};
  if (given.is_relative()) {
    tried.push_back(fs::path(data_root()) / given);
    if (!given.has_parent_path()) {
      const fs::path dir = data_folder_path(folder);
      tried.push_back(dir / given);
      if (given.extension() != ".ini") tried.push_back(dir / (arg + ".ini"));
    }
  }
  for (const auto& p : tried) {
    if (fs::is_regular_file(p, ec)) return p == given ? arg : p.lexically_normal().string();
  }
  // The path is there but cannot be read (permission denied, a folder, a symlink loop): say why.
  if (std::error_code lec; fs::symlink_status(given, lec).type() != fs::file_type::not_found) {
    check_input_file(arg, what);
  }
  std::string msg = std::string("no such ") + what + " (looked for";
  for (std::size_t i = 0; i < tried.size(); ++i) msg += (i ? ", " : " ") + tried[i].lexically_normal().string();
  msg += ")";
  const std::vector<std::string> names = data_folder_names(folder);
  const std::string guess = did_you_mean(given.stem().string(), names);
  if (!guess.empty()) msg += "; " + guess;
  if (!names.empty()) {
    msg += std::string(guess.empty() ? ";" : "") + " Names in " + data_folder_path(folder).string() + ":";
    for (std::size_t i = 0; i < names.size(); ++i) msg += (i ? ", " : " ") + names[i];
  }
  throw InputError(arg, msg);
}

std::string did_you_mean(const std::string& token, const std::vector<std::string>& candidates) {
  // Close spellings (at most a third of the token's letters wrong, at least one allowed), or a
  // candidate whose last dotted part is the token ("tile_width" -> "tiling.tile_width").
  const std::size_t limit = std::max<std::size_t>(1, token.size() / 3);
  std::vector<std::pair<std::size_t, std::string>> close;
  for (const auto& c : candidates) {
    if (c == token) continue;
    const auto dot = c.rfind('.');
    const bool tail = dot != std::string::npos && c.compare(dot + 1, std::string::npos, token) == 0;
    const std::size_t d = tail ? 0 : edit_distance(token, c);
    if (d <= limit) close.emplace_back(d, c);
  }
  // The same words in another order ("dram_energy_mj" -> "energy_dram_mj"), however far apart.
  const auto words = [](const std::string& s) {
    std::vector<std::string> w;
    std::string lower;
    for (char ch : s) lower += static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
    std::size_t start = 0;
    while (start <= lower.size()) {
      const std::size_t end = lower.find_first_of("_.-", start);
      w.push_back(lower.substr(start, end == std::string::npos ? std::string::npos : end - start));
      if (end == std::string::npos) break;
      start = end + 1;
    }
    std::sort(w.begin(), w.end());
    return w;
  };
  const std::vector<std::string> token_words = words(token);
  if (token_words.size() > 1) {
    for (const auto& c : candidates) {
      if (c == token || words(c) != token_words) continue;
      if (std::none_of(close.begin(), close.end(), [&](const auto& e) { return e.second == c; })) close.emplace_back(0, c);
    }
  }
  if (close.empty()) return "";
  std::stable_sort(close.begin(), close.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  std::string text = "did you mean ";
  const std::size_t shown = std::min<std::size_t>(close.size(), 3);
  for (std::size_t i = 0; i < shown; ++i) {
    text += (i == 0 ? "" : i + 1 == shown ? " or " : ", ") + std::string("'") + close[i].second + "'";
  }
  return text + "?";
}

bool parse_command_options(const std::string& command, const std::vector<std::string>& args,
                           const po::options_description& desc,
                           const po::positional_options_description* positional, po::variables_map& vm,
                           std::ostream& out) {
  po::options_description all(desc);
  all.add_options()("help,h", "show this help");
  try {
    // Arguments that are not options: refused by name beyond what the command takes (Boost would
    // drop them silently when the command takes none, or say only "too many positional options").
    {
      po::command_line_parser probe(args);
      probe.options(all);
      const unsigned allowed = positional ? positional->max_total_count() : 0;
      unsigned seen = 0;
      for (const auto& o : probe.run().options) {
        if (o.position_key < 0 || o.original_tokens.empty()) continue;
        if (++seen > allowed) {
          const std::string& token = o.original_tokens.front();
          throw UsageError("tbdrsim " + command + ": unexpected argument '" + token + "' (" +
                           (allowed == 0 ? std::string("this command takes only options")
                                         : "this command takes " + std::to_string(allowed) + " argument(s) besides its options") +
                           "; `tbdrsim " + command + " --help` lists them)");
        }
      }
    }
    po::command_line_parser parser(args);
    parser.options(all);
    if (positional) parser.positional(*positional);
    po::store(parser.run(), vm);
    if (vm.count("help")) {
      out << "usage: tbdrsim " << command << " [options]\n\n" << all << "\n";
      return false;
    }
    po::notify(vm);
  } catch (const po::unknown_option& e) {
    // A misspelled option: the closest ones this command takes, as for parameters and metrics.
    const std::string name = e.get_option_name();
    std::vector<std::string> known;
    for (const auto& o : all.options()) {
      if (!o->long_name().empty()) known.push_back("--" + o->long_name());
    }
    const std::string guess = did_you_mean(name, known);
    if (!guess.empty()) {
      throw UsageError("tbdrsim " + command + ": " + e.what() + "; " + guess + " (`tbdrsim " + command +
                       " --help` lists the options)");
    }
    std::ostringstream help;
    help << all;
    throw UsageError("tbdrsim " + command + ": " + e.what() + "\n\nusage: tbdrsim " + command + " [options]\n\n" + help.str());
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
    if (name == "--views") {  // the analysis views' SQL, compiled in: `tbdrsim --views | sqlite3 DB` from any folder
      out << views_sql();
      return 0;
    }
    if (name == "--checkout") {  // where the configs, sweeps and analysis scripts are
      out << data_root() << "\n";
      return 0;
    }
    if (name == "--version") {
      // The instruction set it was compiled for (CMakeLists.txt, TBDRSIM_X86_64_LEVEL): host
      // timings of builds for different levels differ; no figure does.
      out << "tbdrsim " << kToolVersion << ", compiled for " << TBDRSIM_INSTRUCTION_SET << "\n";
      return 0;
    }
    for (const auto& c : cli_commands()) {
      if (name == c.name) return c.run(std::vector<std::string>(args.begin() + 1, args.end()), out, err);
    }
    std::vector<std::string> names;
    for (const auto& c : cli_commands()) names.push_back(c.name);
    const std::string guess = did_you_mean(name, names);
    err << "tbdrsim: unknown command '" << name << "'" << (guess.empty() ? "" : "; " + guess) << "\n\n";
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
