// The worked examples of docs/queries.md ("Least DRAM energy per configuration, in four commands"
// and "The architect's question in three commands") print tables of figures. The docs command test
// (test_docs_commands.cpp) runs every line at small sizes, which checks that the lines work but not
// the figures. This test runs each example's commands as written, at the documented size, from a
// scratch folder outside the checkout, and expects the report's output to be the ```text block that
// follows them, character for character: the model is deterministic, so a figure that moved makes
// the doc stale and fails here until it is measured again. (About 15 s of two cores each.)
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "file_text.hpp"
#include "scratch_dir.hpp"

namespace tbdr {
namespace {

namespace fs = std::filesystem;

const testing_scratch::ScratchCleanup worked_tables_scratch_cleanup{"docs_worked_tables"};

using testing_support::read_text;

/// The body of the first fenced block labelled `label` after `from` in `text` (npos: none), and
/// where the search may go on.
std::string block_after(const std::string& text, const std::string& label, std::size_t& from) {
  const std::size_t open = text.find("\n```" + label + "\n", from);
  if (open == std::string::npos) return "";
  const std::size_t body = open + 5 + label.size();
  const std::size_t close = text.find("\n```\n", body - 1);
  if (close == std::string::npos) return "";
  from = close + 4;
  return text.substr(body, close + 1 - body);
}

/// The commands of a ```sh block, continuation lines joined.
std::vector<std::string> commands_of(const std::string& block) {
  std::vector<std::string> commands;
  std::string current;
  std::stringstream lines(block);
  for (std::string line; std::getline(lines, line);) {
    if (!line.empty() && line.back() == '\\') {
      current += line.substr(0, line.size() - 1);
      continue;
    }
    current += line;
    if (!current.empty()) commands.push_back(current);
    current.clear();
  }
  return commands;
}

/// Runs the ```sh block under `heading` of docs/queries.md as written, in a scratch folder with the
/// build's tbdrsim first on PATH, and compares the last command's output with the ```text block
/// that comes next.
void expect_worked_table_is_current(const std::string& heading, const std::string& name) {
  const std::string doc = read_text(fs::path(TBDRSIM_SOURCE_DIR) / "docs" / "queries.md");
  std::size_t at = doc.find("\n" + heading + "\n");
  ASSERT_NE(at, std::string::npos) << "docs/queries.md has no heading " << heading;
  const std::vector<std::string> commands = commands_of(block_after(doc, "sh", at));
  const std::string expected = block_after(doc, "text", at);
  ASSERT_GE(commands.size(), 2u) << heading;
  ASSERT_FALSE(expected.empty()) << heading;
  const fs::path dir = testing_scratch::scratch_dir("docs_worked_tables", name);
  const fs::path script = dir / "run.sh", output = dir / "report.txt", log = dir / "log.txt";
  {
    std::ofstream s(script);
    s << "set -euo pipefail\ncd '" << dir.string() << "'\nexport PATH='" << fs::path(TBDRSIM_BINARY).parent_path().string()
      << "':\"$PATH\"\n";
    for (std::size_t i = 0; i + 1 < commands.size(); ++i) s << commands[i] << " > /dev/null\n";
    s << commands.back() << " > '" << output.string() << "'\n";
  }
  const int status = std::system(("bash '" + script.string() + "' > '" + log.string() + "' 2>&1").c_str());
  ASSERT_EQ(status, 0) << read_text(log);
  EXPECT_EQ(read_text(output), expected) << "docs/queries.md, \"" << heading
                                         << "\": the report prints other figures than the doc quotes; measure again";
}

TEST(DocsWorkedTables, LeastDramEnergyPerConfigurationIsCurrent) {
  expect_worked_table_is_current("## Least DRAM energy per configuration, in four commands", "least_dram_energy");
}

TEST(DocsWorkedTables, TheArchitectsQuestionIsCurrent) {
  expect_worked_table_is_current("## The architect's question in three commands", "architects_question");
}

}  // namespace
}  // namespace tbdr
