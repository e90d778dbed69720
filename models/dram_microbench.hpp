#pragma once
// DRAM microbenchmarks: a streaming and a random read pattern run straight on the DRAM model (no
// caches), one in-order stream per channel kept as full as the controller's queues allow. They are
// the model's side of the DRAM checks (`tbdrsim validate`, tests/test_dram_presets.cpp,
// bench/dram.sh): bandwidth efficiency and energy per bit, beside the arithmetic of the timing
// parameters and of the memspec (models/dram_memspec.hpp).
#include <cstdint>

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
  double bytes = 0;       ///< bytes read
  double efficiency = 0;  ///< bytes / (dram peak bandwidth x ns), DramParams::peak_bandwidth_gbps
  double pj_per_bit = 0;  ///< all DRAM energy (dynamic, background, refresh) / bits read
  DramStats stats;        ///< the DRAM's statistics at the end (derived ones set)
};

/// Runs `lines` 64 B reads of `pattern` on a fresh DRAM of `hw` (seeded: the same figures every run);
/// `observer` (optional) sees its requests and commands (models/dram_observer.hpp).
DramBenchResult run_dram_microbench(const HwConfig& hw, DramPattern pattern, std::uint64_t lines, std::uint64_t seed = 1,
                                    DramObserver* observer = nullptr);

/// The memspec's energy per bit for preset `p` loaded as `hw`: its dies on one of hw's channels,
/// at hw's per-channel bandwidth, with hw's I/O energy where the memspec has no VDDQ currents.
MemspecPerBit preset_memspec_per_bit(const DramPresetMemspec& p, const HwConfig& hw);

}  // namespace tbdr
