// Benchmark driver (not part of the build): runs the functional frame of a trace once, then the
// timing model `reps` times on the same FrameWork, and prints the CPU seconds of each run_timing
// call plus a fingerprint of its result (events, frame ps, DRAM statistics) so that two builds
// can be compared for speed and identity. Built by bench/timing_model_bench.sh against a build
// directory's static libraries.
// Usage: timing_model_bench TRACE [reps]
#include <cstdio>
#include <ctime>
#include <cstdlib>
#include <string>
#include <vector>
#include <algorithm>

#include "models/command_processor.hpp"
#include "models/hw_config.hpp"
#include "models/timing_model.hpp"
#include "scene/scene_library.hpp"
#include "trace/trace.hpp"

using namespace tbdr;

static double cpu() { return static_cast<double>(std::clock()) / CLOCKS_PER_SEC; }

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: %s TRACE [reps]\n", argv[0]);
    return 2;
  }
  const int reps = argc > 2 ? std::atoi(argv[2]) : 3;
  const Trace trace = read_trace(argv[1]);
  if (trace.scene.kind != SceneKind::Atrium) {
    std::fprintf(stderr, "atrium traces only\n");
    return 2;
  }
  const Scene scene = load_scene("atrium:" + std::to_string(trace.scene.detail), SceneLoadOptions{.colour_texels = false});
  const HwConfig hw = resolve_config({}, {}).hw;
  const FrameResult frame = simulate_frame(trace, argv[1], scene, hw, FrameOptions{.colour = false, .threads = 1});
  std::vector<double> secs;
  for (int r = 0; r < reps; ++r) {
    const double c0 = cpu();
    const TimingResult t = run_timing(hw, frame.work);
    secs.push_back(cpu() - c0);
    // A hash of every memory statistic (the same rows the database gets, in their order).
    double h = 0;
    const auto hash = [&h](const auto& set) {
      std::vector<tbdr::StatRecord> rows;
      tbdr::collect_stats(set, "", rows);
      for (const tbdr::StatRecord& s : rows) h = h * 1.000001 + s.value;
    };
    const tbdr::MemorySnapshot& m = t.memory_units;
    hash(m.stats);
    for (const auto& c : m.clients) hash(c);
    for (const auto& cache : m.caches) {
      hash(cache.stats);
      for (const auto& cls : cache.classes) hash(cls);
    }
    hash(m.dram.stats);
    for (const auto& ch : m.dram.channels) hash(ch);
    for (const auto& cls : m.dram.classes) hash(cls);
    std::printf("run %d: %.4f s  events %llu  frame_ps %.0f  memhash %.17g\n", r, secs.back(),
                static_cast<unsigned long long>(t.events), t.frame_time_ps, h);
  }
  std::sort(secs.begin(), secs.end());
  std::printf("median %.4f s  min %.4f s\n", secs[secs.size() / 2], secs.front());
  return 0;
}
