// `tbdrsim validate`: the simulator against published figures. Runs small, fixed setups (every run
// stored in a results database) and prints, for each published anchor, the published figure, the
// simulator's, the setup and whether it holds: exactly where the anchor is arithmetic (bytes a
// frame must move), in shape where it is a measurement of other hardware. `--markdown FILE` writes
// the same table (docs/validation.md is that file; a test keeps the two equal).
#include <algorithm>
#include <cmath>
#include <cstdint>
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
#include "app/run_stats.hpp"
#include "models/command_processor.hpp"
#include "models/dram.hpp"
#include "models/memory_system.hpp"
#include "models/dram_memspec.hpp"
#include "models/dram_microbench.hpp"
#include "kernel/errors.hpp"
#include "kernel/output_file.hpp"
#include "scene/camera.hpp"
#include "trace/trace.hpp"

namespace tbdr {

namespace po = boost::program_options;
namespace fs = std::filesystem;

namespace {

/// Where a row's expected side comes from.
enum class Basis {
  Independent,      ///< a published measurement, or another project's tool run on the same input
  SelfConsistency,  ///< arithmetic on the simulator's own parameters, counters or re-implementations
};

/// One published figure beside the simulator's.
struct AnchorRow {
  std::string anchor;     ///< the publication and what it measured
  std::string published;  ///< its figure
  std::string simulated;  ///< ours
  std::string setup;      ///< what ran
  std::string kind;       ///< exact | shape
  bool holds = false;
  Basis basis = Basis::SelfConsistency;
  std::string expected_from = {};  ///< where the expected side comes from, said plainly
};

/// Labels rows [first, rows.size()) with their basis and the origin of their expected side.
void label_rows(std::vector<AnchorRow>& rows, std::size_t first, Basis basis, const std::string& expected_from) {
  for (std::size_t i = first; i < rows.size(); ++i) {
    rows[i].basis = basis;
    rows[i].expected_from = expected_from;
  }
}

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
  for (const auto& s : r.stats) {
    if (s.scope == scope && s.name == name) return s.value;
  }
  return 0.0;
}

/// A statistic of a run named by its declaration (kernel/stats.hpp stat_name).
template <StatSet S, class M>
double stat(const RunOutcome& r, const std::string& scope, M S::*member) {
  return stat(r, scope, stat_name(member));
}

/// A cycle of command `command`'s span ("pass1.consume": its "<command>/timing" statistics).
double command_cycle(const RunOutcome& r, const std::string& command, Accumulator CommandTimingStats::*member) {
  return stat(r, command + CommandTimingStats::kScopeSuffix, member);
}

/// Framebuffer traffic the units requested: colour, G-buffer and depth/stencil, read and written.
double framebuffer_bytes(const RunOutcome& r) {
  double sum = 0;
  for (const char* c : {"frame/dram.color", "frame/dram.gbuffer", "frame/dram.depth_stencil"})
    sum += stat(r, c, &TrafficStats::read_bytes) + stat(r, c, &TrafficStats::write_bytes);
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

/// Bytes of the framebuffer classes (colour, G-buffer, depth/stencil) that reached DRAM in a run.
double framebuffer_device_bytes(const RunOutcome& r) {
  const DramTraffic& d = r.timing.dram;
  double b = 0;
  for (DramClass c : {DramClass::Color, DramClass::Gbuffer, DramClass::DepthStencil}) {
    b += static_cast<double>(d.reads(c) + d.writes(c));
  }
  return b;
}

/// Bjørge's MRT-vs-PLS comparison on the techniques users run: the study's deferred and
/// deferred_tile_store at 1080p (atrium:3, 256 lights, the study's default view), the framebuffer
/// classes (colour, G-buffer, depth/stencil) reconciled with Bjørge's passes line by line, in bytes
/// requested by the units and bytes that reached DRAM. Returns the markdown table; adds one row.
std::string bjorge_on_study(Validator& v, std::vector<AnchorRow>& rows) {
  const std::vector<std::string> common = {"--scene", "atrium:3", "--lights", "256", "--resolution", "1920x1080"};
  auto args = [&](const char* technique) {
    std::vector<std::string> a = {"--technique", technique};
    a.insert(a.end(), common.begin(), common.end());
    return a;
  };
  const RunOutcome mrt = v.run(v.generate("study_deferred_1080p", args("deferred")));
  const RunOutcome pls = v.run(v.generate("study_deferred_tile_store_1080p", args("deferred_tile_store")));
  // One line of the reconciliation: Bjørge's MiB, then requested and device MiB of the study's
  // deferred (`mrt`), from the classes' reads or writes.
  struct Line {
    std::string what;
    std::string bjorge;
    double requested = 0, device = 0;
    std::string why;
  };
  const auto mib = [](std::uint64_t bytes) { return static_cast<double>(bytes) / kMiB; };
  const DramTraffic& rq = mrt.frame.dram;
  const DramTraffic& dv = mrt.timing.dram;
  const std::vector<Line> lines = {
      {"G-buffer fill: albedo + normal + depth written", "23.73",
       mib(rq.writes(DramClass::Gbuffer) + rq.writes(DramClass::DepthStencil)),
       mib(dv.writes(DramClass::Gbuffer) + dv.writes(DramClass::DepthStencil)),
       "the same three 32-bit surfaces (rgba8 albedo, rgb10a2 normal, D24S8)"},
      {"depth reloaded for the light volumes' depth test", "0", mib(rq.reads(DramClass::DepthStencil)),
       mib(dv.reads(DramClass::DepthStencil)),
       "the lighting pass loads depth to test the volumes; Bjørge's light accumulation reads no depth"},
      {"G-buffer read by the lighting", "15.82", mib(rq.reads(DramClass::Gbuffer)), mib(dv.reads(DramClass::Gbuffer)),
       "Bjørge reads each G-buffer texel once; here every light-volume fragment reads albedo and normal (overlapping "
       "volumes re-read them: requested) while the texture cache and SLC serve the re-reads (device: about one "
       "read of the pixels some volume covers)"},
      {"light accumulation written, then read by the resolve", "7.91 + 15.82", 0.0, 0.0,
       "none on a tile-based GPU: the volumes blend into the colour attachment in the tile buffer, so there is "
       "no accumulation target and no resolve pass"},
      {"colour written", "7.91", mib(rq.writes(DramClass::Color)), mib(dv.writes(DramClass::Color)), "the lit frame"},
      {"colour read", "0", mib(rq.reads(DramClass::Color)), mib(dv.reads(DramClass::Color)), "cleared, never loaded"},
  };
  double total_rq = 0, total_dv = 0;
  for (const auto& l : lines) {
    total_rq += l.requested;
    total_dv += l.device;
  }
  const double pls_rq = framebuffer_bytes(pls) / kMiB;
  const double pls_dv = framebuffer_device_bytes(pls) / kMiB;
  std::ostringstream md;
  md << "\n## Bjørge on the study's techniques\n\n"
     << "The study's `deferred` and `deferred_tile_store` at 1920x1080 (atrium:3, 256 lights, the default view), "
        "framebuffer classes only (colour, G-buffer, depth/stencil; MiB), against Bjørge's MRT passes "
        "(GPU Pro 5: 71.19 MB with multiple render targets, 7.91 MB with pixel local storage; MB = MiB). "
        "*requested*: what the units asked for; *DRAM*: what reached the devices after the caches.\n\n"
     << "| traffic | Bjørge MRT | deferred requested | deferred DRAM | why they differ |\n|---|---|---|---|---|\n";
  for (const auto& l : lines) {
    md << "| " << l.what << " | " << l.bjorge << " | " << fixed(l.requested, 2) << " | " << fixed(l.device, 2) << " | "
       << l.why << " |\n";
  }
  md << "| **total** | **71.19** | **" << fixed(total_rq, 2) << "** | **" << fixed(total_dv, 2) << "** | |\n"
     << "| deferred_tile_store (G-buffer in PLS) | 7.91 | " << fixed(pls_rq, 2) << " | " << fixed(pls_dv, 2)
     << " | only the colour leaves the chip, as Bjørge's PLS path |\n"
     << "| ratio deferred / deferred_tile_store | 9.0x | " << fixed(total_rq / std::max(pls_rq, 1e-9), 1) << "x | "
     << fixed(total_dv / std::max(pls_dv, 1e-9), 1) << "x | |\n";
  const double surface = 1920.0 * 1080.0 * 4.0 / kMiB;
  rows.push_back({"Bjørge, GPU Pro 5, on the study's deferred and deferred_tile_store (framebuffer MiB, 1080p)",
                  "71.19 vs 7.91 MB (9x)",
                  fixed(total_rq, 2) + " requested / " + fixed(total_dv, 2) + " at DRAM vs " + fixed(pls_dv, 2) + " (" +
                      fixed(total_rq / std::max(pls_rq, 1e-9), 1) + "x / " + fixed(total_dv / std::max(pls_dv, 1e-9), 1) +
                      "x; reconciled line by line below)",
                  "atrium:3 1920x1080 256 lights, the study's generators and default view", "exact",
                  std::abs(pls_dv - surface) < 0.005 && std::abs(pls_rq - surface) < 0.005});
  return md.str();
}

/// Vendors' published bandwidth and power figures on G-buffers kept on chip:
/// - Arm (Mali developer guidance on on-chip G-buffers, deferred shading with pixel local storage):
///   a 4-target 1080p 32 bpp G-buffer kept on chip saves up to 4 GB/s at 60 FPS, i.e. 4 targets x
///   1920 x 1080 x 4 B written and read once = 66.4 MB a frame x 60;
/// - Martin, Bjørge et al., SIGGRAPH 2013 (deferred shading with pixel local storage): at least
///   1 GB/s saved at 720p;
/// - Arm's rule of thumb: about 100 mW per GB/s of DRAM traffic (100 pJ per byte).
void onchip_gbuffer_savings(Validator& v, std::vector<AnchorRow>& rows) {
  constexpr double kFps = 60.0;  // both vendors' figures are per second at 60 frames per second
  const std::vector<std::string> fits = {"pls.tile_buffer_bits_per_pixel=256"};  // 5 x 32 bits on chip
  auto deferred = [&](const std::string& name, const std::string& storage) {
    return v.run(v.generate(name, {"--technique", "deferred", "--scene", "atrium:3", "--lights", "256", "--resolution",
                                   "1920x1080", "--option", "gbuffer=rgba8,rgba8,rgba8,rgba8", "--option",
                                   "gbuffer_storage=" + storage}),
                 fits);
  };
  const RunOutcome mem = deferred("arm_gbuffer4_memory", "memory");
  const RunOutcome chip = deferred("arm_gbuffer4_onchip", "onchip");
  const double written = static_cast<double>(mem.timing.dram.writes(DramClass::Gbuffer));
  const double read = static_cast<double>(mem.timing.dram.reads(DramClass::Gbuffer));
  const double chip_g = static_cast<double>(chip.timing.dram.writes(DramClass::Gbuffer) + chip.timing.dram.reads(DramClass::Gbuffer));
  const double saved_gbps = (written + read - chip_g) * kFps / 1e9;
  const double full = 4.0 * 1920.0 * 1080.0 * 4.0;  // bytes of the 4 targets
  rows.push_back({"Arm, on-chip G-buffers: a 4-target 1080p 32 bpp G-buffer kept on chip saves up to 4 GB/s at 60 FPS",
                  "up to 3.98 GB/s (4 x 1920 x 1080 x 4 B written and read once, x 60)",
                  fixed(saved_gbps, 2) + " GB/s (written " + fixed(written * kFps / 1e9, 2) + ", read " +
                      fixed(read * kFps / 1e9, 2) + " at DRAM: reads of pixels no light volume covers are not made)",
                  "deferred gbuffer=4 x rgba8, memory vs onchip, atrium:3 1920x1080 256 lights, 256 bits on chip; "
                  "G-buffer bytes at DRAM x 60; holds when the write side is exactly the 4 targets and the total at "
                  "most the published 3.98 GB/s",
                  "exact", written == full && chip_g == 0 && saved_gbps <= 2.0 * full * kFps / 1e9 + 1e-9});
  // Martin et al.: the study's deferred vs deferred_tile_store at 720p, framebuffer bytes at DRAM.
  auto at720 = [&](const char* technique) {
    return v.run(v.generate(std::string("martin_") + technique, {"--technique", technique, "--scene", "atrium:3",
                                                                 "--lights", "256", "--resolution", "1280x720"}));
  };
  const double martin_gbps = (framebuffer_device_bytes(at720("deferred")) -
                              framebuffer_device_bytes(at720("deferred_tile_store"))) * kFps / 1e9;
  rows.push_back({"Martin, Bjørge et al., SIGGRAPH 2013: deferred shading with the G-buffer in pixel local storage "
                  "saves at least 1 GB/s at 720p",
                  "at least 1 GB/s", fixed(martin_gbps, 2) + " GB/s",
                  "deferred vs deferred_tile_store, atrium:3 1280x720 256 lights: framebuffer bytes (colour, G-buffer, "
                  "depth) at DRAM x 60",
                  "shape", martin_gbps >= 1.0});
  // Arm's rule of thumb: DRAM power per GB/s = DRAM energy per byte (1 pJ/B = 1 mW per GB/s).
  const double dram_bytes = static_cast<double>(mem.timing.dram.total_read() + mem.timing.dram.total_written());
  const double mw_per_gbps = stat(mem, "mem/dram", &DramStats::energy_pj) / std::max(1.0, dram_bytes);
  rows.push_back({"Arm rule of thumb: about 100 mW per GB/s of DRAM traffic",
                  "about 100 mW per GB/s",
                  fixed(mw_per_gbps, 0) + " mW per GB/s (" + fixed(mw_per_gbps / 8.0, 1) + " pJ/bit)",
                  "the 4-target deferred frame above on the configured DRAM: DRAM energy (dynamic, background, "
                  "refresh) / bytes at DRAM; holds within 67 .. 150 (\"about\": the rule gives no precision, so a "
                  "factor of 1.5 either way is assumed)",
                  "shape", mw_per_gbps >= 67.0 && mw_per_gbps <= 150.0});
}

void burns_hunt(Validator& v, std::vector<AnchorRow>& rows) {
  const RunOutcome r = v.run(v.generate("visibility_8x", {"--technique", "visibility_buffer", "--scene", "atrium:1",
                                                          "--lights", "16", "--resolution", "480x270", "--samples", "8"}));
  const double per_sample = stat(r, "frame/dram.visibility", &TrafficStats::write_bytes) / (480.0 * 270.0 * 8.0);
  const double at_1080p = per_sample * 1920.0 * 1080.0 * 8.0 / kMiB;
  rows.push_back({"Burns & Hunt, JCGT 2013: visibility buffer bytes per sample", "4 B", fixed(per_sample, 2) + " B",
                  "visibility_buffer, atrium:1 480x270 8x MSAA: visibility bytes stored / samples", "exact",
                  std::abs(per_sample - 4.0) < 1e-9});
  rows.push_back({"Burns & Hunt, JCGT 2013: 1080p 8x MSAA visibility buffer", "about 64 MB", fixed(at_1080p, 1) + " MiB",
                  "the bytes per sample above x 1920 x 1080 x 8", "exact",
                  std::abs(at_1080p - 4.0 * 1920.0 * 1080.0 * 8.0 / kMiB) < 1e-9});
}

/// Fragments coloured per pixel of one plain_forward view on an IMR without early-Z, on TBDR (with
/// the punch-through and blended samples it shaded, which HSR cannot remove) and on TBR.
struct HsrView {
  std::string camera, scene;
  double imr = 0, tbdr = 0, tbr = 0, raster = 0, tbdr_layers = 0;
};

HsrView hsr_view(Validator& v, const std::string& scene, const std::string& camera) {
  const std::string t = v.generate("hsr_" + camera + "_" + scene.substr(scene.find(':') + 1),
                                   {"--technique", "plain_forward", "--scene", scene, "--camera", camera, "--lights",
                                    "16", "--resolution", "480x270"});
  const RunOutcome tbdr = v.run(t, {"gpu.mode=tbdr"});
  const RunOutcome tbr = v.run(t, {"gpu.mode=tbr"});
  // An immediate-mode GPU without early-Z (isp.early_z=0): every rasterised fragment is shaded.
  const RunOutcome imr_late = v.run(t, {"gpu.mode=imr", "isp.early_z=0"});
  const double px = 480.0 * 270.0;
  HsrView h{camera, scene};
  h.raster = tbdr.frame.totals.render.isp.samples_rasterised.as_double() / px;
  h.imr = imr_late.frame.totals.render.tsp.shader_invocations.as_double() / px;
  h.tbdr = tbdr.frame.totals.render.tsp.shader_invocations.as_double() / px;
  h.tbr = tbr.frame.totals.render.tsp.shader_invocations.as_double() / px;
  h.tbdr_layers = (tbdr.frame.totals.render.isp.punch_through_samples.as_double() + tbdr.frame.totals.render.isp.translucent_samples.as_double()) / px;
  return h;
}

/// Imagination's HSR figure (PowerVR Architecture Guide, "Hidden Surface Removal Efficiency": a
/// Shadowgun frame, 4.7 fragments coloured per pixel without early-Z or HSR, 1.2 with PowerVR's
/// HSR, the remainder blended UI), on two atrium views: the one whose depth complexity (fragments
/// per pixel without early-Z) is closest to 4.7 among all the atrium's views, and the study's own
/// view. Only a shape is comparable (another frame of another game): the row holds when the order
/// is IMR > TBR > TBDR and TBDR colours at most 1.2 fragments per pixel beyond the punch-through
/// and blended samples it must shade (alpha-tested and blended geometry is shaded before, or
/// despite, what hides it; Shadowgun's remainder above 1 is its blended UI).
void hsr(Validator& v, std::vector<AnchorRow>& rows) {
  std::vector<HsrView> views;
  for (const auto& c : atrium_viewpoint_names()) views.push_back(hsr_view(v, "atrium:4", c));
  const auto closest = std::min_element(views.begin(), views.end(), [](const HsrView& a, const HsrView& b) {
    return std::abs(a.imr - 4.7) < std::abs(b.imr - 4.7);
  });
  std::string measured;
  for (const auto& h : views) measured += (measured.empty() ? "" : ", ") + h.camera + " " + fixed(h.imr, 2);
  const HsrView study = hsr_view(v, "atrium:3", "entrance");
  const HsrView* chosen_view = &*closest;
  for (const HsrView* h : {chosen_view, &study}) {
    const bool chosen = h == chosen_view;
    rows.push_back({std::string("Imagination, PowerVR Architecture Guide: fragments coloured per pixel without "
                                "early-Z/HSR -> with PowerVR HSR (Shadowgun frame), ") +
                        (chosen ? "on the atrium view closest to its depth complexity" : "on the study's own view"),
                    "4.7 -> 1.2 (3.9x)",
                    fixed(h->imr, 2) + " -> " + fixed(h->tbdr, 2) + " (" + fixed(h->imr / h->tbdr, 2) +
                        "x; punch-through and blended samples shaded on TBDR " + fixed(h->tbdr_layers, 2) +
                        " per pixel); TBR early-Z " + fixed(h->tbr, 2),
                    "plain_forward, " + h->scene + " " + h->camera + " view, 480x270" +
                        (chosen ? " (depth complexity without early-Z measured on every view: " + measured +
                                      "; the closest to 4.7 taken)"
                                : "") +
                        "; holds when IMR > TBR > TBDR and TBDR - its punch-through and blended samples <= 1.2",
                    "shape",
                    h->tbr > h->tbdr && h->imr > h->tbr && h->tbdr - h->tbdr_layers <= 1.2 &&
                        std::abs(h->imr - h->raster) < 1e-9});
  }
}

/// Imagination's GX6250 on-chip memory measurements (PowerVR Performance Recommendations, "On-Chip
/// Memory Performance"): ms per frame at 96, 128, .. 288 bits per pixel on chip, 256 of them fit.
constexpr double kGx6250Ms[] = {20, 21, 23, 24, 28, 29, 39};

/// The cliff: pls.tile_buffer_bytes_per_clock is fitted (bench/onchip_cliff_fit.py) to the flat
/// part of the GX6250 table alone (96 .. 256 bits); the step past the budget (256 -> 288 bits) is a
/// prediction, compared with the published step. Only the shape is comparable (another scene and
/// resolution than the SDK example's): the model's times are scaled by the one factor that fits
/// the flat part best in least squares. The step holds when it lies inside the interval the
/// published figures' rounding to whole milliseconds allows: (39 -+ 0.5) / (29 +- 0.5) - 1 =
/// +30.5 .. +38.6 %.
void onchip_cliff(Validator& v, std::vector<AnchorRow>& rows) {
  std::vector<double> ms;
  for (int k = 2; k <= 8; ++k) {
    std::string layout;
    for (int i = 0; i < std::min(k, 7); ++i) layout += (i ? "," : "") + std::string("rgba8");
    if (k == 8) layout = "rgba8,rgba8,rgba8,rgba8,rgba8,rgba8,rgba16f";
    const std::string t = v.generate("cliff_" + std::to_string(32 * (k + 1)),
                                     {"--technique", "deferred", "--scene", "atrium:2", "--lights", "64", "--resolution",
                                      "480x270", "--option", "gbuffer=" + layout, "--option", "gbuffer_storage=onchip"});
    ms.push_back(stat(v.run(t, {"usc.count=2", "texture.units=1", "pls.tile_buffer_bits_per_pixel=256"}), FrameTimingStats::kScope,
                      &FrameTimingStats::frame_time_ms));
  }
  constexpr std::size_t kFlat = 6;  // 96 .. 256 bits
  double tp = 0, tt = 0;
  for (std::size_t i = 0; i < kFlat; ++i) {
    tp += ms[i] * kGx6250Ms[i];
    tt += ms[i] * ms[i];
  }
  const double scale = tt > 0 ? tp / tt : 0.0;
  double sq = 0;
  for (std::size_t i = 0; i < kFlat; ++i) sq += (scale * ms[i] - kGx6250Ms[i]) * (scale * ms[i] - kGx6250Ms[i]);
  const double rms = std::sqrt(sq / static_cast<double>(kFlat));
  const double slope = ms[kFlat - 1] / ms[0] - 1.0, slope_pub = kGx6250Ms[kFlat - 1] / kGx6250Ms[0] - 1.0;
  const double step = ms[kFlat] / ms[kFlat - 1] - 1.0, step_pub = kGx6250Ms[kFlat] / kGx6250Ms[kFlat - 1] - 1.0;
  const double step_low = (kGx6250Ms[kFlat] - 0.5) / (kGx6250Ms[kFlat - 1] + 0.5) - 1.0;
  const double step_high = (kGx6250Ms[kFlat] + 0.5) / (kGx6250Ms[kFlat - 1] - 0.5) - 1.0;
  std::string scaled;
  for (std::size_t i = 0; i < ms.size(); ++i) scaled += (i ? ", " : "") + fixed(scale * ms[i], 1);
  rows.push_back({"Imagination, PowerVR Performance Recommendations, On-Chip Memory Performance: GX6250 ms per frame, "
                  "96 .. 288 bits per pixel on chip (256 fit); pls.tile_buffer_bytes_per_clock fitted to 96 .. 256 only, "
                  "the step past the budget predicted",
                  "20, 21, 23, 24, 28, 29, 39: flat part +" + fixed(100 * slope_pub, 0) + " %, step +" +
                      fixed(100 * step_pub, 1) + " % (+" + fixed(100 * step_low, 1) + " .. +" + fixed(100 * step_high, 1) +
                      " % within rounding)",
                  scaled + " (model ms x " + fixed(scale, 1) + ", flat part rms " + fixed(rms, 2) + " ms): flat part " +
                      (slope >= 0 ? "+" : "") + fixed(100 * slope, 0) + " %, predicted step " + (step >= 0 ? "+" : "") +
                      fixed(100 * step, 1) + " % (error " + (step >= step_pub ? "+" : "") +
                      fixed(100 * (step - step_pub), 1) + " points)",
                  "deferred gbuffer_storage=onchip, atrium:2 480x270 64 lights, 2 USCs, 1 texture unit, 256 bits on "
                  "chip, pls.over_budget as configured (split_render: the G-buffer stored and read back as images)",
                  "shape", step >= step_low && step <= step_high && rms < 1.0});
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
    const double bound = (r.frame.totals.render.tsp.fragment_alu_ops.as_double() + r.frame.totals.render.geometry.vertex_alu_ops.as_double()) / rate;
    const double cycles = r.timing.frame_cycles;
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
    const double bound = r.frame.totals.render.tsp.texels_filtered.as_double() / rate;
    const double cycles = r.timing.frame_cycles;
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
    const double bound = r.frame.totals.render.isp.samples_rasterised.as_double() / rate;
    const double cycles = r.timing.frame_cycles;
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
    const double bytes = stat(r, "mem/dram", &DramStats::write_bytes) + stat(r, "mem/dram", &DramStats::read_bytes);
    const auto& d = hw.dram;
    const double cycles_per_ns = hw.gpu.core_clock_mhz * 1e-3;
    const double peak_bytes_per_cycle = d.peak_bandwidth_gbps() / cycles_per_ns;
    const double opened = stat(r, "mem/dram", &DramStats::row_misses), refreshes = stat(r, "mem/dram", &DramStats::refreshes);
    const double bound = bytes / peak_bytes_per_cycle +
                         (opened * (d.t_wr_ns + d.t_rp_ns + d.t_rcd_ns) + refreshes * d.t_rfc_ns) * cycles_per_ns /
                             static_cast<double>(d.channels);
    const double cycles = r.timing.frame_cycles;
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
    const double lines = stat(r, "mem/client.texture", &MemoryClientStats::completed);
    const double latency_ns = stat(r, "mem/client.texture", &MemoryClientStats::avg_latency_ns);
    const double bound = lines * latency_ns * hw.gpu.core_clock_mhz * 1e-3;
    // The reading pass's fragment work starts when it is binned and the producing pass is done
    // (its start_cycle is its binning's, which overlaps the producer).
    const double cycles = command_cycle(r, "pass1.consume", &CommandTimingStats::end_cycle) -
                          std::max(command_cycle(r, "pass1.consume", &CommandTimingStats::binning_end_cycle), command_cycle(r, "pass0.produce", &CommandTimingStats::end_cycle));
    rows.push_back(roofline("Roofline: a latency-bound pass (Little's law)", bound, fixed(bound, 0) + " cycles (lines read / 1 in flight x mean latency " + fixed(latency_ns, 1) + " ns)", cycles, "a fullscreen pass reading a stored 480x270 rgba8 image at every pixel, usc.count=1, "
                    "usc.tasks_in_flight=1: " + fixed(lines, 0) + " lines", 0.99));
  }
}

/// Milliseconds between the start and end cycles of the dispatches of `kernel` in a run
/// (dispatch<i>.<kernel>/timing), at the configured core clock.
double dispatch_ms(const RunOutcome& r, const std::string& kernel, double core_clock_mhz) {
  double start = 0, end = 0;
  const std::string suffix = "." + kernel + CommandTimingStats::kScopeSuffix;
  for (const auto& st : r.stats) {
    if (st.scope.rfind("dispatch", 0) != 0 || st.scope.size() < suffix.size() ||
        st.scope.compare(st.scope.size() - suffix.size(), suffix.size(), suffix) != 0) {
      continue;
    }
    if (st.name == stat_name(&CommandTimingStats::start_cycle)) start -= st.value;
    if (st.name == stat_name(&CommandTimingStats::end_cycle)) end += st.value;
  }
  return (end + start) / (core_clock_mhz * 1e3);
}

/// Olsson, Billeter & Assarsson, "Clustered Deferred and Forward Shading" (HPG 2012): about 2,400
/// lights, clustered deferred shading 5.6 ms against tiled deferred's 17.7 ms (3.2x), with 2.3 ms
/// of clustering and 1.5 ms of light assignment against tiled's 1.0 ms; 32x32-pixel screen tiles
/// for both. Here in the same units: the shading dispatches' time of clustered_deferred and
/// tiled_deferred at 2,400 lights and 32-pixel tiles, and the lights each evaluates per pixel.
/// Another GPU and scene: the row holds on the direction (clustered shades faster, evaluating fewer
/// lights) and states the ratio against Olsson's; the ratio itself is not a criterion.
void olsson(Validator& v, std::vector<AnchorRow>& rows, const HwConfig& hw) {
  const char* names[2] = {"tiled_deferred", "clustered_deferred"};
  RunOutcome r[2];
  for (int i = 0; i < 2; ++i) {
    r[i] = v.run(v.generate(std::string("olsson_") + names[i], {"--technique", names[i], "--scene", "atrium:3", "--lights",
                                                                "2400", "--resolution", "480x270", "--option",
                                                                "tile_px=32"}));
  }
  const double mhz = hw.gpu.core_clock_mhz;
  const double tiled_ms = dispatch_ms(r[0], "tiled_deferred_shade", mhz);
  const double clustered_ms = dispatch_ms(r[1], "deferred_shade", mhz);
  const double clustering_ms = dispatch_ms(r[1], "cluster_flag", mhz) + dispatch_ms(r[1], "cluster_light_assign", mhz);
  const double px = 480.0 * 270.0;
  const double lights_tiled = r[0].frame.totals.compute.compute_light_evaluations.as_double() / px;
  const double lights_clustered = r[1].frame.totals.compute.compute_light_evaluations.as_double() / px;
  rows.push_back({"Olsson, Billeter & Assarsson, HPG 2012: clustered deferred shading time against tiled deferred's",
                  "5.6 vs 17.7 ms of shading (3.2x) + 3.8 vs 1.0 ms of clustering and assignment (about 2,400 lights)",
                  fixed(clustered_ms, 3) + " vs " + fixed(tiled_ms, 3) + " ms of shading (" +
                      fixed(tiled_ms / std::max(clustered_ms, 1e-12), 2) + "x) + " + fixed(clustering_ms, 3) +
                      " ms of clustering and assignment (tiled's culling is inside its shading dispatch); " +
                      fixed(lights_clustered, 1) + " vs " + fixed(lights_tiled, 1) + " lights per pixel",
                  "clustered_deferred (16 depth slices) vs tiled_deferred, 32-pixel tiles, atrium:3 480x270, 2,400 "
                  "lights; holds on the direction only (another GPU and scene)",
                  "shape", clustered_ms < tiled_ms && lights_clustered < lights_tiled});
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
  const RunOutcome r = v.run(v.generate("frame_forward_plus", {"--technique", "forward_plus", "--scene", "atrium:3",
                                                               "--lights", "1024", "--resolution", "480x270", "--option",
                                                               "tile_px=16"}));
  const double bits = 8.0 * (stat(r, "mem/dram", &DramStats::read_bytes) + stat(r, "mem/dram", &DramStats::write_bytes));
  const double pj_per_bit = stat(r, "mem/dram", &DramStats::energy_pj) / std::max(1.0, bits);
  rows.push_back({"The memspec's range on a frame (" + frame_dram + ")",
                  fixed(frame_low, 1) + " .. " + fixed(frame_high, 1) + " pJ/bit (streaming .. random above)",
                  fixed(pj_per_bit, 1) + " pJ/bit, row hits " + fixed(100.0 * stat(r, "mem/dram", &DramStats::row_hit_rate), 1) + " %",
                  "forward_plus, 16-pixel tiles, atrium:3 480x270, 1024 lights: DRAM energy (dynamic, standby, refresh) / bits transferred", "shape",
                  pj_per_bit >= frame_low && pj_per_bit <= frame_high});
}

/// Where a cross-check's tbdrsim side comes from.
enum class CrossCheckSide : std::uint8_t {
  Stored,  ///< a frame's DRAM stream: stored by the bench script at kCrossCheckCommit (re-run there)
  Stream,  ///< recomputed here: `tbdrsim dram-bench --pattern stream --lines 65536` on `configs`
  Random,  ///< recomputed here: `tbdrsim dram-bench --pattern random --lines 16384` on `configs`
};
/// Which figure of a microbenchmark a live row reads.
enum class CrossCheckFigure : std::uint8_t { Bandwidth, ReadLatency, RowHitsPerBurst, CoreEnergy };

/// One figure of the DRAM model beside another project's tool run on the same request or command
/// stream, as bench/dram_vs_dramsim3.sh and bench/dram_vs_drampower.sh measured it
/// (docs/dram-cross-check.md). The tool's side is stored (the project does not build the tools);
/// the simulator's side of a microbenchmark is recomputed by every `validate` run on the same
/// configs/crosscheck/ files the scripts use, so a change of the DRAM model shows here at once; a
/// frame's is stored (a 1080p frame per row), re-checked by the scripts.
struct CrossCheck {
  const char* tool;       ///< the tool and the commit built
  const char* figure;     ///< what was compared, on which DRAM and stream
  double reference = 0;   ///< the tool's figure
  double tbdrsim = 0;     ///< the simulator's, as stored at kCrossCheckCommit
  const char* unit;
  double tolerance = 0;   ///< the relative difference that holds (the issue's 10 % timing, 5 % energy)
  CrossCheckSide side = CrossCheckSide::Stored;
  CrossCheckFigure what = CrossCheckFigure::Bandwidth;  ///< (live rows)
  const char* configs = "";  ///< (live rows) the configs/crosscheck/ files, space-separated
};
constexpr const char* kDramsim3 = "DRAMsim3 29817593b3389f1337235d63cac515024ab8fd6e";
constexpr const char* kDrampower4 = "DRAMPower 4.1 1ddc48a3 (LPDDR3)";
constexpr const char* kDrampower5 = "DRAMPower 5.1 5ed2d6e95e10c64ea83e9505c85d1828aeaf49ec (LPDDR4)";
/// The tbdrsim commit whose exports and figures the stored sides are (the bench scripts re-run there
/// gave the figures of 4ef31f0 unchanged).
constexpr const char* kCrossCheckCommit = "bef449b";
constexpr const char* kLpddr3Timing = "configs/crosscheck/lpddr3_1600.ini configs/crosscheck/lpddr3_1600_dramsim3_timing.ini";
constexpr const char* kLpddr3 = "configs/crosscheck/lpddr3_1600.ini";
constexpr const char* kLpddr4 = "configs/crosscheck/lpddr4_3200_x16.ini";
using enum CrossCheckSide;
using enum CrossCheckFigure;
constexpr CrossCheck kDramCrossChecks[] = {
    {kDramsim3, "LPDDR3-1600 2x32, 65536-line read stream: bandwidth", 11.94, 11.94, "GB/s", 0.10, Stream, Bandwidth, kLpddr3Timing},
    {kDramsim3, "LPDDR3-1600 2x32, 16384 random 64 B lines: bandwidth", 9.321, 9.298, "GB/s", 0.10, Random, Bandwidth, kLpddr3Timing},
    {kDramsim3, "LPDDR3-1600 2x32, random lines: mean read latency (queue depths matched)", 470.2, 462.9, "ns", 0.10, Random,
     ReadLatency, kLpddr3Timing},
    {kDramsim3, "LPDDR3-1600 2x32, read stream: row hits per burst", 0.9903, 0.9901, "", 0.10, Stream, RowHitsPerBurst,
     kLpddr3Timing},
    {kDramsim3, "LPDDR3-1600 2x32, deferred 1080p frame's DRAM stream: bandwidth", 8.956, 8.969, "GB/s", 0.10},
    {kDramsim3, "LPDDR3-1600 2x32, deferred 1080p frame: refresh share of time", 0.0538, 0.0538, "", 0.10},
    // Not within 10 %: replayed through a front end that keeps reads and writes apart
    // (bench/dramsim3_replay.cpp) with DRAMsim3's queue at tbdrsim's depth (64 transactions = 32
    // lines); dramsim3main's in-order front end gives 390 ns (237 at queue 32). What is left is how
    // the channel shares its time between reads and writes (docs/dram-cross-check.md, "Frames").
    {kDramsim3, "LPDDR3-1600 2x32, deferred 1080p frame: mean read latency (split front end, queue 64)", 462.5, 530.8, "ns",
     0.10},
    {kDramsim3, "LPDDR4-3200 2x16, 16384 random 64 B lines: bandwidth", 11.26, 11.11, "GB/s", 0.10, Random, Bandwidth, kLpddr4},
    {kDramsim3, "LPDDR4-3200 2x16, forward_plus 1080p frame's DRAM stream: bandwidth", 10.64, 10.69, "GB/s", 0.10},
    {kDrampower4, "LPDDR3-1600 2x32, deferred 1080p frame's commands: core energy", 5.6528e9, 5.6536e9, "pJ", 0.05},
    {kDrampower4, "LPDDR3-1600 2x32, random lines' commands: core energy", 1.2558e8, 1.2919e8, "pJ", 0.05, Random, CoreEnergy,
     kLpddr3},
    {kDrampower5, "LPDDR4-3200 2x16, deferred 1080p frame's commands: core energy", 4.5025e9, 4.545e9, "pJ", 0.05},
    {kDrampower5, "LPDDR4-3200 2x16, read stream's commands: core energy", 2.1017e8, 2.1199e8, "pJ", 0.05, Stream, CoreEnergy,
     kLpddr4},
};

/// A live cross-check row's tbdrsim side: the microbenchmark run here on the row's configs.
double live_cross_check(const CrossCheck& c) {
  std::vector<std::string> files;
  std::istringstream names(c.configs);
  for (std::string f; names >> f;) files.push_back(find_data_file(f, DataFolder::Configs));
  const HwConfig hw = resolve_config(files, {}).hw;
  const bool stream = c.side == CrossCheckSide::Stream;
  const DramBenchResult r = run_dram_microbench(hw, stream ? DramPattern::Stream : DramPattern::Random, stream ? 65536 : 16384);
  switch (c.what) {
    case CrossCheckFigure::Bandwidth: return r.stats.achieved_bandwidth_gbps.value();
    case CrossCheckFigure::ReadLatency: return r.stats.avg_read_latency_ns.value();
    case CrossCheckFigure::RowHitsPerBurst: return row_hits_per_burst(r.stats, hw.dram);
    case CrossCheckFigure::CoreEnergy: return r.stats.energy_pj.value() - r.stats.energy_io_pj.value();
  }
  return 0;
}

/// The cross-checks as rows: independent (another project's tool on the same stream).
void dram_cross_checks(std::vector<AnchorRow>& rows) {
  for (const auto& c : kDramCrossChecks) {
    const bool live = c.side != CrossCheckSide::Stored;
    const double tb = live ? live_cross_check(c) : c.tbdrsim;
    const double diff = tb / c.reference - 1.0;
    const auto num = [](double v) {
      std::ostringstream o;
      o << std::setprecision(4) << v;
      return o.str();
    };
    const std::string setup =
        live ? std::string("simulated now: `tbdrsim dram-bench --pattern ") + (c.side == CrossCheckSide::Stream ? "stream --lines 65536" : "random --lines 16384") +
                   "` on " + c.configs + "; the tool's side stored by bench/dram_vs_dramsim3.sh / bench/dram_vs_drampower.sh"
             : std::string("both sides stored by bench/dram_vs_dramsim3.sh / bench/dram_vs_drampower.sh at tbdrsim ") +
                   kCrossCheckCommit;
    rows.push_back({std::string(c.tool) + ": " + c.figure, num(c.reference) + (*c.unit ? " " : "") + c.unit,
                    num(tb) + (*c.unit ? " " : "") + c.unit + " (" + (diff >= 0 ? "+" : "") + fixed(100.0 * diff, 1) + " %)",
                    setup + " (power-down off: the exports carry no power-down commands); holds within " +
                        fixed(100.0 * c.tolerance, 0) + " %; docs/dram-cross-check.md explains every difference",
                    "shape", std::abs(diff) <= c.tolerance});
  }
}

/// Published figures looked for and not turned into rows, each with the reason.
const char* kNotReproduced =
    "\n## Published figures not reproduced here, and why\n\n"
    "| figure | source | why not a row |\n|---|---|---|\n"
    "| 60 % of the primitives in the parameter buffer are fully occluded; about 46 % of DRAM traffic is parameter-"
    "buffer accesses | Triangle Dropping (ACM TACO 2022), Android game traces on a TBR simulator | properties of those "
    "games' content, not of the hardware: the atrium's shares would test the scene, not the simulator "
    "(`dram_parameter_buffer_mb` / `dram_total_mb` is printed per run for whoever has such traces) |\n"
    "| 1.74x speed-up, 43 % less GPU + memory energy | Rendering Elimination (Anglada et al., HPCA 2019) | frame-to-frame "
    "reuse: the simulator runs one frame (frame sequences are issue 53) |\n"
    "| up to 99 % of framebuffer bandwidth saved on static tiles | Arm, transaction elimination | the same: needs "
    "consecutive frames |\n"
    "| HSR rejects 32 pixels per clock (iPad 2's SGX) against 2x2 per clock early-Z | Unity, \"Fast mobile shaders\" | "
    "it is the source of `isp.samples_per_clock`'s default: checking the model against it would be self-consistency |\n"
    "| DRAM 20-40 pJ/bit all in | Horowitz, ISSCC 2014 | a 45 nm desktop DDR figure; the LPDDR presets are held to "
    "their memspecs and to Arm's mobile rule of thumb above |\n"
    "| tiled and clustered shading's absolute milliseconds | Olsson, Billeter & Assarsson, HPG 2012 | a desktop GPU "
    "and another scene: only the ratio is compared |\n"
    "| TBR power and performance figures | TEAPOT (Arnau et al.) | the simulator and its traces were never released |\n";

/// "independent: X of N hold; self-consistency: Y of M hold".
std::string summary(const std::vector<AnchorRow>& rows) {
  std::size_t n[2] = {0, 0}, held[2] = {0, 0};
  for (const auto& r : rows) {
    const std::size_t k = r.basis == Basis::Independent ? 0 : 1;
    ++n[k];
    if (r.holds) ++held[k];
  }
  return "Independent rows: " + std::to_string(held[0]) + " of " + std::to_string(n[0]) +
         " hold; self-consistency rows: " + std::to_string(held[1]) + " of " + std::to_string(n[1]) + " hold.";
}

std::string markdown(const std::vector<AnchorRow>& rows, const std::string& config_name, const std::string& sections) {
  std::ostringstream md;
  md << "# Validation against published figures\n\n"
     << "Generated by `tbdrsim validate --markdown docs/validation.md` (configuration '" << config_name
     << "'); a test keeps this file equal to the command's output. *exact*: arithmetic the simulator must "
        "reproduce; *shape*: a measurement of other hardware the simulator must follow in direction and size. "
        "*independent*: the expected side is a published measurement or another project's tool run on the same "
        "input, so the row is evidence about the simulator; *self-consistency*: the expected side is arithmetic on "
        "the simulator's own parameters, counters or re-implementations, so the row checks that the model does what "
        "its own formulas say, and nothing more.\n\n"
     << "| anchor | published | simulated | setup | kind | basis | expected side from | holds |\n"
     << "|---|---|---|---|---|---|---|---|\n";
  for (const auto& r : rows) {
    md << "| " << r.anchor << " | " << r.published << " | " << r.simulated << " | " << r.setup << " | " << r.kind << " | "
       << (r.basis == Basis::Independent ? "independent" : "self-consistency") << " | " << r.expected_from << " | "
       << (r.holds ? "yes" : "**no**") << " |\n";
  }
  md << "\n" << summary(rows) << "\n" << sections;
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
  label_rows(rows, 0, Basis::Independent,
             "Bjørge, GPU Pro 5: the published MiB per pass; the trace is built to Bjørge's setup, not the study's "
             "deferred");
  std::size_t first = rows.size();
  const std::string bjorge_table = bjorge_on_study(v, rows);
  label_rows(rows, first, Basis::Independent,
             "Bjørge, GPU Pro 5: the published MiB per pass, against the study's own generators; the PLS side must "
             "match to the byte, the MRT side is reconciled line by line (table below)");
  first = rows.size();
  onchip_gbuffer_savings(v, rows);
  label_rows(rows, first, Basis::Independent,
             "Arm's and Martin, Bjørge et al.'s published savings and Arm's power rule of thumb, against the study's "
             "generators at 60 frames per second");
  first = rows.size();
  burns_hunt(v, rows);
  label_rows(rows, first, Basis::SelfConsistency,
             "the visibility_buffer generator's own id_bytes = 4 (Burns & Hunt's figure is the trace's input, not a "
             "result); the 1080p row is the first row x 1920 x 1080 x 8");
  first = rows.size();
  hsr(v, rows);
  label_rows(rows, first, Basis::Independent,
             "Imagination's measurement on a Shadowgun frame; the atrium view is chosen by its measured depth "
             "complexity, and the study's own view is shown beside it");
  first = rows.size();
  onchip_cliff(v, rows);
  label_rows(rows, first, Basis::Independent,
             "Imagination's GX6250 measurements: the first six fitted (one parameter), the seventh predicted");
  first = rows.size();
  rooflines(v, rows, config.hw);
  fill_and_bandwidth_rooflines(v, rows, config.hw);
  label_rows(rows, first, Basis::SelfConsistency,
             "the simulator's own counters divided by its own configured rates");
  first = rows.size();
  olsson(v, rows, config.hw);
  label_rows(rows, first, Basis::Independent,
             "Olsson, Billeter & Assarsson's measured shading times (compared in direction; the ratio stated)");
  first = rows.size();
  dram_cross_checks(rows);
  label_rows(rows, first, Basis::Independent,
             "DRAMsim3 and DRAMPower, built from their repositories and run on the simulator's exported request and "
             "command streams (the tools' figures stored, the bench scripts re-check them; the simulator's side of a "
             "microbenchmark recomputed by this run)");
  first = rows.size();
  dram_memspecs(v, rows, config.hw);
  label_rows(rows, first, Basis::SelfConsistency,
             "models/dram_memspec.cpp, this project's re-implementation of DRAMPower's equations on the memspecs' "
             "currents, and the configuration's own tRFC / tREFI; not DRAMPower run on the simulator's commands");
  const std::string md = markdown(rows, config.params.config_name, bjorge_table + kNotReproduced);
  out << md;
  if (vm.count("markdown")) {
    const std::string path = vm["markdown"].as<std::string>();
    write_output_file(path, "the markdown table", md);  // whole or not at all
  }
  out << "\nruns in " << v.db() << "\n";
  (void)err;
  return 0;
}

}  // namespace tbdr
