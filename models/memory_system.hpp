#pragma once
// The memory system as the GPU units see it (a DRAMsim3-style facade): per-client L1 caches
// (texture cache; vertex / parameter-buffer cache), the system level cache (SLC) in front of
// DRAM, and the DRAM controller, all on one event queue. A unit calls issue() with a byte range;
// the facade splits it into lines, walks each line through the client's L1 (if any), the SLC and
// DRAM, and calls the unit back once every line is done. The functional fast path,
// access_functional(), makes exactly the same cache decisions and DRAM byte counts without timing.
//
// Routing (Client -> levels):
//   Geometry      vertex/index fetch       vertex cache -> SLC -> DRAM
//   Tiler         parameter buffer writes  SLC (write-allocate) -> DRAM
//   Isp           parameter buffer reads   vertex cache -> SLC -> DRAM
//   Texture       texel fetch              texture cache -> SLC -> DRAM
//   PixelBackEnd  tile loads/stores        SLC, streaming (misses bypass to DRAM) -> DRAM
//   Compute       buffers                  SLC -> DRAM
//   Rop           gpu.mode=imr: the ROP caches' misses and write-backs   SLC -> DRAM
// See docs/memory-model.md.
#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "models/address_space.hpp"
#include "models/cache.hpp"
#include "models/dram.hpp"
#include "models/hw_config.hpp"
#include "trace/traffic.hpp"
#include "kernel/event_queue.hpp"
#include "kernel/ring_queue.hpp"
#include "kernel/run_loop.hpp"
#include "kernel/slot_pool.hpp"
#include "kernel/stats.hpp"
#include "kernel/time.hpp"

namespace tbdr {

/// A GPU unit that issues memory requests; selects the path through the caches.
enum class Client : std::uint8_t {
  Geometry,      ///< vertex and index fetch, through the vertex cache
  Tiler,         ///< parameter buffer writes: no L1, through the SLC
  Isp,           ///< parameter buffer reads, through the vertex cache
  Texture,       ///< texture fetch, through the texture cache
  PixelBackEnd,  ///< tile loads and stores: streaming through the SLC (no allocation on a miss)
  Compute,       ///< compute buffers: no L1, through the SLC
  Rop,           ///< gpu.mode=imr: the ROP caches' misses and write-backs (models/rop.hpp), through the SLC
  Count
};
inline constexpr std::size_t kClientCount = static_cast<std::size_t>(Client::Count);
/// Statistics name of a client ("texture", ...).
const char* to_string(Client c);

/// Construction options that are not hardware parameters.
struct MemorySystemOptions {
  /// false: no cache at all; every access goes straight to DRAM in whole bursts (for tests and
  /// for "what if there were no caches" studies).
  bool caches_enabled = true;
  /// DRAM requests the memory system holds per channel and direction when that channel's DRAM
  /// queue is full (the SLC miss / interconnect queue in front of the controller). issue()
  /// refuses new requests while any of these holds this many or more. 0: refuse as soon as any
  /// DRAM queue overflows. With 32-entry DRAM queues and a 4 KiB channel interleave, an in-order
  /// stream needs about 32 here to keep both channels busy (see docs/memory-model.md).
  std::uint32_t overflow_entries = 32;
};

// Declared once: X(type, member = stored name, unit, Sum | Gauge, description).
#define TBDR_MEMORY_CLIENT_STATS(X) \
  X(Counter, reads, "requests", Sum, "Read requests accepted") \
  X(Counter, writes, "requests", Sum, "Write requests accepted") \
  X(Counter, read_bytes, "bytes", Sum, "Bytes read by accepted requests") \
  X(Counter, write_bytes, "bytes", Sum, "Bytes written by accepted requests") \
  X(Counter, rejected, "requests", Sum, "issue() calls refused (backpressure); the unit retries") \
  X(Counter, completed, "requests", Sum, "Timed requests completed") \
  X(Counter, latency_total_ps, "ps", Sum, "Sum of timed request latencies (issue to callback)") \
  X(Counter, functional_accesses, "requests", Sum, "Requests made through the functional path") \
  X(Accumulator, avg_latency_ns, "ns", Derived, "Mean timed request latency")
/// Requests of one client as issued to the memory system.
struct MemoryClientStats {
  TBDR_STATS(TBDR_MEMORY_CLIENT_STATS)
};

// Declared once: X(type, member = stored name, unit, Sum | Gauge, description).
#define TBDR_MEMORY_SYSTEM_STATS(X) \
  X(Counter, dram_overflows, "requests", Sum, "DRAM requests held back because their DRAM queue was full") \
  X(Counter, merged_misses, "accesses", Sum, "Accesses that found their line already being fetched and waited for it") \
  X(Counter, flushes, "flushes", Sum, "Cache flushes (dirty lines written back)") \
  X(Accumulator, cache_energy_pj, "pJ", Sum, "Energy of the texture, vertex and system level caches") \
  X(Accumulator, dram_energy_pj, "pJ", Sum, "DRAM energy") \
  X(Accumulator, energy_pj, "pJ", Sum, "Caches + DRAM energy")
/// Statistics of the memory system as a whole.
struct MemorySystemStats {
  TBDR_STATS(TBDR_MEMORY_SYSTEM_STATS)
};

/// Caches + DRAM behind one interface, in timed and functional flavours.
/// The memory system's statistics at one moment (MemorySystem::snapshot): its own, each client's,
/// each cache's and the DRAM's, with the scopes their rows take.
struct MemorySnapshot {
  std::string scope;  ///< "mem"; a client's rows: scope + "/client." + client
  MemorySystemStats stats;
  std::array<MemoryClientStats, kClientCount> clients;
  std::vector<CacheSnapshot> caches;  ///< texture, vertex, SLC
  DramSnapshot dram;
};

class MemorySystem final : public Unit {
 public:
  /// Builds the caches from hw.cache.*, the DRAM from hw.dram/hw.energy, the core clock from
  /// hw.gpu.core_clock_mhz. Statistics scopes are "<scope>", "<scope>/client.<name>",
  /// "<scope>/cache.<name>", "<scope>/dram...".
  MemorySystem(const HwConfig& hw, EventQueue& eq, std::string scope = "mem", MemorySystemOptions opt = {});
  MemorySystem(const MemorySystem&) = delete;
  MemorySystem& operator=(const MemorySystem&) = delete;

