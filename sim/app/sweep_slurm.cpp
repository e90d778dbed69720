#include "app/sweep_slurm.hpp"

#include <cctype>
#include <filesystem>
#include <fstream>

#include "app/sweep_spec.hpp"
#include "app/worker_pool.hpp"
#include "kernel/errors.hpp"

namespace tbdr {

namespace fs = std::filesystem;

std::string write_slurm_job(const SweepSpec& spec, const std::string& dir, int slices, int jobs, const std::string& binary) {
  if (slices < 1 || slices > 100000) throw InputError("--slices " + std::to_string(slices), "expected 1..100000");
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (!fs::is_directory(dir)) throw InputError(dir, "cannot create the Slurm job folder");
  const std::string adir = fs::absolute(dir).lexically_normal().string();
  const std::string asweep = fs::absolute(spec.path).lexically_normal().string();
  const std::string abin = fs::absolute(binary.empty() ? self_executable() : binary).lexically_normal().string();
  std::string safe_name;
  for (char c : spec.name) safe_name += std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_' ? c : '_';
  const std::string script = (fs::path(adir) / (safe_name + ".sbatch")).string();
  const std::string merge = shell_quote(abin) + " merge " + shell_quote(adir + "/merged.db") + " " +
                            shell_quote(adir) + "/shard_*.db";
  const std::size_t points = expand_sweep(spec).size();
  std::ofstream f(script);
  f << "#!/bin/bash\n"
    << "# tbdrsim sweep '" << spec.name << "' (" << points << " points) as a Slurm job array of " << slices
    << " tasks.\n"
    << "# Array task i runs every " << slices << "-th point group from offset i (tbdrsim sweep --slice i/" << slices
    << ")\n"
    << "# into its own database " << adir << "/shard_i.db; a task that is re-run skips what its shard holds.\n"
    << "# Submit:            sbatch " << shell_quote(script) << "\n"
    << "# When all are done: " << merge << "\n"
    << "#SBATCH --job-name=tbdrsim-" << safe_name << "\n"
    << "#SBATCH --array=0-" << slices - 1 << "\n"
    << "#SBATCH --cpus-per-task=" << jobs << "\n"
    << "#SBATCH --output=" << adir << "/slurm-%A_%a.out\n"
    << "set -euo pipefail\n"
    << "TBDRSIM=${TBDRSIM:-" << shell_quote(abin) << "}\n"
    << "TASK=${SLURM_ARRAY_TASK_ID:?run this script with sbatch (it is a job array)}\n"
    << "exec \"$TBDRSIM\" sweep " << shell_quote(asweep) << " --slice \"${TASK}/" << slices << "\" \\\n"
    << "  --db " << shell_quote(adir) << "/shard_\"${TASK}\".db -j \"${SLURM_CPUS_PER_TASK:-" << jobs
    << "}\" --progress lines\n";
  f.close();
  if (!f) throw InputError(script, "cannot write the Slurm script");
  fs::permissions(script, fs::perms::owner_exec | fs::perms::group_exec | fs::perms::others_exec, fs::perm_options::add, ec);
  std::ofstream readme(fs::path(adir) / "README.md");
  readme << "# Slurm job for the tbdrsim sweep '" << spec.name << "'\n\n"
         << "Submit: `sbatch " << script << "` (" << slices << " array tasks; task i writes `shard_i.db` here).\n\n"
         << "Merge the shards when every task has finished (re-running a task resumes it):\n\n"
         << "    " << merge << "\n";
  return script;
}

}  // namespace tbdr
