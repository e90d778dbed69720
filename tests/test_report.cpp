// The analysis views in every database and `tbdrsim report`: figures per run (NULL when a run did
// not record them), parameters for pivoting, sensitivity rows, grouping by technique or parameter
// with repetitions averaged, formats, errors, and the SQL of docs/queries.md on a real database.
#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <tuple>

#include "analysis/report.hpp"
#include "analysis/results_db.hpp"
#include "analysis/sql.hpp"
#include "app/cli.hpp"
#include "kernel/errors.hpp"
#include "db_query.hpp"
#include "scratch_dir.hpp"

namespace tbdr {
namespace {

namespace fs = std::filesystem;

testing_scratch::ScratchCleanup scratch_cleanup{"report"};
fs::path scratch(const std::string& name) { return testing_scratch::scratch_dir("report", name); }

/// A run as the simulator writes it, with made-up figures.
RunRecord synthetic_run(const std::string& technique, int tile_width, double shaded_samples, double lights,
                        bool timed, double frame_time_ms = 0) {
  RunRecord r;
  r.started_at = "2026-01-01T00:00:00Z";
  r.finished_at = r.started_at;
  r.tool_version = "test";
  r.host = "test";
  r.command_line = "test";
  r.config_name = "cfg";
  r.config_hash = "c" + std::to_string(tile_width);
  r.trace_path = technique + ".trace";
  r.trace_hash = "t" + technique + std::to_string(lights);
  r.scene = "atrium:1";
  r.technique = technique;
  r.params = {{"tiling.tile_width", std::to_string(tile_width), "--set tiling.tile_width=" + std::to_string(tile_width)},
              {"gpu.mode", "tbdr", "default"},
              {"usc.count", "4", "configs/cfg.ini:7"},  // the preset's own file: not in the label
              {"writeback.compression_ratio", "0.5", "default"}};
  auto st = [&](const std::string& scope, const std::string& name, double v, const std::string& unit) {
    r.stats.push_back({scope, name, v, unit, "test"});
  };
  st("frame/frame", "width", 100, "pixels");
  st("frame/frame", "height", 50, "pixels");
  st("frame/frame", "samples_per_pixel", 1, "samples");
  st("frame/frame", "lights", lights, "lights");
  st("frame/tsp", "shaded_samples", shaded_samples, "samples");
  st("frame/tsp", "shader_invocations", shaded_samples, "fragments");
  st("frame/tsp", "light_evaluations", shaded_samples * 4, "evaluations");
  st("frame/tsp", "lit_surface_invocations", shaded_samples / 2, "fragments");
  // overshading = hidden light evaluations / covered pixels (half the shaded samples' worth here)
  st("frame/tsp", "hidden_light_evaluations", shaded_samples / 2, "evaluations");
  st("frame/tsp", "hidden_lit_samples", shaded_samples / 8, "samples");
  st("frame/frame", "covered_pixels", 4000, "pixels");
  st("frame/dram", "read_bytes", 3e6, "bytes");
  st("frame/dram", "write_bytes", 1e6, "bytes");
  st("frame/dram.color", "read_bytes", 0, "bytes");
  st("frame/dram.color", "write_bytes", 1e6, "bytes");
  st("frame/dram.parameter_buffer", "read_bytes", 3e6, "bytes");
  st("frame/dram.parameter_buffer", "write_bytes", 0, "bytes");
  st("frame/dram.gbuffer", "read_bytes", 0, "bytes");
  st("frame/dram.gbuffer", "write_bytes", 0, "bytes");
  st("pass0.main/dram", "read_bytes", 3e6, "bytes");
  if (timed) {
    // What reached the DRAM devices: the system level cache caught half the parameter buffer reads.
    st("mem/dram", "read_bytes", 1.5e6, "bytes");
    st("mem/dram", "write_bytes", 1e6, "bytes");
    st("mem/dram.class.color", "read_bytes", 0, "bytes");
    st("mem/dram.class.color", "write_bytes", 1e6, "bytes");
    st("mem/dram.class.parameter_buffer", "read_bytes", 1.5e6, "bytes");
    st("mem/dram.class.parameter_buffer", "write_bytes", 0, "bytes");
    st("mem/dram.class.gbuffer", "read_bytes", 0, "bytes");
    st("mem/dram.class.gbuffer", "write_bytes", 0, "bytes");
    st("frame/timing", "frame_cycles", frame_time_ms * 6e5, "cycles");
    st("frame/timing", "frame_time_ms", frame_time_ms, "ms");
    st("frame/energy", "dram_pj", 2e9, "pJ");
    st("frame/energy", "alu_pj", 1e9, "pJ");
    st("frame/energy", "total_pj", 3e9, "pJ");
    st("frame/energy", "total_mj", 3, "mJ");
  }
  return r;
}

double real_of(const ResultsDb& db, const std::string& sql) { return testing_support::query_number(db, sql); }

std::string text_of_query(const ResultsDb& db, const std::string& sql) {
  SqlStatement q(db.sql(), sql);
  return q.step() ? q.text(0) : std::string("(no row)");
}

bool is_null(const ResultsDb& db, const std::string& sql) {
  SqlStatement q(db.sql(), sql);
  return q.step() && q.is_null(0);
}

std::string report_text(const ResultsDb& db, const ReportOptions& opt, ReportFormat f = ReportFormat::Table) {
  std::ostringstream out;
  print_report(build_report(db, opt), f, opt.transpose, out);
  return out.str();
}

std::vector<std::string> lines_of(const std::string& s) {
  std::vector<std::string> v;
  std::istringstream in(s);
  std::string l;
  while (std::getline(in, l)) v.push_back(l);
  return v;
}

// ---------------------------------------------------------------------------------------------

TEST(ReportViews, EveryDatabaseHasCurrentViews) {
  const std::string path = (scratch("views") / "v.db").string();
  std::int64_t cookie = 0;
  {
    ResultsDb db(path);
    for (const char* v : {"v_run_summary", "v_param", "v_metric", "v_sensitivity", "v_technique_comparison",
                          "v_dram_class", "v_energy_component", "v_views_version"}) {
      SqlStatement q(db.sql(), "SELECT count(*) FROM sqlite_master WHERE type = 'view' AND name = ?");
      q.bind(1, std::string(v));
      ASSERT_TRUE(q.step());
      EXPECT_EQ(q.int64(0), 1) << v;
    }
    SqlStatement c(db.sql(), "PRAGMA schema_version");
    c.step();
    cookie = c.int64(0);
  }
  {  // Reopening writes nothing when the views are current.
    ResultsDb db(path);
    SqlStatement c(db.sql(), "PRAGMA schema_version");
    c.step();
    EXPECT_EQ(c.int64(0), cookie);
    db.sql().exec("DROP VIEW v_sensitivity; DROP VIEW v_views_version; CREATE VIEW v_views_version AS SELECT 'old' AS sql_hash");
  }
  {  // Stale views are re-created.
    ResultsDb db(path);
    SqlStatement q(db.sql(), "SELECT sql_hash FROM v_views_version");
    ASSERT_TRUE(q.step());
    EXPECT_EQ(q.text(0), views_sql_hash());
    EXPECT_NO_THROW(SqlStatement(db.sql(), "SELECT * FROM v_sensitivity").step());
  }
  {  // Databases at an older schema version get them too (they only use version-1 tables).
    const std::string old = (scratch("views_v1") / "v1.db").string();
    ResultsDb db(old, 1);
    EXPECT_NO_THROW(SqlStatement(db.sql(), "SELECT * FROM v_technique_comparison").step());
  }
}

TEST(ReportViews, SqlFileIsTheOneEmbeddedCopy) {
  std::ifstream in(std::string(TBDRSIM_SOURCE_DIR) + "/analysis/views.sql");
  ASSERT_TRUE(in);
  std::stringstream ss;
  ss << in.rdbuf();
  const std::string file = ss.str();
  EXPECT_EQ(file, "-- R\"tbdr_views(" + std::string(views_sql()) + ")tbdr_views\"_tbdr_sql\n");
  // And the file runs as plain SQL in a fresh SQLite database with the tables.
  const std::string path = (scratch("plain") / "p.db").string();
  { ResultsDb db(path); }
  EXPECT_NO_THROW(SqlConnection(path).exec(file));
}

TEST(ReportViews, SummaryFiguresAreNullWhenARunDidNotRecordThem) {
  const std::string path = (scratch("summary") / "s.db").string();
  ResultsDb db(path);
  const auto untimed = db.write_run(synthetic_run("plain_forward", 16, 7500, 64, false));
  const auto timed = db.write_run(synthetic_run("deferred", 32, 5000, 64, true, 12.5));
  const std::string u = " FROM v_run_summary WHERE run_id = " + std::to_string(untimed);
  const std::string t = " FROM v_run_summary WHERE run_id = " + std::to_string(timed);
  EXPECT_DOUBLE_EQ(real_of(db, "SELECT shaded_fragments_per_pixel" + u), 1.5);  // 7500 / (100 x 50)
  // 3750 hidden light evaluations / 4000 covered pixels
  EXPECT_DOUBLE_EQ(real_of(db, "SELECT overshading" + u), 0.9375);
  EXPECT_DOUBLE_EQ(real_of(db, "SELECT lights_per_pixel" + u), 6.0);  // 30000 evaluations / 5000 pixels
  EXPECT_DOUBLE_EQ(real_of(db, "SELECT value FROM v_metric WHERE metric = 'overshading' AND run_id = " +
                                   std::to_string(untimed)),
                   0.9375);
  // Requested at the chip boundary: 3 MB read + 1 MB written; no memory system model ran, so the
  // DRAM device figures are NULL, not the requested bytes.
  EXPECT_DOUBLE_EQ(real_of(db, "SELECT requested_total_mb" + u), 4.0);
  EXPECT_DOUBLE_EQ(real_of(db, "SELECT requested_color_write_mb" + u), 1.0);
  EXPECT_DOUBLE_EQ(real_of(db, "SELECT requested_parameter_buffer_read_mb" + u), 3.0);
  EXPECT_TRUE(is_null(db, "SELECT dram_total_mb" + u));
  EXPECT_TRUE(is_null(db, "SELECT dram_color_write_mb" + u));
  // The timed run: 1.5 MB read + 1 MB written reached the devices (half the parameter buffer reads
  // hit the SLC), against the same 4 MB requested.
  EXPECT_DOUBLE_EQ(real_of(db, "SELECT dram_total_mb" + t), 2.5);
  EXPECT_DOUBLE_EQ(real_of(db, "SELECT requested_total_mb" + t), 4.0);
  EXPECT_DOUBLE_EQ(real_of(db, "SELECT dram_parameter_buffer_read_mb" + t), 1.5);
  EXPECT_DOUBLE_EQ(real_of(db, "SELECT dram_color_write_mb" + t), 1.0);
  EXPECT_DOUBLE_EQ(real_of(db, "SELECT value FROM v_metric WHERE metric = 'dram_parameter_buffer_mb' AND run_id = " +
                                   std::to_string(timed)),
                   1.5);
  EXPECT_DOUBLE_EQ(real_of(db, "SELECT value FROM v_metric WHERE metric = 'requested_parameter_buffer_mb' AND run_id = " +
                                   std::to_string(timed)),
                   3.0);
  EXPECT_TRUE(is_null(db, "SELECT frame_time_ms" + u));
  EXPECT_TRUE(is_null(db, "SELECT cycles" + u));
  EXPECT_TRUE(is_null(db, "SELECT energy_total_mj" + u));
  EXPECT_TRUE(is_null(db, "SELECT dram_textures_read_mb" + u));  // class not recorded
  EXPECT_DOUBLE_EQ(real_of(db, "SELECT frame_time_ms" + t), 12.5);
  EXPECT_DOUBLE_EQ(real_of(db, "SELECT cycles" + t), 12.5 * 6e5);
  EXPECT_DOUBLE_EQ(real_of(db, "SELECT energy_total_mj" + t), 3.0);
  EXPECT_NEAR(real_of(db, "SELECT energy_dram_mj" + t), 2.0, 1e-12);
  EXPECT_EQ(real_of(db, "SELECT count(*) FROM v_run_summary"), 2);
  // Long forms: classes and energy components.
  EXPECT_DOUBLE_EQ(real_of(db, "SELECT requested_total_mb FROM v_dram_class WHERE class = 'color' AND run_id = " +
                                   std::to_string(untimed)),
                   1.0);
  EXPECT_TRUE(is_null(db, "SELECT total_mb FROM v_dram_class WHERE class = 'color' AND run_id = " +
                              std::to_string(untimed)));
  EXPECT_DOUBLE_EQ(real_of(db, "SELECT total_mb FROM v_dram_class WHERE class = 'parameter_buffer' AND run_id = " +
                                   std::to_string(timed)),
                   1.5);
  EXPECT_NEAR(real_of(db, "SELECT energy_mj FROM v_energy_component WHERE component = 'alu'"), 1.0, 1e-12);
  EXPECT_NEAR(real_of(db, "SELECT value FROM v_metric WHERE metric = 'energy_alu_mj'"), 1.0, 1e-12);
  EXPECT_DOUBLE_EQ(real_of(db, "SELECT value FROM v_metric WHERE metric = 'tsp.shaded_samples' AND run_id = " +
                                   std::to_string(untimed)),
                   7500);
  EXPECT_DOUBLE_EQ(real_of(db, "SELECT value FROM v_metric WHERE metric = 'requested_color_mb' AND run_id = " +
                                   std::to_string(untimed)),
                   1.0);
  // Technique comparison ranks the timed run first on time (untimed ones sort last).
  EXPECT_EQ(real_of(db, "SELECT count(*) FROM v_technique_comparison"), 2);
  EXPECT_EQ(real_of(db, "SELECT rank_dram FROM v_technique_comparison WHERE technique = 'deferred'"), 1);
}

TEST(ReportViews, ParametersPivotAndSensitivity) {
  const std::string path = (scratch("params") / "p.db").string();
  ResultsDb db(path);
  db.write_run(synthetic_run("a", 16, 5000, 64, false));
  db.write_run(synthetic_run("a", 32, 6000, 64, false));
  RunRecord failed = synthetic_run("a", 64, 9000, 64, false);
  failed.status = "failed";
  failed.error = "boom";
  failed.stats.clear();
  db.write_run(failed);
  EXPECT_TRUE(is_null(db, "SELECT value_num FROM v_param WHERE key = 'gpu.mode' LIMIT 1"));
  // The failed run (3) has its parameters and a summary row, but no figures and no sensitivity rows.
  testing_support::expect_numbers(
      db, {{"SELECT value_num FROM v_param WHERE key = 'tiling.tile_width' AND run_id = 2", 32},
           {"SELECT value_num FROM v_param WHERE key = 'writeback.compression_ratio' LIMIT 1", 0.5},
           {"SELECT value_num FROM v_param WHERE key = 'trace.lights' LIMIT 1", 64},
           {"SELECT count(*) FROM v_param WHERE key = 'trace.technique'", 3},
           {"SELECT count(*) FROM v_sensitivity WHERE key = 'tiling.tile_width' AND metric = 'overshading'", 2},
           {"SELECT metric_value FROM v_sensitivity WHERE key = 'tiling.tile_width' AND value = '32' "
            "AND metric = 'shaded_fragments_per_pixel'",
            1.2},  // 6000 / (100 x 50)
           {"SELECT metric_value FROM v_sensitivity WHERE key = 'tiling.tile_width' AND value = '32' "
            "AND metric = 'overshading'",
            0.75},  // 3000 hidden light evaluations / 4000 covered pixels
           {"SELECT count(*) FROM v_run_summary WHERE status = 'failed' AND error = 'boom'", 1},
           {"SELECT count(*) FROM v_sensitivity WHERE run_id = 3", 0}});
}

TEST(Report, GroupsByTechniqueAveragingRepetitions) {
  const std::string path = (scratch("tech") / "t.db").string();
  ResultsDb db(path);
  db.write_run(synthetic_run("clustered_forward", 16, 5000, 64, true, 10));
  db.write_run(synthetic_run("clustered_forward", 16, 5000, 64, true, 20));  // a repetition
  db.write_run(synthetic_run("deferred", 16, 6000, 64, true, 5));
  RunRecord failed = synthetic_run("deferred", 16, 1, 64, false);
  failed.status = "failed";
  failed.stats.clear();
  db.write_run(failed);
  const ReportTable t = build_report(db, {});
  ASSERT_EQ(t.rows.size(), 2u);
  EXPECT_EQ(t.group_keys, std::vector<std::string>{"technique"});
  EXPECT_EQ(t.rows[0].keys[0], "clustered_forward");
  EXPECT_EQ(t.rows[0].runs, 2);
  EXPECT_EQ(t.runs_used, 3);
  EXPECT_EQ(t.runs_failed, 1);
  ASSERT_EQ(t.metrics[0], "frame_time_ms");
  EXPECT_DOUBLE_EQ(*t.rows[0].values[0], 15.0);
  EXPECT_DOUBLE_EQ(*t.rows[1].values[0], 5.0);
  // Default metrics: only what some run has (no gbuffer traffic, no texture class at all).
  auto has = [&](const std::string& m) { return std::find(t.metrics.begin(), t.metrics.end(), m) != t.metrics.end(); };
  for (const char* m : {"cycles", "dram_total_mb", "dram_color_mb", "dram_parameter_buffer_mb", "energy_total_mj",
                        "energy_dram_mj", "energy_alu_mj", "overshading", "shaded_fragments_per_pixel",
                        "lights_per_pixel"}) {
    EXPECT_TRUE(has(m)) << m;
  }
  EXPECT_FALSE(has("dram_gbuffer_mb"));
  EXPECT_FALSE(has("dram_textures_mb"));

  const std::string text = report_text(db, {});
  EXPECT_NE(text.find("clustered_forward"), std::string::npos);
  EXPECT_NE(text.find("deferred"), std::string::npos);
  EXPECT_NE(text.find("1 failed run(s) left out"), std::string::npos) << text;
  // Three titled tables (frame figures, DRAM per class, energy per component), each aligned: every
  // line of a table is equally long (labels left-aligned, numbers right-aligned).
  EXPECT_NE(text.find("\nper run (a sequence: the sum of its frames"), std::string::npos) << text;
  EXPECT_NE(text.find("\nDRAM MB per traffic class"), std::string::npos) << text;
  EXPECT_NE(text.find("\nenergy mJ per component\n"), std::string::npos) << text;
  const auto lines = lines_of(text);
  int tables = 0;
  for (std::size_t i = 1; i + 1 < lines.size(); ++i) {
    if (!lines[i].empty()) continue;
    ++tables;
    const std::size_t head = i + 2;  // blank, title, header, rule, rows
    ASSERT_LT(head + 2, lines.size()) << text;
    EXPECT_EQ(lines[head + 1].find_first_not_of("- "), std::string::npos) << text;
    for (std::size_t j = head; j < lines.size() && !lines[j].empty(); ++j) {
      EXPECT_EQ(lines[j].size(), lines[head].size()) << text;
    }
  }
  EXPECT_EQ(tables, 3) << text;
  // The DRAM table names the classes briefly and ends with the total.
  EXPECT_NE(text.find("parameter_buffer"), std::string::npos);
  EXPECT_NE(text.find("  total"), std::string::npos);
}

TEST(Report, RanksRowsWithinTheGroupsOfAllButTheLastKeyAndKeepsTheBest) {
  const std::string path = (scratch("rank") / "r.db").string();
  ResultsDb db(path);
  // shaded samples (the ranked figure) per technique and tile width:
  //   tile 16: a 5016, b 6016, c 4016   -> c 1, a 2, b 3
  //   tile 32: a 5032, b 6032, c 6032   -> a 1, b and c share 2
  for (int w : {16, 32}) {
    db.write_run(synthetic_run("a", w, 5000 + w, 64, false));
    db.write_run(synthetic_run("b", w, 6000 + w, 64, false));
    db.write_run(synthetic_run("c", w, (w == 16 ? 4000 : 6000) + w, 64, false));
  }
  ReportOptions opt;
  opt.by = {"tiling.tile_width", "technique"};
  opt.metrics = {"overshading"};
  opt.rank = "tsp.shaded_samples";
  ReportTable t = build_report(db, opt);
  ASSERT_EQ(t.rows.size(), 6u);
  ASSERT_EQ(t.metrics.back(), "tsp.shaded_samples");  // added to the metrics
  const std::vector<std::vector<std::string>> keys = {{"16", "c"}, {"16", "a"}, {"16", "b"},
                                                      {"32", "a"}, {"32", "b"}, {"32", "c"}};
  const std::vector<int> ranks = {1, 2, 3, 1, 2, 2};
  for (std::size_t i = 0; i < keys.size(); ++i) {
    EXPECT_EQ(t.rows[i].keys, keys[i]) << i;
    EXPECT_EQ(t.ranks[i], ranks[i]) << i;
  }
  opt.best = true;
  t = build_report(db, opt);
  ASSERT_EQ(t.rows.size(), 2u);
  EXPECT_EQ(t.rows[0].keys, (std::vector<std::string>{"16", "c"}));
  EXPECT_EQ(t.rows[1].keys, (std::vector<std::string>{"32", "a"}));
  opt.rank = "tsp.shaded_samples:max";  // largest first: tile 32's b and c share rank 1
  t = build_report(db, opt);
  ASSERT_EQ(t.rows.size(), 3u);
  EXPECT_EQ(t.rows[0].keys, (std::vector<std::string>{"16", "b"}));
  EXPECT_EQ(t.rows[1].keys[0], "32");
  EXPECT_EQ(t.rows[2].keys[0], "32");
  std::ostringstream out, err;
  EXPECT_EQ(cli_main({"report", "--db", path, "--rank", "tsp.shaded_sample"}, out, err), 2);
  EXPECT_NE(err.str().find("did you mean 'tsp.shaded_samples'"), std::string::npos) << err.str();
  EXPECT_EQ(cli_main({"report", "--db", path, "--best"}, out, err), 2);
  EXPECT_EQ(cli_main({"report", "--db", path, "--rank", "overshading:best"}, out, err), 2);
  std::ostringstream text;
  ASSERT_EQ(cli_main({"report", "--db", path, "--by", "tiling.tile_width,technique", "--rank", "tsp.shaded_samples",
                      "--best", "--format", "csv"},
                     text, err),
            0)
      << err.str();
  // The default figures, with the ranked one added after them.
  const std::string head = lines_of(text.str())[0];
  EXPECT_EQ(head.rfind("tiling.tile_width,technique,runs,rank,", 0), 0u) << head;
  EXPECT_EQ(head.substr(head.size() - 19), ",tsp.shaded_samples") << head;
  EXPECT_EQ(lines_of(text.str()).size(), 3u);
}

TEST(Report, GroupsByParameterKeysWithFilterAndFormats) {
  const std::string path = (scratch("param") / "p.db").string();
  ResultsDb db(path);
  for (int w : {128, 16, 32}) {
    db.write_run(synthetic_run("a", w, 5000 + w, 64, false));
    db.write_run(synthetic_run("b", w, 6000 + w, 256, false));
  }
  ReportOptions by_tile;
  by_tile.by = {"tiling.tile_width"};
  by_tile.metrics = {"overshading", "tsp.shaded_samples", "requested_color_mb"};
  ReportTable t = build_report(db, by_tile);
  ASSERT_EQ(t.rows.size(), 3u);
  EXPECT_EQ(t.rows[0].keys[0], "16");  // numeric order
  EXPECT_EQ(t.rows[2].keys[0], "128");
  EXPECT_EQ(t.rows[0].runs, 2);
  EXPECT_DOUBLE_EQ(*t.rows[0].values[1], (5016.0 + 6016.0) / 2);
  EXPECT_EQ(t.units[1], "samples");

  ReportOptions two = by_tile;
  two.by = {"technique", "tiling.tile_width"};
  two.where = "lights = 256";
  t = build_report(db, two);
  ASSERT_EQ(t.rows.size(), 3u);
  EXPECT_EQ(t.rows[0].keys, (std::vector<std::string>{"b", "16"}));
  EXPECT_EQ(t.runs_used, 3);

  ReportOptions lights;
  lights.by = {"lights"};
  lights.metrics = {"lights_per_pixel"};
  EXPECT_EQ(build_report(db, lights).rows.size(), 2u);

  const std::string csv = report_text(db, by_tile, ReportFormat::Csv);
  EXPECT_EQ(lines_of(csv)[0], "tiling.tile_width,runs,overshading,tsp.shaded_samples,requested_color_mb");
  EXPECT_EQ(lines_of(csv).size(), 4u);
  const std::string md = report_text(db, by_tile, ReportFormat::Markdown);
  const auto ml = lines_of(md);
  EXPECT_NE(md.find("note: 3 group(s) average runs of different"), std::string::npos) << md;
  std::size_t first = 0;
  while (first < ml.size() && ml[first].rfind("|", 0) != 0) ++first;
  ASSERT_EQ(ml.size(), first + 5) << md;
  EXPECT_EQ(ml[first].rfind("| tiling.tile_width", 0), 0u) << md;
  EXPECT_NE(ml[first + 1].find("---:"), std::string::npos) << md;
  EXPECT_EQ(ml[first + 4].rfind("| 128 ", 0), 0u) << md;
  ReportOptions tr = by_tile;
  tr.transpose = true;
  const std::string tt = report_text(db, tr);
  EXPECT_NE(tt.find("metric \\ tiling.tile_width"), std::string::npos) << tt;
  EXPECT_NE(tt.find("overshading"), std::string::npos);

  ReportOptions bad;
  bad.metrics = {"frame_time_furlongs"};
  EXPECT_THROW(build_report(db, bad), InputError);
  bad.metrics.clear();
  bad.by = {"tiling.tile_widht"};
  EXPECT_THROW(build_report(db, bad), InputError);
  bad.by.clear();
  bad.where = "no_such_column = 1";
  try {
    build_report(db, bad);
    ADD_FAILURE();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("no_such_column"), std::string::npos);
  }
  bad.where = "1; DROP TABLE runs";
  EXPECT_THROW(build_report(db, bad), InputError);
  EXPECT_THROW(parse_report_format("xml"), InputError);
}

TEST(Report, BaselineGivesDifferencesAndRatiosPerGroup) {
  const std::string path = (scratch("baseline") / "b.db").string();
  ResultsDb db(path);
  // technique, tile width, frame time
  const std::vector<std::tuple<std::string, int, double>> runs = {
      {"a", 16, 10}, {"a", 32, 15}, {"b", 16, 4}, {"b", 32, 2}, {"b", 64, 3}};
  for (const auto& [tech, w, ms] : runs) db.write_run(synthetic_run(tech, w, 5000, 64, true, ms));
  ReportOptions opt;
  opt.metrics = {"frame_time_ms"};
  opt.baseline = "tiling.tile_width=16";  // not a --by key: added as the last group key
  const ReportTable t = build_report(db, opt);
  EXPECT_EQ(t.group_keys, (std::vector<std::string>{"technique", "tiling.tile_width"}));
  ASSERT_EQ(t.rows.size(), 5u);
  const std::string csv = report_text(db, opt, ReportFormat::Csv);
  const auto lines = lines_of(csv);
  ASSERT_EQ(lines.size(), 6u) << csv;
  EXPECT_EQ(lines[0], "technique,tiling.tile_width,runs,frame_time_ms,frame_time_ms_delta,frame_time_ms_ratio");
  EXPECT_EQ(lines[1], "a,16,1,10,0,1");      // the baseline itself
  EXPECT_EQ(lines[2], "a,32,1,15,5,1.5");    // 15 - 10, 15 / 10
  EXPECT_EQ(lines[3], "b,16,1,4,0,1");
  EXPECT_EQ(lines[4], "b,32,1,2,-2,0.5");    // 2 - 4, 2 / 4: halving the time is a ratio of 0.5
  EXPECT_EQ(lines[5], "b,64,1,3,-1,0.75");   // 3 - 4, 3 / 4
  const std::string text = report_text(db, opt);
  EXPECT_NE(text.find("baseline: tiling.tile_width = 16"), std::string::npos) << text;
  EXPECT_NE(text.find("frame_time_ms /base"), std::string::npos) << text;
  EXPECT_NE(text.find("1.500"), std::string::npos) << text;
  EXPECT_NE(text.find("+5"), std::string::npos) << text;

  // A technique as the baseline, written as a number the database spells differently.
  ReportOptions by_tech;
  by_tech.by = {"tiling.tile_width", "technique"};
  by_tech.metrics = {"frame_time_ms"};
  by_tech.baseline = "technique=b";
  const auto tl = lines_of(report_text(db, by_tech, ReportFormat::Csv));
  ASSERT_EQ(tl.size(), 6u);
  EXPECT_EQ(tl[1], "16,a,1,10,6,2.5");  // a against b at 16: 10 - 4, 10 / 4
  EXPECT_EQ(tl[3], "32,a,1,15,13,7.5");  // 15 - 2, 15 / 2
  ReportOptions spelled = opt;
  spelled.baseline = "tiling.tile_width=16.0";
  EXPECT_EQ(report_text(db, spelled, ReportFormat::Csv), csv);

  // No group without its baseline is compared with something else: a group whose baseline is
  // absent (a at 64 would be) shows nothing.
  db.write_run(synthetic_run("c", 32, 5000, 64, true, 7));
  const auto cl = lines_of(report_text(db, opt, ReportFormat::Csv));
  ASSERT_EQ(cl.size(), 7u);
  EXPECT_EQ(cl[6], "c,32,1,7,,");
  EXPECT_NE(report_text(db, opt).find("1 group(s) have no baseline group"), std::string::npos);

  ReportOptions bad = opt;
  bad.baseline = "tiling.tile_width=48";
  try {
    build_report(db, bad);
    ADD_FAILURE();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("--baseline tiling.tile_width=48"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("16, 32, 64"), std::string::npos) << e.what();
  }
  bad.baseline = "tiling.tile_width";
  EXPECT_THROW(build_report(db, bad), InputError);
}

TEST(Report, WhereAndByNameParameterKeysAndConfigLabels) {
  const std::string path = (scratch("where") / "w.db").string();
  ResultsDb db(path);
  for (int w : {16, 32}) {
    db.write_run(synthetic_run("a", w, 5000, 64, true, 1));
    db.write_run(synthetic_run("b", w, 5000, 256, true, 2));
  }
  ReportOptions opt;
  opt.metrics = {"frame_time_ms"};
  opt.where = "tiling.tile_width = 32 AND gpu.mode = 'tbdr'";  // dotted keys as columns
  EXPECT_EQ(build_report(db, opt).runs_used, 2);
  opt.where = "\"tiling.tile_width\" >= 32 AND lights = 256";  // already quoted, with a summary column
  EXPECT_EQ(build_report(db, opt).runs_used, 1);
  opt.where = "technique <> 'tiling.tile_width'";  // text in a string literal stays text
  EXPECT_EQ(build_report(db, opt).runs_used, 4);
  // The configuration is labelled by what was set on top of its preset ('cfg'): the --set tile
  // width, not the defaults and not the preset file's own usc.count.
  EXPECT_EQ(text_of_query(db, "SELECT config_label FROM v_run_summary WHERE run_id = 1"), "cfg tiling.tile_width=16");
  ReportOptions by_config;
  by_config.by = {"config"};
  by_config.metrics = {"frame_time_ms"};
  const ReportTable t = build_report(db, by_config);
  ASSERT_EQ(t.rows.size(), 2u);
  EXPECT_EQ(t.rows[0].keys[0], "cfg tiling.tile_width=16");
  EXPECT_EQ(t.rows[1].keys[0], "cfg tiling.tile_width=32");
  EXPECT_EQ(t.mixed_groups, 2);  // techniques a and b share each configuration
}

/// A real database: one tiny trace replayed on two configurations through the command line.
class ReportReal : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new fs::path(scratch("real"));
    db_ = new std::string((*dir_ / "real.db").string());
    const std::string trace = (*dir_ / "pf.trace").string();
    std::ostringstream out, err;
    ASSERT_EQ(cli_main({"trace", "--resolution", "160x90", "--scene", "atrium:1", "--lights", "16", "--out", trace}, out, err),
              0)
        << err.str();
    for (const char* set : {"tiling.tile_width=16", "tiling.tile_width=32"}) {
      ASSERT_EQ(cli_main({"run", "--trace", trace, "--db", *db_, "--set", set, "--quiet"}, out, err), 0) << err.str();
    }
  }
  static void TearDownTestSuite() {
    fs::remove_all(dir_->parent_path());
    delete dir_;
    delete db_;
  }
  static fs::path* dir_;
  static std::string* db_;
};
fs::path* ReportReal::dir_ = nullptr;
std::string* ReportReal::db_ = nullptr;