  /// Timed access of [addr, addr + bytes). False (and nothing happens but a `rejected` count)
  /// while the memory system is backpressured: the caller keeps the request, counts its stall and
  /// retries (notify_when_ready tells it when). Otherwise `on_complete` runs once, at the tick the
  /// last line of the range is back (reads) or accepted (writes are posted). Throws on bytes == 0.
  bool issue(Client client, std::uint64_t addr, std::uint32_t bytes, bool is_write, DramClass cls,
             EventCallback on_complete = {});
  /// Functional access: the same cache and DRAM state and statistics updates, no events.
  void access_functional(Client client, std::uint64_t addr, std::uint32_t bytes, bool is_write, DramClass cls);

  /// Read requests of a client that the caller knows hit the client's L1 and does not simulate
  /// (a tile's re-reads of data it has requested once), tallied to be counted at once
  /// (count_l1_read_hits) as issue() and the L1 would count them: accepted requests, requested
  /// bytes, one read hit per line each touches, SRAM energy; no event, no cache state change.
  struct L1Hits {
    std::uint64_t requests = 0, lines = 0, bytes = 0;
    /// One request of `bytes` at `addr`, touching lines of `line_bytes` (a power of two).
    void add(std::uint64_t addr, std::uint32_t bytes_, std::uint64_t line_bytes) {
      ++requests;
      bytes += bytes_;
      lines += bytes_ == 0 ? 1 : (addr + bytes_ - 1) / line_bytes - addr / line_bytes + 1;
    }
  };
  /// Counts every request of `hits` (of `client`, class `cls`); the client must have an L1 (l1_of).
  void count_l1_read_hits(Client client, const L1Hits& hits, DramClass cls);
  /// Whether issue() would accept a request now.
  /// (Refused too while earlier refused requesters wait for their turn, unless it is theirs.)
  bool can_accept() const { return overflow_full_ == 0 && (ready_waiters_.empty() || serving_waiters_); }
  /// Runs `cb` (as an event) as soon as issue() can accept again; at once if it can now.
  void notify_when_ready(EventCallback cb);

  /// Timed: writes back every dirty line (L1s into the SLC, then the SLC to DRAM); `on_done` runs
  /// when DRAM has completed the last write. Lines stay valid and become clean.
  void flush(EventCallback on_done = {});
  /// Functional flush: the same writebacks, counted without timing.
  void flush_functional();

  /// The L1 a client goes through (nullptr: none).
  Cache* l1_of(Client c) const { return routes_[static_cast<std::size_t>(c)].l1; }
  Cache& texture_cache() { return *texture_; }
  Cache& vertex_cache() { return *vertex_; }
  Cache& slc() { return *slc_; }
  Dram& dram() { return dram_; }
  const Dram& dram() const { return dram_; }
  AddressSpace& address_space() { return space_; }
  const ClockDomain& core_clock() const { return core_; }
  bool caches_enabled() const { return caches_enabled_; }

