// The README's usage block, run as written from an empty folder outside the checkout (with the
// build on PATH), at the small sizes the README states: every documented command must work from
// any folder.
#include <gtest/gtest.h>

#include <sys/wait.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "scratch_dir.hpp"

namespace tbdr {
namespace {

namespace fs = std::filesystem;

const testing_scratch::ScratchCleanup readme_scratch_cleanup{"readme"};

std::string read_text(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

/// The first ```sh block after the "## Usage" heading.
std::string usage_block(const std::string& readme) {
  const auto section = readme.find("\n## Usage");
  if (section == std::string::npos) return "";
  const auto open = readme.find("```sh\n", section);
  if (open == std::string::npos) return "";
  const auto body = open + 6;
  const auto close = readme.find("\n```", body);
  return close == std::string::npos ? "" : readme.substr(body, close - body + 1);
}

/// The size substitutions the README states under its usage block (small sizes for a test).
struct Substitution {
  std::string from, to;
  std::string stated;  ///< how the README names it, in backquotes
};
const std::vector<Substitution> kSmallSizes = {
    {"1920x1080", "160x90", "1920x1080"},
    {"960x540", "160x90", "960x540"},
    {"--lights 256", "--lights 16", "--lights 256"},
    {"atrium:3", "atrium:1", "atrium:3"},
    {"atrium:2", "atrium:1", "atrium:2"},
    {"tbdrsim study ", "tbdrsim study --scene atrium:1 --resolution 160x90 --lights 16 ", "study"},
};

std::string replace_all(std::string s, const std::string& from, const std::string& to) {
  for (auto at = s.find(from); at != std::string::npos; at = s.find(from, at + to.size())) s.replace(at, from.size(), to);
  return s;
}

TEST(Readme, UsageBlockRunsAsWrittenFromAnotherFolder) {
  const std::string readme = read_text(fs::path(TBDRSIM_SOURCE_DIR) / "README.md");
  const std::string block = usage_block(readme);
  ASSERT_FALSE(block.empty()) << "README.md has no ```sh block under ## Usage";
  // Folder-independent as written: no path into the build or the checkout, nothing outside it.
  EXPECT_EQ(block.find("build/"), std::string::npos) << "the usage block names the build folder";
  EXPECT_EQ(block.find("../"), std::string::npos) << "the usage block reaches outside the working folder";
  EXPECT_EQ(block.find("/work/"), std::string::npos);
  // Every substitution the README states is one it needs (a stale one would mean the block changed).
  for (const auto& sub : kSmallSizes) {
    EXPECT_NE(block.find(sub.from), std::string::npos) << "the README's usage block no longer contains " << sub.from;
    EXPECT_NE(readme.find("`" + sub.stated + "`"), std::string::npos) << "the README does not state " << sub.stated;
  }
  std::string script = block;
  for (const auto& sub : kSmallSizes) script = replace_all(script, sub.from, sub.to);

  const fs::path dir = testing_scratch::scratch_dir("readme", "usage");
  ASSERT_EQ(fs::path(dir).lexically_relative(TBDRSIM_SOURCE_DIR).string().rfind("..", 0), 0u)
      << "the scratch folder must be outside the checkout";
  // Each line runs in order; the first failing one stops the script and is named.
  std::ofstream(dir / "usage.sh") << "set -euo pipefail\n"
                                  << "trap 'echo \"README line failed (exit $?): $BASH_COMMAND\" >&2' ERR\n"
                                  << script;
  const std::string bin_dir = fs::path(TBDRSIM_BINARY).parent_path().string();
  const std::string cmd = "cd '" + dir.string() + "' && PATH='" + bin_dir + "':\"$PATH\" bash usage.sh > usage.log 2>&1";
  const int status = std::system(cmd.c_str());
  const std::string log = read_text(dir / "usage.log");
  ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << log.substr(log.size() > 6000 ? log.size() - 6000 : 0);
  // What the lines leave behind, in the working folder only.
  for (const char* f : {"pf.trace", "results.db", "study_mobile/study.db", "sweep.db", "all.db", "tile.png",
                        "slurm/tile_size.sbatch", "slurm/shard_0.db", "slurm/shard_1.db"}) {
    EXPECT_TRUE(fs::exists(dir / f)) << f << "\n" << log;
  }
  // The sweep and its Slurm shards ran the same points: the merged database holds as many
  // finished runs as the sweep's (tile_size: 12 configurations x 3 traces = 36).
  EXPECT_NE(log.find("sweep tile_size: 36 point(s)"), std::string::npos) << log;
  EXPECT_NE(log.find("merged into all.db: 36 run(s) copied"), std::string::npos) << log;
}

}  // namespace
}  // namespace tbdr