TEST_F(ReportReal, CommandPrintsGroups) {
  std::ostringstream out, err;
  ASSERT_EQ(cli_main({"report", "--db", *db_}, out, err), 0) << err.str();
  EXPECT_NE(out.str().find("plain_forward"), std::string::npos) << out.str();
  EXPECT_NE(out.str().find("dram_total_mb"), std::string::npos) << out.str();
  std::ostringstream o2;
  ASSERT_EQ(cli_main({"report", "--db", *db_, "--by", "tiling.tile_width", "--metric", "overshading", "--metric",
                      "dram_parameter_buffer_mb", "--format", "csv"},
                     o2, err),
            0)
      << err.str();
  const auto lines = lines_of(o2.str());
  ASSERT_EQ(lines.size(), 3u) << o2.str();
  EXPECT_EQ(lines[1].rfind("16,1,", 0), 0u) << o2.str();
  EXPECT_EQ(lines[2].rfind("32,1,", 0), 0u) << o2.str();
  std::ostringstream o3, e3;
  EXPECT_EQ(cli_main({"report", "--db", (*dir_ / "absent.db").string()}, o3, e3), 2);
  EXPECT_FALSE(fs::exists(*dir_ / "absent.db"));
  EXPECT_EQ(cli_main({"report", "--db", *db_, "--metric", "nope"}, o3, e3), 2);
  EXPECT_NE(e3.str().find("--metric nope"), std::string::npos) << e3.str();
}

