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
/// with glibc's defaults each block over 128 KiB is a fresh mmap whose pages the kernel maps and
/// zeroes again every time, and freed memory goes back to the kernel: 23,000-84,000 page faults
/// per 1080p run and a fifth of its CPU time in the kernel on the machines measured. Blocks up to
/// 32 MiB (glibc's largest mmap threshold) come from the heap and are kept for the next pass, and
/// the heap is trimmed only past 256 MiB free, so a page is faulted in once per run; larger blocks
/// (whole-frame arrays) are mapped and unmapped as before, so a run's peak stays that of its
/// largest pass. Transparent huge pages (hugetlb=1, used until 2026-12) are not asked for: on the
/// virtual machines measured, a fresh 2 MiB page costs about 1 ms to fault in (the host backs it
/// again), against 0.4 ms for 512 small pages, and a run that touches a few hundred MB once spent
/// 0.2-0.8 s more in the kernel with them. Measured side by side (1 thread, atrium:3 1080p,
/// 1024 lights, kernel CPU seconds with / without huge pages): deferred with images 0.55-0.78 /
/// 0.17-0.20, forward_multipass (256 lights) 0.33-0.51 / 0.08-0.11, light_prepass 0.06-0.21 /
/// 0.03-0.04, user time the same within noise; docs/architecture.md.
constexpr const char* kMallocTunables =
    "glibc.malloc.mmap_threshold=33554432:glibc.malloc.trim_threshold=268435456";
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
