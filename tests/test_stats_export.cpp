// `run --stats FILE` and `run --timeline FILE`: the files parse (nlohmann-json reads the JSON
// ones), carry units and descriptions, and hold exactly what the results database holds for the
// run; a bad output path is refused before the run (exit 2, nothing written).
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

#include "analysis/results_db.hpp"
#include "analysis/sql.hpp"
#include "app/cli.hpp"
#include "db_query.hpp"
#include "models/cache.hpp"
#include "models/dram.hpp"
#include "models/rop.hpp"
#include "scratch_dir.hpp"

namespace tbdr {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

testing_scratch::ScratchCleanup scratch_cleanup{"stats_export"};

std::string file_text(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

/// One tiny deferred run (two passes and a G-buffer) with a stats JSON, a stats text file and a
/// timeline, shared by the tests.
class StatsExport : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new fs::path(testing_scratch::scratch_dir("stats_export", "run"));
    db_ = new std::string((*dir_ / "s.db").string());
    const std::string trace = (*dir_ / "d.trace").string();
    std::ostringstream out, err;
    ASSERT_EQ(cli_main({"trace", "--technique", "deferred", "--resolution", "96x54", "--scene", "atrium:1", "--lights",
                        "8", "--out", trace},
                       out, err),
              0)
        << err.str();
    ASSERT_EQ(cli_main({"run", "--trace", trace, "--db", *db_, "--quiet", "--stats", (*dir_ / "s.json").string(),
                        "--timeline", (*dir_ / "t.json").string()},
                       out, err),
              0)
        << err.str();
    ASSERT_EQ(cli_main({"run", "--trace", trace, "--db", *db_, "--quiet", "--stats", (*dir_ / "stats.txt").string()},
                       out, err),
              0)
        << err.str();
  }
  static void TearDownTestSuite() {
    fs::remove_all(dir_->parent_path());
    delete dir_;
    delete db_;
  }
  static double db_number(const std::string& sql) { return testing_support::query_number(*db_, sql); }
  static fs::path* dir_;
  static std::string* db_;
};
fs::path* StatsExport::dir_ = nullptr;
std::string* StatsExport::db_ = nullptr;

TEST_F(StatsExport, JsonStatsMatchTheDatabaseWithUnitsAndDescriptions) {
  const json j = json::parse(file_text(*dir_ / "s.json"));  // throws (fails the test) unless valid JSON
  EXPECT_EQ(j.at("run").at("run_id").get<int>(), 1);
  EXPECT_EQ(j.at("run").at("technique").get<std::string>(), "deferred");
  EXPECT_EQ(j.at("parameters").at("tiling.tile_width").at("value").get<std::string>(), "32");
  const json& frame_time = j.at("stats").at("frame/timing").at("frame_time_ms");
  EXPECT_EQ(frame_time.at("unit").get<std::string>(), "ms");
  EXPECT_FALSE(frame_time.at("description").get<std::string>().empty());
  EXPECT_DOUBLE_EQ(frame_time.at("value").get<double>(),
                   db_number("SELECT value FROM stats WHERE run_id = 1 AND scope = 'frame/timing' AND name = 'frame_time_ms'"));
  // Every stored statistic is in the file, with its value.
  std::size_t in_file = 0;
  for (const auto& [scope, names] : j.at("stats").items()) {
    if (scope == "derived") continue;
    for (const auto& [name, fig] : names.items()) {
      ++in_file;
      SqlConnection c(*db_);
      SqlStatement q(c, "SELECT value FROM stats WHERE run_id = 1 AND scope = ? AND name = ?");
      q.bind(1, scope).bind(2, name);
      ASSERT_TRUE(q.step()) << scope << " " << name;
      EXPECT_DOUBLE_EQ(fig.at("value").get<double>(), q.real(0)) << scope << " " << name;
    }
  }
  EXPECT_EQ(static_cast<double>(in_file), db_number("SELECT count(*) FROM stats WHERE run_id = 1"));
  // The derived figures, as the views define them.
  const json& derived = j.at("stats").at("derived");
  for (const char* m : {"overshading", "shaded_fragments_per_pixel", "lights_per_pixel", "dram_total_mb", "energy_total_mj"}) {
    EXPECT_DOUBLE_EQ(derived.at(m).at("value").get<double>(),
                     db_number(std::string("SELECT value FROM v_metric WHERE run_id = 1 AND metric = '") + m + "'"))
        << m;
    EXPECT_FALSE(derived.at(m).at("unit").get<std::string>().empty()) << m;
    EXPECT_FALSE(derived.at(m).at("description").get<std::string>().empty()) << m;
  }
}

