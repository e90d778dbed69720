// The capture intermediate (frame.json, docs/capture-import.md "The intermediate") as a trace
// and a GLB: passes at their own render areas, draws with their clip-space geometry (lines and
// points as the triangles that cover their pixels, every instance), pipelines, shaders with their
// captured costs, and the application's transfers as copy dispatches. Everything the trace does
// not carry is listed, never dropped silently.
#include "app/capture_convert.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <set>
#include <sstream>

#include <glm/glm.hpp>
#include <nlohmann/json.hpp>

#include "app/capture_geometry.hpp"
#include "kernel/errors.hpp"
#include "kernel/hash.hpp"
#include "kernel/text_escape.hpp"
#include "scene/gltf_loader.hpp"

namespace tbdr {

namespace fs = std::filesystem;

namespace {
using nlohmann::json;

/// The intermediate's format line (docs/capture-import.md, "The intermediate").
/// The intermediate's format lines this reader takes (docs/capture-import.md, "The intermediate"):
/// 2 adds passes at their own sizes, dynamic rendering, depth clip control, lines, points,
/// instances, transfers and per-stage shader costs to 1.
constexpr const char* kCaptureFormats[] = {"tbdrsim-capture 1", "tbdrsim-capture 2"};

/// The most vertices one imported draw may hold: the glTF loader keeps 32-bit indices, and a
/// frame's geometry is held in memory twice (JSON and GLB), so 2^24 (16.7 M, far above a real
/// frame's draw) bounds the import's memory at a few GB.
constexpr std::uint64_t kMaxDrawVertices = 1ull << 24;

/// A recorded transfer or dispatch's bytes: at most 2^34 (16 GiB), the trace's buffer limit.
constexpr std::uint64_t kMaxRecordedBytes = 1ull << 34;
/// A buffer a recorded command reads is declared `upload=yes` (its contents exist before the
/// command, however they were made), which the trace bounds at 2^28 bytes (docs/limits.md).
constexpr std::uint64_t kMaxUploadBufferBytes = 1ull << 28;
/// A transfer's threads: one 16-byte piece each (four RGBA8 texels, a 128-bit access), in
/// workgroups of 64, so that its thread count follows its bytes.
constexpr std::uint64_t kRecordedBytesPerThread = 16;
constexpr std::uint32_t kRecordedGroupSize = 64;
/// Vulkan's guaranteed limits on a dispatch (maxComputeWorkGroupCount, maxComputeWorkGroupInvocations).
constexpr std::uint64_t kMaxWorkgroupCount = 65535;
constexpr std::uint64_t kMaxWorkgroupInvocations = 1024;

/// A trace camera is required by the format but clip-space geometry never uses it (the geometry
/// unit takes _CLIP_POSITION as it is); this one is a valid, documented placeholder.
Camera placeholder_camera() {
  Camera c;
  c.eye = {0.0f, 0.0f, 1.0f};
  c.target = {0.0f, 0.0f, 0.0f};
  c.up = {0.0f, 1.0f, 0.0f};
  c.fov_y_deg = 90.0f;
  c.near_plane = 0.5f;
  c.far_plane = 2.0f;
  return c;
}

/// Vulkan formats as the trace names them (docs/trace-format.md `attachment format=`).
std::optional<Format> format_of(const std::string& vk) {
  static const std::map<std::string, Format> formats = {
      {"VK_FORMAT_R8_UNORM", Format::R8},           {"VK_FORMAT_R8G8_UNORM", Format::Rg8},
      {"VK_FORMAT_R8G8B8A8_UNORM", Format::Rgba8},  {"VK_FORMAT_R8G8B8A8_SRGB", Format::Rgba8},
      {"VK_FORMAT_B8G8R8A8_UNORM", Format::Rgba8},  {"VK_FORMAT_B8G8R8A8_SRGB", Format::Rgba8},
      {"VK_FORMAT_A8B8G8R8_UNORM_PACK32", Format::Rgba8}, {"VK_FORMAT_A8B8G8R8_SRGB_PACK32", Format::Rgba8},
      {"VK_FORMAT_A2B10G10R10_UNORM_PACK32", Format::Rgb10a2}, {"VK_FORMAT_A2R10G10B10_UNORM_PACK32", Format::Rgb10a2},
      {"VK_FORMAT_B10G11R11_UFLOAT_PACK32", Format::R11g11b10f}, {"VK_FORMAT_R16_SFLOAT", Format::R16f},
      {"VK_FORMAT_R16G16_SFLOAT", Format::Rg16f},   {"VK_FORMAT_R16G16B16A16_SFLOAT", Format::Rgba16f},
      {"VK_FORMAT_R32_SFLOAT", Format::R32f},       {"VK_FORMAT_R32G32_SFLOAT", Format::Rg32f},
      {"VK_FORMAT_R32G32B32A32_SFLOAT", Format::Rgba32f}, {"VK_FORMAT_R32_UINT", Format::R32ui},
      {"VK_FORMAT_R32G32_UINT", Format::Rg32ui},    {"VK_FORMAT_R32G32B32A32_UINT", Format::Rgba32ui},
      {"VK_FORMAT_D16_UNORM", Format::D16},         {"VK_FORMAT_X8_D24_UNORM_PACK32", Format::D24s8},
      {"VK_FORMAT_D24_UNORM_S8_UINT", Format::D24s8}, {"VK_FORMAT_D32_SFLOAT", Format::D32f},
      {"VK_FORMAT_D32_SFLOAT_S8_UINT", Format::D32fs8},
  };
  auto it = formats.find(vk);
  if (it == formats.end()) return std::nullopt;
  return it->second;
}

/// Reads the intermediate's members with errors that name the file and the element.
class Reader {
 public:
  explicit Reader(std::string file) : file_(std::move(file)) {}
  [[noreturn]] void fail(const std::string& where, const std::string& msg) const {
    throw InputError(file_, where + ": " + msg);
  }
  const json& get(const json& obj, const char* key, const std::string& where) const {
    if (!obj.is_object() || !obj.contains(key)) fail(where, std::string("missing '") + key + "'");
    return obj.at(key);
  }
  const json& array(const json& obj, const char* key, const std::string& where) const {
    const json& v = get(obj, key, where);
    if (!v.is_array()) fail(where, std::string("'") + key + "' is not an array");
    return v;
  }
  std::string str(const json& obj, const char* key, const std::string& where) const {
    const json& v = get(obj, key, where);
    if (!v.is_string()) fail(where, std::string("'") + key + "' is not a string");
    return v.get<std::string>();
  }
  bool boolean(const json& obj, const char* key, const std::string& where) const {
    const json& v = get(obj, key, where);
    if (!v.is_boolean()) fail(where, std::string("'") + key + "' is not true/false");
    return v.get<bool>();
  }
  std::uint64_t uint(const json& obj, const char* key, const std::string& where, std::uint64_t max) const {
    const json& v = get(obj, key, where);
    if (!v.is_number_unsigned() || v.get<std::uint64_t>() > max) {
      fail(where, std::string("'") + key + "' must be an integer in 0.." + std::to_string(max));
    }
    return v.get<std::uint64_t>();
  }
  float number(const json& v, const std::string& where) const {
    if (!v.is_number()) fail(where, "not a number");
    const double d = v.get<double>();
    if (!std::isfinite(d) || std::abs(d) > 3.4e38) fail(where, "not a finite float");
    return static_cast<float>(d);
  }
  const std::string& file() const { return file_; }

 private:
  std::string file_;
};

/// Appends little-endian bytes of trivially copyable values.
template <typename T>
void put(std::vector<std::uint8_t>& out, const T& v) {
  const auto* p = reinterpret_cast<const std::uint8_t*>(&v);
  out.insert(out.end(), p, p + sizeof(T));
}

/// Builds a GLB (glTF 2.0 binary container, spec section 4.4): one JSON chunk, one BIN chunk.
class GlbBuilder {
 public:
  /// Adds bytes as a buffer view (4-byte aligned) and returns its index.
  int view(const std::vector<std::uint8_t>& bytes, std::optional<int> target) {
    while (bin_.size() % 4) bin_.push_back(0);
    json v = {{"buffer", 0}, {"byteOffset", bin_.size()}, {"byteLength", bytes.size()}};
    if (target) v["target"] = *target;
    bin_.insert(bin_.end(), bytes.begin(), bytes.end());
    views_.push_back(v);
    return static_cast<int>(views_.size() - 1);
  }
  int accessor(json a) {
    accessors_.push_back(std::move(a));
    return static_cast<int>(accessors_.size() - 1);
  }
  json& doc() { return doc_; }
  std::vector<std::uint8_t> finish() {
    while (bin_.size() % 4) bin_.push_back(0);
    doc_["buffers"] = json::array({{{"byteLength", bin_.size()}}});
    doc_["bufferViews"] = views_;
    doc_["accessors"] = accessors_;
    std::string text = doc_.dump();
    while (text.size() % 4) text.push_back(' ');
    std::vector<std::uint8_t> out;
    put(out, std::uint32_t{0x46546C67});  // "glTF"
    put(out, std::uint32_t{2});
    put(out, static_cast<std::uint32_t>(12 + 8 + text.size() + 8 + bin_.size()));
    put(out, static_cast<std::uint32_t>(text.size()));
    put(out, std::uint32_t{0x4E4F534A});  // "JSON"
    out.insert(out.end(), text.begin(), text.end());
    put(out, static_cast<std::uint32_t>(bin_.size()));
    put(out, std::uint32_t{0x004E4942});  // "BIN\0"
    out.insert(out.end(), bin_.begin(), bin_.end());
    return out;
  }

