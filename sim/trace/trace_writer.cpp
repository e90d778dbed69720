// Canonical trace writer: one fixed order and spelling, so that write -> read -> write gives
// identical bytes and trace_hash() identifies a trace. Floats use the shortest text that reads
// back to the same float (std::to_chars), so values round-trip exactly.
#include <algorithm>
#include <charconv>
#include <fstream>
#include <ostream>
#include <sstream>
#include <stdexcept>
#include <system_error>

#include "kernel/errors.hpp"
#include "kernel/output_file.hpp"
#include "trace/trace.hpp"

namespace tbdr {

namespace {

std::string fmt_float(float v) {
  char buf[64];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  return std::string(buf, r.ptr);
}

std::string fmt_vec3(const glm::vec3& v) { return fmt_float(v.x) + "," + fmt_float(v.y) + "," + fmt_float(v.z); }

const char* yes_no(bool b) { return b ? "yes" : "no"; }

// Quotes a free-text value when the reader would otherwise split or misread it.
std::string quote_if_needed(const std::string& s) {
  bool needs = s.empty();
  for (char c : s)
    if (c == ' ' || c == '\t' || c == '"' || c == '\\' || c == '#' || c == '\r' || c == '\n') needs = true;
  if (!needs) return s;
  std::string out = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') out += '\\';
    out += c;
  }
  out += '"';
  return out;
}

std::string fmt_list(const std::vector<std::string>& v) {
  std::string out;
  for (std::size_t i = 0; i < v.size(); ++i) {
    if (i) out += ',';
    out += v[i];
  }
  return out;
}

std::string fmt_lights(const LightSelection& s) {
  if (s.all) return "all";
  if (s.ranges.empty()) return "none";
  std::string out;
  for (std::size_t i = 0; i < s.ranges.size(); ++i) {
    if (i) out += ',';
    out += std::to_string(s.ranges[i].first);
    if (s.ranges[i].second != s.ranges[i].first) {
      out += '-';
      out += std::to_string(s.ranges[i].second);
    }
  }
  return out;
}

std::string fmt_u32x3(const std::uint32_t (&v)[3]) {
  return std::to_string(v[0]) + "," + std::to_string(v[1]) + "," + std::to_string(v[2]);
}

std::string fmt_rect(const ScissorRect& r) {
  return std::to_string(r.x0) + "," + std::to_string(r.y0) + "," + std::to_string(r.x1) + "," + std::to_string(r.y1);
}

void write_pass(const PassDesc& p, std::ostream& out) {
  out << "pass " << p.name;
  if (p.area) out << " area=" << fmt_rect(*p.area);
  out << "\n";
  for (const auto& a : p.attachments) {
    out << "  attachment " << a.name << " format=" << to_string(a.format) << " samples=" << a.samples
        << " load=" << to_string(a.load) << " store=" << to_string(a.store) << " usage=" << to_string(a.usage)
        << " transient=" << yes_no(a.transient);
    if (!a.resolve.empty()) out << " resolve=" << a.resolve;
    out << "\n";
  }
  for (const auto& v : p.pls) out << "  pls " << v.name << " format=" << to_string(v.format) << "\n";
  for (const auto& d : p.draws) {
    out << "  draw " << to_string(d.geometry) << " pipeline=" << d.pipeline;
    if (d.geometry == GeometryKind::Scene) {
      if (!d.submesh.empty())
        out << " submesh=" << quote_if_needed(d.submesh);
      else if (!d.material.empty())
        out << " material=" << quote_if_needed(d.material);
      else
        out << " subset=" << to_string(d.subset);
    }
    if (d.geometry == GeometryKind::LightSpheres) out << " subdivisions=" << d.subdivisions;
    if (!d.lights.all) out << " lights=" << fmt_lights(d.lights);
    if (d.scissor)
      out << " scissor=" << fmt_rect(*d.scissor);
    if (d.cull) out << " cull_min=" << fmt_vec3(d.cull->min) << " cull_max=" << fmt_vec3(d.cull->max);
    if (!d.reads.empty()) out << " reads=" << fmt_list(d.reads);
    if (!d.fetch.empty()) out << " fetch=" << fmt_list(d.fetch);
    out << "\n";
  }
  out << "end\n";
}

/// The header lines a sequence's frames share: version, technique, scene.
void write_header(const Trace& t, int version, std::ostream& out) {
  out << "tbdrsim-trace " << version << "\n";
  if (!t.technique.empty()) {
    out << "technique " << t.technique;
    for (const auto& [k, v] : t.options) out << " " << k << "=" << quote_if_needed(v);
    out << "\n";
  }
  const auto& s = t.scene;
  if (s.kind == SceneKind::Atrium) {
    out << "scene atrium detail=" << s.detail;
  } else {
    out << "scene gltf path=" << quote_if_needed(s.path);
  }
  if (!s.content_hash.empty()) out << " hash=" << s.content_hash;
  out << "\n";
}

/// What each frame has of its own: its `frame`, `camera`, `pose` and `light` lines.
void write_frame_view(const Trace& t, std::ostream& out) {
  out << "frame width=" << t.frame.width << " height=" << t.frame.height << " samples=" << t.frame.samples << "\n";
  const auto& c = t.camera;
  out << "camera eye=" << fmt_vec3(c.eye) << " target=" << fmt_vec3(c.target) << " up=" << fmt_vec3(c.up)
      << " fov_y_deg=" << fmt_float(c.fov_y_deg) << " near=" << fmt_float(c.near_plane)
      << " far=" << fmt_float(c.far_plane);
  if (!t.camera_name.empty()) out << " name=" << quote_if_needed(t.camera_name);
  out << "\n";
  if (t.pose) out << "pose animation=" << t.pose->animation << " time=" << fmt_float(static_cast<float>(t.pose->time_s)) << "\n";
  for (const auto& l : t.lights) {
    const bool spot = l.type == Light::Type::Spot;
    out << "light " << (spot ? "spot" : "point") << " position=" << fmt_vec3(l.position)
        << " radius=" << fmt_float(l.radius) << " color=" << fmt_vec3(l.color)
        << " intensity=" << fmt_float(l.intensity);
    if (spot)
      out << " direction=" << fmt_vec3(l.direction) << " cos_inner=" << fmt_float(l.cos_inner)
          << " cos_outer=" << fmt_float(l.cos_outer);
    out << "\n";
  }
}

void write_buffer(const BufferDesc& b, std::ostream& out) {
  out << "buffer " << b.name << " bytes=" << b.bytes << " traffic=" << buffer_traffic_name(b.traffic)
      << " content=" << to_string(b.content) << " upload=" << yes_no(b.upload) << "\n";
}

void write_shader(const ShaderDesc& sh, std::ostream& out) {
  out << "shader " << sh.name << " alu_ops=" << sh.alu_ops << " tex_fetches=" << sh.tex_fetches
      << " varyings=" << sh.varyings << " light_alu_ops=" << sh.light_alu_ops
      << " light_source=" << to_string(sh.light_source) << " color_outputs=" << sh.color_outputs
      << " pls=" << to_string(sh.pls) << " discard=" << yes_no(sh.discard);
  if (sh.vertex_alu_ops) out << " vertex_alu_ops=" << *sh.vertex_alu_ops;
  out << "\n";
}

void write_pipeline(const PipelineState& p, std::ostream& out) {
  out << "pipeline " << p.name << " shader=" << p.shader << " depth_test=" << yes_no(p.depth_test)
      << " depth_write=" << yes_no(p.depth_write) << " depth_compare=" << to_string(p.depth_compare)
      << " stencil_test=" << yes_no(p.stencil_test) << " stencil_compare=" << to_string(p.stencil_compare)
      << " stencil_fail_op=" << to_string(p.stencil_fail_op)
      << " stencil_depth_fail_op=" << to_string(p.stencil_depth_fail_op)
      << " stencil_pass_op=" << to_string(p.stencil_pass_op) << " stencil_ref=" << p.stencil_ref
      << " blend=" << to_string(p.blend) << " cull=" << to_string(p.cull) << " alpha=" << to_string(p.alpha)
      << "\n";
}

template <typename T>
std::string declaration_text(const T& d, void (*write)(const T&, std::ostream&)) {
  std::ostringstream s;
  write(d, s);
  return s.str();
}

/// Writes the declarations of `now` that `before` (the previous frame, or none) does not have:
/// a frame's declarations are the earlier frame's followed by its own (the reader appends them).
/// Throws std::invalid_argument when a declaration the earlier frame made differs (by name or
/// text): a name means one thing for the whole sequence.
template <typename T>
void write_new_declarations(const std::vector<T>& now, const std::vector<T>* before, const char* what, int frame,
                            void (*write)(const T&, std::ostream&), std::ostream& out) {
  const std::size_t shared = before ? before->size() : 0;
  if (now.size() < shared) {
    throw std::invalid_argument("sequence frame " + std::to_string(frame) + " declares fewer " + what + "s than the frame before it");
  }
  for (std::size_t i = 0; i < shared; ++i) {
    if (declaration_text(now[i], write) != declaration_text((*before)[i], write)) {
      throw std::invalid_argument("sequence frame " + std::to_string(frame) + " declares " + what + " '" + now[i].name +
                                  "' differently from the frame before it");
    }
  }
  for (std::size_t i = shared; i < now.size(); ++i) write(now[i], out);
}

void write_commands(const Trace& t, std::ostream& out) {
  for (const auto& cmd : t.commands) {
    if (const auto* p = std::get_if<PassDesc>(&cmd)) {
      write_pass(*p, out);
    } else if (const auto* d = std::get_if<DispatchCmd>(&cmd)) {
      out << "dispatch " << to_string(d->kernel) << " groups=" << fmt_u32x3(d->groups)
          << " group_size=" << fmt_u32x3(d->group_size);
      if (!d->reads.empty()) out << " reads=" << fmt_list(d->reads);
      if (!d->writes.empty()) out << " writes=" << fmt_list(d->writes);
      for (const auto& [k, v] : d->params) out << " " << k << "=" << quote_if_needed(v);
      out << "\n";
    } else if (const auto* b = std::get_if<BarrierCmd>(&cmd)) {
      out << "barrier resources=" << (b->all ? std::string("all") : fmt_list(b->resources)) << "\n";
    }
  }
}

/// Writes frame `k` of a sequence (`before`: frame k - 1, or none for the first).
void write_frame(const Trace& t, const Trace* before, int k, std::ostream& out) {
  write_frame_view(t, out);
  write_new_declarations(t.buffers, before ? &before->buffers : nullptr, "buffer", k, write_buffer, out);
  write_new_declarations(t.shaders, before ? &before->shaders : nullptr, "shader", k, write_shader, out);
  write_new_declarations(t.pipelines, before ? &before->pipelines : nullptr, "pipeline", k, write_pipeline, out);
  write_commands(t, out);
}

/// Whether a frame uses what version 5 added (a pass's render area, a shader's vertex cost).
bool uses_version5(const Trace& t) {
  return std::any_of(t.commands.begin(), t.commands.end(),
                     [](const TraceCommand& c) {
                       const auto* p = std::get_if<PassDesc>(&c);
                       return p != nullptr && p->area.has_value();
                     }) ||
         std::any_of(t.shaders.begin(), t.shaders.end(), [](const ShaderDesc& s) { return s.vertex_alu_ops.has_value(); });
}

}  // namespace