/// The description `S` declares for its statistic `name` (empty when it declares none).
template <class S>
std::string declared(const std::string& name) {
  for (const StatDef& d : stat_defs<S>()) {
    if (name == d.name) return d.description;
  }
  return {};
}

// A name that several units declare carries, in the file, the description its own unit declares:
// fill_bytes is the caches' and the ROP's, read_bytes the DRAM's as the units requested it
// (frame/dram) and as the devices served it (mem/dram). Before schema v5 each name had one
// description, the first unit's: the SLC's fill_bytes read "Bytes the ROP caches fetched".
TEST_F(StatsExport, EveryStatisticCarriesItsOwnUnitsDescription) {
  const json j = json::parse(file_text(*dir_ / "s.json"));
  auto description = [&](const char* scope, const char* name) {
    return j.at("stats").at(scope).at(name).at("description").get<std::string>();
  };
  const std::string cache_fills = declared<CacheStats>("fill_bytes"), rop_fills = declared<RopStats>("fill_bytes");
  ASSERT_FALSE(cache_fills.empty());
  ASSERT_NE(cache_fills, rop_fills);
  EXPECT_EQ(description("mem/cache.slc", "fill_bytes"), cache_fills);
  EXPECT_EQ(description("mem/cache.texture", "fill_bytes"), cache_fills);
  EXPECT_EQ(description("frame/rop", "fill_bytes"), rop_fills);
  EXPECT_EQ(description("pass0.gbuffer/rop", "fill_bytes"), rop_fills);
  EXPECT_EQ(description("mem/dram", "read_bytes"), declared<DramStats>("read_bytes"));
  EXPECT_NE(description("frame/dram", "read_bytes"), declared<DramStats>("read_bytes"));
}

TEST_F(StatsExport, TextStatsFollowGem5Layout) {
  const std::string text = file_text(*dir_ / "stats.txt");
  const auto begin = text.find("---------- Begin Simulation Statistics ----------\n");
  const auto end = text.find("---------- End Simulation Statistics   ----------\n");
  ASSERT_NE(begin, std::string::npos) << text.substr(0, 400);
  ASSERT_NE(end, std::string::npos);
  std::istringstream lines(text.substr(begin, end - begin));
  std::string line;
  std::getline(lines, line);  // the banner
  std::map<std::string, double> values;
  int rows = 0;
  while (std::getline(lines, line)) {
    std::istringstream f(line);
    std::string name, hash;
    double v = 0;
    ASSERT_TRUE(f >> name >> v >> hash) << line;
    EXPECT_EQ(hash, "#") << line;
    values[name] = v;
    ++rows;
  }
  // Run 2 wrote this file: its frame cycles, and a per-pass statistic with the scope's '/' as '.'.
  EXPECT_DOUBLE_EQ(values.at("frame.timing.frame_cycles"),
                   db_number("SELECT value FROM stats WHERE run_id = 2 AND scope = 'frame/timing' AND name = 'frame_cycles'"));
  EXPECT_NEAR(values.at("derived.shaded_fragments_per_pixel"),
              db_number("SELECT shaded_fragments_per_pixel FROM v_run_summary WHERE run_id = 2"), 1e-6);
  EXPECT_GE(rows, static_cast<int>(db_number("SELECT count(*) FROM stats WHERE run_id = 2")));
  EXPECT_NE(text.find("# Frame time (ms)"), std::string::npos);
}

