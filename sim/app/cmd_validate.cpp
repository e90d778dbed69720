// `tbdrsim validate`: the simulator against published figures. Runs small, fixed setups (every run
// stored in a results database) and prints, for each published anchor, the published figure, the
// simulator's, the setup and whether it holds: exactly where the anchor is arithmetic (bytes a
// frame must move), in shape where it is a measurement of other hardware. `--markdown FILE` writes
// the same table (docs/validation.md is that file; a test keeps the two equal).
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <ostream>
#include <sstream>
#include <string>
#include <variant>
#include <vector>

#include <boost/program_options.hpp>

#include "analysis/results_db.hpp"
#include "app/cli.hpp"
#include "app/commands.hpp"
#include "app/run_driver.hpp"
#include "models/dram_memspec.hpp"
#include "models/dram_microbench.hpp"
#include "kernel/errors.hpp"
#include "trace/trace.hpp"

namespace tbdr {

namespace po = boost::program_options;
namespace fs = std::filesystem;

namespace {

/// One published figure beside the simulator's.
struct AnchorRow {
  std::string anchor;     ///< the publication and what it measured
  std::string published;  ///< its figure
  std::string simulated;  ///< ours
  std::string setup;      ///< what ran
  std::string kind;       ///< exact | shape
  bool holds = false;
};

std::string fixed(double v, int decimals) {
  std::ostringstream s;
  s << std::fixed << std::setprecision(decimals) << v;
  return s.str();
}

constexpr double kMiB = 1024.0 * 1024.0;

/// Runs traces into the validation database and reads their figures.
class Validator {
 public:
  /// `files` and `sets`: the user's --config and --set, under every run's own settings.
  Validator(std::string dir, std::vector<std::string> files, std::vector<std::string> sets)
      : dir_(std::move(dir)), files_(std::move(files)), sets_(std::move(sets)) {
    fs::create_directories(fs::path(dir_) / "traces");
    db_ = (fs::path(dir_) / "validation.db").string();
    { ResultsDb db(db_); }
  }

  /// Writes a trace with the generator (`tbdrsim trace` arguments) and returns its path.
  std::string generate(const std::string& name, std::vector<std::string> args) {
    const std::string path = trace_path(name);
    args.insert(args.begin(), "trace");
    args.insert(args.end(), {"--out", path});
    std::ostringstream sink, errs;
    if (cli_main(args, sink, errs) != 0) throw InputError("validate", "generating " + name + ": " + errs.str());
    return path;
  }

  std::string trace_path(const std::string& name) const { return (fs::path(dir_) / "traces" / (name + ".trace")).string(); }

  /// Runs a trace on the validation configuration plus `sets`; the run is stored.
  RunOutcome run(const std::string& trace, const std::vector<std::string>& sets = {}) {
    std::vector<std::string> all = sets_;
    all.insert(all.end(), sets.begin(), sets.end());
    RunRequest req;
    req.config = resolve_config(files_, all);
    req.trace_path = trace;
    req.db_path = db_;
    req.command_line = "tbdrsim validate";
    return run_one(req);
  }

  const std::string& db() const { return db_; }

