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
