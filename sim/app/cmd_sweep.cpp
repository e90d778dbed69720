// `tbdrsim sweep`, `tbdrsim merge` and `tbdrsim report`: run a sweep file in parallel worker
// processes (or emit it as a Slurm job array), merge shard databases, print comparison tables.
#include <unistd.h>

#include <iostream>
#include <thread>

#include <boost/program_options.hpp>

#include "analysis/report.hpp"
#include "analysis/results_db.hpp"
#include "app/cli.hpp"
#include "app/commands.hpp"
#include "app/sweep.hpp"
#include "app/sweep_merge.hpp"
#include "app/sweep_slurm.hpp"
#include "app/worker_pool.hpp"
#include "kernel/errors.hpp"

namespace tbdr {

namespace po = boost::program_options;

int cmd_sweep(const std::vector<std::string>& args, std::ostream& out, std::ostream&) {
  const int cores = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  po::options_description desc(
      "sweep options: tbdrsim sweep FILE --db DB [-j N] [--slice i/K] | FILE --emit-slurm DIR [--slices K]\n"
      "(sweep file syntax: docs/sweeps.md)");
  desc.add_options()
      ("file", po::value<std::string>()->required(), "sweep file (INI)")
      ("db,d", po::value<std::string>(), "results database (created if absent); points already in it are skipped")
      ("jobs,j", po::value<int>()->default_value(cores), "worker processes running points in parallel")
      ("slice", po::value<std::string>(), "run only slice i/K: every K-th point group from offset i")
      ("emit-slurm", po::value<std::string>(), "write a Slurm job-array script into this folder instead of running")
      ("slices", po::value<int>(), "array tasks for --emit-slurm (default: point groups, at most 32)")
      ("progress", po::value<std::string>()->default_value("auto"),
       "auto | bar | lines | none (auto: a bar on a terminal, lines otherwise)")
      ("dry-run,n", "list the points and which are already done; run nothing")
      ("tbdrsim", po::value<std::string>(), "tbdrsim executable the workers run (default: this one)");
  po::positional_options_description pos;
  pos.add("file", 1);
  po::variables_map vm;
  if (!parse_command_options("sweep", args, desc, &pos, vm, out)) return 0;

  const SweepSpec spec = parse_sweep_file(vm["file"].as<std::string>());
  const std::string binary = vm.count("tbdrsim") ? vm["tbdrsim"].as<std::string>() : self_executable();
  const int jobs = vm["jobs"].as<int>();
  if (vm.count("emit-slurm")) {
    if (vm.count("slice")) throw UsageError("tbdrsim sweep: --emit-slurm and --slice do not go together");
    std::size_t groups = 0;
    for (const auto& p : expand_sweep(spec)) groups = std::max(groups, p.group + 1);
    const int slices = vm.count("slices") ? vm["slices"].as<int>() : static_cast<int>(std::min<std::size_t>(groups, 32));
    const std::string script = write_slurm_job(spec, vm["emit-slurm"].as<std::string>(), slices, jobs, binary);
    out << "wrote " << script << " (" << slices << " array tasks over " << groups
        << " point groups); submit it with sbatch, then merge the shards (see README.md beside it)\n";
    return 0;
  }
  if (vm.count("slices")) throw UsageError("tbdrsim sweep: --slices goes with --emit-slurm (use --slice i/K to run one)");
  if (!vm.count("db")) throw UsageError("tbdrsim sweep: --db FILE is required (or --emit-slurm DIR)");

  SweepOptions opt;
  opt.db_path = vm["db"].as<std::string>();
  opt.jobs = jobs;
  opt.binary = binary;
  opt.dry_run = vm.count("dry-run") > 0;
  if (vm.count("slice")) opt.slice = parse_slice(vm["slice"].as<std::string>());
  const std::string progress = vm["progress"].as<std::string>();
  if (progress == "auto") {
    opt.progress = (&out == &std::cout && isatty(STDOUT_FILENO)) ? SweepProgress::Bar : SweepProgress::Lines;
  } else if (progress == "bar") {
    opt.progress = SweepProgress::Bar;
  } else if (progress == "lines") {
    opt.progress = SweepProgress::Lines;
  } else if (progress == "none") {
    opt.progress = SweepProgress::None;
  } else {
    throw InputError("--progress " + progress, "expected auto, bar, lines or none");
  }
  const SweepSummary s = run_sweep(spec, opt, out);
  if (s.interrupted) return 130;
  return s.failed ? 1 : 0;
}

int cmd_merge(const std::vector<std::string>& args, std::ostream& out, std::ostream&) {
  po::options_description desc("merge options: tbdrsim merge OUT.db SHARD.db...");
  desc.add_options()
      ("out", po::value<std::string>()->required(), "output database (created if absent)")
      ("shards", po::value<std::vector<std::string>>()->required(), "shard databases to merge into it");
  po::positional_options_description pos;
  pos.add("out", 1).add("shards", -1);
  po::variables_map vm;
  if (!parse_command_options("merge", args, desc, &pos, vm, out)) return 0;
  const std::string target = vm["out"].as<std::string>();
  std::size_t copied = 0, dups = 0;
  for (const auto& r : merge_databases(target, vm["shards"].as<std::vector<std::string>>())) {
    out << r.shard << ": " << r.copied << " run(s) copied, " << r.duplicates << " duplicate(s) skipped\n";
    copied += r.copied;
    dups += r.duplicates;
  }
  out << "merged into " << target << ": " << copied << " run(s) copied, " << dups << " duplicate(s) skipped\n";
  return 0;
}

int cmd_report(const std::vector<std::string>& args, std::ostream& out, std::ostream&) {
  po::options_description desc("report options");
  desc.add_options()
      ("db,d", po::value<std::string>()->required(), "results database")
      ("by,b", po::value<std::vector<std::string>>()->composing(),
       "group by: technique (default), scene, config, lights, or any parameter key (tiling.tile_width); repeatable")
      ("metric,m", po::value<std::vector<std::string>>()->composing(),
       "figure to show (a v_metric name: frame_time_ms, dram_total_mb, dram_color_mb, energy_total_mj, "
       "overshading, tsp.shaded_samples, ...); repeatable; default: the headline figures present")
      ("format,f", po::value<std::string>()->default_value("table"), "table | csv | markdown")
      ("where,w", po::value<std::string>(), "SQL condition on v_run_summary's columns, e.g. \"lights = 256\"")
      ("transpose,t", "one row per metric, one column per group")
      ("baseline", po::value<std::string>(),
       "KEY=VALUE: compare each group with the group differing only in KEY, where KEY = VALUE (difference and ratio "
       "per metric), e.g. pls.tile_buffer_bits_per_pixel=128 or technique=deferred");
  po::variables_map vm;
  if (!parse_command_options("report", args, desc, nullptr, vm, out)) return 0;
  const std::string path = vm["db"].as<std::string>();
  if (access(path.c_str(), F_OK) != 0) throw InputError(path, "no such results database");
  ResultsDb db(path);
  ReportOptions opt;
  if (vm.count("by")) opt.by = vm["by"].as<std::vector<std::string>>();
  if (vm.count("metric")) opt.metrics = vm["metric"].as<std::vector<std::string>>();
  if (vm.count("where")) opt.where = vm["where"].as<std::string>();
  opt.transpose = vm.count("transpose") > 0;
  if (vm.count("baseline")) opt.baseline = vm["baseline"].as<std::string>();
  const ReportFormat format = parse_report_format(vm["format"].as<std::string>());
  print_report(build_report(db, opt), format, opt.transpose, out);
  return 0;
}

}  // namespace tbdr
