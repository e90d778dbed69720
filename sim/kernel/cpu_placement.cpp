#include "kernel/cpu_placement.hpp"

#include <algorithm>

#if defined(__linux__)
#include <sched.h>
#include <sys/syscall.h>
#include <unistd.h>
#endif

namespace tbdr {

namespace {

#if defined(__linux__)
long current_tid() { return static_cast<long>(syscall(SYS_gettid)); }

/// Sets the CPUs of thread `tid` (0: the calling thread); whether the kernel took them.
bool set_cpus(long tid, const CpuList& cpus) {
  cpu_set_t set;
  CPU_ZERO(&set);
  for (const int c : cpus) {
    if (c >= 0 && c < CPU_SETSIZE) CPU_SET(c, &set);
  }
  return sched_setaffinity(static_cast<pid_t>(tid), sizeof(set), &set) == 0;
}
#endif

}  // namespace

CpuList allowed_cpus() {
  CpuList cpus;
#if defined(__linux__)
  cpu_set_t set;
  CPU_ZERO(&set);
  if (sched_getaffinity(0, sizeof(set), &set) == 0) {
    for (int c = 0; c < CPU_SETSIZE; ++c) {
      if (CPU_ISSET(c, &set)) cpus.push_back(c);
    }
  }
#endif
  return cpus;
}

CpuList cpus_apart_from(const CpuList& allowed, int caller_cpu, unsigned threads) {
  if (allowed.size() < 2 || threads < allowed.size()) return {};
  if (std::find(allowed.begin(), allowed.end(), caller_cpu) == allowed.end()) return {};
  CpuList others;
  for (const int c : allowed) {
    if (c != caller_cpu) others.push_back(c);
  }
  return others;
}

CriticalThreadPlacement::CriticalThreadPlacement(unsigned threads) {
#if defined(__linux__)
  allowed_ = allowed_cpus();
  caller_cpu_ = sched_getcpu();
  caller_tid_ = current_tid();
  timing_cpus_ = cpus_apart_from(allowed_, caller_cpu_, threads);
#else
  (void)threads;
#endif
}

void CriticalThreadPlacement::keep_apart() {
#if defined(__linux__)
  std::lock_guard<std::mutex> lock(mutex_);
  if (restored_ || pinned_ || timing_cpus_.empty()) return;
  if (!set_cpus(caller_tid_, {caller_cpu_})) return;
  pinned_ = true;
  (void)set_cpus(0, timing_cpus_);
#endif
}

void CriticalThreadPlacement::restore() {
  std::lock_guard<std::mutex> lock(mutex_);
  if (restored_) return;
  restored_ = true;
#if defined(__linux__)
  if (pinned_) (void)set_cpus(caller_tid_, allowed_);
#endif
  pinned_ = false;
}

bool CriticalThreadPlacement::pinned() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return pinned_;
}

}  // namespace tbdr
