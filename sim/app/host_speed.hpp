#pragma once
// Host-speed machinery, in one place: what tbdrsim does to make the host run it faster. None of it
// changes a figure (tests/test_speed_equivalence.cpp, tests/test_threads.cpp); it sits outside the
// simulation's path, and each choice's measurements are in docs/performance-notes.md ("The
// allocator", "The caller and the timing model on different CPUs").
//  - The allocator: `main` calls tune_allocator first. glibc's heap thresholds are set in the
//    running process (mallopt); where huge pages are wanted, which only GLIBC_TUNABLES can ask
//    for, the program is re-executed once with them all in GLIBC_TUNABLES.
//  - Thread placement: while a pipelined frame runs (`--threads N`, N > 1), run_one keeps the
//    caller's thread and the timing model's on different CPUs (CriticalThreadPlacement,
//    kernel/cpu_placement.hpp, which this header brings in).
//  - What a run records about them: host_speed_facts, stored with the run's host figures
//    (HostRunStats, app/run_stats.hpp), since host timings of runs with and without differ.
#include <cstdlib>
#include <string>

#include "kernel/cpu_placement.hpp"

namespace tbdr {

/// The heap's thresholds: blocks up to 32 MiB (glibc's largest mmap threshold on 64-bit hosts)
/// from the heap, trimmed only past 256 MiB free; as mallopt values and as tunables.
inline constexpr int kMmapThresholdBytes = 32 << 20;
inline constexpr int kTrimThresholdBytes = 256 << 20;
inline constexpr const char* kMallocTunables = "glibc.malloc.mmap_threshold=33554432:glibc.malloc.trim_threshold=268435456";
static_assert(kMmapThresholdBytes == 33554432 && kTrimThresholdBytes == 268435456, "kMallocTunables says the same");
/// The tunable asking for transparent huge pages for malloc's blocks.
inline constexpr const char* kHugePageTunable = "glibc.malloc.hugetlb=1";
/// The environment variable that decides huge pages: "0" leaves them out, "1" asks for them,
/// unset (or anything else): asked for unless the host takes freed memory back
/// (host_reports_free_pages).
inline constexpr const char* kHugePagesVariable = "TBDRSIM_HUGE_PAGES";

/// Whether this machine is a virtual machine that hands the memory it frees back to its host
/// (virtio-balloon free page reporting, VIRTIO_BALLOON_F_REPORTING: Linux reports free blocks of
/// 2 MiB and more and the host discards them). There a transparent huge page comes from such a
/// block, which the host must back again page by page on its first touch: measured 2026-12-06 on
/// a Firecracker VM (kernel 6.18, "Free page reporting enabled"), faulting in 18 GiB of huge pages
/// took 2.9 ms per 2 MiB, and a deferred run with images (1 thread, atrium:3 1080p, 1024 lights)
/// spent 0.56-0.78 s in the kernel with huge pages against 0.14-0.17 s without (small pages come
/// back from the guest's own recently freed ones); the study took 30.4 s against 28.4 s. Reads
/// the balloon device's feature bits in sysfs; false where there is none (bare metal, other
/// hypervisors). `balloon_devices`: where Linux lists the balloon devices (tests point it at a
/// folder of their own).
bool host_reports_free_pages(const std::string& balloon_devices = "/sys/bus/virtio/drivers/virtio_balloon");

/// Whether tbdrsim asks for huge pages: TBDRSIM_HUGE_PAGES=1, or unset (or anything but "0")
/// where the host does not take freed memory back.
bool huge_pages_wanted();

/// The GLIBC_TUNABLES tbdrsim starts with when it wants huge pages: the heap's thresholds and
/// huge pages (without huge pages, only the thresholds).
std::string malloc_tunables();

/// Sets the heap's thresholds in the running process (mallopt: the same settings as the
/// tunables, without starting the program again); false where the allocator refused them or is
/// not glibc's.
bool set_heap_thresholds();

/// Whether this process's allocator asks for huge pages (its GLIBC_TUNABLES has them).
inline bool allocator_huge_pages() {
  const char* tunables = std::getenv("GLIBC_TUNABLES");
  return tunables != nullptr && std::string(tunables).find(kHugePageTunable) != std::string::npos;
}

/// Sets glibc's allocator up for a simulation run, first thing in `main` (`argv`: main's, for the
/// re-execution). May re-execute the program; returns when this process is the one to run.
void tune_allocator(char** argv);

/// Host facts a run records beside its host timings.
struct HostSpeedFacts {
  bool allocator_huge_pages = false;  ///< this process's allocator asks for huge pages
  bool host_free_page_reporting = false;  ///< the host takes freed memory back (host_reports_free_pages)
};
/// This process's and this host's HostSpeedFacts.
HostSpeedFacts host_speed_facts();

}  // namespace tbdr
