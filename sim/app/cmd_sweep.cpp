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
#include "kernel/thread_pool.hpp"
#include "app/sweep.hpp"
#include "app/sweep_merge.hpp"
#include "app/sweep_slurm.hpp"
#include "app/worker_pool.hpp"
#include "kernel/errors.hpp"

namespace tbdr {

namespace po = boost::program_options;

namespace {

/// The values of a multi-valued option, each also split at commas ("--by a,b c" -> a, b, c).
std::vector<std::string> split_option_list(const std::vector<std::string>& values, const std::string& option) {
  std::vector<std::string> out;
  for (const auto& v : values) {
    std::size_t start = 0;
    while (true) {
      const std::size_t comma = v.find(',', start);
      const std::string item = v.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
      if (item.empty()) throw InputError(option + " " + v, "empty name in the list");
      out.push_back(item);
      if (comma == std::string::npos) break;
      start = comma + 1;
    }
  }
  return out;
}

}  // namespace

int cmd_sweep(const std::vector<std::string>& args, std::ostream& out, std::ostream&) {
  const int cores = static_cast<int>(default_thread_count());
  po::options_description desc(
      "sweep options: tbdrsim sweep FILE --db DB [-j N] [--slice i/K] [--trace GLOB...]\n"
      "               tbdrsim sweep FILE --emit-slurm DIR [--slices K] [--time T] [--partition P] [--mem M]\n"
      "FILE is a sweep file, or the name of one in the checkout's configs/sweeps/ (tile_size, lights, ...;\n"
      "`tbdrsim --help` gives the search order); its syntax: docs/sweeps.md");
  desc.add_options()
      ("file", po::value<std::string>()->required(), "sweep file (INI) or name")
      ("db,d", po::value<std::string>(), "results database (created if absent); points already in it are skipped")
      ("trace", po::value<std::vector<std::string>>()->composing(),
       "trace file or glob, from the working folder; repeatable; replaces the sweep file's trace lines")
      ("jobs,j", po::value<int>()->default_value(cores), "worker processes running points in parallel")
      ("slice", po::value<std::string>(), "run only slice i/K: every K-th point group from offset i")
      ("emit-slurm", po::value<std::string>(), "write a Slurm job-array script into this folder instead of running")
      ("slices", po::value<int>(), "array tasks for --emit-slurm (default: point groups, at most 32)")
      ("time", po::value<std::string>(), "--emit-slurm: each task's time limit (#SBATCH --time, e.g. 2:00:00)")
      ("partition", po::value<std::string>(), "--emit-slurm: the partition (#SBATCH --partition)")
      ("mem", po::value<std::string>(), "--emit-slurm: memory per task's node (#SBATCH --mem, e.g. 4G)")
      ("progress", po::value<std::string>()->default_value("auto"),
       "auto | bar | lines | none (auto: a bar on a terminal, lines otherwise)")
      ("dry-run,n", "list the points and which are already done; run nothing, write nothing")
      ("tbdrsim", po::value<std::string>(), "tbdrsim executable the workers run (default: this one)");
  add_threads_option(desc, "the cores this process may use divided between the workers, at least 1, so that "
                           "jobs x threads <= cores; with the default -j, 1");
  po::positional_options_description pos;
  pos.add("file", 1);
  po::variables_map vm;
  if (!parse_command_options("sweep", args, desc, &pos, vm, out)) return 0;

  const std::vector<std::string> traces =
      vm.count("trace") ? vm["trace"].as<std::vector<std::string>>() : std::vector<std::string>{};
  // `config = series6xt_gx6450` in the file names the preset as --config does.
  set_sweep_config_lookup([](const std::string& name) { return find_data_file(name, DataFolder::Configs); });
  const SweepSpec spec = parse_sweep_file(find_data_file(vm["file"].as<std::string>(), DataFolder::Sweeps), traces,
                                          vm.count("db") ? vm["db"].as<std::string>() : std::string(), trace_generators());
  const std::string binary = vm.count("tbdrsim") ? vm["tbdrsim"].as<std::string>() : self_executable();
  const int jobs = vm["jobs"].as<int>();
  const bool slurm = vm.count("emit-slurm") > 0;
  for (const char* o : {"time", "partition", "mem"}) {
    if (!vm.count(o)) continue;
    if (!slurm) throw UsageError(std::string("tbdrsim sweep: --") + o + " goes with --emit-slurm (it is a Slurm request)");
    check_slurm_option(std::string("--") + o, vm[o].as<std::string>());
  }
  if (slurm) {
    if (vm.count("threads")) {
      throw UsageError("tbdrsim sweep: --emit-slurm tasks divide their CPUs (--cpus-per-task) between workers and threads "
                       "themselves; --threads goes with a sweep that runs");
    }
    if (vm.count("slice")) throw UsageError("tbdrsim sweep: --emit-slurm and --slice do not go together");
    if (vm.count("db")) throw UsageError("tbdrsim sweep: --emit-slurm writes one shard database per task; --db goes with a sweep that runs");
    const std::size_t groups = SweepPoints(spec).groups();
    SlurmJobOptions job;
    job.slices = vm.count("slices") ? vm["slices"].as<int>() : static_cast<int>(std::min<std::size_t>(groups, 32));
    job.jobs = jobs;
    job.binary = binary;
    job.traces = traces;
    if (vm.count("time")) job.time = vm["time"].as<std::string>();
    if (vm.count("partition")) job.partition = vm["partition"].as<std::string>();
    if (vm.count("mem")) job.mem = vm["mem"].as<std::string>();
    print_slow_points(spec, out);
    if (vm.count("dry-run")) {
      out << "dry run: would write a Slurm job of " << job.slices << " array tasks over " << groups
          << " point groups into " << vm["emit-slurm"].as<std::string>() << "; wrote nothing\n";
      return 0;
    }
    const std::string script = write_slurm_job(spec, vm["emit-slurm"].as<std::string>(), job);
    out << "wrote " << script << " (" << job.slices << " array tasks over " << groups
        << " point groups); submit it with sbatch, then merge the shards (see README.md beside it)\n";
    return 0;
  }
  if (vm.count("slices")) throw UsageError("tbdrsim sweep: --slices goes with --emit-slurm (use --slice i/K to run one)");
  if (!vm.count("db")) throw UsageError("tbdrsim sweep: --db FILE is required (or --emit-slurm DIR)");

  SweepOptions opt;
  opt.db_path = vm["db"].as<std::string>();
  opt.jobs = jobs;
  opt.threads = static_cast<int>(threads_option(vm, threads_per_worker(jobs)));
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

int cmd_report(const std::vector<std::string>& args, std::ostream& out, std::ostream& err) {
  po::options_description desc("report options");
  desc.add_options()
      ("db,d", po::value<std::string>()->required(), "results database")
      ("by,b", po::value<std::vector<std::string>>()->multitoken()->composing(),
       "group by: technique (default), scene, config, lights, or any parameter key (tiling.tile_width); "
       "several keys: --by technique tiling.tile_width (or repeat --by, or separate them by commas)")
      ("metric,m", po::value<std::vector<std::string>>()->multitoken()->composing(),
       "figures to show (v_metric names: frame_time_ms, dram_total_mb, dram_color_mb, energy_total_mj, "
       "overshading, tsp.shaded_samples, ...); several as for --by; default: the headline figures present")
      ("format,f", po::value<std::string>()->default_value("table"), "table | csv | markdown")
      ("where,w", po::value<std::string>(), "SQL condition on v_run_summary's columns, e.g. \"lights = 256\"")
      ("transpose,t", "one row per metric, one column per group")
      ("baseline", po::value<std::string>(),
       "KEY=VALUE: compare each group with the group differing only in KEY, where KEY = VALUE (difference and ratio "
       "per metric), e.g. pls.tile_buffer_bits_per_pixel=128 or technique=deferred")
      ("rank", po::value<std::string>(),
       "METRIC[:min|:max]: rank the rows by a figure, least first (:max: largest first), among the rows that share "
       "every --by key but the last, e.g. --by tiling.tile_width technique --rank energy_dram_mj")
      ("best", "with --rank: only the best row of each group (ties kept)");
  po::variables_map vm;
  if (!parse_command_options("report", args, desc, nullptr, vm, out)) return 0;
  const std::string path = vm["db"].as<std::string>();
  if (access(path.c_str(), F_OK) != 0) throw InputError(path, "no such results database");
  ResultsDb db(path);
  ReportOptions opt;
  if (vm.count("by")) opt.by = split_option_list(vm["by"].as<std::vector<std::string>>(), "--by");
  if (vm.count("metric")) opt.metrics = split_option_list(vm["metric"].as<std::vector<std::string>>(), "--metric");
  if (vm.count("where")) opt.where = vm["where"].as<std::string>();
  opt.transpose = vm.count("transpose") > 0;
  if (vm.count("baseline")) opt.baseline = vm["baseline"].as<std::string>();
  if (vm.count("rank")) opt.rank = vm["rank"].as<std::string>();
  opt.best = vm.count("best") > 0;
  const ReportFormat format = parse_report_format(vm["format"].as<std::string>());
  ReportTable table;
  try {
    table = build_report(db, opt);
  } catch (const InputError& e) {
    // An unknown group key or metric: name the closest ones this database has.
    const std::string& where = e.where();
    std::string guess;
    if (where.rfind("--by ", 0) == 0) guess = did_you_mean(where.substr(5), report_group_key_names(db));
    if (where.rfind("--metric ", 0) == 0) guess = did_you_mean(where.substr(9), report_metric_names(db));
    if (where.rfind("--rank ", 0) == 0) {
      const std::string name = where.substr(7);
      guess = did_you_mean(name.substr(0, name.rfind(':')), report_metric_names(db));
    }
    if (guess.empty()) throw;
    throw InputError("", std::string(e.what()) + "; " + guess);
  }
  print_report(table, format, opt.transpose, out);
  if (format == ReportFormat::Csv && table.runs_failed > 0) {
    // The CSV stays a table; what it left out is said beside it.
    err << "tbdrsim report: " << table.runs_failed << " failed run(s) left out:";
    for (const auto& [reason, n] : table.failed_reasons) err << "\n  " << n << " x " << reason;
    err << "\n";
  }
  return 0;
}

}  // namespace tbdr
