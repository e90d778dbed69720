#pragma once
// The simulated physical address space: every buffer the GPU touches (vertex and index buffers,
// textures, attachments, the parameter buffer, light lists, compute buffers) is given a named,
// page-aligned region with a DRAM traffic class. Allocation is a bump allocator, so the same
// allocation order always gives the same addresses (runs are reproducible and addresses can be
// compared across techniques). Addresses only matter to the timing model (cache sets, DRAM
// channel/bank/row); no data is stored.
#include <cstdint>
#include <string>
#include <string_view>
#include <unordered_map>
#include <vector>

#include "trace/traffic.hpp"

namespace tbdr {

/// One allocated region of the simulated address space.
struct AddressRegion {
  std::string name;
  std::uint64_t base = 0;        ///< first byte, a multiple of the alignment it was allocated with
  std::uint64_t size_bytes = 0;  ///< bytes requested
  std::uint64_t reserved_bytes = 0;  ///< bytes reserved (size rounded up to whole pages, at least one)
  DramClass cls = DramClass::Other;

  std::uint64_t end() const { return base + size_bytes; }
  bool contains(std::uint64_t addr) const { return addr >= base && addr < base + reserved_bytes; }
};

/// A deterministic bump allocator of named, page-aligned regions, each with a traffic class.
class AddressSpace {
 public:
  /// 4 KiB pages: the GPU MMU's page (and the parameter manager's, ROGUE_PM_PAGE_SIZE in Linux
  /// drivers/gpu/drm/imagination/pvr_rogue_fwif_client.h), so regions start where a driver's would.
  static constexpr std::uint64_t kDefaultPageBytes = 4096;

  /// `page_bytes` (a power of two) is the allocation granule; the first region starts at
  /// `base` rounded up to a page, and address 0 is never handed out (base defaults to one page).
  explicit AddressSpace(std::uint64_t page_bytes = kDefaultPageBytes, std::uint64_t base = kDefaultPageBytes);

  /// Where the high range starts (allocate_high): 2^40 bytes (1 TiB), above any frame's other
  /// regions (its largest, 8K framebuffers and parameter buffers, take a few GiB; allocate
  /// refuses to reach it). Addresses only pick cache sets and DRAM channels, banks and rows, so
  /// a second range costs nothing but lets two sequences of allocations each keep their order.
  static constexpr std::uint64_t kHighBase = std::uint64_t{1} << 40;

  /// Allocates `size_bytes` (rounded up to whole pages, at least one page) aligned to
  /// max(page, align_bytes) (align_bytes: 0 or a power of two). Returns the base address.
  /// Throws std::invalid_argument on an empty or duplicate name or a bad alignment, and
  /// std::overflow_error when the region would reach the high range.
  std::uint64_t allocate(std::string name, std::uint64_t size_bytes, DramClass cls, std::uint64_t align_bytes = 0);
  /// As allocate, in the high range from kHighBase up: regions whose order of allocation is
  /// not the low range's (FrameAddressMap: the commands' buffer areas, placed as each command's
  /// first fragment job starts, while the low range's regions are placed as the timing model
  /// takes the commands), so that neither range's layout depends on how the two interleave.
  std::uint64_t allocate_high(std::string name, std::uint64_t size_bytes, DramClass cls);

  /// A later frame of a sequence's region: the region `name` (or `name#2`, `name#3`, ... after it)
  /// when one exists with at least `size_bytes` reserved and class `cls`, as an application
  /// allocates its render targets and buffers once and uses them every frame; else a new region
  /// (allocate, or allocate_high with `high`) under the first of those names not taken.
  std::uint64_t reuse_or_allocate(const std::string& name, std::uint64_t size_bytes, DramClass cls, bool high = false);

  /// The region with that name, or nullptr.
  const AddressRegion* find(std::string_view name) const;
  /// The region with that name; throws std::out_of_range when there is none.
  const AddressRegion& region(std::string_view name) const;
  /// Base address of a named region; throws std::out_of_range when there is none.
  std::uint64_t base_of(std::string_view name) const { return region(name).base; }
  /// The region whose reserved pages contain `addr`, or nullptr (binary search).
  const AddressRegion* region_at(std::uint64_t addr) const;
  /// Traffic class of the region containing `addr`; DramClass::Other outside every region.
  DramClass class_at(std::uint64_t addr) const;

  /// Regions in address order (each range's in allocation order, the low range's first).
  const std::vector<AddressRegion>& regions() const { return regions_; }
  std::uint64_t page_bytes() const { return page_bytes_; }
  /// First address after the low range's last region (its next allocation starts at or after it).
  std::uint64_t top() const { return top_; }
  /// Sum of reserved bytes of every region.
  std::uint64_t reserved_bytes() const { return reserved_; }
  /// Forgets every region; the next allocation starts at the base again.
  void clear();
  /// Takes the regions of another address space of the same page size (its regions(), as a
  /// sampled window takes the layout the sequence's first frames made: app/sampled_run.hpp), as
  /// if allocated here in the same order: the same names at the same addresses, each range's
  /// next allocation after its last. Throws std::logic_error unless this space is empty.
  void adopt(const std::vector<AddressRegion>& regions);

 private:
  /// Allocates from `cursor` (top_ or high_top_), below `limit`.
  std::uint64_t place(std::string name, std::uint64_t size_bytes, DramClass cls, std::uint64_t align_bytes, std::uint64_t& cursor,
                      std::uint64_t limit);

  std::uint64_t page_bytes_;
  std::uint64_t base_;
  std::uint64_t top_;
  std::uint64_t high_top_ = kHighBase;
  std::uint64_t reserved_ = 0;
  std::vector<AddressRegion> regions_;                     ///< by base
  std::unordered_map<std::string, std::uint64_t> by_name_;  ///< base of each region
};

}  // namespace tbdr
