// Tests for the memory system models: the address space (models/address_space), the
// set-associative cache (models/cache), the DRAM controller (models/dram) and the facade that
// ties them together (models/memory_system). Expected figures are worked out by hand in the
// comments; the DRAM tests use a 1 GHz DRAM clock so that every timing parameter is a whole
// number of nanoseconds and of cycles.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <ctime>
#include <cstdint>
#include <deque>
#include <functional>
#include <iostream>
#include <memory>
#include <utility>
#include <random>
#include <string>
#include <vector>

#include "app/stat_rows.hpp"
#include "models/address_space.hpp"
#include "models/cache.hpp"
#include "models/dram.hpp"
#include "models/hw_config.hpp"
#include "models/memory_system.hpp"
#include "kernel/errors.hpp"
#include "kernel/event_queue.hpp"
#include "kernel/time.hpp"

namespace tbdr {
namespace {

// ---------------------------------------------------------------------------------------------
// Helpers

/// The declared defaults with DRAM timing in whole nanoseconds at a 1 GHz DRAM clock and a 1 GHz
/// core: tRCD 18, tRP 18, RL 15, tRAS 42, tWR 15, tRRD 10, tFAW 50, tWTR 10 cycles, tRTW 4 ns;
/// controller 30 ns each way; 2 channels of 6.4 GB/s (a synthetic 32-bit bus at 1.6 transfers per
/// 1 GHz clock: 1000 x 1.6 x 4 B), so a 64 B line occupies a channel's data bus for exactly 10 ns. Refresh is off (t_refi_ns=0) so that latencies are exact; the refresh tests
/// turn it on with tREFI 3900 and tRFC 130 ns (the LPDDR3 defaults).
/// `sets` (section.key=value, as --set) apply on top.
HwConfig test_config(const std::vector<std::string>& sets = {}) {
  std::vector<std::string> all = {"gpu.core_clock_mhz=1000", "dram.clock_mhz=1000", "dram.channels=2", "dram.banks=8",
                                  "dram.row_bytes=4096", "dram.burst_bytes=32", "dram.transfers_per_clock=1.6", "dram.bus_width_bits=32",
                                  "dram.t_rcd_ns=18", "dram.t_rp_ns=18", "dram.t_cl_ns=15", "dram.t_ras_ns=42",
                                  "dram.t_wr_ns=15", "dram.t_rrd_ns=10", "dram.t_faw_ns=50", "dram.t_wtr_ns=10",
                                  "dram.t_rtw_ns=4", "dram.t_refi_ns=0", "dram.t_rfc_ns=130",
                                  "dram.controller_latency_ns=30", "dram.read_queue_entries=32",
                                  "dram.write_queue_entries=32", "dram.address_mapping=row_bank_channel_column",
                                  // Power-down (on by default) off, as refresh: the latency arithmetic
                                  // below has no tXP; the power-down tests set it themselves.
                                  "dram.powerdown_after_ns=0"};
  all.insert(all.end(), sets.begin(), sets.end());  // the test's own settings win
  return resolve_config({}, all).hw;
}

constexpr std::int64_t kNs = 1000;  // ps

/// Feeds DRAM requests in order, retrying a refused one when the DRAM reports free space, and
/// records each request's completion tick. With `per_channel`, there is one in-order stream per
/// channel (a source with several independent streams, which a full channel does not block).
class DramFeeder {
 public:
  DramFeeder(Dram& dram, EventQueue& eq, bool per_channel = false)
      : dram_(dram), eq_(eq), per_channel_(per_channel), pending_(per_channel ? dram.channels() : 1) {
    dram_.set_space_callback([this](std::uint32_t) { pump(); });
  }
  /// Queues a request (sent in order within its stream).
  void add(std::uint64_t addr, std::uint32_t bytes, bool is_write, DramClass cls) {
    pending_[per_channel_ ? dram_.channel_of(addr) : 0].push_back({addr, bytes, is_write, cls, done_.size()});
    done_.push_back(Tick{-1});
  }
  void pump() {
    for (auto& q : pending_) {
      while (!q.empty()) {
        const Item& it = q.front();
        const std::size_t i = it.index;
        DramRequest r{it.addr, it.bytes, it.is_write, it.cls, [this, i] { done_[i] = eq_.now(); }};
        if (!dram_.enqueue(std::move(r))) {
          ++refused_;
          break;
        }
        q.pop_front();
      }
    }
  }
  const std::vector<Tick>& done() const { return done_; }
  Tick last_done() const {
    Tick t{0};
    for (Tick d : done_) t = std::max(t, d);
    return t;
  }
  std::uint64_t refused() const { return refused_; }
  bool all_done() const {
    for (Tick t : done_) {
      if (t.ps() < 0) return false;
    }
    for (const auto& q : pending_) {
      if (!q.empty()) return false;
    }
    return true;
  }