TEST_F(ReportReal, EveryQueryInDocsRuns) {
  std::ifstream in(std::string(TBDRSIM_SOURCE_DIR) + "/docs/queries.md");
  ASSERT_TRUE(in);
  std::vector<std::string> queries;
  std::string line, cur;
  bool inside = false;
  while (std::getline(in, line)) {
    if (!inside && line.rfind("```sql", 0) == 0) {
      inside = true;
      cur.clear();
    } else if (inside && line.rfind("```", 0) == 0) {
      inside = false;
      queries.push_back(cur);
    } else if (inside) {
      cur += line + "\n";
    }
  }
  ASSERT_GE(queries.size(), 8u);
  ResultsDb db(*db_);
  int with_rows = 0;
  for (const auto& q : queries) {
    try {
      SqlStatement s(db.sql(), q);
      if (s.step()) ++with_rows;
    } catch (const SqlError& e) {
      ADD_FAILURE() << q << "\n" << e.what();
    }
  }
  EXPECT_GE(with_rows, static_cast<int>(queries.size()) / 2) << "most documented queries should answer on a real run";
}

// The trace's technique options are dimensions: forward_multipass with 4 and with 8 lights per
// additive pass, 16 lights: grouped by the option, filtered on it, and its effect on passes.
TEST(ReportRealOptions, TechniqueOptionIsADimension) {
  const fs::path dir = scratch("options");
  const std::string db_path = (dir / "o.db").string();
  for (const char* per_pass : {"4", "8"}) {
    const std::string trace = (dir / (std::string("fm") + per_pass + ".trace")).string();
    std::ostringstream out, err;
    ASSERT_EQ(cli_main({"trace", "--technique", "forward_multipass", "--resolution", "64x36", "--scene", "atrium:1",
                        "--lights", "16", "--option", std::string("lights_per_pass=") + per_pass, "--out", trace},
                       out, err),
              0)
        << err.str();
    ASSERT_EQ(cli_main({"run", "--trace", trace, "--db", db_path, "--quiet"}, out, err), 0) << err.str();
  }
  ResultsDb db(db_path);
  testing_support::expect_numbers(
      db, {{"SELECT count(*) FROM v_param WHERE key = 'technique.lights_per_pass'", 2},
           {"SELECT sum(value_num) FROM v_param WHERE key = 'technique.lights_per_pass'", 12},  // 4 + 8
           {"SELECT count(*) FROM run_params WHERE key = 'technique.lights_per_pass' AND origin GLOB 'trace *.trace:2'", 2},
           {"SELECT count(*) FROM v_param WHERE key = 'trace.camera' AND value = 'entrance'", 2}});
  ReportOptions opt;
  opt.by = {"technique.lights_per_pass"};
  opt.metrics = {"frame.geometry_passes", "frame_time_ms"};
  const ReportTable t = build_report(db, opt);
  ASSERT_EQ(t.rows.size(), 2u);
  EXPECT_EQ(t.rows[0].keys[0], "4");
  EXPECT_EQ(t.rows[1].keys[0], "8");
  EXPECT_EQ(t.mixed_groups, 0);
  // 16 lights in additive geometry passes of 4 and of 8 (one render pass, the scene submitted
  // once per batch after the base pass): 16/4 - 16/8 = 2 geometry passes more with 4 per pass.
  EXPECT_DOUBLE_EQ(*t.rows[0].values[0] - *t.rows[1].values[0], 2.0);
  EXPECT_GT(*t.rows[0].values[1], *t.rows[1].values[1]);  // more passes, more time
  std::ostringstream out, err;
  ASSERT_EQ(cli_main({"report", "--db", db_path, "--where", "technique.lights_per_pass = 8", "--metric", "frame.geometry_passes",
                      "--format", "csv"},
                     out, err),
            0)
      << err.str();
  const auto lines = lines_of(out.str());
  ASSERT_EQ(lines.size(), 2u) << out.str();
  EXPECT_EQ(lines[1].rfind("forward_multipass,1,", 0), 0u) << out.str();
  // The same as a baseline: 4 per pass against 8 per pass.
  std::ostringstream b;
  ASSERT_EQ(cli_main({"report", "--db", db_path, "--baseline", "technique.lights_per_pass=8", "--metric", "frame.geometry_passes",
                      "--format", "csv"},
                     b, err),
            0)
      << err.str();
  const auto bl = lines_of(b.str());
  ASSERT_EQ(bl.size(), 3u) << b.str();
  EXPECT_EQ(bl[0], "technique,technique.lights_per_pass,runs,frame.geometry_passes,frame.geometry_passes_delta,"
                   "frame.geometry_passes_ratio");
  EXPECT_EQ(bl[1], "forward_multipass,4,1,5,2,1.666666667") << b.str();  // 5 - 3 passes, 5 / 3
  EXPECT_EQ(bl[2], "forward_multipass,8,1,3,0,1") << b.str();
}

