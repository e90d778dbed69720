// The command line: usage errors, exit codes, and the params command.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "app/cli.hpp"

namespace tbdr {
namespace {

struct CliResult {
  int code;
  std::string out;
  std::string err;
};

CliResult run_cli(const std::vector<std::string>& args) {
  std::ostringstream out, err;
  const int code = cli_main(args, out, err);
  return {code, out.str(), err.str()};
}

TEST(Cli, HelpAndUnknownCommandOrOption) {
  const auto help = run_cli({"--help"});
  EXPECT_EQ(help.code, 0);
  EXPECT_NE(help.out.find("usage: tbdrsim <command>"), std::string::npos);
  EXPECT_NE(help.out.find("params"), std::string::npos);
  const auto none = run_cli({});
  EXPECT_EQ(none.code, 2);
  const auto bad = run_cli({"frobnicate"});
  EXPECT_EQ(bad.code, 2);
  EXPECT_NE(bad.err.find("unknown command 'frobnicate'"), std::string::npos);
  EXPECT_NE(bad.err.find("usage:"), std::string::npos);
  const auto opt = run_cli({"params", "--colour"});
  EXPECT_EQ(opt.code, 2);
  EXPECT_NE(opt.err.find("colour"), std::string::npos);
  EXPECT_NE(opt.err.find("usage: tbdrsim params"), std::string::npos);
  EXPECT_EQ(run_cli({"params", "--help"}).code, 0);
}

TEST(Cli, ParamsListsEveryParameterWithDocAndRange) {
  const auto r = run_cli({"params"});
  ASSERT_EQ(r.code, 0) << r.err;
  for (const char* key : {"isp.samples_per_clock", "tiling.tile_width", "dram.bandwidth_gbps",
                          "energy.dram_activate_precharge_nj", "cache.slc.size_bytes", "pls.tile_buffer_bits_per_pixel"}) {
    EXPECT_NE(r.out.find(key), std::string::npos) << key;
  }
  EXPECT_NE(r.out.find("[1, 1024]"), std::string::npos);
  const auto md = run_cli({"params", "--format", "markdown"});
  EXPECT_EQ(md.code, 0);
  EXPECT_EQ(md.out.rfind("| parameter | default | unit | range | description | source |", 0), 0u);
}

TEST(Cli, ParamsResolvedShowsOrigins) {
  const auto dir = std::filesystem::temp_directory_path() / "tbdrsim_test_cli";
  std::filesystem::create_directories(dir);
  const auto cfg = (dir / "mine.ini").string();
  std::ofstream(cfg) << "[usc]\ncount = 6\n";
  const auto r = run_cli({"params", "--config", cfg, "--set", "isp.tag_buffers=4"});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find(cfg + ":2"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("--set isp.tag_buffers=4"), std::string::npos);
  EXPECT_NE(r.out.find("configuration 'mine'"), std::string::npos);
}

TEST(Cli, BadConfigExitsTwoWithFileLine) {
  const auto dir = std::filesystem::temp_directory_path() / "tbdrsim_test_cli";
  std::filesystem::create_directories(dir);
  const auto cfg = (dir / "typo.ini").string();
  std::ofstream(cfg) << "[tiling]\ntile_widht = 16\n";
  const auto r = run_cli({"params", "--config", cfg});
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find(cfg + ":2"), std::string::npos) << r.err;
  const auto s = run_cli({"params", "--set", "isp.samples_per_clock=-3"});
  EXPECT_EQ(s.code, 2);
  EXPECT_NE(s.err.find("[1, 1024]"), std::string::npos) << s.err;
}

}  // namespace
}  // namespace tbdr
