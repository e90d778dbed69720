// The timing and energy models: roofline bounds, conservation, determinism, the on-chip cliff.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "kernel/errors.hpp"
#include "models/hw_config.hpp"
#include "models/command_processor.hpp"
#include "models/energy.hpp"
#include "models/sram_energy.hpp"
#include "app/run_driver.hpp"
#include "synthetic_scene.hpp"
#include "timed_run.hpp"
#include "stat_lookup.hpp"

namespace tbdr {
namespace {

using namespace synthetic;



/// A frame of `size` x `size` pixels.
Trace frame_of(int size) {
  Trace t = base_trace();
  t.frame.width = size;
  t.frame.height = size;
  return t;
}

/// A `size` x `size` frame whose pass draws one quad "wall" at depth 3 (add_quad over pixels px0
/// to px1 of the 64-pixel synthetic view) with a shader of `alu_ops` ALU ops and `tex_fetches`
/// fetches; run_wall appends the pass, so a test can widen it first.
struct WallFrame {
  Scene scene = base_scene();
  Trace trace;
  PassDesc pass = base_pass();
};
WallFrame wall_frame(int size, std::uint32_t alu_ops, std::uint32_t tex_fetches, float px0, float px1) {
  WallFrame w;
  w.trace = frame_of(size);
  w.trace.shaders[0].alu_ops = alu_ops;
  w.trace.shaders[0].tex_fetches = tex_fetches;
  add_quad(w.scene, "wall", 3, px0, px1, 0);
  w.pass.draws = {draw_of("wall")};
  return w;
}
Timed run_wall(WallFrame w, const std::vector<std::string>& sets) {
  w.trace.commands.push_back(w.pass);
  return run_timed(w.trace, w.scene, sets);
}

/// Adds color targets to `w` until its pass has `targets`, copies of the first named `prefix`<i>
/// with `usage`, and lets the shader write them all.
void widen(WallFrame& w, int targets, const std::string& prefix, AttachmentUsage usage) {
  for (int i = 1; i < targets; ++i) {
    Attachment a = w.pass.attachments[0];
    a.name = prefix + std::to_string(i);
    a.usage = usage;
    w.pass.attachments.push_back(a);
  }
  w.trace.shaders[0].color_outputs = static_cast<std::uint32_t>(targets);
}

TEST(TimingRoofline, FillBoundFrameMatchesTheRasterRate) {
  // 64 opaque full-frame quads front to back at 256x256: every layer is rasterised and depth
  // tested (64 x 65536 samples), only the front one is shaded (1 ALU op). Bound:
  //   cycles = samples / (isp.samples_per_clock x isp.raster_pipes) = 4194304 / 32 = 131072.
  Scene s = base_scene();
  Trace t = frame_of(256);
  t.shaders[0].alu_ops = 1;
  t.shaders[0].tex_fetches = 0;
  PassDesc p = base_pass();
  for (int i = 0; i < 64; ++i) {
    const std::string name = "layer" + std::to_string(i);
    add_quad(s, name, 2.0f + 0.1f * static_cast<float>(i), -256, 512, 0);
    p.draws.push_back(draw_of(name));
  }
  t.commands.push_back(p);
  const Timed r = run_timed(t, s, {});
  const double samples = stat(r.stats, "frame/isp", "samples_rasterised");
  ASSERT_EQ(samples, 64.0 * 65536);
  const double bound = samples / 32.0;
  EXPECT_NEAR(r.timing.frame_cycles, bound, 0.05 * bound) << "fill bound " << bound;
}

TEST(TimingRoofline, AluBoundFrameMatchesTheUscRate) {
  // One full-frame quad, 4000 ALU ops per fragment, 256x256 (no helper lanes: whole quads).
  // Bound: cycles = 65536 x 4000 / (usc.count 4 x lanes 16 x 2 ops per clock) = 2048000.
  const Timed r = run_wall(wall_frame(256, 4000, 0, -256, 512), {});
  // The quad's two triangles split the 2x2 quads along its diagonal: each launches those quads,
  // so 256 helper lanes run the shader too.
  EXPECT_EQ(stat(r.stats, "frame/tsp", "helper_lanes"), 256);
  EXPECT_EQ(stat(r.stats, "frame/tsp", "fragment_alu_ops"), (65536.0 + 256) * 4000);
  const double bound = (65536.0 + 256) * 4000 / (4 * 16 * 2);
  EXPECT_NEAR(r.timing.frame_cycles, bound, 0.05 * bound) << "ALU bound " << bound;
}

TEST(TimingRoofline, StoreBoundFrameMatchesDramBandwidth) {
  // One cheap full-frame quad at 512x512 writing 8 rgba32f targets that are all stored:
  // 512 x 512 x 128 B = 33554432 B. Bound: bytes / DRAM peak bandwidth (12.8 GB/s) = 2.6214 ms
  // = 1572864 cycles at 600 MHz (the pixel back end alone would need 1048576 cycles), over the
  // bus time refresh leaves: each refresh idles it tWR + tRP + tRFC + tRCD + RL per tREFI
  // (docs/memory-model.md; 1 - 197.5 / 3900 = 94.9 % with LPDDR3): 1656 k cycles.
  WallFrame w = wall_frame(512, 1, 0, -512, 1024);
  w.pass.attachments[0].format = Format::Rgba32f;
  widen(w, 8, "mrt", w.pass.attachments[0].usage);
  const Timed r = run_wall(w, {"pls.tile_buffer_bits_per_pixel=2048"});
  ASSERT_EQ(r.frame.dram.writes(DramClass::Color), 512u * 512u * 128u);
  const DramParams d = resolve_config({}, {}).hw.dram;
  const double bound = 512.0 * 512 * 128 / 12.8e9 * 600e6 /
                       (1.0 - (d.t_wr_ns + d.t_rp_ns + d.t_rfc_ns + d.t_rcd_ns + d.t_cl_ns) / d.t_refi_ns);
  EXPECT_NEAR(r.timing.frame_cycles, bound, 0.05 * bound) << "DRAM bound " << bound;
}

/// One full-frame 512x512 quad mapping an 8192x8192 texture (mip level 4: one texel per pixel),
/// its shader 1 ALU op and `fetches` fetch slots; the trace and scene of the texture tests below.
WallFrame textured_wall(std::uint32_t fetches) {
  WallFrame w = wall_frame(512, 1, fetches, 0, 64);
  TextureInfo tex;
  tex.name = "big";
  tex.format = "procedural";
  tex.width = tex.height = 8192;
  tex.channels = 4;
  w.scene.textures.push_back(tex);
  w.scene.materials[0].base_color_texture = 0;
  return w;
}

TEST(TimingLatencyHiding, MoreResidentTasksHideTextureLatencyUntilTheBandwidthBound) {
  // One fetch per pixel from a 1 MiB footprint that misses the caches (a 32x32 tile reads its
  // 4 KB, about 60 lines, once); the texture units filter 64 texels per clock so they never bind.
  // A tile is 256 quads = 32 tasks of 32 threads and each task keeps its lines in flight (about
  // 20: 8 quads of 2.5 distinct lines), up to texture.outstanding_requests (64) per tile. With 1
  // task per USC (4 slots) one tile is resident at a time and its ~60 lines take a few loaded
  // DRAM round trips while nothing else reads: latency bound, measured 138 k cycles (540 a tile;
  // how loaded a round trip is depends on how the texture reads and the colour stores share DRAM
  // rows: 193 k cycles when the framebuffer sat below the textures in the address map). From 16
  // per USC (64 slots) two 32-task tiles are resident, from 32 four: their reads overlap until the
  // DRAM's 12.8 GB/s binds: 1 MiB + the 1 MiB colour store = 2 MiB / 12.8 GB/s x 600 MHz = 98 k
  // cycles. So 1 task per USC is at least 1.3x the bound.
  const WallFrame w = textured_wall(1);
  std::vector<double> cycles;
  for (int tasks : {1, 2, 4, 8, 16, 32, 64}) {
    // DRAM power-down off (it is on by default): its exits add tXP to requests that find a channel
    // idle, a latency that varies with how the tiles' streams interleave (measured with it on:
    // 138.8 k, 104.9 k, 100.2 k, 104.2 k cycles at 1, 16, 32, 64 tasks: +4.0 % at the last step, against
    // 100.6 k -> 102.8 k, +2.2 %, with it off).
    const Timed r = run_wall(w, {"texture.texels_per_clock=64", "dram.powerdown_after_ns=0",
                                 "usc.tasks_in_flight=" + std::to_string(tasks)});
    cycles.push_back(r.timing.frame_cycles);
  }
  // Never slower by more than the row-buffer conflicts more interleaved tile streams cause
  // (measured: 1.8 % from 128 to 256 slots).
  for (std::size_t i = 1; i < cycles.size(); ++i)
    EXPECT_LE(cycles[i], cycles[i - 1] * 1.025) << "more resident tasks must not be slower (step " << i << ")";
  EXPECT_GT(cycles[0], 1.3 * cycles.back()) << "1 task per USC exposes the latency";
  const double bound = 2.0 * 1024 * 1024 / 12.8e9 * 600e6;
  EXPECT_NEAR(cycles.back(), bound, 0.15 * bound) << "enough tasks: the DRAM bound";
}

TEST(TimingRoofline, TextureBoundFrameMatchesDramBandwidth) {
  // One full-frame quad at 512x512 mapping an 8192x8192 texture (16 texels per pixel: mip level 4,
  // 512x512 texels) with 8 fetch slots (8 copies) and 1 ALU op: the frame is its texture reads
  // (8 x 1 MiB footprints; border lines shared by neighbouring tiles may hit in the SLC) plus a
  // 1 MiB colour store. 2.1 M bilinear fetches (one filtered texel each): at the default 2 x 4
  // filtered texels per clock the texture units take 262 k cycles, near the DRAM bound; at 16 per
  // clock (66 k cycles) the bound is the DRAM: bytes moved / DRAM peak bandwidth (12.8 GB/s), at
  // 600 MHz.
  const Timed r = run_wall(textured_wall(8), {"texture.texels_per_clock=16"});
  const double footprint = static_cast<double>(r.timing.texture_footprint_lines * 64);
  const double texture = static_cast<double>(r.timing.dram.reads(DramClass::Textures));
  const double moved = static_cast<double>(r.timing.dram.total_read() + r.timing.dram.total_written());
  EXPECT_GT(footprint, 0.9 * 8 * 1024 * 1024) << "8 copies of a 512x512 level, 4 B per texel";
  EXPECT_LT(footprint, 1.3 * 8 * 1024 * 1024) << "each line about once per tile";
  EXPECT_LE(texture, footprint);
  EXPECT_GT(texture, 0.8 * moved) << "a texture-bound frame";
  // Within 10 %, not 5 %: four tiles stream 8 copies each at once and the memory system admits
  // them in turn, so their lines conflict in the banks (measured: 93 % row hits, 11.7 GB/s
  // achieved, 9.3 % over the bound). Refresh leaves 1 - (tRP + tRFC + tRCD + RL) / tREFI of the
  // bus (95.3 % with LPDDR3; docs/memory-model.md).
  const DramParams d = resolve_config({}, {}).hw.dram;
  const double bound = moved / 12.8e9 * 600e6 / (1.0 - (d.t_rp_ns + d.t_rfc_ns + d.t_rcd_ns + d.t_cl_ns) / d.t_refi_ns);
  EXPECT_NEAR(r.timing.frame_cycles, bound, 0.10 * bound) << "DRAM bound " << bound;
  // Every footprint line went through the texture cache; quads re-read most lines within a tile.
  EXPECT_EQ(r.timing.texture_footprint_lines * 64, r.frame.dram.reads(DramClass::Textures));
  EXPECT_GT(r.timing.texture_line_accesses, r.timing.texture_footprint_lines);
}

Trace atrium_like(Scene& s) {
  // A small frame with opaque, punch-through and translucent layers (the functional tests' scene).
  s = base_scene();
  add_quad(s, "far", 5, -32, 96, 0);
  add_quad(s, "leaves", 3, -32, 96, 1);
  add_quad(s, "glass", 2, -32, 40, 2);
  Trace t = base_trace();
  PassDesc p = base_pass();
  p.draws = {draw_of("far"), draw_of("leaves"), draw_of("glass", "blend")};
  t.commands.push_back(p);
  return t;
}

TEST(TimingConservation, IssuedBytesEqualFunctionalBytesPerClass) {
  Scene s;
  const Trace t = atrium_like(s);
  for (const char* budget : {"pls.tile_buffer_bits_per_pixel=128", "tiling.pb_capacity_bytes=65536"}) {
    const Timed r = run_timed(t, s, {budget});
    for (std::size_t c = 0; c < kDramClassCount; ++c) {
      EXPECT_EQ(r.timing.requested.read_bytes[c], r.frame.dram.read_bytes[c]) << to_string(static_cast<DramClass>(c));
      EXPECT_EQ(r.timing.requested.write_bytes[c], r.frame.dram.write_bytes[c]) << to_string(static_cast<DramClass>(c));
    }
  }
}

TEST(TimingConservation, EnergyIsTheSumOfCountersTimesUnitCosts) {
  Scene s;
  const Trace t = atrium_like(s);
  const Timed r = run_timed(t, s, {});
  const HwConfig hw = resolve_config({}, {}).hw;
  const auto& st = r.stats;
  // Tile buffer and tag/depth: reads at the array's CACTI read energy per byte, writes at its write
  // energy (sized by the tile and its tiles in flight, at energy.process_nm).
  const auto pjb = [&](OnChipArray a, bool write) { return on_chip_pj_per_byte(hw, a, write); };
  const double tile = (stat(st, "frame/tsp", "tile_buffer_read_bytes") + stat(st, "frame/tile_memory", "tile_store_bytes") +
                       stat(st, "frame/tsp", "pls_bytes_accessed")) * pjb(OnChipArray::TileBuffer, false) +
                      (stat(st, "frame/tsp", "tile_buffer_write_bytes") + stat(st, "frame/tile_memory", "tile_load_bytes") +
                       stat(st, "frame/tile_memory", "tile_clear_bytes")) * pjb(OnChipArray::TileBuffer, true);
  const double tag = stat(st, "frame/isp", "tag_buffer_read_bytes") * pjb(OnChipArray::TagBuffer, false) +
                     stat(st, "frame/isp", "tag_buffer_write_bytes") * pjb(OnChipArray::TagBuffer, true) +
                     stat(st, "frame/isp", "depth_buffer_read_bytes") * pjb(OnChipArray::DepthBuffer, false) +
                     stat(st, "frame/isp", "depth_buffer_write_bytes") * pjb(OnChipArray::DepthBuffer, true);
  // An ALU op: its arithmetic at 45 nm scaled to the node, plus 8 operand bytes (3/4 read, 1/4 written).
  const double scale = process_energy_scale(hw.energy.process_nm, hw.energy.vdd_v);
  const double alu = (stat(st, "frame/tsp", "fragment_alu_ops") + stat(st, "frame/geometry", "vertex_alu_ops")) *
                     (hw.energy.alu_op_pj_45nm * scale +
                      hw.energy.register_file_bytes_per_op *
                          (0.75 * pjb(OnChipArray::RegisterFile, false) + 0.25 * pjb(OnChipArray::RegisterFile, true)));
  const double tex = stat(st, "frame/tsp", "texels_filtered") * hw.energy.texel_pj_45nm * scale;
  const double dram_bits_read = stat(st, "mem/dram", "read_bytes") * 8, dram_bits_written = stat(st, "mem/dram", "write_bytes") * 8;
  const double dram = dram_bits_read * hw.energy.dram_read_pj_per_bit + dram_bits_written * hw.energy.dram_write_pj_per_bit +
                      (dram_bits_read + dram_bits_written) * hw.energy.dram_io_pj_per_bit +
                      stat(st, "mem/dram", "activates") * hw.energy.dram_activate_precharge_nj * 1000.0 +
                      stat(st, "mem/dram", "energy_background_pj") + stat(st, "mem/dram", "refreshes") * hw.dram.refresh_nj * 1000.0;
  const double statics = static_power(hw).total_mw() * r.timing.frame_time_ps * 1e-3;
  EXPECT_NEAR(stat(st, "frame/energy", "static_power_mw"), static_power(hw).total_mw(), 1e-9);
  const double caches = stat(st, "mem", "cache_energy_pj");
  EXPECT_NEAR(stat(st, "mem/dram", "energy_pj"), dram, 1e-6 * dram);
  const double total = tile + tag + alu + tex + dram + statics + caches;
  EXPECT_NEAR(stat(st, "frame/energy", "total_pj"), total, 1e-9 * total);
  EXPECT_GT(tile, 0);
  EXPECT_GT(tag, 0);
  EXPECT_GT(dram, 0);
}

TEST(TimingDeterminism, SameRunTwiceGivesIdenticalFigures) {
  Scene s;
  const Trace t = atrium_like(s);
  const Timed a = run_timed(t, s, {});
  const Timed b = run_timed(t, s, {});
  EXPECT_EQ(a.timing.frame_cycles, b.timing.frame_cycles);
  EXPECT_EQ(a.timing.events, b.timing.events);
  ASSERT_EQ(a.timing.tiles.size(), b.timing.tiles.size());
  for (std::size_t i = 0; i < a.timing.tiles.size(); ++i) EXPECT_EQ(a.timing.tiles[i], b.timing.tiles[i]);
  ASSERT_EQ(a.stats.size(), b.stats.size());
  for (std::size_t i = 0; i < a.stats.size(); ++i) {
    if (a.stats[i].scope == "frame/host") continue;
    EXPECT_EQ(a.stats[i].value, b.stats[i].value) << a.stats[i].scope << " " << a.stats[i].name;
  }
}

/// Adds k transient 32-bit G-buffer targets g1..gk (copies of the colour, store=dont_care) to a
/// pass; returns their names.
std::vector<std::string> add_transient_gbuffer(PassDesc& p, int k) {
  std::vector<std::string> names;
  for (int i = 1; i <= k; ++i) {
    Attachment a = p.attachments[0];
    a.name = "g" + std::to_string(i);
    a.usage = AttachmentUsage::Gbuffer;
    a.store = StoreOp::DontCare;
    a.transient = true;
    p.attachments.push_back(a);
    names.push_back(a.name);
  }
  return names;
}

/// Frame cycles of a 512x512 pass keeping k 32-bit G-buffer targets on chip (transient,
/// store=dont_care) beside its stored colour, one cheap full-frame layer, on the GX6250 preset's
/// 256 bits per pixel (2 USCs) plus `sets`. The tile buffer moves 16 B per clock per USC here (set,
/// not the fitted default, so that the steps' arithmetic is in round numbers).
std::vector<double> onchip_gbuffer_cliff(int k_first, int k_last, std::vector<std::string> sets = {}) {
  Scene s = base_scene();
  add_quad(s, "wall", 3, -512, 1024, 0);
  sets.insert(sets.begin(), {"usc.count=2", "texture.units=1", "pls.tile_buffer_bits_per_pixel=256",
                             "pls.tile_buffer_bytes_per_clock=16"});
  std::vector<double> cycles;
  for (int k = k_first; k <= k_last; ++k) {
    Trace t = frame_of(512);
    t.shaders[0].alu_ops = 4;
    t.shaders[0].tex_fetches = 0;
    t.shaders[0].color_outputs = static_cast<std::uint32_t>(k + 1);
    PassDesc p = base_pass();
    add_transient_gbuffer(p, k);
    p.draws = {draw_of("wall")};
    t.commands.push_back(p);
    const Timed r = run_timed(t, s, sets);
    cycles.push_back(r.timing.frame_cycles);
  }
  return cycles;
}

TEST(TimingCliff, OnChipGbufferCostsTileBufferBandwidthThenSpills) {
  // k = 4..8 transient 32-bit targets + the 32-bit colour: 160 .. 288 bits per pixel against 256
  // on chip. Within the budget each target adds 4 B/pixel of tile-buffer writes at 2 USCs x 16
  // B/clock = 32 B/clock: 512 x 512 x 4 / 32 = 32768 cycles a step (the finite on-chip bandwidth,
  // the slope of Imagination's GX6250 table). Past it the over-budget 32 of 288 bits of every
  // tile-buffer access also go to memory: 1 MiB written and read back (2 MiB of spill traffic),
  // on top of the same USC data-path bytes. This pass has no subpass boundary to split at, so
  // split_render spills too; its spill traffic hides behind the tile-buffer bound (3 MiB at 12.8
  // GB/s = 147 k cycles < 262 k), so the last step is the slope again (the cliff of a pass with
  // subpasses is SubpassesPastTheBudgetSplitTheRender).
  const std::vector<double> c = onchip_gbuffer_cliff(4, 8);
  for (std::size_t i = 0; i < c.size(); ++i) std::printf("[ cliff    ] %3zu bits/pixel: %.3f ms\n", 32 * (5 + i), c[i] / 600e3);
  for (std::size_t i = 1; i < c.size(); ++i) EXPECT_NEAR(c[i] - c[i - 1], 32768.0, 0.02 * 32768.0) << "step " << i;
}

/// Adds shader "light" (the first shader's cost, one colour output) and pipeline "add" (no depth
/// test, additive blend): what a full-screen light layer draws with.
void add_fullscreen_light(Trace& t) {
  ShaderDesc light = t.shaders[0];
  light.name = "light";
  light.color_outputs = 1;
  t.shaders.push_back(light);
  PipelineState add = t.pipelines[0];
  add.name = "add";
  add.shader = "light";
  add.depth_test = false;
  add.depth_write = false;
  add.blend = BlendMode::Add;
  t.pipelines.push_back(add);
}

/// Frame cycles and split renders of a 512x512 pass with subpasses, as deferred shading keeps its
/// G-buffer on chip: a wall writes the colour plus k 32-bit transient G-buffer targets, then a
/// fullscreen draw fetches the k targets at every pixel and adds onto the colour; on the GX6250
/// preset's 256 bits per pixel (2 USCs, one texture unit), 16 B per clock per USC of tile buffer
/// (round arithmetic, as above), plus `sets`.
struct SubpassCliff {
  std::vector<double> cycles;
  std::vector<double> split_renders;
  std::vector<double> gbuffer_written, gbuffer_read;  ///< DRAM bytes of class gbuffer (requested)
};
SubpassCliff onchip_subpass_cliff(int k_first, int k_last, std::vector<std::string> sets = {}) {
  Scene s = base_scene();
  add_quad(s, "wall", 3, -512, 1024, 0);
  sets.insert(sets.begin(), {"usc.count=2", "texture.units=1", "pls.tile_buffer_bits_per_pixel=256",
                             "pls.tile_buffer_bytes_per_clock=16"});
  SubpassCliff out;
  for (int k = k_first; k <= k_last; ++k) {
    Trace t = frame_of(512);
    t.shaders[0].alu_ops = 4;
    t.shaders[0].tex_fetches = 0;
    t.shaders[0].color_outputs = static_cast<std::uint32_t>(k + 1);
    add_fullscreen_light(t);
    PassDesc p = base_pass();
    DrawCmd fullscreen;
    fullscreen.pipeline = "add";
    fullscreen.geometry = GeometryKind::Fullscreen;
    fullscreen.fetch = add_transient_gbuffer(p, k);
    p.draws = {draw_of("wall"), fullscreen};
    t.commands.push_back(p);
    const Timed r = run_timed(t, s, sets);
    out.cycles.push_back(r.timing.frame_cycles);
    out.split_renders.push_back(stat(r.stats, "frame/tile_memory", "split_renders"));
    out.gbuffer_written.push_back(static_cast<double>(r.frame.dram.writes(DramClass::Gbuffer)));
    out.gbuffer_read.push_back(static_cast<double>(r.frame.dram.reads(DramClass::Gbuffer)));
  }
  return out;
}

TEST(TimingCliff, SubpassesPastTheBudgetSplitTheRender) {
  // k = 4..8 G-buffer targets + the colour: 160 .. 288 bits per pixel against 256 on chip.
  // Within the budget each target adds 4 B/pixel of tile-buffer writes (the wall) and 4 B of
  // framebuffer-fetch reads (the fullscreen draw): 512 x 512 x 8 B / (2 USCs x 16 B/clock) = 65536
  // cycles a step. Past it (288 bits) the driver ends the render before the fullscreen draw
  // (pls.over_budget = split_render, Mesa pvr_hw_pass.c): 8 MiB of G-buffer and the 1 MiB colour
  // go to memory, the colour and depth come back, and the fullscreen draw reads the 8 MiB
  // G-buffer as images through the texture unit (8 fetches x 262144 pixels on one unit) and the
  // caches: at least 3x the earlier steps at this tile-buffer rate (the step's size against the
  // GX6250's, at the fitted rate, is `tbdrsim validate`'s cliff row). Under spill the same pass
  // pays only its spilled share: less.
  const SubpassCliff c = onchip_subpass_cliff(4, 8);
  for (std::size_t i = 0; i < c.cycles.size(); ++i)
    std::printf("[ cliff    ] %3zu bits/pixel: %.3f ms, %g split renders\n", 32 * (5 + i), c.cycles[i] / 600e3, c.split_renders[i]);
  double mean = 0;
  for (std::size_t i = 1; i + 1 < c.cycles.size(); ++i) {
    EXPECT_NEAR(c.cycles[i] - c.cycles[i - 1], 65536.0, 0.02 * 65536.0) << "step " << i;
    EXPECT_EQ(c.split_renders[i], 0.0);
    mean += (c.cycles[i] - c.cycles[i - 1]) / static_cast<double>(c.cycles.size() - 2);
  }
  EXPECT_EQ(c.split_renders.back(), 1.0);
  // Only the split moves G-buffer bytes: 8 targets x 4 B x 512 x 512 = 8 MiB stored at the
  // split and read back once by the fullscreen draw's pixels.
  EXPECT_EQ(c.gbuffer_written[c.cycles.size() - 2], 0.0);
  EXPECT_EQ(c.gbuffer_written.back(), 8.0 * 1024 * 1024);
  EXPECT_EQ(c.gbuffer_read.back(), 8.0 * 1024 * 1024);
  const double last = c.cycles.back() - c.cycles[c.cycles.size() - 2];
  EXPECT_GE(last, 3.0 * mean);
  const SubpassCliff spill = onchip_subpass_cliff(8, 8, {"pls.over_budget=spill"});
  EXPECT_EQ(spill.split_renders[0], 0.0);
  EXPECT_LT(spill.cycles[0], c.cycles.back());
  EXPECT_GE(spill.cycles[0], c.cycles[c.cycles.size() - 2]) << "spilling never makes the pass faster than fitting";
}

TEST(TimingCaches, ReReadsOfAStoredGbufferComeFromWhereItWasStoredAndHitTheCaches) {
  // A pass stores a 4-byte G-buffer target of 256 x 256 pixels (256 KiB); a second pass draws k
  // fullscreen layers that each read it at every pixel (reads=g1), as light volumes do: the
  // shaders request k x 256 KiB. The reads go to the addresses the first pass stored to, tile by
  // tile; a tile's 4 KiB streams from memory once while it shades and its k - 1 re-reads are
  // counted as requests and texture-cache hits (not simulated one by one): DRAM delivers about
  // the 256 KiB once (within 10 %), not k times, and requests stay k x 256 KiB. The texture
  // cache's G-buffer read hits grow by the re-reads' lines: (8 - 1) x 256 KiB / 64-byte lines =
  // 28,672 more at k = 8 than at k = 1 (the stores are line-aligned, so each re-read request is one
  // line); and 8 layers of reads and blending never finish sooner than one.
  // A texture cache smaller than a tile's 4 KiB (2 KiB: 32 of the lap's 64 lines) cannot keep the
  // lap: cycling over it, LRU evicts each line before its re-read, so the re-reads miss too and
  // the misses grow with k (8 laps: about 8 x one lap's 4,096 misses, asserted above 4 x), and
  // the frame is never faster than with the 16 KiB cache.
  Scene s = base_scene();
  add_quad(s, "wall", 3, -512, 1024, 0);
  auto gbuffer_dram_reads = [&](int k, const std::vector<std::string>& sets) {
    Trace t = frame_of(256);
    t.shaders[0].tex_fetches = 0;
    t.shaders[0].color_outputs = 2;
    add_fullscreen_light(t);
    PassDesc g = base_pass();
    g.name = "gbuffer";
    Attachment g1 = g.attachments[0];
    g1.name = "g1";
    g1.usage = AttachmentUsage::Gbuffer;
    g.attachments.push_back(g1);
    g.draws = {draw_of("wall")};
    PassDesc l = base_pass();
    l.name = "lighting";
    l.attachments[0].name = "lit";
    for (int i = 0; i < k; ++i) {
      DrawCmd d;
      d.pipeline = "add";
      d.geometry = GeometryKind::Fullscreen;
      d.reads = {"g1"};
      l.draws.push_back(d);
    }
    t.commands = {g, l};
    const Timed r = run_timed(t, s, sets);
    EXPECT_EQ(resolve_config({}, {}).hw.cache.texture.line_bytes, 64);
    const CacheSnapshot& texture = r.timing.memory_units.caches.front();  // texture, vertex, SLC
    EXPECT_EQ(texture.scope, "mem/cache.texture");
    const CacheClassStats& gbuffer = texture.classes[static_cast<std::size_t>(DramClass::Gbuffer)];
    const double hits = static_cast<double>(gbuffer.read_hits.value()), misses = static_cast<double>(gbuffer.read_misses.value());
    struct Figures {
      double dram, requested, hits, misses, cycles;
    };
    return Figures{static_cast<double>(r.timing.dram.reads(DramClass::Gbuffer)),
                   static_cast<double>(r.timing.requested.reads(DramClass::Gbuffer)), hits, misses, r.timing.frame_cycles};
  };
  const double stored = 256.0 * 256.0 * 4.0;
  const auto one = gbuffer_dram_reads(1, {});
  const auto eight = gbuffer_dram_reads(8, {});
  for (const auto& [k, f] : {std::pair{1, one}, std::pair{8, eight}}) {
    std::printf("[ caches   ] %d layers: G-buffer requested %.0f B, from DRAM %.0f B, texture-cache hits %.0f, %.0f cycles\n",
                k, f.requested, f.dram, f.hits, f.cycles);
    EXPECT_EQ(f.requested, k * stored);
    EXPECT_NEAR(f.dram, stored, 0.1 * stored);
  }
  EXPECT_EQ(eight.hits - one.hits, 7 * stored / 64);
  EXPECT_GE(eight.cycles, one.cycles);
  const std::vector<std::string> small_cache = {"cache.texture.size_bytes=2048"};
  const auto small_one = gbuffer_dram_reads(1, small_cache);
  const auto small_eight = gbuffer_dram_reads(8, small_cache);
  std::printf("[ caches   ] 2 KiB texture cache: G-buffer misses %.0f (1 layer), %.0f (8 layers); %.0f cycles\n",
              small_one.misses, small_eight.misses, small_eight.cycles);
  EXPECT_GT(small_eight.misses, 4 * small_one.misses);
  EXPECT_GE(small_eight.cycles, eight.cycles);
}

TEST(TimingCliff, FramebufferFetchReadsTheTileBuffer) {
  // A draw that fetches a 4-byte G-buffer attachment of its pass reads it from the tile buffer
  // at every shaded pixel: 256 x 256 pixels x 4 B more tile-buffer reads than the same draw
  // without the fetch.
  Scene s = base_scene();
  add_quad(s, "wall", 3, -512, 1024, 0);
  double read[2] = {0, 0};
  for (int fetch = 0; fetch < 2; ++fetch) {
    Trace t = frame_of(256);
    t.shaders[0].tex_fetches = 0;
    PassDesc p = base_pass();
    Attachment g = p.attachments[0];
    g.name = "g1";
    g.usage = AttachmentUsage::Gbuffer;
    g.store = StoreOp::DontCare;
    g.transient = true;
    p.attachments.push_back(g);
    DrawCmd d = draw_of("wall");
    if (fetch) d.fetch = {"g1"};
    p.draws = {d};
    t.commands.push_back(p);
    read[fetch] = stat(run_timed(t, s, {}).stats, "frame/tsp", "tile_buffer_read_bytes");
  }
  EXPECT_EQ(read[1] - read[0], 256.0 * 256.0 * 4.0);
}

TEST(TimingCliff, PixelLocalStorageIsRefusedOnAnImmediateModeGpu) {
  // An IMR has no tile memory to keep PLS in (EXT_shader_pixel_local_storage): the pass is refused,
  // naming it, instead of its PLS traffic going unpaid.
  PassDesc p = base_pass();
  p.name = "stack_pass";
  p.pls = {PlsVariable{"stack", Format::Rgba32ui, 0}};
  Scene s = base_scene();
  add_quad(s, "wall", 3, -512, 1024, 0);
  Trace t = frame_of(64);
  p.draws = {draw_of("wall")};
  t.commands.push_back(p);
  try {
    simulate_frame(t, "pls.trace", s, resolve_config({}, {"gpu.mode=imr"}).hw);
    FAIL() << "accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("pass 'stack_pass' declares pixel local storage"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("pls.trace"), std::string::npos) << e.what();
  }
  EXPECT_NO_THROW(simulate_frame(t, "pls.trace", s, resolve_config({}, {"gpu.mode=tbr"}).hw));
}

TEST(TimingCliff, PixelLocalStorageSharesTheColourStorage) {
  // EXT_shader_pixel_local_storage: PLS aliases the colour attachments' storage, so a pass with
  // 16 B of PLS and a 4 B colour target needs 16 B per pixel, not 20: it fits 128 bits.
  PassDesc p = base_pass();
  p.pls = {PlsVariable{"stack", Format::Rgba32ui, 0}};
  EXPECT_EQ(p.pls_bytes_per_pixel(), 16u);
  Scene s = base_scene();
  add_quad(s, "wall", 3, -512, 1024, 0);
  Trace t = frame_of(256);
  p.draws = {draw_of("wall")};
  t.commands.push_back(p);
  const Timed r = run_timed(t, s, {"pls.tile_buffer_bits_per_pixel=128"});
  EXPECT_EQ(stat(r.stats, "frame/tile_memory", "onchip_need_bytes_per_pixel"), 16.0);
  EXPECT_EQ(r.frame.dram.reads(DramClass::Spill) + r.frame.dram.writes(DramClass::Spill), 0u);
}

}  // namespace
}  // namespace tbdr
