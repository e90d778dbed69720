#include "scene/gltf_loader.hpp"

// Debian's libtinygltf is a compiled library built with its default options (stb_image for
// images, nlohmann json, file system callbacks): include the header without
// TINYGLTF_IMPLEMENTATION and without any TINYGLTF_NO_* define so the class layout matches.
#include <tiny_gltf.h>
// The stb_image implementation lives in Debian's libstb; only the declarations are needed.
#include <stb/stb_image.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <iterator>
#include <map>
#include <sstream>

#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>
#include <glm/gtc/type_ptr.hpp>
#include <nlohmann/json.hpp>

#include "kernel/errors.hpp"
#include "kernel/hash.hpp"
#include "kernel/params.hpp"

namespace tbdr {

namespace {

namespace fs = std::filesystem;

// ---------------------------------------------------------------------------------------------
// Image headers

std::uint32_t be32(const std::uint8_t* p) {
  return (std::uint32_t{p[0]} << 24) | (std::uint32_t{p[1]} << 16) | (std::uint32_t{p[2]} << 8) | p[3];
}
std::uint32_t le32(const std::uint8_t* p) {
  return (std::uint32_t{p[3]} << 24) | (std::uint32_t{p[2]} << 16) | (std::uint32_t{p[1]} << 8) | p[0];
}
std::uint16_t be16(const std::uint8_t* p) { return static_cast<std::uint16_t>((p[0] << 8) | p[1]); }
std::uint16_t le16(const std::uint8_t* p) { return static_cast<std::uint16_t>((p[1] << 8) | p[0]); }

std::optional<ImageHeader> parse_png(const std::uint8_t* d, std::size_t n) {
  // Signature (8) + IHDR chunk: length (4) "IHDR" (4) width (4) height (4) depth (1) color type (1).
  if (n < 8 + 8 + 13 || std::memcmp(d + 12, "IHDR", 4) != 0) return std::nullopt;
  ImageHeader h;
  h.format = "png";
  h.width = static_cast<int>(be32(d + 16));
  h.height = static_cast<int>(be32(d + 20));
  switch (d[25]) {
    case 0: h.channels = 1; break;
    case 2: h.channels = 3; break;
    case 3: h.channels = 3; break;
    case 4: h.channels = 2; break;
    case 6: h.channels = 4; break;
    default: return std::nullopt;
  }
  if (d[25] == 3) {
    // A palette image has alpha when a tRNS chunk comes before the image data.
    std::size_t pos = 8;
    while (pos + 8 <= n) {
      const std::uint32_t len = be32(d + pos);
      if (std::memcmp(d + pos + 4, "tRNS", 4) == 0) {
        h.channels = 4;
        break;
      }
      if (std::memcmp(d + pos + 4, "IDAT", 4) == 0) break;
      if (len > n) break;
      pos += 12 + static_cast<std::size_t>(len);
    }
  }
  if (h.width <= 0 || h.height <= 0) return std::nullopt;
  return h;
}

std::optional<ImageHeader> parse_jpeg(const std::uint8_t* d, std::size_t n) {
  std::size_t pos = 2;  // after SOI
  while (pos + 4 <= n) {
    if (d[pos] != 0xFF) return std::nullopt;
    while (pos < n && d[pos] == 0xFF) ++pos;  // fill bytes
    if (pos >= n) return std::nullopt;
    const std::uint8_t marker = d[pos++];
    if (marker == 0x01 || (marker >= 0xD0 && marker <= 0xD7)) continue;  // no length
    if (marker == 0xD9 || marker == 0xDA) return std::nullopt;          // EOI/SOS before a SOF
    if (pos + 2 > n) return std::nullopt;
    const std::size_t len = be16(d + pos);
    if (len < 2) return std::nullopt;
    const bool sof = marker >= 0xC0 && marker <= 0xCF && marker != 0xC4 && marker != 0xC8 && marker != 0xCC;
    if (sof) {
      if (pos + 8 > n) return std::nullopt;
      ImageHeader h;
      h.format = "jpeg";
      h.height = be16(d + pos + 3);
      h.width = be16(d + pos + 5);
      h.channels = d[pos + 7];
      if (h.width <= 0 || h.height <= 0) return std::nullopt;
      return h;
    }
    pos += len;
  }
  return std::nullopt;
}

// ---------------------------------------------------------------------------------------------
// Small helpers

std::string quoted_name(const std::string& name) { return name.empty() ? std::string() : " '" + name + "'"; }

std::string url_decode(const std::string& s) {
  std::string out;
  out.reserve(s.size());
  auto hex = [](char c) -> int {
    if (c >= '0' && c <= '9') return c - '0';
    if (c >= 'a' && c <= 'f') return c - 'a' + 10;
    if (c >= 'A' && c <= 'F') return c - 'A' + 10;
    return -1;
  };
  for (std::size_t i = 0; i < s.size(); ++i) {
    if (s[i] == '%' && i + 2 < s.size() && hex(s[i + 1]) >= 0 && hex(s[i + 2]) >= 0) {
      out.push_back(static_cast<char>(hex(s[i + 1]) * 16 + hex(s[i + 2])));
      i += 2;
    } else {
      out.push_back(s[i]);
    }
  }
  return out;
}

bool is_data_uri(const std::string& uri) { return uri.rfind("data:", 0) == 0; }

std::vector<std::uint8_t> read_all(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, "cannot open file");
  return std::vector<std::uint8_t>(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

int component_bytes(int ct) {
  switch (ct) {
    case TINYGLTF_COMPONENT_TYPE_BYTE:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: return 1;
    case TINYGLTF_COMPONENT_TYPE_SHORT:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: return 2;
    case TINYGLTF_COMPONENT_TYPE_INT:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT:
    case TINYGLTF_COMPONENT_TYPE_FLOAT: return 4;
    default: return 0;
  }
}

int type_components(int type) {
  switch (type) {
    case TINYGLTF_TYPE_SCALAR: return 1;
    case TINYGLTF_TYPE_VEC2: return 2;
    case TINYGLTF_TYPE_VEC3: return 3;
    case TINYGLTF_TYPE_VEC4: return 4;
    case TINYGLTF_TYPE_MAT2: return 4;
    case TINYGLTF_TYPE_MAT3: return 9;
    case TINYGLTF_TYPE_MAT4: return 16;
    default: return 0;
  }
}

const char* component_name(int ct) {
  switch (ct) {
    case TINYGLTF_COMPONENT_TYPE_BYTE: return "BYTE";
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: return "UNSIGNED_BYTE";
    case TINYGLTF_COMPONENT_TYPE_SHORT: return "SHORT";
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: return "UNSIGNED_SHORT";
    case TINYGLTF_COMPONENT_TYPE_INT: return "INT";
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: return "UNSIGNED_INT";
    case TINYGLTF_COMPONENT_TYPE_FLOAT: return "FLOAT";
    default: return "unknown component type";
  }
}

const char* type_name(int type) {
  switch (type) {
    case TINYGLTF_TYPE_SCALAR: return "SCALAR";
    case TINYGLTF_TYPE_VEC2: return "VEC2";
    case TINYGLTF_TYPE_VEC3: return "VEC3";
    case TINYGLTF_TYPE_VEC4: return "VEC4";
    case TINYGLTF_TYPE_MAT2: return "MAT2";
    case TINYGLTF_TYPE_MAT3: return "MAT3";
    case TINYGLTF_TYPE_MAT4: return "MAT4";
    default: return "unknown type";
  }
}

const char* mode_name(int mode) {
  switch (mode) {
    case TINYGLTF_MODE_POINTS: return "POINTS";
    case TINYGLTF_MODE_LINE: return "LINES";
    case TINYGLTF_MODE_LINE_LOOP: return "LINE_LOOP";
    case TINYGLTF_MODE_LINE_STRIP: return "LINE_STRIP";
    case TINYGLTF_MODE_TRIANGLES: return "TRIANGLES";
    case TINYGLTF_MODE_TRIANGLE_STRIP: return "TRIANGLE_STRIP";
    case TINYGLTF_MODE_TRIANGLE_FAN: return "TRIANGLE_FAN";
    default: return "unknown";
  }
}

/// Accessors larger than this (elements) are rejected before anything is allocated.
constexpr std::size_t max_accessor_elements = std::size_t{1} << 28;
/// Base colour images are decoded only up to this many texels (a 8192 x 8192 texture, 256 MiB as RGBA8).
constexpr std::size_t max_decoded_texels = std::size_t{1} << 26;

// Reads one component as a double (exact for every glTF component type).
double read_component(const unsigned char* p, int ct, bool normalized) {
  switch (ct) {
    case TINYGLTF_COMPONENT_TYPE_FLOAT: {
      float f;
      std::memcpy(&f, p, 4);
      return f;
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: return normalized ? p[0] / 255.0 : p[0];
    case TINYGLTF_COMPONENT_TYPE_BYTE: {
      const auto v = static_cast<std::int8_t>(p[0]);
      return normalized ? std::max(v / 127.0, -1.0) : v;
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
      std::uint16_t v;
      std::memcpy(&v, p, 2);
      return normalized ? v / 65535.0 : v;
    }
    case TINYGLTF_COMPONENT_TYPE_SHORT: {
      std::int16_t v;
      std::memcpy(&v, p, 2);
      return normalized ? std::max(v / 32767.0, -1.0) : v;
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: {
      std::uint32_t v;
      std::memcpy(&v, p, 4);
      return v;
    }
    case TINYGLTF_COMPONENT_TYPE_INT: {
      std::int32_t v;
      std::memcpy(&v, p, 4);
      return v;
    }
    default: return 0.0;
  }
}

// ---------------------------------------------------------------------------------------------
// Pre-check of the JSON (before tinygltf loads anything): external buffers must exist with the
// right size, buffer views must lie inside their buffers. tinygltf reports a missing buffer
// file only by its uri and reads image buffer views without a range check, so both are checked
// here, naming the buffer.

/// The deepest nesting of JSON arrays and objects a glTF file may have. The schema's own objects
/// nest at most 7 deep (root, meshes[], mesh, primitives[], primitive, targets[], target) and
/// `extras` are small application data; nlohmann's parser (used by the pre-checks and by
/// tinygltf) and the JSON type check recurse once per level, so an unbounded depth overflowed the
/// stack (a 30 KB file of 15,000 '[' crashed with signal 11). 256 levels keep every recursion a few
/// hundred KB deep, far inside the 8 MiB default stack, also under AddressSanitizer.
constexpr int kMaxJsonNestingDepth = 256;

/// Refuses JSON text nested deeper than kMaxJsonNestingDepth before any parser sees it: a scan of
/// the bytes that counts '[' and '{' outside strings. `offset` is where `text` starts in the file
/// (the GLB JSON chunk starts at byte 20); the error names the file, the line (text glTF) or the
/// byte offset (GLB), the depth and the limit.
void check_json_nesting(const std::string& path, const std::uint8_t* text, std::size_t size, std::size_t offset,
                        bool binary) {
  int depth = 0;
  long line = 1;
  bool in_string = false;
  for (std::size_t i = 0; i < size; ++i) {
    const std::uint8_t c = text[i];
    if (c == '\n') ++line;
    if (in_string) {
      if (c == '\\') {
        ++i;  // the escaped character cannot end the string
      } else if (c == '"') {
        in_string = false;
      }
      continue;
    }
    if (c == '"') {
      in_string = true;
    } else if (c == '[' || c == '{') {
      if (++depth > kMaxJsonNestingDepth) {
        const std::string what = "JSON nested deeper than " + std::to_string(kMaxJsonNestingDepth) +
                                 " arrays/objects (the declared limit, docs/limits.md)";
        if (binary) throw InputError(path, "byte " + std::to_string(offset + i) + ": " + what);
        throw InputError(path, line, what);
      }
    } else if (c == ']' || c == '}') {
      if (depth > 0) --depth;
    }
  }
}

std::optional<nlohmann::json> extract_json(const std::vector<std::uint8_t>& bytes, bool binary) {
  try {
    if (!binary) return nlohmann::json::parse(bytes.begin(), bytes.end());
    if (bytes.size() < 20) return std::nullopt;
    const std::uint32_t chunk_len = le32(bytes.data() + 12);
    const std::uint32_t chunk_type = le32(bytes.data() + 16);
    if (chunk_type != 0x4E4F534Au || 20ull + chunk_len > bytes.size()) return std::nullopt;
    return nlohmann::json::parse(bytes.begin() + 20, bytes.begin() + 20 + chunk_len);
  } catch (const nlohmann::json::exception&) {
    return std::nullopt;  // tinygltf reports the syntax error with its own message
  }
}


// ---------------------------------------------------------------------------------------------
// JSON types (before tinygltf loads anything): tinygltf reads a field of the wrong JSON type as
// if it were absent ("scene": "hello" loads as no default scene), so every field the loader or
// tinygltf reads is checked against its type in the glTF 2.0 JSON schema (Khronos glTF 2.0
// specification, section 5 "Properties Reference"), with the required ones, naming the field by
// its JSON path.

/// The JSON type a glTF field has in the schema.
enum class JType : std::uint8_t {
  Uint,         ///< glTFid and counts: an integer >= 0
  Number,       ///< any number
  Bool,
  String,
  Object,       ///< an object checked no further here (extensions, extras, attributes' values aside)
  UintArray,    ///< array of integers >= 0
  NumberArray,  ///< array of numbers
  UintMap,      ///< object whose values are integers >= 0 (primitive attributes)
};

/// One field of a glTF object: its name, type and whether the schema requires it.
struct JField {
  const char* name;
  JType type;
  bool required = false;
};

const char* jtype_text(JType t) {
  switch (t) {
    case JType::Uint: return "a non-negative integer";
    case JType::Number: return "a number";
    case JType::Bool: return "a boolean";
    case JType::String: return "a string";
    case JType::Object: return "an object";
    case JType::UintArray: return "an array of non-negative integers";
    case JType::NumberArray: return "an array of numbers";
    case JType::UintMap: return "an object of non-negative integers";
  }
  return "?";
}

std::string json_kind(const nlohmann::json& v) {
  if (v.is_number_integer() && v.get<long long>() < 0) return "the negative integer " + v.dump();
  if (v.is_number()) return "the number " + v.dump();
  if (v.is_string()) return "a string";
  if (v.is_boolean()) return "a boolean";
  if (v.is_null()) return "null";
  if (v.is_array()) return "an array";
  return "an object";
}

/// True for an integer >= 0 (glTF ids and counts; 3.0 written as a float is refused as tinygltf does).
bool json_uint(const nlohmann::json& v) { return v.is_number_unsigned() || (v.is_number_integer() && v.get<long long>() >= 0); }

class JsonTypeCheck {
 public:
  explicit JsonTypeCheck(std::string file) : file_(std::move(file)) {}

  [[noreturn]] void fail(const std::string& path, const std::string& msg) const {
    throw InputError(file_, "field '" + path + "': " + msg);
  }

  void value(const nlohmann::json& v, JType t, const std::string& path) const {
    bool ok = false;
    switch (t) {
      case JType::Uint: ok = json_uint(v); break;
      case JType::Number: ok = v.is_number(); break;
      case JType::Bool: ok = v.is_boolean(); break;
      case JType::String: ok = v.is_string(); break;
      case JType::Object: ok = v.is_object(); break;
      case JType::UintArray:
      case JType::NumberArray:
        if (!v.is_array()) break;
        for (std::size_t i = 0; i < v.size(); ++i) {
          const bool item = t == JType::UintArray ? json_uint(v[i]) : v[i].is_number();
          if (!item)
            fail(path + "[" + std::to_string(i) + "]", std::string("expected ") + (t == JType::UintArray ? "a non-negative integer" : "a number") +
                                                       ", found " + json_kind(v[i]));
        }
        ok = true;
        break;
      case JType::UintMap:
        if (!v.is_object()) break;
        for (const auto& [k, item] : v.items())
          if (!json_uint(item)) fail(path + "." + k, "expected a non-negative integer, found " + json_kind(item));
        ok = true;
        break;
    }
    if (!ok) fail(path, std::string("expected ") + jtype_text(t) + ", found " + json_kind(v));
  }

  /// Checks `obj` (which must be an object) against `fields`; `name`, `extensions` and `extras`
  /// are allowed on every object (name a string, extensions an object).
  /// `path` is "" for the root object (its fields are named bare: "scene", "asset").
  void object(const nlohmann::json& obj, const std::string& path, std::initializer_list<JField> fields) const {
    if (!obj.is_object()) fail(path.empty() ? "(root)" : path, "expected an object, found " + json_kind(obj));
    const std::string prefix = path.empty() ? "" : path + ".";
    for (const JField& f : fields) {
      const auto it = obj.find(f.name);
      if (it == obj.end()) {
        if (f.required) fail(prefix + f.name, "required by the glTF 2.0 schema but missing");
        continue;
      }
      value(*it, f.type, prefix + f.name);
    }
    if (auto it = obj.find("name"); it != obj.end() && !path.empty()) value(*it, JType::String, prefix + "name");
    if (auto it = obj.find("extensions"); it != obj.end()) {
      value(*it, JType::Object, prefix + "extensions");
      for (const auto& [k, ext] : it->items()) value(ext, JType::Object, prefix + "extensions." + k);  // each an object
    }
  }

  /// Each element of the top-level array `key` (if present) through `each(element, path)`.
  template <class F>
  void array(const nlohmann::json& root, const char* key, F each) const {
    const auto it = root.find(key);
    if (it == root.end()) return;
    if (!it->is_array()) fail(key, "expected an array, found " + json_kind(*it));
    for (std::size_t i = 0; i < it->size(); ++i) each((*it)[i], std::string(key) + "[" + std::to_string(i) + "]");
  }

  /// A textureInfo (baseColorTexture, normalTexture, ...) if present.
  void texture_info(const nlohmann::json& parent, const char* key, const std::string& path) const {
    const auto it = parent.find(key);
    if (it == parent.end()) return;
    object(*it, path + "." + key, {{"index", JType::Uint, true}, {"texCoord", JType::Uint}, {"scale", JType::Number},
                                   {"strength", JType::Number}});
  }

  void run(const nlohmann::json& j) const {
    object(j, "", {{"asset", JType::Object, true}, {"scene", JType::Uint}});
    object(j["asset"], "asset", {{"version", JType::String, true}, {"minVersion", JType::String},
                                 {"generator", JType::String}, {"copyright", JType::String}});
    for (const char* list : {"extensionsUsed", "extensionsRequired"}) {
      if (auto it = j.find(list); it != j.end()) {
        if (!it->is_array()) fail(list, "expected an array of strings, found " + json_kind(*it));
        for (std::size_t i = 0; i < it->size(); ++i) value((*it)[i], JType::String, std::string(list) + "[" + std::to_string(i) + "]");
      }
    }
    array(j, "scenes", [&](const nlohmann::json& o, const std::string& p) { object(o, p, {{"nodes", JType::UintArray}}); });
    array(j, "nodes", [&](const nlohmann::json& o, const std::string& p) {
      object(o, p, {{"camera", JType::Uint}, {"children", JType::UintArray}, {"skin", JType::Uint},
                    {"matrix", JType::NumberArray}, {"mesh", JType::Uint}, {"rotation", JType::NumberArray},
                    {"scale", JType::NumberArray}, {"translation", JType::NumberArray}, {"weights", JType::NumberArray}});
    });
    array(j, "meshes", [&](const nlohmann::json& o, const std::string& p) {
      object(o, p, {{"weights", JType::NumberArray}});
      const auto prims = o.find("primitives");
      if (prims == o.end()) fail(p + ".primitives", "required by the glTF 2.0 schema but missing");
      if (!prims->is_array()) fail(p + ".primitives", "expected an array, found " + json_kind(*prims));
      for (std::size_t i = 0; i < prims->size(); ++i) {
        const std::string pp = p + ".primitives[" + std::to_string(i) + "]";
        object((*prims)[i], pp, {{"attributes", JType::UintMap, true}, {"indices", JType::Uint},
                                 {"material", JType::Uint}, {"mode", JType::Uint}});
        if (auto t = (*prims)[i].find("targets"); t != (*prims)[i].end()) {
          if (!t->is_array()) fail(pp + ".targets", "expected an array, found " + json_kind(*t));
          for (std::size_t k = 0; k < t->size(); ++k) value((*t)[k], JType::UintMap, pp + ".targets[" + std::to_string(k) + "]");
        }
      }
    });
    array(j, "accessors", [&](const nlohmann::json& o, const std::string& p) {
      object(o, p, {{"bufferView", JType::Uint}, {"byteOffset", JType::Uint}, {"componentType", JType::Uint, true},
                    {"normalized", JType::Bool}, {"count", JType::Uint, true}, {"type", JType::String, true},
                    {"max", JType::NumberArray}, {"min", JType::NumberArray}, {"sparse", JType::Object}});
      if (auto sp = o.find("sparse"); sp != o.end()) {
        object(*sp, p + ".sparse", {{"count", JType::Uint, true}, {"indices", JType::Object, true}, {"values", JType::Object, true}});
        object((*sp)["indices"], p + ".sparse.indices",
               {{"bufferView", JType::Uint, true}, {"byteOffset", JType::Uint}, {"componentType", JType::Uint, true}});
        object((*sp)["values"], p + ".sparse.values", {{"bufferView", JType::Uint, true}, {"byteOffset", JType::Uint}});
      }
    });
    array(j, "bufferViews", [&](const nlohmann::json& o, const std::string& p) {
      object(o, p, {{"buffer", JType::Uint, true}, {"byteOffset", JType::Uint}, {"byteLength", JType::Uint, true},
                    {"byteStride", JType::Uint}, {"target", JType::Uint}});
    });
    array(j, "buffers", [&](const nlohmann::json& o, const std::string& p) {
      object(o, p, {{"uri", JType::String}, {"byteLength", JType::Uint, true}});
    });
    array(j, "materials", [&](const nlohmann::json& o, const std::string& p) {
      object(o, p, {{"pbrMetallicRoughness", JType::Object}, {"emissiveFactor", JType::NumberArray},
                    {"alphaMode", JType::String}, {"alphaCutoff", JType::Number}, {"doubleSided", JType::Bool}});
      for (const char* t : {"normalTexture", "occlusionTexture", "emissiveTexture"}) texture_info(o, t, p);
      if (auto pbr = o.find("pbrMetallicRoughness"); pbr != o.end()) {
        const std::string pp = p + ".pbrMetallicRoughness";
        object(*pbr, pp, {{"baseColorFactor", JType::NumberArray}, {"metallicFactor", JType::Number},
                          {"roughnessFactor", JType::Number}});
        texture_info(*pbr, "baseColorTexture", pp);
        texture_info(*pbr, "metallicRoughnessTexture", pp);
      }
    });
    array(j, "textures", [&](const nlohmann::json& o, const std::string& p) {
      object(o, p, {{"sampler", JType::Uint}, {"source", JType::Uint}});
    });
    array(j, "images", [&](const nlohmann::json& o, const std::string& p) {
      object(o, p, {{"uri", JType::String}, {"mimeType", JType::String}, {"bufferView", JType::Uint}});
    });
    array(j, "samplers", [&](const nlohmann::json& o, const std::string& p) {
      object(o, p, {{"magFilter", JType::Uint}, {"minFilter", JType::Uint}, {"wrapS", JType::Uint}, {"wrapT", JType::Uint}});
    });
    array(j, "cameras", [&](const nlohmann::json& o, const std::string& p) {
      object(o, p, {{"type", JType::String, true}, {"perspective", JType::Object}, {"orthographic", JType::Object}});
    });
    array(j, "skins", [&](const nlohmann::json& o, const std::string& p) {
      object(o, p, {{"inverseBindMatrices", JType::Uint}, {"skeleton", JType::Uint}, {"joints", JType::UintArray, true}});
    });
    array(j, "animations", [&](const nlohmann::json& o, const std::string& p) {
      object(o, p, {{"name", JType::String}});
      for (const char* list : {"channels", "samplers"}) {
        const auto it = o.find(list);
        if (it == o.end()) fail(p + "." + list, "required by the glTF 2.0 schema but missing");
        if (!it->is_array()) fail(p + "." + list, "expected an array, found " + json_kind(*it));
        for (std::size_t i = 0; i < it->size(); ++i) {
          const std::string pp = p + "." + list + "[" + std::to_string(i) + "]";
          if (std::string(list) == "channels") {
            object((*it)[i], pp, {{"sampler", JType::Uint, true}, {"target", JType::Object, true}});
            object((*it)[i]["target"], pp + ".target", {{"node", JType::Uint}, {"path", JType::String, true}});
          } else {
            object((*it)[i], pp, {{"input", JType::Uint, true}, {"output", JType::Uint, true}, {"interpolation", JType::String}});
          }
        }
      }
    });
  }

 private:
  std::string file_;
};

void precheck_json(const std::string& file, const nlohmann::json& j) {
  const fs::path dir = fs::path(file).parent_path();
  std::vector<std::uint64_t> buffer_bytes;
  if (j.is_object() && j.contains("buffers") && j["buffers"].is_array()) {
    const auto& buffers = j["buffers"];
    for (std::size_t i = 0; i < buffers.size(); ++i) {
      const auto& b = buffers[i];
      std::uint64_t len = 0;
      if (b.contains("byteLength") && b["byteLength"].is_number_unsigned()) len = b["byteLength"].get<std::uint64_t>();
      buffer_bytes.push_back(len);
      const std::string name = b.contains("name") && b["name"].is_string() ? b["name"].get<std::string>() : "";
      if (!b.contains("uri") || !b["uri"].is_string()) continue;
      const std::string uri = b["uri"].get<std::string>();
      if (is_data_uri(uri)) continue;
      const fs::path p = dir / url_decode(uri);
      std::error_code ec;
      if (!fs::is_regular_file(p, ec)) {
        throw InputError(file, "buffer " + std::to_string(i) + quoted_name(name) + ": file '" + uri +
                                   "' not found (looked for " + p.string() + ")");
      }
      const auto size = fs::file_size(p, ec);
      if (!ec && size != len) {
        throw InputError(file, "buffer " + std::to_string(i) + quoted_name(name) + ": file '" + p.string() + "' is " +
                                   std::to_string(size) + " bytes but byteLength is " + std::to_string(len));
      }
    }
  }
  if (j.is_object() && j.contains("bufferViews") && j["bufferViews"].is_array()) {
    const auto& views = j["bufferViews"];
    for (std::size_t i = 0; i < views.size(); ++i) {
      const auto& v = views[i];
      const std::string name = v.contains("name") && v["name"].is_string() ? v["name"].get<std::string>() : "";
      const std::string what = "bufferView " + std::to_string(i) + quoted_name(name);
      if (!v.contains("buffer") || !v["buffer"].is_number_integer()) continue;  // tinygltf reports it
      const auto b = v["buffer"].get<long long>();
      if (b < 0 || static_cast<std::size_t>(b) >= buffer_bytes.size()) {
        throw InputError(file, what + ": refers to buffer " + std::to_string(b) + ", but the file has " +
                                   std::to_string(buffer_bytes.size()) + " buffers");
      }
      std::uint64_t off = 0, len = 0;
      if (v.contains("byteOffset") && v["byteOffset"].is_number_unsigned()) off = v["byteOffset"].get<std::uint64_t>();
      if (v.contains("byteLength") && v["byteLength"].is_number_unsigned()) len = v["byteLength"].get<std::uint64_t>();
      const std::uint64_t blen = buffer_bytes[static_cast<std::size_t>(b)];
      if (off > blen || len > blen - off) {
        throw InputError(file, what + ": bytes [" + std::to_string(off) + ", " + std::to_string(off + len) +
                                   ") lie outside buffer " + std::to_string(b) + " (" +
                                   std::to_string(buffer_bytes[static_cast<std::size_t>(b)]) + " bytes)");
      }
    }
  }
}

// ---------------------------------------------------------------------------------------------
// The image loader given to tinygltf: keeps the encoded bytes (as_is) and reads only the header.

bool keep_encoded_image(tinygltf::Image* image, const int /*image_idx*/, std::string* /*err*/,
                        std::string* /*warn*/, int /*req_width*/, int /*req_height*/,
                        const unsigned char* bytes, int size, void* /*user*/) {
  image->image.assign(bytes, bytes + std::max(size, 0));
  image->as_is = true;
  if (auto h = parse_image_header(bytes, static_cast<std::size_t>(std::max(size, 0)))) {
    image->width = h->width;
    image->height = h->height;
    image->component = h->channels;
    image->bits = 8;
  }
  return true;
}

// ---------------------------------------------------------------------------------------------
// The conversion from a validated tinygltf::Model to a Scene.

class Converter {
 public:
  Converter(std::string file, const tinygltf::Model& model, Scene& scene)
      : file_(std::move(file)), m_(model), scene_(scene) {}

  void run();

 private:
  [[noreturn]] void fail(const std::string& msg) const { throw InputError(file_, msg); }

  std::string mesh_desc(int mesh) const {
    return "mesh " + std::to_string(mesh) + quoted_name(m_.meshes[static_cast<std::size_t>(mesh)].name);
  }
  std::string node_desc(int node) const {
    return "node " + std::to_string(node) + quoted_name(m_.nodes[static_cast<std::size_t>(node)].name);
  }
  std::string accessor_desc(int acc, const std::string& role) const {
    return "accessor " + std::to_string(acc) + quoted_name(m_.accessors[static_cast<std::size_t>(acc)].name) + " (" +
           role + ")";
  }

  void check_index(int index, std::size_t size, const std::string& owner, const char* what) const {
    if (index < 0 || static_cast<std::size_t>(index) >= size) {
      fail(owner + ": refers to " + what + " " + std::to_string(index) + ", but the file has " + std::to_string(size));
    }
  }

  // Validates that `count` elements of `elem_bytes` at `byte_offset` with `stride` fit in the view;
  // returns a pointer to the first element.
  const unsigned char* view_range(int view_index, std::size_t byte_offset, std::size_t count, std::size_t elem_bytes,
                                  bool allow_stride, const std::string& desc, std::size_t* stride_out) const;

  template <class Out>
  std::vector<Out> read_accessor(int acc_index, const std::string& desc, std::size_t* element_bytes = nullptr) const;

  void collect_textures();
  void convert_materials();
  std::uint32_t default_material();
  const std::vector<std::uint32_t>& mesh_submeshes(int mesh);
  /// Mesh `mesh`'s primitive `prim` as a submesh, its index appended to `out` (nothing for points and lines).
  void convert_primitive(int mesh, int prim, std::vector<std::uint32_t>& out);
  // The steps of convert_primitive, in order.
  /// Every attribute's accessor checked (one element per vertex); returns the vertex stride in bytes.
  std::uint32_t check_attributes(const tinygltf::Primitive& prim, const std::string& where, int pos_acc,
                                 std::size_t vertex_count) const;
  /// POSITION into sm.positions.
  void read_positions(int pos_acc, const std::string& where, std::size_t vertex_count, SubMesh& sm) const;
  /// NORMAL into sm.normals; false when the primitive has none.
  bool read_normals(const tinygltf::Primitive& prim, const std::string& where, std::size_t vertex_count, SubMesh& sm) const;
  /// _CLIP_POSITION into sm.clip_positions, when present.
  void read_clip_positions(const tinygltf::Primitive& prim, const std::string& where, std::size_t vertex_count,
                           SubMesh& sm) const;
  /// The material (sm.material) and the uvs of the set its base colour texture samples; returns that attribute's name.
  std::string read_uvs(const tinygltf::Primitive& prim, const std::string& where, std::size_t vertex_count, SubMesh& sm);
  /// The attributes not kept, validated (their bytes lie in their buffer views).
  void check_other_attributes(const tinygltf::Primitive& prim, const std::string& where, const std::string& uv_attr) const;
  /// The primitive's indices (0..n-1 when it has none); sets sm.index_bytes.
  std::vector<std::uint32_t> read_indices(const tinygltf::Primitive& prim, const std::string& where,
                                          std::size_t vertex_count, SubMesh& sm) const;
  /// `idx` of topology `mode` as sm.indices, a triangle list.
  void triangle_list(int mode, std::vector<std::uint32_t> idx, const std::string& where, SubMesh& sm);
  /// sm.normals made from the triangles' face normals (a primitive without NORMAL).
  static void smooth_face_normals(std::size_t vertex_count, SubMesh& sm);
  void check_node_graph();
  void place_node(int node, const glm::mat4& parent);
  /// The node's transform in the file (its TRS, or its matrix).
  NodeTransform node_transform(int node) const;
  glm::mat4 local_matrix(int node) const;
  /// The node hierarchy and the animations (Scene::animation), after place_node.
  void convert_animations();
  /// A base colour image decoded once: its texels and, if any texel is not opaque, its alpha mask.
  struct DecodedImage {
    int texels = -1;  ///< index into Scene::base_color_texels (-1: not decoded)
    int mask = -1;    ///< index into Scene::alpha_masks (-1: no alpha)
  };
  const DecodedImage& decode_base_color(int image, const std::string& material_desc);

  std::string file_;
  const tinygltf::Model& m_;
  Scene& scene_;
  std::map<int, std::vector<std::uint32_t>> mesh_cache_;
  std::map<int, DecodedImage> decoded_;  // image -> what decode_base_color made of it
  std::vector<int> material_texcoord_;  // per glTF material: TEXCOORD set of its base color texture
  int default_material_ = -1;
  std::vector<int> parent_;  // per node, -1 for roots (filled by check_node_graph)
};

const unsigned char* Converter::view_range(int view_index, std::size_t byte_offset, std::size_t count,
                                           std::size_t elem_bytes, bool allow_stride, const std::string& desc,
                                           std::size_t* stride_out) const {
  check_index(view_index, m_.bufferViews.size(), desc, "bufferView");
  const tinygltf::BufferView& bv = m_.bufferViews[static_cast<std::size_t>(view_index)];
  const std::string bv_desc = "bufferView " + std::to_string(view_index) + quoted_name(bv.name);
  check_index(bv.buffer, m_.buffers.size(), bv_desc, "buffer");
  const tinygltf::Buffer& buf = m_.buffers[static_cast<std::size_t>(bv.buffer)];
  if (bv.byteOffset > buf.data.size() || bv.byteLength > buf.data.size() - bv.byteOffset) {
    fail(bv_desc + ": bytes [" + std::to_string(bv.byteOffset) + ", " + std::to_string(bv.byteOffset + bv.byteLength) +
         ") lie outside buffer " + std::to_string(bv.buffer) + quoted_name(buf.name) + " (" +
         std::to_string(buf.data.size()) + " bytes)");
  }
  std::size_t stride = elem_bytes;
  if (allow_stride && bv.byteStride != 0) {
    if (bv.byteStride < elem_bytes) {
      fail(desc + ": " + bv_desc + " byteStride " + std::to_string(bv.byteStride) + " is smaller than the element (" +
           std::to_string(elem_bytes) + " bytes)");
    }
    stride = bv.byteStride;
  }
  if (count > 0) {
    // offset + stride*(count-1) + element <= view length, without overflowing.
    const bool fits = byte_offset <= bv.byteLength && elem_bytes <= bv.byteLength - byte_offset &&
                      (count - 1) <= (bv.byteLength - byte_offset - elem_bytes) / stride;
    if (!fits) {
      const long double end = static_cast<long double>(byte_offset) +
                              static_cast<long double>(stride) * static_cast<long double>(count - 1) +
                              static_cast<long double>(elem_bytes);
      std::ostringstream need;
      need.precision(20);
      need << end;
      fail(desc + ": " + std::to_string(count) + " elements of " + std::to_string(elem_bytes) + " bytes (stride " +
           std::to_string(stride) + ") from byte " + std::to_string(byte_offset) + " need " + need.str() +
           " bytes, but " + bv_desc + " has " + std::to_string(bv.byteLength));
    }
  }
  if (stride_out) *stride_out = stride;
  return buf.data.data() + bv.byteOffset + byte_offset;
}

template <class Out>
std::vector<Out> Converter::read_accessor(int acc_index, const std::string& desc, std::size_t* element_bytes) const {
  const tinygltf::Accessor& acc = m_.accessors[static_cast<std::size_t>(acc_index)];
  const int cb = component_bytes(acc.componentType);
  const int nc = type_components(acc.type);
  if (cb == 0) fail(desc + ": invalid componentType " + std::to_string(acc.componentType));
  if (nc == 0) fail(desc + ": invalid type " + std::to_string(acc.type));
  if (acc.count == 0) fail(desc + ": count is 0");
  if (acc.count > max_accessor_elements) {
    fail(desc + ": count " + std::to_string(acc.count) + " exceeds the supported " +
         std::to_string(max_accessor_elements) + " elements");
  }
  const std::size_t elem = static_cast<std::size_t>(cb) * static_cast<std::size_t>(nc);
  if (element_bytes) *element_bytes = elem;
  std::size_t stride = 0;
  const unsigned char* base =
      acc.bufferView >= 0 ? view_range(acc.bufferView, acc.byteOffset, acc.count, elem, true, desc, &stride) : nullptr;
  std::vector<Out> out(acc.count * static_cast<std::size_t>(nc), Out{});
  if (base != nullptr) {
    for (std::size_t i = 0; i < acc.count; ++i) {
      const unsigned char* p = base + i * stride;
      for (int c = 0; c < nc; ++c) {
        out[i * static_cast<std::size_t>(nc) + static_cast<std::size_t>(c)] =
            static_cast<Out>(read_component(p + c * cb, acc.componentType, acc.normalized));
      }
    }
  }  // else: no buffer view, the values start as zeros (glTF spec), sparse data may replace some
  if (acc.sparse.isSparse) {
    const auto& sp = acc.sparse;
    const std::string sdesc = desc + " sparse";
    if (sp.count <= 0 || static_cast<std::size_t>(sp.count) > acc.count) {
      fail(sdesc + ": count " + std::to_string(sp.count) + " must be in 1.." + std::to_string(acc.count));
    }
    const int icb = component_bytes(sp.indices.componentType);
    if (sp.indices.componentType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE &&
        sp.indices.componentType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT &&
        sp.indices.componentType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT) {
      fail(sdesc + " indices: componentType must be UNSIGNED_BYTE, UNSIGNED_SHORT or UNSIGNED_INT");
    }
    const auto n = static_cast<std::size_t>(sp.count);
    const unsigned char* ip = view_range(sp.indices.bufferView, static_cast<std::size_t>(sp.indices.byteOffset), n,
                                         static_cast<std::size_t>(icb), false, sdesc + " indices", nullptr);
    const unsigned char* vp = view_range(sp.values.bufferView, static_cast<std::size_t>(sp.values.byteOffset), n, elem,
                                         false, sdesc + " values", nullptr);
    double prev = -1.0;
    for (std::size_t k = 0; k < n; ++k) {
      const double idx = read_component(ip + k * static_cast<std::size_t>(icb), sp.indices.componentType, false);
      if (idx <= prev || idx >= static_cast<double>(acc.count)) {
        fail(sdesc + " indices: index " + std::to_string(static_cast<std::uint64_t>(idx)) + " at position " +
             std::to_string(k) + " is not increasing or is out of range (" + std::to_string(acc.count) + " elements)");
      }
      prev = idx;
      const auto i = static_cast<std::size_t>(idx);
      for (int c = 0; c < nc; ++c) {
        out[i * static_cast<std::size_t>(nc) + static_cast<std::size_t>(c)] =
            static_cast<Out>(read_component(vp + k * elem + static_cast<std::size_t>(c * cb), acc.componentType,
                                            acc.normalized));
      }
    }
  }
  return out;
}

void Converter::collect_textures() {
  for (std::size_t i = 0; i < m_.images.size(); ++i) {
    const tinygltf::Image& img = m_.images[i];
    TextureInfo t;
    t.name = !img.uri.empty() && !is_data_uri(img.uri) ? url_decode(img.uri)
             : !img.name.empty()                       ? img.name
                                                       : "image " + std::to_string(i);
    const std::string desc = "image " + std::to_string(i) + " '" + t.name + "'";
    if (img.image.empty()) {
      t.missing = true;
      if (!img.uri.empty() && !is_data_uri(img.uri)) {
        scene_.warnings.push_back(desc + ": file not found, texture counted as 0 bytes");
      } else {
        scene_.warnings.push_back(desc + ": no image data, texture counted as 0 bytes");
      }
    } else if (auto h = parse_image_header(img.image.data(), img.image.size())) {
      t.format = h->format;
      t.width = h->width;
      t.height = h->height;
      t.channels = h->channels;
    } else {
      t.format = "unknown";
      scene_.warnings.push_back(desc + ": unrecognised image format (not PNG/JPEG/GIF/BMP/KTX2), counted as 0 bytes");
    }
    scene_.textures.push_back(std::move(t));
  }
}

const Converter::DecodedImage& Converter::decode_base_color(int image, const std::string& material_desc) {
  auto it = decoded_.find(image);
  if (it != decoded_.end()) return it->second;
  DecodedImage out;
  const tinygltf::Image& img = m_.images[static_cast<std::size_t>(image)];
  const auto header = parse_image_header(img.image.data(), img.image.size());
  // stb_image's own header reader covers every format it decodes (TGA, PSD, HDR, ... besides the
  // ones parse_image_header knows): the pixel count is bounded before any pixel is decoded.
  int info_w = 0, info_h = 0, info_comp = 0;
  const bool info = !img.image.empty() && stbi_info_from_memory(img.image.data(), static_cast<int>(img.image.size()),
                                                                &info_w, &info_h, &info_comp) != 0;
  if (!header && !img.image.empty()) {
    // A format the loader does not recognise (collect_textures warned, counted as 0 bytes): not decoded.
    scene_.warnings.push_back(material_desc + ": base color image " + std::to_string(image) +
                              " is not PNG/JPEG/GIF/BMP/KTX2; not decoded, the shader uses the base color factor");
  } else if ((header && static_cast<std::size_t>(header->width) * static_cast<std::size_t>(header->height) > max_decoded_texels) ||
             (info && static_cast<std::size_t>(info_w) * static_cast<std::size_t>(info_h) > max_decoded_texels)) {
    scene_.warnings.push_back(material_desc + ": base color image " + std::to_string(image) + " is too large (" +
                              std::to_string(header->width) + "x" + std::to_string(header->height) +
                              ") to decode; the shader uses the base color factor");
  } else if (!img.image.empty()) {
    int w = 0, h = 0, comp = 0;
    stbi_uc* px = stbi_load_from_memory(img.image.data(), static_cast<int>(img.image.size()), &w, &h, &comp, 4);
    if (px == nullptr) {
      scene_.warnings.push_back(material_desc + ": base color image " + std::to_string(image) +
                                " could not be decoded (" + stbi_failure_reason() +
                                "); the shader uses the base color factor");
    } else {
      const std::size_t texels = static_cast<std::size_t>(w) * static_cast<std::size_t>(h);
      ColorTexels color;
      color.width = w;
      color.height = h;
      color.rgba.assign(px, px + texels * 4);
      AlphaMask mask;
      mask.width = w;
      mask.height = h;
      mask.alpha.resize(texels);
      bool any_transparent = false;
      for (std::size_t i = 0; i < texels; ++i) {
        mask.alpha[i] = px[i * 4 + 3];
        any_transparent |= mask.alpha[i] != 255;
      }
      stbi_image_free(px);
      out.texels = static_cast<int>(scene_.base_color_texels.size());
      scene_.base_color_texels.push_back(std::move(color));
      // An image without alpha (or fully opaque) leaves the factor's alpha alone: no mask.
      if (any_transparent) {
        out.mask = static_cast<int>(scene_.alpha_masks.size());
        scene_.alpha_masks.push_back(std::move(mask));
      }
    }
  }
  return decoded_.emplace(image, out).first->second;
}

void Converter::convert_materials() {
  material_texcoord_.assign(m_.materials.size(), 0);
  for (std::size_t i = 0; i < m_.materials.size(); ++i) {
    const tinygltf::Material& gm = m_.materials[i];
    const std::string desc = "material " + std::to_string(i) + quoted_name(gm.name);
    Material mat;
    mat.name = gm.name.empty() ? "material " + std::to_string(i) : gm.name;
    if (gm.alphaMode.empty() || gm.alphaMode == "OPAQUE") {
      mat.alpha_mode = AlphaMode::Opaque;
    } else if (gm.alphaMode == "MASK") {
      mat.alpha_mode = AlphaMode::PunchThrough;
    } else if (gm.alphaMode == "BLEND") {
      mat.alpha_mode = AlphaMode::Translucent;
    } else {
      fail(desc + ": alphaMode '" + gm.alphaMode + "' is not OPAQUE, MASK or BLEND");
    }
    mat.alpha_cutoff = static_cast<float>(gm.alphaCutoff);
    if (!std::isfinite(mat.alpha_cutoff) || mat.alpha_cutoff < 0.0f) {
      fail(desc + ": alphaCutoff " + std::to_string(gm.alphaCutoff) + " is not a non-negative number");
    }
    mat.double_sided = gm.doubleSided;
    const auto& f = gm.pbrMetallicRoughness.baseColorFactor;
    if (f.size() == 4) {
      mat.base_color = glm::vec4(static_cast<float>(f[0]), static_cast<float>(f[1]), static_cast<float>(f[2]),
                                 static_cast<float>(f[3]));
    } else if (!f.empty()) {
      fail(desc + ": baseColorFactor has " + std::to_string(f.size()) + " components, expected 4");
    }
    const int tex = gm.pbrMetallicRoughness.baseColorTexture.index;
    if (tex >= 0) {
      check_index(tex, m_.textures.size(), desc + " baseColorTexture", "texture");
      const tinygltf::Texture& t = m_.textures[static_cast<std::size_t>(tex)];
      if (t.source >= 0) {
        check_index(t.source, m_.images.size(), "texture " + std::to_string(tex) + quoted_name(t.name), "image");
        mat.base_color_texture = t.source;
        material_texcoord_[i] = gm.pbrMetallicRoughness.baseColorTexture.texCoord;
        const DecodedImage& decoded = decode_base_color(t.source, desc);
        mat.base_color_texels = decoded.texels;
        if (mat.alpha_mode == AlphaMode::PunchThrough) mat.alpha_mask = decoded.mask;
      } else {
        scene_.warnings.push_back("texture " + std::to_string(tex) + quoted_name(t.name) +
                                  ": no source image (extension-only textures are not supported); " + desc +
                                  " is untextured");
      }
    }
    // Other textures must still point at real textures and images.
    const std::pair<const char*, int> others[] = {
        {"normalTexture", gm.normalTexture.index},
        {"occlusionTexture", gm.occlusionTexture.index},
        {"emissiveTexture", gm.emissiveTexture.index},
        {"metallicRoughnessTexture", gm.pbrMetallicRoughness.metallicRoughnessTexture.index}};
    for (const auto& [slot, index] : others) {
      if (index < 0) continue;
      check_index(index, m_.textures.size(), desc + " " + slot, "texture");
      const tinygltf::Texture& t = m_.textures[static_cast<std::size_t>(index)];
      if (t.source >= 0) {
        check_index(t.source, m_.images.size(), "texture " + std::to_string(index) + quoted_name(t.name), "image");
      }
    }
    scene_.materials.push_back(std::move(mat));
  }
}

std::uint32_t Converter::default_material() {
  if (default_material_ < 0) {
    default_material_ = static_cast<int>(scene_.materials.size());
    Material mat;
    mat.name = "default";
    scene_.materials.push_back(mat);
  }
  return static_cast<std::uint32_t>(default_material_);
}

void Converter::convert_primitive(int mesh, int prim_index, std::vector<std::uint32_t>& out) {
  const tinygltf::Mesh& gmesh = m_.meshes[static_cast<std::size_t>(mesh)];
  const tinygltf::Primitive& prim = gmesh.primitives[static_cast<std::size_t>(prim_index)];
  const std::string where = mesh_desc(mesh) + " primitive " + std::to_string(prim_index);

  if (prim.mode >= TINYGLTF_MODE_POINTS && prim.mode <= TINYGLTF_MODE_LINE_STRIP) {
    scene_.warnings.push_back(where + ": mode " + mode_name(prim.mode) + " skipped (only triangles are simulated)");
    return;
  }
  if (prim.mode != TINYGLTF_MODE_TRIANGLES && prim.mode != TINYGLTF_MODE_TRIANGLE_STRIP &&
      prim.mode != TINYGLTF_MODE_TRIANGLE_FAN) {
    fail(where + ": invalid mode " + std::to_string(prim.mode));
  }
  auto pos_it = prim.attributes.find("POSITION");
  if (pos_it == prim.attributes.end()) fail(where + ": has no POSITION attribute");
  const int pos_acc = pos_it->second;
  check_index(pos_acc, m_.accessors.size(), where + " POSITION", "accessor");
  const std::size_t vertex_count = m_.accessors[static_cast<std::size_t>(pos_acc)].count;

  SubMesh sm;
  sm.name = gmesh.name.empty() ? "mesh " + std::to_string(mesh) : gmesh.name;
  if (gmesh.primitives.size() > 1) sm.name += "/" + std::to_string(prim_index);
  sm.vertex_stride_bytes = check_attributes(prim, where, pos_acc, vertex_count);
  read_positions(pos_acc, where, vertex_count, sm);
  const bool has_normals = read_normals(prim, where, vertex_count, sm);
  read_clip_positions(prim, where, vertex_count, sm);
  const std::string uv_attr = read_uvs(prim, where, vertex_count, sm);
  check_other_attributes(prim, where, uv_attr);
  triangle_list(prim.mode, read_indices(prim, where, vertex_count, sm), where, sm);
  if (!has_normals) smooth_face_normals(vertex_count, sm);

  out.push_back(static_cast<std::uint32_t>(scene_.submeshes.size()));
  scene_.submeshes.push_back(std::move(sm));
}

std::uint32_t Converter::check_attributes(const tinygltf::Primitive& prim, const std::string& where, int pos_acc,
                                          std::size_t vertex_count) const {
  // Every attribute: a valid accessor whose bytes lie in its buffer view, one element per vertex.
  std::uint32_t stride_bytes = 0;
  for (const auto& [attr, acc_index] : prim.attributes) {
    check_index(acc_index, m_.accessors.size(), where + " attribute " + attr, "accessor");
    const tinygltf::Accessor& acc = m_.accessors[static_cast<std::size_t>(acc_index)];
    const std::string desc = accessor_desc(acc_index, attr + " of " + where);
    if (acc.count != vertex_count) {
      fail(desc + ": has " + std::to_string(acc.count) + " elements but POSITION (accessor " + std::to_string(pos_acc) +
           ") has " + std::to_string(vertex_count));
    }
    const int cb = component_bytes(acc.componentType);
    const int nc = type_components(acc.type);
    if (cb == 0) fail(desc + ": invalid componentType " + std::to_string(acc.componentType));
    if (nc == 0) fail(desc + ": invalid type " + std::to_string(acc.type));
    stride_bytes += static_cast<std::uint32_t>(cb * nc);
  }
  return stride_bytes;
}

void Converter::read_positions(int pos_acc, const std::string& where, std::size_t vertex_count, SubMesh& sm) const {
  // POSITION: VEC3 FLOAT, all finite.
  const tinygltf::Accessor& acc = m_.accessors[static_cast<std::size_t>(pos_acc)];
  const std::string desc = accessor_desc(pos_acc, "POSITION of " + where);
  if (acc.type != TINYGLTF_TYPE_VEC3 || acc.componentType != TINYGLTF_COMPONENT_TYPE_FLOAT) {
    fail(desc + ": POSITION must be VEC3 FLOAT, found " + type_name(acc.type) + " " + component_name(acc.componentType));
  }
  const std::vector<float> v = read_accessor<float>(pos_acc, desc);
  sm.positions.resize(vertex_count);
  for (std::size_t i = 0; i < vertex_count; ++i) {
    const glm::vec3 p(v[3 * i], v[3 * i + 1], v[3 * i + 2]);
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) {
      std::ostringstream os;
      os << desc << ": vertex " << i << " has a non-finite coordinate (" << p.x << ", " << p.y << ", " << p.z << ")";
      fail(os.str());
    }
    sm.positions[i] = p;
  }
}

bool Converter::read_normals(const tinygltf::Primitive& prim, const std::string& where, std::size_t vertex_count,
                             SubMesh& sm) const {
  // NORMAL: VEC3 FLOAT when present.
  auto it = prim.attributes.find("NORMAL");
  if (it == prim.attributes.end()) return false;
  const tinygltf::Accessor& acc = m_.accessors[static_cast<std::size_t>(it->second)];
  const std::string desc = accessor_desc(it->second, "NORMAL of " + where);
  if (acc.type != TINYGLTF_TYPE_VEC3 || acc.componentType != TINYGLTF_COMPONENT_TYPE_FLOAT) {
    fail(desc + ": NORMAL must be VEC3 FLOAT, found " + type_name(acc.type) + " " + component_name(acc.componentType));
  }
  const std::vector<float> v = read_accessor<float>(it->second, desc);
  sm.normals.resize(vertex_count);
  for (std::size_t i = 0; i < vertex_count; ++i) {
    const glm::vec3 n(v[3 * i], v[3 * i + 1], v[3 * i + 2]);
    if (!std::isfinite(n.x) || !std::isfinite(n.y) || !std::isfinite(n.z)) {
      fail(desc + ": vertex " + std::to_string(i) + " has a non-finite normal");
    }
    sm.normals[i] = n;
  }
  return true;
}

void Converter::read_clip_positions(const tinygltf::Primitive& prim, const std::string& where, std::size_t vertex_count,
                                    SubMesh& sm) const {
  // _CLIP_POSITION (tbdrsim's application-specific attribute, docs/capture-import.md): VEC4 FLOAT
  // clip-space positions a captured vertex shader wrote, all finite (the clipper handles any w).
  auto it = prim.attributes.find(kClipPositionAttribute);
  if (it == prim.attributes.end()) return;
  const tinygltf::Accessor& acc = m_.accessors[static_cast<std::size_t>(it->second)];
  const std::string desc = accessor_desc(it->second, std::string(kClipPositionAttribute) + " of " + where);
  if (acc.type != TINYGLTF_TYPE_VEC4 || acc.componentType != TINYGLTF_COMPONENT_TYPE_FLOAT) {
    fail(desc + ": " + kClipPositionAttribute + " must be VEC4 FLOAT, found " + type_name(acc.type) + " " +
         component_name(acc.componentType));
  }
  const std::vector<float> v = read_accessor<float>(it->second, desc);
  sm.clip_positions.resize(vertex_count);
  for (std::size_t i = 0; i < vertex_count; ++i) {
    const glm::vec4 c(v[4 * i], v[4 * i + 1], v[4 * i + 2], v[4 * i + 3]);
    if (!std::isfinite(c.x) || !std::isfinite(c.y) || !std::isfinite(c.z) || !std::isfinite(c.w)) {
      std::ostringstream os;
      os << desc << ": vertex " << i << " has a non-finite clip coordinate (" << c.x << ", " << c.y << ", " << c.z << ", "
         << c.w << ")";
      fail(os.str());
    }
    sm.clip_positions[i] = c;
  }
}

std::string Converter::read_uvs(const tinygltf::Primitive& prim, const std::string& where, std::size_t vertex_count,
                                SubMesh& sm) {
  // TEXCOORD_n (the set the base color texture uses): VEC2 FLOAT or normalized UBYTE/USHORT.
  std::uint32_t material_index = 0;
  int texcoord_set = 0;
  if (prim.material >= 0) {
    check_index(prim.material, m_.materials.size(), where, "material");
    material_index = static_cast<std::uint32_t>(prim.material);
    texcoord_set = material_texcoord_[static_cast<std::size_t>(prim.material)];
  } else {
    material_index = default_material();
  }
  sm.material = material_index;
  sm.uvs.assign(vertex_count, glm::vec2(0.0f));
  const std::string uv_attr = "TEXCOORD_" + std::to_string(texcoord_set);
  if (auto it = prim.attributes.find(uv_attr); it != prim.attributes.end()) {
    const tinygltf::Accessor& acc = m_.accessors[static_cast<std::size_t>(it->second)];
    const std::string desc = accessor_desc(it->second, uv_attr + " of " + where);
    const bool ok_type = acc.type == TINYGLTF_TYPE_VEC2 &&
                         (acc.componentType == TINYGLTF_COMPONENT_TYPE_FLOAT ||
                          ((acc.componentType == TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE ||
                            acc.componentType == TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT) &&
                           acc.normalized));
    if (!ok_type) {
      fail(desc + ": " + uv_attr + " must be VEC2 FLOAT or normalized UNSIGNED_BYTE/UNSIGNED_SHORT, found " +
           type_name(acc.type) + " " + component_name(acc.componentType));
    }
    const std::vector<float> v = read_accessor<float>(it->second, desc);
    for (std::size_t i = 0; i < vertex_count; ++i) sm.uvs[i] = glm::vec2(v[2 * i], v[2 * i + 1]);
  } else if (scene_.materials[material_index].base_color_texels >= 0) {  // a texture that is sampled
    // glTF 2.0 (section 3.9.2, textureInfo.texCoord): the primitive must provide the set the
    // material samples; with zero uvs every fragment would read one texel.
    fail(where + ": its material '" + scene_.materials[material_index].name + "' samples its base colour texture with " +
         uv_attr + " (baseColorTexture.texCoord = " + std::to_string(texcoord_set) + "), which the primitive lacks");
  }
  return uv_attr;
}

void Converter::check_other_attributes(const tinygltf::Primitive& prim, const std::string& where,
                                       const std::string& uv_attr) const {
  // Remaining attributes: validated (byte ranges), not kept.
  for (const auto& [attr, acc_index] : prim.attributes) {
    if (attr == "POSITION" || attr == "NORMAL" || attr == uv_attr || attr == kClipPositionAttribute) continue;
    std::size_t elem = 0;
    const tinygltf::Accessor& acc = m_.accessors[static_cast<std::size_t>(acc_index)];
    const std::string desc = accessor_desc(acc_index, attr + " of " + where);
    if (acc.bufferView >= 0) {
      elem = static_cast<std::size_t>(component_bytes(acc.componentType) * type_components(acc.type));
      view_range(acc.bufferView, acc.byteOffset, acc.count, elem, true, desc, nullptr);
    }
  }
}

std::vector<std::uint32_t> Converter::read_indices(const tinygltf::Primitive& prim, const std::string& where,
                                                   std::size_t vertex_count, SubMesh& sm) const {
  // Indices: scalar unsigned, all < vertex count. Non-indexed draws get 0..n-1 and index_bytes 0.
  std::vector<std::uint32_t> idx;
  if (prim.indices < 0) {
    idx.resize(vertex_count);
    for (std::size_t i = 0; i < vertex_count; ++i) idx[i] = static_cast<std::uint32_t>(i);
    sm.index_bytes = 0;
    return idx;
  }
  check_index(prim.indices, m_.accessors.size(), where + " indices", "accessor");
  const tinygltf::Accessor& acc = m_.accessors[static_cast<std::size_t>(prim.indices)];
  const std::string desc = accessor_desc(prim.indices, "indices of " + where);
  if (acc.type != TINYGLTF_TYPE_SCALAR ||
      (acc.componentType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE &&
       acc.componentType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT &&
       acc.componentType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT)) {
    fail(desc + ": indices must be SCALAR UNSIGNED_BYTE/UNSIGNED_SHORT/UNSIGNED_INT, found " + type_name(acc.type) + " " +
         component_name(acc.componentType));
  }
  if (acc.bufferView >= 0 && m_.bufferViews.size() > static_cast<std::size_t>(acc.bufferView) &&
      m_.bufferViews[static_cast<std::size_t>(acc.bufferView)].byteStride != 0) {
    fail(desc + ": the buffer view of indices must not have a byteStride");
  }
  idx = read_accessor<std::uint32_t>(prim.indices, desc);
  for (std::size_t i = 0; i < idx.size(); ++i) {
    if (idx[i] >= vertex_count) {
      fail(desc + ": index " + std::to_string(idx[i]) + " at position " + std::to_string(i) + " is out of range (" +
           std::to_string(vertex_count) + " vertices)");
    }
  }
  sm.index_bytes = static_cast<std::uint32_t>(component_bytes(acc.componentType));
  return idx;
}

void Converter::triangle_list(int mode, std::vector<std::uint32_t> idx, const std::string& where, SubMesh& sm) {
  // Topology to a triangle list (glTF 2.0 spec, section 3.7.2.1 winding for strips and fans).
  const std::size_t n = idx.size();
  if (mode == TINYGLTF_MODE_TRIANGLES) {
    if (n % 3 != 0) {
      scene_.warnings.push_back(where + ": " + std::to_string(n) + " indices is not a multiple of 3; the trailing ones are ignored");
    }
    idx.resize(n - n % 3);
    sm.indices = std::move(idx);
  } else if (n >= 3) {
    sm.indices.reserve((n - 2) * 3);
    for (std::size_t i = 0; i + 2 < n; ++i) {
      if (mode == TINYGLTF_MODE_TRIANGLE_STRIP) {
        sm.indices.push_back(idx[i]);
        sm.indices.push_back(idx[i + 1 + i % 2]);
        sm.indices.push_back(idx[i + 2 - i % 2]);
      } else {
        sm.indices.push_back(idx[i + 1]);
        sm.indices.push_back(idx[i + 2]);
        sm.indices.push_back(idx[0]);
      }
    }
  }
}

void Converter::smooth_face_normals(std::size_t vertex_count, SubMesh& sm) {
  // Missing normals: each triangle's face normal, area-weighted at shared vertices (exactly the
  // flat normal for non-indexed geometry and wherever a vertex joins coplanar triangles only).
  sm.normals.assign(vertex_count, glm::vec3(0.0f));
  for (std::size_t t = 0; t + 2 < sm.indices.size(); t += 3) {
    const std::uint32_t a = sm.indices[t], b = sm.indices[t + 1], c = sm.indices[t + 2];
    const glm::vec3 fn = glm::cross(sm.positions[b] - sm.positions[a], sm.positions[c] - sm.positions[a]);
    sm.normals[a] += fn;
    sm.normals[b] += fn;
    sm.normals[c] += fn;
  }
  for (glm::vec3& nrm : sm.normals) {
    const float len = glm::length(nrm);
    nrm = len > 0.0f && std::isfinite(len) ? nrm / len : glm::vec3(0.0f, 0.0f, 1.0f);
  }
}

const std::vector<std::uint32_t>& Converter::mesh_submeshes(int mesh) {
  auto it = mesh_cache_.find(mesh);
  if (it != mesh_cache_.end()) return it->second;
  std::vector<std::uint32_t> list;
  const tinygltf::Mesh& gmesh = m_.meshes[static_cast<std::size_t>(mesh)];
  for (std::size_t p = 0; p < gmesh.primitives.size(); ++p) convert_primitive(mesh, static_cast<int>(p), list);
  return mesh_cache_.emplace(mesh, std::move(list)).first->second;
}

void Converter::check_node_graph() {
  const std::size_t n = m_.nodes.size();
  std::vector<int> parent(n, -1);
  for (std::size_t i = 0; i < n; ++i) {
    const tinygltf::Node& node = m_.nodes[i];
    const std::string desc = node_desc(static_cast<int>(i));
    for (int c : node.children) {
      check_index(c, n, desc + " children", "node");
      if (static_cast<std::size_t>(c) == i) fail(desc + ": is its own child (node graph cycle)");
      if (parent[static_cast<std::size_t>(c)] >= 0) {
        fail(node_desc(c) + ": is a child of both " + node_desc(parent[static_cast<std::size_t>(c)]) + " and " + desc +
             " (glTF nodes must form a tree)");
      }
      parent[static_cast<std::size_t>(c)] = static_cast<int>(i);
    }
    if (node.mesh != -1) check_index(node.mesh, m_.meshes.size(), desc, "mesh");
    if (!node.matrix.empty() && node.matrix.size() != 16) {
      fail(desc + ": matrix has " + std::to_string(node.matrix.size()) + " values, expected 16");
    }
  }
  // With one parent per node, a cycle is a loop when walking up the parent chain.
  std::vector<std::uint8_t> state(n, 0);  // 0 unvisited, 1 on the current walk, 2 known to reach a root
  for (std::size_t start = 0; start < n; ++start) {
    std::vector<std::size_t> walk;
    std::size_t cur = start;
    for (;;) {
      if (state[cur] == 2) break;
      if (state[cur] == 1) {
        std::string chain = std::to_string(cur);
        for (std::size_t c = static_cast<std::size_t>(parent[cur]); c != cur; c = static_cast<std::size_t>(parent[c]))
          chain = std::to_string(c) + " -> " + chain;
        fail(node_desc(static_cast<int>(cur)) + ": node graph cycle (parent -> child: " + std::to_string(cur) +
             " -> " + chain + ")");
      }
      state[cur] = 1;
      walk.push_back(cur);
      if (parent[cur] < 0) break;
      cur = static_cast<std::size_t>(parent[cur]);
    }
    for (std::size_t w : walk) state[w] = 2;
  }
  parent_ = std::move(parent);
}

NodeTransform Converter::node_transform(int node_index) const {
  const tinygltf::Node& node = m_.nodes[static_cast<std::size_t>(node_index)];
  NodeTransform t;
  if (node.matrix.size() == 16) {
    t.has_matrix = true;
    for (int c = 0; c < 4; ++c)
      for (int r = 0; r < 4; ++r) t.matrix[c][r] = static_cast<float>(node.matrix[static_cast<std::size_t>(c * 4 + r)]);
  } else {
    if (node.translation.size() == 3)
      t.translation = glm::vec3(static_cast<float>(node.translation[0]), static_cast<float>(node.translation[1]),
                                static_cast<float>(node.translation[2]));
    else if (!node.translation.empty())
      fail(node_desc(node_index) + ": translation must have 3 values");
    if (node.rotation.size() == 4)
      t.rotation = glm::quat(static_cast<float>(node.rotation[3]), static_cast<float>(node.rotation[0]),
                             static_cast<float>(node.rotation[1]), static_cast<float>(node.rotation[2]));
    else if (!node.rotation.empty())
      fail(node_desc(node_index) + ": rotation must have 4 values");
    if (node.scale.size() == 3)
      t.scale = glm::vec3(static_cast<float>(node.scale[0]), static_cast<float>(node.scale[1]),
                          static_cast<float>(node.scale[2]));
    else if (!node.scale.empty())
      fail(node_desc(node_index) + ": scale must have 3 values");
    const float ql = glm::length(t.rotation);
    if (ql > 0.0f && std::isfinite(ql)) t.rotation = t.rotation / ql;
  }
  return t;
}

glm::mat4 Converter::local_matrix(int node_index) const {
  const glm::mat4 m = node_transform(node_index).local();
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 4; ++r)
      if (!std::isfinite(m[c][r])) fail(node_desc(node_index) + ": transform has a non-finite value");
  return m;
}

void Converter::convert_animations() {
  SceneAnimation& out = scene_.animation;
  for (std::size_t n = 0; n < m_.nodes.size(); ++n) {
    out.nodes.push_back(SceneNode{.parent = parent_[n], .rest = node_transform(static_cast<int>(n))});
  }
  for (std::size_t a = 0; a < m_.animations.size(); ++a) {
    const tinygltf::Animation& ga = m_.animations[a];
    const std::string adesc = "animation " + std::to_string(a) + quoted_name(ga.name);
    Animation anim;
    anim.name = ga.name.empty() ? "animation " + std::to_string(a) : ga.name;
    for (std::size_t c = 0; c < ga.channels.size(); ++c) {
      const tinygltf::AnimationChannel& gc = ga.channels[c];
      const std::string cdesc = adesc + " channel " + std::to_string(c);
      if (gc.target_node < 0) continue;  // targets an extension's object: nothing to move here
      check_index(gc.target_node, m_.nodes.size(), cdesc + " target", "node");
      check_index(gc.sampler, ga.samplers.size(), cdesc, "sampler");
      AnimationChannel ch;
      ch.node = static_cast<std::uint32_t>(gc.target_node);
      std::size_t components = 3;
      if (gc.target_path == "translation") {
        ch.path = AnimationPath::Translation;
      } else if (gc.target_path == "rotation") {
        ch.path = AnimationPath::Rotation;
        components = 4;
      } else if (gc.target_path == "scale") {
        ch.path = AnimationPath::Scale;
      } else if (gc.target_path == "weights") {
        scene_.warnings.push_back(cdesc + ": morph target weights are not animated (the mesh keeps its base shape)");
        continue;
      } else {
        fail(cdesc + ": target path '" + gc.target_path + "' is not translation, rotation, scale or weights");
      }
      if (out.nodes[ch.node].rest.has_matrix) {
        fail(cdesc + ": animates " + node_desc(gc.target_node) + ", which has a matrix (glTF 2.0: animated nodes use TRS)");
      }
      const tinygltf::AnimationSampler& gs = ga.samplers[static_cast<std::size_t>(gc.sampler)];
      const std::string sdesc = adesc + " sampler " + std::to_string(gc.sampler);
      if (gs.interpolation.empty() || gs.interpolation == "LINEAR") {
        ch.interpolation = AnimationInterpolation::Linear;
      } else if (gs.interpolation == "STEP") {
        ch.interpolation = AnimationInterpolation::Step;
      } else if (gs.interpolation == "CUBICSPLINE") {
        ch.interpolation = AnimationInterpolation::CubicSpline;
      } else {
        fail(sdesc + ": interpolation '" + gs.interpolation + "' is not LINEAR, STEP or CUBICSPLINE");
      }
      check_index(gs.input, m_.accessors.size(), sdesc + " input", "accessor");
      check_index(gs.output, m_.accessors.size(), sdesc + " output", "accessor");
      if (type_components(m_.accessors[static_cast<std::size_t>(gs.input)].type) != 1) fail(sdesc + " input: key times must be SCALAR");
      if (static_cast<std::size_t>(type_components(m_.accessors[static_cast<std::size_t>(gs.output)].type)) != components) {
        fail(sdesc + " output: a " + gc.target_path + " channel needs " + (components == 4 ? "VEC4" : "VEC3") + " values");
      }
      ch.times = read_accessor<float>(gs.input, sdesc + " input");
      for (std::size_t k = 0; k < ch.times.size(); ++k) {
        if (!std::isfinite(ch.times[k]) || ch.times[k] < 0.0f || (k > 0 && ch.times[k] < ch.times[k - 1])) {
          fail(sdesc + " input: key time " + std::to_string(k) + " is negative, not finite or before the one before it");
        }
      }
      const std::vector<float> v = read_accessor<float>(gs.output, sdesc + " output");
      const std::size_t per_key = ch.interpolation == AnimationInterpolation::CubicSpline ? 3 : 1;
      if (v.size() != ch.times.size() * per_key * components) {
        fail(sdesc + " output: " + std::to_string(v.size() / components) + " values for " + std::to_string(ch.times.size()) +
             " key times (" + std::to_string(per_key) + " per key expected)");
      }
      for (std::size_t i = 0; i < v.size(); i += components) {
        glm::vec4 value(v[i], v[i + 1], v[i + 2], components == 4 ? v[i + 3] : 0.0f);
        for (int k = 0; k < 4; ++k) {
          if (!std::isfinite(value[k])) fail(sdesc + " output: value " + std::to_string(i / components) + " is not finite");
        }
        ch.values.push_back(value);
      }
      anim.duration_s = std::max(anim.duration_s, ch.times.back());
      anim.channels.push_back(std::move(ch));
    }
    out.animations.push_back(std::move(anim));
  }
  if (!m_.skins.empty()) scene_.warnings.push_back("skins are not applied: skinned meshes keep their bind pose");
}

void Converter::place_node(int root, const glm::mat4& parent) {
  // Depth-first, children in order, with an explicit stack (node chains can be deep).
  std::vector<std::pair<int, glm::mat4>> stack = {{root, parent}};
  while (!stack.empty()) {
    const auto [node_index, parent_world] = stack.back();
    stack.pop_back();
    const tinygltf::Node& node = m_.nodes[static_cast<std::size_t>(node_index)];
    const glm::mat4 world = parent_world * local_matrix(node_index);
    if (node.mesh >= 0) {
      for (std::uint32_t sm : mesh_submeshes(node.mesh)) {
        Instance inst;
        inst.submesh = sm;
        inst.world = world;
        inst.node = node.name.empty() ? "node " + std::to_string(node_index) : node.name;
        scene_.instances.push_back(std::move(inst));
        scene_.animation.instance_node.push_back(node_index);
      }
    }
    for (auto it = node.children.rbegin(); it != node.children.rend(); ++it) stack.emplace_back(*it, world);
  }
}

void Converter::run() {
  for (const std::string& ext : m_.extensionsRequired) {
    if (ext == "KHR_draco_mesh_compression" || ext == "EXT_meshopt_compression" || ext == "KHR_mesh_quantization") {
      fail("requires extension " + ext + ", which tbdrsim does not support");
    }
    scene_.warnings.push_back("required extension " + ext + " is ignored");
  }
  collect_textures();
  convert_materials();
  check_node_graph();

  std::vector<int> roots;
  if (!m_.scenes.empty()) {
    int s = m_.defaultScene >= 0 ? m_.defaultScene : 0;
    check_index(s, m_.scenes.size(), "default scene", "scene");
    const tinygltf::Scene& sc = m_.scenes[static_cast<std::size_t>(s)];
    for (int r : sc.nodes) {
      check_index(r, m_.nodes.size(), "scene " + std::to_string(s) + quoted_name(sc.name), "node");
      if (parent_[static_cast<std::size_t>(r)] >= 0) {
        scene_.warnings.push_back("scene " + std::to_string(s) + " lists " + node_desc(r) + " as a root, but it is a child of " +
                                  node_desc(parent_[static_cast<std::size_t>(r)]) + "; it is placed twice");
      }
      roots.push_back(r);
    }
  } else {
    std::vector<bool> is_child(m_.nodes.size(), false);
    for (const auto& node : m_.nodes)
      for (int c : node.children) is_child[static_cast<std::size_t>(c)] = true;
    for (std::size_t i = 0; i < m_.nodes.size(); ++i)
      if (!is_child[i]) roots.push_back(static_cast<int>(i));
  }
  for (int r : roots) place_node(r, glm::mat4(1.0f));
  convert_animations();
  if (m_.nodes.empty() && !m_.meshes.empty()) {
    scene_.warnings.push_back("no nodes: each mesh is placed once at the origin");
    for (std::size_t mi = 0; mi < m_.meshes.size(); ++mi) {
      for (std::uint32_t sm : mesh_submeshes(static_cast<int>(mi))) {
        Instance inst;
        inst.submesh = sm;
        inst.node = "mesh " + std::to_string(mi);
        scene_.instances.push_back(std::move(inst));
      }
    }
  }
  if (scene_.instances.empty()) scene_.warnings.push_back("the scene has no triangles");
}

}  // namespace

std::optional<ImageHeader> parse_image_header(const std::uint8_t* d, std::size_t n) {
  if (d == nullptr) return std::nullopt;
  static const std::uint8_t png_sig[8] = {0x89, 'P', 'N', 'G', 0x0D, 0x0A, 0x1A, 0x0A};
  if (n >= 8 && std::memcmp(d, png_sig, 8) == 0) return parse_png(d, n);
  if (n >= 3 && d[0] == 0xFF && d[1] == 0xD8 && d[2] == 0xFF) return parse_jpeg(d, n);
  if (n >= 10 && (std::memcmp(d, "GIF87a", 6) == 0 || std::memcmp(d, "GIF89a", 6) == 0)) {
    ImageHeader h{"gif", le16(d + 6), le16(d + 8), 4};
    if (h.width > 0 && h.height > 0) return h;
    return std::nullopt;
  }
  if (n >= 30 && d[0] == 'B' && d[1] == 'M') {
    const auto w = static_cast<std::int32_t>(le32(d + 18));
    const auto h = static_cast<std::int32_t>(le32(d + 22));
    const int bpp = le16(d + 28);
    ImageHeader hd{"bmp", w, h < 0 ? -h : h, bpp == 32 ? 4 : bpp == 8 ? 1 : 3};
    if (hd.width > 0 && hd.height > 0) return hd;
    return std::nullopt;
  }
  static const std::uint8_t ktx2_sig[12] = {0xAB, 'K', 'T', 'X', ' ', '2', '0', 0xBB, 0x0D, 0x0A, 0x1A, 0x0A};
  if (n >= 28 && std::memcmp(d, ktx2_sig, 12) == 0) {
    ImageHeader h{"ktx2", static_cast<int>(le32(d + 20)), static_cast<int>(le32(d + 24)), 4};
    if (h.width > 0 && h.height > 0) return h;
    return std::nullopt;
  }
  return std::nullopt;
}

Scene load_gltf(const std::string& path) {
  check_input_file(path, "scene file");  // not found, permission denied, a folder, a symlink loop: by name
  const std::vector<std::uint8_t> bytes = read_all(path);
  const bool binary = bytes.size() >= 4 && std::memcmp(bytes.data(), "glTF", 4) == 0;
  if (binary) {
    // GLB header (glTF 2.0 specification, section 4.4.3): magic, version, length. Version 1 is the
    // binary glTF 1.0 extension, whose JSON tinygltf would read as 2.0.
    if (bytes.size() < 12) throw InputError(path, "GLB header truncated (" + std::to_string(bytes.size()) + " of 12 bytes)");
    const std::uint32_t version = le32(bytes.data() + 4);
    if (version != 2) {
      throw InputError(path, "GLB header version " + std::to_string(version) + " (byte 4): only version 2 (glTF 2.0) is read");
    }
    if (bytes.size() >= 20) {
      const std::size_t chunk = std::min<std::size_t>(le32(bytes.data() + 12), bytes.size() - 20);
      check_json_nesting(path, bytes.data() + 20, chunk, 20, true);
    }
  } else {
    check_json_nesting(path, bytes.data(), bytes.size(), 0, false);
  }
  if (auto j = extract_json(bytes, binary)) {
    JsonTypeCheck(path).run(*j);
    precheck_json(path, *j);
  }

  tinygltf::TinyGLTF loader;
  loader.SetImageLoader(&keep_encoded_image, nullptr);
  tinygltf::Model model;
  std::string err, warn;
  const std::string base_dir = fs::path(path).parent_path().string();
  bool ok = false;
  if (binary) {
    ok = loader.LoadBinaryFromMemory(&model, &err, &warn, bytes.data(), static_cast<unsigned int>(bytes.size()),
                                     base_dir);
  } else {
    ok = loader.LoadASCIIFromString(&model, &err, &warn, reinterpret_cast<const char*>(bytes.data()),
                                    static_cast<unsigned int>(bytes.size()), base_dir);
  }
  if (!ok) {
    std::string msg = err.empty() ? "tinygltf could not parse the file" : err;
    while (!msg.empty() && (msg.back() == '\n' || msg.back() == '\r')) msg.pop_back();
    for (char& c : msg)
      if (c == '\n') c = ';';
    throw InputError(path, "invalid glTF: " + msg);
  }

  Scene scene;
  scene.name = fs::path(path).stem().string();
  scene.source = path;
  // tinygltf's own warnings, less those about images that collect_textures() words better.
  std::istringstream ws(warn);
  for (std::string line; std::getline(ws, line);) {
    if (line.empty() || line.find("File not found") != std::string::npos ||
        line.find("for image[") != std::string::npos)
      continue;
    scene.warnings.push_back("tinygltf: " + line);
  }

  Converter conv(path, model, scene);
  conv.run();
  update_bounds(scene);

  // Content hash: the file's bytes, then each external buffer's, then each external image's.
  Fnv1a64 h;
  h.update(bytes.data(), bytes.size());
  for (const tinygltf::Buffer& b : model.buffers)
    if (!b.uri.empty() && !is_data_uri(b.uri)) h.update(b.data.data(), b.data.size());
  for (const tinygltf::Image& img : model.images)
    if (!img.uri.empty() && !is_data_uri(img.uri)) h.update(img.image.data(), img.image.size());
  scene.content_hash = h.hex();
  return scene;
}

}  // namespace tbdr
