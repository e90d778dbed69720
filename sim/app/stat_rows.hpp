#pragma once
// Where a run's rows are made. Every statistic the results database stores comes from a typed set
// (kernel/stats.hpp) that a unit, the timing model, the energy model or the run driver filled; this
// file alone turns those sets into rows (collect_stats) with their scopes, so that what a figure is
// called is decided in one place (tests/test_stat_names.cpp checks that nothing else makes rows).
// The scopes:
//   <command>/<unit>, <command>/compute    each pass's units (geometry, tiler, isp, tsp,
//                                          tile_memory, rop) and each dispatch's compute unit
//   <command>/dram[.<class>]               the bytes a command requested, before the caches
//   frame/<unit>, frame/compute, frame/dram[.<class>]   the frame's totals
//   frame/frame                            the frame's shape (FrameShapeStats)
//   frame/timing, <command>/timing, frame/unit.<unit>, frame/texture   the timing model's figures
//   mem, mem/client.<client>, mem/cache.<cache>[.class.<class>], mem/dram[.ch<i>|.class.<class>]
//   frame/energy                           the energy model's components and totals
//   frame/host                             the host's timings (the run driver's HostRunStats)
#include <vector>

#include "app/run_stats.hpp"
#include "app/sampled_run.hpp"
#include "kernel/stats.hpp"
#include "models/command_processor.hpp"
#include "models/energy.hpp"
#include "models/timing_model.hpp"

namespace tbdr {

/// The rows of a frame's functional statistics: each command's, the frame's totals and shape.
std::vector<StatRecord> frame_rows(const FrameResult& frame);
/// Appends the rows of the timing model's result: the frame's time, each command's span, each
/// timed unit's time, the texture fetch's reuse, then the memory system's (append_memory_rows).
void append_timing_rows(const TimingResult& timing, std::vector<StatRecord>& out);
/// Appends the memory system's rows: its own, each client's, each cache's, the DRAM's.
void append_memory_rows(const MemorySnapshot& memory, std::vector<StatRecord>& out);
/// Appends one cache's rows: the main set, then one per traffic class.
void append_cache_rows(const CacheSnapshot& cache, std::vector<StatRecord>& out);
/// Appends the DRAM's rows: the whole DRAM, each channel, each traffic class.
void append_dram_rows(const DramSnapshot& dram, std::vector<StatRecord>& out);
/// Appends the energy model's rows: one per component (<component>_pj) and the totals.
void append_energy_rows(const EnergyBreakdown& energy, std::vector<StatRecord>& out);
/// Appends the host's figures (scope frame/host).
void append_host_rows(const HostRunStats& host, std::vector<StatRecord>& out);
/// Every row of a timed frame but the host's: frame_rows, then the timing, memory and energy rows.
/// What a sequence's run keeps of each frame beside the timing model's FrameTime: its unit
/// statistics and its energy (run_driver's sequence_frame_energy); both empty for a single frame.
struct SequenceFrames {
  std::vector<FrameStats> totals;
  std::vector<EnergyBreakdown> energy;
};

/// `sequence`: a sequence's per-frame statistics and energy, or empty.
std::vector<StatRecord> run_rows(const FrameResult& frame, const TimingResult& timing, const EnergyBreakdown& energy,
                                 const SequenceFrames& sequence = {});
/// Frames of a sequence left out of its steady state: the first, which starts with cold caches,
/// SLC and DRAM rows and whose binning nothing overlaps; every later frame finds the state the
/// frame before left.
inline constexpr std::size_t kSequenceWarmupFrames = 1;
/// Frames at a sequence's end left out of its steady state (when more than warm-up + drain
/// frames remain): the last, whose tiles no later frame's binning competes with, so it ends
/// sooner than a frame in the middle of a run would.
inline constexpr std::size_t kSequenceDrainFrames = 1;
/// A sequence's rows (more than one frame): each frame's SequenceFrameStats (its interval from the
/// end of the frame before, DRAM bytes in that interval) and the SequenceSummaryStats of the
/// frames after the warm-up; `energy_pj` is the sequence's.
void append_sequence_rows(const TimingResult& timing, double energy_pj, const SequenceFrames& sequence,
                          std::vector<StatRecord>& out);
/// A sequence's summary (more than one frame; empty otherwise): frames, steady-state interval and
/// its percentiles, frame rate, DRAM bytes per steady frame, energy per frame (`energy_pj`: the
/// sequence's).
/// `sequence`: each frame's statistics and energy, or empty.
SequenceSummaryStats summarize_sequence(const TimingResult& timing, double energy_pj, const SequenceFrames& sequence = {});
/// Frame k of a sequence as the timing model ran it: its span, interval, DRAM bytes since the
/// frame before, energy (when `sequence` has it) and its own counts.
SequenceFrameStats sequence_frame_stats(const TimingResult& timing, const SequenceFrames& sequence, std::size_t k);
/// The summary of a sequence's frames given one by one (summarize_sequence's, and a sampled run's
/// estimated frames): `total_ms` the sequence's time, `energy_pj` its energy. Empty below 2 frames.
SequenceSummaryStats summarize_frames(const std::vector<SequenceFrameStats>& frames, double total_ms, double energy_pj);
/// Every row of a sampled run (app/sampled_run.hpp): sampling/frame<k> for each frame (group,
/// representative, figures, signature), sampling/summary, sequence/frame<k> for the
/// representatives as their windows ran them, and sequence/summary over every frame's figures
/// (measured or its representative's).
/// `estimate`, `summary`: summarize_sampled's and summarize_sampled_sequence's of `s`.
std::vector<StatRecord> sampled_rows(const SampledSequence& s, const SamplingSummaryStats& estimate, const SequenceSummaryStats& summary);

}  // namespace tbdr
