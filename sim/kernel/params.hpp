#pragma once
// Parameters: every hardware parameter is declared exactly once (key, type, default, unit, range or
// choices, doc, source) in a ParamRegistry bound to the plain struct the units read on their hot
// paths. Resolution layers the declared defaults, config files (INI, read by
// Boost.Program_options) and --set overrides, and remembers where each value came from.
#include <cstdint>
#include <functional>
#include <limits>
#include <map>
#include <memory>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <type_traits>
#include <variant>
#include <vector>

namespace tbdr {

/// `s` without its leading and trailing blanks (space, tab, CR, LF).
std::string trim(const std::string& s);

/// The largest config or sweep file read (bytes): such files are a few kilobytes; a bound keeps a
/// wrong path (a trace, a log) from being read whole. docs/limits.md lists it with the others.
inline constexpr std::uint64_t kMaxIniFileBytes = 1u << 20;

/// Refuses a path longer than the operating system allows, as it reports it: the whole path
/// against pathconf(_PC_PATH_MAX) and each component against pathconf(_PC_NAME_MAX) of the
/// nearest existing folder (PATH_MAX and NAME_MAX when pathconf has no answer). InputError names
/// the path's start, its length and the limit, so a caller never meets ENAMETOOLONG later.
void check_path_length(const std::string& path, const std::string& what);

/// Refuses an input path that cannot be read as a file, saying why by name: not found, permission
/// denied (on the file or a folder on its way), a folder, a symlink loop, and (unless
/// `allow_special`: a trace may be a stream) a device, FIFO or socket. Checks the path's length
/// first (check_path_length). InputError naming the path and `what` ("trace", "config file").
void check_input_file(const std::string& path, const std::string& what, bool allow_special = false);

/// `text` without a leading UTF-8 byte-order mark (EF BB BF), which editors on Windows write.
std::string_view strip_utf8_bom(std::string_view text);

/// Reads a whole text input (`what`: "config file", "sweep file"): its path checked
/// (check_path_length), refused above `max_bytes` before it is read, a UTF-8 byte-order mark
/// dropped. InputError naming the file when it cannot be opened or is too large.
std::string read_text_input(const std::string& path, const std::string& what, std::uint64_t max_bytes);

/// One `key = value` line of an INI file (a config file, a sweep file), with its line number.
struct IniLine {
  std::string section;  ///< the [section] it stands in ("" before the first header)
  std::string name;     ///< the key within its section
  std::string key;      ///< "section.name" (or the bare name outside any section), as Boost.Program_options reports it
  std::string value;    ///< the value text as Boost.Program_options read it
  long line = 0;        ///< 1-based line in the file
};

/// What one kind of INI file may hold; read_ini_file refuses everything else.
struct IniRules {
  const char* what = "config file";                        ///< the file kind in errors
  std::function<bool(const std::string&)> known_section;   ///< is [section] allowed?
  std::string known_sections;                              ///< listed when a section is not
  bool keys_need_section = false;                          ///< refuse keys before the first [section]
  bool sections_once = false;                              ///< refuse a [section] header met twice
  std::function<bool(const IniLine&)> may_repeat;          ///< keys that may be set again (empty: none)
};

/// Reads an INI file: a line scan that keeps line numbers and is strict (the rules; '#' starts a
/// comment anywhere, [section] headers, key = value; a key set twice), then Boost.Program_options
/// (allow_unregistered) for the values, checked to find the same keys in the same order. The file is
/// read by read_text_input (path length, kMaxIniFileBytes, a UTF-8 byte-order mark). Every
/// error is an InputError naming file:line. `section_lines`, when given, receives the first line
/// of each [section].
std::vector<IniLine> read_ini_file(const std::string& path, const IniRules& rules,
                                   std::map<std::string, long>* section_lines = nullptr);

/// The value of one parameter: integer, real, boolean, or text (free text or one of a choice list).
using ParamValue = std::variant<std::int64_t, double, bool, std::string>;

/// The kind of value a parameter holds.
enum class ParamType : std::uint8_t { Int, Real, Bool, Text, Choice };
const char* to_string(ParamType t);

/// Canonical text of a value (shortest round-trip for reals, "true"/"false" for booleans).
std::string format_param_value(const ParamValue& v);

/// One declared parameter: everything `tbdrsim params` prints and everything validation needs.
struct ParamDecl {
  std::string key;            ///< "section.name", e.g. "isp.samples_per_clock"
  ParamType type = ParamType::Int;
  ParamValue default_value;
  std::string unit;           ///< "MHz", "bytes", "pJ/bit", "" for dimensionless
  std::string doc;            ///< one line
  std::string source;         ///< where the default comes from (document, vendor table), or why
  double min = -std::numeric_limits<double>::infinity();  ///< inclusive, Int/Real only
  double max = std::numeric_limits<double>::infinity();   ///< inclusive, Int/Real only
  std::vector<std::string> choices;                       ///< Choice only

