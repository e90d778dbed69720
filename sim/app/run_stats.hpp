#pragma once
// The statistics the run driver books from the timing model's result and the host, declared once
// as typed sets (kernel/stats.hpp) like every unit's: the frame's time, each command's span, each
// timed unit's busy / stalled / idle time, the texture fetch's reuse, and the host's timings.
// Their member names are the names stored in the database; code that reads them back names them
// with stat_name(&Set::member) and the set's kScope.
#include <algorithm>
#include <string>

#include "kernel/stats.hpp"

namespace tbdr {

// The frame's time (scope "frame/timing").
#define TBDR_FRAME_TIMING_STATS(X)                                             \
  X(Accumulator, frame_cycles, "cycles", Gauge, "Frame time in core clock cycles") \
  X(Accumulator, frame_time_ms, "ms", Gauge, "Frame time")                        \
  X(Counter, timing_events, "events", Sum, "Events the timing model executed")

/// The frame's time, as the timing model measured it.
struct FrameTimingStats {
  TBDR_STATS(TBDR_FRAME_TIMING_STATS)
  static constexpr const char* kScope = "frame/timing";
};

// One command's span (scope "<command>/timing": "pass0.gbuffer/timing", "dispatch1.cull/timing").
#define TBDR_COMMAND_TIMING_STATS(X)                                                            \
  X(Accumulator, start_cycle, "cycles", Gauge, "Cycle the command's first work started")          \
  X(Accumulator, binning_end_cycle, "cycles", Gauge, "Cycle its last binning finished (passes)")  \
  X(Accumulator, end_cycle, "cycles", Gauge, "Cycle its last tile or compute work finished")

/// When a pass or dispatch started, finished binning and finished.
struct CommandTimingStats {
  TBDR_STATS(TBDR_COMMAND_TIMING_STATS)
  /// The scope of a command's span: its name + kScopeSuffix.
  static constexpr const char* kScopeSuffix = "/timing";
};

// One timed unit over the frame (scope "frame/unit.<unit>": "frame/unit.usc", "frame/unit.isp").
#define TBDR_UNIT_TIME_STATS(X)                                                                          \
  X(Accumulator, busy_cycles, "cycles", Sum, "Cycles the unit was working")                               \
  X(Accumulator, stalled_cycles, "cycles", Sum, "Cycles the unit waited for a full queue downstream or for memory") \
  X(Accumulator, idle_cycles, "cycles", Derived, "Cycles the unit had nothing to do: frame - busy - stalled")  \
  X(Accumulator, utilization, "ratio", Derived, "Busy cycles / frame cycles")

/// A timed unit's busy, stalled and idle time; idle and utilisation derived from the frame's cycles.
struct UnitTimeStats {
  TBDR_STATS(TBDR_UNIT_TIME_STATS)
  double frame_cycles = 0;  ///< the frame's cycles, which the derived figures divide
  /// The scope of unit `name`: kScopePrefix + name.
  static constexpr const char* kScopePrefix = "frame/unit.";
  void derive() {
    idle_cycles.set(std::max(0.0, frame_cycles - busy_cycles.value() - stalled_cycles.value()));
    utilization.set(frame_cycles > 0 ? busy_cycles.value() / frame_cycles : 0.0);
  }
};

// The texture fetch's lines and their reuse within a tile (scope "frame/texture").
#define TBDR_TEXTURE_FETCH_STATS(X)                                                                         \
  X(Counter, line_accesses, "lines", Sum, "Texture lines the shaded quads accessed (distinct per quad and fetch)") \
  X(Counter, footprint_lines, "lines", Sum,                                                                \
    "Lines of the tiles' texture footprints, each sent once per tile through the texture cache")          \
  X(Counter, cache_misses, "lines", Sum, "Footprint lines that missed the texture cache")                  \
  X(Accumulator, hit_rate_with_tile_reuse, "ratio", Derived,                                               \
    "Texture cache hit rate counting reuse within a tile as hits (its footprint is fetched once): 1 - cache_misses / line_accesses")

/// Texture lines accessed, fetched per tile and missed; the hit rate derived from them.
struct TextureFetchStats {
  TBDR_STATS(TBDR_TEXTURE_FETCH_STATS)
  static constexpr const char* kScope = "frame/texture";
  void derive() {
    const double a = line_accesses.as_double();
    hit_rate_with_tile_reuse.set(a > 0 ? 1.0 - cache_misses.as_double() / a : 0.0);
  }
};

// A frame's share of a sequence: its interval and what DRAM and energy it took in it (rows of
// sequence/frame<k>, and of a sampled run's sampling/frame<k>, where a frame not simulated has its
// representative's).
#define TBDR_FRAME_INTERVAL_STATS(X)                                                                         \
  X(Accumulator, interval_cycles, "cycles", Gauge,                                                            \
    "Its end less the end of the frame before (the first: its end): the frame's share of the sequence")      \
  X(Accumulator, interval_ms, "ms", Gauge, "interval_cycles in milliseconds")                                 \
  X(Counter, dram_interval_bytes, "bytes", Gauge,                                                             \
    "Bytes DRAM transferred between the end of the frame before and its end (what reached the devices)")      \
  X(Accumulator, energy_mj, "mJ", Gauge,                                                                      \
    "Its energy: its units' work, the caches' and DRAM's energy in its interval, leakage over its interval")  \
  X(Accumulator, at_period_energy_mj, "mJ", Gauge,                                                            \
    "energy_mj plus the idle power over gpu.frame_period_us - its interval (= energy_mj without a period)")

// One frame of a sequence (scope "sequence/frame<k>": "sequence/frame0", "sequence/frame1", ...).
#define TBDR_SEQUENCE_FRAME_STATS(X)                                                                        \
  X(Accumulator, start_cycle, "cycles", Gauge, "Cycle the frame's first binning or dispatch started")        \
  X(Accumulator, end_cycle, "cycles", Gauge, "Cycle its last render or dispatch finished")                   \
  X(Accumulator, latency_cycles, "cycles", Gauge, "From its start to its end (overlaps the frame before with gpu.frames_in_flight = 2)") \
  TBDR_FRAME_INTERVAL_STATS(X)                                                                                \
  X(Counter, primitives_out, "primitives", Gauge, "The frame's primitives after clipping and culling (geometry primitives_out)") \
  X(Counter, shader_invocations, "fragments", Gauge, "The frame's fragment shader invocations (tsp shader_invocations)") \
  X(Counter, light_evaluations, "evaluations", Gauge, "The frame's light evaluations, fragment and compute (tsp light_evaluations + compute_light_evaluations)")

/// One frame of a sequence as the timing model ran it (TimingResult::frames).
struct SequenceFrameStats {
  TBDR_STATS(TBDR_SEQUENCE_FRAME_STATS)
  /// The scope of frame k: kScopePrefix + k.
  static constexpr const char* kScopePrefix = "sequence/frame";
};

// The sequence's summary (scope "sequence/summary"); only runs of more than one frame have it.
#define TBDR_SEQUENCE_SUMMARY_STATS(X)                                                                        \
  X(Counter, frames, "frames", Gauge, "Frames in the sequence")                                                 \
  X(Counter, warmup_frames, "frames", Gauge, "First frames left out of the steady state (cold caches, nothing before to overlap)") \
  X(Counter, drain_frames, "frames", Gauge, "Last frames left out of the steady state (no later frame's binning overlaps them)") \
  X(Accumulator, mean_interval_ms, "ms", Gauge, "Mean of the frames' interval_ms (the sequence's time / frames)") \
  X(Accumulator, steady_interval_ms, "ms", Gauge, "Mean interval_ms of the steady frames (after the warm-up, before the drain)")     \
  X(Accumulator, p50_interval_ms, "ms", Gauge, "Median interval_ms of the steady frames (nearest rank)") \
  X(Accumulator, p95_interval_ms, "ms", Gauge, "95th percentile interval_ms of the steady frames (nearest rank)") \
  X(Accumulator, max_interval_ms, "ms", Gauge, "Longest interval_ms of the steady frames")            \
  X(Accumulator, steady_fps, "frames/s", Gauge, "1000 / steady_interval_ms")                                      \
  X(Accumulator, steady_dram_mb_per_frame, "MB", Gauge, "Mean dram_interval_bytes of the steady frames, in MB") \
  X(Accumulator, energy_per_frame_mj, "mJ", Gauge, "The sequence's energy (frame/energy total) / frames")       \
  X(Accumulator, steady_energy_per_frame_mj, "mJ", Gauge, "Mean energy_mj of the steady frames")                   \
  X(Accumulator, steady_at_period_energy_per_frame_mj, "mJ", Gauge, "Mean at_period_energy_mj of the steady frames")

/// Frame rate and per-frame figures of a sequence, from its frames' SequenceFrameStats.
struct SequenceSummaryStats {
  TBDR_STATS(TBDR_SEQUENCE_SUMMARY_STATS)
  static constexpr const char* kScope = "sequence/summary";
};

// One frame of a sampled run (scope "sampling/frame<k>"; tbdrsim run --sample): its group, whether it
// was simulated for it, and its figures, measured or its representative's. Its signature's figures
// (models/frame_signature.hpp) are rows of the same scope.
#define TBDR_SAMPLED_FRAME_STATS(X)                                                                          \
  X(Counter, group, "group", Gauge, "The group of frames with similar signatures it belongs to (one simulated per group)") \
  X(Counter, representative, "flag", Gauge, "1: simulated, and its figures stand for its group; 0: its figures are its representative's") \
  TBDR_FRAME_INTERVAL_STATS(X)

/// Copies a frame's interval figures (TBDR_FRAME_INTERVAL_STATS) from one set to another that has them.
template <class From, class To>
void copy_frame_interval(const From& from, To& to) {
  to.interval_cycles = from.interval_cycles;
  to.interval_ms = from.interval_ms;
  to.dram_interval_bytes = from.dram_interval_bytes;
  to.energy_mj = from.energy_mj;
  to.at_period_energy_mj = from.at_period_energy_mj;
}

/// One frame of a sampled run: its group and its (measured or representative's) figures.
struct SampledFrameStats {
  TBDR_STATS(TBDR_SAMPLED_FRAME_STATS)
  static constexpr const char* kScopePrefix = "sampling/frame";
};

// A sampled run's estimate of the whole sequence (scope "sampling/summary").
#define TBDR_SAMPLING_SUMMARY_STATS(X)                                                                        \
  X(Counter, frames, "frames", Gauge, "Frames in the sequence")                                                 \
  X(Counter, groups, "groups", Gauge, "Groups of frames, one representative simulated for each (--sample)")     \
  X(Counter, frames_simulated, "frames", Gauge, "Frames the timing model ran: the representatives and the frame before and after each") \
  X(Counter, windows, "windows", Gauge, "Runs of consecutive frames simulated, each from cold")                  \
  X(Counter, signature_triangle_stride, "triangles", Gauge, "The signature projects every n-th triangle (kSignatureTriangleStride)") \
  X(Accumulator, total_cycles, "cycles", Gauge, "Estimated cycles of the sequence: over groups, members x the representative's interval_cycles") \
  X(Accumulator, total_cycles_error_pct, "%", Gauge, "Two standard errors of total_cycles had each representative been drawn at random from its group, the group's spread predicted from its signatures (analysis/frame_sampling.hpp)") \
  X(Accumulator, total_ms, "ms", Gauge, "total_cycles in milliseconds")                                          \
  X(Accumulator, dram_bytes, "bytes", Gauge, "Estimated DRAM bytes of the sequence (what reached the devices): over groups, members x dram_interval_bytes") \
  X(Accumulator, dram_bytes_error_pct, "%", Gauge, "Two standard errors of dram_bytes, as total_cycles_error_pct") \
  X(Accumulator, energy_mj, "mJ", Gauge, "Estimated energy of the sequence: over groups, members x energy_mj")    \
  X(Accumulator, energy_error_pct, "%", Gauge, "Two standard errors of energy_mj, as total_cycles_error_pct")

/// What a sampled run estimates for its whole sequence, and how.
struct SamplingSummaryStats {
  TBDR_STATS(TBDR_SAMPLING_SUMMARY_STATS)
  static constexpr const char* kScope = "sampling/summary";
};

// The host's side of a run (scope "frame/host"): no simulated figure depends on these.
#define TBDR_HOST_RUN_STATS(X)                                                                                   \
  X(Accumulator, load_wall_seconds, "s", Gauge,                                                                    \
    "Host wall time of reading the trace and loading (or generating) its scene, before the simulation")           \
  X(Accumulator, simulation_wall_seconds, "s", Gauge, "Host wall time of the functional simulation")               \
  X(Accumulator, timing_wall_seconds, "s", Gauge,                                                                  \
    "Host wall time of the timing model (with more than one thread it runs beside the functional simulation: from that one's start)") \
  X(Accumulator, simulation_cpu_seconds, "s", Gauge,                                                               \
    "Host CPU time of the functional simulation (its threads; not the timing model's or the image writer's)")     \
  X(Accumulator, timing_cpu_seconds, "s", Gauge, "Host CPU time of the timing model")                             \
  X(Accumulator, timing_wait_seconds, "s", Gauge,                                                                  \
    "Host wall time the timing model waited for work the functional simulation had not yet produced "             \
    "(with more than one thread; 0 with one, where it starts after that one ends)")                              \
  X(Accumulator, image_cpu_seconds, "s", Gauge,                                                                    \
    "Host CPU time of writing the frame's images (colour conversion, heat maps, PNG encoding; all its "           \
    "threads; 0 without --images). The colours themselves are computed in the functional simulation")            \
  X(Accumulator, tile_render_wall_seconds, "s", Gauge,                                                             \
    "Host wall time of the functional simulation's tile rendering (the part on --threads threads)")               \
  X(Accumulator, simulation_threads, "threads", Gauge,                                                             \
    "Threads the functional simulation rendered tiles on (--threads; no other figure depends on it)")            \
  X(Accumulator, allocator_huge_pages, "flag", Gauge,                                                              \
    "1 where the allocator asked for transparent huge pages (glibc.malloc.hugetlb=1: TBDRSIM_HUGE_PAGES=1, "      \
    "or unset on a host that does not take freed memory back)")                                                   \
  X(Accumulator, host_free_page_reporting, "flag", Gauge,                                                          \
    "1 on a virtual machine that reports freed memory to its host (virtio-balloon free page reporting): "         \
    "fresh huge pages are slow there, so none are asked for by default")

/// Host timings and the host settings that move them (sim/app/host_speed.hpp).
struct HostRunStats {
  TBDR_STATS(TBDR_HOST_RUN_STATS)
  static constexpr const char* kScope = "frame/host";
};

}  // namespace tbdr
