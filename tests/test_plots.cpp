// `tbdrsim plot`: every kind of plot drawn from a small database the simulator writes (three tiny
// traces on two tile sizes), and bad input answered with one line naming the file or option, exit
// code 2, no Python traceback and nothing written. Skipped with a message when /usr/bin/python3
// lacks pandas or matplotlib (scripts/install_deps.sh installs them).
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "analysis/results_db.hpp"
#include "app/cli.hpp"
#include "scratch_dir.hpp"

namespace fs = std::filesystem;
using namespace tbdr;
using namespace tbdr::testing_scratch;

namespace {

ScratchCleanup cleanup{"plots"};

/// The output of one `tbdrsim plot` call.
struct PlotCall {
  int code = -1;
  std::string out, err;
};

PlotCall plot(std::vector<std::string> args) {
  args.insert(args.begin(), "plot");
  std::ostringstream out, err;
  PlotCall c;
  c.code = cli_main(args, out, err);
  c.out = out.str();
  c.err = err.str();
  return c;
}

/// True when the file starts with the PNG signature.
bool is_png(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  char sig[8] = {};
  in.read(sig, 8);
  return in && std::string(sig, 8) == std::string("\x89PNG\r\n\x1a\n", 8);
}

/// Three traces (plain_forward at 16 and 32 lights, deferred at 16) replayed with 16x16 and 32x32
/// tiles: six runs, two configurations, two light counts.
class Plots : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    python_ok_ = std::system("/usr/bin/python3 -c 'import matplotlib, pandas' > /dev/null 2>&1") == 0;
    if (!python_ok_) return;
    dir_ = new fs::path(scratch_dir("plots", "db"));
    db_ = new std::string((*dir_ / "plots.db").string());
    std::ostringstream out, err;
    const std::vector<std::pair<std::string, std::string>> traces = {
        {"plain_forward", "16"}, {"plain_forward", "32"}, {"deferred", "16"}};
    for (const auto& [tech, lights] : traces) {
      const std::string trace = (*dir_ / (tech + "_" + lights + ".trace")).string();
      ASSERT_EQ(cli_main({"trace", "--technique", tech, "--resolution", "160x90", "--scene", "atrium:1", "--lights",
                          lights, "--out", trace},
                         out, err),
                0)
          << err.str();
      for (const char* tile : {"16", "32"}) {
        ASSERT_EQ(cli_main({"run", "--trace", trace, "--db", *db_, "--set", std::string("tiling.tile_width=") + tile,
                            "--set", std::string("tiling.tile_height=") + tile, "--quiet"},
                           out, err),
                  0)
            << err.str();
      }
    }
  }
  static void TearDownTestSuite() {
    delete dir_;
    delete db_;
    dir_ = nullptr;
    db_ = nullptr;
  }
  void SetUp() override {
    if (!python_ok_) GTEST_SKIP() << "/usr/bin/python3 lacks matplotlib or pandas (scripts/install_deps.sh)";
  }
  /// Draws `kind` with `extra` options into a fresh PNG; expects exit 0 and a PNG, returns stdout.
  static std::string draws(const std::string& kind, std::vector<std::string> extra = {}) {
    const fs::path png = *dir_ / (kind + "_" + std::to_string(counter_++) + ".png");
    std::vector<std::string> args = {kind, "--db", *db_, "--out", png.string()};
    args.insert(args.end(), extra.begin(), extra.end());
    const PlotCall c = plot(args);
    EXPECT_EQ(c.code, 0) << kind << ": " << c.err;
    EXPECT_TRUE(is_png(png)) << png;
    EXPECT_EQ(c.err.find("Traceback"), std::string::npos) << c.err;
    return c.out;
  }
  /// Expects `args` to fail with exit 2, one line on stderr containing `needle`, no traceback and
  /// no PNG written.
  static void refuses(const std::string& kind, std::vector<std::string> extra, const std::string& needle,
                      const std::string& db = "") {
    const fs::path png = *dir_ / "refused.png";
    fs::remove(png);
    std::vector<std::string> args = {kind, "--db", db.empty() ? *db_ : db, "--out", png.string()};
    args.insert(args.end(), extra.begin(), extra.end());
    const PlotCall c = plot(args);
    EXPECT_EQ(c.code, 2) << kind << ": " << c.err;
    EXPECT_NE(c.err.find(needle), std::string::npos) << "expected '" << needle << "' in: " << c.err;
    EXPECT_EQ(c.err.find("Traceback"), std::string::npos) << c.err;
    EXPECT_EQ(std::count(c.err.begin(), c.err.end(), '\n'), 1) << c.err;
    EXPECT_FALSE(fs::exists(png));
  }
  static bool python_ok_;
  static fs::path* dir_;
  static std::string* db_;
  static int counter_;
};
bool Plots::python_ok_ = false;
fs::path* Plots::dir_ = nullptr;
std::string* Plots::db_ = nullptr;
int Plots::counter_ = 0;

/// The configuration with 32x32 tiles, by its label (the preset and what was set on top of it).
const std::string kTile32 = "default tiling.tile_height=32 tiling.tile_width=32";