TEST_F(StatsExport, TimelineIsTraceEventJsonOfThePasses) {
  const json j = json::parse(file_text(*dir_ / "t.json"));
  ASSERT_TRUE(j.at("traceEvents").is_array());
  const double cycles = db_number("SELECT cycles FROM v_run_summary WHERE run_id = 1");
  const double ms = db_number("SELECT frame_time_ms FROM v_run_summary WHERE run_id = 1");
  std::map<int, std::string> threads;  // tid -> name, process 1
  std::map<std::string, std::map<std::string, json>> slices;  // thread -> slice name -> event
  for (const auto& e : j.at("traceEvents")) {
    const std::string ph = e.at("ph").get<std::string>();
    ASSERT_TRUE(ph == "M" || ph == "X" || ph == "C") << e.dump();
    if (ph == "M" && e.at("name") == "thread_name" && e.at("pid") == 1) {
      threads[e.at("tid").get<int>()] = e.at("args").at("name").get<std::string>();
    }
  }
  for (const auto& e : j.at("traceEvents")) {
    if (e.at("ph") == "X" && e.at("pid") == 1) slices[threads.at(e.at("tid").get<int>())][e.at("name")] = e;
  }
  // The frame spans the frame time: ms x 1000 microseconds.
  EXPECT_DOUBLE_EQ(slices.at("frame").at("frame").at("dur").get<double>(), ms * 1000);
  // Each pass: binning, then its tiles, ending at the end cycle the database holds.
  int passes = 0;
  for (const auto& [thread, by_name] : slices) {
    if (thread.rfind("pass", 0) != 0) continue;
    ++passes;
    ASSERT_TRUE(by_name.count("tiles")) << thread;
    const json& tiles = by_name.at("tiles");
    SqlConnection c(*db_);
    SqlStatement q(c, "SELECT value FROM stats WHERE run_id = 1 AND scope = ? AND name = 'end_cycle'");
    q.bind(1, thread + "/timing");
    ASSERT_TRUE(q.step()) << thread;
    EXPECT_NEAR(tiles.at("ts").get<double>() + tiles.at("dur").get<double>(), q.real(0) * ms * 1000 / cycles, 1e-6)
        << thread;
    EXPECT_DOUBLE_EQ(tiles.at("args").at("end_cycle").get<double>(), q.real(0));
  }
  EXPECT_EQ(static_cast<double>(passes), db_number("SELECT passes FROM v_run_summary WHERE run_id = 1"));
  // The units: each with its busy cycles from the database.
  bool usc = false;
  for (const auto& e : j.at("traceEvents")) {
    if (e.at("ph") != "X" || e.at("pid") != 2 || !e.at("args").contains("busy_cycles")) continue;
    if (e.at("name").get<std::string>().rfind("usc ", 0) != 0) continue;
    usc = true;
    EXPECT_DOUBLE_EQ(e.at("args").at("busy_cycles").get<double>(),
                     db_number("SELECT busy_cycles FROM v_unit WHERE run_id = 1 AND unit = 'usc'"));
  }
  EXPECT_TRUE(usc) << "no usc unit track";
}