// The study compares GPU modes on the same trace and passes technique options to its traces:
// the technique x mode table holds the report's figures, and the option is a stored dimension.
TEST(ReportRealOptions, StudyComparesModesAndPassesTechniqueOptions) {
  const fs::path dir = scratch("study_modes");
  std::ostringstream out, err;
  ASSERT_EQ(cli_main({"study", "--out", (dir / "s").string(), "--technique", "plain_forward", "--lights", "4",
                      "--resolution", "64x36", "--scene", "atrium:1", "--images", "none", "--jobs", "1", "--modes", "tbdr",
                      "tbr", "--option", "plain_forward:alu_ops=40"},
                     out, err),
            0)
      << err.str();
  const std::string text = out.str();
  EXPECT_NE(text.find("Technique x GPU mode at 4 lights"), std::string::npos) << text;
  EXPECT_NE(text.find("frame ms tbdr"), std::string::npos) << text;
  EXPECT_NE(text.find("frame ms tbr"), std::string::npos) << text;
  EXPECT_NE(text.find("technique options: plain_forward alu_ops=40"), std::string::npos) << text;
  EXPECT_TRUE(fs::exists(dir / "s" / "traces" / "plain_forward_4_alu_ops-40.trace"));
  ResultsDb db((dir / "s" / "study.db").string());
  testing_support::expect_numbers(
      db, {{"SELECT count(*) FROM v_param WHERE key = 'gpu.mode' AND value IN ('tbdr', 'tbr')", 2},
           {"SELECT count(DISTINCT trace_hash) FROM runs", 1},  // the same trace on both modes
           {"SELECT min(value_num) FROM v_param WHERE key = 'technique.alu_ops'", 40}});
  // The table's TBR frame time is the report's, to the table's two decimals.
  ReportOptions opt;
  opt.by = {"gpu.mode"};
  opt.metrics = {"frame_time_ms"};
  const ReportTable t = build_report(db, opt);
  ASSERT_EQ(t.rows.size(), 2u);
  char tbr[32];
  std::snprintf(tbr, sizeof tbr, "%.2f", *t.rows[1].values[0]);  // rows sorted: tbdr, tbr
  const auto row = text.find("\nplain_forward", text.find("Technique x GPU mode"));
  ASSERT_NE(row, std::string::npos) << text;
  const std::string line = text.substr(row + 1, text.find('\n', row + 1) - row - 1);
  EXPECT_NE(line.find(tbr), std::string::npos) << line << " vs " << tbr;
  std::ostringstream bad_out, bad_err;
  EXPECT_EQ(cli_main({"study", "--out", (dir / "bad").string(), "--technique", "plain_forward", "--option",
                      "deferred:gbuffer=x"},
                     bad_out, bad_err),
            2);
  EXPECT_NE(bad_err.str().find("not in this study"), std::string::npos) << bad_err.str();
}

