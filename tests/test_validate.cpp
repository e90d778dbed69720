// `tbdrsim validate`: the published anchors. docs/validation.md is the command's output (a model
// change that moves a figure must regenerate it: `tbdrsim validate --markdown docs/validation.md`),
// and every anchor that is arithmetic holds.
#include <gtest/gtest.h>

#include <fstream>
#include <sstream>
#include <string>

#include "app/cli.hpp"
#include "scratch_dir.hpp"

namespace tbdr {
namespace {

const testing_scratch::ScratchCleanup cleanup{"validate"};

TEST(Validate, DocsValidationIsTheCommandsTableAndEveryExactAnchorHolds) {
  const auto dir = testing_scratch::scratch_dir("validate", "run");
  const std::string md = (dir / "validation.md").string();
  std::ostringstream out, err;
  ASSERT_EQ(cli_main({"validate", "--out", (dir / "v").string(), "--markdown", md}, out, err), 0) << err.str();
  std::ifstream generated(md), docs(std::string(TBDRSIM_SOURCE_DIR) + "/docs/validation.md");
  std::stringstream g, d;
  g << generated.rdbuf();
  d << docs.rdbuf();
  EXPECT_EQ(g.str(), d.str()) << "regenerate docs/validation.md with `tbdrsim validate --markdown docs/validation.md`";
  // Every exact anchor's row ends "| yes |"; every row says its basis, and the summary line counts
  // the two bases apart as the rows do.
  std::istringstream rows(g.str());
  int exact = 0, independent = 0, self = 0;
  bool in_table = false;  // the anchors' table: from its header to the first line that is not a row
  for (std::string line; std::getline(rows, line);) {
    if (line.rfind("| anchor |", 0) == 0) in_table = true;
    if (line.rfind("| ", 0) != 0) in_table = in_table && line.rfind("|---", 0) == 0;
    if (!in_table || line.rfind("| ", 0) != 0 || line.rfind("| anchor |", 0) == 0) continue;
    const bool ind = line.find("| exact | independent |") != std::string::npos ||
                     line.find("| shape | independent |") != std::string::npos;
    const bool sc = line.find("| exact | self-consistency |") != std::string::npos ||
                    line.find("| shape | self-consistency |") != std::string::npos;
    EXPECT_TRUE(ind != sc) << line;
    independent += ind;
    self += sc;
    if (line.find("| exact |") == std::string::npos) continue;
    ++exact;
    EXPECT_EQ(line.substr(line.size() - 7), "| yes |") << line;
  }
  EXPECT_GE(exact, 6);
  EXPECT_NE(g.str().find("Independent rows: "), std::string::npos);
  EXPECT_NE(g.str().find(" of " + std::to_string(independent) + " hold; self-consistency rows: "), std::string::npos);
  EXPECT_NE(g.str().find(" of " + std::to_string(self) + " hold."), std::string::npos);
}

}  // namespace
}  // namespace tbdr
