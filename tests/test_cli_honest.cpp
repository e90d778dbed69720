// The command line says what it did and what it left out (issue 51): failed and refused runs counted
// with their reasons (report, study), `--images none` meaning no images, a failed run leaving no
// folder behind, a study re-run into its folder counted honestly, misspelled options and metrics
// answered with suggestions, `--stats` repeatable, a non-SQLite --db named cleanly, `params PATTERN`
// and wrapped descriptions, sweep files naming presets as --config does, dry runs naming
// configurations by label, the timeline's time unit, and units' busy + stalled + idle = the frame.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "file_text.hpp"
#include "analysis/report.hpp"
#include "analysis/results_db.hpp"
#include "analysis/sql.hpp"
#include "cli_run.hpp"
#include "db_query.hpp"
#include "scratch_dir.hpp"

namespace tbdr {
namespace {

namespace fs = std::filesystem;
using testing_support::query_number;
using testing_support::run_cli;

const testing_scratch::ScratchCleanup honest_scratch_cleanup{"cli_honest"};

/// A tiny trace (160x90, atrium:1, 16 lights) in `dir`, made by `tbdrsim trace`.
std::string tiny_trace(const fs::path& dir, const std::string& technique = "plain_forward") {
  const std::string path = (dir / (technique + ".trace")).string();
  const auto r = run_cli({"trace", "--technique", technique, "--resolution", "160x90", "--scene", "atrium:1", "--lights",
                          "16", "--out", path});
  EXPECT_EQ(r.code, 0) << r.err;
  return path;
}

using testing_support::read_text;

// Item 10: a misspelled option gets the closest option names of that command, not only the usage.
TEST(CliHonest, MisspelledOptionsAreAnsweredWithASuggestion) {
  const auto r = run_cli({"run", "--trce", "x.trace", "--db", "x.db"});
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("did you mean '--trace'"), std::string::npos) << r.err;
  const auto s = run_cli({"study", "--resolutoin", "64x36"});
  EXPECT_EQ(s.code, 2);
  EXPECT_NE(s.err.find("did you mean '--resolution'"), std::string::npos) << s.err;
  const auto cmd = run_cli({"reprot", "--db", "x.db"});
  EXPECT_EQ(cmd.code, 2);
  EXPECT_NE(cmd.err.find("unknown command 'reprot'; did you mean 'report'?"), std::string::npos) << cmd.err;
  // Nothing close: the usage, as before.
  const auto far = run_cli({"params", "--zzzzzzzz"});
  EXPECT_EQ(far.code, 2);
  EXPECT_EQ(far.err.find("did you mean"), std::string::npos) << far.err;
  EXPECT_NE(far.err.find("usage: tbdrsim params"), std::string::npos) << far.err;
}

// Item 10: the same words in another order are suggested however far apart their spellings are
// (dram_energy_mj is 10 edits from energy_dram_mj).
TEST(CliHonest, MetricWithItsWordsSwappedIsSuggested) {
  const auto dir = testing_scratch::scratch_dir("cli_honest", "metric");
  const std::string db = (dir / "r.db").string();
  ASSERT_EQ(run_cli({"run", "--trace", tiny_trace(dir), "--db", db, "--quiet"}).code, 0);
  const auto r = run_cli({"report", "--db", db, "--metric", "dram_energy_mj"});
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("did you mean 'energy_dram_mj'"), std::string::npos) << r.err;
  const auto rank = run_cli({"report", "--db", db, "--rank", "dram_energy_mj"});
  EXPECT_EQ(rank.code, 2);
  EXPECT_NE(rank.err.find("did you mean 'energy_dram_mj'"), std::string::npos) << rank.err;
}

// Item 10: --stats twice writes both files from one run (one row in the database); the same file
// twice is refused before the run.
TEST(CliHonest, StatsIsRepeatable) {
  const auto dir = testing_scratch::scratch_dir("cli_honest", "stats");
  const std::string trace = tiny_trace(dir);
  const std::string db = (dir / "r.db").string();
  const auto r = run_cli({"run", "--trace", trace, "--db", db, "--quiet", "--stats", (dir / "s.txt").string(), "--stats",
                          (dir / "s.json").string()});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(read_text(dir / "s.txt").find("frame.tsp.shaded_samples"), std::string::npos);
  EXPECT_EQ(read_text(dir / "s.json").rfind("{", 0), 0u);
  EXPECT_EQ(query_number(db, "SELECT count(*) FROM runs"), 1.0);
  const auto twice = run_cli({"run", "--trace", trace, "--db", db, "--quiet", "--stats", (dir / "t.txt").string(), "--stats",
                              (dir / "t.txt").string()});
  EXPECT_EQ(twice.code, 2);
  EXPECT_NE(twice.err.find("given twice"), std::string::npos) << twice.err;
  EXPECT_EQ(query_number(db, "SELECT count(*) FROM runs"), 1.0) << "a refused command ran";
}

