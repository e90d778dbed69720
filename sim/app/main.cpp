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
/// with glibc's defaults each block over 128 KiB is a fresh mmap whose 4 KiB pages the kernel maps
/// and zeroes one fault at a time, and freed memory goes back to the kernel: 23,000-84,000 page
/// faults per 1080p run and a fifth of its CPU time in the kernel on the machines measured.
/// hugetlb=1 backs the heap and the mmapped blocks with transparent huge pages where the kernel
/// grants them on request (madvise mode): 512 times fewer faults. Blocks up to 32 MiB (glibc's
/// largest mmap threshold) come from the heap and are kept for the next pass, and the heap is
/// trimmed only past 256 MiB free; larger blocks (whole-frame arrays) are mapped and unmapped
/// as before, so a run's peak stays that of its largest pass. Measured side by side (1 thread,
/// atrium:3 1080p, 1024 lights; docs/architecture.md): plain_forward 23,400 -> 1,200 faults and
/// 0.2 -> 0.03 s in the kernel; forward_multipass (256 lights) peak 202 -> 231 MB, where 4 GiB
/// thresholds (no mapping, no trimming) grew it to 348 MB.
constexpr const char* kMallocTunables =
    "glibc.malloc.hugetlb=1:glibc.malloc.mmap_threshold=33554432:glibc.malloc.trim_threshold=268435456";
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
