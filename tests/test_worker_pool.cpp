// The worker pool: jobs (functions in forked children, or programs) run at most `workers` at a
// time, their stderr and exit status come back, a throwing hook kills the running children, and
// SIGINT stops launching (once) or kills the running jobs (twice).
#include <gtest/gtest.h>

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <stdexcept>
#include <thread>
#include <vector>

#include "app/worker_pool.hpp"
#include "scratch_dir.hpp"

namespace tbdr {
namespace {

namespace fs = std::filesystem;

testing_scratch::ScratchCleanup scratch_cleanup{"pool"};

/// Hooks that hand out `n` jobs made by `make` and record how each ended.
struct Recorder {
  std::size_t next = 0, max_running = 0;
  std::map<std::size_t, WorkerEnd> ends;
  WorkerPoolHooks hooks(std::size_t n, std::function<WorkerJob(std::size_t)> make) {
    WorkerPoolHooks h;
    h.next = [this, n, make]() -> std::optional<WorkerJob> {
      if (next == n) return std::nullopt;
      return make(next++);
    };
    h.ended = [this](const WorkerEnd& e) { ends[e.id] = e; };
    h.running = [this](std::size_t r) { max_running = std::max(max_running, r); };
    return h;
  }
};

WorkerJob function_job(std::size_t id, std::function<int()> f) {
  WorkerJob j;
  j.id = id;
  j.function = std::move(f);
  return j;
}

// Six jobs on two workers. No clock decides that two run at once: every job waits (in its child)
// on a pipe that the test writes to only once the pool has reported two running workers.
TEST(WorkerPool, RunsFunctionsInChildrenAtMostWorkersAtATime) {
  Recorder rec;
  const pid_t self = getpid();
  int gate[2];
  ASSERT_EQ(pipe(gate), 0);
  auto hooks = rec.hooks(6, [self, &gate](std::size_t i) {
    return function_job(i, [i, self, &gate] {
      std::fprintf(stderr, "job %zu in a child: %s\n", i, getpid() != self ? "yes" : "no");
      char c = 0;
      if (read(gate[0], &c, 1) != 1) return 3;
      return static_cast<int>(i % 2);
    });
  });
  hooks.running = [&rec, &gate](std::size_t r) {
    if (r == 2 && rec.max_running < 2) {  // both workers busy: every job may go
      const char go[6] = {};
      if (write(gate[1], go, sizeof go) != static_cast<ssize_t>(sizeof go)) throw std::runtime_error("write failed");
    }
    rec.max_running = std::max(rec.max_running, r);
  };
  const auto from = std::chrono::steady_clock::now();
  EXPECT_FALSE(run_worker_pool({2, false}, hooks));
  const double pool_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - from).count();
  close(gate[0]);
  close(gate[1]);
  ASSERT_EQ(rec.ends.size(), 6u);
  EXPECT_EQ(rec.max_running, 2u);
  for (const auto& [i, e] : rec.ends) {
    EXPECT_EQ(e.ok(), i % 2 == 0) << i;
    EXPECT_FALSE(e.killed);
    EXPECT_EQ(e.stderr_text, "job " + std::to_string(i) + " in a child: yes\n");
    EXPECT_GT(e.seconds, 0.0);  // a job's wall time: within the pool's
    EXPECT_LE(e.seconds, pool_seconds);
  }
}

TEST(WorkerPool, RunsProgramsAndReportsExceptionsOfFunctions) {
  Recorder rec;
  auto hooks = rec.hooks(3, [](std::size_t i) {
    if (i == 0) return function_job(i, []() -> int { throw std::runtime_error("no trace"); });
    WorkerJob j;
    j.id = i;
    j.argv = i == 1 ? std::vector<std::string>{"/bin/sh", "-c", "echo to stdout; echo to stderr >&2; exit 3"}
                    : std::vector<std::string>{"/nonexistent/tbdrsim", "run"};
    return j;
  });
  run_worker_pool({3, false}, hooks);
  ASSERT_EQ(rec.ends.size(), 3u);
  EXPECT_FALSE(rec.ends[0].ok());
  EXPECT_EQ(rec.ends[0].stderr_text, "error: no trace\n");
  EXPECT_TRUE(WIFEXITED(rec.ends[1].status));
  EXPECT_EQ(WEXITSTATUS(rec.ends[1].status), 3);
  EXPECT_EQ(rec.ends[1].stderr_text, "to stderr\n");  // stdout goes to /dev/null
  EXPECT_EQ(WEXITSTATUS(rec.ends[2].status), 127);
  EXPECT_EQ(rec.ends[2].stderr_text, "cannot execute the tbdrsim binary\n");
}

// run_worker_jobs: a fixed list, every job run once, the ends indexed as the list whatever order
// the jobs end in. Job 0 ends last whatever the machine's speed: it waits until job 4 (run after
// jobs 1-3 on the other worker) has left its file.
TEST(WorkerPool, RunWorkerJobsReturnsTheEndsInTheJobsOrder) {
  const fs::path last_file = testing_scratch::scratch_dir("pool", "order") / "job4.done";
  std::vector<WorkerJob> jobs;
  for (int i = 0; i < 5; ++i) {
    jobs.push_back(function_job(99, [i, last_file] {
      if (i == 0) {
        while (!fs::exists(last_file)) std::this_thread::yield();
      }
      if (i == 4) std::ofstream(last_file) << "done";
      std::fprintf(stderr, "%d", i);
      return i;
    }));
  }
  const std::vector<WorkerEnd> ends = run_worker_jobs(2, std::move(jobs));
  ASSERT_EQ(ends.size(), 5u);
  for (std::size_t i = 0; i < ends.size(); ++i) {
    EXPECT_EQ(ends[i].id, i);
    EXPECT_EQ(WEXITSTATUS(ends[i].status), static_cast<int>(i));
    EXPECT_EQ(ends[i].stderr_text, std::to_string(i));
  }
}

TEST(WorkerPool, AThrowingHookKillsTheRunningChildren) {
  const fs::path pid_file = testing_scratch::scratch_dir("pool", "throw") / "slow.pid";
  WorkerPoolHooks hooks;
  std::size_t next = 0;
  hooks.next = [&]() -> std::optional<WorkerJob> {
    if (next == 2) return std::nullopt;
    const std::size_t i = next++;
    if (i == 0) {
      return function_job(i, [pid_file]() -> int {
        // Written whole, then named: job 1 goes on once the name exists, and the pid is in it.
        const fs::path part = pid_file.string() + ".part";
        std::ofstream(part) << getpid();
        fs::rename(part, pid_file);
        for (;;) pause();  // until killed: a pool that waited for it would never return
      });
    }
    return function_job(i, [pid_file] {
      while (!fs::exists(pid_file)) std::this_thread::yield();
      return 0;
    });
  };
  hooks.ended = [](const WorkerEnd&) { throw std::runtime_error("database full"); };
  EXPECT_THROW(run_worker_pool({2, false}, hooks), std::runtime_error);
  pid_t slow = 0;
  std::ifstream(pid_file) >> slow;
  ASSERT_GT(slow, 0);
  EXPECT_EQ(kill(slow, 0), -1);  // reaped
  EXPECT_EQ(errno, ESRCH);
}

/// What a pool interrupted by SIGINT did.
struct Interrupted {
  std::map<std::size_t, WorkerEnd> ends;
  std::vector<bool> stops;  ///< the `kill` flag of each stopping report
  std::size_t launched = 0;
  bool interrupted = false;
};

/// Ten jobs on two workers: the first returns at once, the others wait (in their child process)
/// until the test writes to a pipe, so the first always ends first, whatever the machine's load.
/// When it has ended, SIGINT is raised `interrupts` times while the second still waits; then,
/// if `release`, the waiting jobs are let go (else they wait until the pool kills them).
Interrupted interrupt_after_first(int interrupts, bool release) {
  Interrupted r;
  int gate[2];
  if (pipe(gate) != 0) throw std::runtime_error("pipe failed");
  WorkerPoolHooks hooks;
  hooks.next = [&]() -> std::optional<WorkerJob> {
    if (r.launched == 10) return std::nullopt;
    const std::size_t i = r.launched++;
    return function_job(i, [i, &gate] {
      if (i == 0) return 0;
      char c = 0;
      return read(gate[0], &c, 1) == 1 ? 0 : 1;
    });
  };
  hooks.ended = [&](const WorkerEnd& e) {
    r.ends[e.id] = e;
    if (r.ends.size() == 1) {
      for (int k = 0; k < interrupts; ++k) raise(SIGINT);
      if (release) {
        const char bytes[9] = {};
        if (write(gate[1], bytes, sizeof bytes) != static_cast<ssize_t>(sizeof bytes)) throw std::runtime_error("write failed");
      }
    }
  };
  hooks.stopping = [&](bool kill, std::size_t) { r.stops.push_back(kill); };
  r.interrupted = run_worker_pool({2, true}, hooks);
  close(gate[0]);
  close(gate[1]);
  return r;
}

TEST(WorkerPool, FirstSigintStopsLaunchingAndWaits) {
  const Interrupted r = interrupt_after_first(1, true);
  EXPECT_TRUE(r.interrupted);
  EXPECT_EQ(r.stops, std::vector<bool>{false});
  EXPECT_EQ(r.launched, 2u);
  EXPECT_EQ(r.ends.size(), r.launched);
  for (const auto& [i, e] : r.ends) EXPECT_TRUE(e.ok() && !e.killed) << i;
}

TEST(WorkerPool, SecondSigintKillsTheRunningJobs) {
  const Interrupted r = interrupt_after_first(2, false);
  EXPECT_TRUE(r.interrupted);
  EXPECT_EQ(r.stops, std::vector<bool>{true});
  EXPECT_EQ(r.ends.size(), r.launched);
  std::size_t killed = 0;
  for (const auto& [i, e] : r.ends) killed += e.killed ? 1 : 0;
  EXPECT_EQ(killed, r.launched - 1);
  // The pool put the old action back.
  struct sigaction now {};
  sigaction(SIGINT, nullptr, &now);
  EXPECT_EQ(now.sa_handler, SIG_DFL);
}

TEST(WorkerPool, ShellQuoting) {
  EXPECT_EQ(shell_quote("plain-arg_1.ini"), "plain-arg_1.ini");
  EXPECT_EQ(shell_quote(""), "''");
  EXPECT_EQ(shell_quote("a b"), "'a b'");
  EXPECT_EQ(shell_quote("it's"), "'it'\\''s'");
  EXPECT_EQ(shell_command_line({"tbdrsim", "run", "--set", "gpu.name=a GPU"}), "tbdrsim run --set 'gpu.name=a GPU'");
}

}  // namespace
}  // namespace tbdr