 private:
  json doc_ = {{"asset", {{"version", "2.0"}, {"generator", "tbdrsim import"}}}};
  json views_ = json::array();
  json accessors_ = json::array();
  std::vector<std::uint8_t> bin_;
};

constexpr int kGlArrayBuffer = 34962;         // glTF bufferView.target for vertex attributes
constexpr int kGlElementArrayBuffer = 34963;  // ... and for indices
constexpr int kGlFloat = 5126;                // glTF accessor.componentType FLOAT
constexpr int kGlUnsignedInt = 5125;          // ... UNSIGNED_INT

std::vector<std::uint8_t> read_bytes(const fs::path& p, const std::string& what) {
  std::ifstream in(p, std::ios::binary);
  if (!in) throw InputError(p.string(), what + ": cannot open file");
  return std::vector<std::uint8_t>(std::istreambuf_iterator<char>(in), {});
}

/// The 8-byte signature every PNG file starts with (ISO/IEC 15948, PNG 5.2).
constexpr std::uint8_t kPngSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};

/// Refuses a file that is not a PNG by its signature, before anything decodes it (a text file
/// named .png was embedded as image/png): InputError naming the file, `what`, and its first bytes.
void check_png_signature(const fs::path& p, const std::string& what, const std::uint8_t* bytes, std::size_t size) {
  if (size >= sizeof kPngSignature && std::equal(kPngSignature, kPngSignature + sizeof kPngSignature, bytes)) return;
  static constexpr char kHex[] = "0123456789abcdef";
  std::string hex;
  std::string text;
  for (std::size_t i = 0; i < std::min(size, sizeof kPngSignature); ++i) {
    hex += (i ? " " : "") + std::string{kHex[bytes[i] >> 4], kHex[bytes[i] & 0xF]};
    text += static_cast<char>(bytes[i]);
  }
  std::string quoted = escape_for_message(text);
  for (std::size_t at = quoted.find('\n'); at != std::string::npos; at = quoted.find('\n', at)) quoted.replace(at, 1, "\\x0a");
  throw InputError(p.string(), what + ": not a PNG file: " +
                                   (size == 0 ? std::string("it is empty")
                                              : "it starts with " + hex + " ('" + quoted + "')") +
                                   ", where a PNG starts with 89 50 4e 47 0d 0a 1a 0a ('\\x89PNG\\r\\n\\x1a\\n')");
}

}  // namespace

void check_png_file(const fs::path& p, const std::string& what) {
  std::ifstream in(p, std::ios::binary);
  if (!in) throw InputError(p.string(), what + ": cannot open file");
  char head[sizeof kPngSignature] = {};
  in.read(head, sizeof head);
  check_png_signature(p, what, reinterpret_cast<const std::uint8_t*>(head), static_cast<std::size_t>(in.gcount()));
}

namespace {

/// A draw's viewport, [x, y, width, height, min_depth, max_depth] in framebuffer pixels (y down
/// for Vulkan); the whole frame, depth [0, 1], when the capture gives none.
struct DrawViewport {
  float x = 0, y = 0, w = 0, h = 0, min_depth = 0, max_depth = 1;
  bool full_frame = true;  ///< the whole frame (the simulator's only viewport)
};

/// A pixel rectangle [x0, x1) x [y0, y1) in floats (a pass's render area).
struct PixelBox {
  float x0 = 0, y0 = 0, x1 = 0, y1 = 0;
};

/// One draw's geometry as the trace takes it: clip positions in the simulator's convention, their
/// texture coordinates (none when the capture has none), and its triangle list.
struct DrawGeometry {
  std::vector<glm::vec4> clip;
  std::vector<glm::vec2> uvs;
  std::vector<std::uint32_t> triangles;
  std::string topology;          ///< as captured: triangles, triangle_strip, triangle_fan, lines, line_strip, points
  std::uint32_t instances = 1;
  bool indexed = false;
  bool lines_or_points = false;  ///< expanded into triangles (never culled)
  std::uint64_t dropped = 0;     ///< lines or points behind the eye or of no length
  std::string note;              ///< for the summary: what the triangles were made from
};

/// What the frames of one import share: the GLB their geometry and textures go to (one scene for
/// a sequence) and their distinct shaders.
struct CaptureScene {
  GlbBuilder glb;
  json meshes = json::array(), nodes = json::array(), materials = json::array(), textures = json::array(),
       images = json::array();
  std::map<std::string, int> image_of_file;         ///< texture file (its path) -> glTF texture index
  std::map<std::string, std::string> shader_of_key;  ///< shader cost -> its declaration's name
};

/// One conversion of a capture intermediate: the trace being built (a frame of the import), the
/// scene its geometry and textures go to, and what its passes share (image formats, stores).
class CaptureConverter {
 public:
  /// `prefix` starts the names of the frame's sub-meshes, pipelines and buffers (a sequence's
  /// frames declare them once each); `before`: the frame before it, whose declarations it keeps.
  CaptureConverter(const std::string& frame_json_path, CaptureScene& scene, std::string prefix, const Trace* before)
      : r_(frame_json_path), dir_(fs::path(frame_json_path).parent_path()), t_(out_.trace), scene_(scene),
        prefix_(std::move(prefix)) {
    if (before != nullptr) {
      t_.shaders = before->shaders;
      t_.pipelines = before->pipelines;
      t_.buffers = before->buffers;
    }
  }
  /// Parses the intermediate and reads its header: format, clip convention, source, frame size.
  void read_header();
  /// The frame's passes, transfers and dispatches, in submission order.
  void convert_commands();
  /// The intermediate's passes.
  const json& passes() const { return r_.array(doc_, "passes", "header"); }
  /// One pass: its attachments, then its draws.
  void convert_pass(const json& pj);
  /// The frame: its trace (without its scene line) and the summary's first line.
  CaptureImport finish();

 private:
  void convert_transfer(const json& tj);
  void convert_dispatch(const json& dj);
  std::string recorded_buffer(const std::string& where, const std::string& name, std::uint64_t bytes, DramClass traffic,
                              bool upload);
  DramClass transfer_traffic(const json& tj, const char* format_key, const char* image_key) const;
  static void recorded_groups(std::uint64_t bytes, DispatchCmd& d);
  Attachment convert_attachment(const json& aj, const std::string& awhere, const std::string& pass_name, std::uint64_t index);
  void name_attachment_image(const json& aj, const std::string& awhere, const std::string& pass_name, std::uint64_t index,
                             Attachment& a);
  void note_clear_values(const json& aj, const std::string& awhere, const Attachment& a);
  void check_pass_attachments(const PassDesc& pass, const std::string& pwhere) const;
  std::optional<ScissorRect> render_area(const json& pj) const;
  void convert_draw(const json& dj, const std::string& pwhere, std::size_t color_targets, bool has_depth, PassDesc& pass);
  void check_clip_meaning(const json& dj, const std::string& dwhere);
  DrawViewport read_viewport(const json& dj, const std::string& dwhere) const;
  std::optional<ScissorRect> draw_scissor(const json& dj, const std::string& dwhere) const;
  DrawGeometry draw_geometry(const json& dj, const std::string& dwhere, const DrawViewport& vp);
  std::vector<glm::vec4> clip_positions(const json& dj, const std::string& dwhere, const DrawViewport& vp);
  std::vector<std::uint32_t> vertex_indices(const json& dj, const std::string& dwhere, std::size_t vertices, bool& indexed) const;
  std::vector<std::uint32_t> triangle_list(const std::vector<std::uint32_t>& idx, const std::string& topo,
                                           const std::string& dwhere) const;
  json position_attributes(const std::vector<glm::vec4>& clip);
  json draw_material(const json& dj, const std::string& dwhere, const std::string& dname, const std::vector<glm::vec2>& uvs,
                     json& attrs, std::string& texture_note);
  int texture_of_file(const std::string& file, const std::string& dwhere);
  std::string draw_shader(const json& dj, const json& sj, const std::string& dwhere, std::size_t color_targets, ShaderDesc& sh);
  PipelineState draw_pipeline(const json& dj, const std::string& dwhere, std::uint64_t ev, const std::string& shader,
                              bool has_depth);

