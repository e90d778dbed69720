// Hostile input (issue 16) through the command line: the refusals of the readers
// (tests/test_input_validation.cpp) and of a trace bound to a configuration exit 2, name
// file:line and write nothing, before any work.
#include <gtest/gtest.h>

#include <unistd.h>

#include <climits>
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include "app/cli.hpp"
#include "cli_run.hpp"
#include "input_validation_fixture.hpp"

namespace tbdr {
namespace {

using namespace input_validation;
const testing_scratch::ScratchCleanup cleanup{"input_validation"};

using testing_support::run_cli;

TEST(InputValidation, DrawOfAMissingSubMeshExitsTwoNamingTheLineAndWritesNothing) {
  const fs::path dir = dir_for("missing_submesh");
  write_file(dir / "t.trace", trace_text(kCamera, "", kDrawOfAMissingSubMesh));
  const auto r = run_cli({"run", "--trace", (dir / "t.trace").string(), "--db", (dir / "r.db").string(), "--quiet"});
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("t.trace:10"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir / "r.db"));
}

TEST(InputValidation, PlsOfTenThousandBytesPerPixelIsRefused) {
  // 625 rgba32f variables x 16 bytes = 10,000 bytes per pixel, far above pls.max_pls_bytes_per_pixel.
  std::string pls;
  for (int i = 0; i < 625; ++i) pls += "  pls v" + std::to_string(i) + " format=rgba32f\n";
  const std::string body = "pass main\n"  // line 7
                           "  attachment color format=rgba8 samples=1 load=clear store=store usage=color\n" +
                           pls + "  draw fullscreen pipeline=q\nend\n";
  const std::string decl = "shader t alu_ops=4 tex_fetches=0 varyings=2 light_alu_ops=0 light_source=none color_outputs=0 "
                           "pls=read_write\npipeline q shader=t depth_test=no depth_write=no blend=off cull=none\n";
  const fs::path dir = dir_for("pls");
  write_file(dir / "t.trace", trace_text(kCamera, decl, body));
  const auto r = run_cli({"run", "--trace", (dir / "t.trace").string(), "--db", (dir / "r.db").string(), "--quiet"});
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("t.trace:9"), std::string::npos) << r.err;  // the pass line (2 declarations more)
  EXPECT_NE(r.err.find("10000 bytes"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("pls.max_pls_bytes_per_pixel"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir / "r.db"));
}

TEST(InputValidation, WhatTheGpuCannotRunIsRefusedBeforeAnyCommandRuns) {
  // Command 1 (line 10) is a dispatch that the compute unit refuses only when it runs it (a kernel
  // parameter it does not know); command 2 (line 11) is a pass with pixel local storage, which an
  // immediate-mode GPU has no tile memory for. Bound to gpu.mode=imr the trace is refused naming
  // the pass: every pass is checked against the configuration before the first command runs.
  const std::string decl = "buffer out bytes=64 traffic=other content=other\n"  // line 5
                           "shader t alu_ops=4 tex_fetches=0 varyings=2 light_alu_ops=0 light_source=none "
                           "color_outputs=0 pls=read_write\n"
                           "pipeline q shader=t depth_test=no depth_write=no blend=off cull=none\n";  // line 7
  const std::string body = "dispatch tile_light_cull groups=1,1,1 group_size=16,16,1 writes=out no_such_key=1\n"  // line 10
                           "pass main\n"                                                                          // line 11
                           "  attachment color format=rgba8 samples=1 load=clear store=store usage=color\n"
                           "  pls v0 format=rgba8\n"
                           "  draw fullscreen pipeline=q\n"
                           "end\n";
  const fs::path dir = dir_for("imr_pls");
  write_file(dir / "t.trace", trace_text(kCamera, decl, body));
  const auto run = [&](const std::string& set) {
    return run_cli({"run", "--trace", (dir / "t.trace").string(), "--db", (dir / "r.db").string(), "--quiet", "--set", set});
  };
  const auto imr = run("gpu.mode=imr");
  EXPECT_EQ(imr.code, 2) << imr.err;
  EXPECT_NE(imr.err.find("t.trace:11"), std::string::npos) << imr.err;
  EXPECT_NE(imr.err.find("pass 'main' declares pixel local storage"), std::string::npos) << imr.err;
  EXPECT_FALSE(fs::exists(dir / "r.db"));
  // On a TBDR the pass is fine, and the dispatch is refused as it runs: the order above is the check's.
  const auto tbdr = run("gpu.mode=tbdr");
  EXPECT_EQ(tbdr.code, 2) << tbdr.err;
  EXPECT_NE(tbdr.err.find("t.trace:10"), std::string::npos) << tbdr.err;
  EXPECT_NE(tbdr.err.find("no_such_key"), std::string::npos) << tbdr.err;
  EXPECT_FALSE(fs::exists(dir / "r.db"));
}

TEST(InputValidation, SamplesTheSubPixelGridCannotPlaceAreRefusedBeforeAnyCommandRuns) {
  // 8x MSAA's standard positions are on a 1/16-pixel grid: 4 sub-pixel bits; 2 bits cannot place
  // them. The frame line (3) is refused when the trace meets geometry.subpixel_bits=2, not the
  // first pass that would use the samples.
  std::string text = trace_text(kCamera, "", kPass);
  text.replace(text.find("samples=1\n"), 10, "samples=8\n");
  for (const char* from : {"color format=rgba8 samples=1", "depth format=d24s8 samples=1"}) {
    std::string to = from;
    to.back() = '8';
    text.replace(text.find(from), to.size(), to);
  }
  const fs::path dir = dir_for("subpixel");
  write_file(dir / "t.trace", text);
  const auto r = run_cli({"run", "--trace", (dir / "t.trace").string(), "--db", (dir / "r.db").string(), "--quiet", "--set",
                          "geometry.subpixel_bits=2"});
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("t.trace:3"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("8x sample positions need 4 to 16 sub-pixel bits, got 2"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir / "r.db"));
}

TEST(InputValidation, PathsLongerThanTheFileSystemAllowsExitTwoNamingTheLimit) {
  const long name_max = ::pathconf(fs::temp_directory_path().c_str(), _PC_NAME_MAX);
  ASSERT_GT(name_max, 0);
  const std::string long_name = (fs::temp_directory_path() / std::string(static_cast<std::size_t>(name_max) + 1, 'a')).string() + ".trace";
  std::string long_path = fs::temp_directory_path().string();
  while (long_path.size() < PATH_MAX + 10) long_path += "/abc";
  const auto r = run_cli({"run", "--trace", long_name, "--db", (dir_for("long") / "r.db").string(), "--quiet"});
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("_PC_NAME_MAX"), std::string::npos) << r.err;
  const auto c = run_cli({"params", "--config", long_path});
  EXPECT_EQ(c.code, 2) << c.err;
  EXPECT_NE(c.err.find("_PC_PATH_MAX"), std::string::npos) << c.err;
}

TEST(InputValidation, AssimpBrokenGltfCorpusExitsTwoFromSceneInfoNamingTheField) {
  if (!fs::is_directory(kAssimpGltf2 / "wrongTypes")) GTEST_SKIP() << "assimp-testmodels not installed (apt install assimp-testmodels)";
  for (const auto& [file, field] : kAssimpBrokenGltf) {
    const std::string p = (kAssimpGltf2 / file).string();
    const auto r = run_cli({"scene", "info", p});
    EXPECT_EQ(r.code, 2) << p << ": " << r.err;
    EXPECT_NE(r.err.find(field), std::string::npos) << "'" << field << "' not in " << r.err;
  }
}

}  // namespace
}  // namespace tbdr
