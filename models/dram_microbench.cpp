#include "models/dram_microbench.hpp"

#include <deque>
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

}  // namespace

DramBenchResult run_dram_microbench(const HwConfig& hw, DramPattern pattern, std::uint64_t lines, std::uint64_t seed,
                                    DramObserver* observer) {
  EventQueue eq;
  Dram dram(hw.dram, hw.energy, eq);
  if (observer != nullptr) {
    observer->attach(dram);
    dram.set_observer(observer);
  }
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
  dram.update_derived_stats();
  DramBenchResult r;
  r.ns = static_cast<double>(eq.now().ps()) * 1e-3;
  r.bytes = static_cast<double>(dram.stats().read_bytes.value());
  r.efficiency = r.ns > 0 ? r.bytes / (hw.dram.peak_bandwidth_gbps() * r.ns) : 0.0;
  r.pj_per_bit = dram.stats().energy_per_bit_pj.value();
  r.stats = dram.stats();
  return r;
}

MemspecPerBit preset_memspec_per_bit(const DramPresetMemspec& p, const HwConfig& hw) {
  MemspecChannel ch;
  ch.dies = p.dies;
  ch.gbps = hw.dram.channel_peak_bandwidth_gbps();
  ch.io_pj_per_bit = hw.energy.dram_io_pj_per_bit;
  ch.vddq_v = p.vddq_v;
  return memspec_per_bit(*p.memspec, ch);
}

}  // namespace tbdr
