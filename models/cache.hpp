#pragma once
// A set-associative cache with true LRU replacement, write-back and write-allocate (optionally
// write-no-allocate, and per-access streaming that never allocates). It models tags only: it
// answers hit or miss, installs lines, and reports the dirty line a fill evicted so the caller can
// write it back to the next level. Timing lives in MemorySystem; this class is the state machine
// and its statistics, shared by the timed and the functional paths.
//
// Hot path: tags, LRU stamps, dirty bits and classes are flat arrays indexed by
// set * ways + way (a "slot"); a lookup scans one set's `ways` tags. True LRU keeps one 64-bit
// access stamp per line and evicts the smallest (invalid lines have stamp 0, so they go first).
// An empty slot is all zero bytes in every array (tags and fills are stored complemented), so the
// arrays are ZeroedArrays: a large cache takes memory for the sets a run touches, not its capacity.
#include <algorithm>
#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "models/hw_config.hpp"
#include "trace/traffic.hpp"
#include "kernel/stats.hpp"
#include "kernel/zeroed_array.hpp"

namespace tbdr {

/// Whether a missing line is installed by this access.
enum class Allocation : std::uint8_t {
  Allocate,    ///< normal: read misses allocate; write misses allocate if the cache is write-allocate
  NoAllocate,  ///< streaming: hits are served (and writes make the line dirty), misses bypass
};

/// What one cache access did.
struct CacheAccess {
  static constexpr std::uint32_t kNoSlot = UINT32_MAX;
  bool hit = false;
  bool allocated = false;        ///< a miss installed the line
  bool writeback = false;        ///< the installed line evicted a dirty line (victim_addr, victim_cls)
  DramClass victim_cls = DramClass::Other;
  std::uint64_t victim_addr = 0;  ///< first byte of the evicted dirty line
  std::uint32_t slot = kNoSlot;   ///< slot of the line hit or installed (kNoSlot on a bypassed miss)
};

// Declared once: X(type, member = stored name, unit, Sum | Gauge, description).
#define TBDR_CACHE_CLASS_STATS(X) \
  X(Counter, read_hits, "accesses", Sum, "Read accesses of this class that hit") \
  X(Counter, read_misses, "accesses", Sum, "Read accesses of this class that missed") \
  X(Counter, write_hits, "accesses", Sum, "Write accesses of this class that hit") \
  X(Counter, write_misses, "accesses", Sum, "Write accesses of this class that missed")
/// Per-traffic-class hit and miss counts of one cache.
struct CacheClassStats {
  TBDR_STATS(TBDR_CACHE_CLASS_STATS)
};

// Declared once: X(type, member = stored name, unit, Sum | Gauge, description).
#define TBDR_CACHE_STATS(X) \
  X(Counter, reads, "accesses", Sum, "Read accesses") \
  X(Counter, writes, "accesses", Sum, "Write accesses") \
  X(Counter, read_hits, "accesses", Sum, "Read accesses that hit") \
  X(Counter, read_misses, "accesses", Sum, "Read accesses that missed") \
  X(Counter, write_hits, "accesses", Sum, "Write accesses that hit") \
  X(Counter, write_misses, "accesses", Sum, "Write accesses that missed") \
  X(Counter, bypasses, "accesses", Sum, "Misses that did not allocate (streaming or write-no-allocate)") \
  X(Counter, fills, "lines", Sum, "Lines installed by read misses (fetched from the next level)") \
  X(Counter, write_allocations, "lines", Sum, "Lines installed by write misses without a fetch") \
  X(Counter, clean_evictions, "lines", Sum, "Valid clean lines replaced") \
  X(Counter, dirty_evictions, "lines", Sum, "Dirty lines replaced (each one written back)") \
  X(Counter, flush_writebacks, "lines", Sum, "Dirty lines written back by flushes") \
  X(Counter, read_bytes, "bytes", Sum, "Bytes read by requesters (hits and misses)") \
  X(Counter, write_bytes, "bytes", Sum, "Bytes written by requesters (hits and misses)") \
  X(Counter, fill_bytes, "bytes", Sum, "Bytes installed by read-miss fills") \
  X(Counter, writeback_bytes, "bytes", Sum, "Bytes of dirty lines written back (evictions and flushes)") \
  X(Accumulator, hit_rate, "ratio", Derived, "Hits / accesses (derived at collection)") \
  X(Accumulator, energy_pj, "pJ", Sum, "SRAM energy: (read + write + fill + writeback bytes) x pJ/byte")
/// Statistics of one cache.
struct CacheStats {
  TBDR_STATS(TBDR_CACHE_STATS)
};

/// A set-associative, true-LRU, write-back cache (tags only).
/// A cache's statistics at one moment (Cache::snapshot), with the scope its rows take.
struct CacheSnapshot {
  std::string scope;  ///< "mem/cache.texture", ...; a class's rows: scope + ".class." + class
  CacheStats stats;
  std::array<CacheClassStats, kDramClassCount> classes;
};

class Cache {
 public:
  /// Geometry from `p` (line_bytes a power of two, size a multiple of ways x line; otherwise
  /// std::invalid_argument). `scope` names the statistics ("mem/cache.texture"); `pj_per_byte` is
  /// the SRAM access energy used for the energy statistic.
  Cache(std::string scope, const CacheParams& p, double pj_per_byte = 0.0, bool write_allocate = true);
  Cache(const Cache&) = delete;
  Cache& operator=(const Cache&) = delete;

