// Parameters: declarations, INI files through Boost.Program_options, --set overrides, errors.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "models/hw_config.hpp"
#include "models/tile_memory.hpp"
#include "kernel/errors.hpp"

namespace tbdr {
namespace {

std::string write_temp(const std::string& name, const std::string& text) {
  const auto dir = std::filesystem::temp_directory_path() / "tbdrsim_test_params";
  std::filesystem::create_directories(dir);
  const auto path = (dir / name).string();
  std::ofstream(path) << text;
  return path;
}

std::string error_of(const std::vector<std::string>& files, const std::vector<std::string>& sets) {
  try {
    resolve_config(files, sets);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(Params, EveryDeclarationIsCompleteAndItsDefaultValid) {
  const auto& table = hw_params().table();
  ASSERT_GE(table.decls().size(), 60u);
  for (const auto& d : table.decls()) {
    EXPECT_FALSE(d.doc.empty()) << d.key;
    EXPECT_FALSE(d.source.empty()) << d.key;
    EXPECT_NE(d.key.find('.'), std::string::npos) << d.key;
    EXPECT_TRUE(table.has_section(d.section())) << d.key;
  }
  // defaults() validates every default against its own range.
  EXPECT_NO_THROW(table.defaults());
}

TEST(Params, DefaultsDescribeTheSeries6xtPreset) {
  const ResolvedConfig rc = resolve_config({}, {});
  EXPECT_EQ(rc.hw.tiling.tile_width, 32);
  EXPECT_EQ(rc.hw.tiling.tile_height, 32);
  EXPECT_EQ(rc.hw.usc.count, 4);
  EXPECT_EQ(rc.hw.pls.tile_buffer_bits_per_pixel, 128);
  EXPECT_DOUBLE_EQ(rc.hw.energy.dram_read_pj_per_bit, 5.1);
  EXPECT_EQ(rc.hw.gpu.mode, GpuMode::Tbdr);
  EXPECT_EQ(rc.params.config_name, kDefaultsPreset);  // the preset the defaults are
  for (const auto& o : rc.params.origins) EXPECT_EQ(o.text, "default");
}

TEST(Params, FileThenSetLayeringAndOrigins) {
  const auto a = write_temp("a.ini", "# preset A\n[tiling]\ntile_width = 16\ntile_height=16\n\n[usc]\ncount = 6 # GX6650\n");
  const auto b = write_temp("b.ini", "[usc]\ncount = 2\n[gpu]\nmode = tbr\n");
  const ResolvedConfig rc = resolve_config({a, b}, {"usc.count=8", "dram.bus_width_bits=64"});
  EXPECT_EQ(rc.hw.tiling.tile_width, 16);
  EXPECT_EQ(rc.hw.usc.count, 8);
  EXPECT_EQ(rc.hw.gpu.mode, GpuMode::Tbr);
  EXPECT_EQ(rc.hw.dram.bus_width_bits, 64);
  // 800 MHz x 2 transfers x 64 bits / 8 x 2 channels = 25.6 GB/s: the derived peak follows the width.
  EXPECT_DOUBLE_EQ(rc.hw.dram.peak_bandwidth_gbps(), 25.6);
  const auto& t = hw_params().table();
  EXPECT_EQ(rc.params.origins[static_cast<std::size_t>(t.find("tiling.tile_width"))].text, a + ":3");
  EXPECT_EQ(rc.params.origins[static_cast<std::size_t>(t.find("gpu.mode"))].text, b + ":4");
  EXPECT_EQ(rc.params.origins[static_cast<std::size_t>(t.find("usc.count"))].text, "--set usc.count=8");
  EXPECT_EQ(rc.params.config_name, "b");
  EXPECT_NE(rc.hash, resolve_config({}, {}).hash);
  EXPECT_EQ(rc.hash, resolve_config({a, b}, {"usc.count=8", "dram.bus_width_bits=64"}).hash);
}

TEST(Params, MisspeltKeyNamesFileLineAndSuggestion) {
  const auto f = write_temp("typo.ini", "[isp]\ntiles_in_flight = 8\nsampels_per_clock = 16\n");
  const std::string e = error_of({f}, {});
  EXPECT_NE(e.find(f + ":3"), std::string::npos) << e;
  EXPECT_NE(e.find("isp.sampels_per_clock"), std::string::npos) << e;
  EXPECT_NE(e.find("did you mean 'isp.samples_per_clock'"), std::string::npos) << e;
}

TEST(Params, UnknownSectionWrongTypeAndRangeAreErrors) {
  const auto s = write_temp("sec.ini", "[gpu]\ncore_clock_mhz = 700\n[shader]\nlanes = 16\n");
  EXPECT_NE(error_of({s}, {}).find(s + ":3: unknown section [shader]"), std::string::npos) << error_of({s}, {});
  const auto t = write_temp("type.ini", "[usc]\ncount = four\n");
  const std::string te = error_of({t}, {});
  EXPECT_NE(te.find(t + ":2"), std::string::npos) << te;
  EXPECT_NE(te.find("'four'"), std::string::npos) << te;
  EXPECT_NE(te.find("an integer in [1, 64]"), std::string::npos) << te;
  const auto r = write_temp("range.ini", "[writeback]\ncompression_ratio = 1.5\n");
  EXPECT_NE(error_of({r}, {}).find("[0.05, 1]"), std::string::npos) << error_of({r}, {});
  const auto c = write_temp("choice.ini", "[gpu]\nmode = deferred\n");
  EXPECT_NE(error_of({c}, {}).find("one of tbdr|tbr|imr"), std::string::npos);
  const auto m = write_temp("malformed.ini", "[gpu]\ncore_clock_mhz 700\n");
  EXPECT_NE(error_of({m}, {}).find(m + ":2: expected 'key = value'"), std::string::npos) << error_of({m}, {});
  const auto d = write_temp("dup.ini", "[gpu]\ncore_clock_mhz = 700\ncore_clock_mhz = 800\n");
  EXPECT_NE(error_of({d}, {}).find(d + ":3: key 'gpu.core_clock_mhz' set twice"), std::string::npos);
  EXPECT_NE(error_of({"/nonexistent/x.ini"}, {}).find("/nonexistent/x.ini: cannot read config file: not found"), std::string::npos);
}

TEST(Params, SetErrorsNameTheArgumentAndTheRange) {
  const std::string e = error_of({}, {"isp.samples_per_clock=-3"});
  EXPECT_NE(e.find("--set isp.samples_per_clock=-3"), std::string::npos) << e;
  EXPECT_NE(e.find("[1, 1024]"), std::string::npos) << e;
  EXPECT_NE(error_of({}, {"isp.samples_per_clock"}).find("expected section.key=value"), std::string::npos);
  EXPECT_NE(error_of({}, {"nosuch.key=1"}).find("unknown section 'nosuch'"), std::string::npos);
  EXPECT_NE(error_of({}, {"dram.clock_mhz=nan"}).find("finite number"), std::string::npos);
  EXPECT_NE(error_of({}, {"usc.count=4.5"}).find("an integer"), std::string::npos);
  EXPECT_NE(error_of({}, {"pls.tile_buffer_bits_per_pixel=128bits"}).find("an integer"), std::string::npos);
}

TEST(Params, ShippedPresetsLoad) {
  const std::string dir = std::string(TBDRSIM_SOURCE_DIR) + "/configs/";
  for (const char* name : {"series6xt_gx6450.ini", "mobile_16x16_lpddr4x.ini"}) {
    EXPECT_NO_THROW(resolve_config({dir + name}, {})) << name;
  }
  const ResolvedConfig m = resolve_config({dir + "mobile_16x16_lpddr4x.ini"}, {});
  EXPECT_EQ(m.hw.tiling.tile_width, 16);
  EXPECT_EQ(m.hw.pls.tile_buffer_bits_per_pixel, 256);
  const ResolvedConfig s = resolve_config({dir + "series6xt_gx6450.ini"}, {});
  EXPECT_EQ(s.hash, resolve_config({}, {}).hash) << "the first preset is the declared defaults";
}

// One hardware, one label, however it was set (issue 51: a study called the GX6450 defaults
// "default", a sweep with configs/series6xt_gx6450.ini "series6xt_gx6450", and a study's --modes
// tbdr "default gpu.mode=tbdr", all one hash). The label is the preset and the values that differ
// from it, sorted by key.
TEST(Params, OneHardwareHasOneLabel) {
  const std::string dir = std::string(TBDRSIM_SOURCE_DIR) + "/configs/";
  const ResolvedConfig none = resolve_config({}, {});
  const ResolvedConfig file = resolve_config({dir + "series6xt_gx6450.ini"}, {});
  const ResolvedConfig set_to_default = resolve_config({}, {"gpu.mode=tbdr", "tiling.tile_width=32"});
  EXPECT_EQ(none.label, "series6xt_gx6450");
  EXPECT_EQ(file.label, none.label);
  EXPECT_EQ(set_to_default.label, none.label);
  EXPECT_EQ(set_to_default.hash, none.hash);
  EXPECT_EQ(resolve_config({}, {"gpu.mode=imr"}).label, "series6xt_gx6450 gpu.mode=imr");
  // Sorted by key, not in the order set: tile_height before tile_width.
  EXPECT_EQ(resolve_config({}, {"tiling.tile_width=16", "tiling.tile_height=16"}).label,
            "series6xt_gx6450 tiling.tile_height=16 tiling.tile_width=16");
  // Relative to the named preset: its own 16x16 tiles are not "set on top".
  EXPECT_EQ(resolve_config({dir + "mobile_16x16_lpddr4x.ini"}, {"tiling.tile_width=16"}).label, "mobile_16x16_lpddr4x");
  // An earlier file's values are on top of the last one, the preset named.
  const ResolvedConfig layered = resolve_config({dir + "mobile_16x16_lpddr4x.ini", dir + "series6xt_gx6450.ini"}, {});
  EXPECT_EQ(layered.label.rfind("series6xt_gx6450 ", 0), 0u) << layered.label;
  EXPECT_NE(layered.label.find("tiling.tile_width=16"), std::string::npos) << layered.label;
}

TEST(Params, ChoicesBecomeEnumsOnceTheTextStaysTheValue) {
  const ResolvedConfig d = resolve_config({}, {});
  EXPECT_EQ(d.hw.tiling.binning, BinningTest::Exact);
  EXPECT_EQ(d.hw.tiling.tile_order, TileOrder::Morton);
  EXPECT_EQ(d.hw.pls.over_budget, PlsOverBudget::SplitRender);
  EXPECT_EQ(d.hw.dram.address_mapping, DramMapping::RowBankChannelColumn);
  const ResolvedConfig rc = resolve_config({}, {"gpu.mode=imr", "tiling.binning=bbox", "tiling.tile_order=row_major",
                                                "pls.over_budget=smaller_tiles",
                                                "dram.address_mapping=row_channel_bank_column"});
  EXPECT_EQ(rc.hw.gpu.mode, GpuMode::Imr);
  EXPECT_EQ(rc.hw.tiling.binning, BinningTest::BoundingBox);
  EXPECT_EQ(rc.hw.tiling.tile_order, TileOrder::RowMajor);
  EXPECT_EQ(rc.hw.pls.over_budget, PlsOverBudget::SmallerTiles);
  EXPECT_EQ(rc.hw.dram.address_mapping, DramMapping::RowChannelBankColumn);
  // The resolved value (stored with every run, printed by `tbdrsim params`) is still the text.
  const auto& t = hw_params().table();
  EXPECT_EQ(std::get<std::string>(rc.params.values[static_cast<std::size_t>(t.find("gpu.mode"))]), "imr");
  EXPECT_EQ(t.decls()[static_cast<std::size_t>(t.find("tiling.tile_order"))].range_text(), "one of row_major|morton");
  EXPECT_STREQ(to_string(rc.hw.pls.over_budget), "smaller_tiles");
  EXPECT_STREQ(to_string(DramMapping::RowChannelBankColumn), "row_channel_bank_column");
  // Every enumerator round-trips through its spelling.
  for (const auto& n : kGpuModeNames) {
    EXPECT_EQ(resolve_config({}, {std::string("gpu.mode=") + n.name}).hw.gpu.mode, n.value) << n.name;
  }
}

TEST(Params, MaxPlsBytesRefusesALargerLayout) {
  PassDesc pass;
  pass.name = "main";
  pass.line = 12;
  for (int i = 0; i < 4; ++i) pass.pls.push_back({"stack" + std::to_string(i), Format::R32ui, 0});  // 16 B
  PlsParams p = resolve_config({}, {}).hw.pls;
  EXPECT_EQ(p.max_pls_bytes_per_pixel, 16);
  EXPECT_NO_THROW(check_pls_layout(p, pass));
  pass.pls.push_back({"stack4", Format::R32ui, 0});  // 20 B
  try {
    check_pls_layout(p, pass);
    ADD_FAILURE() << "a 20-byte layout passed a 16-byte limit";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("pass 'main' (trace line 12)"), std::string::npos) << what;
    EXPECT_NE(what.find("20 bytes"), std::string::npos) << what;
    EXPECT_NE(what.find("pls.max_pls_bytes_per_pixel = 16"), std::string::npos) << what;
  }
  p.max_pls_bytes_per_pixel = 32;
  EXPECT_NO_THROW(check_pls_layout(p, pass));
}

TEST(Params, PlsLightStackHoldsSixteenBitIndicesAfterTheCount) {
  EXPECT_EQ(pls_light_stack_capacity(0), 0u);
  EXPECT_EQ(pls_light_stack_capacity(4), 0u);
  EXPECT_EQ(pls_light_stack_capacity(8), 2u);
  EXPECT_EQ(pls_light_stack_capacity(16), 6u);  // Billeter: 16 bytes hold 6 lights
}

TEST(Params, SourcesNameShippedFilesOrPrimarySources) {
  // A source must be followable by a reader of `tbdrsim params`: never the team's design notes,
  // which the project does not ship.
  for (const auto& d : hw_params().table().decls()) {
    EXPECT_EQ(d.source.find("DESIGN.md"), std::string::npos) << d.key;
    EXPECT_EQ(d.doc.find("DESIGN.md"), std::string::npos) << d.key;
  }
}

}  // namespace
}  // namespace tbdr