 private:
  std::string dir_, db_;
  std::vector<std::string> files_, sets_;
};

/// A statistic of a run (0 when the unit recorded none).
double stat(const RunOutcome& r, const std::string& scope, const std::string& name) {
  for (const auto& s : r.frame.stats) {
    if (s.scope == scope && s.name == name) return s.value;
  }
  return 0.0;
}

/// Framebuffer traffic the units requested: colour, G-buffer and depth/stencil, read and written.
double framebuffer_bytes(const RunOutcome& r) {
  double sum = 0;
  for (const char* c : {"frame/dram.color", "frame/dram.gbuffer", "frame/dram.depth_stencil"})
    sum += stat(r, c, "read_bytes") + stat(r, c, "write_bytes");
  return sum;
}

/// The scene's geometry drawn with `pipeline` (the G-buffer fill: it gives the pixels a surface).
DrawCmd scene_geometry(const std::string& pipeline) {
  DrawCmd d;
  d.pipeline = pipeline;
  d.geometry = GeometryKind::Scene;
  d.subset = SceneSubset::All;
  return d;
}

/// A fullscreen draw of `shader` with `pipeline`.
DrawCmd fullscreen(const std::string& pipeline, std::vector<std::string> reads = {}) {
  DrawCmd d;
  d.pipeline = pipeline;
  d.geometry = GeometryKind::Fullscreen;
  d.reads = std::move(reads);
  return d;
}

Attachment attachment(const std::string& name, Format f, AttachmentUsage usage, StoreOp store, bool transient = false) {
  Attachment a;
  a.name = name;
  a.format = f;
  a.usage = usage;
  a.load = LoadOp::Clear;
  a.store = store;
  a.transient = transient;
  return a;
}

/// `base`'s scene, frame and camera with nothing else: no generator, lights, buffers or commands
/// (the hand-written frames below add their own).
Trace hand_written(const Trace& base) {
  Trace t = base;
  t.technique.clear();
  t.options.clear();
  t.lights.clear();
  t.light_lines.clear();
  t.buffers.clear();
  t.commands.clear();
  return t;
}

/// Bjørge's two 1080p deferred frames (GPU Pro 5, "Bandwidth efficient graphics with ARM Mali
/// GPUs"): framebuffer traffic only, 32-bit colour targets and D24S8. `pls`: the G-buffer, light
/// accumulation and resolve in one pass whose G-buffer lives in pixel local storage. The fill draws
/// the scene; the stores move whole surfaces and the fullscreen passes read every pixel, so the
/// bytes do not depend on what the scene covers.
Trace bjorge_frame(const Trace& base, bool pls) {
  Trace t = hand_written(base);
  auto shader = [](const std::string& name, std::uint32_t outputs, PlsAccess access) {
    ShaderDesc s;
    s.name = name;
    s.alu_ops = 8;
    s.color_outputs = outputs;
    s.pls = access;
    return s;
  };
  auto pipeline = [](const std::string& name, const std::string& shader, bool depth) {
    PipelineState p;
    p.name = name;
    p.shader = shader;
    p.depth_test = depth;
    p.depth_write = depth;
    p.depth_compare = depth ? CompareOp::Less : CompareOp::Always;
    p.cull = CullMode::None;
    return p;
  };
  if (!pls) {
    t.shaders = {shader("fill", 2, PlsAccess::None), shader("accumulate", 1, PlsAccess::None), shader("resolve", 1, PlsAccess::None)};
    t.pipelines = {pipeline("fill", "fill", true), pipeline("accumulate", "accumulate", false), pipeline("resolve", "resolve", false)};
    PassDesc fill;
    fill.name = "gbuffer_fill";
    fill.attachments = {attachment("albedo", Format::Rgba8, AttachmentUsage::Gbuffer, StoreOp::Store),
                        attachment("normal", Format::Rgba8, AttachmentUsage::Gbuffer, StoreOp::Store),
                        attachment("depth", Format::D24s8, AttachmentUsage::Depth, StoreOp::Store)};
    fill.draws = {scene_geometry("fill")};
    PassDesc accumulate;
    accumulate.name = "light_accumulation";
    accumulate.attachments = {attachment("light", Format::Rgba8, AttachmentUsage::Color, StoreOp::Store)};
    // Bjørge's accumulation reads normal and depth; the surface a light needs is kept with the
    // first G-buffer target, so this one reads albedo and normal: the same 2 x 4 bytes per pixel.
    accumulate.draws = {fullscreen("accumulate", {"albedo", "normal"})};
    PassDesc resolve;
    resolve.name = "resolve";
    resolve.attachments = {attachment("color", Format::Rgba8, AttachmentUsage::Color, StoreOp::Store)};
    resolve.draws = {fullscreen("resolve", {"albedo", "light"})};
    t.commands = {fill, accumulate, resolve};
    return t;
  }
  t.shaders = {shader("fill", 0, PlsAccess::Write), shader("accumulate", 0, PlsAccess::ReadWrite), shader("resolve", 1, PlsAccess::Read)};
  t.pipelines = {pipeline("fill", "fill", true), pipeline("accumulate", "accumulate", false), pipeline("resolve", "resolve", false)};
  PassDesc main;
  main.name = "main";
  main.attachments = {attachment("color", Format::Rgba8, AttachmentUsage::Color, StoreOp::Store),
                      attachment("depth", Format::D24s8, AttachmentUsage::Depth, StoreOp::DontCare, true)};
  main.pls = {PlsVariable{"albedo", Format::Rgba8, 0}, PlsVariable{"normal", Format::Rgba8, 0},
              PlsVariable{"light", Format::Rgba8, 0}};
  main.draws = {scene_geometry("fill"), fullscreen("accumulate"), fullscreen("resolve")};
  t.commands = {main};
  return t;
}

void bjorge(Validator& v, std::vector<AnchorRow>& rows) {
  const std::string base_path = v.generate("bjorge_base", {"--technique", "plain_forward", "--scene", "atrium:1",
                                                           "--lights", "0", "--resolution", "1920x1080"});
  const Trace base = read_trace(base_path);
  double mib[2] = {0, 0};
  for (int pls = 0; pls < 2; ++pls) {
    const std::string path = v.trace_path(pls ? "bjorge_pls" : "bjorge_mrt");
    write_trace_file(bjorge_frame(base, pls != 0), path);
    mib[pls] = framebuffer_bytes(v.run(path)) / kMiB;
  }
  // 1920 x 1080 x 4 B = 7.91 MiB per 32-bit surface: 3 written (fill), 2 read + 1 written
  // (accumulation), 2 read + 1 written (resolve) = 9 x 7.91 = 71.19; with PLS only the colour.
  const double surface = 1920.0 * 1080.0 * 4.0 / kMiB;
  rows.push_back({"Bjørge, GPU Pro 5: deferred framebuffer traffic, multiple render targets", "71.19 MB",
                  fixed(mib[0], 2) + " MiB", "1920x1080, albedo + normal rgba8 + D24S8 stored; accumulation and resolve "
                  "passes read 2 surfaces, write 1", "exact", std::abs(mib[0] - 9 * surface) < 0.005});
  rows.push_back({"Bjørge, GPU Pro 5: the same with the G-buffer in pixel local storage", "7.91 MB (9x less)",
                  fixed(mib[1], 2) + " MiB (" + fixed(mib[0] / std::max(mib[1], 1e-9), 2) + "x less)",
                  "one pass, PLS albedo/normal/light, depth transient", "exact", std::abs(mib[1] - surface) < 0.005});
}

void burns_hunt(Validator& v, std::vector<AnchorRow>& rows) {
  const RunOutcome r = v.run(v.generate("visibility_8x", {"--technique", "visibility_buffer", "--scene", "atrium:1",
                                                          "--lights", "16", "--resolution", "480x270", "--samples", "8"}));
  const double per_sample = stat(r, "frame/dram.visibility", "write_bytes") / (480.0 * 270.0 * 8.0);
  const double at_1080p = per_sample * 1920.0 * 1080.0 * 8.0 / kMiB;
  rows.push_back({"Burns & Hunt, JCGT 2013: visibility buffer bytes per sample", "4 B", fixed(per_sample, 2) + " B",
                  "visibility_buffer, atrium:1 480x270 8x MSAA: visibility bytes stored / samples", "exact",
                  std::abs(per_sample - 4.0) < 1e-9});
  rows.push_back({"Burns & Hunt, JCGT 2013: 1080p 8x MSAA visibility buffer", "about 64 MB", fixed(at_1080p, 1) + " MiB",
                  "the bytes per sample above x 1920 x 1080 x 8", "exact",
                  std::abs(at_1080p - 4.0 * 1920.0 * 1080.0 * 8.0 / kMiB) < 1e-9});
}

void hsr(Validator& v, std::vector<AnchorRow>& rows) {
  const std::string t = v.generate("street", {"--technique", "plain_forward", "--scene", "atrium:4", "--camera", "street",
                                              "--lights", "16", "--resolution", "480x270"});
  const RunOutcome tbdr = v.run(t, {"gpu.mode=tbdr"});
  const RunOutcome tbr = v.run(t, {"gpu.mode=tbr"});
  // An immediate-mode GPU without early-Z (isp.early_z=0): every rasterised fragment is shaded.
  const RunOutcome imr_late = v.run(t, {"gpu.mode=imr", "isp.early_z=0"});
  const double px = 480.0 * 270.0;
  const double raster = stat(tbdr, "frame/isp", "samples_rasterised") / px;
  const double shaded_imr = stat(imr_late, "frame/tsp", "shader_invocations") / px;
  const double shaded_tbdr = stat(tbdr, "frame/tsp", "shader_invocations") / px;
  const double shaded_tbr = stat(tbr, "frame/tsp", "shader_invocations") / px;
  rows.push_back({"Imagination, PowerVR Architecture Guide: fragments coloured per pixel without early-Z/HSR -> with "
                  "PowerVR HSR (Shadowgun frame)",
                  "4.7 -> 1.2 (3.9x)",
                  fixed(shaded_imr, 2) + " -> " + fixed(shaded_tbdr, 2) + " (" + fixed(shaded_imr / shaded_tbdr, 2) +
                      "x); TBR early-Z " + fixed(shaded_tbr, 2),
                  "plain_forward, atrium:4 street view, 480x270: shaded samples per pixel on an IMR without early-Z "
                  "(isp.early_z=0), on TBDR and on TBR with early-Z in the trace's order",
                  "shape",
                  shaded_imr / shaded_tbdr >= 3.0 && shaded_tbdr <= 1.3 && shaded_tbr > shaded_tbdr &&
                      shaded_imr > shaded_tbr && std::abs(shaded_imr - raster) < 1e-9});
}

void onchip_cliff(Validator& v, std::vector<AnchorRow>& rows) {
  std::vector<double> ms;
  for (int k = 2; k <= 8; ++k) {
    std::string layout;
    for (int i = 0; i < std::min(k, 7); ++i) layout += (i ? "," : "") + std::string("rgba8");
    if (k == 8) layout = "rgba8,rgba8,rgba8,rgba8,rgba8,rgba8,rgba16f";
    const std::string t = v.generate("cliff_" + std::to_string(32 * (k + 1)),
                                     {"--technique", "deferred", "--scene", "atrium:2", "--lights", "64", "--resolution",
                                      "480x270", "--option", "gbuffer=" + layout, "--option", "gbuffer_storage=onchip"});
    ms.push_back(stat(v.run(t, {"usc.count=2", "texture.units=1", "pls.tile_buffer_bits_per_pixel=256"}), "frame/timing",
                      "frame_time_ms"));
  }
  double mean = 0;
  for (std::size_t i = 1; i + 1 < ms.size(); ++i) mean += (ms[i] - ms[i - 1]) / static_cast<double>(ms.size() - 2);
  const double last = ms.back() - ms[ms.size() - 2];
  std::string sim;
  for (std::size_t i = 0; i < ms.size(); ++i) sim += (i ? ", " : "") + fixed(ms[i], 3);
  rows.push_back({"Imagination, PowerVR Performance Recommendations, On-Chip Memory Performance: GX6250 ms per frame, "
                  "96 .. 288 bits per pixel on chip (256 fit)",
                  "20, 21, 23, 24, 28, 29, 39 (last step 5.6x the mean earlier step)",
                  sim + " (last step " + fixed(last / std::max(mean, 1e-12), 1) + "x)",
                  "deferred gbuffer_storage=onchip, atrium:2 480x270 64 lights, 2 USCs, 1 texture unit, 256 bits on chip",
                  "shape", mean > 0 && last >= 3.0 * mean});
}

/// A roofline anchor: `cycles` simulated against the `bound` its arithmetic (`formula`) gives;
/// it holds from `low` x bound (1: never faster than the bound) up to 5 % over.
AnchorRow roofline(const std::string& name, double bound, const std::string& formula, double cycles, const std::string& setup,
                   double low) {
  return {name, formula, fixed(cycles, 0) + " cycles (" + fixed(100.0 * (cycles / bound - 1.0), 1) + " %)", setup, "exact",
          cycles >= low * bound && cycles <= 1.05 * bound};
}

void rooflines(Validator& v, std::vector<AnchorRow>& rows, const HwConfig& hw) {
  // ALU-bound: 4000 ALU ops per fragment; the frame's ALU ops over the USCs' rate.
  {
    const RunOutcome r = v.run(v.generate("alu_bound", {"--technique", "plain_forward", "--scene", "atrium:1", "--lights", "0",
                                                        "--resolution", "480x270", "--option", "alu_ops=4000",
                                                        "--option", "tex_fetches=0"}));
    const double rate = static_cast<double>(hw.usc.count * hw.usc.lanes) * hw.usc.alu_ops_per_lane_per_clock;
    const double bound = (stat(r, "frame/tsp", "fragment_alu_ops") + stat(r, "frame/geometry", "vertex_alu_ops")) / rate;
    const double cycles = stat(r, "frame/timing", "frame_cycles");
    rows.push_back(roofline("Roofline: an ALU-bound frame", bound, fixed(bound, 0) + " cycles (ALU ops / (usc.count x lanes x ops per lane))", cycles, "plain_forward alu_ops=4000, atrium:1 480x270", 1.0));
  }
  // Texture-bound: 64 bilinear fetches per fragment; filtered texels over the texture units' rate.
  // One texture unit, so that the frame's texture lines use about a third of the DRAM's bandwidth
  // (with the default two, 72 %: refresh and bank conflicts then show in the frame time).
  {
    const RunOutcome r = v.run(v.generate("texture_bound", {"--technique", "plain_forward", "--scene", "atrium:1", "--lights", "0",
                                                            "--resolution", "480x270", "--option", "alu_ops=0",
                                                            "--option", "tex_fetches=64"}),
                               {"texture.units=1"});
    const double rate = 1.0 * hw.texture.texels_per_clock;
    const double bound = stat(r, "frame/tsp", "texels_filtered") / rate;
    const double cycles = stat(r, "frame/timing", "frame_cycles");
    rows.push_back(roofline("Roofline: a texture-bound frame", bound, fixed(bound, 0) + " cycles (filtered texels / (units x texels per clock))", cycles, "plain_forward tex_fetches=64, atrium:1 480x270, texture.units=1", 1.0));
  }
}

/// `layers` fullscreen triangles at one depth over a cleared rgba8 target with a depth test: the
/// first is shaded (one ALU op), the others fail the depth test (Less) and are only rasterised.
Trace fill_frame(const Trace& base, int layers) {
  Trace t = hand_written(base);
  ShaderDesc sh;
  sh.name = "flat";
  sh.alu_ops = 1;
  sh.color_outputs = 1;
  PipelineState pl;
  pl.name = "flat";
  pl.shader = "flat";
  pl.cull = CullMode::None;
  t.shaders = {sh};
  t.pipelines = {pl};
  PassDesc pass;
  pass.name = "fill";
  pass.attachments = {attachment("color", Format::Rgba8, AttachmentUsage::Color, StoreOp::Store),
                      attachment("depth", Format::D24s8, AttachmentUsage::Depth, StoreOp::DontCare, true)};
  for (int i = 0; i < layers; ++i) pass.draws.push_back(fullscreen("flat"));
  t.commands = {pass};
  return t;
}

/// `passes` passes that each clear and store one rgba8 target with one flat fullscreen triangle:
/// the stores move 4 B per pixel and pass, everything else is small.
Trace store_frame(const Trace& base, int passes) {
  Trace t = fill_frame(base, 1);
  t.pipelines[0].depth_test = false;
  t.pipelines[0].depth_write = false;
  PassDesc pass;
  pass.attachments = {attachment("color", Format::Rgba8, AttachmentUsage::Color, StoreOp::Store)};
  pass.draws = {fullscreen("flat")};
  t.commands.clear();
  for (int i = 0; i < passes; ++i) {
    pass.name = "store_" + std::to_string(i);
    t.commands.push_back(pass);
  }
  return t;
}

/// An rgba8 image stored by a flat fullscreen pass, then read at every pixel by a second pass's
/// fullscreen draw (`reads=`): the second pass's shading waits for those reads.
Trace read_back_frame(const Trace& base) {
  Trace t = store_frame(base, 1);
  std::get<PassDesc>(t.commands[0]).name = "produce";  // writes `color`
  PassDesc consume;
  consume.name = "consume";
  consume.attachments = {attachment("result", Format::Rgba8, AttachmentUsage::Color, StoreOp::Store)};
  consume.draws = {fullscreen("flat", {"color"})};
  t.commands.push_back(consume);
  return t;
}

void fill_and_bandwidth_rooflines(Validator& v, std::vector<AnchorRow>& rows, const HwConfig& hw) {
  const Trace base = read_trace(v.generate("roofline_base", {"--technique", "plain_forward", "--scene", "atrium:1",
                                                             "--lights", "0", "--resolution", "480x270"}));
  // Fill-bound: 64 layers of 480 x 270 samples through the ISP's depth test at
  // isp.samples_per_clock x isp.raster_pipes samples per clock.
  {
    constexpr int kLayers = 64;
    const std::string path = v.trace_path("fill_bound");
    write_trace_file(fill_frame(base, kLayers), path);
    const RunOutcome r = v.run(path);
    const double rate = static_cast<double>(hw.isp.samples_per_clock * hw.isp.raster_pipes);
    const double bound = stat(r, "frame/isp", "samples_rasterised") / rate;
    const double cycles = stat(r, "frame/timing", "frame_cycles");
    rows.push_back(roofline("Roofline: a fill-bound frame", bound, fixed(bound, 0) + " cycles (rasterised samples / (samples per clock x raster pipes))", cycles, "64 fullscreen layers at one depth (63 hidden), 480x270", 1.0));
  }
  // DRAM-bound: 32 passes each storing a 480 x 270 rgba8 image. Each tile's store (4 KB) fills
  // one DRAM row, and the bus stops while a row is switched: the write queue
  // (dram.write_queue_entries) holds the current tile's writes, so the next tile's bank is not
  // prepared while they stream. Per channel, the stored bytes at the peak rate, plus per row
  // opened (counted: dram row_misses) write recovery, precharge and activate (tWR + tRP + tRCD),
  // plus per refresh tRFC.
  {
    constexpr int kPasses = 32;
    const std::string path = v.trace_path("dram_bound");
    write_trace_file(store_frame(base, kPasses), path);
    const RunOutcome r = v.run(path);
    const double bytes = stat(r, "mem/dram", "write_bytes") + stat(r, "mem/dram", "read_bytes");
    const auto& d = hw.dram;
    const double cycles_per_ns = hw.gpu.core_clock_mhz * 1e-3;
    const double peak_bytes_per_cycle = d.peak_bandwidth_gbps() / cycles_per_ns;
    const double opened = stat(r, "mem/dram", "row_misses"), refreshes = stat(r, "mem/dram", "refreshes");
    const double bound = bytes / peak_bytes_per_cycle +
                         (opened * (d.t_wr_ns + d.t_rp_ns + d.t_rcd_ns) + refreshes * d.t_rfc_ns) * cycles_per_ns /
                             static_cast<double>(d.channels);
    const double cycles = stat(r, "frame/timing", "frame_cycles");
    rows.push_back(roofline("Roofline: a DRAM-bound frame", bound, fixed(bound, 0) + " cycles (DRAM bytes / peak bandwidth (dram.clock_mhz x transfers_per_clock x bus_width_bits / 8 x channels) + (rows opened x (tWR + tRP + tRCD) + "
                    "refreshes x tRFC) / channels)", cycles, "32 passes each storing a 480x270 rgba8 image: " + fixed(bytes / kMiB, 1) + " MiB, " + fixed(opened, 0) +
                        " rows opened (one per tile store and after refreshes), " + fixed(refreshes, 0) + " refreshes", 1.0));
  }
  // Latency-bound: one USC with one task slot (usc.count=1, usc.tasks_in_flight=1), so one line
  // of the read-back image is in flight at a time (timing model: a tile's image reads keep one
  // line per resident task in flight). By Little's law the reading pass takes its lines x their
  // mean latency (measured: the texture client's issue-to-data time through the texture cache,
  // SLC and DRAM), whatever the bandwidth.
  {
    const std::string path = v.trace_path("latency_bound");
    write_trace_file(read_back_frame(base), path);
    const RunOutcome r = v.run(path, {"usc.count=1", "usc.tasks_in_flight=1"});
    const double lines = stat(r, "mem/client.texture", "completed");
    const double latency_ns = stat(r, "mem/client.texture", "avg_latency_ns");
    const double bound = lines * latency_ns * hw.gpu.core_clock_mhz * 1e-3;
    // The reading pass's fragment work starts when it is binned and the producing pass is done
    // (its start_cycle is its binning's, which overlaps the producer).
    const double cycles = stat(r, "pass1.consume/timing", "end_cycle") -
                          std::max(stat(r, "pass1.consume/timing", "binning_end_cycle"), stat(r, "pass0.produce/timing", "end_cycle"));
    rows.push_back(roofline("Roofline: a latency-bound pass (Little's law)", bound, fixed(bound, 0) + " cycles (lines read / 1 in flight x mean latency " + fixed(latency_ns, 1) + " ns)", cycles, "a fullscreen pass reading a stored 480x270 rgba8 image at every pixel, usc.count=1, "
                    "usc.tasks_in_flight=1: " + fixed(lines, 0) + " lines", 0.99));
  }
}

void olsson(Validator& v, std::vector<AnchorRow>& rows) {
  double per_fragment[2] = {0, 0};
  const char* names[2] = {"forward_plus", "clustered_forward"};
  for (int i = 0; i < 2; ++i) {
    // The same 16-pixel screen tiles for both: clusters add the depth slices (Olsson et al.
    // compare at equal tile size).
    const RunOutcome r = v.run(v.generate(std::string("olsson_") + names[i], {"--technique", names[i], "--scene", "atrium:3",
                                                                              "--lights", "1024", "--resolution", "480x270",
                                                                              "--option", "tile_px=16"}));
    per_fragment[i] = stat(r, "frame/tsp", "light_evaluations") / std::max(1.0, stat(r, "frame/tsp", "lit_surface_invocations"));
  }
  rows.push_back({"Olsson, Billeter & Assarsson, HPG 2012: clustered shading evaluates fewer lights than tiled",
                  "5.6 vs 17.7 ms of shading (about 2,400 lights)",
                  fixed(per_fragment[1], 1) + " vs " + fixed(per_fragment[0], 1) + " lights per lit fragment",
                  "clustered_forward (16 depth slices) vs forward_plus, 16-pixel tiles, atrium:3 480x270, 1024 lights", "shape", per_fragment[1] < per_fragment[0]});
}

/// The DRAM presets against their memspecs: energy per bit of a streaming and a random read
/// microbenchmark (models/dram_microbench) beside the same patterns priced by DRAMPower's formulas
/// on the memspec's currents (models/dram_memspec); the refresh overhead of a stream beside
/// tRFC / tREFI; and the forward_plus frame's energy per bit inside the memspec's range.
void dram_memspecs(Validator& v, std::vector<AnchorRow>& rows, const HwConfig& validated) {
  double frame_low = 0, frame_high = 0;
  std::string frame_dram;
  for (const DramPresetMemspec& p : dram_preset_memspecs()) {
    std::vector<std::string> files;
    for (const auto& c : p.configs) files.push_back(find_data_file(c, DataFolder::Configs));
    const HwConfig hw = resolve_config(files, {}).hw;
    const MemspecPerBit m = preset_memspec_per_bit(p, hw);
    const DramBenchResult s = run_dram_microbench(hw, DramPattern::Stream, 65536);
    const DramBenchResult r = run_dram_microbench(hw, DramPattern::Random, 16384);
    std::string configs;
    for (const auto& c : p.configs) configs += (configs.empty() ? "" : " + ") + c;
    // A stream at full bandwidth must be the memspec's figure; a bank-group stream (tCCD_L-bound,
    // see configs/dram_lpddr5_6400_bg.ini) stands by longer per bit, so it may only be dearer.
    const bool bg = hw.dram.bank_groups > 1;
    const bool stream_ok = bg ? s.pj_per_bit >= m.stream_pj : std::abs(s.pj_per_bit / m.stream_pj - 1.0) <= 0.03;
    const bool random_ok = std::abs(r.pj_per_bit / m.random_pj - 1.0) <= 0.15;
    rows.push_back({"DRAMPower formulas on memspec " + p.memspec->id + ": DRAM energy per bit read, streaming .. random lines (" +
                        p.label + ")",
                    fixed(m.stream_pj, 1) + " .. " + fixed(m.random_pj, 1) + " pJ/bit",
                    fixed(s.pj_per_bit, 1) + " .. " + fixed(r.pj_per_bit, 1) + " pJ/bit (" + fixed(100.0 * s.efficiency, 1) +
                        " % / " + fixed(100.0 * r.efficiency, 1) + " % of peak)",
                    configs + ": 4 MiB stream and 16384 random 64 B lines, a read stream per channel, refresh on; " + p.note +
                        "; " + p.memspec->source,
                    "exact", stream_ok && random_ok});
    if (p.label == validated.dram.name) {  // the DRAM the frames run on
      frame_low = m.stream_pj;
      frame_high = m.random_pj;
      frame_dram = p.label;
    }
    if (&p == &dram_preset_memspecs().front()) {
      // Refresh: the same stream with refresh off; each refresh idles the bus tRP + tRFC + tRCD + RL.
      const DramBenchResult off = run_dram_microbench(resolve_config(files, {"dram.t_refi_ns=0"}).hw, DramPattern::Stream, 65536);
      const auto& d = hw.dram;
      const double lost = 1.0 - s.efficiency / off.efficiency;
      const double predicted = (d.t_rp_ns + d.t_rfc_ns + d.t_rcd_ns + d.t_cl_ns) / d.t_refi_ns;
      rows.push_back({"Refresh overhead as tRFC / tREFI (" + p.label + ")",
                      fixed(100.0 * d.t_rfc_ns / d.t_refi_ns, 2) + " % (tRFC / tREFI); " + fixed(100.0 * predicted, 2) +
                          " % with the tRP + tRCD + RL around each refresh",
                      fixed(100.0 * lost, 2) + " % of the stream's bandwidth",
                      configs + ": the 4 MiB stream above, refresh off and on", "exact",
                      lost >= d.t_rfc_ns / d.t_refi_ns && std::abs(lost - predicted) <= 0.005});
    }
  }
  if (frame_dram.empty()) return;  // a DRAM of the user's own: no memspec to hold the frame to
  const RunOutcome r = v.run(v.trace_path("olsson_forward_plus"));
  const double bits = 8.0 * (stat(r, "mem/dram", "read_bytes") + stat(r, "mem/dram", "write_bytes"));
  const double pj_per_bit = stat(r, "mem/dram", "energy_pj") / std::max(1.0, bits);
  rows.push_back({"The memspec's range on a frame (" + frame_dram + ")",
                  fixed(frame_low, 1) + " .. " + fixed(frame_high, 1) + " pJ/bit (streaming .. random above)",
                  fixed(pj_per_bit, 1) + " pJ/bit, row hits " + fixed(100.0 * stat(r, "mem/dram", "row_hit_rate"), 1) + " %",
                  "forward_plus above: DRAM energy (dynamic, standby, refresh) / bits transferred", "shape",
                  pj_per_bit >= frame_low && pj_per_bit <= frame_high});
}

std::string markdown(const std::vector<AnchorRow>& rows, const std::string& config_name) {
  std::ostringstream md;
  md << "# Validation against published figures\n\n"
     << "Generated by `tbdrsim validate --markdown docs/validation.md` (configuration '" << config_name
     << "'); a test keeps this file equal to the command's output. *exact*: arithmetic the simulator must "
        "reproduce; *shape*: a measurement of other hardware the simulator must follow in direction and size.\n\n"
     << "| anchor | published | simulated | setup | kind | holds |\n|---|---|---|---|---|---|\n";
  for (const auto& r : rows) {
    md << "| " << r.anchor << " | " << r.published << " | " << r.simulated << " | " << r.setup << " | " << r.kind << " | "
       << (r.holds ? "yes" : "**no**") << " |\n";
  }
  return md.str();
}

}  // namespace

int cmd_validate(const std::vector<std::string>& args, std::ostream& out, std::ostream& err) {
  po::options_description desc("validate options");
  add_config_options(desc);
  desc.add_options()("out,o", po::value<std::string>()->default_value("validation"), "output folder (database, traces)")(
      "markdown", po::value<std::string>(), "also write the table to this markdown file");
  po::variables_map vm;
  if (!parse_command_options("validate", args, desc, nullptr, vm, out)) return 0;
  const ResolvedConfig config = config_from_options(vm);
  const std::string dir = vm["out"].as<std::string>();
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) throw InputError(dir, "cannot create the validation folder: " + ec.message());
  Validator v(dir, vm.count("config") ? vm["config"].as<std::vector<std::string>>() : std::vector<std::string>{},
              vm.count("set") ? vm["set"].as<std::vector<std::string>>() : std::vector<std::string>{});
  std::vector<AnchorRow> rows;
  bjorge(v, rows);
  burns_hunt(v, rows);
  hsr(v, rows);
  onchip_cliff(v, rows);
  rooflines(v, rows, config.hw);
  fill_and_bandwidth_rooflines(v, rows, config.hw);
  olsson(v, rows);
  dram_memspecs(v, rows, config.hw);
  const std::string md = markdown(rows, config.params.config_name);
  out << md;
  if (vm.count("markdown")) {
    const std::string path = vm["markdown"].as<std::string>();
    std::ofstream f(path);
    if (!(f << md)) throw InputError(path, "cannot write the markdown table");
  }
  const auto failed = std::count_if(rows.begin(), rows.end(), [](const AnchorRow& r) { return !r.holds; });
  out << "\n" << rows.size() - static_cast<std::size_t>(failed) << " of " << rows.size() << " anchors hold; runs in " << v.db() << "\n";
  (void)err;
  return 0;
}

}  // namespace tbdr