  /// One access of `bytes` (within one line) at `addr`; updates LRU, dirty bits and statistics.
  CacheAccess access(std::uint64_t addr, std::uint32_t bytes, bool is_write, DramClass cls,
                     Allocation alloc = Allocation::Allocate);
  /// Counts `lines` read hits (each within one line), `bytes` in all, of class `cls` that the
  /// caller serves from lines it knows are present (a tile re-reading data it requested once):
  /// statistics and SRAM energy as access() would count them, without a lookup (no LRU or
  /// content change).
  void count_read_hits(std::uint64_t lines, std::uint64_t bytes, DramClass cls);
  /// True if the line holding `addr` is present; changes nothing.
  bool probe(std::uint64_t addr) const;
  /// True if the line holding `addr` is present and dirty; changes nothing.
  bool is_dirty(std::uint64_t addr) const;
  /// Writes back every dirty line: calls fn(line_addr, cls) for each (in slot order) and marks it
  /// clean. Returns the number of lines written back.
  template <class Fn>
  std::uint64_t flush(Fn&& fn);
  /// Drops every line (dirty data is discarded: call flush first to keep it).
  void invalidate_all();

  /// Per-line user tags for the timing model: the pending fill of a line being fetched whose
  /// arrival is not known yet (kNoFill when none), and the tick (ps) its data arrives once it is
  /// (0 when it has always been there). Both reset whenever the slot is (re)allocated.
  static constexpr std::uint32_t kNoFill = UINT32_MAX;
  std::uint32_t fill_of(std::uint32_t slot) const { return ~fill_[slot]; }
  void set_fill(std::uint32_t slot, std::uint32_t fill) { fill_[slot] = ~fill; }
  std::int64_t arrival_ps(std::uint32_t slot) const { return arrival_ps_[slot]; }
  void set_arrival_ps(std::uint32_t slot, std::int64_t ps) { arrival_ps_[slot] = ps; }
  /// Line address (first byte) held by a slot.
  std::uint64_t slot_addr(std::uint32_t slot) const { return ~tags_[slot] << line_shift_; }

  std::uint64_t line_bytes() const { return line_bytes_; }
  std::uint64_t line_addr(std::uint64_t addr) const { return addr & ~(line_bytes_ - 1); }
  std::uint32_t sets() const { return sets_; }
  std::uint32_t ways() const { return ways_; }
  std::uint64_t size_bytes() const { return static_cast<std::uint64_t>(sets_) * ways_ * line_bytes_; }
  std::int64_t hit_latency_cycles() const { return hit_latency_cycles_; }
  bool write_allocate() const { return write_allocate_; }

