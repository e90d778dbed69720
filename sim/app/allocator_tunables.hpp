#pragma once
// The glibc allocator settings tbdrsim runs with: `main` (sim/app/main.cpp) re-executes the
// program once with them in GLIBC_TUNABLES; a run records which it had (run_driver.cpp). Host
// speed only: no figure depends on them. Why each, with measurements: main.cpp and
// docs/architecture.md, "The allocator".
#include <cstdlib>
#include <string>

namespace tbdr {

/// The heap's thresholds: blocks up to 32 MiB from the heap, trimmed only past 256 MiB free.
inline constexpr const char* kMallocTunables = "glibc.malloc.mmap_threshold=33554432:glibc.malloc.trim_threshold=268435456";
/// The tunable asking for transparent huge pages for malloc's blocks.
inline constexpr const char* kHugePageTunable = "glibc.malloc.hugetlb=1";
/// The environment variable that leaves huge pages out ("0").
inline constexpr const char* kHugePagesVariable = "TBDRSIM_HUGE_PAGES";

/// The GLIBC_TUNABLES tbdrsim starts with: the heap's thresholds, and huge pages unless the
/// environment says TBDRSIM_HUGE_PAGES=0.
inline std::string malloc_tunables() {
  const char* huge = std::getenv(kHugePagesVariable);
  const bool without = huge != nullptr && std::string(huge) == "0";
  return std::string(kMallocTunables) + (without ? "" : std::string(":") + kHugePageTunable);
}

/// Whether this process's allocator asks for huge pages (its GLIBC_TUNABLES has them).
inline bool allocator_huge_pages() {
  const char* tunables = std::getenv("GLIBC_TUNABLES");
  return tunables != nullptr && std::string(tunables).find(kHugePageTunable) != std::string::npos;
}

}  // namespace tbdr
