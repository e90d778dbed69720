#include "app/host_speed.hpp"

#include <unistd.h>

#include <filesystem>
#include <fstream>

#if defined(__GLIBC__)
#include <malloc.h>
#endif

namespace tbdr {

namespace {
/// VIRTIO_BALLOON_F_REPORTING: the balloon device takes free page reports (Virtio 1.2, 5.5.3).
constexpr std::size_t kFreePageReportingBit = 5;

// glibc's allocator settings for a simulation run. A 1080p frame touches a few
// hundred MB in vectors that grow, are freed and are allocated again per pass and per render;
// with glibc's defaults each block over 128 KiB is a fresh mmap whose pages the kernel maps and
// zeroes again every time, and freed memory goes back to the kernel: 23,000-84,000 page faults
// per 1080p run and a fifth of its CPU time in the kernel on the machines measured. Blocks up to
// 32 MiB (glibc's largest mmap threshold) come from the heap and are kept for the next pass, and
// the heap is trimmed only past 256 MiB free, so a page is faulted in once per run; larger blocks
// (whole-frame arrays) are mapped and unmapped as before, so a run's peak stays that of its
// largest pass.
//
// Transparent huge pages for malloc's blocks (where the kernel grants them on request): 2 MiB
// pages, 512 times fewer faults and TLB misses over whole-frame arrays. Measured side by side on
// 2026-12-05 (kernel 6.18, 1 thread, atrium:3 1080p, 1024 lights, deferred with images): 82,100
// -> 1,200-2,000 page faults, 3.1-4.1 -> 2.8 user s, the study 36.9-38.6 -> 31.3-33.5 s wall.
// Not on a virtual machine whose host takes freed memory back (free page reporting): there every
// fresh huge page is backed again by the host (2.9 ms per 2 MiB measured 2026-12-06; 1 ms on the
// one measured until 2026-12-03), and the same run spent 0.56-0.78 s in the kernel with them
// against 0.14 s without, the study 30.4 against 28.4 s (host_reports_free_pages).
// TBDRSIM_HUGE_PAGES=1 or 0 decides instead (docs/performance-notes.md, "The allocator"). Both
// settings: malloc_tunables (host_speed.hpp).

/// Set in the environment of the re-executed process, so it runs once (and its children, which
/// inherit GLIBC_TUNABLES, do not re-execute either).
constexpr const char* kTunedMarker = "TBDRSIM_MALLOC_TUNED";

}  // namespace

// The heap's thresholds are set in this process (mallopt). Huge pages only glibc's tunables can
// ask for, and glibc reads those only at process start: then this program is re-executed once
// with them all in GLIBC_TUNABLES (about 2 ms per run, measured 2026-12-06, which a run without
// huge pages no longer pays). A user's own GLIBC_TUNABLES is respected as it is; without /proc
// (exec fails) the run goes on with the thresholds alone. Sanitizer builds have their own
// allocator and skip this, and so does a process with a preloaded library (LD_PRELOAD:
// valgrind, heaptrack, a profiler), which the tool under which it runs may not follow into a new
// program.
void tune_allocator(char** argv) {
#if defined(__GLIBC__) && !defined(__SANITIZE_ADDRESS__)
  if (std::getenv("GLIBC_TUNABLES") != nullptr || std::getenv(kTunedMarker) != nullptr) return;
  if (const char* preload = std::getenv("LD_PRELOAD"); preload != nullptr && *preload != '\0') return;
  (void)set_heap_thresholds();  // (refused: glibc's defaults, slower, the same results)
  if (!huge_pages_wanted()) return;
  const std::string tunables = malloc_tunables();
  if (setenv("GLIBC_TUNABLES", tunables.c_str(), 1) != 0 || setenv(kTunedMarker, "1", 1) != 0) return;
  execv("/proc/self/exe", argv);
  unsetenv("GLIBC_TUNABLES");  // exec failed: run here, with the thresholds only
  unsetenv(kTunedMarker);
#else
  (void)argv;
#endif
}

// Each balloon device listed there has a `features` file: one '0' or '1' per feature bit, bit 0
// first (Linux's virtio sysfs attribute).
bool host_reports_free_pages(const std::string& balloon_devices) {
  namespace fs = std::filesystem;
  std::error_code ec;
  for (fs::directory_iterator it(balloon_devices, ec), end; !ec && it != end; it.increment(ec)) {
    std::ifstream f(it->path() / "features");
    std::string bits;
    if (f && std::getline(f, bits) && bits.size() > kFreePageReportingBit && bits[kFreePageReportingBit] == '1') return true;
  }
  return false;
}

bool huge_pages_wanted() {
  const char* choice = std::getenv(kHugePagesVariable);
  const std::string c = choice != nullptr ? choice : "";
  return c == "1" || (c != "0" && !host_reports_free_pages());
}

std::string malloc_tunables() {
  return std::string(kMallocTunables) + (huge_pages_wanted() ? std::string(":") + kHugePageTunable : std::string());
}

bool set_heap_thresholds() {
#if defined(__GLIBC__)
  return mallopt(M_MMAP_THRESHOLD, kMmapThresholdBytes) == 1 && mallopt(M_TRIM_THRESHOLD, kTrimThresholdBytes) == 1;
#else
  return false;
#endif
}

HostSpeedFacts host_speed_facts() { return {allocator_huge_pages(), host_reports_free_pages()}; }

}  // namespace tbdr