// A technique option its generator refuses (pls_bytes must be 8..128) is bad input: exit 2, the
// message names the technique and the option, and nothing is written: a new study folder is
// removed, an existing one keeps exactly what it held (no traces folder, no database).
TEST(ReportRealOptions, StudyWithARefusedOptionWritesNothing) {
  const fs::path dir = scratch("study_refused_option");
  const std::vector<std::string> bad = {"--technique", "plain_forward", "forward_light_stack", "--lights", "4", "--resolution", "64x36",
                                        "--scene", "atrium:1", "--option", "forward_light_stack:pls_bytes=7"};
  std::vector<std::string> a = {"study", "--out", (dir / "new").string()};
  a.insert(a.end(), bad.begin(), bad.end());
  std::ostringstream out, err;
  EXPECT_EQ(cli_main(a, out, err), 2);
  EXPECT_NE(err.str().find("generating forward_light_stack"), std::string::npos) << err.str();
  EXPECT_NE(err.str().find("pls_bytes=7"), std::string::npos) << err.str();
  EXPECT_FALSE(std::filesystem::exists(dir / "new"));

  std::filesystem::create_directories(dir / "old");
  std::ofstream(dir / "old" / "keep.txt") << "kept\n";
  a[2] = (dir / "old").string();
  std::ostringstream out2, err2;
  EXPECT_EQ(cli_main(a, out2, err2), 2);
  std::vector<std::string> left;
  for (const auto& e : std::filesystem::directory_iterator(dir / "old")) left.push_back(e.path().filename().string());
  EXPECT_EQ(left, std::vector<std::string>{"keep.txt"});
}