  /// DRAM bytes per traffic class so far (after the caches).
  DramTraffic traffic() const { return dram_.traffic(); }
  /// Bytes the units asked for per traffic class so far (accepted timed requests, before the caches).
  const DramTraffic& requested() const { return requested_; }
  /// Caches + DRAM energy so far, pJ.
  double energy_pj() const;
  /// Timed requests accepted and not yet completed.
  std::uint64_t requests_in_flight() const { return live_txns_; }
  const MemoryClientStats& client_stats(Client c) const { return client_stats_[static_cast<std::size_t>(c)]; }
  const MemorySystemStats& stats() const { return stats_; }
  /// Every statistic of the memory system now, derived ones updated first.
  MemorySnapshot snapshot();
  /// Its own statistics now, the caches' and DRAM's energies up to now included (a sequence's
  /// frame ends: the energy of a frame is the difference from the frame before).
  MemorySystemStats energy_stats();

  // Unit (run-loop watchdog)
  std::string_view name() const override { return name_; }
  bool has_pending_work() const override { return live_txns_ != 0 || overflow_count_ != 0 || dram_.in_flight() != 0; }
  std::uint64_t progress() const override { return completed_ + dram_.progress(); }
  std::string stall_reason() const override;

 private:
  enum class WaiterKind : std::uint8_t { None, Txn, Fill };
  // Who waits for data at a level, and the core cycles to add when it arrives there.
  struct Waiter {
    std::uint32_t id = 0;
    std::uint32_t extra_cycles = 0;
    WaiterKind kind = WaiterKind::None;
  };
  // Completion is resolved, not simulated per line: a part (a line of a request, a source of a
  // fill) is "resolved" as soon as the tick its data arrives is known, which is when the DRAM
  // completion, a cache hit or a resolved fill below it is seen. A transaction runs one event, at
  // the latest tick of its parts; a fill needs no event at all (see resolve_fill()).
  // One issue() call in flight.
  struct Txn {
    EventCallback on_complete;
    Tick issued{0};
    Tick due{0};                // latest arrival tick of the parts resolved so far
    std::uint32_t remaining = 0;  // unresolved parts
    Client client = Client::Geometry;
  };
  // A line being fetched into `cache` (nullptr: a streaming read that allocates nothing).
  // While unresolved, accesses that find the line wait in `waiters`; once resolved, the fill is
  // recycled and the line keeps its arrival tick: an access before it gets its data then (a
  // merged miss), one after it is a plain hit.
  struct Fill {
    std::vector<Waiter> waiters;
    Cache* cache = nullptr;
    Tick due{0};
    std::uint32_t slot = 0;
    std::uint32_t parts = 0;  // unresolved sources (DRAM reads, SLC lines)
    std::uint32_t next_in_chain = UINT32_MAX;  // next fill served by the same DRAM burst chain
    std::uint32_t chain_bytes = 0;             // bytes of the chain this fill waits for
  };
  // Consecutive lines of one row and direction that the current walk sends to DRAM, gathered
  // into one request (burst chain) of at most dram.max_chain_bytes.
  struct Chain {
    std::uint64_t addr = 0;
    std::uint32_t bytes = 0;
    std::uint32_t lines = 0;
    DramClass cls = DramClass::Other;
    std::uint32_t first_fill = UINT32_MAX;  // reads: the fills the chain completes, linked
    std::uint32_t last_fill = UINT32_MAX;
  };
  // The path of a client.
  struct Route {
    Cache* l1 = nullptr;
    Allocation slc_alloc = Allocation::Allocate;
  };