  const Reader r_;
  json doc_;
  std::string convention_;  ///< clip_convention: vulkan or opengl
  fs::path dir_;            ///< the intermediate's folder (its textures)
  CaptureImport out_;
  Trace& t_;
  CaptureScene& scene_;
  std::string prefix_;
  std::map<std::uint64_t, Format> image_format_;  ///< attachment image -> format across passes
  std::set<std::uint64_t> stored_images_;
  std::uint32_t max_samples_ = 1;
  int final_width_ = 0, final_height_ = 0;     ///< the application's final colour target
  PixelBox area_;                              ///< the current pass's render area
  std::uint64_t negative_one_to_one_draws_ = 0;  ///< draws imported with depth clip control's -w..w depth
  std::uint64_t vertex_costed_draws_ = 0;
  std::set<std::uint64_t> transfer_images_;      ///< images a transfer wrote (a later load of one is named)        ///< draws whose vertex cost is their captured vertex shader's
};

void CaptureConverter::read_header() {
  const std::string& path = r_.file();
  {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw InputError(path, "cannot open the capture intermediate");
    try {
      doc_ = json::parse(in);
    } catch (const json::exception& e) {
      throw InputError(path, std::string("not valid JSON (truncated export?): ") + e.what());
    }
  }
  const std::string fmt = r_.str(doc_, "format", "header");
  if (std::find(std::begin(kCaptureFormats), std::end(kCaptureFormats), fmt) == std::end(kCaptureFormats)) {
    r_.fail("header", "format '" + fmt + "', expected '" + kCaptureFormats[0] + "' or '" + kCaptureFormats[1] + "'");
  }
  convention_ = r_.str(doc_, "clip_convention", "header");
  if (convention_ != "vulkan" && convention_ != "opengl") {
    r_.fail("header", "clip_convention '" + convention_ + "' (known: vulkan, opengl)");
  }
  t_.technique = "capture_import";
  const json& source = r_.get(doc_, "source", "header");
  for (const char* key : {"tool", "api", "capture"}) {
    if (source.contains(key) && source[key].is_string()) {
      std::string v = source[key].get<std::string>();
      std::replace_if(v.begin(), v.end(), [](char c) { return c == ' ' || c == '"' || c == '#' || c == '\\'; }, '_');
      if (!v.empty()) t_.options[key] = v;
    }
  }
  final_width_ = static_cast<int>(r_.uint(doc_, "width", "header", kMaxFrameSide));
  final_height_ = static_cast<int>(r_.uint(doc_, "height", "header", kMaxFrameSide));
  if (final_width_ == 0 || final_height_ == 0) r_.fail("header", "frame of zero size");
  // The trace's frame is the grid every pass lives in: the largest render area (a 640x480 shadow
  // map beside a 320x240 frame makes it 640x480, the final pass then has its own 320x240 area).
  t_.frame.width = final_width_;
  t_.frame.height = final_height_;
  for (const auto& pj : passes()) {
    if (const auto area = render_area(pj)) {
      t_.frame.width = std::max(t_.frame.width, static_cast<int>(area->x1));
      t_.frame.height = std::max(t_.frame.height, static_cast<int>(area->y1));
    }
  }
  t_.frame.samples = 1;
  t_.camera = placeholder_camera();
  t_.camera_name = "captured_clip_space";

  for (const auto& u : r_.array(doc_, "unsupported", "header")) {
    if (u.is_string()) out_.unsupported.push_back(u.get<std::string>());
  }
}

// The frame's work in submission order: the intermediate's `commands` list when it has one, else
// the passes, transfers and dispatches merged by event (format 1 has passes and dispatches only).
void CaptureConverter::convert_commands() {
  std::map<std::uint64_t, std::pair<std::string, const json*>> by_event;
  auto add = [&](const char* key, const char* kind) {
    if (!doc_.contains(key)) return;
    for (const auto& j : r_.array(doc_, key, "header")) {
      const std::uint64_t ev = r_.uint(j, "event", std::string(kind) + " in '" + key + "'", 1ull << 40);
      if (!by_event.emplace(ev, std::pair{std::string(kind), &j}).second) {
        r_.fail("header", "two commands at event " + std::to_string(ev));
      }
    }
  };
  add("passes", "pass");
  add("transfers", "transfer");
  add("dispatches", "dispatch");
  for (const auto& [ev, entry] : by_event) {
    const auto& [kind, j] = entry;
    if (kind == "pass") {
      convert_pass(*j);
    } else if (kind == "transfer") {
      convert_transfer(*j);
    } else {
      convert_dispatch(*j);
    }
  }
}

// A buffer the transfer or dispatch at `ev` reads (`upload` yes: its contents exist before it,
// whoever made them) or writes, `bytes` long; its name.
std::string CaptureConverter::recorded_buffer(const std::string& where, const std::string& name, std::uint64_t bytes,
                                              DramClass traffic, bool upload) {
  if (upload && bytes > kMaxUploadBufferBytes) {
    r_.fail(where, "reads " + std::to_string(bytes) + " bytes, more than a trace buffer read whole may hold (" +
                       std::to_string(kMaxUploadBufferBytes) + ")");
  }
  BufferDesc b;
  b.name = name;
  b.bytes = bytes;
  b.traffic = traffic;
  b.content = BufferContent::Other;
  b.upload = upload;
  t_.buffers.push_back(b);
  return name;
}

// The traffic class of a transfer's image or buffer: depth for depth formats, colour for other
// images, `other` for buffers.
DramClass CaptureConverter::transfer_traffic(const json& tj, const char* format_key, const char* image_key) const {
  if (!tj.contains(image_key) || tj[image_key].is_null()) return DramClass::Other;
  if (tj.contains(format_key) && tj[format_key].is_string()) {
    if (const auto f = format_of(tj[format_key].get<std::string>()); f && is_depth_format(*f)) return DramClass::DepthStencil;
  }
  return DramClass::Color;
}

// Workgroups of kRecordedGroupSize threads, each thread one kRecordedBytesPerThread-byte piece of
// `bytes`, laid out in x and y within Vulkan's workgroup count limit.
void CaptureConverter::recorded_groups(std::uint64_t bytes, DispatchCmd& d) {
  const std::uint64_t threads = std::max<std::uint64_t>(1, (bytes + kRecordedBytesPerThread - 1) / kRecordedBytesPerThread);
  const std::uint64_t groups = (threads + kRecordedGroupSize - 1) / kRecordedGroupSize;
  d.groups[0] = static_cast<std::uint32_t>(std::min<std::uint64_t>(groups, kMaxWorkgroupCount));
  d.groups[1] = static_cast<std::uint32_t>((groups + d.groups[0] - 1) / d.groups[0]);
  d.group_size[0] = kRecordedGroupSize;
}

// A blit, copy, resolve, clear or fill outside a render pass: a `transfer` dispatch reading and
// writing the bytes the exporter computed from the command's regions.
void CaptureConverter::convert_transfer(const json& tj) {
  const std::uint64_t ev = r_.uint(tj, "event", "transfer", 1ull << 40);
  const std::string where = "transfer at event " + std::to_string(ev) +
                            (tj.contains("name") && tj["name"].is_string() ? " (" + tj["name"].get<std::string>() + ")" : "");
  const std::string kind = r_.str(tj, "kind", where);
  static const std::set<std::string> kinds = {"blit", "copy_image", "copy_buffer", "copy_buffer_to_image", "copy_image_to_buffer",
                                              "resolve", "clear_color_image", "clear_depth_stencil_image", "fill_buffer",
                                              "update_buffer", "generate_mips"};
  if (!kinds.count(kind)) r_.fail(where, "transfer kind '" + kind + "' is not known");
  const std::uint64_t read = r_.uint(tj, "read_bytes", where, kMaxRecordedBytes);
  const std::uint64_t written = r_.uint(tj, "write_bytes", where, kMaxRecordedBytes);
  if (read == 0 && written == 0) {
    out_.unsupported.push_back(where + ": moves no bytes; skipped");
    return;
  }
  DispatchCmd d;
  d.kernel = ComputeKernel::Transfer;
  const std::string base = prefix_ + "xfer_" + std::to_string(ev);
  if (read > 0) d.reads.push_back(recorded_buffer(where, base + "_src", read, transfer_traffic(tj, "src_format", "src_image"), true));
  if (written > 0) {
    d.writes.push_back(recorded_buffer(where, base + "_dst", written, transfer_traffic(tj, "dst_format", "dst_image"), false));
  }
  recorded_groups(std::max(read, written), d);
  t_.commands.emplace_back(std::in_place_type<DispatchCmd>, std::move(d));
  ++out_.transfers;
  out_.summary.push_back(where + ": " + kind + ", " + std::to_string(read) + " bytes read, " + std::to_string(written) +
                         " written (a transfer dispatch: memory traffic only)");
  if (tj.contains("dst_image") && tj["dst_image"].is_number_unsigned()) {
    transfer_images_.insert(tj["dst_image"].get<std::uint64_t>());
  }
}

// The application's own compute dispatch: a `captured_compute` dispatch of its workgroups, costed
// by its shader's static count, reading and writing the bytes the exporter found bound.
void CaptureConverter::convert_dispatch(const json& dj) {
  const std::uint64_t ev = r_.uint(dj, "event", "dispatch", 1ull << 40);
  const std::string where = "dispatch at event " + std::to_string(ev) +
                            (dj.contains("name") && dj["name"].is_string() ? " (" + dj["name"].get<std::string>() + ")" : "");
  if (!dj.contains("shader") || !dj.contains("local_size")) {
    out_.unsupported.push_back(where + ": no shader cost or workgroup size exported; not replayed");
    return;
  }
  DispatchCmd d;
  d.kernel = ComputeKernel::CapturedCompute;
  const json& g = r_.array(dj, "groups", where);
  const json& l = r_.array(dj, "local_size", where);
  if (g.size() != 3 || l.size() != 3) r_.fail(where, "groups and local_size are not 3 numbers each");
  std::uint64_t invocations = 1;
  for (int i = 0; i < 3; ++i) {
    if (!g[i].is_number_unsigned() || g[i].get<std::uint64_t>() == 0 || g[i].get<std::uint64_t>() > kMaxWorkgroupCount ||
        !l[i].is_number_unsigned() || l[i].get<std::uint64_t>() == 0) {
      r_.fail(where, "groups " + g.dump() + " / local_size " + l.dump() + " are not whole numbers from 1 to " +
                         std::to_string(kMaxWorkgroupCount));
    }
    d.groups[i] = g[i].get<std::uint32_t>();
    d.group_size[i] = l[i].get<std::uint32_t>();
    invocations *= d.group_size[i];
  }
  if (invocations > kMaxWorkgroupInvocations) r_.fail(where, "local_size " + l.dump() + " holds more than 1024 invocations");
  const json& sj = r_.get(dj, "shader", where);
  d.params["alu_ops"] = std::to_string(r_.uint(sj, "alu_ops", where + " shader", 1u << 20));
  d.params["tex_fetches"] = std::to_string(sj.contains("tex_fetches") ? r_.uint(sj, "tex_fetches", where + " shader", 1u << 16) : 0);
  const std::string base = prefix_ + "disp_" + std::to_string(ev);
  if (dj.contains("reads_bytes") && r_.uint(dj, "reads_bytes", where, kMaxRecordedBytes) > 0) {
    d.reads.push_back(recorded_buffer(where, base + "_in", r_.uint(dj, "reads_bytes", where, kMaxRecordedBytes), DramClass::Other, true));
  }
  if (dj.contains("writes_bytes") && r_.uint(dj, "writes_bytes", where, kMaxRecordedBytes) > 0) {
    d.writes.push_back(recorded_buffer(where, base + "_out", r_.uint(dj, "writes_bytes", where, kMaxRecordedBytes), DramClass::Other, false));
  } else {
    out_.unsupported.push_back(where + ": the bytes it writes are not known; its writes are not counted");
  }
  if (!dj.contains("reads_bytes")) out_.unsupported.push_back(where + ": the bytes it reads are not known; its reads are not counted");
  t_.commands.emplace_back(std::in_place_type<DispatchCmd>, std::move(d));
  ++out_.dispatches;
  out_.summary.push_back(where + ": " + g.dump() + " workgroups of " + l.dump() + ", " + sj.value("source", std::string("?")));
}

// A pass's `render_area` [x, y, width, height] (format 2) as pixels [x0, x1) x [y0, y1), or none.
std::optional<ScissorRect> CaptureConverter::render_area(const json& pj) const {
  if (!pj.is_object() || !pj.contains("render_area")) return std::nullopt;
  const std::string pwhere = "pass at event " + (pj.contains("event") ? pj["event"].dump() : std::string("?"));
  const json& a = r_.array(pj, "render_area", pwhere);
  if (a.size() != 4) r_.fail(pwhere, "render_area is not [x, y, width, height]");
  std::uint64_t v[4];
  for (int i = 0; i < 4; ++i) {
    if (!a[i].is_number_unsigned() || a[i].get<std::uint64_t>() > kMaxFrameSide) {
      r_.fail(pwhere, "render_area " + a.dump() + " is not 4 whole numbers up to " + std::to_string(kMaxFrameSide));
    }
    v[i] = a[i].get<std::uint64_t>();
  }
  if (v[2] == 0 || v[3] == 0 || v[0] + v[2] > kMaxFrameSide || v[1] + v[3] > kMaxFrameSide) {
    r_.fail(pwhere, "render_area " + a.dump() + " is empty or beyond " + std::to_string(kMaxFrameSide) + " pixels");
  }
  return ScissorRect{static_cast<std::uint32_t>(v[0]), static_cast<std::uint32_t>(v[1]),
                     static_cast<std::uint32_t>(v[0] + v[2]), static_cast<std::uint32_t>(v[1] + v[3])};
}

void CaptureConverter::convert_pass(const json& pj) {
  const std::uint64_t pev = r_.uint(pj, "event", "pass", 1ull << 40);
  const std::string pwhere = "pass at event " + std::to_string(pev);
  PassDesc pass;
  pass.name = "pass_" + std::to_string(pev);
  // Its own size: a render area short of the frame's grid is the pass's `area` (trace version 5).
  if (const auto area = render_area(pj);
      area && (area->x0 != 0 || area->y0 != 0 || static_cast<int>(area->x1) != t_.frame.width ||
               static_cast<int>(area->y1) != t_.frame.height)) {
    pass.area = area;
    area_ = PixelBox{static_cast<float>(area->x0), static_cast<float>(area->y0), static_cast<float>(area->x1),
                     static_cast<float>(area->y1)};
  } else {
    area_ = PixelBox{0.0f, 0.0f, static_cast<float>(t_.frame.width), static_cast<float>(t_.frame.height)};
  }
  if (pj.contains("flags") && pj["flags"].is_array() && !pj["flags"].empty()) {
    out_.unsupported.push_back(pwhere + ": render pass flags " + pj["flags"].dump() +
                               " (suspended and resumed passes are imported as passes of their own)");
  }
  std::map<std::uint64_t, std::size_t> by_index;  // the capture's attachment index -> pass.attachments
  std::vector<std::pair<std::uint64_t, std::size_t>> resolves;  // (multisampled index, resolve target)
  for (const auto& aj : r_.array(pj, "attachments", pwhere)) {
    const std::uint64_t index = r_.uint(aj, "index", pwhere, 64);
    const std::string awhere = pwhere + " attachment " + std::to_string(index);
    if (!by_index.emplace(index, pass.attachments.size()).second) r_.fail(awhere, "index given twice");
    if (aj.contains("resolve_of")) resolves.emplace_back(r_.uint(aj, "resolve_of", awhere, 64), pass.attachments.size());
    pass.attachments.push_back(convert_attachment(aj, awhere, pass.name, index));
  }
  // MSAA resolves: the multisampled attachment names its 1-sample target (`resolve=`), which the
  // tile memory fills on chip at the end of the pass.
  for (const auto& [from, target] : resolves) {
    const std::string awhere = pwhere + " attachment " + std::to_string(from);
    auto it = by_index.find(from);
    if (it == by_index.end()) r_.fail(pwhere, "a resolve attachment names attachment " + std::to_string(from) + ", which the pass does not have");
    Attachment& ms = pass.attachments[it->second];
    const Attachment& one = pass.attachments[target];
    if (ms.samples == 1 || one.samples != 1 || ms.format != one.format || ms.usage != one.usage) {
      r_.fail(awhere, "resolves into " + one.name + ", but a resolve goes from a multisampled attachment into a 1-sample one "
                      "of the same format (" + to_string(ms.format) + " x" + std::to_string(ms.samples) + " into " +
                      to_string(one.format) + " x" + std::to_string(one.samples) + ")");
    }
    ms.resolve = one.name;
  }
  std::size_t color_targets = 0;
  for (const Attachment& a : pass.attachments) color_targets += a.usage == AttachmentUsage::Color && !pass.is_resolve_target(a);
  check_pass_attachments(pass, pwhere);
  const bool has_depth = pass.depth_attachment() != nullptr;
  for (const auto& dj : r_.array(pj, "draws", pwhere)) convert_draw(dj, pwhere, color_targets, has_depth, pass);
  if (pass.draws.empty()) {
    out_.unsupported.push_back(pwhere + ": no draws (a clear-only pass); imported with its load/store");
  }
  t_.commands.emplace_back(std::in_place_type<PassDesc>, std::move(pass));
  ++out_.passes;
}

// One attachment: its format, samples, load and store, image and clear values.
Attachment CaptureConverter::convert_attachment(const json& aj, const std::string& awhere, const std::string& pass_name,
                                                std::uint64_t index) {
  Attachment a;
  const std::string vk = r_.str(aj, "vk_format", awhere);
  const auto f = format_of(vk);
  if (!f) r_.fail(awhere, "format " + vk + " has no trace equivalent (docs/trace-format.md lists the formats)");
  a.format = *f;
  a.samples = static_cast<std::uint32_t>(r_.uint(aj, "samples", awhere, 8));
  if (a.samples != 1 && a.samples != 2 && a.samples != 4 && a.samples != 8) r_.fail(awhere, "samples must be 1, 2, 4 or 8");
  max_samples_ = std::max(max_samples_, a.samples);
  const std::string load = r_.str(aj, "load", awhere), store = r_.str(aj, "store", awhere);
  const auto lo = parse_load_op(load);
  const auto so = parse_store_op(store);
  if (!lo || !so) r_.fail(awhere, "load '" + load + "' / store '" + store + "' not known");
  a.load = *lo;
  a.store = *so;
  a.usage = is_depth_format(a.format) ? AttachmentUsage::Depth : AttachmentUsage::Color;
  name_attachment_image(aj, awhere, pass_name, index, a);
  note_clear_values(aj, awhere, a);
  return a;
}

// The attachment's name (its image's, kept across passes, or the pass's own) and the trace's
// load rule: load=load needs an earlier store of the image in this frame.
void CaptureConverter::name_attachment_image(const json& aj, const std::string& awhere, const std::string& pass_name,
                                             std::uint64_t index, Attachment& a) {
  if (aj.contains("image") && aj["image"].is_number_unsigned()) {
    const std::uint64_t img = aj["image"].get<std::uint64_t>();
    a.name = "img_" + std::to_string(img);
    auto [it, fresh] = image_format_.emplace(img, a.format);
    if (!fresh && it->second != a.format) r_.fail(awhere, "image " + std::to_string(img) + " changes format between passes");
    if (a.load == LoadOp::Load && !stored_images_.count(img)) {
      // The trace's rule: load=load needs an earlier store in this frame. The capture's first
      // pass loads what a previous frame left; it is imported as a clear and said so.
      out_.unsupported.push_back(awhere + ": loads " + a.name + ", which no earlier pass of the frame stored" +
                                 (transfer_images_.count(img) ? " (a transfer wrote it)" : "") + "; imported as load=clear");
      a.load = LoadOp::Clear;
    }
    if (a.store == StoreOp::Store) stored_images_.insert(img);
  } else {
    a.name = pass_name + "_att" + std::to_string(index);
    if (a.load == LoadOp::Load) {
      out_.unsupported.push_back(awhere + ": loads an unnamed image; imported as load=clear");
      a.load = LoadOp::Clear;
    }
  }
}

// Clear values the simulator does not take (depth other than 1, colour other than black): noted.
void CaptureConverter::note_clear_values(const json& aj, const std::string& awhere, const Attachment& a) {
  if (a.usage == AttachmentUsage::Depth && aj.contains("clear") && a.load == LoadOp::Clear) {
    const float depth = r_.number(r_.get(r_.get(aj, "clear", awhere), "depth", awhere), awhere + " clear depth");
    if (depth != 1.0f) {
      out_.unsupported.push_back(awhere + ": clears depth to " + std::to_string(depth) +
                                 "; the simulator clears depth to 1.0 (far)");
    }
  }
  if (a.usage == AttachmentUsage::Color && aj.contains("clear") && a.load == LoadOp::Clear) {
    const json& col = r_.array(r_.get(aj, "clear", awhere), "color", awhere + " clear");
    bool black = true;
    std::string shown;  // the components as the capture's floats read ("0.2", not 0.20000000298023224)
    for (const auto& c : col) {
      const float v = r_.number(c, awhere + " clear colour");
      black = black && v == 0.0f;
      char buf[32];
      std::snprintf(buf, sizeof buf, "%g", static_cast<double>(v));
      shown += (shown.empty() ? "" : ", ") + std::string(buf);
    }
    if (!black) {
      out_.unsupported.push_back(awhere + ": clears to colour [" + shown + "]" +
                                 "; the simulator's images clear to black (counts and traffic are unaffected)");
    }
  }
}

// A pass the trace can hold: some attachment, one sample count, at most one depth attachment.
void CaptureConverter::check_pass_attachments(const PassDesc& pass, const std::string& pwhere) const {
  if (pass.attachments.empty()) r_.fail(pwhere, "has no attachments");
  const Attachment* first = nullptr;
  for (const Attachment& a : pass.attachments) {
    if (pass.is_resolve_target(a)) continue;
    if (first == nullptr) first = &a;
    if (a.samples != first->samples) {
      r_.fail(pwhere, "attachments with different sample counts (" + a.name + ": " + std::to_string(a.samples) + ", " +
                          first->name + ": " + std::to_string(first->samples) +
                          ") that are not a multisampled attachment and its resolve target");
    }
  }
  if (std::count_if(pass.attachments.begin(), pass.attachments.end(),
                    [](const Attachment& a) { return a.usage == AttachmentUsage::Depth; }) > 1) {
    r_.fail(pwhere, "has more than one depth attachment");
  }
}

// One draw: its geometry (a GLB mesh), material, shader and pipeline, appended to `pass`.
void CaptureConverter::convert_draw(const json& dj, const std::string& pwhere, std::size_t color_targets, bool has_depth,
                                    PassDesc& pass) {
  const std::uint64_t ev = r_.uint(dj, "event", pwhere, 1ull << 40);
  std::string dname = prefix_ + "draw_" + std::to_string(ev);
  const std::string dwhere = "draw at event " + std::to_string(ev) +
                             (dj.contains("name") && dj["name"].is_string() ? " (" + dj["name"].get<std::string>() + ")" : "");
  if (dj.contains("refused")) {
    r_.fail(dwhere, "refused by the exporter: " + (dj["refused"].is_string() ? dj["refused"].get<std::string>() : dj["refused"].dump()));
  }
  check_clip_meaning(dj, dwhere);
  const DrawViewport vp = read_viewport(dj, dwhere);
  const std::optional<ScissorRect> scissor = draw_scissor(dj, dwhere);
  if (scissor && (scissor->x0 >= scissor->x1 || scissor->y0 >= scissor->y1)) {
    out_.unsupported.push_back(dwhere + ": its scissor leaves no pixel of the pass; skipped (it draws nothing)");
    return;
  }
  DrawGeometry g = draw_geometry(dj, dwhere, vp);
  std::vector<std::uint32_t>& tri = g.triangles;
  std::vector<glm::vec4>& clip = g.clip;
  if (tri.empty()) {
    out_.unsupported.push_back(dwhere + ": no whole triangle" + (g.dropped ? " (" + std::to_string(g.dropped) +
                               " lines or points behind the eye or of no length)" : std::string()) + "; skipped");
    return;
  }
  const std::string& topo = g.topology;
  const bool cull_all = dj.contains("cull") && dj["cull"].is_string() && dj["cull"].get<std::string>() == "front_and_back";
  if (cull_all && !g.lines_or_points) {
    // VK_CULL_MODE_FRONT_AND_BACK: no triangle reaches the rasteriser.
    out_.unsupported.push_back(dwhere + ": culls front and back faces: its " + std::to_string(tri.size() / 3) +
                               " triangles draw nothing; skipped (its vertex work is not counted)");
    return;
  }
  // Winding: the simulator's front faces are counter-clockwise in its (y-up, OpenGL) clip space
  // (clipper.hpp, front_ccw). Vulkan decides facing from the triangle's area in framebuffer
  // coordinates, whose y runs down, and the y flip of clip_positions keeps every vertex on its
  // pixel, so a Vulkan counter-clockwise front face is the simulator's as it is and a clockwise
  // one is imported by reversing each triangle. Measured on vkcube (cull back, front
  // counter-clockwise): as is, the visible triangles match RenderDoc's pixel history at 240 of
  // 240 sampled pixels; reversed, at 84 (the far faces are drawn instead).
  const bool reverse = r_.str(dj, "front_face", dwhere) == "cw";
  if (reverse) {
    for (std::size_t i = 0; i + 2 < tri.size(); i += 3) std::swap(tri[i + 1], tri[i + 2]);
  }
  out_.triangles += tri.size() / 3;

  json attrs = position_attributes(clip);
  std::string texture_note;
  scene_.materials.push_back(draw_material(dj, dwhere, dname, g.uvs, attrs, texture_note));
  json prim = {{"attributes", attrs}, {"material", scene_.materials.size() - 1}, {"mode", 4}};
  if (g.indexed || topo != "triangles" || reverse || g.instances > 1) {
    std::vector<std::uint8_t> bytes;
    for (auto i : tri) put(bytes, i);
    prim["indices"] = scene_.glb.accessor({{"bufferView", scene_.glb.view(bytes, kGlElementArrayBuffer)},
                                     {"componentType", kGlUnsignedInt}, {"count", tri.size()}, {"type", "SCALAR"}});
  }
  scene_.meshes.push_back({{"name", dname}, {"primitives", json::array({prim})}});
  scene_.nodes.push_back({{"name", dname}, {"mesh", scene_.meshes.size() - 1}});

  const json& sj = r_.get(dj, "shader", dwhere);
  ShaderDesc sh;
  const std::string shader = draw_shader(dj, sj, dwhere, color_targets, sh);
  PipelineState p = draw_pipeline(dj, dwhere, ev, shader, has_depth);
  if (g.lines_or_points) p.cull = CullMode::None;  // lines and points have no facing: never culled
  t_.pipelines.push_back(p);

  DrawCmd d;
  d.pipeline = p.name;
  d.geometry = GeometryKind::Scene;
  d.submesh = dname;
  d.lights.all = false;
  d.scissor = scissor;
  pass.draws.push_back(d);
  ++out_.draws;
  out_.summary.push_back(dwhere + ": " + std::to_string(tri.size() / 3) + " triangles" + g.note + ", shader " + shader + " (" +
                         std::to_string(sh.alu_ops) + " ALU, " + std::to_string(sh.tex_fetches) + " tex, " +
                         std::to_string(sh.varyings) + " varyings; " +
                         (sj.contains("source") && sj["source"].is_string() ? sj["source"].get<std::string>() : "?") +
                         "), texture " + texture_note + ", depth " + (p.depth_test ? to_string(p.depth_compare) : "off") +
                         (p.depth_write ? " write" : "") + ", blend " + to_string(p.blend) + ", cull " + to_string(p.cull));
}

// The draw's viewport (whole frame, depth [0, 1] when none is given).
DrawViewport CaptureConverter::read_viewport(const json& dj, const std::string& dwhere) const {
  const float fw = static_cast<float>(t_.frame.width), fh = static_cast<float>(t_.frame.height);
  DrawViewport vp;
  vp.w = fw;
  vp.h = fh;
  if (dj.contains("viewport")) {
    const json& vj = r_.array(dj, "viewport", dwhere);
    if (vj.size() != 6) r_.fail(dwhere, "viewport is not [x, y, width, height, min_depth, max_depth]");
    vp.x = r_.number(vj[0], dwhere + " viewport");
    vp.y = r_.number(vj[1], dwhere + " viewport");
    vp.w = r_.number(vj[2], dwhere + " viewport");
    vp.h = r_.number(vj[3], dwhere + " viewport");
    vp.min_depth = r_.number(vj[4], dwhere + " viewport");
    vp.max_depth = r_.number(vj[5], dwhere + " viewport");
    if (vp.w <= 0.0f || vp.h == 0.0f) r_.fail(dwhere, "viewport of zero or negative width");
  }
  vp.full_frame = vp.x == 0.0f && vp.y == 0.0f && vp.w == fw && vp.h == fh;
  return vp;
}

// The draw's scissor [x, y, width, height] (framebuffer pixels, the frame's grid) as the trace's
// rectangle, cut to the frame (empty when nothing is left); none when it covers the whole frame.
std::optional<ScissorRect> CaptureConverter::draw_scissor(const json& dj, const std::string& dwhere) const {
  if (!dj.contains("scissor")) return std::nullopt;
  const json& sj = r_.array(dj, "scissor", dwhere);
  if (sj.size() != 4) r_.fail(dwhere, "scissor is not [x, y, width, height]");
  double v[4];
  for (int i = 0; i < 4; ++i) v[i] = r_.number(sj[i], dwhere + " scissor");
  const auto clampi = [](double x, int hi) { return static_cast<std::uint32_t>(std::clamp(x, 0.0, static_cast<double>(hi))); };
  const ScissorRect r{clampi(v[0], t_.frame.width), clampi(v[1], t_.frame.height), clampi(v[0] + v[2], t_.frame.width),
                      clampi(v[1] + v[3], t_.frame.height)};
  if (r.x0 == 0 && r.y0 == 0 && static_cast<int>(r.x1) == t_.frame.width && static_cast<int>(r.y1) == t_.frame.height) {
    return std::nullopt;
  }
  return r;
}

// State that changes what clip coordinates or depth mean: imported with its meaning, or refused
// by name. Depth clamping keeps geometry beyond the near and far planes (clamped depth) where
// the simulator clips it away: refused. A depth bias moves depth values by an offset the trace
// cannot state: listed.
void CaptureConverter::check_clip_meaning(const json& dj, const std::string& dwhere) {
  if (dj.contains("depth_clamp") && r_.boolean(dj, "depth_clamp", dwhere)) {
    r_.fail(dwhere, "depth clamp enabled (VkPipelineRasterizationStateCreateInfo::depthClampEnable): the geometry beyond "
                    "the near and far planes would be drawn with clamped depth, and the simulator clips it; not imported");
  }
  if (dj.contains("depth_bias") && r_.boolean(dj, "depth_bias", dwhere)) {
    out_.unsupported.push_back(dwhere + ": depth bias enabled; imported without it (its depth values lack the offset)");
  }
  if (dj.contains("state_notes")) {
    for (const auto& n : r_.array(dj, "state_notes", dwhere)) {
      if (n.is_string()) out_.unsupported.push_back(dwhere + ": " + n.get<std::string>());
    }
  }
}

// The draw's clip positions (x, y, z, w as the vertex shader wrote them) in the simulator's clip
// space. The simulator's viewport is the whole frame, so each vertex is moved in clip space to
// where the draw's own viewport puts it: with s = size / frame size and
// o = (2 origin + size) / frame size - 1, x_ndc' = s x_ndc + o, i.e. x' = s x + o w (same for
// y), and depth' = min + (max - min) depth, i.e. z' = (max - min) z + min w (Vulkan depth).
std::vector<glm::vec4> CaptureConverter::clip_positions(const json& dj, const std::string& dwhere, const DrawViewport& vp) {
  const float fw = static_cast<float>(t_.frame.width), fh = static_cast<float>(t_.frame.height);
  std::size_t beyond_viewport = 0;
  const std::string depth_clip = dj.contains("depth_clip") ? r_.str(dj, "depth_clip", dwhere) : "zero_to_one";
  if (depth_clip != "zero_to_one" && depth_clip != "negative_one_to_one") {
    r_.fail(dwhere, "depth_clip '" + depth_clip + "' is not known (zero_to_one, negative_one_to_one); not imported");
  }
  if (depth_clip == "negative_one_to_one" && convention_ != "vulkan") {
    r_.fail(dwhere, "depth_clip negative_one_to_one in an OpenGL-convention capture (its clip space is already -w..w)");
  }
  const bool zero_to_one = depth_clip == "zero_to_one";
  if (!zero_to_one) ++negative_one_to_one_draws_;
  const json& cj = r_.array(dj, "clip_positions", dwhere);
  if (cj.empty()) r_.fail(dwhere, "has no vertices");
  if (cj.size() > kMaxDrawVertices) r_.fail(dwhere, std::to_string(cj.size()) + " vertices, more than the import's limit");
  std::vector<glm::vec4> clip(cj.size());
  for (std::size_t v = 0; v < cj.size(); ++v) {
    const std::string vtx = dwhere + " vertex " + std::to_string(v);
    if (!cj[v].is_array() || cj[v].size() != 4) r_.fail(vtx, "clip position is not 4 numbers");
    glm::vec4 c(r_.number(cj[v][0], vtx), r_.number(cj[v][1], vtx), r_.number(cj[v][2], vtx), r_.number(cj[v][3], vtx));
    if (!vp.full_frame) {
      if (std::abs(c.x) > c.w || std::abs(c.y) > c.w) ++beyond_viewport;
      const float sx = vp.w / fw, ox = (2.0f * vp.x + vp.w) / fw - 1.0f;
      const float sy = vp.h / fh, oy = (2.0f * vp.y + vp.h) / fh - 1.0f;
      c = glm::vec4(sx * c.x + ox * c.w, sy * c.y + oy * c.w, c.z, c.w);
    }
    if (convention_ == "vulkan") {
      if (zero_to_one) {
        // Vulkan's default clip space: y points down the framebuffer and depth is
        // min + (max - min) z/w. The simulator's (OpenGL's): y up, depth (z/w + 1)/2. Same pixel
        // and same depth value: y' = -y, z' = 2 (max - min) z + (2 min - 1) w.
        c = glm::vec4(c.x, -c.y, 2.0f * (vp.max_depth - vp.min_depth) * c.z + (2.0f * vp.min_depth - 1.0f) * c.w, c.w);
      } else {
        // VK_EXT_depth_clip_control (negativeOneToOne, as zink draws OpenGL): -w <= z <= w and
        // depth min + (max - min) (z/w + 1)/2, so z' = (max - min) z + (max + min - 1) w; with
        // the range [0, 1], z' = z.
        c = glm::vec4(c.x, -c.y, (vp.max_depth - vp.min_depth) * c.z + (vp.max_depth + vp.min_depth - 1.0f) * c.w, c.w);
      }
    } else if (vp.min_depth != 0.0f || vp.max_depth != 1.0f) {
      r_.fail(dwhere, "a depth range other than [0, 1] is imported for Vulkan captures only");
    }
    clip[v] = c;
  }
  if (beyond_viewport > 0) {
    out_.unsupported.push_back(dwhere + ": " + std::to_string(beyond_viewport) + " vertices outside its viewport " +
                               "(not the whole frame); the simulator clips to the frame, so they may draw beyond it");
  }
  return clip;
}

// The draw's indices (each below `vertices`), or 0, 1, ... when it has none (`indexed` false).
std::vector<std::uint32_t> CaptureConverter::vertex_indices(const json& dj, const std::string& dwhere, std::size_t vertices,
                                                            bool& indexed) const {
  std::vector<std::uint32_t> idx;
  indexed = dj.contains("indices");
  if (indexed) {
    for (const auto& ij : r_.array(dj, "indices", dwhere)) {
      if (!ij.is_number_unsigned() || ij.get<std::uint64_t>() >= vertices) {
        r_.fail(dwhere, "index " + ij.dump() + " is out of range (" + std::to_string(vertices) + " vertices)");
      }
      idx.push_back(ij.get<std::uint32_t>());
    }
  } else {
    idx.resize(vertices);
    for (std::size_t i = 0; i < idx.size(); ++i) idx[i] = static_cast<std::uint32_t>(i);
  }
  return idx;
}

// Strips and fans become lists (the winding of each triangle as the API defines it).
std::vector<std::uint32_t> CaptureConverter::triangle_list(const std::vector<std::uint32_t>& idx, const std::string& topo,
                                                           const std::string& dwhere) const {
  std::vector<std::uint32_t> tri;
  if (topo == "triangles") {
    tri.assign(idx.begin(), idx.end() - static_cast<std::ptrdiff_t>(idx.size() % 3));
  } else if (topo == "triangle_strip" || topo == "triangle_fan") {
    for (std::size_t i = 0; i + 2 < idx.size(); ++i) {
      if (topo == "triangle_fan") {
        tri.insert(tri.end(), {idx[0], idx[i + 1], idx[i + 2]});
      } else if (i % 2 == 0) {
        tri.insert(tri.end(), {idx[i], idx[i + 1], idx[i + 2]});
      } else {
        tri.insert(tri.end(), {idx[i + 1], idx[i], idx[i + 2]});
      }
    }
  } else {
    r_.fail(dwhere, "topology '" + topo + "' is not imported (triangles, triangle_strip, triangle_fan, lines, line_strip, points)");
  }
  return tri;
}

// The draw's triangles over its clip positions: every instance's (instance i's vertices follow
// instance i - 1's), strips and fans as lists, lines and points as the triangles that cover their
// pixels (capture_geometry.hpp), with their texture coordinates.
DrawGeometry CaptureConverter::draw_geometry(const json& dj, const std::string& dwhere, const DrawViewport& vp) {
  DrawGeometry g;
  g.clip = clip_positions(dj, dwhere, vp);
  g.instances = dj.contains("instances") ? static_cast<std::uint32_t>(r_.uint(dj, "instances", dwhere, kMaxDrawVertices)) : 1;
  if (g.instances == 0) r_.fail(dwhere, "has 0 instances");
  std::size_t per_instance = g.clip.size();
  if (g.instances > 1) {
    per_instance = r_.uint(dj, "vertices_per_instance", dwhere, kMaxDrawVertices);
    if (per_instance * g.instances != g.clip.size()) {
      r_.fail(dwhere, std::to_string(g.instances) + " instances of " + std::to_string(per_instance) + " vertices need " +
                          std::to_string(per_instance * g.instances) + " clip positions, it has " + std::to_string(g.clip.size()));
    }
  }
  if (dj.contains("uvs")) {
    const json& uj = r_.array(dj, "uvs", dwhere);
    if (uj.size() != g.clip.size()) {
      r_.fail(dwhere, "has " + std::to_string(uj.size()) + " uvs for " + std::to_string(g.clip.size()) + " vertices");
    }
    for (std::size_t v = 0; v < uj.size(); ++v) {
      const std::string vw = dwhere + " uv " + std::to_string(v);
      if (!uj[v].is_array() || uj[v].size() != 2) r_.fail(vw, "is not 2 numbers");
      g.uvs.emplace_back(r_.number(uj[v][0], vw), r_.number(uj[v][1], vw));
    }
  }
  const std::vector<std::uint32_t> idx = vertex_indices(dj, dwhere, per_instance, g.indexed);
  g.topology = r_.str(dj, "topology", dwhere);
  const auto n = static_cast<std::uint32_t>(per_instance);
  if (g.topology == "lines" || g.topology == "line_strip" || g.topology == "points") {
    g.lines_or_points = true;
    std::vector<std::uint32_t> prims;  // one instance's segments (pairs) or points
    if (g.topology == "points") {
      prims = idx;
    } else {
      for (std::size_t i = 0; i + 1 < idx.size(); i += g.topology == "lines" ? 2 : 1) prims.insert(prims.end(), {idx[i], idx[i + 1]});
    }
    prims = instanced_indices(prims, n, g.instances);
    const FramePixels frame{static_cast<float>(t_.frame.width), static_cast<float>(t_.frame.height)};
    ExpandedPrimitives e;
    if (g.topology == "points") {
      std::vector<float> sizes;
      if (dj.contains("point_sizes")) {
        const json& pj = r_.array(dj, "point_sizes", dwhere);
        if (pj.size() != g.clip.size()) r_.fail(dwhere, "point_sizes has " + std::to_string(pj.size()) + " sizes for " +
                                                            std::to_string(g.clip.size()) + " vertices");
        for (const auto& v : pj) sizes.push_back(r_.number(v, dwhere + " point size"));
      }
      e = points_as_squares(g.clip, g.uvs, sizes, prims, frame);
      g.note = " (" + std::to_string(prims.size()) + " points as squares of their size";
    } else {
      const float width = dj.contains("line_width") ? r_.number(dj["line_width"], dwhere + " line_width") : 1.0f;
      if (!(width > 0.0f) || width > 1024.0f) r_.fail(dwhere, "line_width " + dj["line_width"].dump() + " is not in (0, 1024] pixels");
      e = lines_as_rectangles(g.clip, g.uvs, prims, width, frame);
      char w[32];
      std::snprintf(w, sizeof w, "%g", static_cast<double>(width));
      g.note = " (" + std::to_string(prims.size() / 2) + " line segments as rectangles " + w + " pixels wide";
    }
    g.dropped = e.dropped;
    g.note += g.instances > 1 ? ", " + std::to_string(g.instances) + " instances)" : std::string(")");
    g.clip = std::move(e.clip);
    g.uvs = std::move(e.uvs);
    g.triangles = std::move(e.triangles);
    return g;
  }
  g.triangles = instanced_indices(triangle_list(idx, g.topology, dwhere), n, g.instances);
  if (g.instances > 1) g.note = " (" + std::to_string(g.instances) + " instances)";
  return g;
}

// The GLB mesh's positions: POSITION (clip x, y, z: glTF requires it; the simulator uses it only
// as the vertex's world position, for lights, and an imported frame has none) and _CLIP_POSITION.
json CaptureConverter::position_attributes(const std::vector<glm::vec4>& clip) {
  json attrs;
  std::vector<std::uint8_t> bytes;
  glm::vec3 lo(3.4e38f), hi(-3.4e38f);
  for (const auto& c : clip) {
    put(bytes, c.x);
    put(bytes, c.y);
    put(bytes, c.z);
    lo = glm::min(lo, glm::vec3(c));
    hi = glm::max(hi, glm::vec3(c));
  }
  attrs["POSITION"] = scene_.glb.accessor({{"bufferView", scene_.glb.view(bytes, kGlArrayBuffer)}, {"componentType", kGlFloat},
                                     {"count", clip.size()}, {"type", "VEC3"},
                                     {"min", {lo.x, lo.y, lo.z}}, {"max", {hi.x, hi.y, hi.z}}});
  bytes.clear();
  for (const auto& c : clip) {
    put(bytes, c.x);
    put(bytes, c.y);
    put(bytes, c.z);
    put(bytes, c.w);
  }
  attrs[kClipPositionAttribute] = scene_.glb.accessor({{"bufferView", scene_.glb.view(bytes, kGlArrayBuffer)},
                                                 {"componentType", kGlFloat}, {"count", clip.size()}, {"type", "VEC4"}});
  return attrs;
}

// The draw's material: the first texture the fragment shader binds as its base colour, when the
// exporter saved it and found uvs for it (TEXCOORD_0 added to `attrs`); `texture_note` says which.
json CaptureConverter::draw_material(const json& dj, const std::string& dwhere, const std::string& dname,
                                     const std::vector<glm::vec2>& uvs, json& attrs, std::string& texture_note) {
  json material = {{"name", dname}, {"doubleSided", false}};
  texture_note = "no texture";
  const json& texs = r_.array(dj, "textures", dwhere);
  if (!uvs.empty() && !texs.empty() && texs[0].contains("file")) {
    std::vector<std::uint8_t> bytes;
    for (const glm::vec2& uv : uvs) {
      put(bytes, uv.x);
      put(bytes, uv.y);
    }
    attrs["TEXCOORD_0"] = scene_.glb.accessor({{"bufferView", scene_.glb.view(bytes, kGlArrayBuffer)}, {"componentType", kGlFloat},
                                         {"count", uvs.size()}, {"type", "VEC2"}});
    const std::string file = r_.str(texs[0], "file", dwhere + " texture");
    material["pbrMetallicRoughness"] = {{"baseColorTexture", {{"index", texture_of_file(file, dwhere)}}}, {"metallicFactor", 0.0}};
    texture_note = file;
  } else if (!texs.empty()) {
    out_.unsupported.push_back(dwhere + ": binds " + std::to_string(texs.size()) +
                               " texture(s) but no uvs were exported; drawn untextured");
  }
  if (texs.size() > 1) {
    out_.unsupported.push_back(dwhere + ": binds " + std::to_string(texs.size()) +
                               " textures; only the first is the material's (fetch counts come from the shader)");
  }
  return material;
}

// The glTF texture of a PNG in the intermediate's folder, embedded at its first use.
int CaptureConverter::texture_of_file(const std::string& file, const std::string& dwhere) {
  if (file.find('/') != std::string::npos || file.find("..") != std::string::npos) {
    r_.fail(dwhere, "texture file '" + file + "' must be a plain name in the intermediate's folder");
  }
  const std::string key = (dir_ / file).string();  // a sequence's frames come from several folders
  auto it = scene_.image_of_file.find(key);
  if (it == scene_.image_of_file.end()) {
    const auto png = read_bytes(dir_ / file, dwhere + " texture");
    check_png_signature(dir_ / file, dwhere + " texture", png.data(), png.size());
    scene_.images.push_back({{"bufferView", scene_.glb.view(png, std::nullopt)}, {"mimeType", "image/png"}, {"name", file}});
    scene_.textures.push_back({{"source", scene_.images.size() - 1}});
    it = scene_.image_of_file.emplace(key, static_cast<int>(scene_.textures.size() - 1)).first;
  }
  return it->second;
}

// The draw's shaders: the fragment shader's static SPIR-V cost (into `sh`) and, when captured, its
// vertex shader's ALU count (`vertex_alu_ops`); one declaration per distinct cost. Returns the
// declaration's name.
std::string CaptureConverter::draw_shader(const json& dj, const json& sj, const std::string& dwhere, std::size_t color_targets,
                                          ShaderDesc& sh) {
  if (dj.contains("vertex_shader")) {
    sh.vertex_alu_ops = static_cast<std::uint32_t>(r_.uint(r_.get(dj, "vertex_shader", dwhere), "alu_ops", dwhere + " vertex_shader", 1u << 20));
    ++vertex_costed_draws_;
  }
  sh.alu_ops = static_cast<std::uint32_t>(r_.uint(sj, "alu_ops", dwhere + " shader", 1u << 20));
  sh.tex_fetches = static_cast<std::uint32_t>(r_.uint(sj, "tex_fetches", dwhere + " shader", 1u << 16));
  sh.varyings = static_cast<std::uint32_t>(r_.uint(sj, "varyings", dwhere + " shader", 128));
  sh.discard = r_.boolean(sj, "discard", dwhere + " shader");
  const std::uint64_t outputs = r_.uint(sj, "color_outputs", dwhere + " shader", 8);
  sh.color_outputs = static_cast<std::uint32_t>(std::min<std::uint64_t>(outputs, color_targets));
  if (outputs > color_targets) {
    out_.unsupported.push_back(dwhere + ": shader writes " + std::to_string(outputs) + " colour outputs, the pass has " +
                               std::to_string(color_targets) + " colour targets; counted as " + std::to_string(color_targets));
  }
  sh.light_source = LightSource::None;
  const std::string skey = std::to_string(sh.alu_ops) + "_" + std::to_string(sh.tex_fetches) + "_" +
                           std::to_string(sh.varyings) + "_" + std::to_string(sh.color_outputs) + (sh.discard ? "_d" : "") +
                           (sh.vertex_alu_ops ? "_v" + std::to_string(*sh.vertex_alu_ops) : std::string());
  auto sit = scene_.shader_of_key.find(skey);
  if (sit == scene_.shader_of_key.end()) {
    sh.name = "fs_" + std::to_string(scene_.shader_of_key.size());
    t_.shaders.push_back(sh);
    sit = scene_.shader_of_key.emplace(skey, sh.name).first;
  }
  return sit->second;
}

// The draw's own pipeline state (depth test only with a depth attachment).
PipelineState CaptureConverter::draw_pipeline(const json& dj, const std::string& dwhere, std::uint64_t ev,
                                              const std::string& shader, bool has_depth) {
  PipelineState p;
  p.name = prefix_ + "p_" + std::to_string(ev);
  p.shader = shader;
  p.depth_test = r_.boolean(dj, "depth_test", dwhere) && has_depth;
  p.depth_write = p.depth_test && r_.boolean(dj, "depth_write", dwhere);
  if (r_.boolean(dj, "depth_test", dwhere) && !has_depth) {
    out_.unsupported.push_back(dwhere + ": depth test enabled without a depth attachment; imported without it");
  }
  const auto cmp = parse_compare_op(r_.str(dj, "depth_compare", dwhere));
  const auto blend = parse_blend_mode(r_.str(dj, "blend", dwhere));
  const std::string cull_name = r_.str(dj, "cull", dwhere);
  const auto cull = parse_cull_mode(cull_name == "front_and_back" ? "none" : cull_name);  // lines and points: never culled
  if (!cmp || !blend || !cull) r_.fail(dwhere, "depth_compare, blend or cull not known");
  p.depth_compare = *cmp;
  p.blend = *blend;
  p.cull = *cull;
  return p;
}

CaptureImport CaptureConverter::finish() {
  if (out_.draws == 0) r_.fail("header", "the capture has no draws to import");
  t_.frame.samples = static_cast<int>(max_samples_);
  const std::string grid = std::to_string(t_.frame.width) + "x" + std::to_string(t_.frame.height);
  const std::string final_size = std::to_string(final_width_) + "x" + std::to_string(final_height_);
  out_.summary.insert(
      out_.summary.begin(),
      std::to_string(out_.passes) + " passes, " + std::to_string(out_.draws) + " draws, " + std::to_string(out_.triangles) +
          " triangles, " + std::to_string(out_.transfers) + " transfers, " + std::to_string(out_.dispatches) +
          " dispatches; frame " + final_size + (grid != final_size ? " in a " + grid + " grid (the largest pass)" : "") +
          "; shader costs: static SPIR-V counts of each fragment shader (scripts/capture/spirv_cost.py); vertex shading: " +
          (vertex_costed_draws_ == out_.draws ? std::string("each draw's captured vertex shader, counted the same way")
           : std::to_string(vertex_costed_draws_) + " draws their captured vertex shader's count, the others the hardware "
                                                    "parameter geometry.vertex_shader_alu_ops") +
          (negative_one_to_one_draws_ > 0 ? "; " + std::to_string(negative_one_to_one_draws_) +
                                                " draws with depth clip control (clip z from -w to w, as zink draws OpenGL)"
                                          : std::string()));
  return std::move(out_);
}

}  // namespace