// The study starts its runs longest first: most scene draws, then most lights. With one worker
// the runs end, and are written, in the order they start. plain_forward draws the scene 3 times
// (opaque, masked, translucent) at any light count; forward_multipass (one light per pass) draws
// a depth pre-pass and the first light's pass (opaque and masked each), an opaque and a masked
// additive draw per further light whose box reaches the view, and the translucent draw: 5 draws
// at 2 lights and 9 at 4 in these traces. So the order is forward_multipass 4, forward_multipass
// 2, plain_forward 4, plain_forward 2 (the points were generated plain_forward first, 2 lights first).
TEST(ReportRealOptions, StudyRunsTheLongestPointsFirst) {
  const fs::path dir = scratch("study_order");
  std::ostringstream out, err;
  ASSERT_EQ(cli_main({"study", "--out", (dir / "s").string(), "--technique", "plain_forward", "forward_multipass",
                      "--lights", "2", "4", "--resolution", "64x36", "--scene", "atrium:1", "--images", "none", "--jobs", "1"},
                     out, err),
            0)
      << err.str();
  ResultsDb db((dir / "s" / "study.db").string());
  std::vector<std::string> order;
  SqlStatement q(db.sql(), "SELECT trace_path FROM runs ORDER BY id");
  while (q.step()) order.push_back(fs::path(q.text(0)).filename().string());
  const std::vector<std::string> expected = {"forward_multipass_4.trace", "forward_multipass_2.trace",
                                             "plain_forward_4.trace", "plain_forward_2.trace"};
  EXPECT_EQ(order, expected);
}

}  // namespace
}  // namespace tbdr
