// Every command line of README.md and docs/*.md runs, as written, from an empty folder outside the
// checkout with the build's tbdrsim first on PATH (issue 51). The documents are parsed, not quoted:
// each fenced block carries a label (```sh for command lines, ```text, ```sql, ```ini, ... for the
// rest), and the ```sh blocks of one document run in document order as one bash script (set -euo
// pipefail), so a later block uses the files an earlier one made. What the test changes is listed
// here, visibly, and each entry must still match the documents (a stale entry fails):
//   - kSubstitutions: smaller sizes (resolution, scene detail, light counts, fewer techniques) and
//     stand-ins for what needs a cluster or RenderDoc, so the suite stays about a minute on 2 cores;
//   - kExclusions: lines that cannot run here (package installs, the build itself, the fuzzers and
//     sanitizers, external DRAM simulators, interactive sqlite3), each with its reason;
//   - kKnownFailing: lines that fail because of a tool bug not yet fixed (reported, not run);
//   - kPreludes: commands a document needs from another document (queries.md reports on the sweep
//     databases docs/sweeps.md makes), with the reason.
// Every other command line runs: a line is either run, excluded or known failing, never skipped.
#include <gtest/gtest.h>

#include <sys/wait.h>

#include <algorithm>
#include <cctype>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "file_text.hpp"
#include "scratch_dir.hpp"

