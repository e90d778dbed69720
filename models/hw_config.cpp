#include "models/hw_config.hpp"

#include "models/config_checks.hpp"

namespace tbdr {

// Declares a parameter whose key is the HwConfig member path, so key and member cannot drift apart.
#define TBDR_PARAM(path) #path, [](HwConfig& c) -> auto& { return c.path; }

namespace {

constexpr double kKiB = 1024.0;
constexpr double kMiB = 1024.0 * 1024.0;

/// Declares section cache.<name>: the four parameters of one set-associative cache (`Which` in
/// HwConfig::cache), with their defaults `def`. Only the capacity's upper range and source differ
/// between the caches; the line size is the SLC line of Mesa's device info (`mesa`).
template <CacheParams CachesParams::*Which>
void add_cache(ParamRegistry<HwConfig>& r, const std::string& name, const std::string& doc, const CacheParams& def,
               double max_size_bytes, const std::string& size_source, const std::string& mesa) {
  const std::string key = "cache." + name;
  r.section(key, doc);
  r.add(key + ".size_bytes", [](HwConfig& c) -> auto& { return (c.cache.*Which).size_bytes; }, def.size_bytes)
      .unit("bytes").range(1024, max_size_bytes).doc("Capacity").source(size_source);
  r.add(key + ".ways", [](HwConfig& c) -> auto& { return (c.cache.*Which).ways; }, def.ways)
      .unit("ways").range(1, 64).doc("Associativity").source("no public figure");
  r.add(key + ".line_bytes", [](HwConfig& c) -> auto& { return (c.cache.*Which).line_bytes; }, def.line_bytes)
      .unit("bytes").range(16, 1024).doc("Line size").source(mesa + ": slc_cache_line_size_bits = 512");
  r.add(key + ".hit_latency_cycles", [](HwConfig& c) -> auto& { return (c.cache.*Which).hit_latency_cycles; },
        def.hit_latency_cycles)
      .unit("cycles").range(1, 1000).doc("Hit latency").source("no public figure");
}

ParamRegistry<HwConfig> make_registry() {
  ParamRegistry<HwConfig> r;
  r.name_defaults(kDefaultsPreset);
  // The defaults describe one complete GPU: a PowerVR Series6XT-class part (GX6450-like: 4 USCs,
  // 32x32 tiles, 128 bits per pixel on chip) with LPDDR3-1600. configs/ holds the other presets.
  const std::string mesa = "Mesa src/imagination/common/device_info/gx6250.h";
  const std::string mesa_gx6650 = "Mesa src/imagination/common/device_info/gx6650.h";
  const std::string series6xt = "Imagination, PowerVR Series6XT product briefs";
  const std::string lpddr3_memspec = "DRAMPower memspec MICRON_4Gb_LPDDR3-1600_32bit_A";
  const std::string pb_layout = "Imagination's parameter buffer layout (control streams, primitive blocks) is not published "
                                "byte by byte";

  r.section("gpu", "Whole-GPU identity, core clock and rendering mode");
  r.add(TBDR_PARAM(gpu.name), std::string("Series6XT-class (GX6450-like), LPDDR3-1600"))
      .doc("Label stored with every run").source("preset label");
  r.add(TBDR_PARAM(gpu.core_clock_mhz), 600.0).unit("MHz").range(50, 3000)
      .doc("Core clock of geometry, tiler, ISP, USC, texture and writeback units")
      .source(series6xt + ": 450-850 MHz");
  r.add(TBDR_PARAM(gpu.mode), GpuMode::Tbdr, kGpuModeNames)
      .doc("tbdr: binning + tag-buffer HSR; tbr: binning, early-Z only (Mali-like); imr: no binning, primitives "
           "rasterised and shaded in submission order with early-Z, depth and colour through the ROP caches "
           "(cache.rop_depth, cache.rop_color) to the framebuffer in memory (a pass with pixel local storage is "
           "refused: no tile memory to keep it in)")
      .source("Imagination, PowerVR Architecture Guide (tile-based deferred rendering); tbr and imr are the "
              "comparison modes");
  r.add(TBDR_PARAM(gpu.frame_period_us), 0.0).unit("us").range(0, 1e7)
      .doc("Display frame period: frame/energy also reports the energy of one period (at_period_total_mj), the "
           "frame plus the idle time after it at idle power (gated units' leakage, caches' leakage, DRAM in "
           "power-down then self-refresh); 0 = race to idle only, a frame longer than the period has no idle time")
      .source("a use-case figure, not hardware: 16666.7 us at 60 Hz, 8333.3 us at 120 Hz");
  r.add(TBDR_PARAM(gpu.frames_in_flight), 2).unit("frames").range(1, 2)
      .doc("Sequences of frames: 2 = the binning of frame N+1 may start while frame N's tiles render (in the "
           "parameter buffer the render before the last freed, as between the passes of a frame); 1 = a frame's "
           "work starts when the frame before it has finished (each frame's first binning exposed as latency). "
           "With gpu.frame_period_us > 0 frame k starts no earlier than k periods after the first (the "
           "application submits at the display's rate). No effect on a single frame")
      .source("Imagination, PowerVR Architecture Guide (tile-based deferred rendering: the tiler processes the "
              "geometry of the next render while the tiles of the previous one are rendered); two parameter buffers "
              "of tiling.pb_capacity_bytes, as the timing model allocates them, bound it to 2");

  r.section("geometry", "Vertex fetch, vertex shading, clip/cull and viewport transform");
  r.add(TBDR_PARAM(geometry.primitives_per_clock), 1.0).unit("primitives/clock").range(0.01, 64)
      .doc("Clip, cull and setup throughput").source("no public figure; one triangle per clock is typical");
  r.add(TBDR_PARAM(geometry.vertex_fetch_bytes_per_clock), 32.0).unit("bytes/clock").range(1, 4096)
      .doc("Vertex attribute fetch bandwidth into the vertex pipeline").source("no public figure");
  r.add(TBDR_PARAM(geometry.vertex_cache_entries), 32).unit("vertices").range(0, 4096)
      .doc("Post-transform vertex cache (FIFO) entries; indexed re-use within it is not re-shaded")
      .source("no public figure; 32 is common in the literature");
  r.add(TBDR_PARAM(geometry.vertex_shader_alu_ops), 24).unit("ops/vertex").range(0, 100000)
      .doc("Vertex shader ALU ops per shaded vertex (transform, normal, varyings)")
      .source("a 4x4 transform (16 FMA) plus normal transform and outputs");
  r.add(TBDR_PARAM(geometry.subpixel_bits), 8).unit("bits").range(0, 12)
      .doc("Fractional bits of fixed-point screen coordinates")
      .source("Mesa src/imagination/vulkan/pvr_physical_device.c: 8 sub-pixel bits on cores without "
              "simple_internal_parameter_format (Series6XT), 4 on later ones");

  r.section("tiling", "Binning of primitives into tiles and the parameter buffer in DRAM");
  r.add(TBDR_PARAM(tiling.tile_width), 32).unit("pixels").range(4, 256)
      .doc("Tile width").source(mesa + ": tile_size_x = 32 on Series6XT");
  r.add(TBDR_PARAM(tiling.tile_height), 32).unit("pixels").range(4, 256)
      .doc("Tile height").source(mesa + ": tile_size_y = 32 on Series6XT");
  r.add(TBDR_PARAM(tiling.binning), BinningTest::Exact, kBinningTestNames)
      .doc("Tile/triangle overlap test: exact edge test or bounding box only").source("design choice");
  r.add(TBDR_PARAM(tiling.tile_order), TileOrder::Morton, kTileOrderNames)
      .doc("Order in which tiles are dispatched to the ISP").source("design choice");
  r.add(TBDR_PARAM(tiling.primitives_per_clock), 1.0).unit("primitives/clock").range(0.01, 64)
      .doc("Tiling engine throughput").source("no public figure");
  r.add(TBDR_PARAM(tiling.pb_capacity_bytes), static_cast<std::int64_t>(32 * kMiB)).unit("bytes")
      .range(64 * kKiB, 4096 * kMiB)
      .doc("Parameter buffer capacity; when binning exceeds it a partial render flushes")
      .source("no fixed figure: the driver sizes the free list (Mesa src/imagination/vulkan/pvr_device.c: "
              "2 MiB initially, growing by 1 MiB up to 256 MiB); 32 MiB assumed");
  r.add(TBDR_PARAM(tiling.pb_page_bytes), 4096).unit("bytes").range(256, 1 << 20)
      .doc("Parameter buffer allocation granule")
      .source("Linux drivers/gpu/drm/imagination/pvr_rogue_fwif_client.h: ROGUE_PM_PAGE_SIZE = 4 KB "
              "(parameter management pages)");
  r.add(TBDR_PARAM(tiling.region_header_bytes), 6).unit("bytes").range(0, 64)
      .doc("Region header per tile")
      .source("Mesa src/imagination/vulkan/pvr_job_render.c (region header stride): 5-6 B per tile");
  r.add(TBDR_PARAM(tiling.control_stream_block_bytes), 128).unit("bytes").range(16, 4096)
      .doc("Control stream allocation block").source(pb_layout + "; 128 B blocks assumed");
  r.add(TBDR_PARAM(tiling.control_stream_entry_bytes), 8).unit("bytes").range(1, 64)
      .doc("Control stream entry: primitive block pointer plus primitive mask").source("no public figure");
  r.add(TBDR_PARAM(tiling.prim_block_max_vertices), 64).unit("vertices").range(3, 1024)
      .doc("Vertices per primitive block").source(pb_layout + "; 64 assumed (6-bit vertex indices)");
  r.add(TBDR_PARAM(tiling.prim_block_max_primitives), 128).unit("primitives").range(1, 4096)
      .doc("Primitives per primitive block").source("no public figure");
  r.add(TBDR_PARAM(tiling.prim_block_header_bytes), 16).unit("bytes").range(0, 256)
      .doc("Primitive block header (state word, counts, base address)").source("no public figure");
  r.add(TBDR_PARAM(tiling.pb_vertex_position_bytes), 10).unit("bytes").range(1, 64)
      .doc("Screen-space position (x, y fixed point, z, 1/w) per vertex before compression")
      .source(pb_layout + "; about 10 B assumed (fixed-point x, y; z; 1/w)");
  r.add(TBDR_PARAM(tiling.pb_varying_bytes), 4).unit("bytes/varying").range(0, 16)
      .doc("Bytes per scalar varying written with each vertex").source("FP32 varyings");
  r.add(TBDR_PARAM(tiling.pb_compression_ratio), 1.0).range(0.05, 1.0)
      .doc("Compressed / uncompressed size of primitive block vertex data").source("no public figure; 1 = off");
  r.add(TBDR_PARAM(tiling.prim_index_bytes), 3).unit("bytes/primitive").range(0, 16)
      .doc("Per-primitive index data inside a block (3 x 6-bit indices + flags)")
      .source("64-vertex blocks need 6-bit indices");

  r.section("isp", "Image synthesis processor: rasterisation, depth/stencil, tag-buffer HSR");
  r.add(TBDR_PARAM(isp.tiles_in_flight), 4).unit("tiles").range(1, 64)
      .doc("Tiles the ISP processes concurrently").source(mesa + ": isp_max_tiles_in_flight = 4 (GX6250), 8 (GX6650)");
  r.add(TBDR_PARAM(isp.raster_pipes), 1).unit("pipes").range(1, 16)
      .doc("Raster pipes").source(mesa + ": num_raster_pipes = 1 (GX6250)");
  r.add(TBDR_PARAM(isp.samples_per_clock), 32).unit("samples/clock").range(1, 1024)
      .doc("Depth/stencil tested samples per clock per raster pipe")
      .source("no public figure for Rogue; Unity, \"Fast mobile shaders\" talk: PowerVR SGX rejects 32 "
              "hidden pixels per clock");
  r.add(TBDR_PARAM(isp.tag_buffers), 2).unit("buffers").range(1, 16)
      .doc("Tag buffers per tile: layers of pending translucent / punch-through tags per sample before a flush "
           "(an opaque sample in front clears every layer unshaded)")
      .source("Imagination, US 8,446,409 (Howson): translucent and punch-through tags stay in further tag buffers "
              "and are passed to shading only when an object must overwrite an occupied location; an opaque "
              "surface visible at a pixel clears the tags of all the tag buffers; US 10,210,596");
  r.add(TBDR_PARAM(isp.forward_pixel_kill_window), 0).unit("primitives").range(0, 256)
      .doc("gpu.mode=tbr: primitives between early-Z and shading whose queued fragments a later opaque "
           "fragment at the same sample kills before they are shaded (forward pixel kill); 0 = off")
      .source("Arm, \"Killing Pixels - A New Optimization for Shading on ARM Mali GPUs\" (Arm community blog, "
              "2013): fragments still queued for shading are killed when a later opaque fragment covers them; "
              "the queue depth has no public figure");
  r.add(TBDR_PARAM(isp.early_z), 1).unit("flag").range(0, 1)
      .doc("gpu.mode=tbr|imr: 1 = depth and stencil tests before the fragment shader (early-Z), 0 = after "
           "it (late-Z: every rasterised fragment is shaded, the tests then decide which colours are "
           "written); tbdr's deferred HSR always tests first")
      .source("Khronos, Vulkan 1.3 specification, \"Early Fragment Tests\" (tests may run before shading "
              "when the result is the same); Imagination, PowerVR Architecture Guide, \"Hidden Surface "
              "Removal Efficiency\": 4.7 fragments coloured per pixel without early-Z or HSR, 1.2 with HSR");
  r.add(TBDR_PARAM(isp.tag_bits), 32).unit("bits").range(8, 64)
      .doc("Bits per tag (triangle id) per sample").source("no public figure");
  r.add(TBDR_PARAM(isp.depth_stencil_bytes_per_sample), 4).unit("bytes").range(2, 8)
      .doc("On-chip depth/stencil per sample (D24S8); stored to DRAM only on partial renders")
      .source("D24S8");

  r.section("usc", "Unified shading clusters: fragment, vertex and compute shading");
  r.add(TBDR_PARAM(usc.count), 4).unit("USCs").range(1, 64)
      .doc("Shader clusters")
      .source(series6xt + ": GX6240 2, GX6450 4, GX6650 6 (" + mesa_gx6650 + ": num_clusters = 6)");
  r.add(TBDR_PARAM(usc.lanes), 16).unit("lanes").range(1, 128)
      .doc("SIMD lanes per USC").source(series6xt + ": 16 lanes per USC");
  r.add(TBDR_PARAM(usc.alu_ops_per_lane_per_clock), 2.0).unit("ops/lane/clock").range(0.25, 16)
      .doc("FP32 ALU ops per lane per clock").source(series6xt + ": up to 2 FP32 ops per lane per clock");
  r.add(TBDR_PARAM(usc.tasks_in_flight), 56).unit("tasks").range(1, 4096)
      .doc("Tasks resident per USC: the work that hides memory latency (a tile's shading holds one slot per task "
           "of threads_per_task threads; several tiles are resident while slots last; the ISP stalls when a "
           "resolved tile finds too few free)")
      .source(mesa + ": max_usc_tasks = 56");
  r.add(TBDR_PARAM(usc.threads_per_task), 32).unit("threads").range(1, 1024)
      .doc("Threads (instances) of one USC task").source(mesa + ": max_instances_per_pds_task = 32");

  r.section("texture", "Texture processing units");
  r.add(TBDR_PARAM(texture.units), 2).unit("TPUs").range(1, 64)
      .doc("Texture units (two USCs share one)").source(series6xt + ": one texture unit per two USCs");
  // A "texel" of the texture rate is a filtered texel: one bilinear sample, 4 texels read and
  // blended. Imagination quotes Rogue texture rates in these units, the way GPU vendors quote
  // texture fill rates (bilinear texels per clock); a trilinear fetch costs two.
  r.add(TBDR_PARAM(texture.texels_per_clock), 4.0).unit("filtered texels/clock").range(0.25, 256)
      .doc("Bilinear-filtered texels (bilinear samples, 4 texels read and blended each) per clock per texture unit; "
           "a fetch costs texture.filtered_texels_per_fetch of them")
      .source("AnandTech, \"PowerVR Series 6XT\" (Feb. 2014, after Imagination's Rogue disclosure): texels/clock "
              "GX6650 12, G6430 8, G6230 4, beside NVIDIA K1's 8 (8 TMUs of one bilinear texel each); Imagination, "
              "PowerVR Rogue Architecture for Developers: a USC pair shares one texture processing unit, so 4 per TPU");
  r.add(TBDR_PARAM(texture.filtered_texels_per_fetch), 1).unit("filtered texels").range(1, 64)
      .doc("Filtered texels one texture fetch costs the texture unit: 1 bilinear, 2 trilinear (two mip levels blended). "
           "Sets the rate and energy charge only; the footprint is always one mip level's bilinear texels")
      .source("OpenGL ES 3.2 section 8.14.3: LINEAR_MIPMAP_LINEAR blends two bilinear samples of adjacent levels");
  r.add(TBDR_PARAM(texture.bytes_per_texel), 4).unit("bytes").range(1, 16)
      .doc("Bytes per texel in memory (RGBA8 uncompressed)").source("RGBA8");
  r.add(TBDR_PARAM(texture.outstanding_requests), 64).unit("requests").range(1, 4096)
      .doc("Memory requests the texture units keep in flight for one tile's footprint (miss latency hiding)")
      .source("no public figure; 12.8 GB/s x 0.5 us latency needs about 100 lines in flight");

  r.section("pls", "On-chip tile memory and pixel local storage");
  r.add(TBDR_PARAM(pls.tile_buffer_bits_per_pixel), 128).unit("bits/pixel").range(32, 2048)
      .doc("On-chip color/PLS storage per pixel (depth kept separately)")
      .source("Imagination, PowerVR Performance Recommendations, \"On-Chip Memory Performance\": typically 128 "
              "bits per pixel on low-end parts, 256 on high-end ones");
  r.add(TBDR_PARAM(pls.tile_buffer_bytes_per_clock), 8.73).unit("bytes/clock").range(1, 4096)
      .doc("On-chip tile buffer bandwidth per USC: colour/PLS bytes the shaders read and write in tile memory "
           "(outputs, blending, PLS) per clock; a tile's shading takes at least its tile-buffer bytes over this x usc.count")
      .source("no public figure; fitted: the value whose frame times best match, in shape (least squares after one "
              "scale factor), the flat part (96 .. 256 bits per pixel, inside the budget) of Imagination's GX6250 "
              "measurements in PowerVR Performance Recommendations, \"On-Chip Memory Performance\" (20, 21, 23, 24, "
              "28, 29 ms; rms 0.57 ms), on deferred gbuffer_storage=onchip, atrium:2 480x270 64 lights "
              "(bench/onchip_cliff_fit.py); the step past the budget is then predicted, not fitted "
              "(`tbdrsim validate`)");
  r.add(TBDR_PARAM(pls.max_pls_bytes_per_pixel), 16).unit("bytes/pixel").range(16, 256)
      .doc("Largest pixel local storage a pass may declare; a trace whose pass declares more is refused, as a "
           "driver refuses such a shader")
      .source("EXT_shader_pixel_local_storage: MAX_SHADER_PIXEL_LOCAL_STORAGE_SIZE_EXT is at least 16 bytes");
  r.add(TBDR_PARAM(pls.over_budget), PlsOverBudget::SplitRender, kPlsOverBudgetNames)
      .doc("When a pass needs more bytes per pixel than the tile buffer holds: split_render = end the render "
           "before the first draw that fetches an attachment an earlier draw wrote (a subpass boundary): every "
           "attachment is stored, and the rest of the pass is a new render that reads the fetched attachments "
           "from memory as images and keeps only the others on chip (spill when the pass has no such "
           "boundary or the rest still does not fit); spill = the excess share of tile-buffer accesses goes to "
           "memory; smaller_tiles = render each tile in strips that fit")
      .source("Mesa src/imagination/vulkan/pvr_hw_pass.c pvr_is_subpass_space_available: \"Avoid merging "
              "subpasses which result in tile buffers having to be used\" (the render is closed, "
              "pvr_close_render); pvr_mrt.h: render targets beyond the output registers go to memory tile "
              "buffers (USC_MRT_RESOURCE_TYPE_MEMORY)");

  r.section("writeback", "Pixel back end: stores tiles that must leave the chip");
  r.add(TBDR_PARAM(writeback.compression_ratio), 1.0).range(0.05, 1.0)
      .doc("Compressed / uncompressed bytes of stored attachments (PVRIC/AFBC); 1 = off")
      .source("Arm, Arm Frame Buffer Compression (AFBC): up to 50 % of framebuffer bandwidth saved; PVRIC is "
              "Imagination's equivalent; 1 = off");
  r.add(TBDR_PARAM(writeback.bytes_per_clock), 32.0).unit("bytes/clock").range(1, 4096)
      .doc("Pixel back end write throughput").source("no public figure");
  r.add(TBDR_PARAM(writeback.transaction_elimination), 0).unit("flag").range(0, 1)
      .doc("1: before storing a colour tile (store op, not transient, a whole tile) the pixel back end compares "
           "its signature with the one the same tile of the same pass had in the previous frame of a sequence "
           "and skips the store when they match; the signatures (8 bytes per tile and attachment) are read and "
           "written in memory. Needs the colours, which the run then computes. No effect on a single frame")
      .source("Arm, Mali GPU Transaction Elimination (a CRC per tile compared with the previous frame's; Arm "
              "Mali GPU Best Practices and the Mali Midgard/Bifrost documentation); not a published PowerVR "
              "Series6XT feature, so 0 by default");

  r.section("memory", "The units' DMA streams into the caches and DRAM");
  r.add(TBDR_PARAM(memory.stream_outstanding_requests), 16).unit("requests").range(1, 4096)
      .doc("Requests (of up to 4 KB, never crossing a 4 KB boundary) one unit's DMA stream keeps in flight: "
           "vertex and index fetch, parameter buffer writes and reads, tile loads and stores, compute buffers")
      .source("no public figure; 16 x 4 KB = 64 KB in flight, several times the 12.8 KB a 12.8 GB/s LPDDR3 "
              "needs to cover 1 us of latency");

  r.section("cache", "Caches of the memory hierarchy");
  add_cache<&CachesParams::texture>(r, "texture", "Texture cache (per GPU, shared by the texture units)",
                                    {.size_bytes = static_cast<std::int64_t>(16 * kKiB), .ways = 4, .line_bytes = 64,
                                     .hit_latency_cycles = 4},
                                    64 * kMiB, "no public figure", mesa);
  add_cache<&CachesParams::vertex>(r, "vertex", "Vertex and parameter buffer cache (geometry fetch, ISP primitive fetch)",
                                   {.size_bytes = static_cast<std::int64_t>(16 * kKiB), .ways = 4, .line_bytes = 64,
                                    .hit_latency_cycles = 4},
                                   64 * kMiB, "no public figure", mesa);
  add_cache<&CachesParams::slc>(r, "slc", "System level cache in front of DRAM",
                                {.size_bytes = static_cast<std::int64_t>(128 * kKiB), .ways = 8, .line_bytes = 64,
                                 .hit_latency_cycles = 20},
                                256 * kMiB, "no public figure for Series6XT", mesa);
  // An immediate-mode GPU's render output unit: vendors publish no ROP cache sizes; 16 KiB holds a
  // 64x64-pixel square of 32-bit depth (or colour), the working set of a few small triangles'
  // neighbourhoods, as the texture and vertex caches here.
  add_cache<&CachesParams::rop_depth>(r, "rop_depth", "gpu.mode=imr: ROP depth/stencil cache between the ISP's tests and the depth buffer in memory",
                                      {.size_bytes = static_cast<std::int64_t>(16 * kKiB), .ways = 4, .line_bytes = 64,
                                       .hit_latency_cycles = 4},
                                      64 * kMiB, "no public figure", mesa);
  add_cache<&CachesParams::rop_color>(r, "rop_color", "gpu.mode=imr: ROP colour cache between the shaders' outputs (and blending) and the colour buffers in memory",
                                      {.size_bytes = static_cast<std::int64_t>(16 * kKiB), .ways = 4, .line_bytes = 64,
                                       .hit_latency_cycles = 4},
                                      64 * kMiB, "no public figure", mesa);

  r.section("imr", "gpu.mode=imr: the immediate-mode pipeline (no binning, framebuffer behind the ROP caches)");
  r.add(TBDR_PARAM(imr.primitives_per_batch), 256).unit("primitives").range(1, 1 << 20)
      .doc("Primitives the timing model moves down the pipeline as one unit (geometry, then rasterisation and "
           "early depth, then shading, then the ROP); up to isp.tiles_in_flight batches between geometry and "
           "the end of rasterisation, so geometry, rasterisation, shading and the ROP overlap")
      .source("a modelling granularity, not a hardware figure: the primitive FIFOs between an IMR's geometry "
              "and raster stages are not published; 256 keeps the pipeline full while a frame's batches stay "
              "in the thousands");
  r.add(TBDR_PARAM(imr.clear), ImrClear::Fast, kImrClearNames)
      .doc("fast: a clear marks the attachment's lines cleared in on-chip metadata; the first access to a "
           "cleared line fetches nothing, and at the end of the pass the lines never touched are written only "
           "if the attachment is stored (a fast-clear eliminate); write: the clear writes the whole attachment")
      .source("ATI Radeon HyperZ (2000): Fast Z Clear; AMD, GCN3 ISA / RadeonSI: fast clear with a fast-clear "
              "eliminate pass before the surface is read as a texture");

  const std::string ramulator_queue =
      "no public figure for a GPU's controller; Ramulator's controller queues hold 32 (src/Controller.h)";
  const std::string ramulator_drain =
      "Ramulator src/Controller.h and Ramulator 2.0 GenericDRAMController drain from 0.8 to 0.2 of the queue; "
      "0.75 / 0.25 here";
  r.section("dram", "External memory: channels, banks, row buffers, timing, queues");
  r.add(TBDR_PARAM(dram.name), std::string("LPDDR3-1600 2x32")).doc("Label").source("preset label");
  r.add(TBDR_PARAM(dram.channels), 2).unit("channels").range(1, 32)
      .doc("Independent channels").source("two 32-bit LPDDR3 channels give 12.8 GB/s");
  r.add(TBDR_PARAM(dram.banks), 8).unit("banks").range(1, 64)
      .doc("Banks per channel").source("LPDDR3: 8 banks (JESD209-3)");
  r.add(TBDR_PARAM(dram.row_bytes), 4096).unit("bytes").range(256, 65536)
      .doc("Row (page) size per bank").source("LPDDR3 x32 page size 4 KB (JESD209-3)");
  r.add(TBDR_PARAM(dram.burst_bytes), 32).unit("bytes").range(8, 1024)
      .doc("Bytes per burst (BL8 on a 32-bit channel)").source("LPDDR3 BL8 x32");
  r.add(TBDR_PARAM(dram.clock_mhz), 800.0).unit("MHz").range(50, 8000)
      .doc("DRAM command clock CK: commands and timings (in ns, rounded up to CK cycles) run on it, and the "
           "data rate is clock_mhz x transfers_per_clock")
      .source("JESD209-3: LPDDR3-1600 has tCK 1.25 ns, 800 MHz");
  r.add(TBDR_PARAM(dram.transfers_per_clock), 2.0).unit("transfers/clock").range(0.25, 32)
      .doc("Data transfers per DQ pin per CK cycle: 2 for double data rate on CK (LPDDR3, LPDDR4/4X), "
           "8 for LPDDR5 at a 4:1 WCK:CK ratio (double data rate on WCK), 4 at 2:1; a real number so that a "
           "synthetic part can pair a round command clock with a round burst time")
      .source("JESD209-3: LPDDR3-1600 moves 1600 MT/s on an 800 MHz CK (JESD209-4 likewise for LPDDR4; "
              "JESD209-5: LPDDR5 data is clocked by WCK)");
  r.add(TBDR_PARAM(dram.bus_width_bits), 32).unit("bits").range(8, 1024)
      .doc("Data bus (DQ) width of one channel; the peak bandwidth, derived and reported by `tbdrsim params` "
           "and as mem/dram peak_bandwidth_gbps, is clock_mhz x transfers_per_clock x bus_width_bits / 8 x channels")
      .source("JESD209-3: an LPDDR3 channel is 32 bits wide (x32 die): 1600 MT/s x 4 B x 2 channels = 12.8 GB/s");
  r.retire("dram.bandwidth_gbps",
           "the peak bandwidth is derived, dram.clock_mhz x dram.transfers_per_clock x dram.bus_width_bits / 8 x "
           "dram.channels (LPDDR3-1600 2x32: 800 MHz x 2 x 32 / 8 x 2 = 12.8 GB/s); set those instead "
           "(`tbdrsim params` prints the derived figure)");
  r.add(TBDR_PARAM(dram.t_rcd_ns), 18.0).unit("ns").range(0, 1000)
      .doc("Activate to read/write").source("LPDDR3 tRCD 18 ns");
  r.add(TBDR_PARAM(dram.t_rp_ns), 18.0).unit("ns").range(0, 1000)
      .doc("Precharge").source("LPDDR3 tRPpb 18 ns");
  r.add(TBDR_PARAM(dram.t_cl_ns), 15.0).unit("ns").range(0, 1000)
      .doc("Read latency (RL)").source("LPDDR3-1600 RL=12 at 800 MHz");
  r.add(TBDR_PARAM(dram.t_ras_ns), 42.0).unit("ns").range(0, 1000)
      .doc("Activate to precharge, minimum row active time").source("LPDDR3 tRAS 42 ns (JESD209-3); LPDDR4 42 ns");
  r.add(TBDR_PARAM(dram.t_wr_ns), 15.0).unit("ns").range(0, 1000)
      .doc("Write recovery: end of write data to precharge").source("LPDDR3 tWR 15 ns (JESD209-3); LPDDR4 18 ns");
  // Activate limits, turnaround and refresh: DRAMPower memspec MICRON_4Gb_LPDDR3-1600_32bit_A gives
  // them in cycles of its 800 MHz clock (1.25 ns).
  r.add(TBDR_PARAM(dram.t_rrd_ns), 10.0).unit("ns").range(0, 1000)
      .doc("Activate to activate in different banks of one channel (tRRD)")
      .source(lpddr3_memspec + ": RRD 8 cycles at 800 MHz");
  r.add(TBDR_PARAM(dram.t_faw_ns), 50.0).unit("ns").range(0, 1000)
      .doc("Four-activate window: at most four activates per channel in any window this long (tFAW)")
      .source(lpddr3_memspec + ": FAW 40 cycles at 800 MHz");
  r.add(TBDR_PARAM(dram.t_wtr_ns), 10.0).unit("ns").range(0, 1000)
      .doc("Write-to-read turnaround: end of write data to the next read command of the channel (tWTR)")
      .source(lpddr3_memspec + ": WTR 8 cycles at 800 MHz");
  r.add(TBDR_PARAM(dram.t_rtw_ns), 3.75).unit("ns").range(0, 1000)
      .doc("Read-to-write turnaround: idle data bus between the end of read data and the start of write data")
      .source("JESD209-3 read to write: WL command no earlier than RL + RU(tDQSCKmax/tCK) + BL/2 + 1 - WL after the "
              "read, so the data bus idles RU(tDQSCKmax/tCK) + 1 cycles; " + lpddr3_memspec +
              ": DQSCK 2 cycles, 3 x 1.25 ns");
  r.add(TBDR_PARAM(dram.bank_groups), 1).unit("groups").range(1, 16)
      .doc("Bank groups per channel; bank b belongs to group b mod bank_groups (1: no bank groups)")
      .source("LPDDR3 and LPDDR4 have none (JESD209-3, JESD209-4); LPDDR5 BG mode: 4 groups of 4 banks "
              "(gem5 src/python/gem5/components/memory/dram_interfaces/lpddr5.py, LPDDR5_6400_1x16_BG_BL16)");
  r.add(TBDR_PARAM(dram.t_ccd_l_ns), 0.0).unit("ns").range(0, 1000)
      .doc("Column to column in the same bank group (tCCD_L): a burst starts at least this long after the previous "
           "burst of its group started (0: only the data bus spaces them)")
      .source("no bank groups on LPDDR3 (JESD209-3); LPDDR5 BG mode 4 CK at 800 MHz = 5 ns (gem5 lpddr5.py, "
              "LPDDR5_6400_1x16_BG_BL16 tCCD_L)");
  r.add(TBDR_PARAM(dram.t_ccd_s_ns), 0.0).unit("ns").range(0, 1000)
      .doc("Column to column in different bank groups (tCCD_S): a burst starts at least this long after the previous "
           "burst of the channel started (0: only the data bus spaces them)")
      .source("LPDDR5 BG mode: BL/n_min = 2 CK at 800 MHz = 2.5 ns, the BL16 burst itself (gem5 lpddr5.py, "
              "LPDDR5_6400_1x16_BG_BL16 tBURST_MIN)");
  r.add(TBDR_PARAM(dram.t_refi_ns), 3900.0).unit("ns").range(0, 1e6)
      .doc("All-bank refresh interval per channel (tREFI; 0 or t_rfc_ns = 0: no refresh)")
      .source(lpddr3_memspec + ": REFI 3120 cycles at 800 MHz");
  r.add(TBDR_PARAM(dram.t_rfc_ns), 130.0).unit("ns").range(0, 10000)
      .doc("All-bank refresh cycle time: every bank of the channel is closed and unusable (tRFCab)")
      .source(lpddr3_memspec + ": RFC 104 cycles at 800 MHz (4 Gb die)");
  r.add(TBDR_PARAM(dram.active_standby_mw), 57.6).unit("mW").range(0, 100000)
      .doc("Background power of one channel's devices while a row is open (active standby, IDD3N x VDD per rail)")
      .source(lpddr3_memspec + ": idd3n 2.0 mA x vdd 1.8 V + idd3n2 45 mA x vdd2 1.2 V, one x32 die per channel");
  r.add(TBDR_PARAM(dram.precharge_standby_mw), 49.2).unit("mW").range(0, 100000)
      .doc("Background power of one channel's devices with every bank precharged (precharge standby, IDD2N x VDD)")
      .source(lpddr3_memspec + ": idd2n 2.0 mA x 1.8 V + idd2n2 38 mA x 1.2 V");
  r.add(TBDR_PARAM(dram.refresh_nj), 26.8).unit("nJ").range(0, 100000)
      .doc("Energy of one all-bank refresh of a channel above active standby ((IDD5 - IDD3N) x VDD x tRFC per rail)")
      .source(lpddr3_memspec + ": ((40 - 2) mA x 1.8 V + (160 - 45) mA x 1.2 V) x 130 ns = 206.4 mW x 130 ns");
  r.add(TBDR_PARAM(dram.powerdown_after_ns), 7.5).unit("ns").range(0, 1e9)
      .doc("A channel with no request queued or in service for this long enters power-down (active power-down "
           "with a row open, precharge power-down otherwise) until its next request arrives, which then waits "
           "t_xp_ns; refreshes go on meanwhile (0: never: an idle channel stands by)")
      .source("DRAMSys (github tukl-msd/DRAMSys, src/DRAMSys/controller/powerdown/PowerDownManagerStaggered.cpp at "
              "2107966): its power-down policy (Staggered) requests entry as soon as the controller has no request; "
              "the delay here is one minimum power-down (tCKE, " + lpddr3_memspec + ": CKE 6 cycles at 800 MHz = "
              "7.5 ns), the shortest idle a power-down can fill (JESD209-3)");
  r.add(TBDR_PARAM(dram.active_powerdown_mw), 11.9).unit("mW").range(0, 100000)
      .doc("Background power of one channel in active power-down (IDD3P x VDD per rail)")
      .source(lpddr3_memspec + ": idd3p0 1.2 mA x 1.8 V + idd3p02 8.15 mA x 1.2 V = 11.94 mW");
  r.add(TBDR_PARAM(dram.precharge_powerdown_mw), 2.1).unit("mW").range(0, 100000)
      .doc("Background power of one channel in precharge power-down (IDD2P x VDD per rail)")
      .source(lpddr3_memspec + ": idd2p0 0.6 mA x 1.8 V + idd2p02 0.87 mA x 1.2 V = 2.12 mW");
  r.add(TBDR_PARAM(dram.t_xp_ns), 7.5).unit("ns").range(0, 1000)
      .doc("Power-down exit to the first command (tXP)").source(lpddr3_memspec + ": XP 6 cycles at 800 MHz");
  r.add(TBDR_PARAM(dram.self_refresh_mw), 5.72).unit("mW").range(0, 100000)
      .doc("Background power of one channel in self-refresh, its own refreshes included (IDD6 x VDD per rail). "
           "Used for the idle time after a frame (gpu.frame_period_us): a channel in precharge power-down enters "
           "self-refresh at its next refresh, as DRAMSys's Staggered policy does; 0 = no self-refresh (power-down "
           "and refreshes go on). Not modelled within a frame")
      .source(lpddr3_memspec + ": idd6 1.0 mA x vdd 1.8 V + idd62 3.27 mA x vdd2 1.2 V = 5.72 mW");
  r.add(TBDR_PARAM(dram.controller_latency_ns), 30.0).unit("ns").range(0, 10000)
      .doc("Memory controller and interconnect latency each way").source("no public figure");
  r.add(TBDR_PARAM(dram.read_queue_entries), 32).unit("requests").range(1, 4096)
      .doc("Read queue per channel, in line requests (a burst chain takes one entry per line)")
      .source(ramulator_queue);
  r.add(TBDR_PARAM(dram.write_queue_entries), 32).unit("requests").range(1, 4096)
      .doc("Write queue per channel, in line requests (a burst chain takes one entry per line)")
      .source(ramulator_queue);
  r.add(TBDR_PARAM(dram.write_high_watermark), 0.75).range(0, 1)
      .doc("Write queue occupancy, as a fraction of write_queue_entries, at which the controller starts serving "
           "writes before reads (a write drain)")
      .source(ramulator_drain);
  r.add(TBDR_PARAM(dram.write_low_watermark), 0.25).range(0, 1)
      .doc("Write queue occupancy, as a fraction of write_queue_entries, at which a write drain ends (writes are "
           "also served whenever no read waits)")
      .source(ramulator_drain);
  r.add(TBDR_PARAM(dram.max_chain_bytes), 1024).unit("bytes").range(0, 65536)
      .doc("Longest run of consecutive lines of one row that one memory request misses in the SLC and "
           "the controller queues as one entry and serves as back-to-back bursts (0: one line per entry)")
      .source("design choice: a streaming unit's consecutive misses are row hits served back to back anyway");
  r.add(TBDR_PARAM(dram.address_mapping), DramMapping::RowBankChannelColumn, kDramMappingNames)
      .doc("Physical address bit order, most significant first").source("design choice");

  const std::string horowitz = "Horowitz, \"Computing's energy problem (and what we can do about it)\", ISSCC 2014 "
                               "(45 nm, 0.9 V)";
  const std::string no_leak = "no public figure for a Rogue unit's leakage: the three logic figures are chosen so "
                              "that the default GPU (4 USCs, 2 texture units, 4 fixed-function units) leaks about "
                              "60 mW of logic, near the single 100 mW static figure this model used before";
  r.section("energy", "Energy per access and per op, leakage per unit, and the process node that scales them "
                      "(SRAM figures come from the CACTI 7 table by array size: docs/energy.md)");
  r.add(TBDR_PARAM(energy.process_nm), 28.0).unit("nm").range(7, 130)
      .doc("CMOS node: scales the per-op energies given at 45 nm (Stillmaker & Baas 2017) and picks the CACTI "
           "SRAM figures (interpolated between CACTI's 22, 32, 45, 65, 90 nm)")
      .source("Series6XT shipped on 28 nm: MediaTek MT8173 (GX6250, TSMC 28 nm HPM)");
  r.add(TBDR_PARAM(energy.vdd_v), 0.9).unit("V").range(0.5, 1.5)
      .doc("Core supply at energy.process_nm: the voltage of the Stillmaker & Baas energy factor")
      .source("TSMC 28 nm HPM nominal core supply 0.9 V; no public figure for the GPU rail");
  r.add(TBDR_PARAM(energy.dram_read_pj_per_bit), 5.1).unit("pJ/bit").range(0, 1000)
      .doc("DRAM read energy per bit (core)").source(lpddr3_memspec);
  r.add(TBDR_PARAM(energy.dram_write_pj_per_bit), 5.9).unit("pJ/bit").range(0, 1000)
      .doc("DRAM write energy per bit (core)").source(lpddr3_memspec);
  r.add(TBDR_PARAM(energy.dram_io_pj_per_bit), 3.8).unit("pJ/bit").range(0, 1000)
      .doc("DRAM I/O energy per bit transferred (drivers, strobes, line charging; both ends)")
      .source("estimate, the memspec gives core energy only (ioPower 0): LPDDR3's HSUL_12 I/O is unterminated, so a "
              "bit costs C x VDDQ^2 per 0->1 edge: 1/4 edge per random data bit + 1/8 for the DQS pair per 8 DQ, "
              "C = 7 pF (2 pF DRAM pin + 2 pF SoC pin + 3 pF PoP line), VDDQ 1.2 V (JESD209-3): "
              "0.375 x 7 pF x 1.44 V^2 = 3.8 pJ");
  r.add(TBDR_PARAM(energy.dram_activate_precharge_nj), 4.3).unit("nJ").range(0, 1000)
      .doc("Energy of one activate + precharge pair").source(lpddr3_memspec);
  r.add(TBDR_PARAM(energy.alu_op_pj_45nm), 2.3).unit("pJ/op").range(0, 1000)
      .doc("Arithmetic of one FP32 ALU op at 45 nm, 0.9 V, scaled to energy.process_nm; operand delivery is "
           "charged apart (energy.register_file_bytes_per_op)")
      .source(horowitz + ": FP32 add 0.9 pJ + FP32 mult 3.7 pJ = one FMA, which usc.alu_ops_per_lane_per_clock "
              "counts as 2 ops: 4.6 / 2 = 2.3 pJ/op");
  r.add(TBDR_PARAM(energy.register_file_bytes_per_op), 8.0).unit("bytes/op").range(0, 64)
      .doc("Register-file bytes read and written per ALU op, charged at the register file's CACTI energy per byte "
           "(a lane's slice of energy.register_file_bytes_per_usc)")
      .source("an FMA (2 ops) reads 3 FP32 operands and writes 1: 16 B / 2 ops; no operand cache or forwarding "
              "modelled (Horowitz ISSCC 2014: operand delivery costs more than the arithmetic)");
  r.add(TBDR_PARAM(energy.register_file_bytes_per_usc), 81920.0).unit("bytes").range(1024, 64 * kMiB)
      .doc("Register storage of one USC: its leakage (CACTI RAM of this size) and, per lane slice (/ usc.lanes), "
           "its access energy")
      .source(mesa + ": common_store_size_in_dwords = 1280 x 4 x 4 dwords = 80 KiB; the unified store of "
              "temporaries (unified_store_depth = 256) has no byte size there and is not counted");
  r.add(TBDR_PARAM(energy.texel_pj_45nm), 12.7).unit("pJ/filtered texel").range(0, 1000)
      .doc("Arithmetic of one bilinear-filtered texel (texture.texels_per_clock's unit) at 45 nm, 0.9 V, scaled "
           "to energy.process_nm; its texel bytes are the texture cache's")
      .source(horowitz + " per-op figures: coordinates 2 FP32 mult (2 x 3.7) + 2 FP32 add for the fractions "
              "(2 x 0.9) + 4 texel addresses (4 x 32-bit add 0.1) + RGBA8 filter, 4 channels x 3 lerps x "
              "(8-bit mult 0.2 + 2 x 8-bit add 0.03): 7.4 + 1.8 + 0.4 + 3.12 = 12.7 pJ");
  r.add(TBDR_PARAM(energy.usc_leakage_mw), 10.0).unit("mW").range(0, 100000)
      .doc("Logic leakage of one USC at the configured node (its register file's leakage comes from CACTI); "
           "static power is the sum over usc.count").source(no_leak + "; a USC is the largest block: 10 mW");
  r.add(TBDR_PARAM(energy.texture_unit_leakage_mw), 5.0).unit("mW").range(0, 100000)
      .doc("Logic leakage of one texture unit (texture.units of them) at the configured node")
      .source(no_leak + "; half a USC: 5 mW");
  r.add(TBDR_PARAM(energy.fixed_function_leakage_mw), 3.0).unit("mW").range(0, 100000)
      .doc("Logic leakage of one fixed-function unit at the configured node: geometry, tiler, pixel back end and "
           "one per ISP raster pipe (isp.raster_pipes)")
      .source(no_leak + ": 3 mW");
  r.add(TBDR_PARAM(energy.gated_leakage_fraction), 0.1).range(0, 1)
      .doc("Share of a unit's leakage still drawn while it is power gated: applied to the USCs, texture and "
           "fixed-function units and the per-tile buffers and register files in the idle time after a frame "
           "(gpu.frame_period_us); the caches keep their data and leak in full. Within a frame nothing is gated")
      .source("no public figure: Imagination's PowerGearing gates idle Rogue USCs without published figures; "
              "0.1 assumes the power switches leave a tenth of a domain's leakage");
  return r;
}

}  // namespace

#undef TBDR_PARAM

const ParamRegistry<HwConfig>& hw_params() {
  static const ParamRegistry<HwConfig> registry = make_registry();
  return registry;
}

ResolvedConfig resolve_config(const std::vector<std::string>& config_files,
                              const std::vector<std::string>& overrides) {
  const auto& reg = hw_params();
  ResolvedConfig rc;
  rc.params = reg.table().resolve(config_files, overrides);
  rc.hw = reg.build(rc.params);
  check_config_constraints(rc.hw, rc.params);
  rc.hash = reg.table().hash(rc.params);
  rc.label = reg.table().label(rc.params, reg.table().preset(config_files));
  return rc;
}

}  // namespace tbdr
