#include "models/config_checks.hpp"

#include <cstdint>
#include <limits>

#include "kernel/bits.hpp"
#include "kernel/errors.hpp"

namespace tbdr {

namespace {

/// The caches of CachesParams with their key prefixes, in the order they are checked.
struct CacheRef {
  const char* key;
  CacheParams CachesParams::*member;
};
constexpr CacheRef kCaches[] = {{"cache.texture", &CachesParams::texture},
                                {"cache.vertex", &CachesParams::vertex},
                                {"cache.slc", &CachesParams::slc},
                                {"cache.rop_depth", &CachesParams::rop_depth},
                                {"cache.rop_color", &CachesParams::rop_color}};

/// The least number of parameter-buffer pages one binned primitive allocates: the tiler rounds
/// primitive blocks, control streams and region headers up to whole pages separately
/// (Tiler::allocated_with), so a capacity below three pages cannot hold a single primitive.
constexpr std::int64_t kMinPbPages = 3;

std::string v(std::int64_t x) { return std::to_string(x); }

std::optional<ConstraintViolation> check_cache(const std::string& k, const CacheParams& c) {
  const std::string size = k + ".size_bytes", ways = k + ".ways", line = k + ".line_bytes";
  if (c.line_bytes <= 0 || !is_pow2(static_cast<std::uint64_t>(c.line_bytes))) {
    return ConstraintViolation{line + " = " + v(c.line_bytes) +
                                   " must be a power of two (the cache finds a line's set from the address bits above it)",
                               {line}};
  }
  if (c.ways <= 0 || c.size_bytes <= 0 || c.size_bytes % (c.ways * c.line_bytes) != 0) {
    return ConstraintViolation{size + " = " + v(c.size_bytes) + " must be a positive multiple of " + ways + " x " + line +
                                   " = " + v(c.ways) + " x " + v(c.line_bytes) + " = " + v(c.ways * c.line_bytes) +
                                   " (whole sets)",
                               {size, ways, line}};
  }
  const std::int64_t sets = c.size_bytes / (c.ways * c.line_bytes);
  if (sets > static_cast<std::int64_t>(std::numeric_limits<std::uint32_t>::max() / static_cast<std::uint64_t>(c.ways))) {
    return ConstraintViolation{size + " / " + line + " = " + v(sets * c.ways) + " lines, more than the 2^32 the cache indexes",
                               {size, line}};
  }
  return std::nullopt;
}

const std::vector<std::string>& all_keys() {
  static const std::vector<std::string> keys = [] {
    std::vector<std::string> k;
    for (const auto& c : kCaches) {
      for (const char* n : {".size_bytes", ".ways", ".line_bytes"}) k.push_back(std::string(c.key) + n);
    }
    for (const char* n : {"dram.row_bytes", "dram.burst_bytes", "dram.banks", "dram.bank_groups", "dram.t_refi_ns",
                          "dram.t_rfc_ns", "tiling.pb_capacity_bytes", "tiling.pb_page_bytes", "geometry.subpixel_bits"}) {
      k.emplace_back(n);
    }
    return k;
  }();
  return keys;
}

}  // namespace

std::optional<ConstraintViolation> first_constraint_violation(const HwConfig& hw) {
  for (const auto& c : kCaches) {
    if (auto bad = check_cache(c.key, hw.cache.*(c.member))) return bad;
  }
  const DramParams& d = hw.dram;
  if (d.burst_bytes < 1 || d.row_bytes < d.burst_bytes || d.row_bytes % d.burst_bytes != 0) {
    return ConstraintViolation{"dram.row_bytes = " + v(d.row_bytes) + " must be a positive multiple of dram.burst_bytes = " +
                                   v(d.burst_bytes) + " (a row is read in whole bursts)",
                               {"dram.row_bytes", "dram.burst_bytes"}};
  }
  if (d.bank_groups < 1 || d.banks % d.bank_groups != 0) {
    return ConstraintViolation{"dram.bank_groups = " + v(d.bank_groups) + " must divide dram.banks = " + v(d.banks) +
                                   " (every group has the same number of banks)",
                               {"dram.bank_groups", "dram.banks"}};
  }
  if (d.t_refi_ns > 0 && d.t_rfc_ns > 0 && d.t_rfc_ns >= d.t_refi_ns) {
    return ConstraintViolation{"dram.t_rfc_ns = " + format_param_value(d.t_rfc_ns) +
                                   " must be shorter than dram.t_refi_ns = " + format_param_value(d.t_refi_ns) +
                                   " (a refresh must end before the next is due; 0 in either turns refresh off)",
                               {"dram.t_rfc_ns", "dram.t_refi_ns"}};
  }
  if (d.row_bytes % hw.cache.slc.line_bytes != 0) {
    return ConstraintViolation{"dram.row_bytes = " + v(d.row_bytes) + " must be a multiple of cache.slc.line_bytes = " +
                                   v(hw.cache.slc.line_bytes) + " (a line the SLC fetches lies in one DRAM row)",
                               {"dram.row_bytes", "cache.slc.line_bytes"}};
  }
  const TilingParams& t = hw.tiling;
  if (t.pb_capacity_bytes < kMinPbPages * t.pb_page_bytes) {
    return ConstraintViolation{"tiling.pb_capacity_bytes = " + v(t.pb_capacity_bytes) + " must hold at least " +
                                   v(kMinPbPages) + " pages of tiling.pb_page_bytes = " + v(t.pb_page_bytes) + " (" +
                                   v(kMinPbPages * t.pb_page_bytes) +
                                   " bytes: one binned primitive takes a page of primitive blocks, one of control "
                                   "streams and one of region headers)",
                               {"tiling.pb_capacity_bytes", "tiling.pb_page_bytes"}};
  }
  if (hw.geometry.subpixel_bits < 1) {
    return ConstraintViolation{"geometry.subpixel_bits = " + v(hw.geometry.subpixel_bits) +
                                   " must be at least 1 (a single sample sits at the pixel's centre, half a pixel in)",
                               {"geometry.subpixel_bits"}};
  }
  return std::nullopt;
}

const std::vector<std::string>& constrained_param_keys() { return all_keys(); }

void check_config_constraints(const HwConfig& hw, const ResolvedParams& params) {
  const auto bad = first_constraint_violation(hw);
  if (!bad) return;
  const ParamTable& table = hw_params().table();
  std::string where;
  std::string origins;
  for (const auto& key : bad->keys) {
    const int i = table.find(key);
    const std::string origin = i < 0 ? "default" : params.origins[static_cast<std::size_t>(i)].text;
    if (where.empty() && origin != "default") where = origin;
    origins += (origins.empty() ? "" : "; ") + key + " from " + origin;
  }
  throw InputError(where, bad->message + " [" + origins + "]");
}

}  // namespace tbdr