namespace {

/// The scene's GLB: every frame's meshes, one node each, materials and textures.
std::vector<std::uint8_t> finish_scene(CaptureScene& scene) {
  scene.glb.doc()["meshes"] = scene.meshes;
  scene.glb.doc()["nodes"] = scene.nodes;
  json scene_nodes = json::array();
  for (std::size_t i = 0; i < scene.nodes.size(); ++i) scene_nodes.push_back(i);
  scene.glb.doc()["scenes"] = json::array({{{"nodes", scene_nodes}}});
  scene.glb.doc()["scene"] = 0;
  scene.glb.doc()["materials"] = scene.materials;
  if (!scene.images.empty()) {
    scene.glb.doc()["images"] = scene.images;
    scene.glb.doc()["textures"] = scene.textures;
  }
  return scene.glb.finish();
}

}  // namespace

CaptureSequence convert_captures(const std::vector<std::string>& frame_json_paths, const std::string& glb_name) {
  CaptureScene scene;
  CaptureSequence out;
  for (std::size_t k = 0; k < frame_json_paths.size(); ++k) {
    CaptureConverter converter(frame_json_paths[k], scene, frame_json_paths.size() > 1 ? "f" + std::to_string(k) + "_" : "",
                               k > 0 ? &out.frames.back().trace : nullptr);
    converter.read_header();
    converter.convert_commands();
    out.frames.push_back(converter.finish());
    const Trace& first = out.frames.front().trace;
    const Trace& t = out.frames.back().trace;
    if (t.frame.width != first.frame.width || t.frame.height != first.frame.height || t.frame.samples != first.frame.samples) {
      throw InputError(frame_json_paths[k], "frame " + std::to_string(k) + " is " + std::to_string(t.frame.width) + "x" +
                                                std::to_string(t.frame.height) + " at " + std::to_string(t.frame.samples) +
                                                " samples, the first " + std::to_string(first.frame.width) + "x" +
                                                std::to_string(first.frame.height) + " at " + std::to_string(first.frame.samples) +
                                                " samples: the frames of a sequence share one size");
    }
  }
  // A sequence shares its technique line: the first capture's, with the number of frames.
  for (CaptureImport& f : out.frames) {
    f.trace.technique = out.frames.front().trace.technique;
    f.trace.options = out.frames.front().trace.options;
    if (out.frames.size() > 1) f.trace.options["frames"] = std::to_string(out.frames.size());
  }
  out.glb = finish_scene(scene);
  Fnv1a64 h;
  h.update(out.glb.data(), out.glb.size());
  for (CaptureImport& f : out.frames) {
    f.trace.scene.kind = SceneKind::Gltf;
    f.trace.scene.path = glb_name;
    f.trace.scene.content_hash = h.hex();
  }
  return out;
}

CaptureImport convert_capture(const std::string& frame_json_path, const std::string& glb_name) {
  CaptureSequence s = convert_captures({frame_json_path}, glb_name);
  CaptureImport one = std::move(s.frames.front());
  one.glb = std::move(s.glb);
  return one;
}

}  // namespace tbdr
