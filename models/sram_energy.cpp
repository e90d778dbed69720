#include "models/sram_energy.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

#include "models/hw_config.hpp"
#include "models/sram_energy_table.hpp"

namespace tbdr {

namespace {

/// Stillmaker & Baas, "Scaling equations for the accurate prediction of CMOS device performance from
/// 180 nm to 7 nm", Integration 58 (2017): energy factor a Vdd^2 + b Vdd + c per node, fitted to their
/// HSpice runs (PTM and ITRS models). The coefficients are their energy table's (the one the 2017
/// corrigendum calls Table 5; its worked example's 65 nm row, 3.755 / -4.398 / 1.975, is this one).
/// At 45 nm, 1.0 V the factor is 1.018: the table is normalised to 45 nm.
struct EnergyFit {
  double node_nm, a, b, c;
};
constexpr std::array<EnergyFit, 10> kStillmakerEnergy{{
    {130, 7.171, -6.709, 2.904},
    {90, 4.762, -4.781, 2.092},
    {65, 3.755, -4.398, 1.975},
    {45, 1.103, -0.362, 0.2767},
    {32, 0.9559, -0.7823, 0.471},
    {20, 0.373, -0.1582, 0.04104},
    {16, 0.2958, -0.1241, 0.03024},
    {14, 0.2363, -0.09675, 0.02239},
    {10, 0.2068, -0.09311, 0.02375},
    {7, 0.1776, -0.09097, 0.02447},
}};

/// The node and supply voltage of Horowitz's ISSCC 2014 per-op energies.
constexpr double kHorowitzNodeNm = 45.0;
constexpr double kHorowitzVddV = 0.9;

/// The nodes CACTI 7 was run at (scripts/cacti/run_cacti.sh), ascending.
constexpr std::array<int, 5> kCactiNodes{22, 32, 45, 65, 90};

double fit_at(const EnergyFit& f, double vdd) { return f.a * vdd * vdd + f.b * vdd + f.c; }

/// Linear interpolation of the sorted-by-x points at x (extrapolated from the nearest two beyond the ends).
double interpolate(const std::vector<std::pair<double, double>>& pts, double x) {
  if (pts.size() == 1) return pts.front().second;
  std::size_t i = 1;
  while (i + 1 < pts.size() && pts[i].first < x) ++i;
  const auto& [x0, y0] = pts[i - 1];
  const auto& [x1, y1] = pts[i];
  return y0 + (y1 - y0) * (x - x0) / (x1 - x0);
}

/// CACTI's figures for `kind` at one of its nodes, at `size_bytes`: log-log interpolation in size.
SramCost cacti_at_node(SramArray kind, int node, double size_bytes) {
  std::vector<std::pair<double, double>> rd, wr, lk;
  for (const SramPoint& p : kCactiSramTable) {
    if (p.kind != kind || p.node_nm != node) continue;
    const double ls = std::log(p.size_bytes);
    rd.emplace_back(ls, std::log(p.read_pj));
    wr.emplace_back(ls, std::log(p.write_pj));
    lk.emplace_back(ls, std::log(p.leakage_mw));
  }
  const double ls = std::log(size_bytes);
  SramCost c;
  c.read_pj_per_byte = std::exp(interpolate(rd, ls)) / kCactiAccessBytes;
  c.write_pj_per_byte = std::exp(interpolate(wr, ls)) / kCactiAccessBytes;
  c.leakage_mw = std::exp(interpolate(lk, ls));
  return c;
}

}  // namespace

double stillmaker_energy_factor(double process_nm, double vdd_v) {
  // Nodes descend in the table: find the pair around process_nm (clamped to the table's ends).
  const auto& t = kStillmakerEnergy;
  if (process_nm >= t.front().node_nm) return fit_at(t.front(), vdd_v);
  if (process_nm <= t.back().node_nm) return fit_at(t.back(), vdd_v);
  std::size_t i = 1;
  while (t[i].node_nm > process_nm) ++i;
  const EnergyFit& hi = t[i - 1];
  const EnergyFit& lo = t[i];
  const double w = (process_nm - lo.node_nm) / (hi.node_nm - lo.node_nm);
  return fit_at(lo, vdd_v) + w * (fit_at(hi, vdd_v) - fit_at(lo, vdd_v));
}

double process_energy_scale(double process_nm, double vdd_v) {
  return stillmaker_energy_factor(process_nm, vdd_v) / stillmaker_energy_factor(kHorowitzNodeNm, kHorowitzVddV);
}

SramCost sram_cost(SramArray kind, double size_bytes, double process_nm, double vdd_v) {
  const double lo_node = kCactiNodes.front();
  const double hi_node = kCactiNodes.back();
  if (process_nm <= lo_node || process_nm >= hi_node) {
    // Outside CACTI's nodes: its nearest node, scaled as logic energy scales between the two nodes
    // (at the configured supply), leakage alike.
    const int n = process_nm <= lo_node ? kCactiNodes.front() : kCactiNodes.back();
    SramCost c = cacti_at_node(kind, n, size_bytes);
    const double s = stillmaker_energy_factor(process_nm, vdd_v) / stillmaker_energy_factor(n, vdd_v);
    c.read_pj_per_byte *= s;
    c.write_pj_per_byte *= s;
    c.leakage_mw *= s;
    return c;
  }
  std::size_t i = 1;
  while (kCactiNodes[i] < process_nm) ++i;
  const int n0 = kCactiNodes[i - 1], n1 = kCactiNodes[i];
  const SramCost a = cacti_at_node(kind, n0, size_bytes);
  const SramCost b = cacti_at_node(kind, n1, size_bytes);
  const double w = (process_nm - n0) / static_cast<double>(n1 - n0);
  return {a.read_pj_per_byte + w * (b.read_pj_per_byte - a.read_pj_per_byte),
          a.write_pj_per_byte + w * (b.write_pj_per_byte - a.write_pj_per_byte),
          a.leakage_mw + w * (b.leakage_mw - a.leakage_mw)};
}

OnChipArrayInfo on_chip_array(const HwConfig& hw, OnChipArray a) {
  const double tile_pixels = static_cast<double>(hw.tiling.tile_width * hw.tiling.tile_height);
  const double tiles = static_cast<double>(hw.isp.tiles_in_flight);
  const bool imr = hw.gpu.mode == GpuMode::Imr;
  const auto cache = [&](const char* name, const CacheParams& c, bool present) {
    const double b = static_cast<double>(c.size_bytes);
    return OnChipArrayInfo{name, SramArray::Cache, b, b, present, true};
  };
  // A per-tile buffer: one bank per tile in flight (an access reads one tile's bank).
  const auto per_tile = [&](const char* name, double bytes_per_tile, bool present) {
    return OnChipArrayInfo{name, SramArray::Ram, bytes_per_tile, bytes_per_tile * tiles, present, false};
  };
  switch (a) {
    case OnChipArray::TextureCache: return cache("texture_cache", hw.cache.texture, true);
    case OnChipArray::VertexCache: return cache("vertex_cache", hw.cache.vertex, true);
    case OnChipArray::Slc: return cache("slc", hw.cache.slc, true);
    case OnChipArray::RopDepthCache: return cache("rop_depth_cache", hw.cache.rop_depth, imr);
    case OnChipArray::RopColorCache: return cache("rop_color_cache", hw.cache.rop_color, imr);
    case OnChipArray::TileBuffer:
      return per_tile("tile_buffer", tile_pixels * static_cast<double>(hw.pls.tile_buffer_bits_per_pixel) / 8.0, !imr);
    case OnChipArray::TagBuffer:
      return per_tile("tag_buffer",
                      tile_pixels * static_cast<double>(hw.isp.tag_bits) / 8.0 * static_cast<double>(hw.isp.tag_buffers),
                      hw.gpu.mode == GpuMode::Tbdr);
    case OnChipArray::DepthBuffer:
      return per_tile("depth_buffer", tile_pixels * static_cast<double>(hw.isp.depth_stencil_bytes_per_sample), !imr);
    case OnChipArray::RegisterFile: {
      // A SIMD register file is sliced per lane: an access reads one lane's slice.
      const double per_usc = hw.energy.register_file_bytes_per_usc;
      return {"register_file", SramArray::Ram, per_usc / static_cast<double>(std::max<std::int64_t>(1, hw.usc.lanes)),
              per_usc * static_cast<double>(hw.usc.count), true, false};
    }
  }
  return {};
}

double on_chip_pj_per_byte(const HwConfig& hw, OnChipArray a, bool write) {
  const OnChipArrayInfo info = on_chip_array(hw, a);
  const SramCost c = sram_cost(info.kind, info.bank_bytes, hw.energy.process_nm, hw.energy.vdd_v);
  return write ? c.write_pj_per_byte : c.read_pj_per_byte;
}

double on_chip_leakage_mw(const HwConfig& hw, OnChipArray a) {
  const OnChipArrayInfo info = on_chip_array(hw, a);
  if (!info.present) return 0.0;
  // Leakage of the banks together: one bank's figure x the number of banks.
  const double banks = info.total_bytes / info.bank_bytes;
  return sram_cost(info.kind, info.bank_bytes, hw.energy.process_nm, hw.energy.vdd_v).leakage_mw * banks;
}

}  // namespace tbdr
