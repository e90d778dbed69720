#pragma once
// Threads inside one process (the sweep's worker pool, sim/app/worker_pool.hpp, runs processes):
// a fixed set of threads that run the items of one job at a time. Items are taken from a dynamic
// queue in item order (each free thread takes the lowest item not yet started), so cheap and dear
// items balance; the caller's thread is one of the workers and the call returns when every item
// has ended. Which thread runs an item is not deterministic: callers give each thread its own
// scratch (the `worker` index) and write each item's result to its own slot, then merge the slots
// in item order, so what they compute does not depend on the number of threads.
#include <condition_variable>
#include <cstddef>
#include <exception>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

namespace tbdr {

/// The threads a run uses when none is asked for: the hardware threads this process may run on
/// (its CPU affinity on Linux, else std::thread::hardware_concurrency), at least 1.
unsigned default_thread_count();

/// A fixed pool of threads running one job's items at a time (see the file comment).
class ThreadPool {
 public:
  /// A pool of `threads` workers (clamped to at least 1): the caller's thread and threads - 1 more.
  /// `helper_niceness` > 0 lowers the helpers' scheduling priority by that much (Linux nice, per
  /// thread; elsewhere ignored), so that threads outside the pool that the run waits on (the
  /// timing model beside the functional run) and the caller's thread keep their cores when the
  /// threads outnumber them, and the helpers take what those leave idle.
  explicit ThreadPool(unsigned threads, int helper_niceness = 0);
  ~ThreadPool();
  ThreadPool(const ThreadPool&) = delete;
  ThreadPool& operator=(const ThreadPool&) = delete;

  /// Workers, the caller's thread included: `worker` arguments are in [0, size()).
  unsigned size() const { return static_cast<unsigned>(threads_.size()) + 1; }

  /// Runs fn(item, worker) for every item in [0, count) and returns when all have ended. Items
  /// start in increasing order. If items throw, no further item starts, the started ones finish,
  /// and the exception of the lowest item that threw is rethrown here (the same one at any thread
  /// count: every item below it has started). Not reentrant: fn must not call for_each.
  void for_each(std::size_t count, const std::function<void(std::size_t item, unsigned worker)>& fn);

  /// for_each in two halves: start() posts the job to the helpers and returns at once (the
  /// caller may do other work meanwhile, but must not post another job); join() then works on
  /// the items left, waits for the helpers and rethrows as for_each does. With no helpers (one
  /// thread) every item runs in join(). `fn` is kept until join() returns.
  void start(std::size_t count, std::function<void(std::size_t item, unsigned worker)> fn);
  void join();
  /// Whether a job start() posted awaits its join().
  bool started() const { return started_; }

 private:
  /// Posts the job: sets it up and wakes the helpers (not for a single item: the caller runs it).
  void launch(std::size_t count, const std::function<void(std::size_t, unsigned)>* fn);
  /// Takes and runs items of the current job until none is left.
  void work(unsigned worker);
  /// A helper thread's loop: waits for a job, works on it, reports its end.
  void helper(unsigned worker);

  int helper_niceness_ = 0;

  std::vector<std::thread> threads_;
  std::mutex mutex_;
  std::condition_variable start_;  ///< a job was posted (or the pool is stopping)
  std::condition_variable done_;   ///< a helper finished its share of the job
  const std::function<void(std::size_t, unsigned)>* fn_ = nullptr;
  std::size_t count_ = 0;
  std::size_t next_ = 0;            ///< the next item to start (under mutex_)
  std::size_t job_ = 0;             ///< job generation: helpers start a job once
  unsigned busy_ = 0;               ///< helpers still working on the current job
  bool stop_ = false;
  std::size_t error_item_ = 0;      ///< the lowest item that threw
  std::exception_ptr error_;
  std::function<void(std::size_t, unsigned)> owned_fn_;  ///< start()'s job
  bool started_ = false;                                  ///< start() awaiting join()
};

}  // namespace tbdr