TEST_F(StatsExport, TimelineHasEveryUnitsBusyIntervalsInsideTheirPass) {
  const json j = json::parse(file_text(*dir_ / "t.json"));  // throws (fails the test) unless valid JSON
  const double cycles = db_number("SELECT cycles FROM v_run_summary WHERE run_id = 1");
  const double ms = db_number("SELECT frame_time_ms FROM v_run_summary WHERE run_id = 1");
  const double us_per_cycle = ms * 1000 / cycles;
  std::map<int, std::string> units;  // pid -> unit, from "unit NAME: busy intervals per pass"
  for (const auto& e : j.at("traceEvents")) {
    if (e.at("ph") != "M" || e.at("name") != "process_name") continue;
    const std::string name = e.at("args").at("name").get<std::string>();
    if (name.rfind("unit ", 0) == 0) units[e.at("pid").get<int>()] = name.substr(5, name.find(':') - 5);
  }
  // Every unit of the timing model has its process (its per-pass tracks).
  std::set<std::string> names;
  for (const auto& [pid, unit] : units) names.insert(unit);
  EXPECT_EQ(names, (std::set<std::string>{"binning", "tile_fetch", "isp", "usc", "texture", "tile_buffer", "pixel_back_end"}));
  std::map<std::string, double> unit_busy;                          // unit -> busy cycles, all passes
  std::map<std::pair<std::string, std::string>, double> pass_busy;  // (unit, pass) -> busy cycles
  for (const auto& e : j.at("traceEvents")) {
    if (e.at("ph") != "X" || !units.count(e.at("pid").get<int>())) continue;
    const std::string unit = units.at(e.at("pid").get<int>());
    const std::string pass = e.at("args").at("command").get<std::string>();
    const double from = e.at("args").at("start_cycle").get<double>(), to = e.at("args").at("end_cycle").get<double>();
    const double busy = e.at("args").at("busy_cycles").get<double>();
    SqlConnection c(*db_);
    SqlStatement q(c, "SELECT max(CASE WHEN name = 'start_cycle' THEN value END), "
                      "max(CASE WHEN name = 'end_cycle' THEN value END) FROM stats WHERE run_id = 1 AND scope = ?");
    q.bind(1, pass + "/timing");
    ASSERT_TRUE(q.step() && !q.is_null(0)) << pass;
    // Inside its pass (a reservation ends within the cycle its whole-cycle booking ends), up to
    // the clock's 1 ps rounding explained below (0.0006 cycles at 600 MHz).
    EXPECT_GE(from, q.real(0) - 0.01) << unit << " " << pass;
    EXPECT_LE(to, q.real(1) + 0.01) << unit << " " << pass;
    EXPECT_GT(busy, 0) << unit << " " << pass;
    // An interval holds at most its span of work, up to the clock's rounding: ticks are whole
    // picoseconds, so a reservation starting on a clock edge may begin up to 1 ps (0.0006 cycles
    // at 600 MHz) before the cycle count its predecessor's booking ends at; merged intervals add
    // those up over a handful of reservations.
    EXPECT_LE(busy, to - from + 0.01) << unit << " " << pass;
    EXPECT_NEAR(e.at("ts").get<double>(), from * us_per_cycle, 1e-9);
    unit_busy[unit] += busy;
    pass_busy[{unit, pass}] += busy;
  }
  for (const auto& [key, busy] : pass_busy) {
    const double start = db_number("SELECT value FROM stats WHERE run_id = 1 AND scope = '" + key.second + "/timing' AND name = 'start_cycle'");
    const double end = db_number("SELECT value FROM stats WHERE run_id = 1 AND scope = '" + key.second + "/timing' AND name = 'end_cycle'");
    EXPECT_LE(busy, end - start + 1e-6) << key.first << " " << key.second;
  }
  // The intervals split the database's busy cycles of each unit between the passes, losing none.
  for (const auto& unit : names) {
    EXPECT_NEAR(unit_busy[unit], db_number("SELECT busy_cycles FROM v_unit WHERE run_id = 1 AND unit = '" + unit + "'"), 1e-3)
        << unit;
  }
  // The DRAM: a track per channel over the frame, its slices' busy cycles adding up to the
  // channel's busy_ps in the database (ps -> cycles: x cycles / (ms x 1e9)).
  int dram_pid = -1;
  for (const auto& e : j.at("traceEvents")) {
    if (e.at("ph") == "M" && e.at("name") == "process_name" &&
        e.at("args").at("name").get<std::string>().rfind("dram:", 0) == 0) {
      dram_pid = e.at("pid").get<int>();
    }
  }
  ASSERT_GE(dram_pid, 0) << "no dram process";
  // The memory system's run ends after the frame's last tile when writes it does not wait for
  // (dirty lines evicted from the caches) are still draining: the DRAM's elapsed time, busy_ps /
  // utilization, bounds its intervals.
  const double dram_elapsed_ps = db_number(
      "SELECT max(b.value / u.value) FROM stats b JOIN stats u ON u.run_id = b.run_id AND u.scope = b.scope "
      "AND u.name = 'utilization' WHERE b.run_id = 1 AND b.scope GLOB 'mem/dram.ch*' AND b.name = 'busy_ps'");
  const double dram_elapsed_cycles = dram_elapsed_ps * cycles / (ms * 1e9);
  EXPECT_GE(dram_elapsed_cycles, cycles * 0.99);
  std::map<std::string, double> channel_busy;
  for (const auto& e : j.at("traceEvents")) {
    if (e.at("ph") != "X" || e.at("pid") != dram_pid) continue;
    const double from = e.at("args").at("start_cycle").get<double>(), to = e.at("args").at("end_cycle").get<double>();
    EXPECT_GE(from, -1e-6);
    EXPECT_LE(to, dram_elapsed_cycles + 1e-3);
    EXPECT_LE(e.at("args").at("busy_cycles").get<double>(), to - from + 1e-6);
    channel_busy[e.at("args").at("unit").get<std::string>()] += e.at("args").at("busy_cycles").get<double>();
  }
  const double channels = db_number("SELECT count(*) FROM stats WHERE run_id = 1 AND scope GLOB 'mem/dram.ch*' AND name = 'busy_ps'");
  EXPECT_EQ(static_cast<double>(channel_busy.size()), channels);
  for (const auto& [channel, busy] : channel_busy) {
    const double busy_ps = db_number("SELECT value FROM stats WHERE run_id = 1 AND scope = 'mem/" + channel + "' AND name = 'busy_ps'");
    EXPECT_NEAR(busy, busy_ps * cycles / (ms * 1e9), 1e-3) << channel;
  }
  // By hand: the lighting pass stores only the 96x54 RGBA8 colour target (the G-buffer was stored
  // by pass 0), 96 x 54 x 4 B = 20736 B, at writeback.bytes_per_clock = 32: 20736 / 32 = 648 cycles
  // of pixel back end. The G-buffer pass stores albedo rgba8 + normal rgb10a2 + 4 B depth = 12 B/px:
  // 3 x 648 = 1944 cycles.
  EXPECT_DOUBLE_EQ(pass_busy.at({"pixel_back_end", "pass1.lighting"}), 648.0);
  EXPECT_DOUBLE_EQ(pass_busy.at({"pixel_back_end", "pass0.gbuffer"}), 1944.0);
}

TEST_F(StatsExport, BadOutputPathIsRefusedBeforeTheRun) {
  const double runs = db_number("SELECT count(*) FROM runs");
  std::ostringstream out, err;
  EXPECT_EQ(cli_main({"run", "--trace", (*dir_ / "d.trace").string(), "--db", *db_, "--stats",
                      (*dir_ / "no_such_folder" / "s.json").string()},
                     out, err),
            2);
  EXPECT_NE(err.str().find("no_such_folder"), std::string::npos) << err.str();
  EXPECT_EQ(cli_main({"run", "--trace", (*dir_ / "d.trace").string(), "--db", *db_, "--timeline", dir_->string()}, out, err), 2);
  EXPECT_NE(err.str().find("is a folder"), std::string::npos) << err.str();
  EXPECT_EQ(db_number("SELECT count(*) FROM runs"), runs);  // no run written
}

}  // namespace
}  // namespace tbdr
