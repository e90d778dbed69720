// tbdrsim entry point: everything but argument forwarding lives in the core library (sim/cli.cpp).
#include <unistd.h>

#include <cstdlib>
#include <iostream>
#include <string>
#include <vector>

#include "app/cli.hpp"

namespace {

/// glibc's allocator settings for a simulation run (issue 15). A 1080p frame touches a few
/// hundred MB in vectors that grow, are freed and are allocated again per pass and per render;
/// with glibc's defaults each large block is a fresh mmap and is trimmed when freed, so the
/// kernel zeroes and maps every 4 KiB page again: 23,000-80,000 page faults and 20 % of a run's
/// CPU time in the kernel on the machines measured. hugetlb=1 backs the heap with transparent
/// huge pages (512 times fewer faults) where the kernel allows them on request (madvise mode);
/// the mmap and trim thresholds of 4 GiB keep freed blocks in the heap for the next pass
/// instead of returning them to the kernel. Measured side by side (1 thread, atrium:3 1080p, 1024 lights):
/// plain_forward 1.31 -> 0.95 CPU s, the kernel's share 0.24 -> 0.06 s. docs/architecture.md says more.
constexpr const char* kMallocTunables =
    "glibc.malloc.hugetlb=1:glibc.malloc.mmap_threshold=4294967296:glibc.malloc.trim_threshold=4294967296";
/// Set in the environment of the re-executed process, so it runs once (and its children, which
/// inherit GLIBC_TUNABLES, do not re-execute either).
constexpr const char* kTunedMarker = "TBDRSIM_MALLOC_TUNED";

/// glibc reads its tunables only at process start: re-execute this program once with them set.
/// A user's own GLIBC_TUNABLES is respected as it is; without /proc (exec fails) the run goes
/// on with the defaults. Sanitizer builds have their own allocator and skip this, and so does a
/// process with a preloaded library (LD_PRELOAD: valgrind, heaptrack, a profiler), which the
/// tool under which it runs may not follow into a new program.
void reexec_with_malloc_tunables(char** argv) {
#if defined(__GLIBC__) && !defined(__SANITIZE_ADDRESS__)
  if (std::getenv("GLIBC_TUNABLES") != nullptr || std::getenv(kTunedMarker) != nullptr) return;
  if (const char* preload = std::getenv("LD_PRELOAD"); preload != nullptr && *preload != '\0') return;
  if (setenv("GLIBC_TUNABLES", kMallocTunables, 1) != 0 || setenv(kTunedMarker, "1", 1) != 0) return;
  execv("/proc/self/exe", argv);
  unsetenv("GLIBC_TUNABLES");  // exec failed: run here, untuned
  unsetenv(kTunedMarker);
#else
  (void)argv;
#endif
}

}  // namespace

int main(int argc, char** argv) {
  reexec_with_malloc_tunables(argv);
  std::vector<std::string> args(argv + 1, argv + argc);
  std::string& line = tbdr::invocation_command_line();
  for (int i = 0; i < argc; ++i) line += (i ? " " : "") + std::string(argv[i]);
  return tbdr::cli_main(args, std::cout, std::cerr);
}
