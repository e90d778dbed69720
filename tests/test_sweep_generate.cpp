// Sweeps that generate their traces ([generate], docs/sweeps.md): parsing (lists of techniques,
// light counts and technique options; options passed only to the techniques that read them;
// errors naming file:line), a dry run that generates nothing, and a real sweep of
// configs/sweeps/light_stack_bytes.ini whose technique option is a dimension of the database.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>

#include "app/sweep.hpp"
#include "cli_run.hpp"
#include "db_query.hpp"
#include "kernel/errors.hpp"
#include "scratch_dir.hpp"

namespace tbdr {
namespace {

namespace fs = std::filesystem;
using testing_support::run_cli;

testing_scratch::ScratchCleanup scratch_cleanup{"sweep_generate"};
fs::path scratch(const std::string& name) { return testing_scratch::scratch_dir("sweep_generate", name); }

void write_file(const fs::path& p, const std::string& text) {
  fs::create_directories(p.parent_path());
  std::ofstream(p) << text;
}

/// Every entry under `dir`, recursively (what a command left behind).
std::set<std::string> listing(const fs::path& dir) {
  std::set<std::string> out;
  for (const auto& e : fs::recursive_directory_iterator(dir)) out.insert(fs::relative(e.path(), dir).string());
  return out;
}

std::int64_t scalar(const std::string& db, const std::string& sql) {
  return std::llround(testing_support::query_number(db, sql));
}

TEST(SweepGenerate, ParsesListsAndPassesOptionsOnlyToTechniquesThatReadThem) {
  const fs::path dir = scratch("parse");
  write_file(dir / "g.ini",
             "[sweep]\nname = g\n"
             "[vary]\nisp.tag_buffers = 1, 2\n"
             "[generate]\n"
             "technique = plain_forward, forward_light_stack\n"
             "scene = atrium:1\n"
             "resolution = 64x32\n"
             "lights = 16..32 step 16\n"
             "option.pls_bytes = 16, 32\n");
  const SweepSpec spec = parse_sweep_file((dir / "g.ini").string(), {}, (dir / "out" / "r.db").string(), trace_generators());
  // plain_forward does not read pls_bytes: 2 light counts; forward_light_stack: 2 x 2. 2 + 4 = 6.
  ASSERT_EQ(spec.generate.size(), 6u);
  EXPECT_EQ(spec.generate[0].label, "plain_forward lights=16");
  EXPECT_EQ(spec.generate[5].label, "forward_light_stack lights=32 pls_bytes=32");
  const std::vector<std::string> last = {"--technique", "forward_light_stack", "--scene", "atrium:1", "--resolution",
                                         "64x32", "--lights", "32", "--option", "pls_bytes=32"};
  EXPECT_EQ(spec.generate[5].args, last);
  std::set<std::string> ids;
  for (const auto& g : spec.generate) ids.insert(g.id);
  EXPECT_EQ(ids.size(), 6u) << "every request has its own hash";
  EXPECT_EQ(spec.generated_dir, (dir / "out" / "r.traces").string());
  EXPECT_EQ(generated_trace_path(spec, spec.generate[0]),
            (dir / "out" / "r.traces" / ("plain_forward-" + spec.generate[0].id + ".trace")).string());
  // The hash names what generates the trace, not where the database is: another database, same ids.
  const SweepSpec again = parse_sweep_file((dir / "g.ini").string(), {}, (dir / "other.db").string(), trace_generators());
  for (std::size_t i = 0; i < spec.generate.size(); ++i) EXPECT_EQ(again.generate[i].id, spec.generate[i].id);
  // Points: 2 configurations x 6 traces, labelled by the request.
  const auto points = expand_sweep(spec);
  ASSERT_EQ(points.size(), 12u);
  EXPECT_EQ(points[0].label, "isp.tag_buffers=1 | plain_forward lights=16");
  EXPECT_EQ(points[0].trace, generated_trace_path(spec, spec.generate[0]));
}

TEST(SweepGenerate, ErrorsNameFileAndLine) {
  const fs::path dir = scratch("errors");
  const std::string head = "[sweep]\nname = e\n[generate]\n";  // lines 1-3
  struct Case {
    std::string body;
    int line;
    std::string message;
  };
  const std::vector<Case> cases = {
      {head + "technique = plain_forwrd\n", 4, "unknown technique 'plain_forwrd'"},
      {head + "technique = plain_forward\nlight = 16\n", 5, "unknown key 'light' in [generate]"},
      {head + "technique = plain_forward\noption.pls_bytes = 16\n", 5, "no technique of this [generate] has the option 'pls_bytes'"},
      {head + "lights = 16\n", 3, "names no technique"},
      {head + "technique = plain_forward\nscene = missing.glb\n", 5, "not found"},
      {head + "technique = plain_forward\nlights = 16, 16\n", 5, "listed twice"},
      {head + "technique = plain_forward\nlights = 32..16\n", 5, "end is below the start"},
  };
  for (const auto& c : cases) {
    const fs::path p = dir / "s.ini";
    write_file(p, c.body);
    try {
      parse_sweep_file(p.string(), {}, {}, trace_generators());
      ADD_FAILURE() << "no error for:\n" << c.body;
    } catch (const InputError& e) {
      EXPECT_EQ(e.where(), p.string() + ":" + std::to_string(c.line)) << c.body << "\n" << e.what();
      EXPECT_NE(std::string(e.what()).find(c.message), std::string::npos) << e.what();
    }
  }
  // No trace line and no [generate]: nothing to replay.
  write_file(dir / "none.ini", "[sweep]\nname = n\n");
  EXPECT_THROW(parse_sweep_file((dir / "none.ini").string(), {}, {}, trace_generators()), InputError);
  // The reader alone (no generators given, as tests/fuzz builds it) knows no technique.
  write_file(dir / "alone.ini", head + "technique = plain_forward\n");
  EXPECT_THROW(parse_sweep_file((dir / "alone.ini").string()), InputError);
  // The tool version is part of each trace's hash: another version generates anew.
  write_file(dir / "v.ini", head + "technique = plain_forward\n");
  TraceGenerators other = trace_generators();
  other.version += "+1";
  EXPECT_NE(parse_sweep_file((dir / "v.ini").string(), {}, {}, trace_generators()).generate.at(0).id,
            parse_sweep_file((dir / "v.ini").string(), {}, {}, other).generate.at(0).id);
}

TEST(SweepGenerate, DryRunListsThePointsAndGeneratesNothing) {
  const fs::path dir = scratch("dry");
  const std::string db = (dir / "stack.db").string();
  const auto before = listing(dir);
  const auto r = run_cli({"sweep", "light_stack_bytes", "--db", db, "--dry-run"});
  ASSERT_EQ(r.code, 0) << r.err;
  // One configuration x 3 traces (pls_bytes = 16, 32, 64).
  EXPECT_NE(r.out.find("3 point(s) (1 configuration(s) x 3 trace(s)), 0 already in " + db + ", 3 to run"),
            std::string::npos) << r.out;
  EXPECT_NE(r.out.find("would generate 3 trace(s) into " + (dir / "stack.traces").string()), std::string::npos) << r.out;
  for (const char* v : {"pls_bytes=16", "pls_bytes=32", "pls_bytes=64"}) {
    EXPECT_NE(r.out.find(std::string("forward_light_stack ") + v), std::string::npos) << r.out;
  }
  EXPECT_EQ(listing(dir), before) << "a dry run writes no database and no trace";
}

TEST(SweepGenerate, RealSweepStoresTheOptionAsADimensionAndReusesItsTraces) {
  const fs::path dir = scratch("run");
  const std::string db = (dir / "stack.db").string();
  auto r = run_cli({"sweep", "light_stack_bytes", "--db", db, "-j", "2", "--tbdrsim", TBDRSIM_BINARY});
  ASSERT_EQ(r.code, 0) << r.out << r.err;
  EXPECT_NE(r.out.find("generate: 3 trace(s) into"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("3 ok, 0 failed"), std::string::npos) << r.out;
  EXPECT_EQ(listing(dir / "stack.traces").size(), 3u) << "three traces, no staging folder left";
  // One finished run per option value, the value read from the trace's technique line.
  EXPECT_EQ(scalar(db, "SELECT count(*) FROM runs WHERE status = 'ok'"), 3);
  for (const char* v : {"16", "32", "64"}) {
    EXPECT_EQ(scalar(db, std::string("SELECT count(*) FROM run_params WHERE key = 'technique.pls_bytes' AND value = '") +
                             v + "'"),
              1)
        << v;
  }
  // report groups by it: a header, a rule and one row per value.
  r = run_cli({"report", "--db", db, "--by", "technique.pls_bytes", "--metric", "frame_time_ms", "--format", "csv"});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("technique.pls_bytes"), std::string::npos) << r.out;
  for (const char* v : {"\n16,1,", "\n32,1,", "\n64,1,"}) EXPECT_NE(r.out.find(v), std::string::npos) << v << "\n" << r.out;
  // Run again: the traces are found by their hash, nothing is generated or run twice.
  r = run_cli({"sweep", "light_stack_bytes", "--db", db, "-j", "2", "--tbdrsim", TBDRSIM_BINARY});
  ASSERT_EQ(r.code, 0) << r.out << r.err;
  EXPECT_NE(r.out.find("generate: 3 trace(s) already in"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("3 already in"), std::string::npos) << r.out;
  EXPECT_EQ(scalar(db, "SELECT count(*) FROM runs"), 3);
}

TEST(SweepGenerate, BadOptionValueNamesItsLineAndWritesNothing) {
  const fs::path dir = scratch("bad");
  const fs::path file = dir / "bad.ini";
  // pls_bytes = 7: forward_light_stack takes 8..128 (a multiple of 4); the 16 B trace would generate
  // first, and must not be left behind.
  write_file(file, "[sweep]\nname = bad\n[generate]\ntechnique = forward_light_stack\nscene = atrium:1\n"
                   "resolution = 64x32\nlights = 8\noption.pls_bytes = 16, 7\n");
  const auto before = listing(dir);
  const auto r = run_cli({"sweep", file.string(), "--db", (dir / "b.db").string(), "--tbdrsim", TBDRSIM_BINARY});
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find(file.string() + ":8: generating the trace 'forward_light_stack pls_bytes=7'"), std::string::npos)
      << r.err;
  EXPECT_EQ(listing(dir), before) << "no database, no traces";
  // A malformed light count: Boost's message, at the line of the key.
  write_file(file, "[sweep]\nname = bad\n[generate]\ntechnique = plain_forward\nlights = many\n");
  const auto r2 = run_cli({"sweep", file.string(), "--db", (dir / "b.db").string(), "--tbdrsim", TBDRSIM_BINARY});
  EXPECT_EQ(r2.code, 2);
  EXPECT_NE(r2.err.find(file.string() + ":5:"), std::string::npos) << r2.err;
  EXPECT_NE(r2.err.find("'--lights'"), std::string::npos) << r2.err;
  EXPECT_EQ(listing(dir), before);
}

}  // namespace
}  // namespace tbdr
