// The tiler on its own: which of the 2x2 tiles of a 64x64 viewport a triangle touches, and the
// parameter buffer bytes (primitive blocks, control streams, region headers, pages) worked out
// from the parameters.
//
// Default parameters used below: 32x32 tiles; region header 6 B per tile; control stream entries
// of 8 B in 128 B blocks; primitive blocks of at most 64 vertices / 128 primitives with a 16 B
// header, 10 B of position per vertex plus 4 B per varying, 3 B of index data per primitive,
// no compression; 4 KiB pages.
#include <gtest/gtest.h>

#include <array>
#include <vector>

#include "unit_fixture.hpp"

namespace tbdr {
namespace {

using namespace unit;

// A triangle of draw `draw` with 8 varyings whose vertices carry the keys `keys` (shared vertices
// share keys).
ScreenTri keyed(ScreenTri t, std::array<std::uint32_t, 3> keys, std::uint32_t draw) {
  t.draw = draw;
  t.varyings = 8;
  t.keys = {keys[0], keys[1], keys[2]};
  return t;
}
// The upper-left half of the viewport: covers samples with x + y <= 62, in tiles 0, 1, 2 (tile 3's
// nearest sample, (32.5, 32.5), has x + y = 65 > 64).
ScreenTri upper_left_64(std::uint32_t draw = 0) { return keyed({{0, 0}, {64, 0}, {0, 64}}, {1, 2, 3}, draw); }
// The lower-right half, sharing the vertices (64,0) and (0,64): its diagonal is its left edge,
// samples with x + y >= 63, in tiles 1, 2, 3.
ScreenTri lower_right_64(std::uint32_t draw = 0) { return keyed({{64, 0}, {64, 64}, {0, 64}}, {2, 4, 3}, draw); }

std::vector<std::uint32_t> prims_of(TilerRig& rig, int tx, int ty) { return rig.tiler().tile_primitives(rig.tile(tx, ty)); }

TEST(UnitTiler, ExactBinningTouchesOnlyTilesWithCoveredSamples) {
  TilerRig rig;
  ASSERT_EQ(rig.tiler().tile_count(), 4);
  ASSERT_TRUE(rig.bin(upper_left_64()));
  EXPECT_EQ(rig.stats.primitives_binned.value(), 1u);
  EXPECT_EQ(rig.stats.tile_references.value(), 3u);
  EXPECT_EQ(prims_of(rig, 0, 0).size(), 1u);
  EXPECT_EQ(prims_of(rig, 1, 0).size(), 1u);
  EXPECT_EQ(prims_of(rig, 0, 1).size(), 1u);
  EXPECT_TRUE(prims_of(rig, 1, 1).empty());
}

TEST(UnitTiler, BoundingBoxBinningAlsoTouchesTheTileTheTriangleMisses) {
  // Bounding box: the triangle's pixels [0,64) x [0,64) overlap all 4 tiles.
  TilerRig rig({"tiling.binning=bbox"});
  ASSERT_TRUE(rig.bin(upper_left_64()));
  EXPECT_EQ(rig.stats.tile_references.value(), 4u);
  EXPECT_EQ(prims_of(rig, 1, 1).size(), 1u);
}

TEST(UnitTiler, AVertexOnATileEdgeWidensTheBoundingBoxByAPixel) {
  // (0,0), (32,0), (0,32) covers only tile 0's samples (x + y <= 30). Its pixel bounding box is
  // [0, 32 + 1): the vertex at x = 32.0 lies on pixel 32's left edge, where a sample could sit,
  // so bbox binning also puts it in tiles 1, 2 and 3. Ending at 31.0 keeps it in tile 0.
  for (const char* binning : {"exact", "bbox"}) {
    TilerRig rig({std::string("tiling.binning=") + binning});
    ASSERT_TRUE(rig.bin(ScreenTri{{0, 0}, {32, 0}, {0, 32}}));
    ASSERT_TRUE(rig.bin(ScreenTri{{0, 0}, {31, 0}, {0, 31}}));
    const bool bbox = std::string(binning) == "bbox";
    EXPECT_EQ(rig.stats.tile_references.value(), bbox ? 4u + 1u : 1u + 1u) << binning;
  }
}

TEST(UnitTiler, ATriangleCoveringNoSampleIsDropped) {
  // A sliver between pixel centres: (0.6, 0) (0.9, 0) (0.6, 64) contains no x + 0.5 column. The
  // tiler says so (NoSample), and the pass renderer then keeps no record of it.
  TilerRig rig;
  const ScreenTri sliver{{0.6f, 0}, {0.9f, 0}, {0.6f, 64}};
  EXPECT_EQ(rig.tiler().bin(0, make_primitive(sliver, rig.viewport, 0), make_vertex_keys(sliver, 0), rig.stats),
            BinResult::NoSample);
  ASSERT_TRUE(rig.bin(sliver));
  EXPECT_EQ(rig.stats.primitives_binned.value(), 0u);
  EXPECT_EQ(rig.stats.tile_references.value(), 0u);
}

TEST(UnitTiler, ParameterBufferBytesOfAQuadFollowTheParameters) {
  // Two triangles of one draw sharing 2 vertices: one primitive block of 4 vertices with
  // 8 varyings: 16 + 4 x (10 + 4 x 8) + 2 x 3 = 16 + 168 + 6 = 190 B.
  // Touches: UL tiles 0,1,2; LR tiles 1,2,3: 6 references; one control stream entry per tile
  // (both reference the same block): 4 entries, each tile's stream one 128 B block: 512 B.
  // Region headers: 4 x 6 = 24 B. Written: 190 + 512 + 24 = 726 B.
  TilerRig rig;
  ASSERT_TRUE(rig.bin(upper_left_64()));
  ASSERT_TRUE(rig.bin(lower_right_64()));
  rig.finish_render();
  // Allocated in 4 KiB pages, blocks, control streams and headers each rounded up: 3 pages.
  expect_counters(rig.stats, {{&TilerStats::primitives_binned, 2},
                              {&TilerStats::tile_references, 6},
                              {&TilerStats::primitive_blocks, 1},
                              {&TilerStats::pb_vertices, 4},
                              {&TilerStats::control_stream_entries, 4},
                              {&TilerStats::pb_primitive_block_bytes, 190},
                              {&TilerStats::pb_control_stream_bytes, 512},
                              {&TilerStats::pb_region_header_bytes, 24},
                              {&TilerStats::pb_bytes_written, 726},
                              {&TilerStats::pb_peak_allocated_bytes, 3 * 4096}});
  EXPECT_EQ(rig.dram.writes(DramClass::ParameterBuffer), 726u);
  // What the ISP reads for a tile: its header (6), its stream's 1 entry (8), the block (190).
  EXPECT_EQ(rig.tiler().tile_read_bytes(rig.tile(0, 0)), 204u);
  EXPECT_EQ(rig.tiler().tile_read_bytes(rig.tile(1, 1)), 204u);
  // Layout: headers at 0 (6 B each), then the streams tile after tile (8 B each), then the
  // blocks. Tile 3: header at 18, its entry at 24 + 3 x 8 = 48, the block at 24 + 4 x 8 = 56.
  const std::vector<ByteRange> r = rig.tiler().tile_read_ranges(rig.tile(1, 1));
  ASSERT_EQ(r.size(), 3u);
  EXPECT_EQ(r[0].offset, 18u);
  EXPECT_EQ(r[0].bytes, 6u);
  EXPECT_EQ(r[1].offset, 48u);
  EXPECT_EQ(r[1].bytes, 8u);
  EXPECT_EQ(r[2].offset, 56u);
  EXPECT_EQ(r[2].bytes, 190u);
}

TEST(UnitTiler, ANewDrawOrTheVertexLimitStartsANewBlock) {
  // Different draws never share a block: 2 blocks of 3 vertices, 16 + 3 x 42 + 3 = 145 B each.
  // Control stream entries: tile 0 one (UL), tiles 1 and 2 two (UL's block, LR's), tile 3 one.
  {
    TilerRig rig;
    ASSERT_TRUE(rig.bin(upper_left_64(0)));
    ASSERT_TRUE(rig.bin(lower_right_64(1)));
    rig.finish_render();
    // 2 entries still fit a control stream block: 512 B.
    expect_counters(rig.stats, {{&TilerStats::primitive_blocks, 2},
                                {&TilerStats::pb_vertices, 6},
                                {&TilerStats::pb_primitive_block_bytes, 290},
                                {&TilerStats::control_stream_entries, 6},
                                {&TilerStats::pb_control_stream_bytes, 512}});
    EXPECT_EQ(rig.tiler().tile_read_bytes(rig.tile(1, 0)), 6u + 2u * 8u + 290u);
  }
  // At most 3 vertices per block: the same split within one draw.
  TilerRig rig({"tiling.prim_block_max_vertices=3"});
  ASSERT_TRUE(rig.bin(upper_left_64()));
  ASSERT_TRUE(rig.bin(lower_right_64()));
  rig.finish_render();
  EXPECT_EQ(rig.stats.primitive_blocks.value(), 2u);
  EXPECT_EQ(rig.stats.pb_primitive_block_bytes.value(), 290u);
}

TEST(UnitTiler, AFanSharesItsCentreVertexInBlocksOfAtMost64Vertices) {
  // 100 triangles of one draw, triangle i with the vertices {1000, i + 1, i + 2} (a fan around
  // vertex 1000): a block takes triangles while its distinct vertices stay within 64, 62 of them
  // (2 + 62 = 64 vertices); the other 38 go to a second block (2 + 38 = 40): 104 vertices in 2
  // blocks. Each triangle covers tiles 0, 1 and 2: 300 tile references. Looking the tiles up
  // ahead (Tiler::touched_tiles, as the geometry unit's set-up threads do) bins the same.
  for (const bool listed : {false, true}) {
    TilerRig rig;
    for (std::uint32_t i = 0; i < 100; ++i) ASSERT_TRUE(rig.bin(keyed(upper_left_64(), {1000, i + 1, i + 2}, 0), listed)) << i;
    rig.finish_render();
    expect_counters(rig.stats, {{&TilerStats::primitives_binned, 100},
                                {&TilerStats::primitive_blocks, 2},
                                {&TilerStats::pb_vertices, 104},
                                {&TilerStats::tile_references, 300}});
    EXPECT_EQ(rig.tiler().tile_primitives(rig.tile(1, 1)).size(), 0u) << listed;
    EXPECT_EQ(rig.tiler().tile_primitives(rig.tile(1, 0)).size(), 100u) << listed;
  }
}

TEST(UnitTiler, CompressionShrinksOnlyTheVertexData) {
  // pb_compression_ratio 0.5: the quad's block is 16 + ceil(168 x 0.5) + 6 = 106 B.
  TilerRig rig({"tiling.pb_compression_ratio=0.5"});
  ASSERT_TRUE(rig.bin(upper_left_64()));
  ASSERT_TRUE(rig.bin(lower_right_64()));
  rig.finish_render();
  EXPECT_EQ(rig.stats.pb_primitive_block_bytes.value(), 106u);
  EXPECT_EQ(rig.stats.pb_bytes_written.value(), 106u + 512u + 24u);
}

TEST(UnitTiler, ControlStreamsGrowInWholeBlocks) {
  // Each triangle of its own draw in tile 0 adds an 8 B entry to tile 0's stream: 16 entries fill
  // one 128 B block, the 17th opens a second one.
  TilerRig rig;
  for (std::uint32_t d = 0; d < 16; ++d) {
    ScreenTri t{{0, 0}, {8, 0}, {0, 8}};
    t.draw = d;
    ASSERT_TRUE(rig.bin(t));
  }
  EXPECT_EQ(rig.stats.control_stream_entries.value(), 16u);
  ScreenTri t{{0, 0}, {8, 0}, {0, 8}};
  t.draw = 16;
  ASSERT_TRUE(rig.bin(t));
  rig.finish_render();
  EXPECT_EQ(rig.stats.control_stream_entries.value(), 17u);
  EXPECT_EQ(rig.stats.pb_control_stream_bytes.value(), 256u);
}

/// Small triangles in tile 0, one draw, 60 varyings, no shared vertices.
ScreenTri heavy_triangle() {
  ScreenTri t{{0, 0}, {8, 0}, {0, 8}};
  t.varyings = 60;
  return t;
}

TEST(UnitTiler, AFullParameterBufferRefusesThePrimitiveForAPartialRender) {
  // Capacity 64 KiB = 16 pages: region headers take 1 page, tile 0's control stream (at most a
  // few entries: 1 block of 128 B) 1 page, which leaves 14 pages = 57344 B for primitive blocks.
  // A vertex is 10 + 4 x 60 = 250 B; a block holds 21 triangles (63 of 64 vertices):
  // 16 + 63 x 250 + 21 x 3 = 15829 B. Three full blocks: 47487 B. The fourth holds
  // 16 + 753 k <= 57344 - 47487 = 9857 B: k = 13 (9805 B). So 63 + 13 = 76 triangles fit; the
  // 77th would need 15 data pages (61440 + 8192 > 65536) and is refused.
  TilerRig rig({"tiling.pb_capacity_bytes=65536"});
  int binned = 0;
  while (binned < 200 && rig.bin(heavy_triangle())) ++binned;
  EXPECT_EQ(binned, 76);
  EXPECT_EQ(rig.stats.primitives_binned.value(), 76u);
  rig.finish_render();
  expect_counters(rig.stats, {{&TilerStats::primitive_blocks, 4},
                              {&TilerStats::pb_vertices, 76 * 3},
                              {&TilerStats::pb_primitive_block_bytes, 3 * 15829 + 16 + 13 * 753},
                              {&TilerStats::pb_peak_allocated_bytes, 65536}});
  // After the partial render the buffer is free again: the refused triangle bins.
  rig.reset();
  EXPECT_TRUE(rig.tiler().empty());
  EXPECT_TRUE(rig.bin(heavy_triangle()));
}

TEST(UnitTiler, TheDefaultCapacityHoldsTheSameTriangles) {
  // 32 MiB: the 77th heavy triangle fits (and many more).
  TilerRig rig;
  int binned = 0;
  while (binned < 200 && rig.bin(heavy_triangle())) ++binned;
  EXPECT_EQ(binned, 200);
}

}  // namespace
}  // namespace tbdr
