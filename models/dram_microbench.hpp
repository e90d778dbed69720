#pragma once
// DRAM microbenchmarks: a streaming and a random read pattern run straight on the DRAM model (no
// caches), one in-order stream per channel kept as full as the controller's queues allow. They are
// the model's side of the DRAM checks (`tbdrsim validate`, tests/test_dram_presets.cpp,
// bench/dram.sh): bandwidth efficiency and energy per bit, beside the arithmetic of the timing
// parameters and of the memspec (models/dram_memspec.hpp).
#include <cstdint>
#include <vector>

#include "models/dram.hpp"
#include "models/dram_memspec.hpp"
#include "models/hw_config.hpp"

namespace tbdr {

/// The access pattern of a microbenchmark (reads of 64 B lines).
enum class DramPattern : std::uint8_t {
  Stream,  ///< consecutive lines from address 0: every row read whole
  Random,  ///< lines drawn uniformly from 1 GiB (PCG32): almost every line opens a row
};

/// What a microbenchmark measured.
struct DramBenchResult {
  double ns = 0;          ///< first request to last data back
  double bytes = 0;       ///< bytes read and written (a microbenchmark only reads)
  double efficiency = 0;  ///< bytes / (dram peak bandwidth x ns), DramParams::peak_bandwidth_gbps
  double pj_per_bit = 0;  ///< all DRAM energy (dynamic, background, refresh) / bits read
  DramStats stats;        ///< the DRAM's statistics at the end (derived ones set)
};

/// Row-buffer hits per burst (one column command each), as a tool counting bursts sees them:
/// 1 - activates / bursts read and written.
double row_hits_per_burst(const DramStats& s, const DramParams& p);
/// The share of channel time spent refreshing over `ns`: refreshes x tRFC / (channels x ns).
double refresh_share(const DramStats& s, const DramParams& p, double ns);

/// Runs `lines` 64 B reads of `pattern` on a fresh DRAM of `hw` (seeded: the same figures every run);
/// `observer` (optional) sees its requests and commands (models/dram_observer.hpp).
DramBenchResult run_dram_microbench(const HwConfig& hw, DramPattern pattern, std::uint64_t lines, std::uint64_t seed = 1,
                                    DramObserver* observer = nullptr);

/// One request of an open-loop replay: issued at `arrival` (or when its queue has room).
struct DramReplayRequest {
  Tick arrival;
  std::uint64_t addr = 0;
  std::uint32_t bytes = 0;  ///< a line or a chain of consecutive lines of one row (DramRequest::lines)
  std::uint32_t lines = 1;
  bool is_write = false;
};

/// What an open-loop replay measured beyond the DRAM's own statistics (whose read latency starts
/// when the controller accepted a request): the mean time a read line waited for room in its
/// queue after its arrival, ns. Read latency from arrival = avg_read_latency_ns + this.
struct DramReplayResult {
  DramBenchResult bench;
  double read_wait_outside_ns = 0;
};

/// Replays `requests` (sorted by arrival) on a fresh DRAM of `hw`, open loop: each channel keeps
/// the reads and the writes that arrived and found their queue full in two FIFOs of their own and
/// offers them when the controller reports room (a write waiting never holds a read back).
DramReplayResult run_dram_replay(const HwConfig& hw, const std::vector<DramReplayRequest>& requests,
                                 DramObserver* observer = nullptr);

/// The memspec's energy per bit for preset `p` loaded as `hw`: its dies on one of hw's channels,
/// at hw's per-channel bandwidth, with hw's I/O energy where the memspec has no VDDQ currents.
MemspecPerBit preset_memspec_per_bit(const DramPresetMemspec& p, const HwConfig& hw);

}  // namespace tbdr
