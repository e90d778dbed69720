// Every statistic's name is declared once, as a member of a typed statistics set (TBDR_STATS,
// sim/kernel/stats.hpp), and code that reads a figure back names it through the set
// (stat_name(&Set::member), a set's kScope) or the database's own definitions (analysis/views.sql).
// Rows are made from the sets in one place (sim/app/stat_rows.cpp). This test holds the project to that: it collects every name a run stores (runs of a TBDR frame,
// an IMR frame and compute techniques), reads every string literal of sim/, models/ and analysis/
// (C++ sources and analysis/views.sql; X-macro declaration lines, where names are identifiers and
// the literals are units and descriptions, left out), and fails when a statistic's name is spelled
// as a literal in more than one file, unless an entry below says why that word is also something
// else (a unit, an option, a trace keyword). The Python plot scripts are not read: they select
// the views' columns, which views.sql defines.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "file_text.hpp"
#include "analysis/report.hpp"
#include "analysis/results_db.hpp"
#include "analysis/sql.hpp"
#include "cli_run.hpp"
#include "scratch_dir.hpp"

namespace tbdr {
namespace {

namespace fs = std::filesystem;
using testing_support::run_cli;

const testing_scratch::ScratchCleanup stat_names_scratch_cleanup{"stat_names"};

using testing_support::read_text;

/// The words quoted with single quotes inside `text` (SQL string literals).
void single_quoted(const std::string& text, std::vector<std::string>& out) {
  for (std::size_t at = text.find('\''); at != std::string::npos;) {
    const std::size_t end = text.find('\'', at + 1);
    if (end == std::string::npos) break;
    out.push_back(text.substr(at + 1, end - at - 1));
    at = text.find('\'', end + 1);
  }
}

/// Whether the line starting at `at` is an X-macro entry of a statistics list (`X(...)`).
bool x_macro_line(const std::string& src, std::size_t at) {
  while (at < src.size() && (src[at] == ' ' || src[at] == '\t')) ++at;
  return src.compare(at, 2, "X(") == 0;
}

/// The string literals of C++ source `src` (comments, character literals and X-macro declaration
/// lines skipped; raw strings read whole), each with the single-quoted words inside it.
std::vector<std::string> cpp_literals(const std::string& src) {
  std::vector<std::string> out;
  std::size_t i = 0;
  bool line_start = true;
  while (i < src.size()) {
    if (line_start && x_macro_line(src, i)) {  // skip to the end of the line
      i = src.find('\n', i);
      if (i == std::string::npos) break;
    }
    line_start = false;
    const char c = src[i];
    if (c == '\n') {
      line_start = true;
      ++i;
    } else if (src.compare(i, 2, "//") == 0) {
      i = src.find('\n', i);
      if (i == std::string::npos) break;
    } else if (src.compare(i, 2, "/*") == 0) {
      const std::size_t end = src.find("*/", i + 2);
      i = end == std::string::npos ? src.size() : end + 2;
    } else if (c == 'R' && i + 1 < src.size() && src[i + 1] == '"' &&
               (i == 0 || !(std::isalnum(static_cast<unsigned char>(src[i - 1])) || src[i - 1] == '_'))) {
      const std::size_t open = src.find('(', i + 2);
      const std::string close = ")" + src.substr(i + 2, open - i - 2) + "\"";
      const std::size_t end = src.find(close, open);
      out.push_back(src.substr(open + 1, end - open - 1));
      single_quoted(out.back(), out);
      i = end + close.size();
    } else if (c == '"') {
      std::string s;
      for (++i; i < src.size() && src[i] != '"'; ++i) {
        if (src[i] == '\\' && i + 1 < src.size()) ++i;
        s += src[i];
      }
      ++i;
      single_quoted(s, out);
      out.push_back(std::move(s));
    } else if (c == '\'' && !(i > 0 && std::isxdigit(static_cast<unsigned char>(src[i - 1])))) {  // a char literal, not 1'000
      for (++i; i < src.size() && src[i] != '\''; ++i) {
        if (src[i] == '\\') ++i;
      }
      ++i;
    } else {
      ++i;
    }
  }
  return out;
}

/// Every statistic name the runs of this test stored.
std::set<std::string> stored_stat_names(const std::string& db) {
  std::set<std::string> names;
  ResultsDb results(db);
  SqlStatement q(results.sql(), "SELECT DISTINCT name FROM stats");
  while (q.step()) names.insert(q.text(0));
  return names;
}

/// A statistic's name that is also another word of the project, with the files where that other
/// word is spelled and why.
struct AlsoAnotherWord {
  std::string name;
  std::set<std::string> files;
  std::string reason;
};

const std::vector<AlsoAnotherWord> kAlsoAnotherWord = {
    {"bytes", {"models/energy.cpp", "models/hw_config.cpp", "sim/trace/trace_reader.cpp"},
     "a unit (energy terms, parameters) and a trace keyword (buffer bytes=)"},
    {"width", {"sim/app/capture_convert.cpp", "sim/trace/trace_reader.cpp"}, "the trace's frame keyword and the capture JSON's key"},
    {"height", {"sim/app/capture_convert.cpp", "sim/trace/trace_reader.cpp"}, "the trace's frame keyword and the capture JSON's key"},
    {"lights",
     {"analysis/report.cpp", "sim/app/cmd_run.cpp", "sim/app/cmd_study.cpp", "sim/app/sweep_spec.cpp", "sim/trace/trace.cpp",
      "sim/trace/trace_reader.cpp"},
     "the --lights option (trace, study, sweep generate keys), the trace's keyword and report's dimension"},
    {"passes", {"sim/app/capture_convert.cpp", "sim/app/cmd_plot.cpp"}, "the capture JSON's key and the name of a plot"},
    {"threads", {"models/hw_config.cpp", "sim/app/cli.cpp", "sim/app/cmd_sweep.cpp"}, "a parameter's unit and the --threads option"},
    {"frame_time_ms", {"analysis/report.hpp", "analysis/views.sql"},
     "a metric of report (metric::kFrameTimeMs, its default) defined by views.sql's v_metric_def: checked below"},
};

TEST(StatNames, NoStatisticNameIsSpelledInTwoSourceFiles) {
  const fs::path dir = testing_scratch::scratch_dir("stat_names", "runs");
  const std::string db = (dir / "s.db").string();
  // A TBDR frame with compute (clustered_deferred), a visibility buffer, and the same frame on an IMR.
  for (const char* technique : {"clustered_deferred", "visibility_buffer", "forward_plus"}) {
    const std::string trace = (dir / (std::string(technique) + ".trace")).string();
    ASSERT_EQ(run_cli({"trace", "--technique", technique, "--scene", "atrium:1", "--lights", "16", "--resolution", "64x36", "--out", trace}).code, 0);
    ASSERT_EQ(run_cli({"run", "--trace", trace, "--db", db, "--quiet"}).code, 0);
  }
  ASSERT_EQ(run_cli({"run", "--trace", (dir / "forward_plus.trace").string(), "--db", db, "--quiet", "--set", "gpu.mode=imr"}).code, 0);
  const std::set<std::string> names = stored_stat_names(db);
  ASSERT_GT(names.size(), 150u);  // 212 names measured

  std::map<std::string, std::set<std::string>> spelled;  // name -> files with a literal of it
  const fs::path root = TBDRSIM_SOURCE_DIR;
  std::size_t files_read = 0;
  for (const char* folder : {"sim", "models", "analysis"}) {
    for (const auto& e : fs::recursive_directory_iterator(root / folder)) {
      const std::string ext = e.path().extension().string();
      if (ext != ".cpp" && ext != ".hpp" && ext != ".sql") continue;
      const std::string text = read_text(e.path());
      std::vector<std::string> literals;
      if (ext == ".sql") {
        single_quoted(text, literals);
      } else {
        literals = cpp_literals(text);
      }
      ++files_read;
      const std::string rel = fs::relative(e.path(), root).generic_string();
      for (const std::string& s : literals) {
        if (names.count(s)) spelled[s].insert(rel);
      }
    }
  }
  ASSERT_GT(files_read, 100u);

  std::map<std::string, const AlsoAnotherWord*> allowed;
  for (const auto& a : kAlsoAnotherWord) allowed[a.name] = &a;
  for (const auto& [name, files] : spelled) {
    if (files.size() < 2) continue;
    std::ostringstream where;
    for (const auto& f : files) where << " " << f;
    const auto it = allowed.find(name);
    ASSERT_TRUE(it != allowed.end()) << "statistic '" << name << "' is spelled as a literal in" << where.str()
                                     << ": read it through its set (stat_name(&Set::member)) or a view";
    for (const auto& f : files) EXPECT_TRUE(it->second->files.count(f)) << "'" << name << "' spelled again in " << f;
  }
  // Every entry is still needed (else it would hide a new spelling).
  for (const auto& a : kAlsoAnotherWord) {
    EXPECT_TRUE(names.count(a.name)) << a.name << " is no longer a statistic";
    EXPECT_GE(spelled[a.name].size(), 2u) << a.name << ": the entry is stale";
  }

  // The report's metric names are the database's: each is defined by v_metric_def.
  ResultsDb results(db);
  for (const char* m : metric::kAll) {
    SqlStatement q(results.sql(), "SELECT count(*) FROM v_metric_def WHERE metric = ?", std::string(m));
    ASSERT_TRUE(q.step());
    EXPECT_EQ(q.int64(0), 1) << m;
  }
}

/// Rows are made in one place: collect_stats is called only in sim/app/stat_rows.cpp (and defined in
/// sim/kernel/stats.hpp); the models hand over typed sets.
TEST(StatNames, RowsAreMadeOnlyInStatRows) {
  const fs::path root = TBDRSIM_SOURCE_DIR;
  std::set<std::string> callers;
  for (const char* folder : {"sim", "models", "workloads", "analysis"}) {
    for (const auto& e : fs::recursive_directory_iterator(root / folder)) {
      const std::string ext = e.path().extension().string();
      if (ext != ".cpp" && ext != ".hpp") continue;
      if (read_text(e.path()).find("collect_stats(") != std::string::npos) callers.insert(fs::relative(e.path(), root).generic_string());
    }
  }
  EXPECT_EQ(callers, (std::set<std::string>{"sim/app/stat_rows.cpp", "sim/kernel/stats.hpp"}));
}

/// The scanner itself: literals found, comments, char literals and X-macro lines not.
TEST(StatNames, LiteralScannerReadsWhatTheCompilerWould) {
  const std::string src =
      "// \"in_a_comment\"\n"
      "/* \"in_a_block\" */ auto a = \"plain\";\n"
      "  X(Counter, member, \"in_a_declaration\", Sum, \"description\")\n"
      "char q = '\"'; int n = 1'000; auto r = R\"sql(SELECT 'quoted' \"x\")sql\";\n"
      "auto e = \"esc\\\"aped\";\n";
  const std::vector<std::string> got = cpp_literals(src);
  const std::set<std::string> s(got.begin(), got.end());
  EXPECT_TRUE(s.count("plain"));
  EXPECT_TRUE(s.count("quoted"));
  EXPECT_TRUE(s.count("SELECT 'quoted' \"x\""));
  EXPECT_TRUE(s.count("esc\"aped"));
  EXPECT_FALSE(s.count("in_a_comment"));
  EXPECT_FALSE(s.count("in_a_block"));
  EXPECT_FALSE(s.count("in_a_declaration"));
  EXPECT_EQ(s.size(), 4u) << "a character literal or digit separator read as a string";
}

}  // namespace
}  // namespace tbdr