  CacheStats& stats() { return stats_; }
  const CacheStats& stats() const { return stats_; }
  const CacheClassStats& class_stats(DramClass c) const { return class_stats_[static_cast<std::size_t>(c)]; }
  /// SRAM energy so far: (read + write + fill + writeback bytes) x pJ/byte.
  double energy_pj() const;
  /// Sets the derived statistics (hit rate, energy).
  void update_derived_stats();
  /// Its statistics now, derived ones updated first: the main set and one per traffic class.
  CacheSnapshot snapshot();
  /// Zeroes the statistics (not the contents).
  void reset_stats();

 private:
  /// The stored tag of an empty slot: tags are stored complemented (~line), so an empty slot is
  /// zero bytes like every other array's (a line address of all ones is beyond any address).
  static constexpr std::uint64_t kInvalid = 0;
  /// access() for a cache of W ways (0: any number, read from ways_).
  template <std::uint32_t W>
  CacheAccess access_in(std::uint64_t addr, std::uint32_t bytes, bool is_write, DramClass cls, Allocation alloc);
  std::uint32_t set_of(std::uint64_t line) const {
    return static_cast<std::uint32_t>(sets_pow2_ ? (line & set_mask_) : (line % sets_));
  }

  std::uint64_t line_bytes_;
  unsigned line_shift_;
  std::uint32_t ways_;
  std::uint32_t sets_;
  std::uint64_t set_mask_;  // sets_ - 1 (used when sets_pow2_)
  bool sets_pow2_;
  std::int64_t hit_latency_cycles_;
  double pj_per_byte_;
  bool write_allocate_;
  std::uint64_t clock_ = 0;  // LRU stamp source: incremented per access

  ZeroedArray<std::uint64_t> tags_;    // ~line address (~(addr >> line_shift_)), kInvalid (0) when empty
  ZeroedArray<std::uint64_t> stamps_;  // last access stamp, 0 when empty
  ZeroedArray<std::uint8_t> dirty_;
  ZeroedArray<DramClass> cls_;         // class of the line's data (allocating access or last writer); any when empty
  ZeroedArray<std::uint32_t> fill_;    // ~ the timing model's pending fill id (0: kNoFill)
  ZeroedArray<std::int64_t> arrival_ps_;  // timing model's data arrival tick (ps)
  /// Slots per chunk of used_: a 4 KiB page of tags. flush() reads the chunks a line was ever
  /// installed in, not every slot: reading a page of a ZeroedArray can take memory too (it does in
  /// some sandboxes), and flushes come at the end of every pass.
  static constexpr std::uint32_t kSlotsPerChunk = 512;
  std::vector<std::uint8_t> used_;     // 1: a line was installed in the chunk since the last invalidate_all

  std::string scope_;  // statistics scope, e.g. "mem/cache.texture"
  CacheStats stats_;
  std::array<CacheClassStats, kDramClassCount> class_stats_;
};

template <class Fn>
std::uint64_t Cache::flush(Fn&& fn) {
  std::uint64_t n = 0;
  const auto slots = static_cast<std::uint32_t>(tags_.size());
  for (std::uint32_t chunk = 0; chunk < used_.size(); ++chunk) {
    if (!used_[chunk]) continue;
    const std::uint32_t end = std::min(slots, (chunk + 1) * kSlotsPerChunk);
    for (std::uint32_t s = chunk * kSlotsPerChunk; s < end; ++s) {
      if (tags_[s] == kInvalid || !dirty_[s]) continue;
      dirty_[s] = 0;
      ++n;
      ++stats_.flush_writebacks;
      stats_.writeback_bytes += line_bytes_;
      fn(~tags_[s] << line_shift_, cls_[s]);
    }
  }
  return n;
}

}  // namespace tbdr
