// Command blocks of docs/ run as written from an empty folder outside the checkout (the build on
// PATH), at small sizes, as tests/test_readme.cpp runs the README's: the worked example of
// docs/queries.md (least DRAM energy per configuration in four commands), the capture import of
// docs/capture-import.md without RenderDoc (import, replay on three modes, compare), and the lines
// that name analysis/views.sql or the plot scripts (docs/queries.md, docs/plots.md).
#include <gtest/gtest.h>

#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "scratch_dir.hpp"

namespace tbdr {
namespace {

namespace fs = std::filesystem;

const testing_scratch::ScratchCleanup docs_scratch_cleanup{"docs_commands"};

std::string read_text(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

std::string doc(const std::string& name) { return read_text(fs::path(TBDRSIM_SOURCE_DIR) / "docs" / name); }

/// The `index`-th ```sh block after the heading line `heading` (empty when there is none).
std::string sh_block(const std::string& text, const std::string& heading, int index = 0) {
  auto at = text.find("\n" + heading + "\n");
  if (at == std::string::npos) return "";
  for (int i = 0; i <= index; ++i) {
    at = text.find("```sh\n", at + 1);
    if (at == std::string::npos) return "";
  }
  const auto body = at + 6;
  const auto close = text.find("\n```", body);
  return close == std::string::npos ? "" : text.substr(body, close - body + 1);
}

std::string replace_all(std::string s, const std::string& from, const std::string& to) {
  for (auto at = s.find(from); at != std::string::npos; at = s.find(from, at + to.size())) s.replace(at, from.size(), to);
  return s;
}

/// Runs `script` with bash (set -euo pipefail) in a new scratch folder outside the checkout with
/// the build's tbdrsim first on PATH; returns its exit status and output.
struct ScriptRun {
  bool ok;
  std::string log;
  fs::path dir;
};
ScriptRun run_script(const std::string& name, const std::string& script) {
  const fs::path dir = testing_scratch::scratch_dir("docs_commands", name);
  EXPECT_EQ(dir.lexically_relative(TBDRSIM_SOURCE_DIR).string().rfind("..", 0), 0u) << "scratch inside the checkout";
  std::ofstream(dir / "doc.sh") << "set -euo pipefail\n"
                                << "trap 'echo \"doc line failed (exit $?): $BASH_COMMAND\" >&2' ERR\n"
                                << script;
  const std::string bin_dir = fs::path(TBDRSIM_BINARY).parent_path().string();
  const std::string cmd = "cd '" + dir.string() + "' && PATH='" + bin_dir + "':\"$PATH\" bash doc.sh > doc.log 2>&1";
  const int status = std::system(cmd.c_str());
  return {WIFEXITED(status) && WEXITSTATUS(status) == 0, read_text(dir / "doc.log"), dir};
}

std::string tail(const std::string& log) { return log.substr(log.size() > 6000 ? log.size() - 6000 : 0); }

// docs/queries.md: the question of issue 51 in four commands, none of them SQL, at the doc's
// commands with 160x90, atrium:1 and 16 lights for its 960x540, atrium:2 and 256.
TEST(DocsCommands, LeastDramEnergyExampleRunsFromAnotherFolder) {
  const std::string block = sh_block(doc("queries.md"), "## Least DRAM energy per configuration, in four commands");
  ASSERT_FALSE(block.empty());
  EXPECT_EQ(block.find("sqlite3"), std::string::npos) << "the example is without SQL";
  std::size_t commands = 0;
  for (auto at = block.find("tbdrsim "); at != std::string::npos; at = block.find("tbdrsim ", at + 1)) {
    commands += (at == 0 || block[at - 1] == '\n') ? 1 : 0;
  }
  EXPECT_LE(commands, 5u);
  std::string script = block;
  for (const auto& [from, to] : std::vector<std::pair<std::string, std::string>>{
           {"960x540", "160x90"}, {"atrium:2", "atrium:1"}, {"--lights 256", "--lights 16"}}) {
    EXPECT_NE(script.find(from), std::string::npos) << from;
    script = replace_all(script, from, to);
  }
  const ScriptRun r = run_script("least_dram_energy", script);
  ASSERT_TRUE(r.ok) << tail(r.log);
  // Three studies of 13 techniques in one database; the report's best row per configuration.
  EXPECT_NE(r.log.find("39 finished run(s), grouped by config x technique"), std::string::npos) << tail(r.log);
  for (const char* config : {"\nseries6xt_gx6450  ", "\nseries6xt_gx6450 isp.tag_buffers=4  ",
                             "\nseries6xt_gx6450 tiling.tile_height=16 tiling.tile_width=16  "}) {
    EXPECT_NE(r.log.find(config), std::string::npos) << config << "\n" << tail(r.log);
  }
}

// docs/capture-import.md without RenderDoc: the committed intermediate imported from any folder,
// then the doc's steps 3 and 4 (replay on three modes, compare with the application's frame) as
// written.
TEST(DocsCommands, CaptureImportWithoutRenderDocRunsFromAnotherFolder) {
  if (std::system("/usr/bin/python3 -c 'import numpy, matplotlib' > /dev/null 2>&1") != 0) {
    GTEST_SKIP() << "no python3 with numpy and matplotlib for compare_frame.py";
  }
  const std::string text = doc("capture-import.md");
  const std::string steps = sh_block(text, "## Worked example: vkcube on lavapipe, without a display", 0);
  const std::string import = sh_block(text, "## Worked example: vkcube on lavapipe, without a display", 1);
  ASSERT_FALSE(steps.empty());
  ASSERT_NE(import.find("tbdrsim import \"$(tbdrsim --checkout)/tests/data/capture/vkcube\""), std::string::npos) << import;
  const auto step3 = steps.find("# 3.");
  ASSERT_NE(step3, std::string::npos) << steps;
  const ScriptRun r = run_script("capture_import", import + steps.substr(step3));
  ASSERT_TRUE(r.ok) << tail(r.log);
  EXPECT_TRUE(fs::is_directory(r.dir / "vkcube.capture"));
  EXPECT_TRUE(fs::is_regular_file(r.dir / "vkcube_compare.png"));
  EXPECT_NE(r.log.find("coverage: 76800 of 76800 pixels agree"), std::string::npos) << tail(r.log);
}

// The lines that named analysis/views.sql or analysis/plot_*.py relative to the checkout now run
// from any folder: `tbdrsim --views | sqlite3 DB` and the plot script through `tbdrsim --checkout`.
TEST(DocsCommands, ViewsAndPlotScriptLinesRunFromAnotherFolder) {
  const std::string queries = doc("queries.md"), plots = doc("plots.md");
  ASSERT_NE(queries.find("`tbdrsim --views | sqlite3 results.db`"), std::string::npos);
  const std::string plot_line = "/usr/bin/python3 \"$(tbdrsim --checkout)/analysis/plot_energy.py\" --db study/study.db";
  ASSERT_NE(plots.find("`" + plot_line + "`"), std::string::npos);
  EXPECT_EQ(queries.find("< analysis/views.sql"), std::string::npos);
  std::string script =
      "tbdrsim trace --technique plain_forward --scene atrium:1 --lights 4 --resolution 64x36 --out t.trace\n"
      "tbdrsim run --trace t.trace --db results.db --quiet\n"
      "command -v sqlite3 > /dev/null && tbdrsim --views | sqlite3 results.db\n";
  if (std::system("/usr/bin/python3 -c 'import pandas, matplotlib' > /dev/null 2>&1") == 0) {
    script += "tbdrsim study --out study --scene atrium:1 --resolution 64x36 --lights 4 --technique plain_forward deferred "
              "--images none --jobs 1\n" + plot_line + "\n";
  }
  const ScriptRun r = run_script("views_and_plots", script);
  ASSERT_TRUE(r.ok) << tail(r.log);
}

}  // namespace
}  // namespace tbdr
