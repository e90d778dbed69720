#include "app/worker_pool.hpp"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <exception>
#include <filesystem>
#include <stdexcept>

namespace tbdr {

namespace {

volatile sig_atomic_t g_interrupts = 0;
volatile sig_atomic_t g_terminate = 0;

extern "C" void on_sigint(int) { g_interrupts = g_interrupts + 1; }
extern "C" void on_sigterm(int) { g_terminate = 1; }

/// Installs the pool's SIGINT/SIGTERM handlers for its lifetime and restores the old ones.
class SignalScope {
 public:
  SignalScope() {
    g_interrupts = 0;
    g_terminate = 0;
    struct sigaction sa {};
    sa.sa_handler = on_sigint;
    sigemptyset(&sa.sa_mask);
    sa.sa_flags = 0;  // no SA_RESTART: poll() returns EINTR at once
    sigaction(SIGINT, &sa, &old_int_);
    sa.sa_handler = on_sigterm;
    sigaction(SIGTERM, &sa, &old_term_);
  }
  ~SignalScope() {
    sigaction(SIGINT, &old_int_, nullptr);
    sigaction(SIGTERM, &old_term_, nullptr);
  }
  SignalScope(const SignalScope&) = delete;
  SignalScope& operator=(const SignalScope&) = delete;

 private:
  struct sigaction old_int_ {};
  struct sigaction old_term_ {};
};

/// A running child process.
struct Worker {
  std::size_t id = 0;
  pid_t pid = -1;
  int err_fd = -1;
  std::string err_text;
  std::chrono::steady_clock::time_point start;
  bool killed = false;
};

/// In the child, before it runs its job: its own process group, killed when the pool's process
/// dies, default signal actions, stdin and stdout on /dev/null, stderr into the pipe. Only
/// async-signal-safe calls.
void prepare_child(pid_t parent, int err_write_fd) {
  setpgid(0, 0);
  prctl(PR_SET_PDEATHSIG, SIGKILL);
  if (getppid() != parent) _exit(127);
  signal(SIGINT, SIG_DFL);
  signal(SIGTERM, SIG_DFL);
  const int devnull = open("/dev/null", O_RDWR);
  if (devnull >= 0) {
    dup2(devnull, STDIN_FILENO);
    dup2(devnull, STDOUT_FILENO);
  }
  dup2(err_write_fd, STDERR_FILENO);
}

/// Runs a function job in the child and leaves with its exit code (no atexit handlers, no flushing
/// of buffers copied from the parent).
[[noreturn]] void run_function_child(const std::function<int()>& function) {
  int rc = 1;
  try {
    rc = function();
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
  } catch (...) {
    std::fputs("error: unknown exception\n", stderr);
  }
  _exit(rc);
}

/// Starts one job in a child process with its stderr on a non-blocking pipe.
Worker spawn(const WorkerJob& job) {
  int fds[2];
  if (pipe2(fds, O_CLOEXEC) != 0) throw std::runtime_error(std::string("pipe: ") + std::strerror(errno));
  std::vector<char*> argv;
  for (const auto& a : job.argv) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  const pid_t parent = getpid();
  const pid_t pid = fork();
  if (pid < 0) {
    close(fds[0]);
    close(fds[1]);
    throw std::runtime_error(std::string("fork: ") + std::strerror(errno));
  }
  if (pid == 0) {
    prepare_child(parent, fds[1]);
    if (job.function) run_function_child(job.function);
    execv(argv[0], argv.data());
    const char msg[] = "cannot execute the tbdrsim binary\n";
    (void)!write(STDERR_FILENO, msg, sizeof msg - 1);
    _exit(127);
  }
  close(fds[1]);
  fcntl(fds[0], F_SETFL, fcntl(fds[0], F_GETFL) | O_NONBLOCK);
  Worker w;
  w.id = job.id;
  w.pid = pid;
  w.err_fd = fds[0];
  w.start = std::chrono::steady_clock::now();
  return w;
}

/// Reads what is available on a worker's stderr; false at end of file.
bool drain(Worker& w) {
  char buf[4096];
  for (;;) {
    const ssize_t n = read(w.err_fd, buf, sizeof buf);
    if (n > 0) {
      w.err_text.append(buf, static_cast<std::size_t>(n));
      if (w.err_text.size() > 64 * 1024) w.err_text.erase(0, w.err_text.size() - 64 * 1024);
      continue;
    }
    if (n == 0) return false;
    if (errno == EINTR) continue;
    return true;  // EAGAIN
  }
}

/// Reads the rest of a reaped worker's stderr and tells how it ended.
WorkerEnd end_of(Worker& w, int status) {
  while (drain(w)) {
  }
  close(w.err_fd);
  WorkerEnd end;
  end.id = w.id;
  end.status = status;
  end.killed = w.killed;
  end.stderr_text = std::move(w.err_text);
  end.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - w.start).count();
  return end;
}

/// Kills and reaps the workers still running when the pool leaves by an exception.
class WorkerGuard {
 public:
  explicit WorkerGuard(std::vector<Worker>& running) : running_(running) {}
  ~WorkerGuard() {
    for (auto& w : running_) {
      kill(w.pid, SIGKILL);
      waitpid(w.pid, nullptr, 0);
      close(w.err_fd);
    }
  }
  WorkerGuard(const WorkerGuard&) = delete;
  WorkerGuard& operator=(const WorkerGuard&) = delete;