  std::string section() const;     ///< key up to the last '.'
  std::string range_text() const;  ///< "[1, 1024]", "one of a|b|c", "true|false", "any text"
  /// Parses and validates text for this parameter; on failure returns false and sets `why`
  /// to what was expected.
  bool parse(const std::string& text, ParamValue& out, std::string& why) const;
};

/// One enumerator of a choice parameter bound to an enum, and its spelling in config files.
template <class E>
struct ChoiceName {
  E value;
  const char* name;
};

/// The spelling of `v` in `names` ("?" when it is not listed).
template <class E>
constexpr const char* choice_name(std::span<const ChoiceName<E>> names, E v) {
  for (const auto& n : names) {
    if (n.value == v) return n.name;
  }
  return "?";
}

/// Where a resolved value came from: the declaration, a config file line, or a --set argument.
struct ParamOrigin {
  std::string text = "default";  ///< "default", "configs/x.ini:12", "--set isp.tag_buffers=4"
};

/// A fully resolved parameter set: one value and one origin per declaration, in declaration order.
struct ResolvedParams {
  std::vector<ParamValue> values;
  std::vector<ParamOrigin> origins;
  std::string config_name = "default";  ///< stem of the last config file, or the defaults' name (ParamTable::name_defaults)
};

/// The list of declarations, independent of the struct they bind to.
class ParamTable {
 public:
  /// Fluent setter returned by ParamTable::declare for the optional attributes.
  class Builder {
   public:
    explicit Builder(ParamDecl& d) : d_(d) {}
    Builder& unit(std::string u) { d_.unit = std::move(u); return *this; }
    Builder& doc(std::string s) { d_.doc = std::move(s); return *this; }
    Builder& source(std::string s) { d_.source = std::move(s); return *this; }
    Builder& range(double lo, double hi) { d_.min = lo; d_.max = hi; return *this; }
    Builder& choices(std::vector<std::string> c) { d_.type = ParamType::Choice; d_.choices = std::move(c); return *this; }

   private:
    ParamDecl& d_;
  };

  /// Declares a parameter; throws std::logic_error on a duplicate key or a default outside its range.
  Builder declare(std::string key, ParamType type, ParamValue default_value);
  /// Declares a section so its name is known (and documented) even before it has keys.
  void section(std::string name, std::string doc);
  /// Records a key that was removed: a config file or --set that still sets it is refused with
  /// `replacement` (what to set instead) rather than a bare "unknown parameter".
  void retire(std::string key, std::string replacement);
  /// What replaced a removed key, or nullptr when `key` was never retired.
  const std::string* retired(const std::string& key) const;

  const std::vector<ParamDecl>& decls() const { return decls_; }
  const std::vector<std::pair<std::string, std::string>>& sections() const { return sections_; }
  /// Index of a key, or -1.
  int find(const std::string& key) const;
  bool has_section(const std::string& name) const;

  /// The defaults, every origin "default", named as name_defaults() says ("default" unless set).
  ResolvedParams defaults() const;
  /// Names the defaults (the config_name of a configuration resolved without a config file): the
  /// preset file that equals them, so that one hardware has one name with and without that file.
  void name_defaults(std::string name) { defaults_name_ = std::move(name); }
  /// The preset a configuration is named after: the defaults plus the last of `config_files`
  /// (config_name: that file's stem), the defaults alone without files.
  ResolvedParams preset(const std::vector<std::string>& config_files) const;
  /// The label of a configuration: its config_name followed by " key=value" for every parameter
  /// whose value differs from `preset`'s (preset(its files)), sorted by key, e.g.
  /// "series6xt_gx6450 tiling.tile_height=16 tiling.tile_width=16". A function of the values, not
  /// of how they were set: one hardware and preset, one label (run, sweep, study).
  std::string label(const ResolvedParams& p, const ResolvedParams& preset) const;
  /// Applies one INI file (Boost.Program_options parser) on top of `p`. Unknown section or key,
  /// malformed line, duplicate key, bad value: InputError naming file:line, key, value, expectation.
  void apply_config_file(ResolvedParams& p, const std::string& path) const;
  /// Applies one "section.key=value" override. Errors name the --set argument.
  void apply_override(ResolvedParams& p, const std::string& assignment) const;
  /// Defaults, then every file in order, then every override in order.
  ResolvedParams resolve(const std::vector<std::string>& config_files,
                         const std::vector<std::string>& overrides) const;
  /// Hash of the canonical "key=value" lines of every parameter (the run's config hash).
  std::string hash(const ResolvedParams& p) const;

