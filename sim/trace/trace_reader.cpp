// Strict trace reader: one pass over the lines, validating as it goes (names are declared before
// they are used), so every error names the line where it happened and the offending token.
#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <istream>
#include <set>
#include <unordered_map>

#include <glm/glm.hpp>

#include "kernel/errors.hpp"
#include "kernel/params.hpp"
#include "kernel/text_escape.hpp"
#include "scene/atrium.hpp"
#include "trace/trace.hpp"

namespace tbdr {

namespace {

/// One `key=value` token of a line.
struct KeyValue {
  std::string key;
  std::string value;
};

/// A tokenised line: command, optional positional word, key=value pairs.
struct Line {
  int number = 0;
  std::string command;
  std::string positional;  ///< empty if none
  bool has_positional = false;
  std::vector<KeyValue> kvs;
};

bool is_ident(std::string_view s) {
  if (s.empty()) return false;
  const auto c0 = static_cast<unsigned char>(s[0]);
  if (!(std::isalpha(c0) || s[0] == '_')) return false;
  for (char ch : s) {
    const auto c = static_cast<unsigned char>(ch);
    if (!(std::isalnum(c) || ch == '_' || ch == '.' || ch == '-')) return false;
  }
  return true;
}

bool is_key(std::string_view s) {
  if (s.empty()) return false;
  const auto c0 = static_cast<unsigned char>(s[0]);
  if (!(std::isalpha(c0) || s[0] == '_')) return false;
  for (char ch : s) {
    const auto c = static_cast<unsigned char>(ch);
    if (!(std::isalnum(c) || ch == '_' || ch == '.')) return false;
  }
  return true;
}

std::string q(std::string_view s) { return "'" + std::string(s) + "'"; }

/// Parser state and all checks. One instance per parse.
class Reader {
 public:
  explicit Reader(std::string name) : name_(std::move(name)) {}

  std::vector<Trace> run(std::istream& in);

 private:
  [[noreturn]] void fail(int line, const std::string& msg) const {
    throw InputError(name_, line, escape_for_message(msg));  // a quoted value may hold any byte
  }

  // --- tokenising -------------------------------------------------------------------------
  bool tokenize(const std::string& text, int number, Line& out) const;

  // --- key=value access -------------------------------------------------------------------
  /// Rejects keys not in `known` (and duplicates); call first for each line.
  void check_keys(const Line& l, std::initializer_list<std::string_view> known) const;
  const std::string* find(const Line& l, std::string_view key) const;
  const std::string& require(const Line& l, std::string_view key) const;

  std::uint64_t to_u64(const Line& l, std::string_view key, const std::string& v, std::uint64_t max) const;
  std::uint32_t get_u32(const Line& l, std::string_view key, std::uint32_t max = 0xffffffffu) const {
    return static_cast<std::uint32_t>(to_u64(l, key, require(l, key), max));
  }
  std::uint32_t get_u32_or(const Line& l, std::string_view key, std::uint32_t def, std::uint32_t max) const {
    const auto* v = find(l, key);
    return v ? static_cast<std::uint32_t>(to_u64(l, key, *v, max)) : def;
  }
  float to_float(const Line& l, std::string_view key, const std::string& v) const;
  float get_float(const Line& l, std::string_view key) const { return to_float(l, key, require(l, key)); }
  glm::vec3 get_vec3(const Line& l, std::string_view key) const;
  void get_u32x3(const Line& l, std::string_view key, std::uint32_t (&out)[3]) const;
  bool get_bool(const Line& l, std::string_view key, std::optional<bool> def = std::nullopt) const;
  std::string get_ident(const Line& l, std::string_view key) const;
  std::vector<std::string> get_ident_list(const Line& l, std::string_view key) const;
  LightSelection get_lights(const Line& l, std::string_view key) const;
  /// A pixel rectangle `key=x0,y0,x1,y1` (a draw's `scissor`, version 3; a pass's `area`,
  /// version 5): integers up to kMaxFrameSide, x0 < x1, y0 < y1.
  std::optional<ScissorRect> get_rect(const Line& l, std::string_view key, int version) const;
  /// A scene draw's `cull_min=` and `cull_max=` (version 3, both or neither): min <= max per
  /// component, each within kMaxWorldCoordinate.
  std::optional<CullBox> get_cull_box(const Line& l) const;
  /// Refuses `key` in a trace older than `version` (kDrawBoundsVersion by default).
  void need_version(const Line& l, std::string_view key, int version = kDrawBoundsVersion) const;
  template <typename E>
  E get_enum(const Line& l, std::string_view key, std::optional<E> (*parse)(std::string_view),
             std::optional<E> def = std::nullopt) const;
  std::string positional_ident(const Line& l, const char* what) const;
  void no_positional(const Line& l) const;

  // --- commands ---------------------------------------------------------------------------
  void header(const std::string& text);
  void command(const Line& l);
  void declaration_allowed(const Line& l, bool before_commands_only);
  void on_technique(const Line& l);
  void on_scene(const Line& l);
  void on_frame(const Line& l);
  void on_camera(const Line& l);
  void on_pose(const Line& l);
  void on_light(const Line& l);
  void on_buffer(const Line& l);
  void on_shader(const Line& l);
  void on_pipeline(const Line& l);
  void on_pass(const Line& l);
  void on_attachment(const Line& l);
  void on_pls(const Line& l);
  void on_draw(const Line& l);
  void on_end(const Line& l);
  void on_dispatch(const Line& l);
  void on_barrier(const Line& l);
  void finish_layout();
  /// Checks the frame being read as complete (`last_line`: where it ends) and keeps it.
  void finish_frame(int last_line);
  /// Starts the next frame of a sequence at `frame_line`: the frame read so far is kept; the new
  /// one keeps the header lines and the declarations, and has no camera, light or command yet.
  void next_frame(int frame_line);
  void finish(int last_line);
  /// Counts one more pass, dispatch or barrier against kMaxTraceCommands.
  void count_command(const Line& l);
  /// Refuses a vector with a component beyond kMaxWorldCoordinate.
  void check_world(const Line& l, std::string_view key, const glm::vec3& v) const;

  // --- resources --------------------------------------------------------------------------
  /// An image: the contents of an attachment name across passes.
  struct Image {
    Format format;
    std::uint32_t samples;
    AttachmentUsage usage;
    int line;             ///< first declaration
    bool in_dram = false; ///< stored by a pass or written by a dispatch
  };
  /// Who wrote a resource last, not yet covered by a barrier.
  struct PendingWrite {
    int line;
    bool by_dispatch;
  };
  PassDesc& pass() { return std::get<PassDesc>(trace_.commands[*current_pass_]); }
  void check_new_resource_name(const Line& l, const std::string& name);
  /// An attachment named after a buffer: allowed for a `content=image` buffer (version 2), which
  /// it then is (rgba8, 1 sample, usage color, the frame's size).
  void check_image_buffer_attachment(const Line& l, const Attachment& a);
  /// A read by a draw (`reads=`) or a dispatch of a buffer or stored image.
  void read_resource(const Line& l, const std::string& name, bool by_dispatch);
  void check_hazard(const Line& l, const std::string& name, bool by_dispatch);

