#include "app/sweep_slurm.hpp"

#include <cctype>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <regex>

#include "app/sweep_spec.hpp"
#include "app/worker_pool.hpp"
#include "kernel/errors.hpp"
#include "kernel/output_file.hpp"

namespace tbdr {

namespace fs = std::filesystem;

namespace {

/// An absolute, normalised folder path without a trailing separator ("out/job/" -> "/w/out/job"),
/// so that "DIR/shard_0.db" never reads "DIR//shard_0.db".
std::string clean_dir(const std::string& dir) {
  fs::path p = fs::absolute(dir).lexically_normal();
  if (!p.has_filename() && p.has_parent_path() && p != p.root_path()) p = p.parent_path();
  return p.string();
}

}  // namespace

void check_slurm_option(const std::string& option, const std::string& value) {
  // The forms sbatch(1) documents: --time "minutes", "minutes:seconds", "hours:minutes:seconds",
  // "days-hours", "days-hours:minutes", "days-hours:minutes:seconds", or UNLIMITED/INFINITE;
  // --mem "<size>[K|M|G|T]"; --partition a comma-separated list of partition names.
  static const std::regex time_re(R"(\d+(:\d{1,2}){0,2}|\d+-\d{1,2}(:\d{1,2}){0,2}|UNLIMITED|INFINITE)");
  static const std::regex mem_re(R"(\d+[KMGT]?)");
  static const std::regex partition_re(R"([A-Za-z0-9_.-]+(,[A-Za-z0-9_.-]+)*)");
  if (option == "--time" && !std::regex_match(value, time_re)) {
    throw InputError("--time " + value, "expected a Slurm time limit: MINUTES, MINUTES:SECONDS, HOURS:MINUTES:SECONDS, "
                                        "DAYS-HOURS[:MINUTES[:SECONDS]] (e.g. 2:00:00) or UNLIMITED");
  }
  if (option == "--mem" && !std::regex_match(value, mem_re)) {
    throw InputError("--mem " + value, "expected a Slurm memory size: a number with an optional K, M, G or T (e.g. 4G)");
  }
  if (option == "--partition" && !std::regex_match(value, partition_re)) {
    throw InputError("--partition " + value, "expected partition names (letters, digits, _ . -), comma-separated");
  }
}

std::string write_slurm_job(const SweepSpec& spec, const std::string& dir, const SlurmJobOptions& opt) {
  const int slices = opt.slices, jobs = opt.jobs;
  if (slices < 1 || slices > 100000) throw InputError("--slices " + std::to_string(slices), "expected 1..100000");
  check_slurm_option("--time", opt.time.empty() ? "0" : opt.time);
  check_slurm_option("--mem", opt.mem.empty() ? "0" : opt.mem);
  check_slurm_option("--partition", opt.partition.empty() ? "x" : opt.partition);
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (!fs::is_directory(dir)) throw InputError(dir, "cannot create the Slurm job folder");
  const std::string adir = clean_dir(dir);
  const std::string asweep = fs::absolute(spec.path).lexically_normal().string();
  const std::string abin = fs::absolute(opt.binary.empty() ? self_executable() : opt.binary).lexically_normal().string();
  std::string safe_name;
  for (char c : spec.name) safe_name += std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_' ? c : '_';
  const std::string script = (fs::path(adir) / (safe_name + ".sbatch")).string();
  const std::string merge = shell_quote(abin) + " merge " + shell_quote(adir + "/merged.db") + " " +
                            shell_quote(adir) + "/shard_*.db";
  std::string trace_args;
  for (const auto& t : opt.traces) trace_args += " --trace " + shell_quote(fs::absolute(t).lexically_normal().string());
  const std::size_t points = SweepPoints(spec).total();
  std::ostringstream f;
  f << "#!/bin/bash\n"
    << "# tbdrsim sweep '" << spec.name << "' (" << points << " points) as a Slurm job array of " << slices
    << " tasks.\n"
    << "# Array task i runs every " << slices << "-th point group from offset i (tbdrsim sweep --slice i/" << slices
    << ")\n"
    << "# into its own database " << adir << "/shard_i.db; a task that is re-run skips what its shard holds.\n"
    << "# Submit:            sbatch " << shell_quote(script) << "\n"
    << "# Without Slurm:     SLURM_ARRAY_TASK_ID=i bash " << shell_quote(script) << "   (one task, i = 0.."
    << slices - 1 << ")\n"
    << "# When all are done: " << merge << "\n"
    << "#SBATCH --job-name=tbdrsim-" << safe_name << "\n"
    << "#SBATCH --array=0-" << slices - 1 << "\n"
    << "#SBATCH --cpus-per-task=" << jobs << "\n";
  if (!opt.time.empty()) f << "#SBATCH --time=" << opt.time << "\n";
  if (!opt.partition.empty()) f << "#SBATCH --partition=" << opt.partition << "\n";
  if (!opt.mem.empty()) f << "#SBATCH --mem=" << opt.mem << "\n";
  f << "#SBATCH --output=" << adir << "/slurm-%A_%a.out\n"
    << "set -euo pipefail\n"
    << "TBDRSIM=${TBDRSIM:-" << shell_quote(abin) << "}\n"
    << "TASK=${SLURM_ARRAY_TASK_ID:?run this script with sbatch (it is a job array)}\n"
    << "exec \"$TBDRSIM\" sweep " << shell_quote(asweep) << trace_args << " --slice \"${TASK}/" << slices << "\" \\\n"
    << "  --db " << shell_quote(adir) << "/shard_\"${TASK}\".db -j \"${SLURM_CPUS_PER_TASK:-" << jobs
    << "}\" --progress lines\n";
  write_output_file(script, "the Slurm script", f.str());  // whole or not at all
  fs::permissions(script, fs::perms::owner_exec | fs::perms::group_exec | fs::perms::others_exec, fs::perm_options::add, ec);
  std::ostringstream readme;
  readme << "# Slurm job for the tbdrsim sweep '" << spec.name << "'\n\n"
         << "Submit: `sbatch " << script << "` (" << slices << " array tasks; task i writes `shard_i.db` here).\n"
         << "Without Slurm, run task i by hand: `SLURM_ARRAY_TASK_ID=i bash " << script << "`.\n\n"
         << "Merge the shards when every task has finished (re-running a task resumes it):\n\n"
         << "    " << merge << "\n";
  write_output_file((fs::path(adir) / "README.md").string(), "the job's README", readme.str());
  return script;
}

}  // namespace tbdr