namespace tbdr {
namespace {

namespace fs = std::filesystem;

const testing_scratch::ScratchCleanup docs_scratch_cleanup{"docs_commands"};

using testing_support::read_text;

/// The documents whose command lines run: README.md and every docs/*.md, by path from the checkout.
std::vector<std::string> all_documents() {
  std::vector<std::string> docs{"README.md"};
  for (const auto& e : fs::directory_iterator(fs::path(TBDRSIM_SOURCE_DIR) / "docs")) {
    if (e.path().extension() == ".md") docs.push_back("docs/" + e.path().filename().string());
  }
  std::sort(docs.begin() + 1, docs.end());
  return docs;
}

/// One fenced block of a document.
struct Block {
  std::string label;               ///< what follows the opening ``` ("sh", "text", ...)
  int first_line = 0;              ///< 1-based line of the block's first content line
  std::vector<std::string> lines;  ///< its content lines
};

std::vector<std::string> split_lines(const std::string& text) {
  std::vector<std::string> lines;
  std::stringstream ss(text);
  for (std::string line; std::getline(ss, line);) lines.push_back(line);
  return lines;
}

/// The fenced blocks of `text` in order (an unclosed block is returned as it stands).
std::vector<Block> fenced_blocks(const std::string& text) {
  std::vector<Block> blocks;
  const auto lines = split_lines(text);
  bool inside = false;
  for (std::size_t i = 0; i < lines.size(); ++i) {
    const std::string& line = lines[i];
    const bool fence = line.rfind("```", 0) == 0;
    if (fence && !inside) {
      blocks.push_back({line.substr(3), static_cast<int>(i) + 2, {}});
      inside = true;
    } else if (fence) {
      inside = false;
    } else if (inside) {
      blocks.back().lines.push_back(line);
    }
  }
  return blocks;
}

std::string trim(const std::string& s) {
  const auto a = s.find_first_not_of(" \t");
  if (a == std::string::npos) return "";
  return s.substr(a, s.find_last_not_of(" \t") - a + 1);
}

/// A shell line continues on the next when it ends (comment aside) in a backslash, `|`, `&&` or `||`.
bool continues(const std::string& line) {
  const std::string t = trim(line);
  return !t.empty() && (t.back() == '\\' || t.back() == '|' || (t.size() >= 2 && t.substr(t.size() - 2) == "&&"));
}

/// One command of a ```sh block: its lines (with continuations) and where it is.
struct Command {
  std::string doc;
  int line = 0;                    ///< 1-based line of its first line in the document
  std::vector<std::string> lines;  ///< as written
  std::string text() const {
    std::string s;
    for (const auto& l : lines) s += l + "\n";
    return s;
  }
};

/// The commands of one document's ```sh blocks, in order; blank and `#` comment lines are not
/// commands (a comment is kept with nothing to run).
std::vector<std::vector<Command>> sh_commands(const std::string& doc) {
  std::vector<std::vector<Command>> blocks;
  for (const Block& b : fenced_blocks(read_text(fs::path(TBDRSIM_SOURCE_DIR) / doc))) {
    if (b.label != "sh") continue;
    blocks.emplace_back();
    for (std::size_t i = 0; i < b.lines.size(); ++i) {
      const std::string t = trim(b.lines[i]);
      if (t.empty() || t[0] == '#') continue;
      Command c{doc, b.first_line + static_cast<int>(i), {b.lines[i]}};
      while (continues(b.lines[i]) && i + 1 < b.lines.size()) c.lines.push_back(b.lines[++i]);
      blocks.back().push_back(c);
    }
  }
  return blocks;
}

// ---- What the test changes, visibly ----

/// A text substitution applied to one document's commands before they run.
struct Substitution {
  std::string doc, from, to, why;
};
const std::vector<Substitution> kSubstitutions = {
    // README.md states these under its usage block (checked below).
    {"README.md", "1920x1080", "160x90", "small frame"},
    {"README.md", "960x540", "160x90", "small frame"},
    {"README.md", "--lights 256", "--lights 16", "few lights"},
    {"README.md", "atrium:3", "atrium:1", "lightest atrium detail"},
    {"README.md", "atrium:2", "atrium:1", "lightest atrium detail"},
    {"README.md", "tbdrsim study ", "tbdrsim study --scene atrium:1 --resolution 160x90 --lights 16 ",
     "the main job at a small size"},
    // The doc says so: without RenderDoc, step 2 imports the committed intermediate of that capture.
    {"docs/capture-import.md", "tbdrsim import /tmp/vkcube_frame272.rdc --out vkcube.trace",
     "tbdrsim import \"$(tbdrsim --checkout)/tests/data/capture/vkcube\" --out vkcube.trace",
     "no RenderDoc here: the committed intermediate of the same capture"},
    // Installing into the scratch folder instead of the user's ~/.local.
    {"docs/install.md", "cmake --install build --prefix ~/.local",
     "cmake --install \"$TBDRSIM_BUILD_DIR\" --prefix \"$PWD/local\"", "install this build into the scratch folder"},
    {"docs/install.md", "$HOME/.local/bin", "$PWD/local/bin", "the prefix above"},
    {"docs/queries.md", "--scene atrium:2", "--scene atrium:1", "lightest atrium detail"},
    {"docs/queries.md", "tbdrsim study --out ", "tbdrsim study --scene atrium:1 --out ", "lightest atrium detail"},
    {"docs/queries.md", "--resolution 960x540", "--resolution 64x36", "small frame"},
    {"docs/queries.md", "--lights 256", "--lights 16", "few lights"},
    {"docs/queries.md", "--lights 1024 --images none", "--lights 16 --images none", "few lights (studies only)"},
    {"docs/sweeps.md", "cut -d: -f1)", "cut -d: -f1 | grep -x -e plain_forward -e deferred -e forward_light_stack)",
     "3 of the 13 techniques (the light stack is the one pls_budget changes)"},
    {"docs/sweeps.md", "--scene atrium:2", "--scene atrium:1", "lightest atrium detail"},
    {"docs/sweeps.md", "--resolution 960x540", "--resolution 64x36", "small frame"},
    {"docs/sweeps.md", "--slices 16", "--slices 2", "two array tasks"},
    {"docs/sweeps.md", "sbatch tile_job/tile_size.sbatch",
     "for i in 0 1; do SLURM_ARRAY_TASK_ID=$i bash tile_job/tile_size.sbatch; done",
     "no Slurm here: each array task by hand, as docs/sweeps.md describes"},
};

/// A command that does not run here: every command containing `line` in document `doc`.
struct Exclusion {
  std::string doc, line, reason;
};
const std::vector<Exclusion> kExclusions = {
    {"README.md", "bash scripts/install_deps.sh && cmake -S . -B build && cmake --build build -j2 && build/tbdrsim study",
     "installs packages as root and builds; CI builds, and the usage block runs the study"},
    {"README.md", "bash scripts/install_deps.sh && cmake -S . -B build -DTBDRSIM_WERROR=ON",
     "installs packages and runs this very test suite: it is CI itself"},
    {"docs/capture-import.md", "xvfb-run -a -s \"-screen 0 1280x720x24\" /usr/bin/python3",
     "needs Xvfb, vkcube and RenderDoc (scripts/install_capture_deps.sh), not installed for the tests"},
    {"docs/capture-import.md", "VK_LAYER_LUNARG_gfxreconstruct", "needs Xvfb, vkcube and gfxreconstruct"},
    {"docs/capture-import.md", "scripts/capture/capture_gl.sh",
     "needs Xvfb, zink, RenderDoc and the application (scripts/install_capture_deps.sh --examples)"},
    {"docs/capture-import.md", "tbdrsim import /tmp/glmark2_shading.rdc", "imports the capture the line above makes"},
    {"docs/capture-import.md", "tbdrsim import /tmp/shading_0.rdc", "imports the captures the line above makes"},
    {"docs/capture-import.md", "tbdrsim run --trace shading_seq.trace", "replays the import the line above makes"},
    {"docs/capture-import.md", "gfxrecon-convert", "needs gfxreconstruct"},
    {"docs/dram-cross-check.md", "bash bench/dram_vs_dramsim3.sh", "needs the user's build of DRAMsim3"},
    {"docs/dram-cross-check.md", "bash bench/dram_vs_drampower.sh", "needs the user's build of DRAMPower"},
    {"docs/fuzzing.md", "bash scripts/fuzz.sh", "builds with clang and runs the fuzzers for minutes: CI's own step"},
    {"docs/fuzzing.md", "bash scripts/sanitize.sh", "a second build under ASan + UBSan: CI's own step"},
    {"docs/install.md", "cmake -S . -B build -DCMAKE_BUILD_TYPE=Release", "the build itself (in the checkout): CI"},
    {"docs/install.md", "cmake -S . -B build -DTBDRSIM_X86_64_LEVEL=baseline", "a second build of the checkout"},
    {"docs/queries.md", "sqlite3 -column -header out/tile_size.db", "opens an interactive sqlite3 shell"},
};

/// A command that fails as written because of a tool bug not fixed yet: not run, and reported.
struct KnownFailing {
  std::string doc, line, reason;
};
const std::vector<KnownFailing> kKnownFailing = {};

/// Commands run before a document's own, for what it takes from another document.
struct Prelude {
  std::string doc, script, reason;
};
const std::vector<Prelude> kPreludes = {
    {"docs/queries.md",
     // The report and plot lines read the databases of the example sweeps (docs/sweeps.md): its
     // traces (3 techniques, 64x36, atrium:1), each sweep into out/NAME.db (pls_budget on the one
     // trace the budget changes, the light stack's); `run` lines replay t.trace.
     "mkdir -p out/traces\n"
     "for t in plain_forward deferred forward_light_stack; do for n in 64 256 1024; do\n"
     "  tbdrsim trace --technique $t --scene atrium:1 --lights $n --resolution 64x36 --out out/traces/${t}_l$n.trace\n"
     "done; done\n"
     "tbdrsim sweep techniques --trace 'out/traces/*.trace' --db out/techniques.db -j 2 --progress none\n"
     "tbdrsim sweep tile_size --trace 'out/traces/*_l256.trace' --db out/tile_size.db -j 2 --progress none\n"
     "tbdrsim sweep lights --trace 'out/traces/*.trace' --db out/lights.db -j 2 --progress none\n"
     "tbdrsim sweep pls_budget --trace out/traces/forward_light_stack_l1024.trace --db out/pls.db -j 2 --progress none\n"
     "tbdrsim trace --technique plain_forward --scene atrium:1 --lights 16 --resolution 64x36 --out t.trace\n",
     "reports on docs/sweeps.md's sweep databases and on a trace of the reader's"},
    {"docs/plots.md",
     // The examples plot the study (README.md: 13 techniques x 256 and 1024 lights; here 3 of
     // them, deferred the delta plot's baseline), the tile_size sweep and the light stack sweep
     // (docs/sweeps.md).
     "tbdrsim study --out study --scene atrium:1 --resolution 64x36 --images none --technique plain_forward deferred "
     "tiled_deferred\n"
     "mkdir -p out/traces\n"
     "for t in plain_forward deferred forward_light_stack; do\n"
     "  tbdrsim trace --technique $t --scene atrium:1 --lights 256 --resolution 64x36 --out out/traces/${t}_l256.trace\n"
     "done\n"
     "tbdrsim sweep tile_size --trace 'out/traces/*_l256.trace' --db out/tile_size.db -j 2 --progress none\n"
     "tbdrsim sweep light_stack_bytes --db stack.db -j 2 --progress none\n",
     "plots the README's study and docs/sweeps.md's sweep databases"},
};

/// What a document's run must print or leave behind (beyond exiting 0).
struct Expectation {
  std::string doc;
  std::vector<std::string> log_lines;  ///< substrings of the output
  std::vector<std::string> files;      ///< paths from the scratch folder
};
const std::vector<Expectation> kExpectations = {
    // The sweep and its Slurm shards ran the same points: the merged database holds as many
    // finished runs as the sweep's (tile_size: 12 configurations x 3 traces = 36).
    {"README.md",
     {"sweep tile_size: 36 point(s)", "merged into all.db: 36 run(s) copied", "30 frames sampled: 8 groups"},
     {"pf.trace", "results.db", "study_mobile/study.db", "sweep.db", "all.db", "tile.png", "slurm/tile_size.sbatch",
      "slurm/shard_0.db", "slurm/shard_1.db", "vkcube.trace", "validation/validation.db"}},
    {"docs/capture-import.md",
     {"coverage: 76800 of 76800 pixels agree", "coverage: 75758 of 76800 pixels agree",
      "coverage agrees at 1200; covered in both 1200, triangle matches at 1200 (100.00%)", "pass pass_54 area=0,0,84,84",
      // the desktop rows of the doc's per-mode table
      "| imr      |    1 | 409148 |        0.6819 |         5.981 |          0.6977 |",
      "| tbdr     |    1 | 521780 |        0.8696 |         8.552 |           0.932 |"},
     {"vkcube.capture/frame.json", "vkcube_compare.png", "img_tbdr", "img_tbr", "img_imr", "desktop.capture/frame.json",
      "desktop_compare.png", "desktop_tbdr", "desktop_imr"}},
    {"docs/install.md", {"/local/share/tbdrsim\n"}, {"local/bin/tbdrsim"}},
    // Three studies of 13 techniques in one database; the report's best row per configuration.
    {"docs/queries.md",
     {"39 finished run(s), grouped by config x technique", "\nseries6xt_gx6450  ",
      "\nseries6xt_gx6450 isp.tag_buffers=4  ", "\nseries6xt_gx6450 tiling.tile_height=16 tiling.tile_width=16  "},
     {"techniques.md", "techniques.png", "scaling.png", "sens.png", "run.txt", "run.json", "run.trace.json"}},
    {"docs/plots.md", {}, {"time.png", "dram.png", "tiles.png", "tile.png", "budget.png", "stack.png", "stack_bytes.png"}},
    {"docs/sweeps.md", {}, {"stack.db", "tile_size.db", "tile_job/tile_size.sbatch", "tile_job/shard_1.db"}},
    // Two runs of the 6-frame sequence, each with its summary, and a sampled run of it.
    {"docs/sequences.md",
     {"6 frames (camera orbit, lights orbit)", "sequence: 6 frames", "2|steady_interval_ms|", "6 frames sampled: 4 groups"},
     {"orbit.trace", "seq.db", "seq.png", "sampled.png"}},
};

std::string replace_all(std::string s, const std::string& from, const std::string& to, int* count = nullptr) {
  for (auto at = s.find(from); at != std::string::npos; at = s.find(from, at + to.size())) {
    s.replace(at, from.size(), to);
    if (count) ++*count;
  }
  return s;
}

bool contains(const std::string& s, const std::string& part) { return s.find(part) != std::string::npos; }

/// One document's plan: the script that runs, and what was left out.
struct DocPlan {
  std::string script;                     ///< bash lines to run (prelude, then the doc's commands)
  int commands_run = 0;                   ///< commands of the document that run
  std::vector<std::string> not_run;       ///< "doc:line: reason" of excluded and known failing commands
  std::map<std::string, int> applied;     ///< substitution `from` -> how often it applied
};

/// Builds the script of document `doc` from its ```sh blocks and the tables above.
DocPlan plan(const std::string& doc) {
  DocPlan p;
  for (const auto& pre : kPreludes) {
    if (pre.doc == doc) p.script += "# prelude: " + pre.reason + "\n__doc_at prelude\n" + pre.script;
  }
  for (const auto& block : sh_commands(doc)) {
    for (const Command& c : block) {
      const std::string text = c.text();
      std::string why;
      for (const auto& e : kExclusions) {
        if (e.doc == doc && contains(text, e.line)) why = "excluded: " + e.reason;
      }
      for (const auto& k : kKnownFailing) {
        if (k.doc == doc && contains(text, k.line)) why = "known failing: " + k.reason;
      }
      const std::string where = doc + ":" + std::to_string(c.line);
      if (!why.empty()) {
        p.not_run.push_back(where + ": " + why);
        p.script += ":  # " + where + " not run (" + why + ")\n";  // `:` keeps a loop body non-empty
        continue;
      }
      std::string run = text;
      for (const auto& s : kSubstitutions) {
        if (s.doc != doc) continue;
        int n = 0;
        run = replace_all(run, s.from, s.to, &n);
        p.applied[s.from] += n;
      }
      p.script += "__doc_at '" + where + "'\n" + run;
      ++p.commands_run;
    }
  }
  return p;
}

/// How a script ran: exit status 0, its output, and the folder it ran in.
struct ScriptRun {
  bool ok;
  std::string log;
  fs::path dir;
};

/// Runs `script` with bash (set -euo pipefail) in a new scratch folder outside the checkout with
/// the build's tbdrsim first on PATH; returns its exit status and output. A failing command names
/// its document line.
ScriptRun run_script(const std::string& name, const std::string& script) {
  const fs::path dir = testing_scratch::scratch_dir("docs_commands", name);
  EXPECT_EQ(dir.lexically_relative(TBDRSIM_SOURCE_DIR).string().rfind("..", 0), 0u) << "scratch inside the checkout";
  // __doc_at names the document line that runs next in the log, with the seconds since the start.
  std::ofstream(dir / "doc.sh") << "set -euo pipefail\n__doc_line=''\n"
                                << "__doc_at() { __doc_line=$1; echo \"[doc line $1, at $SECONDS s]\"; }\n"
                                << "trap 'echo \"doc line failed (exit $?) at $__doc_line: $BASH_COMMAND\" >&2' ERR\n"
                                << script;
  const fs::path bin_dir = fs::path(TBDRSIM_BINARY).parent_path();
  const std::string cmd = "cd '" + dir.string() + "' && TBDRSIM_BUILD_DIR='" + bin_dir.string() + "' PATH='" +
                          bin_dir.string() + "':\"$PATH\" bash doc.sh > doc.log 2>&1";
  const int status = std::system(cmd.c_str());
  return {WIFEXITED(status) && WEXITSTATUS(status) == 0, read_text(dir / "doc.log"), dir};
}

std::string tail(const std::string& log) { return log.substr(log.size() > 6000 ? log.size() - 6000 : 0); }

/// The documents that have ```sh blocks, each a parameter of DocsCommands.RunAsWrittenFromAnotherFolder.
const std::vector<std::string> kDocsWithCommands = {
    "README.md",          "docs/capture-import.md", "docs/dram-cross-check.md", "docs/fuzzing.md",
    "docs/install.md",    "docs/plots.md",          "docs/queries.md",          "docs/sequences.md",
    "docs/sweeps.md",
};

// Every fenced block says what it holds; command lines are in ```sh blocks only, without prompts
// or output; every document with commands is run below; every entry of the tables above still
// matches its document.
TEST(DocsCommands, EveryCommandIsRunOrExcludedAndEveryTableEntryMatches) {
  const std::set<std::string> labels = {"sh", "text", "sql", "ini", "trace", "cpp"};
  std::vector<std::string> with_commands;
  for (const std::string& doc : all_documents()) {
    bool has_sh = false;
    for (const Block& b : fenced_blocks(read_text(fs::path(TBDRSIM_SOURCE_DIR) / doc))) {
      const std::string where = doc + ":" + std::to_string(b.first_line - 1);
      EXPECT_TRUE(labels.count(b.label)) << where << ": fenced block labelled '" << b.label << "' (want one of sh, text, "
                                         << "sql, ini, trace, cpp)";
      has_sh = has_sh || b.label == "sh";
      for (const std::string& line : b.lines) {
        const std::string t = trim(line);
        EXPECT_NE(t.rfind("$ ", 0), 0u) << where << ": a prompt line; commands go in ```sh without '$ ': " << line;
        if (b.label != "sh") {
          for (const char* cmd : {"tbdrsim ", "bash ", "sqlite3 ", "cmake ", "/usr/bin/python3 "}) {
            EXPECT_NE(t.rfind(cmd, 0), 0u) << where << ": a command line in a ```" << b.label << " block: " << line;
          }
        }
      }
    }
    if (has_sh) with_commands.push_back(doc);
  }
  EXPECT_EQ(with_commands, kDocsWithCommands) << "a document with ```sh blocks is missing from kDocsWithCommands";

  for (const auto& e : kExclusions) {
    int matches = 0;
    for (const auto& block : sh_commands(e.doc)) {
      for (const Command& c : block) matches += contains(c.text(), e.line) ? 1 : 0;
    }
    EXPECT_GT(matches, 0) << "stale exclusion: no command of " << e.doc << " contains '" << e.line << "'";
  }
  for (const auto& k : kKnownFailing) {
    int matches = 0;
    for (const auto& block : sh_commands(k.doc)) {
      for (const Command& c : block) matches += contains(c.text(), k.line) ? 1 : 0;
    }
    EXPECT_GT(matches, 0) << "stale known-failing entry: no command of " << k.doc << " contains '" << k.line << "'";
  }
  for (const std::string& doc : kDocsWithCommands) {
    const DocPlan p = plan(doc);
    for (const auto& s : kSubstitutions) {
      if (s.doc != doc) continue;
      EXPECT_GT(p.applied.at(s.from), 0) << "stale substitution in " << doc << ": '" << s.from << "'";
    }
    for (const std::string& n : p.not_run) std::cout << "not run: " << n << "\n";
  }
  for (const auto& x : kExpectations) {
    EXPECT_NE(std::find(kDocsWithCommands.begin(), kDocsWithCommands.end(), x.doc), kDocsWithCommands.end()) << x.doc;
  }
  for (const auto& pre : kPreludes) {
    EXPECT_NE(std::find(kDocsWithCommands.begin(), kDocsWithCommands.end(), pre.doc), kDocsWithCommands.end()) << pre.doc;
  }

  // README.md tells its readers how its usage block is run: each of its substitutions is stated there.
  const std::string readme = read_text(fs::path(TBDRSIM_SOURCE_DIR) / "README.md");
  EXPECT_TRUE(contains(readme, "`tests/test_docs_commands.cpp`"));
  for (const auto& s : kSubstitutions) {
    if (s.doc != "README.md") continue;
    const std::string stated = s.from == "tbdrsim study " ? "study" : s.from;
    EXPECT_TRUE(contains(readme, "`" + stated + "`")) << "README.md does not state the substitution of " << s.from;
  }
}

class DocsCommands : public testing::TestWithParam<std::string> {};

// The document's commands, with its prelude and substitutions, run in order and all succeed.
TEST_P(DocsCommands, RunAsWrittenFromAnotherFolder) {
  const std::string doc = GetParam();
  const DocPlan p = plan(doc);
  for (const std::string& n : p.not_run) std::cout << "not run: " << n << "\n";
  if (p.commands_run == 0) GTEST_SKIP() << doc << ": every command is excluded (listed above)";
  std::string name = doc;
  for (char& ch : name) ch = std::isalnum(static_cast<unsigned char>(ch)) ? ch : '_';
  const ScriptRun r = run_script(name, p.script);
  ASSERT_TRUE(r.ok) << tail(r.log);
  // Where the time went: the log's line markers.
  std::stringstream log(r.log);
  for (std::string line; std::getline(log, line);) {
    if (line.rfind("[doc line ", 0) == 0) std::cout << line << "\n";
  }
  for (const auto& x : kExpectations) {
    if (x.doc != doc) continue;
    for (const std::string& line : x.log_lines) EXPECT_TRUE(contains(r.log, line)) << line << "\n" << tail(r.log);
    for (const std::string& f : x.files) EXPECT_TRUE(fs::exists(r.dir / f)) << f << "\n" << tail(r.log);
  }
}

std::string doc_test_name(const testing::TestParamInfo<std::string>& info) {
  std::string name = info.param;
  if (name.rfind("docs/", 0) == 0) name = name.substr(5);
  for (char& ch : name) ch = std::isalnum(static_cast<unsigned char>(ch)) ? ch : '_';
  return name;
}

INSTANTIATE_TEST_SUITE_P(Docs, DocsCommands, testing::ValuesIn(kDocsWithCommands), doc_test_name);

// Lines in the prose (not in a command block) that name analysis/views.sql or the plot scripts run
// from any folder: `tbdrsim --views | sqlite3 DB` and a plot script through `tbdrsim --checkout`.
TEST(DocsProseCommands, ViewsAndPlotScriptLinesRunFromAnotherFolder) {
  const std::string queries = read_text(fs::path(TBDRSIM_SOURCE_DIR) / "docs/queries.md");
  const std::string plots = read_text(fs::path(TBDRSIM_SOURCE_DIR) / "docs/plots.md");
  ASSERT_TRUE(contains(queries, "`tbdrsim --views | sqlite3 results.db`"));
  const std::string plot_line = "/usr/bin/python3 \"$(tbdrsim --checkout)/analysis/plot_energy.py\" --db study/study.db";
  ASSERT_TRUE(contains(plots, "`" + plot_line + "`"));
  EXPECT_FALSE(contains(queries, "< analysis/views.sql"));
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