  template <bool kTimed>
  void access(Client client, std::uint64_t addr, std::uint32_t bytes, bool is_write, DramClass cls, std::uint32_t txn);
  template <bool kTimed>
  void l1_access(Cache& l1, std::uint64_t addr, std::uint32_t bytes, bool is_write, DramClass cls, Waiter w);
  // [addr, addr + bytes) may span several SLC lines.
  template <bool kTimed>
  void slc_range(Allocation alloc, std::uint64_t addr, std::uint64_t bytes, bool is_write, DramClass cls, Waiter w);
  template <bool kTimed>
  void slc_access(Allocation alloc, std::uint64_t addr, std::uint32_t bytes, bool is_write, DramClass cls, Waiter w);
  // slc_access's work once the SLC answered `a` (its writeback, hit, fill or streaming miss).
  template <bool kTimed>
  void slc_after_lookup(const CacheAccess& a, std::uint64_t addr, std::uint32_t bytes, bool is_write, DramClass cls, Waiter w);
  // Straight to DRAM (streaming miss or no caches), whole bursts.
  template <bool kTimed>
  void dram_bypass(std::uint64_t addr, std::uint32_t bytes, bool is_write, DramClass cls, Waiter w);
  // A DRAM write (a line, or a chain of `lines` lines); counted by a timed flush in progress.
  template <bool kTimed>
  void dram_write_line(std::uint64_t addr, std::uint32_t bytes, DramClass cls, std::uint32_t lines = 1);
  // Adds a DRAM transfer to the read (fill != kNoFill or functional) or write chain, sending the
  // chain first if the transfer does not extend it.
  template <bool kTimed>
  void chain(bool is_write, std::uint64_t addr, std::uint32_t bytes, DramClass cls, std::uint32_t fill);
  template <bool kTimed>
  void send_chain(bool is_write);
  template <bool kTimed>
  void send_chains() {
    send_chain<kTimed>(false);
    send_chain<kTimed>(true);
  }
  // DRAM scheduled a read chain: each fill's line arrives after its share of the transfer.
  void resolve_chain(std::uint32_t first_fill, const DramSchedule& when);

  Tick core_after(Tick base, Cycles n);  // core_.after(base, n), memoised
  void ready(Waiter w);                       // data available at the waiter's level now
  void attach(std::uint32_t fill, Waiter w);  // data available when `fill` resolves
  // A line that hit in `cache` at `slot`: ready now, or when the fill still bringing it arrives.
  void hit(Cache& cache, std::uint32_t slot, Waiter w);
  // When the data of a line that hit in `cache` at `slot` with no fill pending is there, plus
  // `extra_cycles`: now, or its arrival tick if it is still on its way (a merged miss, counted).
  Tick known_arrival(const Cache& cache, std::uint32_t slot, std::uint32_t extra_cycles);
  void resolve(Waiter w, Tick arrival);       // one part of the waiter arrives at `arrival`
  void resolve_txn(std::uint32_t txn, Tick arrival);
  void resolve_fill(std::uint32_t fill, Tick arrival);
  std::uint32_t new_fill(Cache* cache, std::uint32_t slot);
  void finish_txn(std::uint32_t txn);
  void send(DramRequest&& req);
  void drain_overflow(std::uint32_t channel);
  template <bool kTimed>
  void flush_caches();

  std::string name_;
  EventQueue& eq_;
  ClockDomain core_;
  bool caches_enabled_;
  EnergyParams energy_;
  AddressSpace space_;
  std::unique_ptr<Cache> texture_;
  std::unique_ptr<Cache> vertex_;
  std::unique_ptr<Cache> slc_;
  Dram dram_;
  std::array<Route, kClientCount> routes_{};
  std::uint32_t burst_bytes_;
  std::uint64_t max_chain_bytes_;
  std::array<Chain, 2> chains_{};  // [0] reads, [1] writes

  Tick memo_base_{-1};
  std::int64_t memo_edge_ = 0, memo_cycles_ = -1;
  Tick memo_tick_{0};
  SlotPool<Txn> txns_;
  std::uint64_t live_txns_ = 0;
  std::uint64_t completed_ = 0;
  SlotPool<Fill> fills_;

  // DRAM requests refused by a full DRAM queue, per channel and direction, in order.
  std::vector<std::array<RingQueue<DramRequest>, 2>> overflow_;
  std::vector<std::array<std::size_t, 2>> overflow_lines_;  // lines held per queue
  std::uint64_t overflow_count_ = 0;  // requests in all overflow queues
  std::uint32_t overflow_full_ = 0;   // overflow queues holding their cap of lines or more
  std::size_t overflow_cap_;
  std::vector<EventCallback> ready_waiters_;  // refused requesters, in order
  // The waiters being served (schedule_waiters): swapped with ready_waiters_, so that neither
  // gives its storage up (a refused stream's wait would otherwise allocate it again each time).
  std::vector<EventCallback> serving_;
  bool waiters_scheduled_ = false;            // an event will serve them
  bool serving_waiters_ = false;              // that event is running: they may issue
  void schedule_waiters();
  // Timed flush in progress: outstanding DRAM writes (+1 while the flush is being issued).
  bool flushing_ = false;
  std::uint64_t flush_outstanding_ = 0;
  std::vector<EventCallback> flush_done_;

  MemorySystemStats stats_;
  std::array<MemoryClientStats, kClientCount> client_stats_;
  DramTraffic requested_;
};

}  // namespace tbdr
