// Threads inside one run (FrameOptions::threads, `tbdrsim run --threads`): the tiles of each render
// are rendered on a pool of threads, each with its own ISP/TSP scratch, and merged in tile order.
// Whatever the thread count, a run must give the same statistic rows, tile rows (the timing
// model's), TileWork lists, images (every attachment's colour, depth, stencil and stored
// surfaces, and the per-pixel counters) and database rows. Compared here at 1, 2 and 7 threads
// for all 13 techniques at a small size, with MSAA 4x, with partial renders (parameter buffer
// overflow: a barrier between the tiles of one render and the binning of the next), strips and
// spills of passes over the tile memory budget, and in the tbr (early and late Z) and imr modes; plus the thread
// pool's own contract (items in order, each once, the lowest item's exception).
#include <cstdio>

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cstddef>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <future>
#include <iterator>
#include <mutex>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#if defined(__linux__)
#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>
#endif

#include "app/stat_rows.hpp"
#include "analysis/results_db.hpp"
#include "analysis/sql.hpp"
#include "app/cli.hpp"
#include "app/commands.hpp"
#include "app/run_driver.hpp"
#include "kernel/cpu_placement.hpp"
#include "kernel/thread_pool.hpp"
#include "models/command_processor.hpp"
#include "models/hw_config.hpp"
#include "models/work_feed.hpp"
#include "scene/scene_library.hpp"
#include "techniques/technique.hpp"
#include "trace/trace.hpp"
#include "atrium_trace_setup.hpp"
#include "db_query.hpp"
#include "scratch_dir.hpp"

