#include "kernel/thread_pool.hpp"

#include <algorithm>
#include <stdexcept>

#if defined(__linux__)
#include <sched.h>
#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>
#endif

namespace tbdr {

unsigned default_thread_count() {
#if defined(__linux__)
  // The CPUs this process may run on (what taskset, cgroups or a Slurm allocation leave it), which
  // can be fewer than the machine has.
  cpu_set_t set;
  CPU_ZERO(&set);
  if (sched_getaffinity(0, sizeof(set), &set) == 0 && CPU_COUNT(&set) > 0) return static_cast<unsigned>(CPU_COUNT(&set));
#endif
  return std::max(1u, std::thread::hardware_concurrency());
}

ThreadPool::ThreadPool(unsigned threads, int helper_niceness) : helper_niceness_(helper_niceness) {
  const unsigned n = std::max(1u, threads);
  threads_.reserve(n - 1);
  for (unsigned w = 1; w < n; ++w) threads_.emplace_back([this, w] { helper(w); });
}

ThreadPool::~ThreadPool() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  start_.notify_all();
  for (auto& t : threads_) t.join();
}

void ThreadPool::work(unsigned worker) {
  for (;;) {
    std::size_t item = 0;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (next_ >= count_ || error_) return;
      item = next_++;
    }
    try {
      (*fn_)(item, worker);
    } catch (...) {
      std::lock_guard<std::mutex> lock(mutex_);
      if (!error_ || item < error_item_) {
        error_ = std::current_exception();
        error_item_ = item;
      }
    }
  }
}

void ThreadPool::helper(unsigned worker) {
#if defined(__linux__)
  // Linux applies nice to one thread when given its thread id (a helper's priority only; the
  // thread ends with the pool). Failing (a sandbox refusing it) changes no result: ignored.
  if (helper_niceness_ > 0) (void)setpriority(PRIO_PROCESS, static_cast<id_t>(syscall(SYS_gettid)), helper_niceness_);
#endif
  std::size_t seen = 0;
  for (;;) {
    {
      std::unique_lock<std::mutex> lock(mutex_);
      start_.wait(lock, [&] { return stop_ || job_ != seen; });
      if (stop_) return;
      seen = job_;
    }
    work(worker);
    {
      std::lock_guard<std::mutex> lock(mutex_);
      --busy_;
    }
    done_.notify_one();
  }
}

void ThreadPool::launch(std::size_t count, const std::function<void(std::size_t, unsigned)>* fn) {
  bool helpers = false;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    fn_ = fn;
    count_ = count;
    next_ = 0;
    error_ = nullptr;
    error_item_ = 0;
    // A single item needs no helper: it runs here (waking the helpers would cost more).
    busy_ = count > 1 ? static_cast<unsigned>(threads_.size()) : 0;
    helpers = busy_ > 0;
    if (helpers) ++job_;
  }
  if (helpers) start_.notify_all();
}

void ThreadPool::join() {
  work(0);
  std::exception_ptr error;
  {
    std::unique_lock<std::mutex> lock(mutex_);
    done_.wait(lock, [&] { return busy_ == 0; });
    fn_ = nullptr;
    error = error_;
    error_ = nullptr;
  }
  started_ = false;
  owned_fn_ = nullptr;
  if (error) std::rethrow_exception(error);
}

void ThreadPool::for_each(std::size_t count, const std::function<void(std::size_t, unsigned)>& fn) {
  if (started_) throw std::logic_error("ThreadPool::for_each: the job started before awaits its join()");
  if (count == 0) return;
  launch(count, &fn);
  join();
}

void ThreadPool::start(std::size_t count, std::function<void(std::size_t, unsigned)> fn) {
  if (started_) throw std::logic_error("ThreadPool::start: the job started before awaits its join()");
  started_ = true;
  owned_fn_ = std::move(fn);
  launch(count, &owned_fn_);
}

}  // namespace tbdr