// Item 10: a text file given as --db is named, exit 2, without SQLite's statement text.
TEST(CliHonest, TextFileAsDatabaseIsNamedCleanly) {
  const auto dir = testing_scratch::scratch_dir("cli_honest", "text_db");
  const fs::path notes = dir / "notes.txt";
  std::ofstream(notes) << "not a database, just text that is long enough to have a header of its own\n";
  for (const std::vector<std::string>& args : {std::vector<std::string>{"report", "--db", notes.string()},
                                               std::vector<std::string>{"report", "--db", notes.string(), "--by", "config"}}) {
    const auto r = run_cli(args);
    EXPECT_EQ(r.code, 2) << args.front() << ": " << r.err;
    EXPECT_NE(r.err.find(notes.string()), std::string::npos) << r.err;
    EXPECT_EQ(r.err.find("cannot prepare"), std::string::npos) << r.err;
    EXPECT_EQ(r.err.find("SELECT"), std::string::npos) << r.err;
  }
}

// Item 10: `params PATTERN` lists the matching keys only; no line is longer than 100 characters
// (descriptions are wrapped); a pattern matching nothing is an error with a suggestion.
TEST(CliHonest, ParamsFiltersAndWraps) {
  const auto all = run_cli({"params"});
  ASSERT_EQ(all.code, 0) << all.err;
  std::istringstream lines(all.out);
  std::size_t longest = 0;
  std::string longest_line;
  for (std::string l; std::getline(lines, l);) {
    // (a single word longer than the line, a URL, stays whole)
    const auto first = l.find_first_not_of(' ');
    if (first != std::string::npos && l.find(' ', first) == std::string::npos) continue;
    if (l.size() > longest) {
      longest = l.size();
      longest_line = l;
    }
  }
  EXPECT_LE(longest, 100u) << longest_line;
  const auto tile = run_cli({"params", "tile_width"});
  ASSERT_EQ(tile.code, 0) << tile.err;
  EXPECT_NE(tile.out.find("tiling.tile_width"), std::string::npos) << tile.out;
  EXPECT_EQ(tile.out.find("tiling.tile_height"), std::string::npos) << tile.out;
  EXPECT_EQ(tile.out.find("isp.samples_per_clock"), std::string::npos) << tile.out;
  EXPECT_NE(tile.out.find("(matching 'tile_width')"), std::string::npos) << tile.out;
  const auto glob = run_cli({"params", "isp.*", "--format", "markdown"});
  ASSERT_EQ(glob.code, 0) << glob.err;
  EXPECT_NE(glob.out.find("`isp.tag_buffers`"), std::string::npos) << glob.out;
  EXPECT_EQ(glob.out.find("`tiling."), std::string::npos) << glob.out;
  const auto none = run_cli({"params", "tiling.tile_widht"});
  EXPECT_EQ(none.code, 2);
  EXPECT_NE(none.err.find("did you mean 'tiling.tile_width'"), std::string::npos) << none.err;
}

// Item 6: the views' SQL is printed by the tool itself (`tbdrsim --views | sqlite3 DB` from any
// folder, where `sqlite3 DB < analysis/views.sql` needs the checkout), exactly as compiled in.
TEST(CliHonest, ViewsArePrintedFromAnyFolder) {
  const auto r = run_cli({"--views"});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(r.out, std::string(views_sql()));
  EXPECT_NE(r.out.find("CREATE VIEW v_run_summary"), std::string::npos);
  const auto dir = testing_scratch::scratch_dir("cli_honest", "views");
  const SqlConnection db((dir / "by_hand.db").string());
  db.exec(r.out);  // what sqlite3 does with it
  SqlStatement q(db, "SELECT count(*) FROM sqlite_master WHERE type = 'view' AND name = 'v_unit'");
  ASSERT_TRUE(q.step());
  EXPECT_EQ(q.int64(0), 1);
}