namespace tbdr {
namespace {

testing_scratch::ScratchCleanup cleanup{"threads"};

/// The thread counts every comparison runs: serial, the 2-core machine's, and more threads than
/// cores (and an odd count, so tiles go to threads in no regular pattern).
constexpr unsigned kThreadCounts[] = {1, 2, 7};

/// A frame simulated and timed at `threads` threads, with colours.
struct ThreadedRun {
  FrameResult frame;
  TimingResult timing;
  std::vector<StatRecord> stats;  ///< every row the run stores but the host's
};

/// With more than one thread the timing model runs beside the functional run, fed command by
/// command (models/work_feed.hpp), as `tbdrsim run` does; with one, after it.
ThreadedRun run(const Trace& t, const Scene& s, const HwConfig& hw, unsigned threads) {
  ThreadedRun r;
  if (threads == 1) {
    r.frame = simulate_frame(t, "t.trace", s, hw, FrameOptions{.colour = true, .threads = threads});
    EnergyBreakdown energy;
    time_frame(hw, r.frame, r.timing, energy);
    r.stats = run_rows(r.frame, r.timing, energy);
    return r;
  }
  WorkFeed feed;
  std::future<TimingResult> timed = std::async(std::launch::async, [&] { return run_timing(hw, feed); });
  r.frame = simulate_frame(t, "t.trace", s, hw, FrameOptions{.colour = true, .threads = threads, .feed = &feed});
  r.timing = timed.get();
  r.frame.work = feed.take();
  EnergyBreakdown energy;
  book_timing(hw, r.frame, r.timing, energy);
  r.stats = run_rows(r.frame, r.timing, energy);
  return r;
}

/// Bitwise equality of two vectors of trivially copyable values (floats compared as bits: -0 and
/// NaN patterns count).
template <class T>
bool same_bits(const std::vector<T>& a, const std::vector<T>& b) {
  return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0);
}

/// Expects two TileWork lists (every command's renders) to be the same, field by field.
void expect_same_work(const FrameWork& a, const FrameWork& b, const std::string& what) {
  ASSERT_EQ(a.commands.size(), b.commands.size()) << what;
  for (std::size_t c = 0; c < a.commands.size(); ++c) {
    const CommandWork& ca = a.commands[c];
    const CommandWork& cb = b.commands[c];
    ASSERT_EQ(ca.renders.size(), cb.renders.size()) << what << " " << ca.name;
    EXPECT_TRUE(same_bits(ca.texture_lines, cb.texture_lines)) << what << " " << ca.name;
    for (std::size_t r = 0; r < ca.renders.size(); ++r) {
      const auto& ta = ca.renders[r].tiles;
      const auto& tb = cb.renders[r].tiles;
      ASSERT_EQ(ta.size(), tb.size()) << what << " " << ca.name << " render " << r;
      for (std::size_t i = 0; i < ta.size(); ++i) {
        const TileWork& x = ta[i];
        const TileWork& y = tb[i];
        const std::string where = what + " " + ca.name + " render " + std::to_string(r) + " tile " + std::to_string(i);
        EXPECT_EQ(x.tile_x, y.tile_x) << where;
        EXPECT_EQ(x.tile_y, y.tile_y) << where;
        EXPECT_TRUE(x.rect == y.rect) << where;
        EXPECT_TRUE(x.load_bytes == y.load_bytes && x.image_read_bytes == y.image_read_bytes && x.store_bytes == y.store_bytes)
            << where;
        EXPECT_EQ(x.primitives, y.primitives) << where;
        EXPECT_EQ(x.samples, y.samples) << where;
        EXPECT_EQ(x.invocations, y.invocations) << where;
        EXPECT_EQ(x.quads, y.quads) << where;
        EXPECT_EQ(x.alu_ops, y.alu_ops) << where;
        EXPECT_EQ(x.texels, y.texels) << where;
        EXPECT_EQ(x.isp_wait_alu_ops, y.isp_wait_alu_ops) << where;
        EXPECT_EQ(x.texture_line_accesses, y.texture_line_accesses) << where;
        EXPECT_EQ(x.tile_buffer_bytes, y.tile_buffer_bytes) << where;
        EXPECT_EQ(x.spill_read_bytes + x.spill_write_bytes, y.spill_read_bytes + y.spill_write_bytes) << where;
        EXPECT_EQ(x.tag_bytes, y.tag_bytes) << where;
        EXPECT_EQ(x.depth_bytes, y.depth_bytes) << where;
        EXPECT_TRUE(same_bits(x.texture_lines, y.texture_lines)) << where;
        EXPECT_TRUE(same_bits(x.pb_reads, y.pb_reads)) << where;
        EXPECT_EQ(x.rop_depth.size() + x.rop_color.size(), y.rop_depth.size() + y.rop_color.size()) << where;
      }
    }
  }
}

/// Expects two frames' images to be bit for bit the same: every attachment (colour, depth,
/// stencil, stored surfaces), image buffer and per-pixel counter.
void expect_same_images(const FrameImages& a, const FrameImages& b, const std::string& what) {
  ASSERT_EQ(a.attachments.size(), b.attachments.size()) << what;
  for (const auto& [name, x] : a.attachments) {
    const auto it = b.attachments.find(name);
    ASSERT_NE(it, b.attachments.end()) << what << " " << name;
    const AttachmentImage& y = it->second;
    EXPECT_TRUE(same_bits(x.color, y.color)) << what << ": attachment " << name << " colour";
    EXPECT_TRUE(same_bits(x.depth, y.depth)) << what << ": attachment " << name << " depth";
    EXPECT_TRUE(same_bits(x.stencil, y.stencil)) << what << ": attachment " << name << " stencil";
    EXPECT_TRUE(same_bits(x.surface_valid, y.surface_valid)) << what << ": attachment " << name << " surface_valid";
    // The stored surfaces where they are set (a store leaves the others undefined: SurfaceStore).
    ASSERT_EQ(x.surface.size(), y.surface.size()) << what << ": attachment " << name;
    std::size_t differing = 0;
    for (std::size_t k = 0; k < x.surface.size() && k < x.surface_valid.size(); ++k) {
      if (!x.surface_valid[k]) continue;
      const SurfacePoint p = x.surface[k], q = y.surface[k];
      const bool same = std::memcmp(&p.position, &q.position, sizeof p.position) == 0 &&
                        std::memcmp(&p.normal, &q.normal, sizeof p.normal) == 0 &&
                        std::memcmp(&p.albedo, &q.albedo, sizeof p.albedo) == 0 &&
                        std::memcmp(&p.alpha, &q.alpha, sizeof p.alpha) == 0 && p.material == q.material &&
                        p.triangle == q.triangle && std::memcmp(p.quad_uv.data(), q.quad_uv.data(), sizeof p.quad_uv) == 0;
      differing += same ? 0 : 1;
    }
    EXPECT_EQ(differing, 0u) << what << ": attachment " << name << " stored surfaces";
  }
  ASSERT_EQ(a.image_buffers.size(), b.image_buffers.size()) << what;
  for (const auto& [name, x] : a.image_buffers) {
    EXPECT_TRUE(same_bits(x.color, b.image_buffers.at(name).color)) << what << ": image buffer " << name;
  }
  EXPECT_TRUE(same_bits(a.counters.rasterised_samples, b.counters.rasterised_samples)) << what;
  EXPECT_TRUE(same_bits(a.counters.shaded, b.counters.shaded)) << what;
  EXPECT_TRUE(same_bits(a.counters.lights_evaluated, b.counters.lights_evaluated)) << what;
  EXPECT_TRUE(same_bits(a.counters.triangle_id, b.counters.triangle_id)) << what;
}

/// Expects two runs to give the same statistic rows (scope, name and value, in order), tile rows,
/// frame cycles, TileWork lists and images.
void expect_same_run(const ThreadedRun& a, const ThreadedRun& b, const std::string& what) {
  ASSERT_EQ(a.stats.size(), b.stats.size()) << what;
  std::size_t differing = 0;
  for (std::size_t i = 0; i < a.stats.size(); ++i) {
    const StatRecord& x = a.stats[i];
    const StatRecord& y = b.stats[i];
    EXPECT_EQ(x.scope, y.scope) << what << " row " << i;
    EXPECT_EQ(x.name, y.name) << what << " row " << i;
    if (std::memcmp(&x.value, &y.value, sizeof(double)) != 0) {
      ++differing;
      ADD_FAILURE() << what << ": " << x.scope << "/" << x.name << " is " << x.value << " and " << y.value;
    }
  }
  EXPECT_EQ(differing, 0u) << what;
  EXPECT_TRUE(a.timing.tiles == b.timing.tiles) << what << ": tile rows differ";
  EXPECT_EQ(a.timing.frame_cycles, b.timing.frame_cycles) << what;
  expect_same_work(a.frame.work, b.frame.work, what);
  expect_same_images(a.frame.images, b.frame.images, what);
}

/// Runs `t` at every count of kThreadCounts and compares each with the serial run. Returns the
/// serial run.
ThreadedRun expect_same_at_every_thread_count(const Trace& t, const Scene& s, const HwConfig& hw, const std::string& what) {
  ThreadedRun serial = run(t, s, hw, kThreadCounts[0]);
  for (std::size_t k = 1; k < std::size(kThreadCounts); ++k) {
    const unsigned n = kThreadCounts[k];
    expect_same_run(serial, run(t, s, hw, n), what + " at " + std::to_string(n) + " threads");
  }
  return serial;
}

/// A statistic's value in a frame's functional rows (NaN and a failure when absent).
double stat(const FrameResult& f, const std::string& scope, const std::string& name) {
  for (const StatRecord& r : frame_rows(f)) {
    if (r.scope == scope && r.name == name) return r.value;
  }
  ADD_FAILURE() << "no statistic " << scope << "/" << name;
  return std::nan("");
}

class ThreadEquivalence : public testing_support::AtriumTechniqueSuite {};

TEST_P(ThreadEquivalence, EveryStatisticTileRowAndImageIsTheSameAtOneTwoAndSevenThreads) {
  const std::string technique = GetParam();
  const Trace t = small_trace(technique);
  const HwConfig hw = resolve_config({}, {}).hw;
  const ThreadedRun serial = expect_same_at_every_thread_count(t, *scene_, hw, technique);
  // The runs did shade something (a frame of nothing would compare equal at any count).
  EXPECT_GT(serial.frame.totals.render.tsp.shader_invocations.value() + serial.frame.totals.compute.threads.value(), 0u)
      << technique;
}

INSTANTIATE_TEST_SUITE_P(Techniques, ThreadEquivalence, testing_support::every_technique(),
                         testing_support::technique_test_name);

// MSAA 4x (the techniques that support it): per-sample coverage of the alpha-tested cloth,
// blending and the resolves at the end of each tile.
TEST_F(ThreadEquivalence, MultisampledRunsAreTheSameAtEveryThreadCount) {
  for (const char* technique : kMultisampledTechniques) {
    const Trace t = msaa4_trace(technique);
    const HwConfig hw = resolve_config({}, {}).hw;
    const ThreadedRun serial = expect_same_at_every_thread_count(t, *scene_, hw, std::string(technique) + " 4x");
    // The resolves ran (visibility_buffer resolves in its compute shading kernel instead).
    if (std::string(technique) != "visibility_buffer") {
      EXPECT_GT(stat(serial.frame, "frame/tile_memory", "resolved_samples"), 0) << technique;
    }
  }
}

// A parameter buffer of 64 KiB overflows: each pass is several renders, each a barrier (its
// tiles finish, are merged, and reload what the previous render stored, before binning goes on).
// forward_plus's forward pass is binned past the light culling dispatch at 2 and 7 threads
// (command_processor.cpp; at 1 thread it is set up after the dispatch, in trace order): its first
// partial render catches up (the prepass's tiles, the dispatch, the light grid it reads) before
// its tiles, with the same results as the order of the trace.
TEST_F(ThreadEquivalence, PartialRendersAreTheSameAtEveryThreadCount) {
  for (const char* technique : {"plain_forward", "deferred", "forward_plus"}) {
    const TraceSetup setup = testing_support::atrium_entrance_setup(*scene_, 32, 200, 120);
    const Trace t = generate_trace(technique, setup);
    const HwConfig hw = resolve_config({}, {"tiling.pb_capacity_bytes=65536"}).hw;
    const ThreadedRun serial = expect_same_at_every_thread_count(t, *scene_, hw, std::string(technique) + " partial renders");
    EXPECT_GT(stat(serial.frame, "frame/tiler", "partial_renders"), 0) << technique;
    EXPECT_GT(stat(serial.frame, "frame/tile_memory", "partial_render_reload_bytes"), 0) << technique;
    if (std::string(technique) == "forward_plus") {
      EXPECT_GT(stat(serial.frame, "pass1.forward/tiler", "partial_renders"), 0);
    }
  }
}

// A smaller parameter buffer costs more, run at 2 threads (binning's set-up and tile test on the
// pool, a partial render settling the set-up it interrupts). deferred at 200x120, 32 lights, its
// G-buffer pass binned into 1 MiB (no partial render), 128, 96 and 64 KiB (the least allowed):
// the partial renders grow as the buffer shrinks (measured 0 / 1 / 2 / 3). Each stores the depth
// and G-buffer of the tiles it touched and the next render reloads them: the attachments' DRAM
// bytes (depth/stencil, G-buffer, colour) grow by exactly the partial renders' store and reload
// bytes (measured +576,000 / +454,656 / +319,488 B), while the parameter buffer's shrink a little
// (a partial render's tiles read only what was binned since the last one). The frame is never
// faster (measured 127,706 / 147,449 / 178,627 / 187,975 cycles).
TEST_F(ThreadEquivalence, ASmallerParameterBufferMeansMorePartialRendersAndNeverAFasterFrame) {
  const TraceSetup setup = testing_support::atrium_entrance_setup(*scene_, 32, 200, 120);
  const Trace t = generate_trace("deferred", setup);
  struct Point {
    double partial = 0, stored = 0, attachments = 0, cycles = 0;
  };
  std::vector<Point> points;
  for (const char* capacity : {"1048576", "131072", "98304", "65536"}) {
    const HwConfig hw = resolve_config({}, {std::string("tiling.pb_capacity_bytes=") + capacity}).hw;
    const ThreadedRun r = run(t, *scene_, hw, 2);
    Point p;
    p.partial = stat(r.frame, "frame/tiler", "partial_renders");
    p.stored = stat(r.frame, "frame/tile_memory", "partial_render_store_bytes") +
               stat(r.frame, "frame/tile_memory", "partial_render_reload_bytes");
    for (const DramClass c : {DramClass::DepthStencil, DramClass::Gbuffer, DramClass::Color}) {
      p.attachments += static_cast<double>(r.frame.dram.reads(c) + r.frame.dram.writes(c));
    }
    p.cycles = r.timing.frame_cycles;
    points.push_back(p);
  }
  EXPECT_EQ(points[0].partial, 0.0);
  for (std::size_t i = 1; i < points.size(); ++i) {
    const Point& a = points[i - 1];
    const Point& b = points[i];
    EXPECT_GT(b.partial, a.partial) << i;
    EXPECT_GT(b.stored, a.stored) << i;
    EXPECT_EQ(b.attachments - a.attachments, b.stored - a.stored) << i;
    EXPECT_GE(b.cycles, a.cycles) << i;
  }
  EXPECT_GT(points.back().cycles, points.front().cycles);
}

// Binning past the dispatches (2 threads) keeps the dispatch's cost where the physics puts it.
// tiled_deferred's shading dispatch made ALU-bound: 4000 ALU operations per pixel over 200x120 =
// 24,000 pixels is 96 M operations, at usc.count x 16 lanes x 2 ops per cycle 1.5 M cycles with 2
// USCs and 0.75 M with 4, far above its G-buffer and colour traffic (about 0.3 MB). Twice the USCs
// halve the dispatch (ratio 0.5; within 0.45-0.55 for the traffic and the tail around it). The
// pass after it was binned while the earlier work ran (its binning starts before the dispatch)
// and renders after the dispatch (it ends after it).
TEST_F(ThreadEquivalence, TwiceTheUscsHalveAnAluBoundDispatchBinnedPast) {
  const TraceSetup setup = testing_support::atrium_entrance_setup(*scene_, 32, 200, 120);
  Trace t = generate_trace("tiled_deferred", setup);
  std::string shader;
  for (const TraceCommand& c : t.commands) {
    if (const auto* d = std::get_if<DispatchCmd>(&c); d && d->params.contains("shader")) shader = d->params.at("shader");
  }
  ASSERT_FALSE(shader.empty());
  for (ShaderDesc& sh : t.shaders) {
    if (sh.name == shader) sh.alu_ops = 4000;
  }
  auto dispatch_cycles = [&](int uscs, double* pass_start, double* pass_end, double* dispatch_start, double* dispatch_end) {
    const HwConfig hw = resolve_config({}, {"usc.count=" + std::to_string(uscs)}).hw;
    const ThreadedRun r = run(t, *scene_, hw, 2);
    for (std::size_t c = 0; c < r.timing.commands.size(); ++c) {
      const CommandTime& ct = r.timing.commands[c];
      if (ct.name.rfind("dispatch", 0) == 0) {
        *dispatch_start = ct.start_cycle;
        *dispatch_end = ct.end_cycle;
        *pass_start = r.timing.commands.at(c + 1).start_cycle;
        *pass_end = r.timing.commands.at(c + 1).end_cycle;
        return ct.end_cycle - ct.start_cycle;
      }
    }
    ADD_FAILURE() << "no dispatch";
    return 0.0;
  };
  double pass_start[2], pass_end[2], d_start[2], d_end[2];
  const double two = dispatch_cycles(2, &pass_start[0], &pass_end[0], &d_start[0], &d_end[0]);
  const double four = dispatch_cycles(4, &pass_start[1], &pass_end[1], &d_start[1], &d_end[1]);
  ASSERT_GT(two, 0.0);
  EXPECT_GE(four / two, 0.45) << two << " -> " << four;
  EXPECT_LE(four / two, 0.55) << two << " -> " << four;
  for (int k = 0; k < 2; ++k) {
    EXPECT_LT(pass_start[k], d_start[k]) << "the translucent pass is binned while the earlier work runs";
    EXPECT_GT(pass_end[k], d_end[k]) << "and renders after the dispatch";
  }
}

// Passes over the tile memory budget: rendered as strips (smaller_tiles), spilled (spill), or
// split at a subpass boundary (split_render), with deferred's 4 G-buffer targets in 64 bits.
TEST_F(ThreadEquivalence, OverBudgetPassesAreTheSameAtEveryThreadCount) {
  const TraceSetup setup = testing_support::atrium_entrance_setup(*scene_, 32, 200, 120);
  const Trace t = generate_trace("deferred", setup);
  for (const char* policy : {"smaller_tiles", "spill", "split_render"}) {
    const HwConfig hw =
        resolve_config({}, {"pls.tile_buffer_bits_per_pixel=64", std::string("pls.over_budget=") + policy}).hw;
    expect_same_at_every_thread_count(t, *scene_, hw, std::string("deferred over budget, ") + policy);
  }
}

// The other GPU modes: tile-based without deferred shading (forward pixel kill; and with the
// depth/stencil tests after the shader, isp.early_z=0), and immediate mode (one frame-sized "tile"
// per batch, through the ROP caches, on one thread).
TEST_F(ThreadEquivalence, TbrAndImrModesAreTheSameAtEveryThreadCount) {
  const std::vector<std::vector<std::string>> modes = {{"gpu.mode=tbr"}, {"gpu.mode=tbr", "isp.early_z=0"}, {"gpu.mode=imr"}};
  for (const auto& mode : modes) {
    for (const char* technique : {"plain_forward", "tiled_deferred"}) {
      const TraceSetup setup = testing_support::atrium_entrance_setup(*scene_, 32, 160, 96);
      const Trace t = generate_trace(technique, setup);
      const HwConfig hw = resolve_config({}, mode).hw;
      const ThreadedRun serial = expect_same_at_every_thread_count(t, *scene_, hw, std::string(technique) + " " + mode.back());
      // Forward shading without HSR lights surfaces that are replaced later (LitSampleLedger): the
      // ledger's counts are among those compared.
      if (std::string(technique) == "plain_forward") {
        EXPECT_GT(stat(serial.frame, "frame/tsp", "hidden_lit_samples"), 0) << mode.back();
      }
    }
  }
}

/// Every row of a run in the database but its host figures (frame/host), as text in a fixed
/// order: statistics, tile rows and parameters.
std::vector<std::string> database_rows(const std::string& db_path, std::int64_t run_id) {
  const ResultsDb db(db_path, ResultsDb::QueryOnly{});
  std::vector<std::string> rows;
  const std::string id = std::to_string(run_id);
  for (const std::string& sql :
       {"SELECT scope || '|' || name || '|' || printf('%.17g', value) || '|' || unit FROM stats WHERE run_id = " + id +
            " AND scope <> 'frame/host' ORDER BY scope, name",
        "SELECT pass || '|' || tile_x || '|' || tile_y || '|' || printf('%.17g', cycles) || '|' || printf('%.17g', samples) || "
        "'|' || printf('%.17g', dram_bytes) FROM tile_stats WHERE run_id = " + id + " ORDER BY pass, tile_x, tile_y",
        "SELECT key || '=' || value || '|' || origin FROM run_params WHERE run_id = " + id + " ORDER BY key"}) {
    SqlStatement q(db.sql(), sql);
    while (q.step()) rows.push_back(q.text(0));
  }
  return rows;
}

// What `tbdrsim run` writes: the same database rows (all but the host timings and the thread
// count itself) at 1, 2 and 7 threads, and the same PNG images.
TEST(ThreadEquivalenceDatabase, RunsWriteTheSameRowsAndImagesAtEveryThreadCount) {
  const auto dir = testing_scratch::scratch_dir("threads", "db");
  const Scene scene = load_scene("atrium:1");
  TraceSetup setup = testing_support::atrium_entrance_setup(scene, 32, 160, 96);
  const std::string trace_path = (dir / "deferred.trace").string();
  write_trace_file(generate_trace("deferred", setup), trace_path);
  std::vector<std::vector<std::string>> rows;
  std::vector<std::vector<std::string>> images;
  const CpuList cpus_before = allowed_cpus();
  for (const unsigned n : kThreadCounts) {
    RunRequest req;
    req.config = resolve_config({}, {});
    req.trace_path = trace_path;
    req.db_path = (dir / "runs.db").string();
    req.images_dir = (dir / ("images" + std::to_string(n))).string();
    req.threads = n;
    const RunOutcome o = run_one(req);
    // Kept apart from the timing model's while the frame ran (kernel/cpu_placement.hpp), the
    // caller's thread has every CPU it had once the run is done.
    EXPECT_EQ(allowed_cpus(), cpus_before) << n << " threads";
    rows.push_back(database_rows(req.db_path, o.run_id));
    EXPECT_EQ(testing_support::query_number(req.db_path, "SELECT value FROM stats WHERE run_id = " + std::to_string(o.run_id) +
                                                             " AND scope = 'frame/host' AND name = 'simulation_threads'"),
              static_cast<double>(n));
    // The host CPU of writing them is recorded at every count (on the caller's thread at 1, beside
    // the timing model at more): time the run spent, so more than nothing.
    EXPECT_GT(testing_support::query_number(req.db_path, "SELECT value FROM stats WHERE run_id = " + std::to_string(o.run_id) +
                                                             " AND scope = 'frame/host' AND name = 'image_cpu_seconds'"),
              0.0)
        << n << " threads";
    std::vector<std::string> files;
    for (const std::string& p : o.images_written) {
      std::ifstream in(p, std::ios::binary);
      files.push_back(std::string(std::istreambuf_iterator<char>(in), {}));
    }
    images.push_back(std::move(files));
  }
  ASSERT_GT(rows[0].size(), 100u);
  ASSERT_GT(images[0].size(), 3u);
  {  // Without images nothing is written, and no image CPU is recorded.
    RunRequest req;
    req.config = resolve_config({}, {});
    req.trace_path = trace_path;
    req.db_path = (dir / "runs.db").string();
    const RunOutcome o = run_one(req);
    EXPECT_TRUE(o.images_written.empty());
    EXPECT_EQ(testing_support::query_number(req.db_path, "SELECT value FROM stats WHERE run_id = " + std::to_string(o.run_id) +
                                                             " AND scope = 'frame/host' AND name = 'image_cpu_seconds'"),
              0.0);
  }
  for (std::size_t k = 1; k < rows.size(); ++k) {
    EXPECT_TRUE(rows[k] == rows[0]) << kThreadCounts[k] << " threads: database rows differ";
    EXPECT_TRUE(images[k] == images[0]) << kThreadCounts[k] << " threads: images differ";
  }
}

// A thread count outside 1..1024 is refused before anything runs (exit 2, naming the option),
// and no database is written.
TEST(ThreadOption, RefusesABadCountAndWritesNothing) {
  const auto dir = testing_scratch::scratch_dir("threads", "cli");
  const Scene scene = load_scene("atrium:1");
  const std::string trace = (dir / "pf.trace").string();
  write_trace_file(generate_trace("plain_forward", testing_support::atrium_entrance_setup(scene, 8, 64, 32)), trace);
  for (const char* bad : {"0", "-3", "1025"}) {
    const std::string db = (dir / (std::string("bad") + bad + ".db")).string();
    std::ostringstream out, err;
    EXPECT_EQ(cli_main({"run", "--trace", trace, "--db", db, "--threads", bad}, out, err), 2) << bad;
    EXPECT_NE(err.str().find("--threads " + std::string(bad)), std::string::npos) << err.str();
    EXPECT_NE(err.str().find("expected 1..1024 threads per run"), std::string::npos) << err.str();
    EXPECT_FALSE(std::filesystem::exists(db)) << bad;
  }
  std::ostringstream out, err;
  EXPECT_EQ(cli_main({"run", "--trace", trace, "--db", (dir / "ok.db").string(), "--threads", "3"}, out, err), 0) << err.str();
  EXPECT_NE(out.str().find("on 3 threads"), std::string::npos) << out.str();
}

// Sweeps and studies divide the cores between their worker processes: threads per run = cores /
// workers, at least 1 (so workers x threads <= cores).
TEST(ThreadOption, WorkersDivideTheCores) {
  const unsigned cores = default_thread_count();
  EXPECT_EQ(threads_per_worker(1), cores);
  EXPECT_EQ(threads_per_worker(static_cast<int>(cores)), 1u);
  EXPECT_EQ(threads_per_worker(static_cast<int>(cores) * 4), 1u);  // more workers than cores: still 1
  for (int workers = 1; workers <= 8; ++workers) {
    EXPECT_LE(threads_per_worker(workers) * static_cast<unsigned>(workers), std::max(cores, static_cast<unsigned>(workers)));
    EXPECT_GE(threads_per_worker(workers), 1u);
  }
}

// The pool itself: every item runs exactly once, on a worker index below size(); items start in
// increasing order; the exception rethrown is the lowest item's, whichever thread ran it.
TEST(ThreadPool, RunsEveryItemOnceAndStartsThemInOrder) {
  for (const unsigned threads : {1u, 2u, 7u}) {
    ThreadPool pool(threads);
    EXPECT_EQ(pool.size(), threads);
    constexpr std::size_t kItems = 1000;
    std::vector<std::atomic<int>> runs(kItems);
    std::mutex m;
    std::vector<std::size_t> started;
    std::set<unsigned> workers;
    pool.for_each(kItems, [&](std::size_t i, unsigned w) {
      {
        std::lock_guard<std::mutex> lock(m);
        started.push_back(i);
        workers.insert(w);
      }
      runs[i].fetch_add(1);
    });
    for (std::size_t i = 0; i < kItems; ++i) EXPECT_EQ(runs[i].load(), 1) << "item " << i << " at " << threads << " threads";
    ASSERT_EQ(started.size(), kItems);
    // Taken in order: the k-th item to start is at most `threads - 1` places from k.
    for (std::size_t k = 0; k < kItems; ++k) {
      EXPECT_LE(started[k], k + threads - 1) << threads << " threads";
    }
    for (const unsigned w : workers) EXPECT_LT(w, threads);
    // The pool is reusable: a second job of one item runs on the caller's thread.
    unsigned ran_on = 99;
    pool.for_each(1, [&](std::size_t, unsigned w) { ran_on = w; });
    EXPECT_EQ(ran_on, 0u);
  }
}

TEST(ThreadPool, RethrowsTheLowestFailingItemsException) {
  for (const unsigned threads : {1u, 2u, 7u}) {
    ThreadPool pool(threads);
    try {
      pool.for_each(200, [](std::size_t i, unsigned) {
        if (i == 150 || i == 40 || i == 41) throw std::runtime_error("item " + std::to_string(i));
      });
      ADD_FAILURE() << "no exception at " << threads << " threads";
    } catch (const std::runtime_error& e) {
      EXPECT_STREQ(e.what(), "item 40") << threads << " threads";
    }
    // And it still works afterwards.
    std::atomic<std::size_t> sum{0};
    pool.for_each(100, [&](std::size_t i, unsigned) { sum += i; });
    EXPECT_EQ(sum.load(), 4950u);  // 0 + 1 + ... + 99 = 99 x 100 / 2
  }
}

// start() posts a job and returns; the caller works on something else (as the frame bins the
// next pass beside the last one's tiles), then join() runs what is left and waits: every item
// once, at any thread count (with one thread, all of them in join()); a second start() before
// the join is refused; an item's exception comes out of join(); the pool takes jobs again after.
TEST(ThreadPool, StartReturnsAtOnceAndJoinRunsTheRest) {
  for (const unsigned threads : {1u, 2u, 7u}) {
    ThreadPool pool(threads);
    constexpr std::size_t kItems = 300;
    std::vector<std::atomic<int>> runs(kItems);
    std::atomic<std::size_t> before_join{0};
    pool.start(kItems, [&](std::size_t i, unsigned) { runs[i].fetch_add(1); });
    EXPECT_TRUE(pool.started());
    EXPECT_THROW(pool.start(1, [](std::size_t, unsigned) {}), std::logic_error);
    // The caller's own work meanwhile.
    std::size_t caller_sum = 0;
    for (std::size_t i = 0; i < 1000; ++i) caller_sum += i;
    before_join = static_cast<std::size_t>(std::count_if(runs.begin(), runs.end(), [](const std::atomic<int>& r) { return r.load() > 0; }));
    if (threads == 1) {
      EXPECT_EQ(before_join.load(), 0u);  // no helper: nothing runs before join()
    }
    pool.join();
    EXPECT_FALSE(pool.started());
    EXPECT_EQ(caller_sum, 499500u);  // 0 + ... + 999
    for (std::size_t i = 0; i < kItems; ++i) EXPECT_EQ(runs[i].load(), 1) << "item " << i << " at " << threads << " threads";
    pool.start(50, [](std::size_t i, unsigned) {
      if (i == 30) throw std::runtime_error("item 30");
    });
    EXPECT_THROW(pool.join(), std::runtime_error);
    std::atomic<std::size_t> sum{0};
    pool.for_each(100, [&](std::size_t i, unsigned) { sum += i; });
    EXPECT_EQ(sum.load(), 4950u);
  }
}

#if defined(__linux__)
// Helpers asked to step back run at that niceness (their own threads only); the caller's thread
// keeps its own: with the timing model beside the frame, the caller and the timing thread keep
// their cores (models/command_processor.cpp, kHelperNicenessBesideTiming).
TEST(ThreadPool, HelpersRunAtTheNicenessAskedTheCallerAtItsOwn) {
  const auto thread_nice = [] {
    errno = 0;
    return getpriority(PRIO_PROCESS, static_cast<id_t>(syscall(SYS_gettid)));
  };
  const int own = thread_nice();
  if (own + 5 > 19) GTEST_SKIP() << "already at niceness " << own;
  ThreadPool pool(3, 5);
  std::mutex m;
  std::vector<std::pair<unsigned, int>> seen;
  // Enough items that every helper takes some (each waits until all three have started one).
  std::atomic<int> started{0};
  pool.for_each(3, [&](std::size_t, unsigned w) {
    ++started;
    while (started.load() < 3) std::this_thread::yield();
    std::lock_guard<std::mutex> lock(m);
    seen.push_back({w, thread_nice()});
  });
  ASSERT_EQ(seen.size(), 3u);
  for (const auto& [w, nice] : seen) EXPECT_EQ(nice, w == 0 ? own : own + 5) << "worker " << w;
  EXPECT_EQ(thread_nice(), own);
}
#endif

}  // namespace
}  // namespace tbdr