 private:
  struct Item {
    std::uint64_t addr;
    std::uint32_t bytes;
    bool is_write;
    DramClass cls;
    std::size_t index;
  };
  Dram& dram_;
  EventQueue& eq_;
  bool per_channel_;
  std::vector<std::deque<Item>> pending_;
  std::vector<Tick> done_;
  std::uint64_t refused_ = 0;
};

// ---------------------------------------------------------------------------------------------
// AddressSpace

TEST(AddressSpaceTest, PageAlignedBumpAllocation) {
  AddressSpace as;  // 4 KiB pages, first region at 4096
  EXPECT_EQ(as.allocate("vb", 100, DramClass::Vertices), 4096u);
  EXPECT_EQ(as.allocate("tex", 5000, DramClass::Textures), 8192u);      // 2 pages reserved
  EXPECT_EQ(as.allocate("pb", 0, DramClass::ParameterBuffer), 16384u);  // empty still gets a page
  EXPECT_EQ(as.allocate("color", 64, DramClass::Color, 65536), 65536u);  // explicit alignment
  EXPECT_EQ(as.top(), 65536u + 4096u);
  EXPECT_EQ(as.reserved_bytes(), 4096u + 8192u + 4096u + 4096u);
  for (const AddressRegion& r : as.regions()) EXPECT_EQ(r.base % 4096, 0u) << r.name;
}

TEST(AddressSpaceTest, LookupByNameAndAddress) {
  AddressSpace as;
  as.allocate("vb", 100, DramClass::Vertices);
  as.allocate("tex", 5000, DramClass::Textures);
  EXPECT_EQ(as.base_of("tex"), 8192u);
  EXPECT_EQ(as.region("vb").size_bytes, 100u);
  EXPECT_EQ(as.find("nope"), nullptr);
  EXPECT_THROW(as.region("nope"), std::out_of_range);
  EXPECT_EQ(as.region_at(8192 + 4999)->name, "tex");
  EXPECT_EQ(as.region_at(8192 + 8191)->name, "tex");  // reserved tail page
  EXPECT_EQ(as.region_at(8192 + 8192), nullptr);
  EXPECT_EQ(as.region_at(0), nullptr);
  EXPECT_EQ(as.class_at(4096 + 99), DramClass::Vertices);
  EXPECT_EQ(as.class_at(1), DramClass::Other);
}

TEST(AddressSpaceTest, RejectsBadRequests) {
  AddressSpace as;
  as.allocate("a", 1, DramClass::Other);
  EXPECT_THROW(as.allocate("a", 1, DramClass::Other), std::invalid_argument);
  EXPECT_THROW(as.allocate("", 1, DramClass::Other), std::invalid_argument);
  EXPECT_THROW(as.allocate("b", 1, DramClass::Other, 3000), std::invalid_argument);
  EXPECT_THROW(AddressSpace(3000), std::invalid_argument);
}

TEST(AddressSpaceTest, DeterministicAndClearable) {
  const auto build = [](AddressSpace& as) {
    std::vector<std::uint64_t> bases;
    for (int i = 0; i < 20; ++i) {
      bases.push_back(as.allocate("r" + std::to_string(i), static_cast<std::uint64_t>(i * 3000 + 1),
                                  static_cast<DramClass>(i % static_cast<int>(kDramClassCount))));
    }
    return bases;
  };
  AddressSpace a, b;
  const auto first = build(a);
  EXPECT_EQ(first, build(b));
  a.clear();
  EXPECT_EQ(a.regions().size(), 0u);
  EXPECT_EQ(first, build(a));
}

// The high range keeps its own order: however its allocations interleave with the low range's,
// each range's bases are the same (FrameAddressMap places command buffer areas there as their
// first fragment jobs start, the other regions as commands are taken), and lookups see both.
TEST(AddressSpaceTest, TheHighRangeKeepsItsOwnOrderHoweverTheRangesInterleave) {
  AddressSpace a, b;
  // a: low, high, low, high; b: high, high, low, low.
  const std::uint64_t a_low0 = a.allocate("fb.0", 5000, DramClass::Color);
  const std::uint64_t a_high0 = a.allocate_high("buffers.0", 100, DramClass::Other);
  const std::uint64_t a_low1 = a.allocate("fb.1", 100, DramClass::Color);
  const std::uint64_t a_high1 = a.allocate_high("buffers.1", 9000, DramClass::LightLists);
  const std::uint64_t b_high0 = b.allocate_high("buffers.0", 100, DramClass::Other);
  const std::uint64_t b_high1 = b.allocate_high("buffers.1", 9000, DramClass::LightLists);
  const std::uint64_t b_low0 = b.allocate("fb.0", 5000, DramClass::Color);
  const std::uint64_t b_low1 = b.allocate("fb.1", 100, DramClass::Color);
  EXPECT_EQ(a_low0, b_low0);
  EXPECT_EQ(a_low1, b_low1);
  EXPECT_EQ(a_high0, b_high0);
  EXPECT_EQ(a_high1, b_high1);
  EXPECT_EQ(a_low1, 4096u + 8192u);  // after fb.0's two pages, as if no high region were there
  EXPECT_EQ(a_high0, AddressSpace::kHighBase);
  EXPECT_EQ(a_high1, AddressSpace::kHighBase + 4096u);
  EXPECT_EQ(a.top(), 4096u + 8192u + 4096u);  // the low range's
  // Lookups in address order across both ranges.
  ASSERT_EQ(a.regions().size(), 4u);
  for (std::size_t i = 1; i < a.regions().size(); ++i) EXPECT_LT(a.regions()[i - 1].base, a.regions()[i].base);
  EXPECT_EQ(a.class_at(a_high1 + 8999), DramClass::LightLists);
  EXPECT_EQ(a.region_at(a_low1)->name, "fb.1");
  EXPECT_EQ(a.base_of("buffers.0"), AddressSpace::kHighBase);
  EXPECT_EQ(a.region_at(AddressSpace::kHighBase - 1), nullptr);
  // The low range may not grow into the high one.
  EXPECT_THROW(a.allocate("huge", AddressSpace::kHighBase, DramClass::Other), std::overflow_error);
}

// ---------------------------------------------------------------------------------------------
// Cache

// 256 B, 2 ways, 64 B lines: 2 sets. Line n = addr / 64 goes to set n % 2.
CacheParams tiny_cache() { return CacheParams{256, 2, 64, 3}; }
constexpr std::uint64_t A = 0, B = 128, C = 256, D = 64;  // A, B, C: set 0; D: set 1

TEST(CacheTest, HitMissAndLruEviction) {
  Cache c("t", tiny_cache());
  ASSERT_EQ(c.sets(), 2u);
  ASSERT_EQ(c.ways(), 2u);
  const auto rd = [&](std::uint64_t a) { return c.access(a, 4, false, DramClass::Textures); };
  EXPECT_FALSE(rd(A).hit);  // set0: A
  EXPECT_FALSE(rd(B).hit);  // set0: A B
  EXPECT_TRUE(rd(A).hit);   // A most recent; B is LRU
  CacheAccess r = rd(C);    // evicts B
  EXPECT_FALSE(r.hit);
  EXPECT_TRUE(r.allocated);
  EXPECT_FALSE(r.writeback);
  EXPECT_FALSE(c.probe(B));
  EXPECT_TRUE(c.probe(A));
  EXPECT_FALSE(rd(B).hit);  // evicts A (C used more recently)
  EXPECT_FALSE(c.probe(A));
  EXPECT_TRUE(rd(C).hit);   // B is now LRU
  EXPECT_FALSE(rd(A).hit);  // evicts B
  EXPECT_FALSE(c.probe(B));
  EXPECT_FALSE(rd(D).hit);  // set 1, no eviction
  EXPECT_TRUE(c.probe(A) && c.probe(C) && c.probe(D));

  const CacheStats& s = c.stats();
  EXPECT_EQ(s.reads.value(), 8u);
  EXPECT_EQ(s.read_hits.value(), 2u);
  EXPECT_EQ(s.read_misses.value(), 6u);
  EXPECT_EQ(s.fills.value(), 6u);
  EXPECT_EQ(s.clean_evictions.value(), 3u);
  EXPECT_EQ(s.dirty_evictions.value(), 0u);
  EXPECT_EQ(s.read_bytes.value(), 8u * 4u);
  EXPECT_EQ(s.fill_bytes.value(), 6u * 64u);
  EXPECT_EQ(c.class_stats(DramClass::Textures).read_misses.value(), 6u);
  EXPECT_EQ(c.class_stats(DramClass::Color).read_misses.value(), 0u);
}

TEST(CacheTest, FourWayTrueLru) {
  Cache c("t", CacheParams{256, 4, 64, 1});  // one set of 4 ways
  for (std::uint64_t l : {0, 1, 2, 3}) c.access(l * 64, 64, false, DramClass::Other);
  // Touch 0 and 2: LRU order (oldest first) is 1, 3, 0, 2.
  c.access(0, 64, false, DramClass::Other);
  c.access(2 * 64, 64, false, DramClass::Other);
  c.access(4 * 64, 64, false, DramClass::Other);  // evicts 1
  EXPECT_FALSE(c.probe(1 * 64));
  c.access(5 * 64, 64, false, DramClass::Other);  // evicts 3
  EXPECT_FALSE(c.probe(3 * 64));
  c.access(6 * 64, 64, false, DramClass::Other);  // evicts 0
  EXPECT_FALSE(c.probe(0));
  EXPECT_TRUE(c.probe(2 * 64) && c.probe(4 * 64) && c.probe(5 * 64) && c.probe(6 * 64));
}

TEST(CacheTest, EveryAssociativityMatchesAReferenceTrueLru) {
  // Cache::access has lookups specialised for 4, 8 and 16 ways (unrolled compares) and a general
  // one for any other count: each must make the decisions of a plain true-LRU model (a list per
  // set, most recent first) on the same mixed reads and writes: hit or miss, the victim, and
  // whether it was dirty. 3 sets each, 4000 accesses over 40 lines: every set sees many evictions.
  for (const int ways : {1, 2, 3, 4, 5, 8, 16}) {
    const int sets = 3, line = 64;
    Cache c("t", CacheParams{static_cast<std::int64_t>(sets) * ways * line, ways, line, 1});
    std::vector<std::vector<std::pair<std::uint64_t, bool>>> ref(sets);  // per set: (line, dirty), most recent first
    std::uint64_t x = 12345;
    for (int i = 0; i < 4000; ++i) {
      x = x * 6364136223846793005ull + 1442695040888963407ull;
      const std::uint64_t l = (x >> 33) % 40;
      const bool write = ((x >> 20) & 3) == 0;
      const CacheAccess a = c.access(l * line, 4, write, DramClass::Other);
      auto& set = ref[l % sets];
      auto it = std::find_if(set.begin(), set.end(), [&](const auto& e) { return e.first == l; });
      const bool hit = it != set.end();
      ASSERT_EQ(a.hit, hit) << ways << " ways, access " << i;
      bool dirty = write;
      if (hit) {
        dirty = dirty || it->second;
        set.erase(it);
      } else if (static_cast<int>(set.size()) == ways) {
        ASSERT_EQ(a.writeback, set.back().second) << ways << " ways, access " << i;
        if (a.writeback) {
          EXPECT_EQ(a.victim_addr, set.back().first * line);
        }
        set.pop_back();
      } else {
        EXPECT_FALSE(a.writeback);
      }
      set.insert(set.begin(), {l, dirty});
      EXPECT_TRUE(c.probe(l * line));
      EXPECT_EQ(c.is_dirty(l * line), dirty);
    }
  }
}

TEST(CacheTest, MoreWaysHoldAConflictingLoopThatFewerThrash) {
  // Response to associativity at a fixed capacity (16 KiB, 64 B lines): a loop over k lines that
  // all fall in one set (addresses k * capacity) hits on every access after the first round when
  // the set has k or more ways, and never under true LRU when it has fewer (each access evicts
  // the line needed next). Loop of 6 lines, 10 rounds = 60 accesses, 6 cold misses:
  //   ways 1, 2, 4: 0 hits; ways 8, 16: 54 hits (9 rounds x 6). Never fewer hits with more ways.
  const std::int64_t capacity = 16 * 1024;
  std::uint64_t previous_hits = 0;
  for (const int ways : {1, 2, 4, 8, 16}) {
    Cache c("t", CacheParams{capacity, ways, 64, 1});
    for (int round = 0; round < 10; ++round)
      for (std::uint64_t k = 0; k < 6; ++k) c.access(k * static_cast<std::uint64_t>(capacity), 4, false, DramClass::Other);
    const std::uint64_t hits = c.stats().read_hits.value();
    EXPECT_EQ(hits, ways >= 6 ? 54u : 0u) << ways << " ways";
    EXPECT_EQ(c.stats().read_misses.value(), 60u - hits) << ways << " ways";
    EXPECT_GE(hits, previous_hits) << ways << " ways";
    previous_hits = hits;
  }
}

TEST(CacheTest, DirtyWritebackAndFlush) {
  Cache c("t", tiny_cache());
  CacheAccess r = c.access(A, 16, true, DramClass::Color);  // write miss: allocate, no fetch
  EXPECT_FALSE(r.hit);
  EXPECT_TRUE(r.allocated);
  EXPECT_TRUE(c.is_dirty(A));
  EXPECT_EQ(c.stats().write_allocations.value(), 1u);
  EXPECT_EQ(c.stats().fills.value(), 0u);
  c.access(B, 4, false, DramClass::Textures);
  r = c.access(C, 4, false, DramClass::Textures);  // evicts A, which is dirty
  EXPECT_TRUE(r.writeback);
  EXPECT_EQ(r.victim_addr, A);
  EXPECT_EQ(r.victim_cls, DramClass::Color);
  EXPECT_EQ(c.stats().dirty_evictions.value(), 1u);
  EXPECT_EQ(c.stats().writeback_bytes.value(), 64u);

  EXPECT_TRUE(c.access(B, 8, true, DramClass::Gbuffer).hit);  // write hit: B dirty, class of the writer
  std::vector<std::pair<std::uint64_t, DramClass>> wb;
  EXPECT_EQ(c.flush([&](std::uint64_t a, DramClass k) { wb.push_back({a, k}); }), 1u);
  ASSERT_EQ(wb.size(), 1u);
  EXPECT_EQ(wb[0].first, B);
  EXPECT_EQ(wb[0].second, DramClass::Gbuffer);
  EXPECT_FALSE(c.is_dirty(B));
  EXPECT_TRUE(c.probe(B));  // flushed lines stay valid
  EXPECT_EQ(c.flush([&](std::uint64_t, DramClass) { FAIL(); }), 0u);
  EXPECT_EQ(c.stats().writeback_bytes.value(), 128u);
  c.invalidate_all();
  EXPECT_FALSE(c.probe(B));
}

TEST(CacheTest, StreamingAndWriteNoAllocate) {
  Cache c("t", tiny_cache());
  CacheAccess r = c.access(A, 64, false, DramClass::Color, Allocation::NoAllocate);
  EXPECT_FALSE(r.hit);
  EXPECT_FALSE(r.allocated);
  EXPECT_EQ(r.slot, CacheAccess::kNoSlot);
  EXPECT_FALSE(c.probe(A));
  c.access(A, 64, false, DramClass::Color);  // now present
  EXPECT_TRUE(c.access(A, 64, true, DramClass::Color, Allocation::NoAllocate).hit);  // streaming hits are served
  EXPECT_TRUE(c.is_dirty(A));
  EXPECT_EQ(c.stats().bypasses.value(), 1u);

  Cache wna("wna", tiny_cache(), 0.0, /*write_allocate=*/false);
  EXPECT_FALSE(wna.access(B, 4, true, DramClass::Color).allocated);
  EXPECT_FALSE(wna.probe(B));
  EXPECT_TRUE(wna.access(B, 4, false, DramClass::Color).allocated);  // reads still allocate
}

TEST(CacheTest, NonPowerOfTwoSetsAndBadGeometry) {
  Cache c("t", CacheParams{192, 1, 64, 1});  // 3 sets, direct mapped: lines 0 and 3 collide
  EXPECT_EQ(c.sets(), 3u);
  c.access(0, 4, false, DramClass::Other);
  c.access(64, 4, false, DramClass::Other);
  c.access(3 * 64, 4, false, DramClass::Other);
  EXPECT_FALSE(c.probe(0));
  EXPECT_TRUE(c.probe(64));
  EXPECT_THROW(Cache("bad", CacheParams{256, 2, 48, 1}), std::invalid_argument);
  EXPECT_THROW(Cache("bad", CacheParams{200, 2, 64, 1}), std::invalid_argument);
  EXPECT_THROW(Cache("bad", CacheParams{256, 0, 64, 1}), std::invalid_argument);
}

TEST(CacheTest, EnergyAndCollect) {
  Cache c("mem/cache.t", tiny_cache(), 2.5);
  c.access(A, 4, false, DramClass::Textures);  // 4 read bytes + 64 fill bytes
  c.access(A, 4, true, DramClass::Textures);   // 4 write bytes
  EXPECT_DOUBLE_EQ(c.energy_pj(), (4 + 64 + 4) * 2.5);
  std::vector<StatRecord> out;
  append_cache_rows(c.snapshot(), out);
  ASSERT_FALSE(out.empty());
  EXPECT_EQ(out.front().scope, "mem/cache.t");
  bool saw_class = false;
  for (const StatRecord& r : out) saw_class |= r.scope == "mem/cache.t.class.textures";
  EXPECT_TRUE(saw_class);
}

// ---------------------------------------------------------------------------------------------
// DRAM

TEST(DramTest, AddressMappings) {
  EventQueue eq;
  HwConfig hw = test_config();
  {
    Dram d(hw.dram, hw.energy, eq);  // row | bank | channel | column
    EXPECT_EQ(d.map(100).channel, 0u);
    EXPECT_EQ(d.map(100).column, 100u);
    EXPECT_EQ(d.map(4096).channel, 1u);
    EXPECT_EQ(d.map(4096).bank, 0u);
    EXPECT_EQ(d.map(2 * 4096).channel, 0u);
    EXPECT_EQ(d.map(2 * 4096).bank, 1u);
    EXPECT_EQ(d.map(16 * 4096).row, 1u);
    EXPECT_EQ(d.map(16 * 4096).bank, 0u);
  }
  hw.dram.address_mapping = DramMapping::RowChannelBankColumn;
  {
    Dram d(hw.dram, hw.energy, eq);  // row | channel | bank | column
    EXPECT_EQ(d.map(4096).channel, 0u);
    EXPECT_EQ(d.map(4096).bank, 1u);
    EXPECT_EQ(d.map(8 * 4096).channel, 1u);
    EXPECT_EQ(d.map(8 * 4096).bank, 0u);
    EXPECT_EQ(d.map(16 * 4096 + 7).row, 1u);
    EXPECT_EQ(d.map(16 * 4096 + 7).column, 7u);
  }
  hw.dram.channels = 3;  // not a power of two: the division path
  hw.dram.address_mapping = DramMapping::RowBankChannelColumn;
  {
    Dram d(hw.dram, hw.energy, eq);
    EXPECT_EQ(d.map(2 * 4096).channel, 2u);
    EXPECT_EQ(d.map(3 * 4096).channel, 0u);
    EXPECT_EQ(d.map(3 * 4096).bank, 1u);
    EXPECT_EQ(d.map(24 * 4096).row, 1u);
  }
  // The mapping is an enum: an unknown spelling never reaches the DRAM, the configuration refuses it.
  EXPECT_THROW(resolve_config({}, {"dram.address_mapping=interleaved"}), InputError);
  hw.dram.write_high_watermark = 1.5;
  EXPECT_THROW(Dram(hw.dram, hw.energy, eq), std::invalid_argument);
}

TEST(DramTest, TimingFromParameters) {
  EventQueue eq;
  const HwConfig hw = test_config();
  Dram d(hw.dram, hw.energy, eq);
  EXPECT_EQ(d.timing().t_rcd_cycles, 18);
  EXPECT_EQ(d.timing().t_rp_cycles, 18);
  EXPECT_EQ(d.timing().t_cl_cycles, 15);
  EXPECT_EQ(d.timing().t_ras_cycles, 42);
  EXPECT_EQ(d.timing().controller, Tick{30 * kNs});
  EXPECT_EQ(d.timing().transfer(2), Tick{10 * kNs});  // 64 B at 6.4 GB/s per channel
  // The default LPDDR3-1600 clock: 18 ns = 14.4 cycles of 1.25 ns, rounded up to 15.
  HwConfig lp = resolve_config({}, {}).hw;
  Dram d2(lp.dram, lp.energy, eq);
  EXPECT_EQ(d2.timing().t_rcd_cycles, 15);
  EXPECT_EQ(d2.timing().t_cl_cycles, 12);
}

TEST(DramTest, SequentialReadsHitTheOpenRow) {
  // 4096 sequential lines = 64 bank-rows of 64 lines: each bank-row misses once, then hits 63
  // times, so hits / requests = (4096/64 - 1) / (4096/64) = 63/64 exactly.
  const HwConfig hw = test_config();
  constexpr std::uint64_t kLines = 4096, kLinesPerRow = 4096 / 64;
  for (const bool timed : {true, false}) {
    EventQueue eq;
    Dram d(hw.dram, hw.energy, eq);
    DramFeeder f(d, eq);
    for (std::uint64_t i = 0; i < kLines; ++i) {
      if (timed) {
        f.add(i * 64, 64, false, DramClass::Textures);
      } else {
        d.access_functional(i * 64, 64, false, DramClass::Textures);
      }
    }
    f.pump();
    eq.run();
    ASSERT_TRUE(f.all_done());
    const DramStats& s = d.stats();
    EXPECT_EQ(s.reads.value(), kLines) << timed;
    EXPECT_EQ(s.row_misses.value(), kLines / kLinesPerRow) << timed;
    EXPECT_EQ(s.row_hits.value(), kLines - kLines / kLinesPerRow) << timed;
    EXPECT_EQ(s.row_misses_empty.value(), 16u) << timed;  // 2 channels x 8 banks opened once from empty
    EXPECT_EQ(s.row_conflicts.value(), kLines / kLinesPerRow - 16) << timed;
    d.update_derived_stats();
    EXPECT_DOUBLE_EQ(s.row_hit_rate.value(), 63.0 / 64.0) << timed;
  }
}

TEST(DramTest, StridedRowConflictsPayPrechargeActivateRead) {
  // Stride = row x channels x banks: every access is channel 0, bank 0, a new row.
  const HwConfig hw = test_config();
  constexpr std::uint64_t kStride = 4096ull * 2 * 8;
  constexpr int kN = 12;
  // Serialised (next request issued when the previous completes): the latency of one request is
  // controller + [tRP] + tRCD + RL + burst + controller = 30 + 18 + 18 + 15 + 10 + 30 = 121 ns
  // (the first finds the bank empty: no precharge, 103 ns).
  {
    EventQueue eq;
    Dram d(hw.dram, hw.energy, eq);
    std::vector<Tick> issued, done;
    std::function<void(int)> send = [&](int i) {
      issued.push_back(eq.now());
      ASSERT_TRUE(d.enqueue(DramRequest{static_cast<std::uint64_t>(i) * kStride, 64, false, DramClass::Color, [&, i] {
        done.push_back(eq.now());
        if (i + 1 < kN) send(i + 1);
      }}));
    };
    send(0);
    eq.run();
    ASSERT_EQ(done.size(), static_cast<std::size_t>(kN));
    EXPECT_EQ((done[0] - issued[0]).ps(), 103 * kNs);
    for (int i = 1; i < kN; ++i) EXPECT_EQ((done[i] - issued[i]).ps(), 121 * kNs) << i;
    EXPECT_EQ(d.stats().row_hits.value(), 0u);
    EXPECT_EQ(d.stats().row_conflicts.value(), static_cast<std::uint64_t>(kN - 1));
    EXPECT_EQ(d.stats().precharges.value(), static_cast<std::uint64_t>(kN - 1));
    EXPECT_EQ(d.stats().activates.value(), static_cast<std::uint64_t>(kN));
  }
  // Queued all at once: consecutive completions are tRP + tRCD + RL + burst = 61 ns apart (the
  // precharge waits for the previous data, which ends after tRAS = 42 ns from its activate).
  {
    EventQueue eq;
    Dram d(hw.dram, hw.energy, eq);
    DramFeeder f(d, eq);
    for (int i = 0; i < kN; ++i) f.add(static_cast<std::uint64_t>(i) * kStride, 64, false, DramClass::Color);
    f.pump();
    eq.run();
    ASSERT_TRUE(f.all_done());
    EXPECT_EQ(f.done()[0].ps(), 103 * kNs);
    for (int i = 1; i < kN; ++i) EXPECT_EQ((f.done()[i] - f.done()[i - 1]).ps(), 61 * kNs) << i;
    EXPECT_EQ(d.stats().row_hits.value(), 0u);
  }
}

/// Time for `lines` sequential 64 B reads from address 0, and the feeder's refusal count.
std::pair<double, std::uint64_t> sequential_stream_ps(const HwConfig& hw, std::uint64_t lines, bool per_channel,
                                                      Dram** keep = nullptr, EventQueue* eq_out = nullptr) {
  EventQueue local;
  EventQueue& eq = eq_out ? *eq_out : local;
  auto d = std::make_unique<Dram>(hw.dram, hw.energy, eq);
  DramFeeder f(*d, eq, per_channel);
  for (std::uint64_t i = 0; i < lines; ++i) f.add(i * 64, 64, false, DramClass::Textures);
  f.pump();
  eq.run();
  EXPECT_TRUE(f.all_done());
  const double took = static_cast<double>(f.last_done().ps());
  if (keep) *keep = d.release();
  return {took, f.refused()};
}

TEST(DramTest, BandwidthBoundStreamWithinFivePercent) {
  // 16384 sequential 64 B reads (1 MiB), one in-order stream per channel, each kept as full as
  // the queues allow. Bound: N x 64 B / 12.8 GB/s = 81.92 us; it must finish within 5 % of it.
  // (Row switches are hidden: the next bank's row is opened while the current row streams.)
  const HwConfig hw = test_config();
  constexpr std::uint64_t kLines = 16384;
  const double bound_ps = static_cast<double>(kLines * 64) / 12.8 * 1000.0;
  EventQueue eq;
  Dram* raw = nullptr;
  const auto [took_ps, refused] = sequential_stream_ps(hw, kLines, true, &raw, &eq);
  std::unique_ptr<Dram> d(raw);
  EXPECT_GE(took_ps, bound_ps);
  EXPECT_LE(took_ps, 1.05 * bound_ps) << "took " << took_ps / 1e6 << " us, bound " << bound_ps / 1e6 << " us";
  EXPECT_GT(refused, 0u) << "the feeder should have been backpressured";
  d->update_derived_stats();
  std::cout << "[ figures  ] sequential stream, per-channel feed: " << took_ps / 1e6 << " us vs bound "
            << bound_ps / 1e6 << " us (" << 100.0 * bound_ps / took_ps << " % of peak), achieved "
            << d->stats().achieved_bandwidth_gbps.value() << " GB/s, row hit rate " << d->stats().row_hit_rate.value()
            << "\n";
  EXPECT_NEAR(d->channel_stats(0).utilization.value(), bound_ps / took_ps, 0.01);
  EXPECT_NEAR(d->channel_stats(1).utilization.value(), bound_ps / took_ps, 0.01);
}

/// Refresh on: the LPDDR3 defaults, tREFI 3900 ns and tRFC 130 ns (whole cycles at 1 GHz).
const std::vector<std::string> kRefreshOn = {"dram.t_refi_ns=3900", "dram.t_rfc_ns=130"};

TEST(DramTest, StreamingWithRefreshReachesWhatTrfcOverTrefiLeaves) {
  // The same 1 MiB per-channel read stream as above, refresh off and on. A refresh closes every
  // bank and blocks them for tRFC; the stream loses, per refresh, the bus time from its last data
  // to the first data after the refresh: the open row's precharge tRP + tRFC + the next row's
  // tRCD + RL = 18 + 130 + 18 + 15 = 181 ns (its last data still flows while the refresh waits, so
  // nothing else is lost). Each channel refreshes once per 3900 ns whatever the traffic, so:
  //   efficiency with refresh = 1 - 181 / 3900 = 95.36 %   (tRFC alone: 1 - 130 / 3900 = 96.67 %)
  //   time with refresh / time without = 1 / 0.9536 = 1.0487.
  constexpr std::uint64_t kLines = 16384;
  const double bound_ps = static_cast<double>(kLines * 64) / 12.8 * 1000.0;
  const auto [off_ps, r0] = sequential_stream_ps(test_config(), kLines, true);
  EventQueue eq;
  Dram* raw = nullptr;
  const auto [on_ps, r1] = sequential_stream_ps(test_config(kRefreshOn), kLines, true, &raw, &eq);
  std::unique_ptr<Dram> d(raw);
  const double lost_per_refresh_ns = 18 + 130 + 18 + 15;
  const double predicted = 1.0 - lost_per_refresh_ns / 3900.0;
  std::cout << "[ figures  ] stream with refresh: " << 100.0 * bound_ps / on_ps << " % of peak (predicted "
            << 100.0 * predicted << " %), without: " << 100.0 * bound_ps / off_ps << " %; " << d->stats().refreshes.value()
            << " refreshes\n";
  EXPECT_GT(on_ps, off_ps);
  EXPECT_NEAR(on_ps / off_ps, 1.0 / predicted, 0.01) << "refresh costs (tRP + tRFC + tRCD + RL) / tREFI";
  EXPECT_GT(on_ps / off_ps, 1.0 / (1.0 - 130.0 / 3900.0)) << "at least tRFC / tREFI";
  EXPECT_NEAR(bound_ps / on_ps, predicted, 0.01);
  // Refreshes: one per channel per 3900 ns of the run (channel c first at (c + 1) / 2 of it).
  const auto per_channel = static_cast<std::uint64_t>(on_ps / 3900e3);
  EXPECT_GE(d->stats().refreshes.value(), 2 * per_channel - 1);
  EXPECT_LE(d->stats().refreshes.value(), 2 * per_channel + 2);
}

TEST(DramTest, IdleChannelsRefreshOnTimeAndTheirStandbyIsCharged) {
  // One read at t = 0 on channel 0, then nothing until 39 us. Channel 0 refreshes at 1950 + k x
  // 3900 ns (10 by 39 us), channel 1 at 3900 + k x 3900 (10, the last at 39 us). Refresh energy =
  // 20 x refresh_nj. Channel 1 never opens a row: 39 us of precharge standby. Channel 0 has a row
  // open from its activate (controller 30 ns: ACT at 30 ns) until the first refresh ends
  // (1950 + tRFC 130 = 2080 ns): 2050 ns of active standby, the rest precharged.
  const HwConfig hw = test_config(kRefreshOn);
  EventQueue eq;
  Dram d(hw.dram, hw.energy, eq);
  ASSERT_TRUE(d.enqueue(DramRequest{0, 64, false, DramClass::Color, {}}));
  eq.schedule(Tick{39000 * kNs}, [] {});
  eq.run();
  d.update_derived_stats();
  EXPECT_EQ(d.stats().refreshes.value(), 20u);
  EXPECT_EQ(d.channel_stats(0).refreshes.value(), 10u);
  EXPECT_EQ(d.channel_stats(1).precharged_ps.value(), static_cast<std::uint64_t>(39000 * kNs));
  EXPECT_EQ(d.channel_stats(0).precharged_ps.value(), static_cast<std::uint64_t>((39000 - 2050) * kNs));
  EXPECT_DOUBLE_EQ(d.stats().energy_refresh_pj.value(), 20 * hw.dram.refresh_nj * 1000.0);
  const double background = (hw.dram.precharge_standby_mw * (39000 + 39000 - 2050) + hw.dram.active_standby_mw * 2050) * kNs * 1e-3;
  EXPECT_NEAR(d.stats().energy_background_pj.value(), background, 1e-6 * background);
  // A read after that finds its row closed by the refresh: an activate from an empty bank.
  ASSERT_TRUE(d.enqueue(DramRequest{64, 64, false, DramClass::Color, {}}));
  eq.run();
  EXPECT_EQ(d.stats().row_misses_empty.value(), 2u);
}

/// Time from t = 0 until the last of `n` reads on channel 0 completes, every read opening a new
/// row in the next bank (bank i mod 8, row i / 8 + 1: each one a row conflict once the banks are
/// open), all queued at once.
double row_miss_stream_ps(const HwConfig& hw, int n, std::uint64_t* activates = nullptr) {
  EventQueue eq;
  Dram d(hw.dram, hw.energy, eq);
  DramFeeder f(d, eq);
  for (int i = 0; i < n; ++i) {
    const std::uint64_t bank = static_cast<std::uint64_t>(i % 8), row = static_cast<std::uint64_t>(i / 8 + 1);
    f.add(((row * 8 + bank) * 2 + 0) * 4096, 64, false, DramClass::Textures);  // row | bank | channel 0 | column
  }
  f.pump();
  eq.run();
  EXPECT_TRUE(f.all_done());
  EXPECT_EQ(d.stats().row_hits.value(), 0u);
  if (activates) *activates = d.stats().activates.value();
  return static_cast<double>(f.last_done().ps());
}

TEST(DramTest, RowMissStreamIsBoundByTfawTrrdOrTrc) {
  // Every read needs its own activate, so the channel serves one read per
  //   max(tRRD, tFAW / 4, tRC / banks, burst) = max(10, 50 / 4, (42 + 18) / 8, 10) = 12.5 ns (tFAW)
  // tRRD 15 ns instead: 15 ns per read; tRRD and tFAW 0: the data bus, 10 ns (tRC / 8 = 7.5).
  // 800 reads: 800 x the bound, plus the pipeline fill (controller + tRCD + RL + burst + controller
  // = 103 ns): within 3 %.
  constexpr int kN = 800;
  struct Case {
    std::vector<std::string> sets;
    double per_read_ns;
  };
  const std::vector<Case> cases = {{{}, 12.5}, {{"dram.t_rrd_ns=15"}, 15.0}, {{"dram.t_rrd_ns=0", "dram.t_faw_ns=0"}, 10.0}};
  for (const Case& c : cases) {
    std::uint64_t acts = 0;
    const double took = row_miss_stream_ps(test_config(c.sets), kN, &acts);
    const double predicted = (kN * c.per_read_ns + 103) * kNs;
    std::cout << "[ figures  ] row-miss stream, " << c.per_read_ns << " ns per read predicted: " << took / kN / kNs
              << " ns per read\n";
    EXPECT_NEAR(took / predicted, 1.0, 0.03) << c.per_read_ns;
    EXPECT_EQ(acts, static_cast<std::uint64_t>(kN));
  }
}

TEST(DramTest, ReadAfterWriteWaitsTwtrWriteAfterReadWaitsTrtw) {
  // A write to an empty bank enqueued at 0: arrives at 30 ns, ACT 30, column command at 48 (tRCD
  // 18), data 63..73 (RL 15, 10 ns). A read of the same row enqueued at 19 ns arrives at 49, after
  // the write's column command: it may not issue its read command before the write data ended +
  // tWTR: 73 + 10 = 83, data 98..108 (RL), back at 138 ns (controller 30). With tWTR = 0: 128 ns.
  // The data bus idles tWTR + RL = 25 ns between the two transfers.
  for (const double t_wtr : {10.0, 0.0}) {
    const HwConfig hw = test_config({"dram.t_wtr_ns=" + std::to_string(t_wtr)});
    EventQueue eq;
    Dram d(hw.dram, hw.energy, eq);
    Tick read_done{-1};
    ASSERT_TRUE(d.enqueue(DramRequest{0, 64, true, DramClass::Color, {}}));
    eq.schedule(Tick{19 * kNs}, [&] {
      ASSERT_TRUE(d.enqueue(DramRequest{64, 64, false, DramClass::Color, [&] { read_done = eq.now(); }}));
    });
    eq.run();
    EXPECT_EQ(read_done.ps(), static_cast<std::int64_t>((128 + t_wtr) * kNs)) << t_wtr;
    EXPECT_EQ(d.stats().write_to_read_turnarounds.value(), 1u);
  }
  // Mirror: a read (data 63..73) then a write of the same row arriving after the read's column
  // command: the write data starts tRTW = 4 ns after the read data ends: 77..87, acknowledged at
  // 117 ns; with tRTW = 0 at 113 ns.
  for (const double t_rtw : {4.0, 0.0}) {
    const HwConfig hw = test_config({"dram.t_rtw_ns=" + std::to_string(t_rtw)});
    EventQueue eq;
    Dram d(hw.dram, hw.energy, eq);
    Tick write_done{-1};
    ASSERT_TRUE(d.enqueue(DramRequest{0, 64, false, DramClass::Color, {}}));
    eq.schedule(Tick{19 * kNs}, [&] {
      ASSERT_TRUE(d.enqueue(DramRequest{64, 64, true, DramClass::Color, [&] { write_done = eq.now(); }}));
    });
    eq.run();
    EXPECT_EQ(write_done.ps(), static_cast<std::int64_t>((113 + t_rtw) * kNs)) << t_rtw;
    EXPECT_EQ(d.stats().read_to_write_turnarounds.value(), 1u);
  }
}

TEST(DramTest, PresetEnergyPerBitIsTheMemspecArithmetic) {
  // Each shipped DRAM preset streams 4 MiB of sequential reads (one in-order stream per channel),
  // refresh on. Its energy per bit read must be, within 1 %, the memspec arithmetic:
  //   read_pj + io_pj                                   the bits themselves
  // + act_nj x 1000 / (row_bytes x 8)                   one activate per row (and per refresh: < 0.02)
  // + channels x active_standby_mw x T x 1e-3 / bits    rows stay open: active standby for the run T
  // + (channels x T / tREFI) x refresh_nj x 1000 / bits one refresh per channel per tREFI
  // (the difference: the moments after a refresh when a channel has every bank precharged).
  // LPDDR3-1600 at 95 % of 12.8 GB/s: 5.1 + 3.8 + 0.13 + 1.18 + 0.14 = about 10.4 pJ/bit.
  const std::string dir = std::string(TBDRSIM_SOURCE_DIR) + "/configs/";
  const std::vector<std::vector<std::string>> presets = {
      {dir + "series6xt_gx6450.ini"}, {dir + "mobile_16x16_lpddr4x.ini"},
      {dir + "mobile_16x16_lpddr4x.ini", dir + "dram_lpddr5_6400.ini"}};
  for (const auto& files : presets) {
    const HwConfig hw = resolve_config(files, {}).hw;
    constexpr std::uint64_t kLines = 65536;  // 4 MiB
    EventQueue eq;
    Dram* raw = nullptr;
    const auto [took_ps, refused] = sequential_stream_ps(hw, kLines, true, &raw, &eq);
    std::unique_ptr<Dram> d(raw);
    d->update_derived_stats();
    const double bits = static_cast<double>(kLines * 64 * 8);
    const double T = static_cast<double>(eq.now().ps());
    const double ch = static_cast<double>(hw.dram.channels);
    const double rows = static_cast<double>(kLines * 64) / static_cast<double>(hw.dram.row_bytes);
    const double predicted = hw.energy.dram_read_pj_per_bit + hw.energy.dram_io_pj_per_bit +
                             rows * hw.energy.dram_activate_precharge_nj * 1000.0 / bits +
                             ch * hw.dram.active_standby_mw * T * 1e-3 / bits +
                             ch * (T / (hw.dram.t_refi_ns * 1000.0)) * hw.dram.refresh_nj * 1000.0 / bits;
    const double simulated = d->stats().energy_per_bit_pj.value();
    std::cout << "[ figures  ] " << hw.dram.name << ": streaming read " << simulated << " pJ/bit (memspec arithmetic "
              << predicted << "; core read " << hw.energy.dram_read_pj_per_bit << " + I/O " << hw.energy.dram_io_pj_per_bit
              << "), " << 100.0 * static_cast<double>(kLines * 64) / hw.dram.peak_bandwidth_gbps() * 1000.0 / took_ps
              << " % of peak\n";
    EXPECT_NEAR(simulated / predicted, 1.0, 0.01) << hw.dram.name;
    // A refresh closes the rows being streamed: each costs up to two activates more (the row in
    // use and the one opened ahead).
    EXPECT_GE(d->stats().activates.value(), static_cast<std::uint64_t>(rows)) << hw.dram.name;
    EXPECT_LE(d->stats().activates.value(), static_cast<std::uint64_t>(rows) + 2 * d->stats().refreshes.value());
    EXPECT_GT(d->stats().energy_background_pj.value(), 0.0);
    EXPECT_GT(d->stats().energy_refresh_pj.value(), 0.0);
  }
}

TEST(DramTest, InOrderSourceIsLimitedByQueueDepthVersusChannelInterleave) {
  // A single in-order source blocks on the first full channel queue. With 32-entry queues (2 KiB
  // of lines) and channels interleaved every 4 KiB row, each channel runs dry while the source
  // waits on the other one; 64 entries cover a whole interleave unit and restore the bandwidth.
  HwConfig hw = test_config();
  constexpr std::uint64_t kLines = 16384;
  const double bound_ps = static_cast<double>(kLines * 64) / 12.8 * 1000.0;
  const double shallow = bound_ps / sequential_stream_ps(hw, kLines, false).first;
  hw.dram.read_queue_entries = 64;
  const double deep = bound_ps / sequential_stream_ps(hw, kLines, false).first;
  std::cout << "[ figures  ] sequential stream, single in-order feed: " << 100.0 * shallow
            << " % of peak with 32-entry queues, " << 100.0 * deep << " % with 64\n";
  EXPECT_LT(shallow, 0.95);
  EXPECT_GT(shallow, 0.75);
  EXPECT_GE(deep, 0.95);
}

TEST(DramTest, QueueFullBackpressureLosesNothing) {
  const HwConfig hw = test_config();
  EventQueue eq;
  Dram d(hw.dram, hw.energy, eq);
  // 40 reads to channel 0 (addresses within the first 4 KiB row) at tick 0: 32 fit.
  std::vector<int> completions(40, 0);
  std::deque<DramRequest> refused;
  for (int i = 0; i < 40; ++i) {
    DramRequest r{static_cast<std::uint64_t>(i % 64) * 64, 64, false, DramClass::Other, [&completions, i] { ++completions[i]; }};
    if (!d.enqueue(std::move(r))) {
      EXPECT_TRUE(static_cast<bool>(r.on_complete)) << "a refused request must be left intact";
      refused.push_back(std::move(r));
    }
  }
  EXPECT_EQ(refused.size(), 8u);
  EXPECT_EQ(d.read_queue_size(0), 32u);
  EXPECT_FALSE(d.can_accept(0, false));
  EXPECT_TRUE(d.can_accept(0, true));     // the write queue is separate
  EXPECT_TRUE(d.can_accept(4096, false));  // channel 1 is empty
  EXPECT_EQ(d.stats().queue_full_rejections.value(), 8u);
  d.set_space_callback([&](std::uint32_t) {
    while (!refused.empty() && d.enqueue(std::move(refused.front()))) refused.pop_front();
  });
  eq.run();
  EXPECT_TRUE(refused.empty());
  for (int i = 0; i < 40; ++i) EXPECT_EQ(completions[i], 1) << i;
  EXPECT_EQ(d.stats().completed.value(), 40u);
  EXPECT_EQ(d.in_flight(), 0u);
  EXPECT_FALSE(d.has_pending_work());
}

TEST(DramTest, ReadsBeforeWritesBelowTheWatermark) {
  const HwConfig hw = test_config();
  EventQueue eq;
  Dram d(hw.dram, hw.energy, eq);
  Tick last_read{0}, first_write = Tick::max();
  for (int i = 0; i < 4; ++i) {
    ASSERT_TRUE(d.enqueue(DramRequest{static_cast<std::uint64_t>(i) * 64, 64, true, DramClass::Color,
                                      [&] { first_write = std::min(first_write, eq.now()); }}));
  }
  for (int i = 0; i < 4; ++i) {
    ASSERT_TRUE(d.enqueue(DramRequest{2048 + static_cast<std::uint64_t>(i) * 64, 64, false, DramClass::Textures,
                                      [&] { last_read = std::max(last_read, eq.now()); }}));
  }
  eq.run();
  EXPECT_LT(last_read, first_write);
  EXPECT_EQ(d.stats().writes.value(), 4u);
  EXPECT_EQ(d.stats().write_bytes.value(), 256u);
}

TEST(DramTest, WriteDrainAtHighWatermark) {
  const HwConfig hw = test_config({"dram.write_queue_entries=8"});  // high watermark 6, low 2
  EventQueue eq;
  Dram d(hw.dram, hw.energy, eq);
  DramFeeder f(d, eq);
  for (int i = 0; i < 64; ++i) {
    f.add(static_cast<std::uint64_t>(i) * 64, 64, i % 2 == 0, i % 2 == 0 ? DramClass::Color : DramClass::Textures);
  }
  f.pump();
  eq.run();
  ASSERT_TRUE(f.all_done());
  EXPECT_GT(d.channel_stats(0).write_drains.value(), 0u);
  EXPECT_EQ(d.stats().completed.value(), 64u);
}

TEST(DramTest, RowHitsFirstButTheOldestIsNotStarved) {
  // Bank 0 of channel 0: A opens row 0, X wants row 1, then 40 more row-0 hits. FR-FCFS serves the
  // hits first, but after kStarvationCap of them X gets its row (and the remaining hits pay a
  // conflict to reopen row 0).
  const HwConfig hw = test_config();
  EventQueue eq;
  Dram d(hw.dram, hw.energy, eq);
  DramFeeder f(d, eq);
  f.add(0, 64, false, DramClass::Other);                     // A
  f.add(16 * 4096, 64, false, DramClass::Other);             // X: bank 0, row 1
  for (std::uint64_t i = 1; i <= 40; ++i) f.add(i * 64, 64, false, DramClass::Other);  // row 0 hits
  f.pump();
  eq.run();
  ASSERT_TRUE(f.all_done());
  const Tick x = f.done()[1];
  int hits_before_x = 0;
  for (std::size_t i = 2; i < f.done().size(); ++i) hits_before_x += f.done()[i] < x ? 1 : 0;
  EXPECT_GE(hits_before_x, static_cast<int>(Dram::kStarvationCap));
  EXPECT_LE(hits_before_x, static_cast<int>(Dram::kStarvationCap) + 2);
  EXPECT_EQ(d.stats().row_conflicts.value(), 2u);
  EXPECT_EQ(d.stats().row_hits.value(), 40u - 1u);
}

/// A mixed, pseudo-random workload: reads and writes of several classes over 8 MiB.
std::vector<Tick> run_mixed(Dram& d, EventQueue& eq, std::uint32_t seed, int n) {
  DramFeeder f(d, eq);
  std::mt19937 rng(seed);
  for (int i = 0; i < n; ++i) {
    const std::uint64_t line = rng() % (8u << 20) / 64;
    const bool w = rng() % 3 == 0;
    const auto cls = static_cast<DramClass>(rng() % kDramClassCount);
    f.add(line * 64, 64, w, cls);
  }
  f.pump();
  eq.run();
  EXPECT_TRUE(f.all_done());
  return f.done();
}

// Dram::wakeup derives the banks holding a row hit after its decisions from its one pass over
// the queue (the prepared request's bank gains one, the issued one's loses its only one); a
// second pass after every step must find the same banks, through mixed traffic (reads, writes,
// write drains, row conflicts across the banks of both channels) and the starvation cap's
// override.
TEST(DramTest, SchedulerSinglePassFindsTheRowHitsASecondPassWould) {
  const HwConfig hw = test_config();
  for (std::uint32_t seed : {1u, 7u, 42u}) {
    EventQueue eq;
    Dram d(hw.dram, hw.energy, eq);
    d.set_verify_scheduler(true);
    EXPECT_NO_THROW(run_mixed(d, eq, seed, 4000)) << seed;
    EXPECT_EQ(d.stats().completed.value(), 4000u);
  }
  // Few rows, many hits per row: the oldest request is bypassed until the cap lets it close a
  // row younger requests still want (a cycle after the last column command to that row).
  EventQueue eq;
  Dram d(hw.dram, hw.energy, eq);
  d.set_verify_scheduler(true);
  DramFeeder f(d, eq);
  std::mt19937 rng(3);
  for (int i = 0; i < 3000; ++i) f.add((rng() % 4) * 16 * 4096 + (rng() % 64) * 64, 64, rng() % 5 == 0, DramClass::Other);
  f.pump();
  EXPECT_NO_THROW(eq.run());
  EXPECT_TRUE(f.all_done());
  EXPECT_GT(d.stats().row_conflicts.value(), 0u);
}

// The scheduler's response to banks, where there is locality to keep: 5000 reads of random
// lines within 32 hot 4 KiB rows (consecutive rows: with row_bank_channel_column mapping, row r
// lands in channel r mod 2, bank (r / 2) mod B, DRAM row r / 2B). With B banks per channel the
// 32 rows share 2B row buffers: 16 banks give every hot row its own (after the first activate
// into an empty bank, no conflict at all); 8 banks put 2 rows in each bank, 4 banks 4, and
// FR-FCFS can batch a bank's hits only within its 32-entry queue, so conflicts grow as banks
// shrink and the traffic ends no earlier. (Random lines over 8 MiB, by contrast, conflict on
// nearly every request at any bank count: 4848 / 4851 / 4800 of 5000 at 4 / 8 / 16 banks; there
// more banks only add parallelism.) Measured 2026-12-06: 1379 / 1237 / 0 conflicts, the last
// read at 26.03 / 25.56 / 25.51 us.
TEST(DramTest, MoreBanksKeepMoreHotRowsOpen) {
  std::uint64_t conflicts[3] = {};
  Tick end[3];
  const int banks[3] = {4, 8, 16};
  for (int k = 0; k < 3; ++k) {
    const HwConfig hw = test_config({"dram.banks=" + std::to_string(banks[k])});
    EventQueue eq;
    Dram d(hw.dram, hw.energy, eq);
    d.set_verify_scheduler(true);
    DramFeeder f(d, eq);
    std::mt19937 rng(11);
    for (int i = 0; i < 5000; ++i) f.add((rng() % 32) * 4096 + (rng() % 64) * 64, 64, false, DramClass::Other);
    f.pump();
    eq.run();
    ASSERT_TRUE(f.all_done());
    conflicts[k] = d.stats().row_conflicts.value();
    end[k] = *std::max_element(f.done().begin(), f.done().end());
  }
  EXPECT_EQ(conflicts[2], 0u);  // 16 banks x 2 channels: a row buffer per hot row
  EXPECT_GT(conflicts[0], conflicts[1]);
  EXPECT_GT(conflicts[1], conflicts[2]);
  EXPECT_LE(end[1], end[0]);
  EXPECT_LE(end[2], end[1]);
  std::cout << "[          ] row conflicts at 4/8/16 banks: " << conflicts[0] << " / " << conflicts[1] << " / " << conflicts[2]
            << "; end " << end[0].ps() << " / " << end[1].ps() << " / " << end[2].ps() << " ps\n";
}

TEST(DramTest, Deterministic) {
  const HwConfig hw = test_config();
  std::vector<Tick> ticks[2];
  std::vector<StatRecord> stats[2];
  for (int k = 0; k < 2; ++k) {
    EventQueue eq;
    Dram d(hw.dram, hw.energy, eq);
    ticks[k] = run_mixed(d, eq, 42, 5000);
    append_dram_rows(d.snapshot(), stats[k]);
  }
  EXPECT_EQ(ticks[0], ticks[1]);
  ASSERT_EQ(stats[0].size(), stats[1].size());
  for (std::size_t i = 0; i < stats[0].size(); ++i) {
    EXPECT_EQ(stats[0][i].scope, stats[1][i].scope);
    EXPECT_EQ(stats[0][i].name, stats[1][i].name);
    EXPECT_EQ(stats[0][i].value, stats[1][i].value) << stats[0][i].scope << " " << stats[0][i].name;
  }
}

TEST(DramTest, EnergyConservation) {
  // LPDDR4-like, so every term is non-zero
  const HwConfig hw = test_config({"energy.dram_read_pj_per_bit=5.3", "energy.dram_write_pj_per_bit=3.9",
                                   "energy.dram_io_pj_per_bit=3.2", "energy.dram_activate_precharge_nj=1.2"});
  EventQueue eq;
  Dram d(hw.dram, hw.energy, eq);
  run_mixed(d, eq, 7, 3000);
  for (int i = 0; i < 500; ++i) d.access_functional(static_cast<std::uint64_t>(i) * 4096 * 3, 64, i % 2 == 1, DramClass::Spill);
  const DramStats& s = d.stats();
  // The same arithmetic as the model: total == counters x unit costs, exactly.
  const double rb = 8.0 * static_cast<double>(s.read_bytes.value());
  const double wb = 8.0 * static_cast<double>(s.write_bytes.value());
  const double expected = rb * 5.3 + wb * 3.9 + (rb + wb) * 3.2 + static_cast<double>(s.activates.value()) * (1.2 * 1000.0);
  // The total adds the standby energy up to now and the refreshes (none: refresh is off here).
  const double background = d.background_energy_pj(eq.now());
  EXPECT_GT(background, 0);
  EXPECT_EQ(d.energy_pj(), expected + background);
  d.update_derived_stats();
  EXPECT_EQ(s.energy_pj.value(), expected + background);
  EXPECT_EQ(s.energy_dynamic_pj.value(), expected);
  EXPECT_EQ(s.energy_background_pj.value(), background);
  EXPECT_EQ(s.energy_refresh_pj.value(), 0.0);
  EXPECT_EQ(s.energy_read_pj.value() + s.energy_write_pj.value() + s.energy_io_pj.value() + s.energy_activate_pj.value(),
            expected);
  // Classes partition the counters, so their energies add up to the total (to rounding).
  double sum = 0;
  std::uint64_t acts = 0, bytes = 0;
  for (std::size_t c = 0; c < kDramClassCount; ++c) {
    const DramClassStats& cs = d.class_stats(static_cast<DramClass>(c));
    sum += cs.energy_pj.value();
    acts += cs.activates.value();
    bytes += cs.read_bytes.value() + cs.write_bytes.value();
  }
  EXPECT_EQ(acts, s.activates.value());
  EXPECT_EQ(bytes, s.read_bytes.value() + s.write_bytes.value());
  EXPECT_NEAR(sum, expected, expected * 1e-12);
  EXPECT_GT(s.activates.value(), 0u);
}

TEST(DramTest, ActivatesBelongToTheClassThatOpenedTheRow) {
  const HwConfig hw = test_config();
  EventQueue eq;
  Dram d(hw.dram, hw.energy, eq);
  EXPECT_EQ(d.access_functional(0, 64, false, DramClass::Color), RowOutcome::Empty);
  EXPECT_EQ(d.access_functional(64, 64, false, DramClass::Textures), RowOutcome::Hit);
  EXPECT_EQ(d.access_functional(16 * 4096, 64, true, DramClass::Gbuffer), RowOutcome::Conflict);
  EXPECT_EQ(d.class_stats(DramClass::Color).activates.value(), 1u);
  EXPECT_EQ(d.class_stats(DramClass::Textures).activates.value(), 0u);
  EXPECT_EQ(d.class_stats(DramClass::Gbuffer).activates.value(), 1u);
  EXPECT_EQ(d.stats().precharges.value(), 1u);
  EXPECT_EQ(d.traffic().reads(DramClass::Textures), 64u);
  EXPECT_EQ(d.traffic().writes(DramClass::Gbuffer), 64u);
  EXPECT_EQ(d.access_functional(16 * 4096 + 128, 20, false, DramClass::Other), RowOutcome::Hit);
  EXPECT_EQ(d.traffic().reads(DramClass::Other), 32u) << "rounded up to a whole burst";
}

TEST(DramTest, RejectsRowCrossingRequests) {
  const HwConfig hw = test_config();
  EventQueue eq;
  Dram d(hw.dram, hw.energy, eq);
  EXPECT_THROW(d.enqueue(DramRequest{4096 - 32, 64, false, DramClass::Other, {}}), std::invalid_argument);
  EXPECT_THROW(d.enqueue(DramRequest{0, 0, false, DramClass::Other, {}}), std::invalid_argument);
}

// ---------------------------------------------------------------------------------------------
// MemorySystem

struct Access {
  Client client;
  std::uint64_t addr;
  std::uint32_t bytes;
  bool is_write;
  DramClass cls;
};

/// A pseudo-random mix of every client: texture reads with reuse, vertex/index fetch, parameter
/// buffer writes then reads, tile loads and stores, compute buffers.
std::vector<Access> mixed_accesses(std::uint32_t seed, int n) {
  std::mt19937 rng(seed);
  std::vector<Access> v;
  for (int i = 0; i < n; ++i) {
    switch (rng() % 6) {
      case 0: v.push_back({Client::Texture, (1u << 20) + rng() % (512u << 10) / 16 * 16, 16, false, DramClass::Textures}); break;
      case 1: v.push_back({Client::Geometry, (4u << 20) + rng() % (256u << 10) / 32 * 32, 32, false,
                           rng() % 2 ? DramClass::Vertices : DramClass::Indices}); break;
      case 2: v.push_back({Client::Tiler, (8u << 20) + rng() % (1u << 20) / 64 * 64, 64, true, DramClass::ParameterBuffer}); break;
      case 3: v.push_back({Client::Isp, (8u << 20) + rng() % (1u << 20) / 64 * 64, 64, false, DramClass::ParameterBuffer}); break;
      case 4: v.push_back({Client::PixelBackEnd, (16u << 20) + rng() % (2u << 20) / 128 * 128, 128, rng() % 2 == 0,
                           DramClass::Color}); break;
      default: v.push_back({Client::Compute, (24u << 20) + rng() % (256u << 10) / 8 * 8, 8, rng() % 4 == 0,
                            DramClass::LightLists}); break;
    }
  }
  return v;
}

/// Issues `v` in order through the timed path, retrying refused requests when the memory system
/// is ready again; returns the number of refusals.
std::uint64_t run_timed(MemorySystem& m, EventQueue& eq, const std::vector<Access>& v, std::vector<Tick>* done = nullptr) {
  std::size_t next = 0;
  std::uint64_t refusals = 0;
  if (done) done->assign(v.size(), Tick{-1});
  std::function<void()> pump = [&] {
    while (next < v.size()) {
      const Access& a = v[next];
      const std::size_t i = next;
      if (!m.issue(a.client, a.addr, a.bytes, a.is_write, a.cls, [done, i, &eq] { if (done) (*done)[i] = eq.now(); })) {
        ++refusals;
        m.notify_when_ready([&] { pump(); });
        return;
      }
      ++next;
    }
  };
  pump();
  eq.run();
  EXPECT_EQ(next, v.size());
  EXPECT_EQ(m.requests_in_flight(), 0u);
  return refusals;
}

TEST(MemorySystemTest, HitAndMissLatencies) {
  const HwConfig hw = test_config();  // core 1 GHz: texture hit 4 cycles, SLC hit 20 cycles
  EventQueue eq;
  MemorySystem m(hw, eq);
  Tick t0{-1}, t1{-1}, t2{-1};
  // Texture read, cold: DRAM (30 + 18 + 15 + 10 + 30 = 103 ns, bank empty) + SLC 20 + L1 4.
  ASSERT_TRUE(m.issue(Client::Texture, 0x10000, 16, false, DramClass::Textures, [&] { t0 = eq.now(); }));
  eq.run();
  EXPECT_EQ(t0.ps(), (103 + 20 + 4) * kNs);
  // Same line again: L1 hit.
  const Tick s1 = eq.now();
  ASSERT_TRUE(m.issue(Client::Texture, 0x10000 + 32, 16, false, DramClass::Textures, [&] { t1 = eq.now(); }));
  eq.run();
  EXPECT_EQ((t1 - s1).ps(), 4 * kNs);
  // The compute client has no L1: the line is in the SLC.
  const Tick s2 = eq.now();
  ASSERT_TRUE(m.issue(Client::Compute, 0x10000, 64, false, DramClass::Textures, [&] { t2 = eq.now(); }));
  eq.run();
  EXPECT_EQ((t2 - s2).ps(), 20 * kNs);
  EXPECT_EQ(m.dram().stats().reads.value(), 1u);
  EXPECT_EQ(m.texture_cache().stats().read_hits.value(), 1u);
  EXPECT_EQ(m.slc().stats().read_hits.value(), 1u);
}

/// The tick a texture-cache hit issued at `at` (a warm line, nothing else in flight) completes at,
/// with the core at `core_mhz`.
Tick texture_hit_done(double core_mhz, Tick at) {
  const HwConfig hw = test_config({"gpu.core_clock_mhz=" + std::to_string(core_mhz)});
  EventQueue eq;
  MemorySystem m(hw, eq);
  EXPECT_TRUE(m.issue(Client::Texture, 0x10000, 16, false, DramClass::Textures));  // warm the line
  eq.run();
  EXPECT_LT(eq.now(), at);
  Tick done{-1};
  eq.schedule(at, [&] { EXPECT_TRUE(m.issue(Client::Texture, 0x10000, 16, false, DramClass::Textures, [&] { done = eq.now(); })); });
  eq.run();
  return done;
}

TEST(MemorySystemTest, HitLatencyCountsCoreCyclesFromTheNextCoreEdge) {
  // A hit issued between two core edges is served from the next edge on, hit_latency_cycles
  // (4 for the texture cache) later: issued at tick 1e9 + 700 ps, it completes at
  // tick_of(edge_index(t) + 4), at 600 MHz (a period of 5000/3 ps: edges fall between
  // picoseconds) as at 300 MHz. Half the clock doubles the cycles' length: the same hit takes 4
  // periods of 3,333.3 ps instead of 1,666.7 ps, plus the wait for the next edge (under a period).
  const Tick at{1'000'000'700};
  const std::int64_t hit_cycles = test_config().cache.texture.hit_latency_cycles;
  ASSERT_EQ(hit_cycles, 4);
  for (const double mhz : {600.0, 300.0}) {
    const ClockDomain core = ClockDomain::from_mhz("core", mhz);
    const Tick want = core.tick_of(core.edge_index(at) + Cycles{hit_cycles});
    EXPECT_EQ(texture_hit_done(mhz, at), want) << mhz << " MHz";
  }
  // 600 MHz: 4 periods, 6,666.7 ps, plus the wait; 300 MHz: 13,333.3 ps plus its wait.
  const std::int64_t fast = (texture_hit_done(600.0, at) - at).ps(), slow = (texture_hit_done(300.0, at) - at).ps();
  std::printf("[ hit      ] 600 MHz %lld ps, 300 MHz %lld ps\n", static_cast<long long>(fast), static_cast<long long>(slow));
  EXPECT_GE(fast, 6666);
  EXPECT_LE(fast, 6666 + 1667);
  EXPECT_GE(slow, 13333);
  EXPECT_LE(slow, 13333 + 3334);
  EXPECT_GT(slow, fast);
}

TEST(MemorySystemTest, MissLatencyGrowsWhenTheDramClockSlowsDown) {
  // A cold texture read at a 1000 MHz DRAM clock takes the 103 ns of DRAM timings plus the SLC
  // and L1 latencies (HitAndMissLatencies); at 400 MHz each ns-based timing is rounded up to
  // whole 2.5 ns DRAM cycles from the next DRAM edge, and the burst takes longer on the bus: the
  // same miss is slower, by less than the roundings (5 timings x 2.5 ns) plus a burst.
  auto cold_read = [](const std::string& dram_mhz) {
    const HwConfig hw = test_config({"dram.clock_mhz=" + dram_mhz});
    EventQueue eq;
    MemorySystem m(hw, eq);
    Tick done{-1};
    EXPECT_TRUE(m.issue(Client::Texture, 0x10000, 16, false, DramClass::Textures, [&] { done = eq.now(); }));
    eq.run();
    return done.ps();
  };
  const std::int64_t fast = cold_read("1000"), slow = cold_read("400");
  std::printf("[ miss     ] DRAM 1000 MHz %lld ps, 400 MHz %lld ps\n", static_cast<long long>(fast), static_cast<long long>(slow));
  EXPECT_EQ(fast, (103 + 20 + 4) * kNs);
  EXPECT_GT(slow, fast);
  EXPECT_LT(slow, fast + 5 * 2500 + 10 * kNs);
}

TEST(MemorySystemTest, RequestsToALineBeingFetchedWaitForIt) {
  const HwConfig hw = test_config();
  EventQueue eq;
  MemorySystem m(hw, eq);
  Tick a{-1}, b{-1}, c{-1};
  ASSERT_TRUE(m.issue(Client::Texture, 0x20000, 16, false, DramClass::Textures, [&] { a = eq.now(); }));
  ASSERT_TRUE(m.issue(Client::Texture, 0x20010, 16, false, DramClass::Textures, [&] { b = eq.now(); }));
  // A multi-line request: one line being fetched, one new; done when both are.
  ASSERT_TRUE(m.issue(Client::Texture, 0x20030, 32, false, DramClass::Textures, [&] { c = eq.now(); }));
  eq.run();
  EXPECT_EQ(a.ps(), 127 * kNs);
  EXPECT_EQ(b, a) << "the second access waits for the fill instead of hitting early";
  EXPECT_GE(c, a);
  EXPECT_EQ(m.dram().stats().reads.value(), 2u);
  EXPECT_EQ(m.stats().merged_misses.value(), 2u);
  EXPECT_EQ(m.texture_cache().stats().read_misses.value(), 2u);
}

TEST(MemorySystemTest, L1LinesWiderThanSlcLines) {
  HwConfig hw = test_config();
  hw.cache.texture.line_bytes = 128;  // an L1 miss needs two SLC lines
  EventQueue eq;
  MemorySystem m(hw, eq);
  Tick done{-1};
  ASSERT_TRUE(m.issue(Client::Texture, 0x30000, 16, false, DramClass::Textures, [&] { done = eq.now(); }));
  eq.run();
  EXPECT_EQ(m.dram().stats().reads.value(), 2u);
  EXPECT_EQ(m.traffic().reads(DramClass::Textures), 128u);
  // Both lines in the same row: the second is a row hit 10 ns behind the first.
  EXPECT_EQ(done.ps(), (103 + 10 + 20 + 4) * kNs);
  // And the functional path agrees on a mixed workload.
  EventQueue eq_t, eq_f;
  MemorySystem t(hw, eq_t), f(hw, eq_f);
  const std::vector<Access> v = mixed_accesses(21, 5000);
  run_timed(t, eq_t, v);
  for (const Access& a : v) f.access_functional(a.client, a.addr, a.bytes, a.is_write, a.cls);
  EXPECT_EQ(t.traffic().read_bytes, f.traffic().read_bytes);
  EXPECT_EQ(t.traffic().write_bytes, f.traffic().write_bytes);
}

TEST(MemorySystemTest, CachesDisabledDramSeesExactlyTheIssuedBytes) {
  const HwConfig hw = test_config();
  const std::vector<Access> v = mixed_accesses(3, 4000);
  DramTraffic issued;
  for (const Access& a : v) {
    // Round to whole bursts as DRAM transfers them (every access here is burst-aligned or smaller
    // than a burst within one burst).
    const std::uint64_t start = a.addr / 32 * 32, end = (a.addr + a.bytes + 31) / 32 * 32;
    if (a.is_write) issued.write(a.cls, end - start); else issued.read(a.cls, end - start);
  }
  for (const bool timed : {true, false}) {
    EventQueue eq;
    MemorySystem m(hw, eq, "mem", MemorySystemOptions{.caches_enabled = false});
    if (timed) {
      run_timed(m, eq, v);
    } else {
      for (const Access& a : v) m.access_functional(a.client, a.addr, a.bytes, a.is_write, a.cls);
    }
    const DramTraffic t = m.traffic();
    for (std::size_t c = 0; c < kDramClassCount; ++c) {
      EXPECT_EQ(t.read_bytes[c], issued.read_bytes[c]) << to_string(static_cast<DramClass>(c)) << " timed=" << timed;
      EXPECT_EQ(t.write_bytes[c], issued.write_bytes[c]) << to_string(static_cast<DramClass>(c)) << " timed=" << timed;
    }
    EXPECT_EQ(m.slc().stats().reads.value() + m.slc().stats().writes.value(), 0u);
  }
}

TEST(MemorySystemTest, CachesEnabledDramBytesAreMissesTimesLines) {
  const HwConfig hw = test_config();
  EventQueue eq;
  MemorySystem m(hw, eq);
  // Cached clients only (no streaming): every DRAM read is an SLC read miss, every DRAM write a
  // dirty SLC line written back (by eviction or the final flush).
  std::vector<Access> v;
  for (const Access& a : mixed_accesses(11, 20000)) {
    if (a.client != Client::PixelBackEnd) v.push_back(a);
  }
  run_timed(m, eq, v);
  bool flushed = false;
  m.flush([&] { flushed = true; });
  eq.run();
  EXPECT_TRUE(flushed);
  const CacheStats& slc = m.slc().stats();
  const DramTraffic t = m.traffic();
  EXPECT_EQ(t.total_read(), slc.read_misses.value() * 64);
  EXPECT_EQ(t.total_written(), (slc.dirty_evictions.value() + slc.flush_writebacks.value()) * 64);
  for (std::size_t c = 0; c < kDramClassCount; ++c) {
    EXPECT_EQ(t.read_bytes[c], m.slc().class_stats(static_cast<DramClass>(c)).read_misses.value() * 64)
        << to_string(static_cast<DramClass>(c));
  }
  EXPECT_GT(slc.read_hits.value(), 0u);
  EXPECT_GT(m.texture_cache().stats().read_hits.value(), 0u);
  EXPECT_GT(t.total_written(), 0u);
}

TEST(MemorySystemTest, FunctionalAndTimedPathsCountTheSameBytes) {
  const HwConfig hw = test_config();
  const std::vector<Access> v = mixed_accesses(5, 30000);
  EventQueue eq_t, eq_f;
  MemorySystem timed(hw, eq_t), functional(hw, eq_f);
  run_timed(timed, eq_t, v);
  for (const Access& a : v) functional.access_functional(a.client, a.addr, a.bytes, a.is_write, a.cls);
  timed.flush();
  eq_t.run();
  functional.flush_functional();
  const DramTraffic a = timed.traffic(), b = functional.traffic();
  for (std::size_t c = 0; c < kDramClassCount; ++c) {
    EXPECT_EQ(a.read_bytes[c], b.read_bytes[c]) << to_string(static_cast<DramClass>(c));
    EXPECT_EQ(a.write_bytes[c], b.write_bytes[c]) << to_string(static_cast<DramClass>(c));
  }
  for (Cache* c : {&timed.texture_cache(), &timed.vertex_cache(), &timed.slc()}) {
    Cache& f = c == &timed.texture_cache() ? functional.texture_cache()
               : c == &timed.vertex_cache() ? functional.vertex_cache()
                                             : functional.slc();
    EXPECT_EQ(c->stats().read_hits.value(), f.stats().read_hits.value());
    EXPECT_EQ(c->stats().write_misses.value(), f.stats().write_misses.value());
    EXPECT_EQ(c->stats().dirty_evictions.value(), f.stats().dirty_evictions.value());
  }
  EXPECT_GT(a.reads(DramClass::Color), 0u);
  EXPECT_GT(a.writes(DramClass::Color), 0u);
  EXPECT_GT(a.reads(DramClass::Textures), 0u);
}

TEST(MemorySystemTest, ConsecutiveMissesOfARowFormOneBurstChain) {
  // A 4 KiB tile load (one row of one channel) streams past the SLC as 64 line misses. With
  // 1 KiB chains they are 4 queue entries; statistics still count 64 line requests, the first a
  // row miss (bank empty) and 63 row hits. Either way the data bus carries 64 x 10 ns back to back:
  // done at 30 (controller) + 18 (tRCD) + 15 (RL) + 640 (data) + 30 (controller) = 733 ns, plus
  // the SLC lookup that found the misses (20 ns).
  for (const std::int64_t chain : {std::int64_t{0}, std::int64_t{1024}}) {
    const HwConfig hw = test_config({"dram.max_chain_bytes=" + std::to_string(chain)});
    EventQueue eq;
    MemorySystem m(hw, eq);
    Tick done{-1};
    ASSERT_TRUE(m.issue(Client::PixelBackEnd, 0x100000, 4096, false, DramClass::Color, [&] { done = eq.now(); }));
    eq.run();
    const DramStats& s = m.dram().stats();
    EXPECT_EQ(s.reads.value(), 64u) << chain;
    EXPECT_EQ(s.queue_entries_served.value(), chain == 0 ? 64u : 4u) << chain;
    EXPECT_EQ(s.row_hits.value(), 63u) << chain;
    EXPECT_EQ(s.row_misses.value(), 1u) << chain;
    EXPECT_EQ(s.activates.value(), 1u) << chain;
    EXPECT_EQ(m.traffic().reads(DramClass::Color), 4096u) << chain;
    EXPECT_EQ(done.ps(), (733 + 20) * kNs) << chain;
  }
  // A chain never takes more lines than a queue holds: 8-entry queues, 4 KiB chains -> 8 lines each.
  const HwConfig hw = test_config({"dram.max_chain_bytes=4096", "dram.read_queue_entries=8"});
  EventQueue eq;
  MemorySystem m(hw, eq);
  ASSERT_TRUE(m.issue(Client::PixelBackEnd, 0x100000, 4096, false, DramClass::Color));
  eq.run();
  EXPECT_EQ(m.dram().stats().queue_entries_served.value(), 8u);
  EXPECT_EQ(m.dram().stats().reads.value(), 64u);
  // The functional path forms the same chains.
  EventQueue eq_f;
  MemorySystem f(hw, eq_f);
  f.access_functional(Client::PixelBackEnd, 0x100000, 4096, false, DramClass::Color);
  EXPECT_EQ(f.dram().stats().queue_entries_served.value(), 8u);
  EXPECT_EQ(f.dram().stats().row_hits.value(), 63u);
}

TEST(MemorySystemTest, EachLineOfAChainArrivesWithItsOwnBursts) {
  // A 1 KiB compute read misses 16 SLC lines: one chain whose data occupies the bus for 160 ns.
  // Its first line is back after 30 + 18 + 15 + 10 + 30 = 103 ns, the last after 253 ns; a
  // request for the first line issued at the same time waits only for that line.
  const HwConfig hw = test_config({"dram.max_chain_bytes=1024"});
  EventQueue eq;
  MemorySystem m(hw, eq);
  Tick whole{-1}, first{-1};
  ASSERT_TRUE(m.issue(Client::Compute, 0x40000, 1024, false, DramClass::LightLists, [&] { whole = eq.now(); }));
  ASSERT_TRUE(m.issue(Client::Compute, 0x40000, 64, false, DramClass::LightLists, [&] { first = eq.now(); }));
  eq.run();
  EXPECT_EQ(whole.ps(), (253 + 20) * kNs);
  EXPECT_EQ(first.ps(), (103 + 20) * kNs);
  EXPECT_EQ(m.dram().stats().queue_entries_served.value(), 1u);
  EXPECT_EQ(m.stats().merged_misses.value(), 1u);
  // Mean read latency per line: (103 + 113 + ... + 253) / 16 = 178 ns.
  m.dram().update_derived_stats();
  EXPECT_DOUBLE_EQ(m.dram().stats().avg_read_latency_ns.value(), 178.0);
}

TEST(MemorySystemTest, RefusedRequestersAreAdmittedBeforeAnyoneElse) {
  // A fills the memory system with 4 KiB reads until it is refused. B is then refused and waits.
  // Between every two events C tries to issue; none of its tries may succeed before B has been
  // admitted, even at the moments the DRAM has just made room (a unit that happens to issue then
  // must not take the place of one that was waiting: that starved Forward+'s first tiles).
  const HwConfig hw = test_config();
  EventQueue eq;
  MemorySystem m(hw, eq);
  std::uint64_t a = 0;
  while (m.issue(Client::PixelBackEnd, 0x1000000 + a * 4096, 4096, false, DramClass::Color)) ++a;
  ASSERT_GE(a, 1u);
  bool b_admitted = false;
  std::function<void()> try_b = [&] {
    if (m.issue(Client::Compute, 0x100000, 64, false, DramClass::LightLists)) {
      b_admitted = true;
    } else {
      m.notify_when_ready([&] { try_b(); });
    }
  };
  try_b();
  ASSERT_FALSE(b_admitted) << "the queues are full";
  std::uint64_t c_tries = 0, c_before_b = 0;
  while (!b_admitted && eq.step()) {
    if (b_admitted) break;  // that event admitted B
    ++c_tries;
    if (m.issue(Client::Compute, 0x200000 + c_tries * 64, 64, false, DramClass::LightLists)) ++c_before_b;
  }
  EXPECT_TRUE(b_admitted);
  EXPECT_GE(c_tries, 1u);
  EXPECT_EQ(c_before_b, 0u) << "C was admitted while B waited";
  eq.run();
  EXPECT_EQ(m.requests_in_flight(), 0u);
}

TEST(MemorySystemTest, PixelBackEndStreamsPastTheSlc) {
  const HwConfig hw = test_config();
  EventQueue eq;
  MemorySystem m(hw, eq);
  // A 32x32 RGBA8 tile store (4 KiB) and a load of another tile: nothing is allocated.
  m.access_functional(Client::PixelBackEnd, 0x100000, 4096, true, DramClass::Color);
  m.access_functional(Client::PixelBackEnd, 0x200000, 4096, false, DramClass::DepthStencil);
  EXPECT_EQ(m.traffic().writes(DramClass::Color), 4096u);
  EXPECT_EQ(m.traffic().reads(DramClass::DepthStencil), 4096u);
  EXPECT_FALSE(m.slc().probe(0x100000));
  EXPECT_FALSE(m.slc().probe(0x200000));
  EXPECT_EQ(m.slc().stats().bypasses.value(), 128u);
}

TEST(MemorySystemTest, BackpressurePropagatesAndNothingIsLost) {
  const HwConfig hw = test_config({"dram.read_queue_entries=4"});
  EventQueue eq;
  MemorySystem m(hw, eq);
  // 2000 texture reads of distinct lines in one 4 KiB-row-sized stripe per channel: misses all the way.
  std::vector<Access> v;
  for (std::uint64_t i = 0; i < 2000; ++i) v.push_back({Client::Texture, i * 64, 4, false, DramClass::Textures});
  std::vector<Tick> done;
  const std::uint64_t refusals = run_timed(m, eq, v, &done);
  EXPECT_GT(refusals, 0u);
  EXPECT_GT(m.stats().dram_overflows.value(), 0u);
  for (std::size_t i = 0; i < done.size(); ++i) ASSERT_GE(done[i].ps(), 0) << i;
  EXPECT_EQ(m.dram().stats().reads.value(), 2000u);
  EXPECT_EQ(m.client_stats(Client::Texture).completed.value(), 2000u);
  EXPECT_EQ(m.client_stats(Client::Texture).rejected.value(), refusals);
  EXPECT_FALSE(m.has_pending_work());
}

/// Streams `total` bytes of tile loads (or stores) in 1 KiB requests from one in-order source
/// with up to 64 requests outstanding (as the pixel back end issues them) through `m`; returns
/// the bytes issued (all of them once the queue has run dry).
std::uint64_t stream_tile_traffic(MemorySystem& m, EventQueue& eq, std::uint64_t total, bool write) {
  constexpr std::uint64_t kChunk = 1024;
  std::uint64_t next = 0;
  int outstanding = 0;
  bool waiting = false;
  std::function<void()> pump = [&] {
    waiting = false;
    while (next < total && outstanding < 64) {
      if (!m.issue(Client::PixelBackEnd, (1u << 20) + next, kChunk, write, DramClass::Color, [&] {
            --outstanding;
            if (!waiting) pump();
          })) {
        waiting = true;
        m.notify_when_ready([&] { pump(); });
        return;
      }
      ++outstanding;
      next += kChunk;
    }
  };
  pump();
  eq.run();
  return next;
}

TEST(MemorySystemTest, StreamingReachesDramBandwidth) {
  // 4 MiB of tile loads, then of tile stores (stream_tile_traffic), on both shipped DRAM presets.
  // Bound: 4 MiB / (peak bandwidth x refresh efficiency), where each refresh idles the bus
  // for [tWR after the last write +] tRP + tRFC + tRCD + RL per tREFI (LPDDR3 loads: 1 - 182.5 /
  // 3900 = 95.3 %; LPDDR4X loads: 1 - 333.5 / 3904 = 91.5 %). The overflow queue in front of each
  // DRAM channel lets the source run ahead of a full channel, so the stream must come within 5 %
  // of it. (LPDDR4X lands about 3 % below: its 280 ns refresh outlasts the 4 KiB the other
  // channel has queued, and the in-order source waits on the refreshing one.)
  const std::string dir = std::string(TBDRSIM_SOURCE_DIR) + "/configs/";
  for (const std::string preset : {"series6xt_gx6450.ini", "mobile_16x16_lpddr4x.ini"}) {
    const HwConfig hw = resolve_config({dir + preset}, {}).hw;
    for (const bool write : {false, true}) {
      EventQueue eq;
      MemorySystem m(hw, eq);
      constexpr std::uint64_t kTotal = 4u << 20;
      ASSERT_EQ(stream_tile_traffic(m, eq, kTotal, write), kTotal);
      const auto& p = hw.dram;
      const double lost_ns = (write ? p.t_wr_ns : 0.0) + p.t_rp_ns + p.t_rfc_ns + p.t_rcd_ns + p.t_cl_ns;
      const double bound_ps = static_cast<double>(kTotal) / hw.dram.peak_bandwidth_gbps() * 1000.0 / (1.0 - lost_ns / p.t_refi_ns);
      const double took_ps = static_cast<double>(eq.now().ps());
      std::cout << "[ figures  ] " << preset << (write ? " stores" : " loads") << ": " << 100.0 * bound_ps / took_ps
                << " % of " << hw.dram.peak_bandwidth_gbps() << " GB/s less refresh ("
                << 100.0 * (1.0 - lost_ns / p.t_refi_ns) << " % of it)\n";
      EXPECT_LE(took_ps, 1.05 * bound_ps) << preset << " write=" << write;
      EXPECT_EQ(write ? m.traffic().writes(DramClass::Color) : m.traffic().reads(DramClass::Color), kTotal);
    }
  }
}

// The overflow queues in front of the DRAM channels (a reused ring, kernel/ring_queue.hpp) let one
// in-order stream keep both channels busy when the DRAM's own queues are shallow: the source runs
// ahead of a full channel into the next 4 KiB, which the other channel serves. 2 MiB of tile
// loads with 8-entry DRAM read queues (series6xt_gx6450 otherwise): the DRAM bound is 2 MiB /
// (12.8 GB/s x 95.4 % after refresh) = 171.8 us. With room for one line only (0 entries: refused
// as soon as a DRAM queue overflows) the source waits on whichever channel is full while the
// other drains and idles: measured 285 us, 1.66x the bound (the channels mostly take turns);
// 32 entries (the default) 178 us; 128 entries 172 us, the bound. More room never slows the
// stream. (With the default 32-entry DRAM queues those hold enough: 0 entries 200 us at 16, 172
// us at 32.)
TEST(MemorySystemTest, OverflowRoomLetsOneStreamKeepBothChannelsBusy) {
  const HwConfig hw =
      resolve_config({std::string(TBDRSIM_SOURCE_DIR) + "/configs/series6xt_gx6450.ini"}, {"dram.read_queue_entries=8"}).hw;
  constexpr std::uint64_t kTotal = 2u << 20;
  const double bound_ps = static_cast<double>(kTotal) / hw.dram.peak_bandwidth_gbps() * 1000.0;  // (before refresh)
  std::vector<double> took;
  for (const std::uint32_t entries : {0u, 8u, 32u, 128u}) {
    EventQueue eq;
    MemorySystem m(hw, eq, "mem", MemorySystemOptions{.overflow_entries = entries});
    ASSERT_EQ(stream_tile_traffic(m, eq, kTotal, false), kTotal);
    EXPECT_EQ(m.traffic().reads(DramClass::Color), kTotal);
    EXPECT_FALSE(m.has_pending_work());
    took.push_back(static_cast<double>(eq.now().ps()));
    std::cout << "[ figures  ] overflow_entries " << entries << ": " << took.back() / 1e6 << " us\n";
  }
  for (std::size_t i = 1; i < took.size(); ++i) EXPECT_LE(took[i], took[i - 1]) << "more overflow room made the stream slower";
  EXPECT_GT(took[0], 1.4 * took[2]) << "one line of room should leave a channel idle much of the time";
  EXPECT_LT(took[3], 1.10 * bound_ps) << "with room to run ahead, the stream reaches the DRAM's bandwidth";
}

TEST(MemorySystemTest, FlushWritesBackDirtyLines) {
  const HwConfig hw = test_config();
  EventQueue eq;
  MemorySystem m(hw, eq);
  bool written = false;
  ASSERT_TRUE(m.issue(Client::Tiler, 0x40000, 1024, true, DramClass::ParameterBuffer, [&] { written = true; }));
  eq.run();
  EXPECT_TRUE(written);
  EXPECT_EQ(m.traffic().total_written(), 0u) << "write-back: still in the SLC";
  Tick flushed{-1};
  m.flush([&] { flushed = eq.now(); });
  eq.run();
  EXPECT_GT(flushed.ps(), 0);
  EXPECT_EQ(m.traffic().writes(DramClass::ParameterBuffer), 1024u);
  // The ISP reads the parameter buffer back through the vertex cache: SLC hits, no DRAM reads.
  m.access_functional(Client::Isp, 0x40000, 1024, false, DramClass::ParameterBuffer);
  EXPECT_EQ(m.traffic().total_read(), 0u);
  EXPECT_EQ(m.slc().stats().read_hits.value(), 16u);
}

TEST(MemorySystemTest, DeterministicAndCollects) {
  const HwConfig hw = test_config();
  const std::vector<Access> v = mixed_accesses(9, 5000);
  std::vector<Tick> done[2];
  std::vector<StatRecord> stats[2];
  for (int k = 0; k < 2; ++k) {
    EventQueue eq;
    MemorySystem m(hw, eq, "frame/mem");
    run_timed(m, eq, v, &done[k]);
    append_memory_rows(m.snapshot(), stats[k]);
  }
  EXPECT_EQ(done[0], done[1]);
  ASSERT_EQ(stats[0].size(), stats[1].size());
  for (std::size_t i = 0; i < stats[0].size(); ++i) EXPECT_EQ(stats[0][i].value, stats[1][i].value) << stats[0][i].name;
  bool dram = false, client = false;
  for (const StatRecord& r : stats[0]) {
    dram |= r.scope == "frame/mem/dram.class.color" && r.name == "read_bytes";
    client |= r.scope == "frame/mem/client.texture" && r.name == "avg_latency_ns" && r.value > 0;
  }
  EXPECT_TRUE(dram);
  EXPECT_TRUE(client);
}

TEST(MemorySystemTest, EnergyIsCachesPlusDram) {
  const HwConfig hw = test_config();
  EventQueue eq;
  MemorySystem m(hw, eq);
  for (const Access& a : mixed_accesses(13, 2000)) m.access_functional(a.client, a.addr, a.bytes, a.is_write, a.cls);
  const double caches = m.texture_cache().energy_pj() + m.vertex_cache().energy_pj() + m.slc().energy_pj();
  EXPECT_DOUBLE_EQ(m.energy_pj(), caches + m.dram().energy_pj());
  EXPECT_GT(m.dram().energy_pj(), 0.0);
  EXPECT_GT(caches, 0.0);
}

/// Accesses per second of CPU time (not wall-clock: the test machine may be shared).
template <class Fn>
double rate_per_cpu_second(std::size_t accesses, Fn&& fn) {
  const std::clock_t c0 = std::clock();
  fn();
  const double s = static_cast<double>(std::clock() - c0) / CLOCKS_PER_SEC;
  return static_cast<double>(accesses) / std::max(s, 1e-9);
}

TEST(MemorySystemTest, Throughput) {
  // Not a pass/fail figure: prints accesses per CPU second of both paths for two texture
  // workloads, "hits" (a 8 KiB working set: all texture cache hits) and "misses" (uniform over a
  // 2 MiB texture: almost every fetch goes to DRAM), 16 B fetches in pairs.
  const HwConfig hw = resolve_config({}, {}).hw;
  for (const bool misses : {false, true}) {
    std::mt19937 rng(1);
    std::vector<Access> v;
    for (int i = 0; i < 250'000; ++i) {
      const std::uint64_t base = misses ? (1u << 20) + (rng() % (2u << 20)) / 32 * 32
                                        : (1u << 20) + static_cast<std::uint64_t>(i) * 32 % (8u << 10);
      v.push_back({Client::Texture, base, 16, false, DramClass::Textures});
      v.push_back({Client::Texture, base + 16, 16, false, DramClass::Textures});
    }
    EventQueue eq_f, eq_t;
    MemorySystem f(hw, eq_f), t(hw, eq_t);
    const double functional = rate_per_cpu_second(4 * v.size(), [&] {
      for (int rep = 0; rep < 4; ++rep) {
        for (const Access& a : v) f.access_functional(a.client, a.addr, a.bytes, a.is_write, a.cls);
      }
    });
    const double timed = rate_per_cpu_second(v.size(), [&] { run_timed(t, eq_t, v); });
    std::cout << "[ figures  ] " << (misses ? "misses" : "hits") << ": functional " << functional / 1e6
              << " M accesses/s, timed " << timed / 1e6 << " M accesses/s ("
              << static_cast<double>(eq_t.events_executed()) / static_cast<double>(v.size()) << " events/access, "
              << eq_t.now().seconds() * 1e6 << " us simulated, DRAM reads " << t.dram().stats().reads.value() << ")\n";
    EXPECT_GT(functional, 0.0);
    EXPECT_GT(timed, 0.0);
  }
}

}  // namespace
}  // namespace tbdr
