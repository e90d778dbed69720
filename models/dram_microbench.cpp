#include "models/dram_microbench.hpp"

#include <algorithm>
#include <deque>
#include <functional>
#include <vector>

#include "kernel/event_queue.hpp"
#include "kernel/random.hpp"
#include "models/dram_observer.hpp"

namespace tbdr {

namespace {

constexpr std::uint32_t kLineBytes = 64;
/// The random pattern's footprint: 1 GiB, many rows per bank of every preset, so that two lines
/// rarely share a row.
constexpr std::uint64_t kRandomLines = (std::uint64_t{1} << 30) / kLineBytes;

/// Reports the DRAM's requests and commands to `observer` (when given).
void observe(Dram& dram, DramObserver* observer) {
  if (observer == nullptr) return;
  observer->attach(dram);
  dram.set_observer(observer);
}

/// The figures of a finished run: first request to last data, the bytes moved (read and written),
/// their share of the peak bandwidth, energy per bit and the DRAM's statistics.
DramBenchResult finish(Dram& dram, const EventQueue& eq, const HwConfig& hw) {
  dram.update_derived_stats();
  DramBenchResult r;
  r.ns = static_cast<double>(eq.now().ps()) * 1e-3;
  r.bytes = static_cast<double>(dram.stats().read_bytes.value() + dram.stats().write_bytes.value());
  r.efficiency = r.ns > 0 ? r.bytes / (hw.dram.peak_bandwidth_gbps() * r.ns) : 0.0;
  r.pj_per_bit = dram.stats().energy_per_bit_pj.value();
  r.stats = dram.stats();
  return r;
}

}  // namespace

DramBenchResult run_dram_microbench(const HwConfig& hw, DramPattern pattern, std::uint64_t lines, std::uint64_t seed,
                                    DramObserver* observer) {
  EventQueue eq;
  Dram dram(hw.dram, hw.energy, eq);
  observe(dram, observer);
  // One in-order stream per channel: a refused request waits at its stream's head until the
  // controller reports space on that channel.
  std::vector<std::deque<std::uint64_t>> pending(dram.channels());
  Pcg32 rng = Pcg32::from_seed(seed);
  for (std::uint64_t i = 0; i < lines; ++i) {
    std::uint64_t line = i;
    if (pattern == DramPattern::Random) {
      line = ((static_cast<std::uint64_t>(rng.next()) << 32) | rng.next()) % kRandomLines;
    }
    const std::uint64_t addr = line * kLineBytes;
    pending[dram.channel_of(addr)].push_back(addr);
  }
  const auto pump = [&](std::uint32_t c) {
    auto& q = pending[c];
    while (!q.empty() && dram.enqueue(DramRequest{q.front(), kLineBytes, false, DramClass::Other, {}})) q.pop_front();
  };
  dram.set_space_callback(pump);
  for (std::uint32_t c = 0; c < dram.channels(); ++c) pump(c);
  eq.run();
  return finish(dram, eq, hw);
}

DramReplayResult run_dram_replay(const HwConfig& hw, const std::vector<DramReplayRequest>& requests,
                                 DramObserver* observer) {
  EventQueue eq;
  Dram dram(hw.dram, hw.energy, eq);
  observe(dram, observer);
  // Per channel and kind, the requests that arrived and wait for room, oldest first (indices).
  std::vector<std::deque<std::size_t>> waiting(2 * static_cast<std::size_t>(dram.channels()));
  double wait_ps = 0;  // summed over read lines: accepted - arrival
  std::uint64_t read_lines = 0;
  const auto offer = [&](std::deque<std::size_t>& q) {
    while (!q.empty()) {
      const DramReplayRequest& r = requests[q.front()];
      if (!dram.enqueue(DramRequest{r.addr, r.bytes, r.is_write, DramClass::Other, {}, r.lines})) return;
      if (!r.is_write) {
        wait_ps += static_cast<double>((eq.now() - r.arrival).ps()) * r.lines;
        read_lines += r.lines;
      }
      q.pop_front();
    }
  };
  dram.set_space_callback([&](std::uint32_t c) {
    offer(waiting[2 * c]);
    offer(waiting[2 * c + 1]);
  });
  // One event per distinct arrival tick, each scheduling the next: the queue never holds the
  // whole stream (a frame is millions of requests).
  std::size_t next = 0;
  std::function<void()> arrive = [&] {
    const Tick t = requests[next].arrival;
    for (; next < requests.size() && requests[next].arrival == t; ++next) {
      auto& q = waiting[2 * dram.channel_of(requests[next].addr) + (requests[next].is_write ? 1 : 0)];
      q.push_back(next);
      if (q.size() == 1) offer(q);
    }
    if (next < requests.size()) eq.schedule(requests[next].arrival, [&] { arrive(); });
  };
  if (!requests.empty()) eq.schedule(requests.front().arrival, [&] { arrive(); });
  eq.run();
  DramReplayResult out;
  out.bench = finish(dram, eq, hw);
  out.read_wait_outside_ns = read_lines > 0 ? wait_ps * 1e-3 / static_cast<double>(read_lines) : 0.0;
  return out;
}

MemspecPerBit preset_memspec_per_bit(const DramPresetMemspec& p, const HwConfig& hw) {
  MemspecChannel ch;
  ch.dies = p.dies;
  ch.gbps = hw.dram.channel_peak_bandwidth_gbps();
  ch.io_pj_per_bit = hw.energy.dram_io_pj_per_bit;
  ch.vddq_v = p.vddq_v;
  return memspec_per_bit(*p.memspec, ch);
}

double row_hits_per_burst(const DramStats& s, const DramParams& p) {
  const double bursts = static_cast<double>(s.read_bytes.value() + s.write_bytes.value()) / p.burst_bytes;
  return bursts > 0 ? 1.0 - static_cast<double>(s.activates.value()) / bursts : 0.0;
}

double refresh_share(const DramStats& s, const DramParams& p, double ns) {
  return ns > 0 ? static_cast<double>(s.refreshes.value()) * p.t_rfc_ns / (static_cast<double>(p.channels) * ns) : 0.0;
}

}  // namespace tbdr