 private:
  void check_default(const ParamDecl& d) const;
  std::vector<ParamDecl> decls_;
  std::vector<std::pair<std::string, std::string>> sections_;
  std::vector<std::pair<std::string, std::string>> retired_;  ///< removed key, what replaced it
  std::string defaults_name_ = "default";                      ///< config_name of the defaults
};

/// A ParamTable bound to a plain struct `Config`: each declaration also knows how to write its
/// value into the struct member it configures, so units read members, never strings.
template <class Config>
class ParamRegistry {
 public:
  /// A member accessor, e.g. [](Config& c) -> auto& { return c.isp.samples_per_clock; }.
  template <class T>
  using Accessor = T& (*)(Config&);

  ParamTable::Builder add(std::string key, std::int64_t& (*acc)(Config&), std::int64_t def) {
    binders_.push_back([acc](Config& c, const ParamValue& v) { acc(c) = std::get<std::int64_t>(v); });
    return table_.declare(std::move(key), ParamType::Int, def);
  }
  ParamTable::Builder add(std::string key, double& (*acc)(Config&), double def) {
    binders_.push_back([acc](Config& c, const ParamValue& v) { acc(c) = std::get<double>(v); });
    return table_.declare(std::move(key), ParamType::Real, def);
  }
  ParamTable::Builder add(std::string key, bool& (*acc)(Config&), bool def) {
    binders_.push_back([acc](Config& c, const ParamValue& v) { acc(c) = std::get<bool>(v); });
    return table_.declare(std::move(key), ParamType::Bool, def);
  }
  /// Text parameters; call .choices({...}) on the result to restrict them.
  ParamTable::Builder add(std::string key, std::string& (*acc)(Config&), std::string def) {
    binders_.push_back([acc](Config& c, const ParamValue& v) { acc(c) = std::get<std::string>(v); });
    return table_.declare(std::move(key), ParamType::Text, std::move(def));
  }
  /// Choice parameters bound to an enum member. `names` spells every enumerator, in the order the
  /// choices are listed, and must outlive the registry (a static table). The text stays the
  /// parameter's value (config files, `tbdrsim params`, the database); the struct gets the
  /// enumerator, looked up once when the config is built, so units never compare strings.
  template <class E>
    requires std::is_enum_v<E>
  ParamTable::Builder add(std::string key, std::type_identity_t<E& (*)(Config&)> acc, E def,
                          std::type_identity_t<std::span<const ChoiceName<E>>> names) {
    std::vector<std::string> choices;
    for (const auto& n : names) choices.emplace_back(n.name);
    const std::string def_name = choice_name(names, def);
    binders_.push_back([acc, names, key](Config& c, const ParamValue& v) {
      const auto& text = std::get<std::string>(v);
      for (const auto& n : names) {
        if (text == n.name) {
          acc(c) = n.value;
          return;
        }
      }
      throw std::logic_error("parameter " + key + ": '" + text + "' is not one of its choices");
    });
    return table_.declare(std::move(key), ParamType::Text, def_name).choices(std::move(choices));
  }
  void section(std::string name, std::string doc) { table_.section(std::move(name), std::move(doc)); }
  /// See ParamTable::name_defaults.
  void name_defaults(std::string name) { table_.name_defaults(std::move(name)); }
  /// See ParamTable::retire.
  void retire(std::string key, std::string replacement) { table_.retire(std::move(key), std::move(replacement)); }

  const ParamTable& table() const { return table_; }
  /// Writes every resolved value into a fresh Config.
  Config build(const ResolvedParams& p) const {
    Config c{};
    for (std::size_t i = 0; i < binders_.size(); ++i) binders_[i](c, p.values[i]);
    return c;
  }

 private:
  ParamTable table_;
  std::vector<std::function<void(Config&, const ParamValue&)>> binders_;
};

}  // namespace tbdr
