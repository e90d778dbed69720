#include "models/memory_system.hpp"

#include <algorithm>
#include <functional>
#include <stdexcept>

#include "models/sram_energy.hpp"

namespace tbdr {

namespace {

// Calls fn(addr, bytes) for each piece of [addr, addr + bytes) that lies within one line.
template <class Fn>
void for_each_line(std::uint64_t addr, std::uint64_t bytes, std::uint64_t line_bytes, Fn&& fn) {
  const std::uint64_t end = addr + bytes;
  while (addr < end) {
    const std::uint64_t next = (addr & ~(line_bytes - 1)) + line_bytes;
    const std::uint64_t n = std::min(next, end) - addr;
    fn(addr, static_cast<std::uint32_t>(n));
    addr += n;
  }
}

}  // namespace

const char* to_string(Client c) {
  switch (c) {
    case Client::Geometry: return "geometry";
    case Client::Tiler: return "tiler";
    case Client::Isp: return "isp";
    case Client::Texture: return "texture";
    case Client::PixelBackEnd: return "pixel_back_end";
    case Client::Compute: return "compute";
    case Client::Rop: return "rop";
    case Client::Count: break;
  }
  return "?";
}

MemorySystem::MemorySystem(const HwConfig& hw, EventQueue& eq, std::string scope, MemorySystemOptions opt)
    : name_(scope),
      eq_(eq),
      core_(ClockDomain::from_mhz("core", hw.gpu.core_clock_mhz)),
      caches_enabled_(opt.caches_enabled),
      energy_(hw.energy),
      texture_(std::make_unique<Cache>(scope + "/cache.texture", hw.cache.texture,
                                          on_chip_pj_per_byte(hw, OnChipArray::TextureCache))),
      vertex_(std::make_unique<Cache>(scope + "/cache.vertex", hw.cache.vertex,
                                         on_chip_pj_per_byte(hw, OnChipArray::VertexCache))),
      slc_(std::make_unique<Cache>(scope + "/cache.slc", hw.cache.slc, on_chip_pj_per_byte(hw, OnChipArray::Slc))),
      dram_(hw.dram, hw.energy, eq, scope + "/dram"),
      burst_bytes_(static_cast<std::uint32_t>(hw.dram.burst_bytes)),
      max_chain_bytes_(static_cast<std::uint64_t>(std::max<std::int64_t>(0, hw.dram.max_chain_bytes))),
      overflow_(dram_.channels()),
      overflow_lines_(dram_.channels()),
      overflow_cap_(std::max<std::size_t>(1, opt.overflow_entries)) {
  if (dram_.row_bytes() % slc_->line_bytes() != 0) {
    throw std::invalid_argument("memory system: dram.row_bytes must be a multiple of cache.slc.line_bytes");
  }
  if (caches_enabled_) {
    routes_[static_cast<std::size_t>(Client::Geometry)] = {vertex_.get(), Allocation::Allocate};
    routes_[static_cast<std::size_t>(Client::Isp)] = {vertex_.get(), Allocation::Allocate};
    routes_[static_cast<std::size_t>(Client::Texture)] = {texture_.get(), Allocation::Allocate};
  }
  routes_[static_cast<std::size_t>(Client::PixelBackEnd)].slc_alloc = Allocation::NoAllocate;
  dram_.set_space_callback([this](std::uint32_t c) { drain_overflow(c); });
  dram_.set_schedule_callback(
      [this](std::uint64_t tag, const DramSchedule& when) { resolve_chain(static_cast<std::uint32_t>(tag), when); });
}

// ---------------------------------------------------------------------------------------------
// Entry points

bool MemorySystem::issue(Client client, std::uint64_t addr, std::uint32_t bytes, bool is_write, DramClass cls,
                         EventCallback on_complete) {
  if (bytes == 0) throw std::invalid_argument("memory system: request of 0 bytes");
  MemoryClientStats& cs = client_stats_[static_cast<std::size_t>(client)];
  if (!can_accept()) {
    ++cs.rejected;
    return false;
  }
  if (is_write) {
    ++cs.writes;
    cs.write_bytes += bytes;
    requested_.write(cls, bytes);
  } else {
    ++cs.reads;
    cs.read_bytes += bytes;
    requested_.read(cls, bytes);
  }
  const std::uint32_t t = txns_.acquire();
  const Tick now = eq_.now();
  Txn& x = txns_[t];
  x.on_complete = std::move(on_complete);
  x.issued = now;
  x.due = now;
  x.remaining = 1;  // guard while the parts are being issued
  x.client = client;
  ++live_txns_;
  access<true>(client, addr, bytes, is_write, cls, t);
  resolve_txn(t, now);  // drop the guard
  return true;
}

void MemorySystem::access_functional(Client client, std::uint64_t addr, std::uint32_t bytes, bool is_write,
                                     DramClass cls) {
  if (bytes == 0) return;
  MemoryClientStats& cs = client_stats_[static_cast<std::size_t>(client)];
  ++cs.functional_accesses;
  if (is_write) {
    ++cs.writes;
    cs.write_bytes += bytes;
  } else {
    ++cs.reads;
    cs.read_bytes += bytes;
  }
  access<false>(client, addr, bytes, is_write, cls, 0);
}

void MemorySystem::count_l1_read_hits(Client client, const L1Hits& hits, DramClass cls) {
  Cache* l1 = l1_of(client);
  if (l1 == nullptr) throw std::logic_error("memory system: count_l1_read_hits for a client without an L1");
  MemoryClientStats& cs = client_stats_[static_cast<std::size_t>(client)];
  cs.reads += hits.requests;
  cs.read_bytes += hits.bytes;
  requested_.read(cls, hits.bytes);
  l1->count_read_hits(hits.lines, hits.bytes, cls);
}

void MemorySystem::notify_when_ready(EventCallback cb) {
  // Requesters refused earlier are served first, in the order they asked (fair admission: a unit
  // whose completions keep it issuing cannot starve one that is waiting).
  ready_waiters_.push_back(std::move(cb));
  if (overflow_full_ == 0) schedule_waiters();
}

void MemorySystem::schedule_waiters() {
  if (waiters_scheduled_ || ready_waiters_.empty()) return;
  waiters_scheduled_ = true;
  eq_.schedule(eq_.now(), Priority::Default, [this] {
    waiters_scheduled_ = false;
    serving_.swap(ready_waiters_);  // (ready_waiters_ takes serving_'s emptied storage)
    std::vector<EventCallback>& ws = serving_;
    serving_waiters_ = true;
    for (std::size_t i = 0; i < ws.size(); ++i) {
      if (overflow_full_ != 0) {  // full again: the rest keep their place, ahead of newcomers
        ready_waiters_.insert(ready_waiters_.begin(), std::make_move_iterator(ws.begin() + static_cast<std::ptrdiff_t>(i)),
                              std::make_move_iterator(ws.end()));
        break;
      }
      ws[i]();
    }
    ws.clear();
    serving_waiters_ = false;
    if (overflow_full_ == 0) schedule_waiters();
  });
}

void MemorySystem::flush(EventCallback on_done) {
  ++stats_.flushes;
  if (on_done) flush_done_.push_back(std::move(on_done));
  flushing_ = true;
  ++flush_outstanding_;  // guard while the writebacks are being issued
  flush_caches<true>();
  flushing_ = false;
  if (--flush_outstanding_ == 0) {
    std::vector<EventCallback> cbs = std::move(flush_done_);
    flush_done_.clear();
    for (EventCallback& cb : cbs) eq_.schedule(eq_.now(), Priority::Default, std::move(cb));
  }
}

void MemorySystem::flush_functional() {
  ++stats_.flushes;
  flush_caches<false>();
}

template <bool kTimed>
void MemorySystem::flush_caches() {
  if (!caches_enabled_) return;
  for (Cache* l1 : {texture_.get(), vertex_.get()}) {
    l1->flush([&](std::uint64_t a, DramClass c) {
      slc_range<kTimed>(Allocation::Allocate, a, l1->line_bytes(), true, c, Waiter{});
    });
  }
  send_chains<kTimed>();
  slc_->flush([&](std::uint64_t a, DramClass c) {
    dram_write_line<kTimed>(a, static_cast<std::uint32_t>(slc_->line_bytes()), c);
  });
}

// ---------------------------------------------------------------------------------------------
// The walk through the levels (shared by the timed and functional paths)

template <bool kTimed>
void MemorySystem::access(Client client, std::uint64_t addr, std::uint32_t bytes, bool is_write, DramClass cls,
                          std::uint32_t txn) {
  const Route& r = routes_[static_cast<std::size_t>(client)];
  const Waiter w{txn, 0, kTimed ? WaiterKind::Txn : WaiterKind::None};
  if (r.l1 != nullptr) {
    Cache& l1 = *r.l1;
    for_each_line(addr, bytes, l1.line_bytes(), [&](std::uint64_t a, std::uint32_t n) {
      l1_access<kTimed>(l1, a, n, is_write, cls, w);
    });
  } else {
    slc_range<kTimed>(r.slc_alloc, addr, bytes, is_write, cls, w);
  }
  send_chains<kTimed>();
}

template <bool kTimed>
void MemorySystem::l1_access(Cache& l1, std::uint64_t addr, std::uint32_t bytes, bool is_write, DramClass cls,
                             Waiter w) {
  const CacheAccess a = l1.access(addr, bytes, is_write, cls, Allocation::Allocate);
  if (a.writeback) slc_range<kTimed>(Allocation::Allocate, a.victim_addr, l1.line_bytes(), true, a.victim_cls, Waiter{});
  w.extra_cycles += static_cast<std::uint32_t>(l1.hit_latency_cycles());
  if (is_write) {
    if (!a.hit && !a.allocated) {  // write-no-allocate L1: the write goes on to the SLC
      slc_range<kTimed>(Allocation::Allocate, addr, bytes, true, cls, w);
      return;
    }
    if constexpr (kTimed) ready(w);  // write-allocate without a fetch (whole-line write-validate)
    return;
  }
  if (a.hit) {
    if constexpr (kTimed) hit(l1, a.slot, w);
    return;
  }
  // Read miss: the line was allocated; fetch all of it from the SLC.
  if constexpr (kTimed) {
    if (caches_enabled_ && l1.line_bytes() == slc_->line_bytes()) {
      // The L1 line is one SLC line: it is looked up there first. When it hits with its data's
      // arrival known (no fill of it pending), the L1 line's arrival follows at once and no fill
      // is tracked: the ticks the general path below gives (hit(), then resolve_fill() of the
      // L1 fill), in fewer steps. The requests of a tile's parameter-buffer and texture reads
      // that miss the L1 mostly take this path.
      Cache& slc = *slc_;
      const std::uint64_t line = l1.line_addr(addr);
      const auto line_bytes = static_cast<std::uint32_t>(l1.line_bytes());
      const CacheAccess s = slc.access(line, line_bytes, false, cls, Allocation::Allocate);
      if (s.hit && slc.fill_of(s.slot) == Cache::kNoFill) {
        const Tick due = std::max(eq_.now(), known_arrival(slc, s.slot, static_cast<std::uint32_t>(slc.hit_latency_cycles())));
        l1.set_arrival_ps(a.slot, due.ps());
        resolve(w, core_after(due, Cycles{w.extra_cycles}));
        return;
      }
      const std::uint32_t f = new_fill(&l1, a.slot);
      l1.set_fill(a.slot, f);
      attach(f, w);
      fills_[f].parts = 1;  // guard while the SLC line is looked up
      slc_after_lookup<true>(s, line, line_bytes, false, cls, Waiter{f, 0, WaiterKind::Fill});
      resolve_fill(f, eq_.now());
      return;
    }
    const std::uint32_t f = new_fill(&l1, a.slot);
    l1.set_fill(a.slot, f);
    attach(f, w);
    fills_[f].parts = 1;  // guard while the SLC lines are being looked up
    slc_range<true>(Allocation::Allocate, l1.line_addr(addr), l1.line_bytes(), false, cls, Waiter{f, 0, WaiterKind::Fill});
    resolve_fill(f, eq_.now());
  } else {
    slc_range<false>(Allocation::Allocate, l1.line_addr(addr), l1.line_bytes(), false, cls, Waiter{});
  }
}

template <bool kTimed>
void MemorySystem::slc_range(Allocation alloc, std::uint64_t addr, std::uint64_t bytes, bool is_write, DramClass cls,
                             Waiter w) {
  for_each_line(addr, bytes, slc_->line_bytes(), [&](std::uint64_t a, std::uint32_t n) {
    slc_access<kTimed>(alloc, a, n, is_write, cls, w);
  });
}

template <bool kTimed>
void MemorySystem::slc_access(Allocation alloc, std::uint64_t addr, std::uint32_t bytes, bool is_write, DramClass cls,
                              Waiter w) {
  if (!caches_enabled_) {
    dram_bypass<kTimed>(addr, bytes, is_write, cls, w);
    return;
  }
  slc_after_lookup<kTimed>(slc_->access(addr, bytes, is_write, cls, alloc), addr, bytes, is_write, cls, w);
}

template <bool kTimed>
void MemorySystem::slc_after_lookup(const CacheAccess& a, std::uint64_t addr, std::uint32_t bytes, bool is_write,
                                    DramClass cls, Waiter w) {
  Cache& slc = *slc_;
  if (a.writeback) dram_write_line<kTimed>(a.victim_addr, static_cast<std::uint32_t>(slc.line_bytes()), a.victim_cls);
  w.extra_cycles += static_cast<std::uint32_t>(slc.hit_latency_cycles());
  if (is_write) {
    if (!a.hit && !a.allocated) dram_bypass<kTimed>(addr, bytes, true, cls, Waiter{});  // streaming store
    if constexpr (kTimed) ready(w);  // writes are posted
    return;
  }
  if (a.hit) {
    if constexpr (kTimed) hit(slc, a.slot, w);
    return;
  }
  if (!a.allocated) {  // streaming read miss: fetch the bursts, install nothing
    dram_bypass<kTimed>(addr, bytes, false, cls, w);
    return;
  }
  const std::uint64_t line = slc.line_addr(addr);
  const auto line_bytes = static_cast<std::uint32_t>(slc.line_bytes());
  if constexpr (kTimed) {
    const std::uint32_t f = new_fill(&slc, a.slot);
    slc.set_fill(a.slot, f);
    attach(f, w);
    ++fills_[f].parts;
    chain<true>(false, line, line_bytes, cls, f);
  } else {
    chain<false>(false, line, line_bytes, cls, Cache::kNoFill);
  }
}

template <bool kTimed>
void MemorySystem::dram_bypass(std::uint64_t addr, std::uint32_t bytes, bool is_write, DramClass cls, Waiter w) {
  const std::uint64_t start = addr / burst_bytes_ * burst_bytes_;
  const std::uint64_t end = (addr + bytes + burst_bytes_ - 1) / burst_bytes_ * burst_bytes_;
  const auto n = static_cast<std::uint32_t>(end - start);
  if constexpr (!kTimed) {
    chain<false>(is_write, start, n, cls, Cache::kNoFill);
  } else if (is_write) {
    chain<true>(true, start, n, cls, Cache::kNoFill);
    ready(w);  // posted
  } else {
    const std::uint32_t f = new_fill(nullptr, 0);
    attach(f, w);
    ++fills_[f].parts;
    chain<true>(false, start, n, cls, f);
  }
}

template <bool kTimed>
void MemorySystem::chain(bool is_write, std::uint64_t addr, std::uint32_t bytes, DramClass cls, std::uint32_t fill) {
  Chain& c = chains_[is_write ? 1 : 0];
  if (c.lines != 0 && (c.addr + c.bytes != addr || c.cls != cls || c.bytes + bytes > max_chain_bytes_ ||
                       c.lines == dram_.max_request_lines() || addr / dram_.row_bytes() != c.addr / dram_.row_bytes())) {
    send_chain<kTimed>(is_write);
  }
  if (c.lines == 0) {
    c.addr = addr;
    c.bytes = bytes;
    c.cls = cls;
    c.first_fill = fill;
  } else {
    c.bytes += bytes;
    if constexpr (kTimed) {
      if (!is_write) fills_[c.last_fill].next_in_chain = fill;
    }
  }
  if constexpr (kTimed) {
    if (!is_write) fills_[fill].chain_bytes = bytes;
  }
  c.last_fill = fill;
  ++c.lines;
}

template <bool kTimed>
void MemorySystem::send_chain(bool is_write) {
  Chain& c = chains_[is_write ? 1 : 0];
  if (c.lines == 0) return;
  if (is_write) {
    dram_write_line<kTimed>(c.addr, c.bytes, c.cls, c.lines);
  } else if constexpr (!kTimed) {
    dram_.access_functional(c.addr, c.bytes, false, c.cls, c.lines);
  } else {
    DramRequest r{c.addr, c.bytes, false, c.cls, {}};
    r.lines = c.lines;
    r.report_when_scheduled = true;
    r.tag = c.first_fill;
    send(std::move(r));
  }
  c.lines = 0;
}

void MemorySystem::resolve_chain(std::uint32_t f, const DramSchedule& when) {
  // Total bytes first, then each line's arrival: after its share of the data transfer.
  std::uint64_t total = 0;
  for (std::uint32_t g = f; g != Cache::kNoFill; g = fills_[g].next_in_chain) total += fills_[g].chain_bytes;
  const std::int64_t span = (when.data_end - when.data_start).ps();
  std::uint64_t done = 0;
  while (f != Cache::kNoFill) {
    Fill& x = fills_[f];
    const std::uint32_t next = x.next_in_chain;
    x.next_in_chain = Cache::kNoFill;
    done += x.chain_bytes;
    const Tick data = when.data_start + Tick{static_cast<std::int64_t>(static_cast<std::uint64_t>(span) * done / total)};
    resolve_fill(f, data + when.return_latency);  // recycles f; no fill is created meanwhile
    f = next;
  }
}

template <bool kTimed>
void MemorySystem::dram_write_line(std::uint64_t addr, std::uint32_t bytes, DramClass cls, std::uint32_t lines) {
  if constexpr (!kTimed) {
    dram_.access_functional(addr, bytes, true, cls, lines);
  } else {
    DramRequest r{addr, bytes, true, cls, {}};
    r.lines = lines;
    if (flushing_) {
      ++flush_outstanding_;
      r.on_complete = [this] {
        if (--flush_outstanding_ == 0) {
          std::vector<EventCallback> cbs = std::move(flush_done_);
          flush_done_.clear();
          for (EventCallback& cb : cbs) cb();
        }
      };
    }
    send(std::move(r));
  }
}

// ---------------------------------------------------------------------------------------------
// Completion bookkeeping (timed path only)

Tick MemorySystem::core_after(Tick base, Cycles n) {
  // Most calls share their base tick (everything resolved at one DRAM completion or one issue())
  // and a handful of latencies: remember the last base's edge and the last answer.
  if (base != memo_base_) {
    memo_base_ = base;
    memo_edge_ = core_.edge_index(base).count();  // cycles_at(next_edge(base)) in one conversion
    memo_cycles_ = -1;
  }
  if (n.count() != memo_cycles_) {
    memo_cycles_ = n.count();
    memo_tick_ = core_.tick_of(Cycles{memo_edge_ + memo_cycles_});
  }
  return memo_tick_;
}

void MemorySystem::ready(Waiter w) { resolve(w, core_after(eq_.now(), Cycles{w.extra_cycles})); }

void MemorySystem::attach(std::uint32_t fill, Waiter w) {
  switch (w.kind) {
    case WaiterKind::None: return;
    case WaiterKind::Txn: ++txns_[w.id].remaining; break;
    case WaiterKind::Fill: ++fills_[w.id].parts; break;
  }
  fills_[fill].waiters.push_back(w);
}

void MemorySystem::hit(Cache& cache, std::uint32_t slot, Waiter w) {
  const std::uint32_t f = cache.fill_of(slot);
  if (f != Cache::kNoFill) {  // still being fetched, arrival unknown: wait for it
    ++stats_.merged_misses;
    attach(f, w);
    return;
  }
  resolve(w, known_arrival(cache, slot, w.extra_cycles));
}

Tick MemorySystem::known_arrival(const Cache& cache, std::uint32_t slot, std::uint32_t extra_cycles) {
  const Tick arrival{cache.arrival_ps(slot)};
  if (arrival > eq_.now()) {  // being fetched, arrives at a known tick
    ++stats_.merged_misses;
    return core_after(arrival, Cycles{extra_cycles});
  }
  return core_after(eq_.now(), Cycles{extra_cycles});
}

void MemorySystem::resolve(Waiter w, Tick arrival) {
  switch (w.kind) {
    case WaiterKind::None: return;
    case WaiterKind::Txn: {
      Txn& x = txns_[w.id];
      x.due = std::max(x.due, arrival);
      return;
    }
    case WaiterKind::Fill: {
      Fill& x = fills_[w.id];
      x.due = std::max(x.due, arrival);
      return;
    }
  }
}

void MemorySystem::resolve_txn(std::uint32_t t, Tick arrival) {
  Txn& x = txns_[t];
  x.due = std::max(x.due, arrival);
  if (--x.remaining != 0) return;
  eq_.schedule(x.due, Priority::CacheResponse, [this, t] { finish_txn(t); });
}

std::uint32_t MemorySystem::new_fill(Cache* cache, std::uint32_t slot) {
  const std::uint32_t f = fills_.acquire();
  Fill& x = fills_[f];
  x.cache = cache;
  x.slot = slot;
  x.parts = 0;
  x.due = eq_.now();
  x.next_in_chain = Cache::kNoFill;
  x.waiters.clear();
  return f;
}

void MemorySystem::resolve_fill(std::uint32_t f, Tick arrival) {
  Fill& x = fills_[f];
  x.due = std::max(x.due, arrival);
  if (--x.parts != 0) return;
  // Every source is resolved: the line is complete at x.due. Its waiters get it then (plus their
  // own latency), without an event; later accesses find the arrival tick on the line itself.
  const Tick due = x.due;
  if (x.cache != nullptr && x.cache->fill_of(x.slot) == f) {  // (else the line was replaced meanwhile)
    x.cache->set_fill(x.slot, Cache::kNoFill);
    x.cache->set_arrival_ps(x.slot, due.ps());
  }
  // Resolving a waiter never creates a fill, so fills_ (and x) stay where they are.
  for (const Waiter& w : x.waiters) {
    const Tick t = core_after(due, Cycles{w.extra_cycles});
    if (w.kind == WaiterKind::Txn) {
      resolve_txn(w.id, t);
    } else if (w.kind == WaiterKind::Fill) {
      resolve_fill(w.id, t);
    }
  }
  x.waiters.clear();
  fills_.release(f);
}

void MemorySystem::finish_txn(std::uint32_t t) {
  Txn& x = txns_[t];
  MemoryClientStats& cs = client_stats_[static_cast<std::size_t>(x.client)];
  ++cs.completed;
  cs.latency_total_ps += static_cast<std::uint64_t>((eq_.now() - x.issued).ps());
  EventCallback cb = std::move(x.on_complete);
  x.on_complete.reset();
  txns_.release(t);
  --live_txns_;
  ++completed_;
  if (cb) cb();
}

void MemorySystem::send(DramRequest&& req) {
  // The overflow queues count lines, like the DRAM queues (a burst chain holds one per line).
  const std::uint32_t c = dram_.channel_of(req.addr);
  const std::size_t dir = req.is_write ? 1 : 0;
  auto& q = overflow_[c][dir];
  if (q.empty() && dram_.enqueue(std::move(req))) return;
  std::size_t& lines = overflow_lines_[c][dir];
  const bool was_full = lines >= overflow_cap_;
  lines += std::max<std::uint32_t>(1, req.lines);
  q.push_back(std::move(req));
  ++overflow_count_;
  ++stats_.dram_overflows;
  if (!was_full && lines >= overflow_cap_) ++overflow_full_;
}

void MemorySystem::drain_overflow(std::uint32_t channel) {
  for (std::size_t dir = 0; dir < 2; ++dir) {
    auto& q = overflow_[channel][dir];
    std::size_t& lines = overflow_lines_[channel][dir];
    while (!q.empty()) {
      const std::uint32_t n = std::max<std::uint32_t>(1, q.front().lines);
      if (!dram_.enqueue(std::move(q.front()))) break;
      const bool was_full = lines >= overflow_cap_;
      lines -= n;
      if (was_full && lines < overflow_cap_) --overflow_full_;
      q.pop_front();
      --overflow_count_;
    }
  }
  if (overflow_full_ == 0) schedule_waiters();
}

// ---------------------------------------------------------------------------------------------
// Statistics

double MemorySystem::energy_pj() const {
  return texture_->energy_pj() + vertex_->energy_pj() + slc_->energy_pj() + dram_.energy_pj();
}

MemorySystemStats MemorySystem::energy_stats() {
  dram_.update_derived_stats();  // first: the refreshes an idle channel did up to now count in its energy
  const double caches = texture_->energy_pj() + vertex_->energy_pj() + slc_->energy_pj();
  stats_.cache_energy_pj.set(caches);
  stats_.dram_energy_pj.set(dram_.energy_pj());
  stats_.energy_pj.set(energy_pj());
  return stats_;
}

MemorySnapshot MemorySystem::snapshot() {
  energy_stats();
  for (MemoryClientStats& cs : client_stats_) {
    const std::uint64_t n = cs.completed.value();
    cs.avg_latency_ns.set(n == 0 ? 0.0 : static_cast<double>(cs.latency_total_ps.value()) * 1e-3 / static_cast<double>(n));
  }
  MemorySnapshot s{name_, stats_, client_stats_, {}, {}};
  s.caches = {texture_->snapshot(), vertex_->snapshot(), slc_->snapshot()};
  s.dram = dram_.snapshot();
  return s;
}

std::string MemorySystem::stall_reason() const {
  return std::to_string(live_txns_) + " requests in flight, " + std::to_string(overflow_count_) +
         " DRAM requests waiting for queue space; dram: " + dram_.stall_reason();
}

}  // namespace tbdr
