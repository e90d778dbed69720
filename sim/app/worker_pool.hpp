#pragma once
// The worker pool: runs jobs in parallel child processes, each a program to execute or a function
// run in a forked copy of this process, capturing what each writes to stderr. Sweeps run
// `tbdrsim run` per point on it, the study one simulation per point. It can stop cleanly on
// Ctrl-C: the first SIGINT stops launching and waits for the running jobs, a second SIGINT or a
// SIGTERM kills them.
#include <cstddef>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace tbdr {

/// One job: a program (argv[0] is its path) or, when `function` is set, a function run in a forked
/// copy of this process whose return value is the child's exit code.
struct WorkerJob {
  std::size_t id = 0;               ///< the caller's index, handed back when the job ends
  std::vector<std::string> argv;
  std::function<int()> function;
};

/// How a job ended.
struct WorkerEnd {
  std::size_t id = 0;
  int status = 0;            ///< the waitpid status
  bool killed = false;       ///< killed by the pool when stopping: it did not run to its end
  std::string stderr_text;   ///< what the job wrote to stderr (the last 64 KiB)
  double seconds = 0;        ///< wall time from start to end
  /// True when the job exited with code 0.
  bool ok() const;
};

/// What the pool asks of its caller and tells it; every hook but `next` may be empty.
struct WorkerPoolHooks {
  /// The next job, or nullopt when none is left; asked whenever a worker is free (not when stopping).
  std::function<std::optional<WorkerJob>()> next;
  /// A job ended (killed ones too), after `running` reported the workers still busy.
  std::function<void(const WorkerEnd&)> ended;
  /// The number of running workers, after launching and after each job ends.
  std::function<void(std::size_t running)> running;
  /// Called about ten times a second while jobs run, for a progress display.
  std::function<void()> tick;
  /// The pool is stopping on a signal: waiting for the `running` jobs, or killing them (`kill`).
  std::function<void(bool kill, std::size_t running)> stopping;
};

/// How the pool runs.
struct WorkerPoolOptions {
  int workers = 1;              ///< jobs running at once (1 or more)
  bool handle_signals = false;  ///< stop cleanly on SIGINT/SIGTERM (see the file comment)
};

/// Runs jobs until `next` has no more (or a signal stops it) and every started job has ended;
/// returns true when a signal stopped it. Each child has its own process group (a terminal Ctrl-C
/// reaches only this process, which decides), dies with this process, and has stdin and stdout on
/// /dev/null. When a hook throws, the running children are killed and reaped before it propagates.
bool run_worker_pool(const WorkerPoolOptions& options, const WorkerPoolHooks& hooks);

/// Runs a fixed list of jobs, `workers` at once (no signal handling), and returns how each ended,
/// indexed as `jobs` (each job's id is set to its index).
std::vector<WorkerEnd> run_worker_jobs(int workers, std::vector<WorkerJob> jobs);

/// This executable's path (/proc/self/exe): the program sweep workers run by default.
std::string self_executable();

/// One argument quoted for a POSIX shell (unchanged when it needs no quotes).
std::string shell_quote(const std::string& s);

/// A command line as a shell would take it: the arguments quoted and joined by spaces.
std::string shell_command_line(const std::vector<std::string>& argv);

}  // namespace tbdr