  std::string name_;
  Trace trace_;
  std::vector<Trace> frames_;  ///< the sequence's frames read before the current one
  std::uint64_t held_declarations_ = 0;  ///< declarations summed over frames_ (kMaxSequenceDeclarations)
  bool have_scene_ = false, have_frame_ = false, have_camera_ = false;
  int first_command_line_ = 0;
  std::optional<std::size_t> current_pass_;
  bool layout_done_ = false;
  std::unordered_map<std::string, int> shader_lines_, pipeline_lines_, buffer_lines_, pass_lines_;
  std::unordered_map<std::string, Image> images_;
  std::set<std::string> written_buffers_;
  std::unordered_map<std::string, PendingWrite> pending_;
  std::uint64_t commands_ = 0, draws_ = 0;
};

// ------------------------------------------------------------------------------------------------
// Tokenising
// ------------------------------------------------------------------------------------------------

bool Reader::tokenize(const std::string& text, int number, Line& out) const {
  out = Line{};
  out.number = number;
  std::vector<std::string> words;  // token text, quotes removed
  std::size_t i = 0;
  const std::size_t n = text.size();
  while (i < n) {
    while (i < n && (text[i] == ' ' || text[i] == '\t')) ++i;
    if (i >= n) break;
    if (text[i] == '#') break;
    std::string tok;
    bool seen_eq = false;
    while (i < n && text[i] != ' ' && text[i] != '\t') {
      const char c = text[i];
      if (c == '"') {
        if (!seen_eq || tok.back() != '=')
          fail(number, "unexpected quote in " + q(tok + text.substr(i, text.find_first_of(" \t", i) - i)) +
                           " (only a whole value may be quoted: key=\"...\")");
        ++i;
        bool closed = false;
        while (i < n) {
          if (text[i] == '\\' && i + 1 < n && (text[i + 1] == '"' || text[i + 1] == '\\')) {
            tok += text[i + 1];
            i += 2;
          } else if (text[i] == '"') {
            closed = true;
            ++i;
            break;
          } else {
            tok += text[i++];
          }
        }
        if (!closed) fail(number, "unterminated quoted value in " + q(tok));
        if (i < n && text[i] != ' ' && text[i] != '\t')
          fail(number, "junk after closing quote: " + q(text.substr(i, text.find_first_of(" \t", i) - i)));
        break;
      }
      if (c == '=') seen_eq = true;
      tok += c;
      ++i;
    }
    words.push_back(std::move(tok));
  }
  if (words.empty()) return false;

  out.command = words[0];
  for (std::size_t w = 1; w < words.size(); ++w) {
    const std::string& tok = words[w];
    const auto eq = tok.find('=');
    if (eq == std::string::npos) {
      if (w != 1) fail(number, "unexpected token " + q(tok) + " (expected key=value)");
      out.positional = tok;
      out.has_positional = true;
      continue;
    }
    KeyValue kv{tok.substr(0, eq), tok.substr(eq + 1)};
    if (!is_key(kv.key)) fail(number, "malformed key " + q(kv.key) + " in " + q(tok));
    if (kv.value.empty()) fail(number, "empty value for key " + q(kv.key));
    for (const auto& other : out.kvs)
      if (other.key == kv.key) fail(number, "duplicate key " + q(kv.key));
    out.kvs.push_back(std::move(kv));
  }
  return true;
}

// ------------------------------------------------------------------------------------------------
// Values
// ------------------------------------------------------------------------------------------------

void Reader::check_keys(const Line& l, std::initializer_list<std::string_view> known) const {
  for (const auto& kv : l.kvs) {
    if (std::find(known.begin(), known.end(), kv.key) == known.end()) {
      std::string list;
      for (auto k : known) list += (list.empty() ? "" : ", ") + std::string(k);
      fail(l.number, "unknown key " + q(kv.key) + " for " + q(l.command) +
                         (known.size() ? " (known: " + list + ")" : " (it takes no keys)"));
    }
  }
}

const std::string* Reader::find(const Line& l, std::string_view key) const {
  for (const auto& kv : l.kvs)
    if (kv.key == key) return &kv.value;
  return nullptr;
}

const std::string& Reader::require(const Line& l, std::string_view key) const {
  const auto* v = find(l, key);
  if (!v) fail(l.number, "missing required key " + q(key) + " for " + q(l.command));
  return *v;
}

std::uint64_t Reader::to_u64(const Line& l, std::string_view key, const std::string& v, std::uint64_t max) const {
  std::uint64_t out = 0;
  const auto* end = v.data() + v.size();
  const auto r = std::from_chars(v.data(), end, out);
  if (r.ec == std::errc::result_out_of_range || (r.ec == std::errc() && r.ptr == end && out > max))
    fail(l.number, "value " + q(v) + " for key " + q(key) + " is out of range (0.." + std::to_string(max) + ")");
  if (r.ec != std::errc() || r.ptr != end)
    fail(l.number, "malformed number " + q(v) + " for key " + q(key) + " (expected a non-negative integer)");
  return out;
}

float Reader::to_float(const Line& l, std::string_view key, const std::string& v) const {
  float out = 0.0f;
  const auto* end = v.data() + v.size();
  const auto r = std::from_chars(v.data(), end, out, std::chars_format::general);
  if (r.ec == std::errc::result_out_of_range)
    fail(l.number, "number " + q(v) + " for key " + q(key) + " is out of the float range");
  if (r.ec != std::errc() || r.ptr != end || !std::isfinite(out))
    fail(l.number, "malformed number " + q(v) + " for key " + q(key) + " (expected a finite decimal number)");
  return out;
}

glm::vec3 Reader::get_vec3(const Line& l, std::string_view key) const {
  const std::string& v = require(l, key);
  glm::vec3 out{0.0f};
  std::size_t start = 0;
  for (int c = 0; c < 3; ++c) {
    const auto comma = v.find(',', start);
    const bool last = c == 2;
    if (last != (comma == std::string::npos))
      fail(l.number, "malformed vector " + q(v) + " for key " + q(key) + " (expected x,y,z)");
    out[c] = to_float(l, key, v.substr(start, last ? std::string::npos : comma - start));
    start = comma + 1;
  }
  return out;
}

void Reader::get_u32x3(const Line& l, std::string_view key, std::uint32_t (&out)[3]) const {
  const std::string& v = require(l, key);
  std::size_t start = 0;
  for (int c = 0; c < 3; ++c) {
    const auto comma = v.find(',', start);
    const bool last = c == 2;
    if (last != (comma == std::string::npos))
      fail(l.number, "malformed triple " + q(v) + " for key " + q(key) + " (expected x,y,z)");
    out[c] = static_cast<std::uint32_t>(
        to_u64(l, key, v.substr(start, last ? std::string::npos : comma - start), 0xffffffffu));
    if (out[c] == 0) fail(l.number, "value " + q(v) + " for key " + q(key) + " must be at least 1 in each component");
    start = comma + 1;
  }
}

bool Reader::get_bool(const Line& l, std::string_view key, std::optional<bool> def) const {
  const auto* found = find(l, key);
  if (!found && def) return *def;
  const std::string& v = found ? *found : require(l, key);
  if (v == "yes") return true;
  if (v == "no") return false;
  fail(l.number, "malformed value " + q(v) + " for key " + q(key) + " (expected yes or no)");
}

std::string Reader::get_ident(const Line& l, std::string_view key) const {
  const std::string& v = require(l, key);
  if (!is_ident(v)) fail(l.number, "malformed name " + q(v) + " for key " + q(key));
  return v;
}

std::vector<std::string> Reader::get_ident_list(const Line& l, std::string_view key) const {
  std::vector<std::string> out;
  const auto* v = find(l, key);
  if (!v) return out;
  std::size_t start = 0;
  while (true) {
    const auto comma = v->find(',', start);
    std::string item = v->substr(start, comma == std::string::npos ? std::string::npos : comma - start);
    if (!is_ident(item)) fail(l.number, "malformed name " + q(item) + " in list " + q(*v) + " for key " + q(key));
    if (std::find(out.begin(), out.end(), item) != out.end())
      fail(l.number, "name " + q(item) + " listed twice for key " + q(key));
    out.push_back(std::move(item));
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  return out;
}

LightSelection Reader::get_lights(const Line& l, std::string_view key) const {
  LightSelection sel;
  const auto* v = find(l, key);
  if (!v || *v == "all") return sel;
  sel.all = false;
  if (*v == "none") return sel;
  const auto count = static_cast<std::uint64_t>(trace_.lights.size());
  std::size_t start = 0;
  while (true) {
    const auto comma = v->find(',', start);
    const std::string item = v->substr(start, comma == std::string::npos ? std::string::npos : comma - start);
    const auto dash = item.find('-');
    std::uint64_t first = 0, last = 0;
    if (dash == std::string::npos) {
      first = last = to_u64(l, key, item, 0xffffffffu);
    } else {
      first = to_u64(l, key, item.substr(0, dash), 0xffffffffu);
      last = to_u64(l, key, item.substr(dash + 1), 0xffffffffu);
      if (last < first) fail(l.number, "light range " + q(item) + " is reversed");
    }
    if (last >= count)
      fail(l.number, "light index " + std::to_string(last) + " in " + q(item) + " is out of range (the trace has " +
                         std::to_string(count) + " lights)");
    sel.ranges.emplace_back(static_cast<std::uint32_t>(first), static_cast<std::uint32_t>(last));
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  // Canonical form: sorted, overlapping and adjacent ranges merged.
  std::sort(sel.ranges.begin(), sel.ranges.end());
  std::vector<std::pair<std::uint32_t, std::uint32_t>> merged;
  for (const auto& r : sel.ranges) {
    if (!merged.empty() && std::uint64_t{r.first} <= std::uint64_t{merged.back().second} + 1)
      merged.back().second = std::max(merged.back().second, r.second);
    else
      merged.push_back(r);
  }
  sel.ranges = std::move(merged);
  return sel;
}

void Reader::need_version(const Line& l, std::string_view key, int version) const {
  if (trace_.version < version)
    fail(l.number, "key " + q(key) + " needs trace version " + std::to_string(version) +
                       " (this trace is version " + std::to_string(trace_.version) + ")");
}

std::optional<ScissorRect> Reader::get_rect(const Line& l, std::string_view key, int version) const {
  const auto* v = find(l, key);
  if (!v) return std::nullopt;
  need_version(l, key, version);
  std::uint32_t c[4] = {};
  std::size_t start = 0;
  for (int i = 0; i < 4; ++i) {
    const auto comma = v->find(',', start);
    const bool last = i == 3;
    if (last != (comma == std::string::npos))
      fail(l.number, "malformed " + std::string(key) + " " + q(*v) + " (expected x0,y0,x1,y1 in pixels)");
    c[i] = static_cast<std::uint32_t>(
        to_u64(l, key, v->substr(start, last ? std::string::npos : comma - start), kMaxFrameSide));
    start = comma + 1;
  }
  const ScissorRect r{c[0], c[1], c[2], c[3]};
  if (r.x0 >= r.x1 || r.y0 >= r.y1)
    fail(l.number, std::string(key) + " " + q(*v) + " is empty (it needs x0 < x1 and y0 < y1: pixels [x0,x1) x [y0,y1))");
  return r;
}

std::optional<CullBox> Reader::get_cull_box(const Line& l) const {
  const bool has_min = find(l, "cull_min") != nullptr, has_max = find(l, "cull_max") != nullptr;
  if (!has_min && !has_max) return std::nullopt;
  need_version(l, has_min ? "cull_min" : "cull_max");
  if (!has_min) fail(l.number, "cull_max without cull_min (the culling box needs both corners)");
  if (!has_max) fail(l.number, "cull_min without cull_max (the culling box needs both corners)");
  CullBox b;
  b.min = get_vec3(l, "cull_min");
  b.max = get_vec3(l, "cull_max");
  check_world(l, "cull_min", b.min);
  check_world(l, "cull_max", b.max);
  for (int c = 0; c < 3; ++c)
    if (b.min[c] > b.max[c])
      fail(l.number, "cull_min=" + require(l, "cull_min") + " is above cull_max=" + require(l, "cull_max") + " in " +
                         "xyz"[c] + " (the box needs min <= max in every component)");
  return b;
}

template <typename E>
E Reader::get_enum(const Line& l, std::string_view key, std::optional<E> (*parse)(std::string_view),
                   std::optional<E> def) const {
  const auto* found = find(l, key);
  if (!found && def) return *def;
  const std::string& v = found ? *found : require(l, key);
  if (auto e = parse(v)) return *e;
  fail(l.number, "unknown value " + q(v) + " for key " + q(key));
}

std::string Reader::positional_ident(const Line& l, const char* what) const {
  if (!l.has_positional) fail(l.number, q(l.command) + " needs a " + what + " after it");
  if (!is_ident(l.positional)) fail(l.number, "malformed " + std::string(what) + " " + q(l.positional));
  return l.positional;
}

void Reader::no_positional(const Line& l) const {
  if (l.has_positional) fail(l.number, "unexpected token " + q(l.positional) + " (expected key=value)");
}

// ------------------------------------------------------------------------------------------------
// Commands
// ------------------------------------------------------------------------------------------------

void Reader::header(const std::string& text) {
  Line l;
  if (!tokenize(text, 1, l) || l.command != "tbdrsim-trace")
    fail(1, "not a tbdrsim trace: the first line must be 'tbdrsim-trace " + std::to_string(kTraceVersion) + "'");
  if (!l.has_positional || !l.kvs.empty()) fail(1, "malformed header: expected 'tbdrsim-trace <version>'");
  int version = 0;
  const auto& v = l.positional;
  const auto r = std::from_chars(v.data(), v.data() + v.size(), version);
  if (r.ec != std::errc() || r.ptr != v.data() + v.size() || version < 1)
    fail(1, "malformed trace version " + q(v));
  if (version > kTraceVersion)
    fail(1, "trace version " + std::to_string(version) + " is newer than this reader (" +
                std::to_string(kTraceVersion) + "); use a newer tbdrsim or regenerate the trace");
  trace_.version = version;
}

void Reader::declaration_allowed(const Line& l, bool before_commands_only) {
  if (current_pass_)
    fail(l.number, q(l.command) + " inside pass " + q(pass().name) + " (declare it before the pass)");
  if (before_commands_only && first_command_line_)
    fail(l.number, q(l.command) + " must come before the first pass, dispatch or barrier (line " +
                       std::to_string(first_command_line_) + ")");
}

void Reader::command(const Line& l) {
  const std::string& c = l.command;
  if (c == "technique") return on_technique(l);
  if (c == "scene") return on_scene(l);
  if (c == "frame") return on_frame(l);
  if (c == "camera") return on_camera(l);
  if (c == "pose") return on_pose(l);
  if (c == "light") return on_light(l);
  if (c == "buffer") return on_buffer(l);
  if (c == "shader") return on_shader(l);
  if (c == "pipeline") return on_pipeline(l);
  if (c == "pass") return on_pass(l);
  if (c == "attachment") return on_attachment(l);
  if (c == "pls") return on_pls(l);
  if (c == "draw") return on_draw(l);
  if (c == "end") return on_end(l);
  if (c == "dispatch") return on_dispatch(l);
  if (c == "barrier") return on_barrier(l);
  if (c == "tbdrsim-trace") fail(l.number, "version header " + q(c) + " repeated");
  fail(l.number, "unknown command " + q(c));
}

void Reader::on_technique(const Line& l) {
  declaration_allowed(l, true);
  if (trace_.technique_line)
    fail(l.number, "duplicate 'technique' line (first at line " + std::to_string(trace_.technique_line) + ")");
  trace_.technique = positional_ident(l, "technique name");
  for (const auto& kv : l.kvs) trace_.options[kv.key] = kv.value;
  trace_.technique_line = l.number;
}

void Reader::on_scene(const Line& l) {
  declaration_allowed(l, true);
  if (have_scene_) fail(l.number, "duplicate 'scene' line (first at line " + std::to_string(trace_.scene.line) + ")");
  if (!l.has_positional) fail(l.number, "'scene' needs a kind after it: atrium or gltf");
  auto kind = parse_scene_kind(l.positional);
  if (!kind) fail(l.number, "unknown scene kind " + q(l.positional) + " (expected atrium or gltf)");
  TraceScene s;
  s.kind = *kind;
  s.line = l.number;
  if (s.kind == SceneKind::Atrium) {
    check_keys(l, {"detail", "hash"});
    s.detail = static_cast<int>(get_u32(l, "detail", kAtriumMaxDetail));
    if (s.detail < kAtriumMinDetail)
      fail(l.number, "detail " + q(require(l, "detail")) + " is out of range (" + std::to_string(kAtriumMinDetail) + ".." +
                         std::to_string(kAtriumMaxDetail) + ", the atrium's detail levels)");
  } else {
    check_keys(l, {"path", "hash"});
    s.path = require(l, "path");
    try {
      check_path_length(s.path, "scene");
    } catch (const InputError& e) {
      fail(l.number, "path " + q(s.path.substr(0, 60)) + "...: " + e.what());
    }
    require(l, "hash");
  }
  if (const auto* h = find(l, "hash")) {
    const bool ok = h->size() == 16 && std::all_of(h->begin(), h->end(), [](char c) {
                      return (c >= '0' && c <= '9') || (c >= 'a' && c <= 'f');
                    });
    if (!ok) fail(l.number, "malformed hash " + q(*h) + " (expected 16 lowercase hex digits)");
    s.content_hash = *h;
  }
  trace_.scene = s;
  have_scene_ = true;
}

void Reader::on_frame(const Line& l) {
  if (have_frame_ && !current_pass_) {
    if (trace_.version < kSequenceVersion)
      fail(l.number, "duplicate 'frame' line (first at line " + std::to_string(trace_.frame.line) +
                         "); a trace of several frames needs version " + std::to_string(kSequenceVersion));
    if (!first_command_line_)
      fail(l.number, "the frame begun at line " + std::to_string(trace_.frame.line) +
                         " has no pass, dispatch or barrier before the next 'frame' line");
    if (frames_.size() + 1 >= kMaxTraceFrames)
      fail(l.number, "more than " + std::to_string(kMaxTraceFrames) + " frames, the most a trace holds (docs/limits.md)");
    next_frame(l.number);
  }
  declaration_allowed(l, true);
  if (have_frame_) fail(l.number, "duplicate 'frame' line (first at line " + std::to_string(trace_.frame.line) + ")");
  no_positional(l);
  check_keys(l, {"width", "height", "samples"});
  TraceFrame f;
  f.width = static_cast<int>(get_u32(l, "width", kMaxFrameSide));
  f.height = static_cast<int>(get_u32(l, "height", kMaxFrameSide));
  if (f.width == 0 || f.height == 0) fail(l.number, "frame width and height must be at least 1");
  f.samples = static_cast<int>(get_u32(l, "samples", 8));
  if (f.samples != 1 && f.samples != 2 && f.samples != 4 && f.samples != 8)
    fail(l.number, "samples " + q(require(l, "samples")) + " must be 1, 2, 4 or 8");
  const std::uint64_t frame_samples = std::uint64_t{static_cast<std::uint32_t>(f.width)} *
                                      static_cast<std::uint32_t>(f.height) * static_cast<std::uint32_t>(f.samples);
  if (frame_samples > kMaxFrameSamples)
    fail(l.number, "frame " + std::to_string(f.width) + "x" + std::to_string(f.height) + " at " +
                       std::to_string(f.samples) + " samples holds " + std::to_string(frame_samples) +
                       " samples; the largest accepted is " + std::to_string(kMaxFrameSamples) + " (docs/limits.md)");
  f.line = l.number;
  if (!frames_.empty()) {
    const TraceFrame& first = frames_.front().frame;
    if (f.width != first.width || f.height != first.height || f.samples != first.samples)
      fail(l.number, "frame " + std::to_string(f.width) + "x" + std::to_string(f.height) + " at " + std::to_string(f.samples) +
                         " samples differs from the first frame's " + std::to_string(first.width) + "x" +
                         std::to_string(first.height) + " at " + std::to_string(first.samples) + " (line " +
                         std::to_string(first.line) + "): the frames of a sequence share one size");
  }
  trace_.frame = f;
  have_frame_ = true;
}

void Reader::on_pose(const Line& l) {
  declaration_allowed(l, true);
  if (trace_.pose) fail(l.number, "duplicate 'pose' line (first at line " + std::to_string(trace_.pose->line) + ")");
  no_positional(l);
  check_keys(l, {"animation", "time"});
  Trace::Pose pose;
  const float animation = get_float(l, "animation");
  if (!(animation >= 0 && animation <= static_cast<float>(kMaxPoseAnimation)) || animation != std::floor(animation)) {
    fail(l.number, "animation " + q(require(l, "animation")) + " must be a whole number from 0 to " + std::to_string(kMaxPoseAnimation) +
                       " (the glTF animation's index)");
  }
  pose.animation = static_cast<int>(animation);
  pose.time_s = get_float(l, "time");
  if (!(pose.time_s >= 0.0 && pose.time_s <= kMaxPoseSeconds)) {
    fail(l.number, "time " + q(require(l, "time")) + " must be from 0 to " + std::to_string(static_cast<long>(kMaxPoseSeconds)) + " seconds");
  }
  pose.line = l.number;
  trace_.pose = pose;
}

void Reader::on_camera(const Line& l) {
  declaration_allowed(l, true);
  if (have_camera_) fail(l.number, "duplicate 'camera' line (first at line " + std::to_string(trace_.camera_line) + ")");
  no_positional(l);
  check_keys(l, {"eye", "target", "up", "fov_y_deg", "near", "far", "name"});
  Camera c;
  c.eye = get_vec3(l, "eye");
  c.target = get_vec3(l, "target");
  c.up = get_vec3(l, "up");
  c.fov_y_deg = get_float(l, "fov_y_deg");
  c.near_plane = get_float(l, "near");
  c.far_plane = get_float(l, "far");
  check_world(l, "eye", c.eye);
  check_world(l, "target", c.target);
  if (c.eye == c.target) fail(l.number, "camera eye and target are the same point");
  if (c.up == glm::vec3(0.0f)) fail(l.number, "camera up vector is zero");
  {
    // In double: the float32 products of the bounds below must not round the test away.
    const glm::dvec3 view = glm::normalize(glm::dvec3(c.target) - glm::dvec3(c.eye));
    const glm::dvec3 up = glm::normalize(glm::dvec3(c.up));
    const double sine = glm::length(glm::cross(view, up));
    if (!(sine >= kMinUpViewSine))
      fail(l.number, "up " + q(require(l, "up")) + " is parallel to the view direction (target - eye): the sine of "
                         "their angle is " + std::to_string(sine) + ", at least " + std::to_string(kMinUpViewSine) +
                         " is needed for a camera basis");
  }
  if (!(c.fov_y_deg >= kMinFovYDeg && c.fov_y_deg <= kMaxFovYDeg))
    fail(l.number, "fov_y_deg " + q(require(l, "fov_y_deg")) + " is out of range [0.01, 179] (degrees)");
  if (!(c.near_plane >= kMinClipDistance && c.near_plane <= kMaxClipDistance))
    fail(l.number, "near " + q(require(l, "near")) + " is out of range [1e-06, 1e+09] (world units)");
  if (!(c.far_plane > c.near_plane && c.far_plane <= kMaxClipDistance))
    fail(l.number, "far " + q(require(l, "far")) + " must be greater than near and at most 1e+09 (world units)");
  if (c.far_plane / c.near_plane > kMaxFarNearRatio)
    fail(l.number, "far/near = " + q(require(l, "far")) + "/" + q(require(l, "near")) + " is above 2^24 = 16777216, " +
                       "the resolution of a 24-bit depth buffer (docs/limits.md)");
  if (const auto* n = find(l, "name")) trace_.camera_name = *n;
  trace_.camera = c;
  trace_.camera_line = l.number;
  have_camera_ = true;
}

void Reader::on_light(const Line& l) {
  declaration_allowed(l, true);
  if (trace_.lights.size() >= kMaxTraceLights)
    fail(l.number, "more than " + std::to_string(kMaxTraceLights) + " lights, the most accepted (docs/limits.md)");
  if (!l.has_positional) fail(l.number, "'light' needs a type after it: point or spot");
  Light light;
  if (l.positional == "point") {
    light.type = Light::Type::Point;
    check_keys(l, {"position", "radius", "color", "intensity"});
  } else if (l.positional == "spot") {
    light.type = Light::Type::Spot;
    check_keys(l, {"position", "radius", "color", "intensity", "direction", "cos_inner", "cos_outer"});
  } else {
    fail(l.number, "unknown light type " + q(l.positional) + " (expected point or spot)");
  }
  light.position = get_vec3(l, "position");
  check_world(l, "position", light.position);
  light.radius = get_float(l, "radius");
  if (!(light.radius > 0.0f && light.radius <= kMaxWorldCoordinate))
    fail(l.number, "radius " + q(require(l, "radius")) + " must be positive and at most 1e+09 (world units)");
  light.color = get_vec3(l, "color");
  if (light.color.x < 0 || light.color.y < 0 || light.color.z < 0)
    fail(l.number, "color " + q(require(l, "color")) + " must not be negative");
  light.intensity = get_float(l, "intensity");
  if (light.intensity < 0) fail(l.number, "intensity " + q(require(l, "intensity")) + " must not be negative");
  if (light.type == Light::Type::Spot) {
    light.direction = get_vec3(l, "direction");
    if (light.direction == glm::vec3(0.0f)) fail(l.number, "spot direction is zero");
    light.cos_inner = get_float(l, "cos_inner");
    light.cos_outer = get_float(l, "cos_outer");
    if (light.cos_inner < -1 || light.cos_inner > 1 || light.cos_outer < -1 || light.cos_outer > 1)
      fail(l.number, "cos_inner and cos_outer must be in [-1, 1]");
    if (light.cos_inner < light.cos_outer)
      fail(l.number, "cos_inner " + q(require(l, "cos_inner")) + " must be at least cos_outer (the inner cone is narrower)");
  }
  trace_.lights.push_back(light);
  trace_.light_lines.push_back(l.number);
}

void Reader::check_new_resource_name(const Line& l, const std::string& name) {
  if (auto it = buffer_lines_.find(name); it != buffer_lines_.end())
    fail(l.number, "duplicate name " + q(name) + ": already a buffer (line " + std::to_string(it->second) + ")");
  if (auto it = images_.find(name); it != images_.end())
    fail(l.number, "duplicate name " + q(name) + ": already an attachment (line " + std::to_string(it->second.line) + ")");
}

void Reader::check_image_buffer_attachment(const Line& l, const Attachment& a) {
  const int line = buffer_lines_.at(a.name);
  const BufferDesc* b = trace_.find_buffer(a.name);
  if (b->content != BufferContent::Image)
    fail(l.number, "duplicate name " + q(a.name) + ": already a buffer (line " + std::to_string(line) +
                       "; only a content=image buffer can be an attachment)");
  if (trace_.version < kImageAttachmentVersion)
    fail(l.number, "attachment " + q(a.name) + " is the image buffer of line " + std::to_string(line) +
                       ", which needs trace version " + std::to_string(kImageAttachmentVersion) + " (this trace is version " +
                       std::to_string(trace_.version) + ")");
  const std::uint64_t bytes = static_cast<std::uint64_t>(trace_.frame.width) * static_cast<std::uint64_t>(trace_.frame.height) *
                              bytes_per_sample(Format::Rgba8);
  if (a.format != Format::Rgba8 || a.samples != 1 || a.usage != AttachmentUsage::Color || a.transient || b->bytes != bytes)
    fail(l.number, "attachment " + q(a.name) + " is the image buffer of line " + std::to_string(line) +
                       ": it must be format=rgba8 samples=1 usage=color, not transient, and the buffer " +
                       std::to_string(bytes) + " bytes (width x height x 4)");
}

void Reader::on_buffer(const Line& l) {
  declaration_allowed(l, false);
  check_keys(l, {"bytes", "traffic", "content", "upload"});
  BufferDesc b;
  b.name = positional_ident(l, "buffer name");
  check_new_resource_name(l, b.name);
  b.bytes = to_u64(l, "bytes", require(l, "bytes"), kMaxBufferBytes);
  if (b.bytes == 0) fail(l.number, "buffer " + q(b.name) + " has bytes=0");
  b.traffic = get_enum(l, "traffic", parse_buffer_traffic);
  b.content = get_enum(l, "content", parse_buffer_content);
  b.upload = get_bool(l, "upload", false);
  if (b.upload && b.bytes > kMaxUploadBufferBytes)
    fail(l.number, "upload=yes buffer " + q(b.name) + " has bytes=" + std::to_string(b.bytes) + "; a CPU-filled buffer "
                   "is read whole, and the largest accepted is " + std::to_string(kMaxUploadBufferBytes) + " (docs/limits.md)");
  b.line = l.number;
  buffer_lines_[b.name] = l.number;
  if (b.upload) written_buffers_.insert(b.name);
  trace_.buffers.push_back(std::move(b));
}

void Reader::on_shader(const Line& l) {
  declaration_allowed(l, false);
  check_keys(l, {"alu_ops", "tex_fetches", "varyings", "light_alu_ops", "light_source", "color_outputs", "pls",
                 "discard", "vertex_alu_ops"});
  ShaderDesc s;
  s.name = positional_ident(l, "shader name");
  if (auto it = shader_lines_.find(s.name); it != shader_lines_.end())
    fail(l.number, "duplicate shader name " + q(s.name) + " (first declared at line " + std::to_string(it->second) + ")");
  s.alu_ops = get_u32(l, "alu_ops", 1000000);
  s.tex_fetches = get_u32(l, "tex_fetches", 10000);
  s.varyings = get_u32(l, "varyings", 128);
  s.light_alu_ops = get_u32(l, "light_alu_ops", 1000000);
  s.light_source = get_enum(l, "light_source", parse_light_source);
  s.color_outputs = get_u32(l, "color_outputs", 8);
  s.pls = get_enum(l, "pls", parse_pls_access, std::optional(PlsAccess::None));
  s.discard = get_bool(l, "discard", false);
  if (find(l, "vertex_alu_ops")) {
    need_version(l, "vertex_alu_ops", kVertexCostVersion);
    s.vertex_alu_ops = get_u32(l, "vertex_alu_ops", 1000000);
  }
  if (s.light_source == LightSource::None && s.light_alu_ops != 0)
    fail(l.number, "light_alu_ops=" + std::to_string(s.light_alu_ops) + " with light_source=none");
  s.line = l.number;
  shader_lines_[s.name] = l.number;
  trace_.shaders.push_back(std::move(s));
}

void Reader::on_pipeline(const Line& l) {
  declaration_allowed(l, false);
  check_keys(l, {"shader", "depth_test", "depth_write", "depth_compare", "stencil_test", "stencil_compare",
                 "stencil_fail_op", "stencil_depth_fail_op", "stencil_pass_op", "stencil_ref", "blend", "cull",
                 "alpha"});
  PipelineState p;
  p.name = positional_ident(l, "pipeline name");
  if (auto it = pipeline_lines_.find(p.name); it != pipeline_lines_.end())
    fail(l.number, "duplicate pipeline name " + q(p.name) + " (first declared at line " + std::to_string(it->second) + ")");
  p.shader = get_ident(l, "shader");
  if (!shader_lines_.count(p.shader)) fail(l.number, "undeclared shader " + q(p.shader));
  p.depth_test = get_bool(l, "depth_test");
  p.depth_write = get_bool(l, "depth_write");
  p.depth_compare = get_enum(l, "depth_compare", parse_compare_op, std::optional(CompareOp::Less));
  p.stencil_test = get_bool(l, "stencil_test", false);
  p.stencil_compare = get_enum(l, "stencil_compare", parse_compare_op, std::optional(CompareOp::Always));
  p.stencil_fail_op = get_enum(l, "stencil_fail_op", parse_stencil_op, std::optional(StencilOp::Keep));
  p.stencil_depth_fail_op = get_enum(l, "stencil_depth_fail_op", parse_stencil_op, std::optional(StencilOp::Keep));
  p.stencil_pass_op = get_enum(l, "stencil_pass_op", parse_stencil_op, std::optional(StencilOp::Keep));
  p.stencil_ref = get_u32_or(l, "stencil_ref", 0, 255);
  p.blend = get_enum(l, "blend", parse_blend_mode);
  p.cull = get_enum(l, "cull", parse_cull_mode);
  p.alpha = get_enum(l, "alpha", parse_alpha_override, std::optional(AlphaOverride::Material));
  if (p.depth_write && !p.depth_test)
    fail(l.number, "depth_write=yes needs depth_test=yes (use depth_compare=always to write unconditionally)");
  p.line = l.number;
  pipeline_lines_[p.name] = l.number;
  trace_.pipelines.push_back(std::move(p));
}

void Reader::on_pass(const Line& l) {
  if (current_pass_)
    fail(l.number, "pass " + q(l.positional) + " inside pass " + q(pass().name) + " (missing 'end' for the pass at line " +
                       std::to_string(pass().line) + ")");
  check_keys(l, {"area"});
  PassDesc p;
  p.name = positional_ident(l, "pass name");
  p.area = get_rect(l, "area", kPassAreaVersion);
  if (p.area && (p.area->x1 > static_cast<std::uint32_t>(trace_.frame.width) ||
                 p.area->y1 > static_cast<std::uint32_t>(trace_.frame.height)))
    fail(l.number, "area " + q(require(l, "area")) + " reaches beyond the frame (" + std::to_string(trace_.frame.width) +
                       "x" + std::to_string(trace_.frame.height) +
                       "): the frame is the largest surface, and every pass's area lies inside it");
  if (auto it = pass_lines_.find(p.name); it != pass_lines_.end())
    fail(l.number, "duplicate pass name " + q(p.name) + " (first at line " + std::to_string(it->second) + ")");
  count_command(l);
  p.line = l.number;
  pass_lines_[p.name] = l.number;
  if (!first_command_line_) first_command_line_ = l.number;
  trace_.commands.emplace_back(std::move(p));
  current_pass_ = trace_.commands.size() - 1;
  layout_done_ = false;
}

void Reader::on_attachment(const Line& l) {
  if (!current_pass_) fail(l.number, "'attachment' outside a pass (attachments are declared inside 'pass ... end')");
  if (layout_done_) fail(l.number, "'attachment' after the first draw of pass " + q(pass().name));
  check_keys(l, {"format", "samples", "load", "store", "usage", "transient", "resolve"});
  Attachment a;
  a.name = positional_ident(l, "attachment name");
  if (const auto* prev = pass().find_attachment(a.name))
    fail(l.number, "duplicate attachment " + q(a.name) + " in pass " + q(pass().name) + " (line " +
                       std::to_string(prev->line) + ")");
  a.format = get_enum(l, "format", parse_format);
  a.samples = get_u32(l, "samples", 8);
  if (a.samples != 1 && a.samples != 2 && a.samples != 4 && a.samples != 8)
    fail(l.number, "samples " + q(require(l, "samples")) + " must be 1, 2, 4 or 8");
  a.load = get_enum(l, "load", parse_load_op);
  a.store = get_enum(l, "store", parse_store_op);
  a.usage = get_enum(l, "usage", parse_attachment_usage);
  a.transient = get_bool(l, "transient", false);
  if (find(l, "resolve")) a.resolve = get_ident(l, "resolve");
  a.line = l.number;

  if ((a.usage == AttachmentUsage::Depth) != is_depth_format(a.format))
    fail(l.number, "usage=" + std::string(to_string(a.usage)) + " does not fit format " + q(to_string(a.format)) +
                       (a.usage == AttachmentUsage::Depth ? " (depth needs d16, d24s8, d32f or d32fs8)"
                                                          : " (a depth format needs usage=depth)"));
  if (a.usage == AttachmentUsage::Depth && pass().depth_attachment())
    fail(l.number, "second depth attachment " + q(a.name) + " in pass " + q(pass().name));
  if (a.transient && (a.load == LoadOp::Load || a.store == StoreOp::Store))
    fail(l.number, "transient attachment " + q(a.name) + " cannot use load=load or store=store (it never reaches DRAM)");
  if (!a.resolve.empty() && a.samples == 1)
    fail(l.number, "attachment " + q(a.name) + " has resolve=" + a.resolve + " but only 1 sample");

  if (buffer_lines_.count(a.name)) check_image_buffer_attachment(l, a);

  if (auto it = images_.find(a.name); it != images_.end()) {
    const Image& img = it->second;
    if (img.format != a.format || img.samples != a.samples || img.usage != a.usage)
      fail(l.number, "attachment " + q(a.name) + " redeclared as " + to_string(a.format) + "/" +
                         std::to_string(a.samples) + " samples/" + to_string(a.usage) + "; line " +
                         std::to_string(img.line) + " declared it " + to_string(img.format) + "/" +
                         std::to_string(img.samples) + " samples/" + to_string(img.usage));
  } else {
    // An image buffer a dispatch wrote is in DRAM before any pass stores it.
    images_.emplace(a.name, Image{a.format, a.samples, a.usage, l.number, written_buffers_.count(a.name) > 0});
  }
  if (a.load == LoadOp::Load) {
    if (!images_.at(a.name).in_dram)
      fail(l.number, "attachment " + q(a.name) + " has load=load but no earlier pass or dispatch stored it");
    check_hazard(l, a.name, false);
  }
  pass().attachments.push_back(std::move(a));
}

void Reader::on_pls(const Line& l) {
  if (!current_pass_) fail(l.number, "'pls' outside a pass");
  if (layout_done_) fail(l.number, "'pls' after the first draw of pass " + q(pass().name));
  check_keys(l, {"format"});
  PlsVariable v;
  v.name = positional_ident(l, "pixel local storage variable name");
  for (const auto& other : pass().pls)
    if (other.name == v.name)
      fail(l.number, "duplicate pixel local storage variable " + q(v.name) + " (line " + std::to_string(other.line) + ")");
  v.format = get_enum(l, "format", parse_format);
  if (is_depth_format(v.format)) fail(l.number, "pixel local storage cannot use depth format " + q(to_string(v.format)));
  v.line = l.number;
  pass().pls.push_back(std::move(v));
}

// Checks of the pass layout that need all attachments: resolve targets, sample counts, PLS with MSAA.
void Reader::finish_layout() {
  if (layout_done_) return;
  layout_done_ = true;
  const PassDesc& p = pass();
  if (p.attachments.empty()) fail(p.line, "pass " + q(p.name) + " declares no attachment");
  std::uint32_t samples = 0;
  int samples_line = 0;
  for (const auto& a : p.attachments) {
    if (!a.resolve.empty()) {
      const Attachment* t = p.find_attachment(a.resolve);
      if (!t) fail(a.line, "resolve target " + q(a.resolve) + " is not an attachment of pass " + q(p.name));
      if (t->samples != 1) fail(a.line, "resolve target " + q(a.resolve) + " must have samples=1");
      if (t->format != a.format || t->usage != a.usage)
        fail(a.line, "resolve target " + q(a.resolve) + " must have the same format and usage as " + q(a.name));
    }
    if (p.is_resolve_target(a)) continue;
    if (samples == 0) {
      samples = a.samples;
      samples_line = a.line;
    } else if (a.samples != samples) {
      fail(a.line, "attachment " + q(a.name) + " has " + std::to_string(a.samples) + " samples but line " +
                       std::to_string(samples_line) + " has " + std::to_string(samples) +
                       " (all attachments of a pass but resolve targets share one sample count)");
    }
  }
  if (!p.pls.empty() && samples > 1)
    fail(p.pls.front().line, "pixel local storage is not usable with MSAA (pass " + q(p.name) + " has " +
                                 std::to_string(samples) + " samples)");
}

void Reader::check_hazard(const Line& l, const std::string& name, bool by_dispatch) {
  auto it = pending_.find(name);
  if (it == pending_.end()) return;
  if (it->second.by_dispatch || by_dispatch)
    fail(l.number, q(name) + " is read here but was written at line " + std::to_string(it->second.line) +
                       " with no barrier in between (add 'barrier resources=" + name + "')");
}

void Reader::read_resource(const Line& l, const std::string& name, bool by_dispatch) {
  if (buffer_lines_.count(name)) {
    if (!written_buffers_.count(name))
      fail(l.number, "buffer " + q(name) + " is read before anything wrote it (declare it upload=yes or write it in a dispatch)");
  } else if (auto it = images_.find(name); it != images_.end()) {
    if (current_pass_ && pass().find_attachment(name))
      fail(l.number, "attachment " + q(name) + " is read as a texture inside its own pass " + q(pass().name) +
                         " (use fetch= to read it on chip)");
    if (!it->second.in_dram)
      fail(l.number, "attachment " + q(name) + " used outside its pass: no earlier pass stores it (store=store) "
                                               "and no dispatch writes it");
  } else {
    fail(l.number, "undeclared buffer or attachment " + q(name));
  }
  check_hazard(l, name, by_dispatch);
}

void Reader::on_draw(const Line& l) {
  if (!current_pass_) fail(l.number, "'draw' outside a pass");
  finish_layout();
  const PassDesc& p = pass();
  DrawCmd d;
  d.line = l.number;
  if (!l.has_positional) fail(l.number, "'draw' needs a geometry kind: scene, fullscreen, light_spheres or light_quads");
  auto kind = parse_geometry_kind(l.positional);
  if (!kind) fail(l.number, "unknown geometry kind " + q(l.positional) + " (expected scene, fullscreen, light_spheres or light_quads)");
  d.geometry = *kind;
  switch (d.geometry) {
    case GeometryKind::Scene:
      check_keys(l, {"pipeline", "subset", "submesh", "material", "lights", "reads", "fetch", "scissor", "cull_min",
                     "cull_max"});
      break;
    case GeometryKind::LightSpheres: check_keys(l, {"pipeline", "subdivisions", "lights", "reads", "fetch", "scissor"}); break;
    default: check_keys(l, {"pipeline", "lights", "reads", "fetch", "scissor"}); break;
  }
  if (++draws_ > kMaxTraceDraws)
    fail(l.number, "more than " + std::to_string(kMaxTraceDraws) + " draws, the most accepted (docs/limits.md)");
  d.pipeline = get_ident(l, "pipeline");
  const PipelineState* ps = trace_.find_pipeline(d.pipeline);
  if (!ps) fail(l.number, "undeclared pipeline " + q(d.pipeline));
  const ShaderDesc* sh = trace_.find_shader(ps->shader);

  if (d.geometry == GeometryKind::Scene) {
    const int selectors = (find(l, "subset") != nullptr) + (find(l, "submesh") != nullptr) + (find(l, "material") != nullptr);
    if (selectors > 1) fail(l.number, "give only one of subset=, submesh= and material=");
    d.subset = get_enum(l, "subset", parse_scene_subset, std::optional(SceneSubset::All));
    if (const auto* v = find(l, "submesh")) d.submesh = *v;
    if (const auto* v = find(l, "material")) d.material = *v;
  }
  if (d.geometry == GeometryKind::LightSpheres) d.subdivisions = get_u32_or(l, "subdivisions", 1, 6);
  d.lights = get_lights(l, "lights");
  d.scissor = get_rect(l, "scissor", kDrawBoundsVersion);
  d.cull = get_cull_box(l);
  d.reads = get_ident_list(l, "reads");
  d.fetch = get_ident_list(l, "fetch");

  for (const auto& name : d.reads) read_resource(l, name, false);
  for (const auto& name : d.fetch) {
    if (p.find_attachment(name)) continue;
    if (images_.count(name)) fail(l.number, "attachment " + q(name) + " used outside its pass (fetch= reads only attachments of pass " + q(p.name) + ")");
    fail(l.number, "undeclared attachment " + q(name) + " in fetch=");
  }

  const auto targets = p.color_targets();
  if (sh->color_outputs > targets.size())
    fail(l.number, "shader " + q(sh->name) + " writes " + std::to_string(sh->color_outputs) + " color outputs but pass " +
                       q(p.name) + " has " + std::to_string(targets.size()) + " color attachments");
  const Attachment* depth = p.depth_attachment();
  if ((ps->depth_test || ps->depth_write) && !depth)
    fail(l.number, "pipeline " + q(ps->name) + " tests depth but pass " + q(p.name) + " has no depth attachment");
  if (ps->stencil_test && !(depth && has_stencil(depth->format)))
    fail(l.number, "pipeline " + q(ps->name) + " tests stencil but pass " + q(p.name) + " has no stencil format");
  if ((sh->pls != PlsAccess::None || sh->light_source == LightSource::PlsStack) && p.pls.empty())
    fail(l.number, "shader " + q(sh->name) + " uses pixel local storage but pass " + q(p.name) + " declares none");
  const bool proxy_geometry = d.geometry == GeometryKind::LightSpheres || d.geometry == GeometryKind::LightQuads;
  if (sh->light_source == LightSource::Proxy && !proxy_geometry)
    fail(l.number, "shader " + q(sh->name) + " has light_source=proxy but draws " + q(to_string(d.geometry)) +
                       " (proxy needs light_spheres or light_quads)");
  pass().draws.push_back(std::move(d));
}

void Reader::on_end(const Line& l) {
  if (!current_pass_) fail(l.number, "'end' without an open pass");
  if (l.has_positional || !l.kvs.empty()) fail(l.number, "'end' takes nothing after it");
  finish_layout();
  PassDesc& p = pass();
  p.end_line = l.number;
  for (const auto& a : p.attachments) {
    if (a.store != StoreOp::Store) continue;
    images_.at(a.name).in_dram = true;
    if (buffer_lines_.count(a.name)) written_buffers_.insert(a.name);  // an image buffer's frame
    pending_[a.name] = PendingWrite{l.number, false};
  }
  current_pass_.reset();
}

void Reader::on_dispatch(const Line& l) {
  if (current_pass_)
    fail(l.number, "'dispatch' inside pass " + q(pass().name) + " (close the pass with 'end' first)");
  if (!first_command_line_) first_command_line_ = l.number;
  count_command(l);
  DispatchCmd d;
  const std::string kernel = positional_ident(l, "kernel name");
  const std::optional<ComputeKernel> parsed = parse_compute_kernel(kernel);
  if (!parsed) fail(l.number, "unknown kernel " + q(kernel) + " (known: " + compute_kernel_list() + ")");
  d.kernel = *parsed;
  d.line = l.number;
  get_u32x3(l, "groups", d.groups);
  get_u32x3(l, "group_size", d.group_size);
  for (const std::uint32_t g : d.groups)
    if (g > kMaxDispatchGroups)
      fail(l.number, "groups=" + require(l, "groups") + " has a component above " + std::to_string(kMaxDispatchGroups) +
                         " (Vulkan maxComputeWorkGroupCount)");
  const std::uint64_t invocations = std::uint64_t{d.group_size[0]} * d.group_size[1] * d.group_size[2];
  if (invocations > kMaxWorkGroupInvocations)
    fail(l.number, "group_size=" + require(l, "group_size") + " is " + std::to_string(invocations) +
                       " invocations per group; at most " + std::to_string(kMaxWorkGroupInvocations) +
                       " (maxComputeWorkGroupInvocations)");
  d.reads = get_ident_list(l, "reads");
  d.writes = get_ident_list(l, "writes");
  for (const auto& kv : l.kvs)
    if (kv.key != "groups" && kv.key != "group_size" && kv.key != "reads" && kv.key != "writes")
      d.params[kv.key] = kv.value;
  for (const auto& name : d.reads) read_resource(l, name, true);
  for (const auto& name : d.writes) {
    if (buffer_lines_.count(name)) {
      written_buffers_.insert(name);
      if (auto it = images_.find(name); it != images_.end()) it->second.in_dram = true;  // an image buffer's frame
    } else if (auto it = images_.find(name); it != images_.end()) {
      it->second.in_dram = true;
    } else {
      fail(l.number, "undeclared buffer or attachment " + q(name) + " in writes=");
    }
    pending_[name] = PendingWrite{l.number, true};
  }
  trace_.commands.emplace_back(std::move(d));
}

void Reader::on_barrier(const Line& l) {
  if (current_pass_) fail(l.number, "'barrier' inside pass " + q(pass().name) + " (close the pass with 'end' first)");
  no_positional(l);
  check_keys(l, {"resources"});
  if (!first_command_line_) first_command_line_ = l.number;
  count_command(l);
  BarrierCmd b;
  b.line = l.number;
  if (require(l, "resources") == "all") {
    b.all = true;
    pending_.clear();
  } else {
    b.resources = get_ident_list(l, "resources");
    for (const auto& name : b.resources) {
      if (!buffer_lines_.count(name) && !images_.count(name))
        fail(l.number, "undeclared buffer or attachment " + q(name) + " in resources=");
      pending_.erase(name);
    }
  }
  trace_.commands.emplace_back(std::move(b));
}

/// The most workgroups one dispatch may launch per pixel of its frame. Every kernel works on the
/// frame's pixels, tiles or clusters (docs/kernels.md); the most a generator launches is
/// cluster_light_assign with 4-pixel tiles (1/16 of a pixel each) and 4,096 depth slices: 256 per
/// pixel. Groups beyond it find no work, and the count was recorded as if they ran
/// (65535^3 = 2.8e14 workgroups on a 320x180 frame).
constexpr std::uint64_t kMaxWorkgroupsPerPixel = 256;

void Reader::finish(int last_line) {
  if (current_pass_)
    fail(pass().line, "pass " + q(pass().name) + " is not closed (missing 'end' before the end of the file)");
  finish_frame(last_line);
}

void Reader::next_frame(int frame_line) {
  finish_frame(frame_line - 1);
  // What a frame declared stays declared; what it did (its commands and what they wrote, its
  // camera and lights) is its own: each frame replays on its own, so it writes what it reads.
  trace_.commands.clear();
  trace_.lights.clear();
  trace_.light_lines.clear();
  trace_.camera = Camera{};
  trace_.camera_name.clear();
  trace_.camera_line = 0;
  trace_.pose.reset();
  have_frame_ = false;
  have_camera_ = false;
  first_command_line_ = 0;
  pass_lines_.clear();
  images_.clear();
  written_buffers_.clear();
  for (const BufferDesc& b : trace_.buffers) {
    if (b.upload) written_buffers_.insert(b.name);  // the CPU fills it again before each frame
  }
  pending_.clear();
}

void Reader::finish_frame(int last_line) {
  const int at = last_line > 0 ? last_line : 1;
  if (!have_scene_) fail(at, "missing required 'scene' line");
  if (!have_frame_) fail(at, "missing required 'frame' line");
  if (!have_camera_) fail(at, "missing required 'camera' line");
  const std::uint64_t pixels = static_cast<std::uint64_t>(trace_.frame.width) * static_cast<std::uint64_t>(trace_.frame.height);
  for (const auto& cmd : trace_.commands) {
    const auto* d = std::get_if<DispatchCmd>(&cmd);
    if (d == nullptr) continue;
    const std::uint64_t groups = std::uint64_t{d->groups[0]} * d->groups[1] * d->groups[2];
    if (groups > kMaxWorkgroupsPerPixel * pixels)
      fail(d->line, "dispatch of " + std::to_string(groups) + " workgroups on a " + std::to_string(trace_.frame.width) +
                        "x" + std::to_string(trace_.frame.height) + " frame; at most " +
                        std::to_string(kMaxWorkgroupsPerPixel) + " per pixel (" +
                        std::to_string(kMaxWorkgroupsPerPixel * pixels) +
                        "): the kernels work on the frame's pixels, tiles and clusters (docs/limits.md)");
  }
  const std::uint64_t light_bytes = kLightBufferBytesPerLight * trace_.lights.size();
  for (const auto& b : trace_.buffers) {
    if (b.content == BufferContent::Lights && b.bytes < light_bytes)
      fail(b.line, "buffer " + q(b.name) + " holds the lights (content=lights) but has bytes=" + std::to_string(b.bytes) +
                       "; the trace's " + std::to_string(trace_.lights.size()) + " lights need " +
                       std::to_string(light_bytes) + " (" + std::to_string(kLightBufferBytesPerLight) + " bytes each)");
  }
  const std::uint64_t declarations = trace_.buffers.size() + trace_.shaders.size() + trace_.pipelines.size();
  held_declarations_ += declarations;
  if (held_declarations_ > kMaxSequenceDeclarations)
    fail(trace_.frame.line, "frame " + std::to_string(frames_.size()) + " brings the declarations the sequence's frames hold to " +
                                std::to_string(held_declarations_) + " (" + std::to_string(declarations) +
                                " per frame); at most " + std::to_string(kMaxSequenceDeclarations) + " (docs/limits.md)");
  frames_.push_back(trace_);
}

void Reader::count_command(const Line& l) {
  if (++commands_ > kMaxTraceCommands)
    fail(l.number, "more than " + std::to_string(kMaxTraceCommands) +
                       " passes, dispatches and barriers, the most accepted (docs/limits.md)");
}

void Reader::check_world(const Line& l, std::string_view key, const glm::vec3& v) const {
  for (int c = 0; c < 3; ++c)
    if (!(std::fabs(v[c]) <= kMaxWorldCoordinate))
      fail(l.number, std::string(key) + "=" + require(l, key) + " has a component beyond +-1e+09 world units (docs/limits.md)");
}

/// std::getline with a bound: reads the next line of `in` into `out` (without its '\n') and returns
/// false at the end of the input. A line longer than `max_bytes` stops the read as soon as the bound
/// is passed (`too_long` set), so a stream without newlines (/dev/zero) is never held whole.
bool read_line_bounded(std::istream& in, std::string& out, std::uint64_t max_bytes, bool& too_long) {
  // Chunks of this many bytes are read at once (istream::getline scans them for the newline).
  constexpr std::streamsize kChunkBytes = 1 << 16;
  char buf[kChunkBytes];
  out.clear();
  too_long = false;
  bool any = false;
  for (;;) {
    in.getline(buf, kChunkBytes);
    const std::streamsize n = in.gcount();
    if (!in.fail()) {  // a whole line: the newline was extracted and counted
      out.append(buf, static_cast<std::size_t>(n > 0 ? n - 1 : 0));
      too_long = out.size() > max_bytes;
      return true;
    }
    if (in.bad()) return false;
    any |= n > 0;
    out.append(buf, static_cast<std::size_t>(n));
    if (in.eof()) return any;  // the last line has no newline (or the input ended)
    in.clear();                // the chunk filled without a newline: read on
    if (out.size() > max_bytes) {
      too_long = true;
      return true;
    }
  }
}

/// The longest trace line read (bytes), checked while the line is read: the longest line a
/// generator writes is a draw whose `lights=` lists 1,000,000 scattered lights one by one (at most
/// 7 bytes each, 6.9 MB); the bound keeps a stream without newlines (/dev/zero) to 16 MiB held.
constexpr std::uint64_t kMaxTraceLineBytes = 16ull << 20;

std::vector<Trace> Reader::run(std::istream& in) {
  std::string text;
  int number = 0;
  bool have_header = false;
  Line l;
  std::uint64_t bytes = 0;
  bool too_long = false;
  while (read_line_bounded(in, text, std::min(kMaxTraceLineBytes, kMaxTraceBytes - std::min(bytes, kMaxTraceBytes)),
                           too_long)) {
    ++number;
    bytes += text.size() + 1;
    if (too_long && text.size() > kMaxTraceLineBytes)
      fail(number, "line " + std::to_string(number) + " is longer than " + std::to_string(kMaxTraceLineBytes) +
                       " bytes, the longest accepted (docs/limits.md)");
    if (too_long || bytes > kMaxTraceBytes + 1)
      fail(number, "the trace is longer than " + std::to_string(kMaxTraceBytes) + " bytes, the largest accepted (docs/limits.md)");
    if (!text.empty() && text.back() == '\r') text.pop_back();
    if (!have_header) {
      text = std::string(strip_utf8_bom(text));
      header(text);
      have_header = true;
      continue;
    }
    if (!tokenize(text, number, l)) continue;
    command(l);
  }
  if (in.bad()) fail(number, "read error");
  if (!have_header) fail(1, "empty file: expected 'tbdrsim-trace " + std::to_string(kTraceVersion) + "' on the first line");
  finish(number);
  return std::move(frames_);
}

}  // namespace

std::vector<Trace> parse_trace_frames(std::istream& in, const std::string& name) { return Reader(name).run(in); }

Trace parse_trace(std::istream& in, const std::string& name) {
  std::vector<Trace> frames = parse_trace_frames(in, name);
  if (frames.size() > 1)
    throw InputError(name, frames[1].frame.line,
                     "the trace holds a sequence of " + std::to_string(frames.size()) +
                         " frames; this command reads one frame ('tbdrsim run' replays sequences)");
  return std::move(frames.front());
}

namespace {
/// Opens a trace file for reading, refusing what cannot be a trace (a folder, a file too large).
std::ifstream open_trace_file(const std::string& path) {
  // Streams (a FIFO, /dev/stdin) are read too: the bounded line reader keeps them to kMaxTraceBytes.
  check_input_file(path, "trace", /*allow_special=*/true);
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, "cannot open the trace file");
  std::error_code ec;
  const auto size = std::filesystem::file_size(path, ec);
  if (!ec && size > kMaxTraceBytes) {
    throw InputError(path, "the trace is " + std::to_string(size) + " bytes; the largest accepted is " +
                               std::to_string(kMaxTraceBytes) + " (docs/limits.md)");
  }
  return in;
}
}  // namespace

Trace read_trace(const std::string& path) {
  std::ifstream in = open_trace_file(path);
  return parse_trace(in, path);
}

std::vector<Trace> read_trace_frames(const std::string& path) {
  std::ifstream in = open_trace_file(path);
  return parse_trace_frames(in, path);
}

}  // namespace tbdr