// Item 8: `run --images none` writes no images and no folder named none; a run that fails (its
// trace is missing) leaves no images folder it created.
TEST(CliHonest, RunImagesNoneAndFailedRunsLeaveNoFolder) {
  const auto dir = testing_scratch::scratch_dir("cli_honest", "images");
  const std::string trace = tiny_trace(dir);
  const std::string db = (dir / "r.db").string();
  const auto before = fs::current_path();
  fs::current_path(dir);
  const auto r = run_cli({"run", "--trace", trace, "--db", db, "--quiet", "--images", "none"});
  const auto failed = run_cli({"run", "--trace", (dir / "missing.trace").string(), "--db", db, "--quiet", "--images",
                               (dir / "img").string()});
  fs::current_path(before);
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_FALSE(fs::exists(dir / "none"));
  EXPECT_EQ(failed.code, 2);
  EXPECT_FALSE(fs::exists(dir / "img")) << "the failed run left its images folder";
}

// Items 4 and 8: a study whose only failures are documented refusals (forward_light_stack's pixel
// local storage on an immediate-mode GPU) exits 0 and says which and why; the database holds the
// refused row with its reason, which `report` counts and explains; --images none makes no images
// folder and announces none; a second study into the same folder counts this study's runs and the
// database's apart.
TEST(CliHonest, StudyRefusalsAreCountedNotFailures) {
  const auto dir = testing_scratch::scratch_dir("cli_honest", "study");
  const std::string out = (dir / "s").string();
  const std::vector<std::string> args = {"study", "--out", out, "--resolution", "64x36", "--scene", "atrium:1", "--lights",
                                         "4", "--technique", "plain_forward", "forward_light_stack", "--modes", "tbdr",
                                         "imr", "--images", "none", "--jobs", "1"};
  const auto r = run_cli(args);
  EXPECT_EQ(r.code, 0) << r.out << r.err;
  // 2 techniques x 2 modes = 4 points: 3 run, forward_light_stack on imr refused.
  EXPECT_NE(r.out.find("refused: 1 of the 4 points"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("forward_light_stack at 4 lights on imr: pass"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("(this study: 3 finished run(s), 1 refused; the database holds 4 run(s), 3 finished)"),
            std::string::npos) << r.out;
  EXPECT_EQ(r.out.find("images and heat maps"), std::string::npos) << r.out;
  EXPECT_FALSE(fs::exists(fs::path(out) / "images"));
  const std::string db = (fs::path(out) / "study.db").string();
  EXPECT_EQ(query_number(db, "SELECT count(*) FROM runs WHERE status = 'failed' AND error LIKE 'refused: %pixel local storage%'"),
            1.0);
  const auto rep = run_cli({"report", "--db", db, "--metric", "cycles"});
  ASSERT_EQ(rep.code, 0) << rep.err;
  EXPECT_NE(rep.out.find("3 finished run(s) (1 failed run(s) left out)"), std::string::npos) << rep.out;
  EXPECT_NE(rep.out.find("  1 x refused: pass '"), std::string::npos) << rep.out;
  EXPECT_NE(rep.out.find("immediate-mode GPU (gpu.mode=imr) does not have"), std::string::npos) << rep.out;
  const auto csv = run_cli({"report", "--db", db, "--metric", "cycles", "--format", "csv"});
  ASSERT_EQ(csv.code, 0) << csv.err;
  EXPECT_EQ(csv.out.find("refused"), std::string::npos) << "the CSV stays a table: " << csv.out;
  EXPECT_NE(csv.err.find("1 failed run(s) left out:\n  1 x refused: pass '"), std::string::npos) << csv.err;
  // Again into the same folder: 3 more finished runs; the database holds 8 rows, 4 of them earlier.
  const auto again = run_cli(args);
  EXPECT_EQ(again.code, 0) << again.err;
  EXPECT_NE(again.out.find("(this study: 3 finished run(s), 1 refused; the database holds 8 run(s), 6 finished, 4 of them "
                           "from earlier studies into " + out),
            std::string::npos) << again.out;
}

// Item 10: a study refuses a light count of 0 (nothing to compare: the frame is unlit) before
// writing anything, even for techniques whose generators accept it; `trace --lights 0` stays the
// documented unlit frame (validate's probes), with no light evaluated.
TEST(CliHonest, StudyRefusesZeroLightsTraceDocumentsThem) {
  const auto dir = testing_scratch::scratch_dir("cli_honest", "zero_lights");
  const std::string out = (dir / "s").string();
  const auto r = run_cli({"study", "--out", out, "--resolution", "64x36", "--scene", "atrium:1", "--lights", "0", "--technique",
                          "plain_forward", "--images", "none", "--jobs", "1"});
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("--lights 0"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(out));
  const auto help = run_cli({"trace", "--help"});
  EXPECT_NE(help.out.find("0: none, the surfaces shaded"), std::string::npos) << help.out;  // (Boost wraps the rest)
  const std::string trace = (dir / "unlit.trace").string();
  ASSERT_EQ(run_cli({"trace", "--lights", "0", "--resolution", "64x36", "--scene", "atrium:1", "--out", trace}).code, 0);
  const std::string db = (dir / "r.db").string();
  ASSERT_EQ(run_cli({"run", "--trace", trace, "--db", db, "--quiet"}).code, 0);
  EXPECT_EQ(query_number(db, "SELECT lights_per_pixel FROM v_run_summary"), 0.0);
}

// Item 9: a sweep file's `config = NAME` names a preset as --config does; the dry run names each
// point's configuration by its label (the preset and the values that differ from it: 32 is the
// preset's tile width, so that point is the preset itself), its hash beside it.
TEST(CliHonest, SweepFileNamesPresetsAndDryRunShowsLabels) {
  const auto dir = testing_scratch::scratch_dir("cli_honest", "sweep");
  const std::string trace = tiny_trace(dir);
  std::ofstream(dir / "s.ini") << "[sweep]\nconfig = series6xt_gx6450\ntrace = " << trace
                               << "\n[vary]\ntiling.tile_width = 16, 32\n";
  const auto r = run_cli({"sweep", (dir / "s.ini").string(), "--dry-run", "--db", (dir / "r.db").string()});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("(config series6xt_gx6450 tiling.tile_width=16 ["), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("tiling.tile_width=32 | plain_forward.trace  (config series6xt_gx6450 ["), std::string::npos) << r.out;
  std::ofstream(dir / "bad.ini") << "[sweep]\nconfig = series6xt_gx6540\ntrace = " << trace << "\n";
  const auto bad = run_cli({"sweep", (dir / "bad.ini").string(), "--dry-run", "--db", (dir / "r.db").string()});
  EXPECT_EQ(bad.code, 2);
  EXPECT_NE(bad.err.find("bad.ini:2"), std::string::npos) << bad.err;
  EXPECT_NE(bad.err.find("did you mean 'series6xt_gx6450'"), std::string::npos) << bad.err;
}

// Item 7: the timeline declares how its microsecond timestamps are shown (ms, not ns), and every
// unit's busy, stalled and idle cycles add up to the frame (stalled time counted once however many
// tiles wait at once, and not while the unit works): v_unit's three shares add up to 100.
TEST(CliHonest, UnitSharesAddUpToTheFrameAndTheTimelineUnitIsRight) {
  const auto dir = testing_scratch::scratch_dir("cli_honest", "units");
  const std::string trace = [&] {
    const std::string path = (dir / "deferred.trace").string();
    const auto t = run_cli({"trace", "--technique", "deferred", "--resolution", "480x270", "--scene", "atrium:2", "--lights",
                            "64", "--out", path});
    EXPECT_EQ(t.code, 0) << t.err;
    return path;
  }();
  const std::string db = (dir / "r.db").string();
  const fs::path timeline = dir / "t.json";
  const auto r = run_cli({"run", "--trace", trace, "--db", db, "--quiet", "--timeline", timeline.string()});
  ASSERT_EQ(r.code, 0) << r.err;
  const std::string json = read_text(timeline);
  EXPECT_NE(json.find("\"displayTimeUnit\": \"ms\""), std::string::npos);
  EXPECT_EQ(json.find("\"displayTimeUnit\": \"ns\""), std::string::npos);
  const ResultsDb rdb(db);
  const double frame = query_number(rdb, "SELECT value FROM stats WHERE scope = 'frame/timing' AND name = 'frame_cycles'");
  SqlStatement q(rdb.sql(), "SELECT unit, busy_cycles, stalled_cycles, idle_cycles, busy_pct + stalled_pct + idle_pct FROM v_unit");
  int units = 0;
  while (q.step()) {
    ++units;
    const std::string unit = q.text(0);
    // (the frame is a whole number of cycles, the spans are not: a cycle of rounding)
    EXPECT_NEAR(q.real(1) + q.real(2) + q.real(3), frame, 1.0) << unit;
    EXPECT_GE(q.real(3), 0.0) << unit;
    EXPECT_LE(q.real(2), frame - q.real(1) + 1.0) << unit;
    EXPECT_NEAR(q.real(4), 100.0, 100.0 / frame) << unit;
  }
  EXPECT_EQ(units, 7);
}

}  // namespace
}  // namespace tbdr
