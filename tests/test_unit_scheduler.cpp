// The scheduler of the timing model on hand-made work (no memory traffic, so every time is a
// service time): default rates are 4 USCs x 16 lanes x 2 ops = 128 ALU ops per clock, 32 samples
// per clock on 1 raster pipe, 2 texture units x 4 texels = 8 texels per clock, 1 primitive per
// clock of geometry; 4 tiles in flight in the ISP; the 4 USCs hold 56 resident tasks of 32
// threads each, 224 in all (a tile of 1792 shaded quads is 1792 x 4 / 32 = 224 tasks). Cycles are whole core cycles; every
// service time below is exact.
#include <gtest/gtest.h>

#include <stdexcept>
#include <vector>

#include "models/address_space.hpp"
#include "models/frame_address_map.hpp"
#include "unit_fixture.hpp"

namespace tbdr {
namespace {

using namespace unit;

// Times read back from ticks (whole picoseconds) at 600 MHz differ from whole cycles by less than
// a picosecond per cycle edge: 1001 cycles end at ceil(1001 x 1666.67) ps = 1001.0004 cycles.
constexpr double kTickRounding = 0.01;

/// One pass of one render with `tiles`.
FrameWork one_render(std::vector<TileWork> tiles, BinningWork binning = {}) {
  return frame_work({pass_work("pass0", {render_work(std::move(tiles), binning)})});
}

TEST(UnitScheduler, AnAluBoundTileTakesItsOpsOverTheUscRate) {
  // ISP: max(1 primitive, 32 samples / 32) = 1 cycle; USCs: 128000 / 128 = 1000 cycles.
  const TimingResult r = run_schedule(one_render({tile_work(0, 0, 1, 32, 128000)}));
  EXPECT_EQ(r.frame_cycles, 1001.0);
  EXPECT_EQ(r.unit(TimedUnit::Usc).busy_cycles, 1000.0);
  EXPECT_EQ(r.unit(TimedUnit::Isp).busy_cycles, 1.0);
  EXPECT_EQ(r.unit(TimedUnit::Isp).stalled_cycles, 0.0);
  // One tile row for the heat map: fetched at 0, stored at 1001.
  ASSERT_EQ(r.tiles.size(), 1u);
  EXPECT_NEAR(r.tiles[0].cycles, 1001.0, kTickRounding);
}

TEST(UnitScheduler, TwiceTheUscsHalveTheShadingTime) {
  // 8 USCs: 128000 / (8 x 16 x 2) = 500; as do 32 lanes, or 4 ops per lane per clock.
  const FrameWork w = one_render({tile_work(0, 0, 1, 32, 128000)});
  for (const char* set : {"usc.count=8", "usc.lanes=32", "usc.alu_ops_per_lane_per_clock=4"}) {
    const TimingResult r = run_schedule(w, {set});
    EXPECT_EQ(r.unit(TimedUnit::Usc).busy_cycles, 500.0) << set;
    EXPECT_EQ(r.frame_cycles, 501.0) << set;
  }
}

TEST(UnitScheduler, AFillBoundTileTakesItsSamplesOverTheRasterRate) {
  // 64000 samples / 32 per clock = 2000 cycles; with 2 raster pipes 1000. No shading.
  const FrameWork w = one_render({tile_work(0, 0, 10, 64000, 0)});
  const TimingResult one = run_schedule(w);
  EXPECT_EQ(one.frame_cycles, 2000.0);
  EXPECT_EQ(one.unit(TimedUnit::Isp).busy_cycles, 2000.0);
  const TimingResult two = run_schedule(w, {"isp.raster_pipes=2"});
  EXPECT_EQ(two.frame_cycles, 1000.0);
  // Setup bound: 3000 primitives of few samples take 3000 cycles (one per clock).
  EXPECT_EQ(run_schedule(one_render({tile_work(0, 0, 3000, 3200, 0)})).frame_cycles, 3000.0);
}

TEST(UnitScheduler, ATextureBoundTileTakesItsTexelsOverTheTextureRate) {
  // 8000 texels / (2 units x 4 texels per clock) = 1000 cycles on the texture units, while the
  // ALU work takes 128 ops / 128 = 1 cycle on the USCs.
  const TimingResult r = run_schedule(one_render({tile_work(0, 0, 0, 0, 128, 8000)}));
  EXPECT_EQ(r.unit(TimedUnit::Texture).busy_cycles, 1000.0);
  EXPECT_EQ(r.unit(TimedUnit::Usc).busy_cycles, 1.0);
  EXPECT_EQ(r.frame_cycles, 1000.0);
  const TimingResult more = run_schedule(one_render({tile_work(0, 0, 0, 0, 128, 8000)}), {"texture.units=4"});
  EXPECT_EQ(more.frame_cycles, 500.0);
}

/// Four tiles, each 1000 cycles on the ISP (32000 samples) and 1000 on the USCs (128000 ops).
FrameWork four_balanced_tiles() {
  return one_render({tile_work(0, 0, 1, 32000, 128000), tile_work(1, 0, 1, 32000, 128000),
                     tile_work(0, 1, 1, 32000, 128000), tile_work(1, 1, 1, 32000, 128000)});
}

TEST(UnitScheduler, OneTilesShadingOverlapsTheNextOnesRasterisation) {
  // ISP 0-1000, 1000-2000, ..., 3000-4000; each tile's shading follows its ISP work: USCs
  // 1000-2000, ..., 4000-5000. Frame 1000 + 4 x 1000 = 5000. A tile leaves the ISP's tiles in
  // flight when the USCs take it, so even 1 tile in flight keeps the ISP and USCs overlapped
  // (with no memory traffic the tile fetch takes no time).
  for (const char* set : {"isp.tiles_in_flight=4", "isp.tiles_in_flight=1"}) {
    const TimingResult r = run_schedule(four_balanced_tiles(), {set});
    EXPECT_EQ(r.frame_cycles, 5000.0) << set;
    EXPECT_EQ(r.unit(TimedUnit::Isp).busy_cycles, 4000.0) << set;
    EXPECT_EQ(r.unit(TimedUnit::Usc).busy_cycles, 4000.0) << set;
  }
}

TEST(UnitScheduler, FullTaskSlotsStallTheIsp) {
  // Three tiles of 100 ISP cycles (3200 samples), 1000 USC cycles and 1792 quads = 224 tasks
  // each. 4 x 56 = 224 slots hold one such tile: tile 1 is resolved at 200 but waits until tile 0
  // leaves the USCs at 1100 (900 stalled); tile 2 rasterises 1100-1200 and waits for 2100 (900).
  // Frame: 100 + 3 x 1000 = 3100.
  std::vector<TileWork> tiles = {tile_work(0, 0, 1, 3200, 128000), tile_work(1, 0, 1, 3200, 128000),
                                 tile_work(0, 1, 1, 3200, 128000)};
  for (auto& t : tiles) t.quads = 1792;
  const FrameWork w = one_render(tiles);
  const TimingResult r = run_schedule(w);
  EXPECT_EQ(r.frame_cycles, 3100.0);
  EXPECT_EQ(r.unit(TimedUnit::Isp).busy_cycles, 300.0);
  EXPECT_NEAR(r.unit(TimedUnit::Isp).stalled_cycles, 1800.0, kTickRounding);
  // 4 x 168 = 672 slots hold all three tiles (3 x 224): no stall, the same ALU-bound frame.
  const TimingResult deep = run_schedule(w, {"usc.tasks_in_flight=168"});
  EXPECT_NEAR(deep.unit(TimedUnit::Isp).stalled_cycles, 0.0, kTickRounding);
  EXPECT_EQ(deep.frame_cycles, 3100.0);
  // 4 x 167 = 668 slots hold two (448 + 224 > 668): tile 2, resolved at 300, waits for tile 0 to
  // leave at 1100: 800 stalled.
  const TimingResult two = run_schedule(w, {"usc.tasks_in_flight=167"});
  EXPECT_NEAR(two.unit(TimedUnit::Isp).stalled_cycles, 800.0, kTickRounding);
}

TEST(UnitScheduler, QuadsWithNothingToRunHoldNoTaskSlots) {
  // The three tiles above with 1792 quads each, of which 896 idle (a depth-only shader's:
  // TileWork::idle_quads): their tasks retire at once, so a tile holds 896 x 4 / 32 = 112 of the
  // 224 slots. Tiles 0 and 1 are resident together; tile 2, resolved at 300, waits for tile 0 to
  // leave at 1100: 800 stalled instead of 1800 (every quad working: 224 slots a tile). The frame
  // is the USCs' 100 + 3 x 1000 = 3100 either way.
  std::vector<TileWork> tiles = {tile_work(0, 0, 1, 3200, 128000), tile_work(1, 0, 1, 3200, 128000),
                                 tile_work(0, 1, 1, 3200, 128000)};
  for (auto& t : tiles) t.quads = 1792;
  const TimingResult working = run_schedule(one_render(tiles));
  EXPECT_NEAR(working.unit(TimedUnit::Isp).stalled_cycles, 1800.0, kTickRounding);
  for (auto& t : tiles) t.idle_quads = 896;
  const TimingResult half_idle = run_schedule(one_render(tiles));
  EXPECT_NEAR(half_idle.unit(TimedUnit::Isp).stalled_cycles, 800.0, kTickRounding);
  EXPECT_EQ(half_idle.frame_cycles, 3100.0);
  EXPECT_EQ(working.frame_cycles, 3100.0);
}

TEST(UnitScheduler, VertexShadingCompetesWithFragmentShadingForTheUscs) {
  // Pass a: one 1000-cycle ALU tile. Pass b bins 1000 primitives (1000 cycles on the binning
  // engine) whose vertex shaders need 128000 ops = 1000 USC cycles. b's binning starts at 0
  // (before a's tile: a's binning has nothing to do) and reserves the USCs 0-1000; a's tile then
  // shades 1000-2000; b's tile 2000-3000. Were the vertex shaders on a unit of their own, a's
  // tile would shade 0-1000 and the frame end at 2000.
  BinningWork vs = binning_work(1000);
  vs.vertex_alu_ops = 128000;
  const RenderWork a = render_work({tile_work(0, 0, 0, 0, 128000)});
  const RenderWork b = render_work({tile_work(0, 0, 0, 0, 128000)}, vs);
  const TimingResult r = run_schedule(frame_work({pass_work("a", {a}), pass_work("b", {b})}));
  EXPECT_EQ(r.unit(TimedUnit::Usc).busy_cycles, 3000.0);
  EXPECT_EQ(r.frame_cycles, 3000.0);
}

TEST(UnitScheduler, BinningOfTheNextPassOverlapsTheTilesOfThisOne) {
  // Two passes, each binning 1000 primitives (1000 cycles at 1 per clock) and one 1000-cycle
  // ALU tile. Pass 1 bins 1000-2000 while pass 0's tile shades 1000-2000; its tile 2000-3000.
  const RenderWork r = render_work({tile_work(0, 0, 0, 0, 128000)}, binning_work(1000));
  const TimingResult two_passes = run_schedule(frame_work({pass_work("a", {r}), pass_work("b", {r})}));
  EXPECT_EQ(two_passes.frame_cycles, 3000.0);
  EXPECT_EQ(two_passes.unit(TimedUnit::Binning).busy_cycles, 2000.0);
  ASSERT_EQ(two_passes.commands.size(), 2u);
  EXPECT_NEAR(two_passes.commands[1].start_cycle, 1000.0, kTickRounding);
  EXPECT_NEAR(two_passes.commands[1].binning_end_cycle, 2000.0, kTickRounding);
  // The same two renders as one pass cut by a partial render: the second binning needs the
  // parameter buffer the first render's tiles are reading: 1000 + 1000 + 1000 + 1000 = 4000.
  RenderWork partial = r;
  partial.partial = true;
  const TimingResult one_pass = run_schedule(frame_work({pass_work("a", {partial, r})}));
  EXPECT_EQ(one_pass.frame_cycles, 4000.0);
}

TEST(UnitScheduler, ADispatchTakesItsOpsOverTheUscRate) {
  // 256000 ops / 128 = 2000 cycles; 32000 texels / 8 = 4000 cycles: the larger bounds it.
  EXPECT_EQ(run_schedule(frame_work({dispatch_work("d", 256000)})).frame_cycles, 2000.0);
  EXPECT_EQ(run_schedule(frame_work({dispatch_work("d", 256000, 32000)})).frame_cycles, 4000.0);
}

TEST(UnitScheduler, ARenderAfterAPartialRenderReloadsWhatItStoredFromDram) {
  // A pass of two renders over the 4 tiles of a 64x64 frame: the partial render stores 4 KiB of
  // colour per tile (everything on chip leaves it: 16 KiB), the render after it reloads the same
  // 4 KiB per tile from the partial renders' slots and stores its result (16 KiB). Tile stores
  // stream past the SLC (the pixel back end's misses do not allocate, docs/memory-model.md), so
  // every reload comes from DRAM: 16 KiB read, 32 KiB written. At 8 KiB per tile every figure
  // doubles, and the frame takes longer. (Each tile's reload fits the slot the partial render
  // stored it to; a larger one throws: FrameAddressMap::end_command.)
  auto run = [](std::uint64_t bytes) {
    std::vector<TileWork> stored, reloaded;
    for (int t = 0; t < 4; ++t) {
      TileWork a = tile_work(t % 2, t / 2, 1, 32, 1000);
      a.store_bytes[static_cast<std::size_t>(DramClass::Color)] = bytes;
      stored.push_back(a);
      TileWork b = tile_work(t % 2, t / 2, 1, 32, 1000);
      b.load_bytes[static_cast<std::size_t>(DramClass::Color)] = bytes;
      b.store_bytes[static_cast<std::size_t>(DramClass::Color)] = bytes;
      reloaded.push_back(b);
    }
    return run_schedule(frame_work({pass_work("p", {render_work(stored, {}, true), render_work(reloaded)})}));
  };
  const TimingResult four = run(4096), eight = run(8192);
  EXPECT_EQ(four.requested.reads(DramClass::Color), 4u * 4096u);
  EXPECT_EQ(four.dram.reads(DramClass::Color), 4u * 4096u);
  EXPECT_EQ(four.dram.writes(DramClass::Color), 8u * 4096u);
  EXPECT_EQ(eight.dram.reads(DramClass::Color), 2 * four.dram.reads(DramClass::Color));
  EXPECT_EQ(eight.dram.writes(DramClass::Color), 2 * four.dram.writes(DramClass::Color));
  EXPECT_GT(eight.frame_cycles, four.frame_cycles);
}

TEST(UnitScheduler, ATileThatStoresMoreThanItsSlotHoldsIsRefused) {
  // The slot comes from the pass's attachments before its tiles render (the functional run's
  // TileMemory::tile_slot_bytes); a tile storing past it would write into its neighbour's slot.
  TileWork t = tile_work(0, 0, 1, 32, 1000);
  t.store_bytes[static_cast<std::size_t>(DramClass::Color)] = 4096;
  CommandWork pass = pass_work("p", {render_work({t})});
  EXPECT_NO_THROW(run_schedule(frame_work({pass})));
  pass.tile_slot_bytes = 2048;
  EXPECT_THROW(run_schedule(frame_work({pass})), std::logic_error);
}

TEST(UnitScheduler, FrameTimeIsCyclesAtTheCoreClock) {
  // 500 MHz: 2 ns per cycle; 1001 cycles = 2002000 ps.
  const TimingResult r = run_schedule(one_render({tile_work(0, 0, 1, 32, 128000)}), {"gpu.core_clock_mhz=500"});
  EXPECT_EQ(r.frame_cycles, 1001.0);
  EXPECT_EQ(r.frame_time_ps, 2002000.0);
}

// The timing model places a command's buffer area when its first fragment job starts, and the
// other regions when it takes the commands (models/frame_address_map.hpp): how the two interleave
// depends on the schedule, which every swept parameter changes (with a faster binning engine the
// pass after a dispatch is taken before the dispatch starts). The addresses must not: the buffer
// areas live in their own range, each range in command order. Two interleavings of one frame
// (a pass, a dispatch, a pass reading what the dispatch wrote) give the same addresses.
TEST(UnitScheduler, AddressesDoNotDependOnHowTheScheduleInterleavesPlacements) {
  TileWork t = tile_work(0, 0, 1, 32, 1000);
  t.store_bytes[static_cast<std::size_t>(DramClass::Gbuffer)] = 4096;
  BinningWork b = binning_work(100);
  b.vertex_fetch_bytes = 6000;
  CommandWork first = pass_work("pass0.first", {render_work({t}, b)});
  CommandWork dispatch = dispatch_work("dispatch1.between", 1000);
  dispatch.read_bytes[static_cast<std::size_t>(DramClass::Gbuffer)] = 4096;
  dispatch.write_bytes[static_cast<std::size_t>(DramClass::LightLists)] = 10000;
  CommandWork last = pass_work("pass2.last", {render_work({t}, b)});
  last.read_bytes[static_cast<std::size_t>(DramClass::LightLists)] = 10000;
  const FrameWork frame = frame_work({first, dispatch, last});

  struct Layout {
    std::vector<std::uint64_t> buffers, vertices, tiles;
  };
  // `early`: the last pass is taken (its slots, its vertex range) before the dispatch starts.
  auto layout = [&](bool early) {
    AddressSpace space;
    FrameAddressMap map(frame, 65536, space);
    map.add_command(first);
    map.add_render(0, first.renders[0]);
    map.place_buffers(0, first);
    map.add_command(dispatch);
    if (!early) map.place_buffers(1, dispatch);
    map.add_command(last);
    map.add_render(2, last.renders[0]);
    if (early) map.place_buffers(1, dispatch);
    map.end_command(first);
    map.end_command(dispatch);
    map.place_buffers(2, last);
    Layout l;
    for (std::size_t c = 0; c < 3; ++c) {
      l.buffers.push_back(map.buffers(c));
      l.tiles.push_back(c == 1 ? 0 : map.tile(c, t));
    }
    l.vertices = {map.vertices(0, 0), map.vertices(2, 0)};
    return l;
  };
  const Layout early = layout(true), late = layout(false);
  EXPECT_EQ(early.buffers, late.buffers);
  EXPECT_EQ(early.vertices, late.vertices);
  EXPECT_EQ(early.tiles, late.tiles);
  // Buffer areas in the high range, one after another in command order; the rest below it.
  EXPECT_EQ(early.buffers[0], AddressSpace::kHighBase);
  EXPECT_LT(early.buffers[0], early.buffers[1]);
  EXPECT_LT(early.buffers[1], early.buffers[2]);
  EXPECT_LT(early.vertices[1], AddressSpace::kHighBase);
  EXPECT_LT(early.tiles[2], AddressSpace::kHighBase);
  // Before its first fragment job a command has no buffer area.
  AddressSpace space;
  FrameAddressMap map(frame, 65536, space);
  map.add_command(first);
  EXPECT_THROW(map.buffers(0), std::logic_error);
}

}  // namespace
}  // namespace tbdr
