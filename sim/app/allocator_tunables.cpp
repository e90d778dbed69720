#include "app/allocator_tunables.hpp"

#include <filesystem>
#include <fstream>

#if defined(__GLIBC__)
#include <malloc.h>
#endif

namespace tbdr {

namespace {
/// VIRTIO_BALLOON_F_REPORTING: the balloon device takes free page reports (Virtio 1.2, 5.5.3).
constexpr std::size_t kFreePageReportingBit = 5;
}  // namespace

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

}  // namespace tbdr
