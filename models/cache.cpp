#include "models/cache.hpp"

#include <algorithm>
#include <bit>
#include <stdexcept>

#include "kernel/bits.hpp"

namespace tbdr {

Cache::Cache(std::string scope, const CacheParams& p, double pj_per_byte, bool write_allocate)
    : pj_per_byte_(pj_per_byte), write_allocate_(write_allocate), scope_(scope) {
  if (p.line_bytes <= 0 || !is_pow2(static_cast<std::uint64_t>(p.line_bytes))) {
    throw std::invalid_argument("cache '" + scope + "': line_bytes must be a power of two");
  }
  if (p.ways <= 0 || p.size_bytes <= 0 || p.size_bytes % (p.ways * p.line_bytes) != 0) {
    throw std::invalid_argument("cache '" + scope + "': size_bytes must be a positive multiple of ways x line_bytes");
  }
  if (p.hit_latency_cycles < 0) throw std::invalid_argument("cache '" + scope + "': negative hit latency");
  line_bytes_ = static_cast<std::uint64_t>(p.line_bytes);
  line_shift_ = log2_exact(line_bytes_);
  ways_ = static_cast<std::uint32_t>(p.ways);
  const std::int64_t sets = p.size_bytes / (p.ways * p.line_bytes);
  if (sets > static_cast<std::int64_t>(UINT32_MAX / ways_)) throw std::invalid_argument("cache '" + scope + "': too many lines");
  sets_ = static_cast<std::uint32_t>(sets);
  sets_pow2_ = is_pow2(sets_);
  set_mask_ = sets_ - 1;
  hit_latency_cycles_ = p.hit_latency_cycles;
  const std::size_t lines = static_cast<std::size_t>(sets_) * ways_;
  // All empty: zero bytes (kInvalid tags, no fill), pages mapped as sets are first written.
  tags_ = ZeroedArray<std::uint64_t>(lines);
  stamps_ = ZeroedArray<std::uint64_t>(lines);
  dirty_ = ZeroedArray<std::uint8_t>(lines);
  cls_ = ZeroedArray<DramClass>(lines);
  fill_ = ZeroedArray<std::uint32_t>(lines);
  arrival_ps_ = ZeroedArray<std::int64_t>(lines);
  used_.assign((lines + kSlotsPerChunk - 1) / kSlotsPerChunk, 0);
}

namespace {

/// The way of a set (its `ways` stored tags) holding stored tag `line` (~ the line address), or
/// `ways` when none does. W: the ways known
/// when compiled (the configurations' 4, 8 and 16: a fixed count the compiler unrolls into
/// compares without a branch per way), 0: `ways` read at run time.
template <std::uint32_t W>
inline std::uint32_t way_holding(const std::uint64_t* tags, std::uint64_t line, std::uint32_t ways) {
  if constexpr (W == 0) {
    for (std::uint32_t w = 0; w < ways; ++w) {
      if (tags[w] == line) return w;
    }
    return ways;
  } else {
    std::uint32_t found = 0;  // bit w: way w holds the line (at most one does)
    for (std::uint32_t w = 0; w < W; ++w) found |= static_cast<std::uint32_t>(tags[w] == line) << w;
    return found != 0 ? static_cast<std::uint32_t>(std::countr_zero(found)) : W;
  }
}

/// The least recently used way of a set (its `ways` stamps): the first of the smallest stamps
/// (empty ways have stamp 0 and are taken first). W as for way_holding.
template <std::uint32_t W>
inline std::uint32_t least_recent_way(const std::uint64_t* stamps, std::uint32_t ways) {
  const std::uint32_t n = W == 0 ? ways : W;
  std::uint32_t lru = 0;
  std::uint64_t oldest = stamps[0];
  for (std::uint32_t w = 1; w < n; ++w) {
    const bool older = stamps[w] < oldest;  // strictly: the first of equals stays
    lru = older ? w : lru;
    oldest = older ? stamps[w] : oldest;
  }
  return lru;
}

}  // namespace

CacheAccess Cache::access(std::uint64_t addr, std::uint32_t bytes, bool is_write, DramClass cls, Allocation alloc) {
  switch (ways_) {
    case 4: return access_in<4>(addr, bytes, is_write, cls, alloc);
    case 8: return access_in<8>(addr, bytes, is_write, cls, alloc);
    case 16: return access_in<16>(addr, bytes, is_write, cls, alloc);
    default: return access_in<0>(addr, bytes, is_write, cls, alloc);
  }
}

template <std::uint32_t W>
CacheAccess Cache::access_in(std::uint64_t addr, std::uint32_t bytes, bool is_write, DramClass cls, Allocation alloc) {
  const std::uint64_t line = addr >> line_shift_;
  const std::uint32_t base = set_of(line) * ways_;
  const std::uint64_t* tags = tags_.data() + base;
  const std::uint64_t tag = ~line;  // as stored
  CacheClassStats& cs = class_stats_[static_cast<std::size_t>(cls)];
  const std::uint64_t stamp = ++clock_;
  CacheAccess r;

  if (is_write) {
    ++stats_.writes;
    stats_.write_bytes += bytes;
  } else {
    ++stats_.reads;
    stats_.read_bytes += bytes;
  }

  // The hit, if any (a hit does not read the ways' stamps).
  if (const std::uint32_t w = way_holding<W>(tags, tag, ways_); w != ways_) {
    const std::uint32_t slot = base + w;
    stamps_[slot] = stamp;
    if (is_write) {
      dirty_[slot] = 1;
      cls_[slot] = cls;
      ++stats_.write_hits;
      ++cs.write_hits;
    } else {
      ++stats_.read_hits;
      ++cs.read_hits;
    }
    r.hit = true;
    r.slot = slot;
    return r;
  }
  // A miss: the least recently used way, the first of equals (empty ways have stamp 0 and are
  // taken first).
  const std::uint32_t lru = least_recent_way<W>(stamps_.data() + base, ways_);

  if (is_write) {
    ++stats_.write_misses;
    ++cs.write_misses;
  } else {
    ++stats_.read_misses;
    ++cs.read_misses;
  }
  if (alloc == Allocation::NoAllocate || (is_write && !write_allocate_)) {
    ++stats_.bypasses;
    return r;
  }
  const std::uint32_t victim = base + lru;
  if (tags_[victim] != kInvalid) {
    if (dirty_[victim]) {
      r.writeback = true;
      r.victim_addr = ~tags_[victim] << line_shift_;
      r.victim_cls = cls_[victim];
      ++stats_.dirty_evictions;
      stats_.writeback_bytes += line_bytes_;
    } else {
      ++stats_.clean_evictions;
    }
  }
  tags_[victim] = tag;
  used_[victim / kSlotsPerChunk] = 1;
  stamps_[victim] = stamp;
  dirty_[victim] = is_write ? 1 : 0;
  cls_[victim] = cls;
  fill_[victim] = ~kNoFill;
  arrival_ps_[victim] = 0;
  if (is_write) {
    ++stats_.write_allocations;
  } else {
    ++stats_.fills;
    stats_.fill_bytes += line_bytes_;
  }
  r.allocated = true;
  r.slot = victim;
  return r;
}

bool Cache::probe(std::uint64_t addr) const {
  const std::uint64_t line = addr >> line_shift_;
  const std::uint32_t base = set_of(line) * ways_;
  return way_holding<0>(tags_.data() + base, ~line, ways_) != ways_;
}

bool Cache::is_dirty(std::uint64_t addr) const {
  const std::uint64_t line = addr >> line_shift_;
  const std::uint32_t base = set_of(line) * ways_;
  const std::uint32_t w = way_holding<0>(tags_.data() + base, ~line, ways_);
  return w != ways_ && dirty_[base + w] != 0;
}

void Cache::invalidate_all() {
  // Empty is zero bytes (kInvalid tags, no fill); mapped arrays give their pages back.
  tags_.clear();
  stamps_.clear();
  dirty_.clear();
  cls_.clear();
  fill_.clear();
  arrival_ps_.clear();
  std::fill(used_.begin(), used_.end(), 0);
}

void Cache::update_derived_stats() {
  const std::uint64_t accesses = stats_.reads.value() + stats_.writes.value();
  const std::uint64_t hits = stats_.read_hits.value() + stats_.write_hits.value();
  stats_.hit_rate.set(accesses == 0 ? 0.0 : static_cast<double>(hits) / static_cast<double>(accesses));
  stats_.energy_pj.set(energy_pj());
}

void Cache::count_read_hits(std::uint64_t lines, std::uint64_t bytes, DramClass cls) {
  stats_.reads += lines;
  stats_.read_bytes += bytes;
  stats_.read_hits += lines;
  class_stats_[static_cast<std::size_t>(cls)].read_hits += lines;
}

double Cache::energy_pj() const {
  const std::uint64_t bytes = stats_.read_bytes.value() + stats_.write_bytes.value() + stats_.fill_bytes.value() +
                              stats_.writeback_bytes.value();
  return static_cast<double>(bytes) * pj_per_byte_;
}

CacheSnapshot Cache::snapshot() {
  update_derived_stats();
  return {scope_, stats_, class_stats_};
}

void Cache::reset_stats() {
  stats_ = {};
  class_stats_ = {};
}

}  // namespace tbdr