 private:
  std::vector<Worker>& running_;
};

/// The pool's reaction to SIGINT/SIGTERM: whether it still launches jobs, and killing when asked.
class StopState {
 public:
  /// Looks at the signals received so far; returns true when launching must stop.
  bool update(std::vector<Worker>& running, const WorkerPoolHooks& hooks) {
    if (g_terminate || g_interrupts >= 2) {
      if (!killing_) {
        killing_ = stopping_ = true;
        if (hooks.stopping) hooks.stopping(true, running.size());
      }
      for (auto& w : running) {
        if (!w.killed) {
          kill(w.pid, SIGKILL);
          w.killed = true;
        }
      }
    } else if (g_interrupts >= 1 && !announced_) {
      announced_ = stopping_ = true;
      if (hooks.stopping) hooks.stopping(false, running.size());
    }
    return stopping_;
  }

 private:
  bool stopping_ = false, killing_ = false, announced_ = false;
};

}  // namespace

bool WorkerEnd::ok() const { return WIFEXITED(status) && WEXITSTATUS(status) == 0; }

bool run_worker_pool(const WorkerPoolOptions& opt, const WorkerPoolHooks& hooks) {
  if (opt.workers < 1) throw std::logic_error("run_worker_pool: no workers");
  std::optional<SignalScope> signals;
  if (opt.handle_signals) signals.emplace();
  std::vector<Worker> running;
  WorkerGuard guard(running);
  StopState stop;
  while (true) {
    const bool stopping = opt.handle_signals && stop.update(running, hooks);
    while (!stopping && running.size() < static_cast<std::size_t>(opt.workers)) {
      std::optional<WorkerJob> job = hooks.next();
      if (!job) break;
      running.push_back(spawn(*job));
    }
    if (hooks.running) hooks.running(running.size());
    if (running.empty()) break;
    if (hooks.tick) hooks.tick();

    std::vector<pollfd> fds;
    for (const auto& w : running) fds.push_back({w.err_fd, POLLIN, 0});
    if (poll(fds.data(), fds.size(), 100) > 0) {
      for (std::size_t k = 0; k < running.size(); ++k) {
        if (fds[k].revents) drain(running[k]);
      }
    }
    // Reap.
    for (std::size_t k = 0; k < running.size();) {
      int status = 0;
      if (waitpid(running[k].pid, &status, WNOHANG) != running[k].pid) {
        ++k;
        continue;
      }
      Worker done = std::move(running[k]);  // reaped: no longer the guard's to kill
      running.erase(running.begin() + static_cast<std::ptrdiff_t>(k));
      if (hooks.running) hooks.running(running.size());
      const WorkerEnd end = end_of(done, status);
      if (hooks.ended) hooks.ended(end);
    }
  }
  return opt.handle_signals && (g_interrupts > 0 || g_terminate);
}

std::vector<WorkerEnd> run_worker_jobs(int workers, std::vector<WorkerJob> jobs) {
  std::vector<WorkerEnd> ends(jobs.size());
  std::size_t next = 0;
  WorkerPoolHooks hooks;
  hooks.next = [&]() -> std::optional<WorkerJob> {
    if (next == jobs.size()) return std::nullopt;
    jobs[next].id = next;
    return std::move(jobs[next++]);
  };
  hooks.ended = [&](const WorkerEnd& end) { ends[end.id] = end; };
  run_worker_pool({std::max(1, workers), false}, hooks);
  return ends;
}

std::string self_executable() {
  std::error_code ec;
  const std::filesystem::path p = std::filesystem::read_symlink("/proc/self/exe", ec);
  return ec ? std::string("tbdrsim") : p.string();
}

std::string shell_quote(const std::string& s) {
  if (!s.empty() && s.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_-./=:,+@%") ==
                        std::string::npos) {
    return s;
  }
  std::string q = "'";
  for (char c : s) {
    if (c == '\'') {
      q += "'\\''";
    } else {
      q += c;
    }
  }
  return q + "'";
}

std::string shell_command_line(const std::vector<std::string>& argv) {
  std::string line;
  for (std::size_t a = 0; a < argv.size(); ++a) line += (a ? " " : "") + shell_quote(argv[a]);
  return line;
}

}  // namespace tbdr
