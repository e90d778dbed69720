// `tbdrsim plot`: every kind of plot drawn from a small database the simulator writes (three tiny
// traces on two tile sizes), and bad input answered with one line naming the file or option, exit
// code 2, no Python traceback and nothing written. Skipped with a message when /usr/bin/python3
// lacks pandas or matplotlib (scripts/install_deps.sh installs them).
#include <gtest/gtest.h>

#include <sys/wait.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>
#include <string>
#include <vector>

#include "file_text.hpp"
#include "analysis/results_db.hpp"
#include "analysis/sql.hpp"
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

/// The configuration with 32x32 tiles, by its label: the preset's own tile size, so nothing is
/// set on top of it (--set tiling.tile_width=32 gives the GX6450 preset's hardware and its name).
const std::string kTile32 = "series6xt_gx6450";

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

TEST_F(Plots, PanelsShareOneYScaleUnlessAskedOtherwise) {
  // Four panels of frame time: one y scale by default, one each with --independent-y.
  EXPECT_NE(draws("techniques", {"--metric", "frame_time_ms"}).find("4 panel(s), one y scale"), std::string::npos);
  EXPECT_NE(draws("techniques", {"--metric", "frame_time_ms", "--independent-y"}).find("y scale per panel"),
            std::string::npos);
  EXPECT_NE(draws("dram", {"--config", kTile32}).find("one y scale"), std::string::npos);
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

// ---------------------------------------------------------------------------------------------
// Every plot command of docs/plots.md and docs/queries.md, as written (small sizes substituted),
// on a study database and a sweep database; every kind with its options on both; issue 51's
// problems each pinned.

/// The text of a file.
using testing_support::read_text;

/// A shell line split into words ('...' and "..." quoted, a # comment outside quotes ends it).
std::vector<std::string> shell_words(const std::string& line) {
  std::vector<std::string> words;
  std::string w;
  bool in_word = false;
  char quote = 0;
  for (const char c : line) {
    if (quote) {
      if (c == quote) {
        quote = 0;
      } else {
        w += c;
      }
    } else if (c == '\'' || c == '"') {
      quote = c;
      in_word = true;
    } else if (c == '#' && !in_word) {
      break;
    } else if (c == ' ' || c == '\t') {
      if (in_word) words.push_back(w);
      w.clear();
      in_word = false;
    } else {
      w += c;
      in_word = true;
    }
  }
  if (in_word) words.push_back(w);
  return words;
}

/// The `tbdrsim plot` command lines in the ``` blocks of a doc ("\" continuations joined).
std::vector<std::string> doc_plot_lines(const fs::path& doc) {
  std::vector<std::string> lines;
  std::istringstream in(read_text(doc));
  std::string line, joined;
  bool block = false;
  while (std::getline(in, line)) {
    if (line.rfind("```", 0) == 0) {
      block = !block;
      continue;
    }
    if (!block) continue;
    joined += line;
    if (!joined.empty() && joined.back() == '\\') {
      joined.pop_back();
      continue;
    }
    const auto at = joined.find_first_not_of(' ');
    if (at != std::string::npos && joined.compare(at, 13, "tbdrsim plot ") == 0) lines.push_back(joined.substr(at));
    joined.clear();
  }
  return lines;
}

/// The documented light counts, at the small study's: 1024 -> 32, 256 -> 8.
std::string small_lights(const std::string& n) { return n == "1024" ? "32" : n == "256" ? "8" : n; }

/// A study and a sweep as the docs make them, small: the study of three techniques at 8 and 32
/// lights (320x180, atrium detail 1); the sweep over the tile size (16, 32 zipped), the tile memory
/// budget (128, 256 bits per pixel) and the light stack's pls_bytes (16, 32, and 64, which the
/// preset's 32-byte PLS limit refuses: 4 failed runs), plain_forward beside it.
class DocumentedPlots : public ::testing::Test {
 protected:
  void SetUp() override {
    if (std::system("/usr/bin/python3 -c 'import matplotlib, pandas' > /dev/null 2>&1") != 0) {
      GTEST_SKIP() << "/usr/bin/python3 lacks matplotlib or pandas (scripts/install_deps.sh)";
    }
    dir_ = scratch_dir("plots", ::testing::UnitTest::GetInstance()->current_test_info()->name());
  }
  /// Runs the tbdrsim binary (as a user does: a sweep's workers are that binary) with `args`;
  /// its exit code, its output in `log`.
  int tbdrsim(const std::string& args, const std::string& log) {
    const int status = std::system((std::string(TBDRSIM_BINARY) + " " + args + " > '" + (dir_ / log).string() + "' 2>&1").c_str());
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  }
  /// The study's database.
  std::string make_study() {
    const std::string study = (dir_ / "study").string();
    EXPECT_EQ(tbdrsim("study --out '" + study + "' --scene atrium:1 --resolution 320x180 --lights 8 32 --technique "
                      "plain_forward deferred forward_light_stack --images none -j 2",
                      "study.log"),
              0)
        << read_text(dir_ / "study.log");
    return study + "/study.db";
  }
  /// The sweep's database.
  std::string make_sweep() {
    const fs::path spec = dir_ / "small.ini";
    std::ofstream(spec) << "[sweep]\nname = small\nconfig = " << TBDRSIM_SOURCE_DIR
                        << "/configs/series6xt_gx6450.ini\n"
                           "[set]\npls.max_pls_bytes_per_pixel = 32\n"
                           "[generate]\ntechnique = plain_forward, forward_light_stack\nscene = atrium:1\n"
                           "resolution = 320x180\nlights = 8\noption.pls_bytes = 16, 32, 64\n"
                           "[vary]\npls.tile_buffer_bits_per_pixel = 128, 256\n"
                           "[zip.tile]\ntiling.tile_width = 16, 32\ntiling.tile_height = 16, 32\n";
    const std::string db = (dir_ / "small.db").string();
    tbdrsim("sweep '" + spec.string() + "' --db '" + db + "' -j 2", "sweep.log");  // exit 1: its 4 refused points
    const std::string log = read_text(dir_ / "sweep.log");
    EXPECT_NE(log.find("12 ok, 4 failed"), std::string::npos) << log;
    return db;
  }
  /// Runs `tbdrsim plot` with `args` (--out added when absent); expects exit 0 and a PNG (or, with
  /// `may_refuse`, exit 2 with one line); never an internal error. Returns stdout and stderr.
  std::string draw(std::vector<std::string> args, bool may_refuse = false) {
    fs::path png = dir_ / ("plot_" + std::to_string(count_++) + ".png");
    const bool help = std::find(args.begin(), args.end(), "--help") != args.end();
    const auto out = std::find(args.begin(), args.end(), "--out");
    if (out != args.end() && out + 1 != args.end()) {
      png = *(out + 1);
    } else if (!help) {
      args.insert(args.end(), {"--out", png.string()});
    }
    std::string line;
    for (const auto& a : args) line += " " + a;
    const PlotCall c = plot(args);
    EXPECT_EQ(c.err.find("internal error"), std::string::npos) << line << ": " << c.err;
    EXPECT_EQ(c.err.find("Traceback"), std::string::npos) << line << ": " << c.err;
    if (may_refuse && c.code == 2) {
      EXPECT_EQ(std::count(c.err.begin(), c.err.end(), '\n'), 1) << line << ": " << c.err;
      return c.out + c.err;
    }
    EXPECT_EQ(c.code, 0) << line << ": " << c.err;
    if (!help) {
      EXPECT_TRUE(is_png(png)) << line;
    }
    return c.out + c.err;
  }
  /// Runs every documented plot line whose database `db_of` maps to a path (empty: not this test's).
  int draw_documented(const std::function<std::string(const std::string&)>& db_of) {
    int drawn = 0;
    const fs::path docs = fs::path(TBDRSIM_SOURCE_DIR) / "docs";
    for (const char* doc : {"plots.md", "queries.md"}) {
      for (const auto& line : doc_plot_lines(docs / doc)) {
        std::vector<std::string> w = shell_words(line);
        std::vector<std::string> args(w.begin() + 2, w.end());
        bool mine = std::find(args.begin(), args.end(), "--db") == args.end();  // --help lines: every test's
        for (std::size_t i = 0; i + 1 < args.size(); ++i) {
          if (args[i] == "--db") {
            args[i + 1] = db_of(args[i + 1]);
            mine = !args[i + 1].empty();
          } else if (args[i] == "--out") {
            args[i + 1] = (dir_ / ("doc_" + std::to_string(count_++) + ".png")).string();
          } else if (args[i] == "--lights") {
            args[i + 1] = small_lights(args[i + 1]);
          }
        }
        if (!mine) continue;
        SCOPED_TRACE(std::string(doc) + ": " + line);
        draw(args);
        ++drawn;
      }
    }
    return drawn;
  }
  fs::path dir_;
  int count_ = 0;
};

TEST_F(DocumentedPlots, EveryDocumentedStudyPlotDraws) {
  const std::string db = make_study();
  // docs/plots.md's seven study lines, queries.md's techniques and scaling lines, two --help lines.
  EXPECT_EQ(draw_documented([&](const std::string& d) {
              return d.find("study") != std::string::npos || d.find("techniques.db") != std::string::npos ||
                             d.find("lights.db") != std::string::npos
                         ? db
                         : std::string();
            }),
            11);
}

TEST_F(DocumentedPlots, EveryKindWithItsOptionsOnAStudyDrawsOrRefusesInOneLine) {
  const std::string db = make_study();
  // The study's configuration is the GX6450 preset's hardware, called by its name (issue 51:
  // "default", which the sweeps of configs/series6xt_gx6450.ini did not match).
  EXPECT_NE(draw({"dram", "--db", db, "--config", "series6xt_gx6450", "--lights", "32"}).find("config series6xt_gx6450"),
            std::string::npos);
  // Every kind with its options: a plot, or a one-line refusal (exit 2), never an internal error.
  const std::vector<std::vector<std::string>> options = {
      {"techniques", "--metric", "energy_total_mj", "--log", "--independent-y", "--technique", "deferred",
       "--technique", "plain_forward"},
      {"energy", "--share", "--scene", "atrium:1", "--independent-y"},
      {"passes", "--lights", "8", "--ms", "--fix", "tiling.tile_width=32"},
      {"scaling", "--linear", "--metric", "dram_total_mb"},
      {"sensitivity", "--param", "technique.pls_bytes", "--linear", "--lights", "8"},
      {"delta", "--baseline", "technique=plain_forward", "--ratio", "--lights", "8"},
      {"tiles", "--lights", "8", "--value", "dram_bytes", "--pass", "0", "--log", "--where", "technique <> 'deferred'"},
      {"sequence", "--lights", "8"},  // a study of single frames: refused in one line
  };
  for (auto args : options) {
    args.insert(args.begin() + 1, {"--db", db});
    draw(args, /*may_refuse=*/true);
  }
}

TEST_F(DocumentedPlots, EveryDocumentedSweepPlotDrawsAndTechniqueOptionsAreParameters) {
  const std::string db = make_sweep();
  // docs/plots.md's four sweep lines, queries.md's sensitivity line, two --help lines.
  EXPECT_EQ(draw_documented([&](const std::string& d) {
              return d.find("tile_size") != std::string::npos || d.find("stack") != std::string::npos ? db : "";
            }),
            7);
  // Issue 51, item 1: a technique option as the baseline ended in "internal error: ValueError:
  // cannot insert technique, already exists". pls_bytes 32 against 16 in each of the 4
  // configurations: 4 comparisons; plain_forward (no such option) and the refused runs counted.
  const std::string d = draw({"delta", "--db", db, "--baseline", "technique.pls_bytes=16", "--metric", "frame_time_ms"});
  EXPECT_NE(d.find("4 comparisons, 4 panel(s), one y scale"), std::string::npos) << d;
  EXPECT_NE(d.find("left out: 4 run(s) of techniques without the option technique.pls_bytes (plain_forward)"),
            std::string::npos) << d;
  // Item 4: the 4 refused runs (64-byte stacks over the 32-byte limit) are counted, with why.
  EXPECT_NE(d.find("left out: 4 run(s) that did not finish: 4 failed (forward_light_stack): pass 'main' declares 64 "
                   "bytes of pixel local storage per pixel"),
            std::string::npos) << d;
  // Item 3: plot takes the technique options that report --by takes: as the x axis, and in --fix.
  const std::string s = draw({"sensitivity", "--db", db, "--param", "technique.pls_bytes"});
  EXPECT_NE(s.find("1 parameter(s), 4 row(s)"), std::string::npos) << s;
  EXPECT_NE(draw({"techniques", "--db", db, "--metric", "frame_time_ms", "--fix", "technique.pls_bytes=16",
                  "--fix", "tiling.tile_width=16"})
                .find("1 series, 2 panel(s)"),
            std::string::npos);
  // A --fix narrows the unfinished runs counted too: 2 of the 4 had 16x16 tiles.
  EXPECT_NE(draw({"energy", "--db", db, "--fix", "tiling.tile_width=16"}).find("left out: 2 run(s) that did not finish"),
            std::string::npos);
  // The sweep's labels are the run's: the preset and the values that differ from it, sorted.
  {
    ResultsDb rdb(db, ResultsDb::QueryOnly{});
    SqlStatement q(rdb.sql(), "SELECT group_concat(config_label, '|') FROM (SELECT DISTINCT config_label FROM v_run_summary "
                              "ORDER BY config_label)");
    ASSERT_TRUE(q.step());
    EXPECT_EQ(q.text(0),
              "series6xt_gx6450 pls.max_pls_bytes_per_pixel=32|"
              "series6xt_gx6450 pls.max_pls_bytes_per_pixel=32 pls.tile_buffer_bits_per_pixel=256|"
              "series6xt_gx6450 pls.max_pls_bytes_per_pixel=32 pls.tile_buffer_bits_per_pixel=256 tiling.tile_height=16 "
              "tiling.tile_width=16|"
              "series6xt_gx6450 pls.max_pls_bytes_per_pixel=32 tiling.tile_height=16 tiling.tile_width=16");
  }
}

TEST_F(DocumentedPlots, EveryKindWithItsOptionsOnASweepDrawsOrRefusesInOneLine) {
  const std::string db = make_sweep();
  const std::vector<std::vector<std::string>> options = {
      {"techniques", "--metric", "frame_time_ms", "--independent-y", "--technique", "plain_forward"},
      {"dram", "--config", "series6xt_gx6450 pls.max_pls_bytes_per_pixel=32"},
      {"energy", "--config", "series6xt_gx6450", "--share"},  // the preset: every configuration of it, a panel each
      {"passes", "--config", "series6xt_gx6450 pls.max_pls_bytes_per_pixel=32", "--fix", "technique.pls_bytes=16"},
      {"scaling", "--technique", "plain_forward"},
      {"sensitivity", "--independent-y", "--linear", "--technique", "plain_forward"},
      {"delta", "--baseline", "config=series6xt_gx6450 pls.max_pls_bytes_per_pixel=32", "--ratio"},
      {"tiles", "--config", "series6xt_gx6450 pls.max_pls_bytes_per_pixel=32", "--value", "samples"},
  };
  for (auto args : options) {
    args.insert(args.begin() + 1, {"--db", db});
    draw(args, /*may_refuse=*/true);
  }
}

// Issue 51, item 2: the names `plot` lists are the names it accepts. The same hardware run without
// a config file, with configs/series6xt_gx6450.ini and with --set gpu.mode=tbdr (its default) is
// one configuration with one label; gpu.mode=imr is another.
TEST_F(DocumentedPlots, ConfigurationsListedAreAccepted) {
  const std::string trace = (dir_ / "pf.trace").string();
  const std::string db = (dir_ / "names.db").string();
  std::ostringstream out, err;
  ASSERT_EQ(cli_main({"trace", "--technique", "plain_forward", "--resolution", "160x90", "--scene", "atrium:1", "--lights",
                      "8", "--out", trace},
                     out, err),
            0)
      << err.str();
  const std::string preset = std::string(TBDRSIM_SOURCE_DIR) + "/configs/series6xt_gx6450.ini";
  for (const std::vector<std::string>& extra : std::vector<std::vector<std::string>>{
           {}, {"--config", preset}, {"--set", "gpu.mode=tbdr"}, {"--set", "gpu.mode=imr"}}) {
    std::vector<std::string> args = {"run", "--trace", trace, "--db", db, "--quiet"};
    args.insert(args.end(), extra.begin(), extra.end());
    ASSERT_EQ(cli_main(args, out, err), 0) << err.str();
  }
  {
    ResultsDb rdb(db, ResultsDb::QueryOnly{});
    SqlStatement q(rdb.sql(), "SELECT group_concat(config_label, '|') FROM (SELECT config_label FROM v_run_summary ORDER BY "
                              "run_id)");
    ASSERT_TRUE(q.step());
    EXPECT_EQ(q.text(0), "series6xt_gx6450|series6xt_gx6450|series6xt_gx6450|series6xt_gx6450 gpu.mode=imr");
  }
  // Without --config the dram plot lists the two; each listed name draws.
  const std::string listed = draw({"dram", "--db", db}, /*may_refuse=*/true);
  EXPECT_NE(listed.find("mixes 2 configurations (series6xt_gx6450, series6xt_gx6450 gpu.mode=imr)"), std::string::npos)
      << listed;
  EXPECT_NE(draw({"dram", "--db", db, "--config", "series6xt_gx6450"}).find("mean of up to 3 repetitions"),
            std::string::npos);
  EXPECT_NE(draw({"dram", "--db", db, "--config", "series6xt_gx6450 gpu.mode=imr"}).find("1 runs"), std::string::npos);
}

}  // namespace