// The draws are split over several tests so that ctest runs them in parallel, each well inside
// its timeout (a script takes seconds to start pandas and matplotlib on a loaded machine).
TEST_F(Plots, TechniquesDramAndEnergyDrawAndTitlesNameWhatTheRunsShare) {
  // Four panels (two configurations x two light counts): the title names only what all share.
  const std::string t = draws("techniques", {"--metric", "frame_time_ms"});
  EXPECT_NE(t.find("4 panel(s)"), std::string::npos) << t;
  EXPECT_NE(t.find("scene atrium:1"), std::string::npos) << t;
  EXPECT_NE(t.find("160x90"), std::string::npos) << t;
  // One configuration: two light-count panels; the configuration is in the title.
  const std::string d = draws("dram", {"--config", kTile32});
  EXPECT_NE(d.find("config " + kTile32), std::string::npos) << d;
  EXPECT_NE(d.find("2 panel(s)"), std::string::npos) << d;
  draws("energy", {"--lights", "16"});
  draws("energy", {"--share"});
}

TEST_F(Plots, PassesAndTilesDrawOneRunPerTechnique) {
  // One configuration, one light count: 2 techniques on one timeline, 16 lights in the title.
  const std::string p = draws("passes", {"--config", kTile32, "--lights", "16"});
  EXPECT_NE(p.find("2 runs drawn"), std::string::npos) << p;
  EXPECT_NE(p.find("16 lights"), std::string::npos) << p;
  // 160x90 in 32x32 tiles: 5 x 3 tiles.
  const std::string h = draws("tiles", {"--config", kTile32, "--lights", "16"});
  EXPECT_NE(h.find("2 heat maps, 5x3 tiles"), std::string::npos) << h;
  EXPECT_NE(h.find("config " + kTile32), std::string::npos) << h;
}

TEST_F(Plots, ScalingAndSensitivityDrawLinesPerTechnique) {
  // plain_forward has 16 and 32 lights: one line per configuration panel.
  const std::string s = draws("scaling", {"--technique", "plain_forward"});
  EXPECT_NE(s.find("2 light counts, 2 panel(s)"), std::string::npos) << s;
  // The tile width on x; the two light counts are rows of panels, not averaged.
  const std::string v = draws("sensitivity", {"--param", "tiling.tile_width"});
  EXPECT_NE(v.find("2 row(s)"), std::string::npos) << v;
}

TEST_F(Plots, DeltasAgainstAParameterOrATechnique) {
  // 16x16 against 32x32 for the 3 traces: 3 comparisons, one panel per light count.
  const std::string x = draws("delta", {"--baseline", "tiling.tile_width=32"});
  EXPECT_NE(x.find("3 comparisons, 2 panel(s)"), std::string::npos) << x;
  // deferred against plain_forward at 16 lights, per configuration: 2 comparisons in 2 panels.
  const std::string y = draws("delta", {"--baseline", "technique=plain_forward", "--lights", "16", "--ratio"});
  EXPECT_NE(y.find("2 comparisons, 2 panel(s)"), std::string::npos) << y;
}

TEST_F(Plots, MixedDimensionsAreRefusedNotAveraged) {
  // passes draws one run per technique: two light counts and two configurations cannot share it.
  refuses("passes", {"--config", kTile32}, "mixes 2 light counts (16, 32)");
  refuses("tiles", {"--lights", "16"}, "mixes 2 configurations");
  // dram is for one configuration.
  refuses("dram", {}, "pick one with --config");
  // delta over the tile width while nothing else varies is fine; with a selection where the
  // baseline value is absent it says which values exist.
  refuses("delta", {"--baseline", "tiling.tile_width=64"}, "they have 16, 32");
}

TEST_F(Plots, BadDatabaseOrOutputIsOneLineAndExitTwo) {
  refuses("techniques", {}, "no such results database", (*dir_ / "absent.db").string());
  EXPECT_FALSE(fs::exists(*dir_ / "absent.db"));
  const fs::path text = *dir_ / "notes.txt";
  std::ofstream(text) << "not a database\n";
  refuses("energy", {}, "notes.txt: not a", text.string());
  const fs::path empty = *dir_ / "empty.db";
  { ResultsDb created(empty.string()); }
  refuses("energy", {}, "holds no runs", empty.string());
  // --out into a folder that does not exist: refused before any work.
  refuses("energy", {"--out", (*dir_ / "no" / "such" / "x.png").string()}, "--out");
}

TEST_F(Plots, BadOptionsAreOneLineAndExitTwo) {
  refuses("techniques", {"--metric", "frame_time_msx"}, "did you mean frame_time_ms");
  refuses("techniques", {"--bogus"}, "unrecognized arguments: --bogus");
  refuses("techniques", {"--where", "no_such_column = 1"}, "--where \"no_such_column = 1\": no such column");
  refuses("scaling", {"--technique", "nope"}, "no finished run matches the selection (--technique nope)");
  refuses("sensitivity", {"--param", "tiling.tile_widht"}, "--param tiling.tile_widht");
  refuses("delta", {"--baseline", "tiling.tile_width"}, "--baseline tiling.tile_width: expected KEY=VALUE");
  refuses("tiles", {"--value", "watts"}, "invalid choice: 'watts'");
}

TEST_F(Plots, CommandRefusesUnknownKindsAndShowsHelp) {
  const PlotCall k = plot({"histogram", "--db", *db_});
  EXPECT_EQ(k.code, 2);
  EXPECT_NE(k.err.find("unknown plot kind 'histogram'"), std::string::npos) << k.err;
  EXPECT_EQ(plot({}).code, 2);
  const PlotCall help = plot({"--help"});
  EXPECT_EQ(help.code, 0);
  EXPECT_NE(help.out.find("sensitivity"), std::string::npos) << help.out;
  const PlotCall kind_help = plot({"delta", "--help"});
  EXPECT_EQ(kind_help.code, 0);
  EXPECT_NE(kind_help.out.find("--baseline"), std::string::npos) << kind_help.out;
}

}  // namespace