void write_trace(const Trace& t, std::ostream& out) {
  // One frame needs nothing version 4 added: written as version 3, which older readers read,
  // unless a pass has its own render area (version 5).
  write_header(t, uses_version5(t) ? kPassAreaVersion : kDrawBoundsVersion, out);
  write_frame(t, nullptr, 0, out);
}

void write_trace_frames(const std::vector<Trace>& frames, std::ostream& out) {
  if (frames.empty()) throw std::invalid_argument("write_trace_frames: a sequence has at least one frame");
  if (frames.size() == 1) return write_trace(frames.front(), out);
  const Trace& first = frames.front();
  write_header(first, std::any_of(frames.begin(), frames.end(), uses_version5) ? kPassAreaVersion : kSequenceVersion, out);
  for (std::size_t k = 0; k < frames.size(); ++k) {
    const Trace& t = frames[k];
    if (k > 0 && (t.technique != first.technique || t.options != first.options || t.scene.kind != first.scene.kind ||
                  t.scene.detail != first.scene.detail || t.scene.path != first.scene.path ||
                  t.scene.content_hash != first.scene.content_hash || t.frame.width != first.frame.width ||
                  t.frame.height != first.frame.height || t.frame.samples != first.frame.samples)) {
      throw std::invalid_argument("sequence frame " + std::to_string(k) +
                                  " differs from the first in technique, scene or frame size, which a sequence shares");
    }
    write_frame(t, k > 0 ? &frames[k - 1] : nullptr, static_cast<int>(k), out);
  }
}

void write_trace_frames_file(const std::vector<Trace>& frames, const std::string& path) {
  write_output_file(path, "the trace file", [&](std::ostream& out) { write_trace_frames(frames, out); });
}

void write_trace_file(const Trace& trace, const std::string& path) {
  // Whole or not at all: a full disk leaves no partial trace (kernel/output_file.hpp).
  write_output_file(path, "the trace file", [&](std::ostream& out) { write_trace(trace, out); });
}

}  // namespace tbdr
