-- R"tbdr_views(
-- tbdrsim results database: the analysis views. This file is the ONLY copy of their SQL.
--
-- tbdrsim compiles it into the binary (analysis/views.cpp #includes it: the first and last lines
-- are SQL comments to SQLite but open and close a C++ raw string) and creates or refreshes the
-- views in every database it opens. It is also plain SQL for the sqlite3 shell:
--   sqlite3 results.db < analysis/views.sql
--
-- Figures a run did not record (cycles, time and energy before the timing model existed, a
-- traffic class a version did not book) come out NULL, never 0 and never an error.
-- Units are in the column names: _mb = 1e6 bytes, _mj = millijoules, _ms = milliseconds.
-- dram_*_mb is what reached the DRAM devices (mem/dram*: after the texture, vertex and system level
-- caches), per traffic class by the class of the request that caused it (a miss, or the eviction of
-- a dirty line the class wrote); requested_*_mb is the traffic the units requested at the chip
-- boundary, before those caches (frame/dram*). A "DRAM" figure without qualifier is device bytes.
-- light_evaluations counts fragment shading (tsp) and compute shading (deferred dispatches).
-- The derived figures are defined HERE and nowhere else (the study, `report`, `run` and the stats
-- files read them from v_run_summary; docs/queries.md states each):
--   shaded_fragments_per_pixel = tsp.shader_invocations / (width x height): fragment shader
--     invocations of every pass (scene geometry, light proxies, full-screen passes) per screen pixel;
--   overshading = tsp.hidden_light_evaluations / covered_pixels: light evaluations spent on scene
--     surfaces that are not in the final image (lit, then replaced by an unblended write in the same
--     pass, or failing a late depth test), per covered pixel; 0 for a technique that lights only the
--     final surface (deferred, tiled, clustered, visibility buffer, forward after a depth pre-pass);
--   hidden_lit_fragments_per_pixel = tsp.hidden_lit_samples / (covered_pixels x samples_per_pixel):
--     the same in lit fragments (samples) per covered sample;
--   lights_per_pixel = (tsp.light_evaluations + compute.compute_light_evaluations) / (width x height);
--   lights_per_fragment = the same evaluations / tsp.shader_invocations;
--   a unit's utilization = busy cycles / frame cycles (stored as frame/unit.<unit> utilization by
--     the run driver, app/run_driver.cpp time_frame, its one definition; v_unit reads it).
-- Docs and ready-to-paste questions: docs/queries.md.

-- The label of each run's configuration: the preset's name (config_name: the stem of the last
-- config file; series6xt_gx6450, which the defaults are, without one) followed by the parameters
-- whose values differ from the preset's, sorted by key:
-- 'series6xt_gx6450 pls.tile_buffer_bits_per_pixel=256'. The run driver stores it as the run
-- parameter config.label (sim/kernel/params.cpp ParamTable::label: one hardware and preset, one
-- label, however it was set); for runs stored before it did, the parameters set on top of the
-- preset (origin neither 'default' nor the preset's own file). Labels, not hashes, name configurations.
DROP VIEW IF EXISTS v_config_label;
CREATE VIEW v_config_label AS
SELECT r.id AS run_id,
  coalesce((SELECT value FROM run_params WHERE run_id = r.id AND key = 'config.label'),
  r.config_name || coalesce(' ' || (
    SELECT group_concat(key || '=' || value, ' ') FROM (
      SELECT p.key, p.value FROM run_params p
      WHERE p.run_id = r.id AND p.origin <> 'default' AND instr(p.origin, r.config_name || '.ini:') = 0
        AND p.key NOT GLOB 'technique.*' AND p.key NOT GLOB 'trace.*' AND p.key NOT GLOB 'config.*'
      ORDER BY p.key)), '')) AS config_label
FROM runs r;

-- One row per run: identity, status, frame size, the headline figures.
DROP VIEW IF EXISTS v_run_summary;
CREATE VIEW v_run_summary AS
WITH f AS (
  -- One index lookup per figure (stats is keyed by run_id, scope, name): far faster than
  -- aggregating every statistic of every run.
  SELECT r.id AS run_id,
    -- A sampled run has no frame/ rows: the size and lights of its trace are run parameters (trace.*).
    coalesce((SELECT value FROM stats WHERE run_id = r.id AND scope = 'frame/frame' AND name = 'width'),
             (SELECT CAST(value AS REAL) FROM run_params WHERE run_id = r.id AND key = 'trace.width')) AS width,
    coalesce((SELECT value FROM stats WHERE run_id = r.id AND scope = 'frame/frame' AND name = 'height'),
             (SELECT CAST(value AS REAL) FROM run_params WHERE run_id = r.id AND key = 'trace.height')) AS height,
    coalesce((SELECT value FROM stats WHERE run_id = r.id AND scope = 'frame/frame' AND name = 'samples_per_pixel'),
             (SELECT CAST(value AS REAL) FROM run_params WHERE run_id = r.id AND key = 'trace.samples')) AS samples_per_pixel,
    coalesce((SELECT value FROM stats WHERE run_id = r.id AND scope = 'frame/frame' AND name = 'lights'),
             (SELECT CAST(value AS REAL) FROM run_params WHERE run_id = r.id AND key = 'trace.lights')) AS lights,
    (SELECT value FROM stats WHERE run_id = r.id AND scope = 'frame/frame' AND name = 'passes') AS passes,
    (SELECT value FROM stats WHERE run_id = r.id AND scope = 'frame/frame' AND name = 'geometry_passes') AS geometry_passes,
    (SELECT value FROM stats WHERE run_id = r.id AND scope = 'frame/frame' AND name = 'dispatches') AS dispatches,
    (SELECT value FROM stats WHERE run_id = r.id AND scope = 'frame/tsp' AND name = 'shaded_samples') AS shaded_samples,
    (SELECT value FROM stats WHERE run_id = r.id AND scope = 'frame/tsp' AND name = 'shader_invocations') AS shader_invocations,
    (SELECT value FROM stats WHERE run_id = r.id AND scope = 'frame/tsp' AND name = 'light_evaluations') AS tsp_light_evaluations,
    (SELECT value FROM stats WHERE run_id = r.id AND scope = 'frame/tsp' AND name = 'lit_surface_invocations') AS lit_surface_invocations,
    (SELECT value FROM stats WHERE run_id = r.id AND scope = 'frame/tsp' AND name = 'hidden_lit_samples') AS hidden_lit_samples,
    (SELECT value FROM stats WHERE run_id = r.id AND scope = 'frame/tsp' AND name = 'hidden_light_evaluations') AS hidden_light_evaluations,
    (SELECT value FROM stats WHERE run_id = r.id AND scope = 'frame/frame' AND name = 'covered_pixels') AS covered_pixels,
    -- The frames of a sequence (docs/sequences.md: its frame/ figures are their sums); 1 for one frame.
    coalesce((SELECT value FROM stats WHERE run_id = r.id AND scope = 'sequence/summary' AND name = 'frames'), 1) AS frames,
    (SELECT value FROM stats WHERE run_id = r.id AND scope = 'frame/compute' AND name = 'compute_light_evaluations') AS compute_light_evaluations,
    (SELECT value FROM stats WHERE run_id = r.id AND scope = 'frame/isp' AND name = 'samples_rasterised') AS samples_rasterised,
    (SELECT value FROM stats WHERE run_id = r.id AND scope = 'frame/tiler' AND name = 'partial_renders') AS partial_renders,
    (SELECT value FROM stats WHERE run_id = r.id AND scope = 'frame/dram' AND name = 'read_bytes') AS requested_read_bytes,
    (SELECT value FROM stats WHERE run_id = r.id AND scope = 'frame/dram' AND name = 'write_bytes') AS requested_write_bytes,
    (SELECT value FROM stats WHERE run_id = r.id AND scope = 'mem/dram' AND name = 'read_bytes') AS device_read_bytes,
    (SELECT value FROM stats WHERE run_id = r.id AND scope = 'mem/dram' AND name = 'write_bytes') AS device_write_bytes,
    -- A sampled run (docs/sequences.md) has no frame/ figures: its estimates of the whole sequence stand in.
    coalesce((SELECT value FROM stats WHERE run_id = r.id AND scope = 'frame/timing' AND name = 'frame_cycles'),
             (SELECT value FROM stats WHERE run_id = r.id AND scope = 'sampling/summary' AND name = 'total_cycles')) AS cycles,
    coalesce((SELECT value FROM stats WHERE run_id = r.id AND scope = 'frame/timing' AND name = 'frame_time_ms'),
             (SELECT value FROM stats WHERE run_id = r.id AND scope = 'sampling/summary' AND name = 'total_ms')) AS frame_time_ms,
    coalesce((SELECT value FROM stats WHERE run_id = r.id AND scope = 'frame/energy' AND name = 'total_mj'),
             (SELECT value FROM stats WHERE run_id = r.id AND scope = 'sampling/summary' AND name = 'energy_mj')) AS energy_total_mj,
    (SELECT value FROM stats WHERE run_id = r.id AND scope = 'sampling/summary' AND name = 'dram_bytes') AS sampled_dram_bytes,
    (SELECT value FROM stats WHERE run_id = r.id AND scope = 'sequence/summary' AND name = 'steady_interval_ms') AS steady_interval_ms,
    (SELECT value FROM stats WHERE run_id = r.id AND scope = 'sequence/summary' AND name = 'p95_interval_ms') AS p95_interval_ms,
    (SELECT value FROM stats WHERE run_id = r.id AND scope = 'sequence/summary' AND name = 'steady_fps') AS steady_fps,
    (SELECT value FROM stats WHERE run_id = r.id AND scope = 'sequence/summary' AND name = 'steady_dram_mb_per_frame') AS steady_dram_mb_per_frame,
    (SELECT value FROM stats WHERE run_id = r.id AND scope = 'sequence/summary' AND name = 'steady_energy_per_frame_mj') AS steady_energy_per_frame_mj,
    (SELECT value FROM stats WHERE run_id = r.id AND scope = 'frame/energy' AND name = 'dram_pj') AS e_dram_pj,
    (SELECT value FROM stats WHERE run_id = r.id AND scope = 'frame/energy' AND name = 'caches_pj') AS e_caches_pj,
    (SELECT value FROM stats WHERE run_id = r.id AND scope = 'frame/energy' AND name = 'tile_buffer_pj') AS e_tile_buffer_pj,
    (SELECT value FROM stats WHERE run_id = r.id AND scope = 'frame/energy' AND name = 'tag_and_depth_buffer_pj') AS e_tag_depth_pj,
    (SELECT value FROM stats WHERE run_id = r.id AND scope = 'frame/energy' AND name = 'alu_pj') AS e_alu_pj,
    (SELECT value FROM stats WHERE run_id = r.id AND scope = 'frame/energy' AND name = 'texture_pj') AS e_texture_pj,
    (SELECT value FROM stats WHERE run_id = r.id AND scope = 'frame/energy' AND name = 'static_pj') AS e_static_pj,
    (SELECT value FROM stats WHERE run_id = r.id AND scope = 'frame/energy' AND name = 'rop_caches_pj') AS e_rop_caches_pj,
    (SELECT value FROM stats WHERE run_id = r.id AND scope = 'frame/energy' AND name = 'at_period_total_mj') AS energy_at_period_mj,
    (SELECT value FROM stats WHERE run_id = r.id AND scope = 'frame/energy' AND name = 'static_power_mw') AS static_power_mw,
    (SELECT value FROM stats WHERE run_id = r.id AND scope = 'frame/host' AND name = 'simulation_wall_seconds') AS sim_wall_seconds
  FROM runs r
),
dram AS (
  -- Per traffic class, MB read and written: at the DRAM devices (mem/dram.class.<class>) and as
  -- requested by the units (frame/dram.<class>): one index range per run and scope prefix.
  SELECT r.id AS run_id,
    sum(CASE WHEN s.scope = 'mem/dram.class.parameter_buffer' AND s.name = 'read_bytes' THEN s.value END) / 1e6 AS dram_parameter_buffer_read_mb,
    sum(CASE WHEN s.scope = 'mem/dram.class.parameter_buffer' AND s.name = 'write_bytes' THEN s.value END) / 1e6 AS dram_parameter_buffer_write_mb,
    sum(CASE WHEN s.scope = 'mem/dram.class.vertices' AND s.name = 'read_bytes' THEN s.value END) / 1e6 AS dram_vertices_read_mb,
    sum(CASE WHEN s.scope = 'mem/dram.class.vertices' AND s.name = 'write_bytes' THEN s.value END) / 1e6 AS dram_vertices_write_mb,
    sum(CASE WHEN s.scope = 'mem/dram.class.indices' AND s.name = 'read_bytes' THEN s.value END) / 1e6 AS dram_indices_read_mb,
    sum(CASE WHEN s.scope = 'mem/dram.class.indices' AND s.name = 'write_bytes' THEN s.value END) / 1e6 AS dram_indices_write_mb,
    sum(CASE WHEN s.scope = 'mem/dram.class.textures' AND s.name = 'read_bytes' THEN s.value END) / 1e6 AS dram_textures_read_mb,
    sum(CASE WHEN s.scope = 'mem/dram.class.textures' AND s.name = 'write_bytes' THEN s.value END) / 1e6 AS dram_textures_write_mb,
    sum(CASE WHEN s.scope = 'mem/dram.class.color' AND s.name = 'read_bytes' THEN s.value END) / 1e6 AS dram_color_read_mb,
    sum(CASE WHEN s.scope = 'mem/dram.class.color' AND s.name = 'write_bytes' THEN s.value END) / 1e6 AS dram_color_write_mb,
    sum(CASE WHEN s.scope = 'mem/dram.class.depth_stencil' AND s.name = 'read_bytes' THEN s.value END) / 1e6 AS dram_depth_stencil_read_mb,
    sum(CASE WHEN s.scope = 'mem/dram.class.depth_stencil' AND s.name = 'write_bytes' THEN s.value END) / 1e6 AS dram_depth_stencil_write_mb,
    sum(CASE WHEN s.scope = 'mem/dram.class.gbuffer' AND s.name = 'read_bytes' THEN s.value END) / 1e6 AS dram_gbuffer_read_mb,
    sum(CASE WHEN s.scope = 'mem/dram.class.gbuffer' AND s.name = 'write_bytes' THEN s.value END) / 1e6 AS dram_gbuffer_write_mb,
    sum(CASE WHEN s.scope = 'mem/dram.class.visibility' AND s.name = 'read_bytes' THEN s.value END) / 1e6 AS dram_visibility_read_mb,
    sum(CASE WHEN s.scope = 'mem/dram.class.visibility' AND s.name = 'write_bytes' THEN s.value END) / 1e6 AS dram_visibility_write_mb,
    sum(CASE WHEN s.scope = 'mem/dram.class.light_data' AND s.name = 'read_bytes' THEN s.value END) / 1e6 AS dram_light_data_read_mb,
    sum(CASE WHEN s.scope = 'mem/dram.class.light_data' AND s.name = 'write_bytes' THEN s.value END) / 1e6 AS dram_light_data_write_mb,
    sum(CASE WHEN s.scope = 'mem/dram.class.light_lists' AND s.name = 'read_bytes' THEN s.value END) / 1e6 AS dram_light_lists_read_mb,
    sum(CASE WHEN s.scope = 'mem/dram.class.light_lists' AND s.name = 'write_bytes' THEN s.value END) / 1e6 AS dram_light_lists_write_mb,
    sum(CASE WHEN s.scope = 'mem/dram.class.work_lists' AND s.name = 'read_bytes' THEN s.value END) / 1e6 AS dram_work_lists_read_mb,
    sum(CASE WHEN s.scope = 'mem/dram.class.work_lists' AND s.name = 'write_bytes' THEN s.value END) / 1e6 AS dram_work_lists_write_mb,
    sum(CASE WHEN s.scope = 'mem/dram.class.spill' AND s.name = 'read_bytes' THEN s.value END) / 1e6 AS dram_spill_read_mb,
    sum(CASE WHEN s.scope = 'mem/dram.class.spill' AND s.name = 'write_bytes' THEN s.value END) / 1e6 AS dram_spill_write_mb,
    sum(CASE WHEN s.scope = 'mem/dram.class.other' AND s.name = 'read_bytes' THEN s.value END) / 1e6 AS dram_other_read_mb,
    sum(CASE WHEN s.scope = 'mem/dram.class.other' AND s.name = 'write_bytes' THEN s.value END) / 1e6 AS dram_other_write_mb,
    sum(CASE WHEN s.scope = 'frame/dram.parameter_buffer' AND s.name = 'read_bytes' THEN s.value END) / 1e6 AS requested_parameter_buffer_read_mb,
    sum(CASE WHEN s.scope = 'frame/dram.parameter_buffer' AND s.name = 'write_bytes' THEN s.value END) / 1e6 AS requested_parameter_buffer_write_mb,
    sum(CASE WHEN s.scope = 'frame/dram.vertices' AND s.name = 'read_bytes' THEN s.value END) / 1e6 AS requested_vertices_read_mb,
    sum(CASE WHEN s.scope = 'frame/dram.vertices' AND s.name = 'write_bytes' THEN s.value END) / 1e6 AS requested_vertices_write_mb,
    sum(CASE WHEN s.scope = 'frame/dram.indices' AND s.name = 'read_bytes' THEN s.value END) / 1e6 AS requested_indices_read_mb,
    sum(CASE WHEN s.scope = 'frame/dram.indices' AND s.name = 'write_bytes' THEN s.value END) / 1e6 AS requested_indices_write_mb,
    sum(CASE WHEN s.scope = 'frame/dram.textures' AND s.name = 'read_bytes' THEN s.value END) / 1e6 AS requested_textures_read_mb,
    sum(CASE WHEN s.scope = 'frame/dram.textures' AND s.name = 'write_bytes' THEN s.value END) / 1e6 AS requested_textures_write_mb,
    sum(CASE WHEN s.scope = 'frame/dram.color' AND s.name = 'read_bytes' THEN s.value END) / 1e6 AS requested_color_read_mb,
    sum(CASE WHEN s.scope = 'frame/dram.color' AND s.name = 'write_bytes' THEN s.value END) / 1e6 AS requested_color_write_mb,
    sum(CASE WHEN s.scope = 'frame/dram.depth_stencil' AND s.name = 'read_bytes' THEN s.value END) / 1e6 AS requested_depth_stencil_read_mb,
    sum(CASE WHEN s.scope = 'frame/dram.depth_stencil' AND s.name = 'write_bytes' THEN s.value END) / 1e6 AS requested_depth_stencil_write_mb,
    sum(CASE WHEN s.scope = 'frame/dram.gbuffer' AND s.name = 'read_bytes' THEN s.value END) / 1e6 AS requested_gbuffer_read_mb,
    sum(CASE WHEN s.scope = 'frame/dram.gbuffer' AND s.name = 'write_bytes' THEN s.value END) / 1e6 AS requested_gbuffer_write_mb,
    sum(CASE WHEN s.scope = 'frame/dram.visibility' AND s.name = 'read_bytes' THEN s.value END) / 1e6 AS requested_visibility_read_mb,
    sum(CASE WHEN s.scope = 'frame/dram.visibility' AND s.name = 'write_bytes' THEN s.value END) / 1e6 AS requested_visibility_write_mb,
    sum(CASE WHEN s.scope = 'frame/dram.light_data' AND s.name = 'read_bytes' THEN s.value END) / 1e6 AS requested_light_data_read_mb,
    sum(CASE WHEN s.scope = 'frame/dram.light_data' AND s.name = 'write_bytes' THEN s.value END) / 1e6 AS requested_light_data_write_mb,
    sum(CASE WHEN s.scope = 'frame/dram.light_lists' AND s.name = 'read_bytes' THEN s.value END) / 1e6 AS requested_light_lists_read_mb,
    sum(CASE WHEN s.scope = 'frame/dram.light_lists' AND s.name = 'write_bytes' THEN s.value END) / 1e6 AS requested_light_lists_write_mb,
    sum(CASE WHEN s.scope = 'frame/dram.work_lists' AND s.name = 'read_bytes' THEN s.value END) / 1e6 AS requested_work_lists_read_mb,
    sum(CASE WHEN s.scope = 'frame/dram.work_lists' AND s.name = 'write_bytes' THEN s.value END) / 1e6 AS requested_work_lists_write_mb,
    sum(CASE WHEN s.scope = 'frame/dram.spill' AND s.name = 'read_bytes' THEN s.value END) / 1e6 AS requested_spill_read_mb,
    sum(CASE WHEN s.scope = 'frame/dram.spill' AND s.name = 'write_bytes' THEN s.value END) / 1e6 AS requested_spill_write_mb,
    sum(CASE WHEN s.scope = 'frame/dram.other' AND s.name = 'read_bytes' THEN s.value END) / 1e6 AS requested_other_read_mb,
    sum(CASE WHEN s.scope = 'frame/dram.other' AND s.name = 'write_bytes' THEN s.value END) / 1e6 AS requested_other_write_mb
  FROM runs r LEFT JOIN stats s ON s.run_id = r.id
    AND ((s.scope > 'frame/dram.' AND s.scope < 'frame/dram/') OR (s.scope > 'mem/dram.class.' AND s.scope < 'mem/dram.class/'))
  GROUP BY r.id
),
g AS (
  SELECT f.*,
    CASE WHEN f.tsp_light_evaluations IS NULL AND f.compute_light_evaluations IS NULL THEN NULL
         ELSE coalesce(f.tsp_light_evaluations, 0) + coalesce(f.compute_light_evaluations, 0) END AS light_evaluations
  FROM f
)
SELECT d.*,  -- run_id, dram_<class>_read_mb / _write_mb (device), requested_<class>_read_mb / _write_mb
  r.technique, r.scene, r.config_name, l.config_label, r.status, r.error,
  r.config_hash, r.trace_hash, r.trace_path, r.started_at, r.host,
  f.width, f.height, f.samples_per_pixel, f.lights, f.passes, f.geometry_passes, f.dispatches,
  f.shaded_samples, f.shader_invocations, f.light_evaluations, f.samples_rasterised, f.partial_renders,
  f.covered_pixels,
  f.shader_invocations / nullif(f.width * f.height * f.frames, 0) AS shaded_fragments_per_pixel,
  f.hidden_light_evaluations / nullif(f.covered_pixels, 0) AS overshading,
  f.hidden_lit_samples / nullif(f.covered_pixels * f.samples_per_pixel, 0) AS hidden_lit_fragments_per_pixel,
  f.light_evaluations / nullif(f.width * f.height * f.frames, 0) AS lights_per_pixel,
  f.light_evaluations / nullif(f.shader_invocations, 0) AS lights_per_fragment,
  f.device_read_bytes / 1e6 AS dram_read_mb,
  f.device_write_bytes / 1e6 AS dram_write_mb,
  coalesce((f.device_read_bytes + f.device_write_bytes) / 1e6, f.sampled_dram_bytes / 1e6) AS dram_total_mb,
  f.requested_read_bytes / 1e6 AS requested_read_mb,
  f.requested_write_bytes / 1e6 AS requested_write_mb,
  (f.requested_read_bytes + f.requested_write_bytes) / 1e6 AS requested_total_mb,
  f.cycles, f.frame_time_ms,
  f.energy_total_mj,
  f.e_dram_pj * 1e-9 AS energy_dram_mj,
  f.e_caches_pj * 1e-9 AS energy_caches_mj,
  f.e_tile_buffer_pj * 1e-9 AS energy_tile_buffer_mj,
  f.e_tag_depth_pj * 1e-9 AS energy_tag_and_depth_buffer_mj,
  f.e_alu_pj * 1e-9 AS energy_alu_mj,
  f.e_texture_pj * 1e-9 AS energy_texture_mj,
  f.e_static_pj * 1e-9 AS energy_static_mj,
  f.e_rop_caches_pj * 1e-9 AS energy_rop_caches_mj,
  f.energy_at_period_mj, f.static_power_mw,
  f.frames, f.steady_interval_ms, f.p95_interval_ms, f.steady_fps, f.steady_dram_mb_per_frame, f.steady_energy_per_frame_mj,
  f.sim_wall_seconds
FROM runs r JOIN g AS f ON f.run_id = r.id JOIN dram d ON d.run_id = r.id JOIN v_config_label l ON l.run_id = r.id;

-- Every parameter of every run, one row each, for pivoting and grouping: the resolved hardware
-- parameters and what the run driver stored from the trace's header (run_params: the technique's
-- options as technique.<option>, the viewpoint as trace.camera), plus pseudo-keys: trace.technique,
-- trace.scene, trace.lights, trace.width, trace.height, trace.samples, trace.resolution,
-- trace.path, trace.hash, config.name, config.label (v_config_label).
-- value_num is the value as a number (booleans 1/0) or NULL for text.
DROP VIEW IF EXISTS v_param;
CREATE VIEW v_param AS
SELECT run_id, key, value,
  CASE WHEN value = 'true' THEN 1 WHEN value = 'false' THEN 0
       WHEN value <> '' AND trim(value, '0123456789.eE+-') = '' AND value GLOB '*[0-9]*'
         THEN CAST(value AS REAL) END AS value_num,
  origin
FROM run_params WHERE key <> 'config.label'  -- (below, from v_config_label)
UNION ALL
SELECT id, 'trace.technique', technique, NULL, 'trace' FROM runs
UNION ALL
SELECT id, 'trace.scene', scene, NULL, 'trace' FROM runs
UNION ALL
SELECT id, 'config.name', config_name, NULL, 'config file' FROM runs
UNION ALL
SELECT run_id, 'config.label', config_label, NULL, 'config' FROM v_config_label
UNION ALL
SELECT id, 'trace.path', trace_path, NULL, 'trace' FROM runs
UNION ALL
SELECT id, 'trace.hash', trace_hash, NULL, 'trace' FROM runs
UNION ALL
SELECT r.id, 'trace.resolution', CAST(CAST(w.value AS INTEGER) AS TEXT) || 'x' || CAST(CAST(h.value AS INTEGER) AS TEXT),
  NULL, 'trace'
FROM runs r
JOIN stats w ON w.run_id = r.id AND w.scope = 'frame/frame' AND w.name = 'width'
JOIN stats h ON h.run_id = r.id AND h.scope = 'frame/frame' AND h.name = 'height'
UNION ALL
SELECT r.id,
  CASE s.name WHEN 'lights' THEN 'trace.lights' WHEN 'width' THEN 'trace.width' WHEN 'height' THEN 'trace.height'
              ELSE 'trace.samples' END,
  CAST(CAST(s.value AS INTEGER) AS TEXT), s.value, 'trace'
FROM runs r JOIN stats s ON s.run_id = r.id AND s.scope = 'frame/frame'
  AND s.name IN ('lights', 'width', 'height', 'samples_per_pixel');

-- DRAM traffic per run and traffic class (long form: works for classes added later). read/write/
-- total_mb: what reached the DRAM devices after the caches (mem/dram.class.<class>), booked to the
-- class of the request that caused it; requested_*_mb: what the units requested at the chip boundary
-- (frame/dram.<class>). Device figures are NULL for runs without a memory system model.
DROP VIEW IF EXISTS v_dram_class;
CREATE VIEW v_dram_class AS
SELECT r.id AS run_id, r.technique, r.config_name, r.status, substr(s.scope, 12) AS class,
  (SELECT value FROM stats WHERE run_id = r.id AND scope = 'mem/dram.class.' || substr(s.scope, 12)
     AND name = 'read_bytes') / 1e6 AS read_mb,
  (SELECT value FROM stats WHERE run_id = r.id AND scope = 'mem/dram.class.' || substr(s.scope, 12)
     AND name = 'write_bytes') / 1e6 AS write_mb,
  (SELECT sum(value) FROM stats WHERE run_id = r.id AND scope = 'mem/dram.class.' || substr(s.scope, 12)
     AND name IN ('read_bytes', 'write_bytes')) / 1e6 AS total_mb,
  sum(CASE WHEN s.name = 'read_bytes' THEN s.value END) / 1e6 AS requested_read_mb,
  sum(CASE WHEN s.name = 'write_bytes' THEN s.value END) / 1e6 AS requested_write_mb,
  sum(s.value) / 1e6 AS requested_total_mb
FROM runs r
JOIN stats s ON s.run_id = r.id AND s.scope > 'frame/dram.' AND s.scope < 'frame/dram/'  -- 'frame/dram.*'
  AND s.name IN ('read_bytes', 'write_bytes')
GROUP BY r.id, s.scope;

-- Energy per run and component in mJ (long form: every frame/energy <component>_pj row).
DROP VIEW IF EXISTS v_energy_component;
CREATE VIEW v_energy_component AS
SELECT r.id AS run_id, r.technique, r.config_name, r.status,
  substr(s.name, 1, length(s.name) - 3) AS component, s.value * 1e-9 AS energy_mj
FROM runs r JOIN stats s ON s.run_id = r.id AND s.scope = 'frame/energy'
WHERE s.name GLOB '*_pj' AND s.name <> 'total_pj';

-- Busy, stalled and idle cycles and utilization per run and timed unit (binning, tile fetch, ISP,
-- USC, pixel back end: every frame/unit.<unit> scope the run driver wrote). A unit's instances
-- (the USCs) are one server: busy is the time it worked, stalled the time its work waited (for
-- memory, for a full queue downstream) while it was not working, counted once however many tiles
-- waited at once, idle the rest; the three add up to the frame, and their _pct columns to 100.
DROP VIEW IF EXISTS v_unit;
CREATE VIEW v_unit AS
SELECT u.*, 100.0 * u.busy_cycles / f.value AS busy_pct, 100.0 * u.stalled_cycles / f.value AS stalled_pct,
  100.0 * u.idle_cycles / f.value AS idle_pct
FROM (
  SELECT r.id AS run_id, r.technique, r.config_name, r.status, substr(s.scope, 12) AS unit,
    max(CASE WHEN s.name = 'busy_cycles' THEN s.value END) AS busy_cycles,
    max(CASE WHEN s.name = 'stalled_cycles' THEN s.value END) AS stalled_cycles,
    max(CASE WHEN s.name = 'idle_cycles' THEN s.value END) AS idle_cycles,
    max(CASE WHEN s.name = 'utilization' THEN s.value END) AS utilization
  FROM runs r JOIN stats s ON s.run_id = r.id AND s.scope > 'frame/unit.' AND s.scope < 'frame/unit/'  -- 'frame/unit.*'
  GROUP BY r.id, s.scope) u
LEFT JOIN stats f ON f.run_id = u.run_id AND f.scope = 'frame/timing' AND f.name = 'frame_cycles' AND f.value > 0;

-- The derived figures of v_metric: name, unit and meaning (stats files and docs/queries.md use it).
DROP VIEW IF EXISTS v_metric_def;
CREATE VIEW v_metric_def AS
SELECT column1 AS metric, column2 AS unit, column3 AS description FROM (VALUES
  ('frame_time_ms', 'ms', 'Frame time (timing model)'),
  ('cycles', 'cycles', 'Frame time in core clock cycles'),
  ('energy_total_mj', 'mJ', 'Energy of the frame, every component'),
  ('dram_total_mb', 'MB', 'Bytes read from and written to the DRAM devices (after the texture, vertex and system level caches), 1e6 bytes'),
  ('dram_read_mb', 'MB', 'Bytes read from the DRAM devices'),
  ('dram_write_mb', 'MB', 'Bytes written to the DRAM devices'),
  ('requested_total_mb', 'MB', 'Bytes the units requested from memory at the chip boundary, read + written, before the caches'),
  ('requested_read_mb', 'MB', 'Bytes the units requested to read, before the caches'),
  ('requested_write_mb', 'MB', 'Bytes the units requested to write, before the caches'),
  ('overshading', 'light evaluations/covered pixel',
   'tsp.hidden_light_evaluations / covered_pixels: lights evaluated on scene surfaces that are not in the final image, per covered pixel; 0 = only the final surface is lit'),
  ('hidden_lit_fragments_per_pixel', 'fragments/covered sample',
   'tsp.hidden_lit_samples / (covered_pixels x samples_per_pixel): lit scene-surface samples later hidden, per covered sample'),
  ('energy_at_period_mj', 'mJ', 'Energy of the frame plus the idle time to gpu.frame_period_us at idle power (= energy_total_mj when the period is 0: race to idle)'),
  ('static_power_mw', 'mW', 'Leakage of the configured units and arrays while the frame runs'),
  ('shaded_fragments_per_pixel', 'fragments/pixel',
   'tsp.shader_invocations / (width x height): fragment shader invocations of every pass per screen pixel'),
  ('covered_pixels', 'pixels', 'Pixels shaded at least once (the visible surface)'),
  ('lights_per_pixel', 'lights/pixel',
   '(tsp.light_evaluations + compute.compute_light_evaluations) / (width x height)'),
  ('lights_per_fragment', 'lights/fragment', 'The same light evaluations / tsp.shader_invocations'),
  ('shaded_samples', 'samples', 'Samples whose color a shader wrote'),
  ('samples_rasterised', 'samples', 'Samples the ISP rasterised'),
  ('partial_renders', 'renders', 'Partial renders (parameter buffer full)'),
  ('frames', 'frames', 'Frames of the run: the frame/ figures of a sequence (frame_time_ms, cycles, DRAM, energy) are their sums'),
  ('steady_interval_ms', 'ms', 'A sequence: mean frame interval after the warm-up frame and before the last (sequence/summary)'),
  ('p95_interval_ms', 'ms', 'A sequence: 95th percentile of the steady frames intervals'),
  ('steady_fps', 'frames/s', 'A sequence: 1000 / steady_interval_ms'),
  ('steady_dram_mb_per_frame', 'MB', 'A sequence: DRAM MB at the devices per steady frame'),
  ('steady_energy_per_frame_mj', 'mJ', 'A sequence: energy per steady frame'),
  ('sim_wall_seconds', 's', 'Host wall time of the functional simulation'));

-- Every figure of every run, one row each (metric, value, unit): the derived figures of
-- v_run_summary under their column names (frame_time_ms, cycles, dram_total_mb, energy_total_mj,
-- overshading, shaded_fragments_per_pixel, lights_per_pixel, ...), DRAM MB at the devices read+written
-- per class ('dram_<class>_mb'), energy per component ('energy_<component>_mj'), MB the units requested
-- per class ('requested_<class>_mb'), and every raw frame statistic as '<unit>.<name>' (the scope without
-- 'frame/': 'tsp.shaded_samples', 'dram.color.write_bytes', 'unit.usc.utilization').
DROP VIEW IF EXISTS v_metric;
CREATE VIEW v_metric AS
SELECT s.run_id, m.metric,
  CASE m.metric
    WHEN 'frame_time_ms' THEN s.frame_time_ms
    WHEN 'cycles' THEN s.cycles
    WHEN 'energy_total_mj' THEN s.energy_total_mj
    WHEN 'dram_total_mb' THEN s.dram_total_mb
    WHEN 'dram_read_mb' THEN s.dram_read_mb
    WHEN 'dram_write_mb' THEN s.dram_write_mb
    WHEN 'requested_total_mb' THEN s.requested_total_mb
    WHEN 'requested_read_mb' THEN s.requested_read_mb
    WHEN 'requested_write_mb' THEN s.requested_write_mb
    WHEN 'overshading' THEN s.overshading
    WHEN 'hidden_lit_fragments_per_pixel' THEN s.hidden_lit_fragments_per_pixel
    WHEN 'energy_at_period_mj' THEN s.energy_at_period_mj
    WHEN 'static_power_mw' THEN s.static_power_mw
    WHEN 'shaded_fragments_per_pixel' THEN s.shaded_fragments_per_pixel
    WHEN 'covered_pixels' THEN s.covered_pixels
    WHEN 'lights_per_pixel' THEN s.lights_per_pixel
    WHEN 'lights_per_fragment' THEN s.lights_per_fragment
    WHEN 'shaded_samples' THEN s.shaded_samples
    WHEN 'samples_rasterised' THEN s.samples_rasterised
    WHEN 'partial_renders' THEN s.partial_renders
    WHEN 'frames' THEN s.frames
    WHEN 'steady_interval_ms' THEN s.steady_interval_ms
    WHEN 'p95_interval_ms' THEN s.p95_interval_ms
    WHEN 'steady_fps' THEN s.steady_fps
    WHEN 'steady_dram_mb_per_frame' THEN s.steady_dram_mb_per_frame
    WHEN 'steady_energy_per_frame_mj' THEN s.steady_energy_per_frame_mj
    WHEN 'sim_wall_seconds' THEN s.sim_wall_seconds
  END AS value,
  m.unit
FROM v_run_summary s
CROSS JOIN v_metric_def m
UNION ALL
SELECT run_id, 'dram_' || class || '_mb', total_mb, 'MB' FROM v_dram_class WHERE total_mb IS NOT NULL
UNION ALL
SELECT run_id, 'requested_' || class || '_mb', requested_total_mb, 'MB' FROM v_dram_class
WHERE requested_total_mb IS NOT NULL
UNION ALL
SELECT run_id, 'energy_' || component || '_mj', energy_mj, 'mJ' FROM v_energy_component
UNION ALL
SELECT run_id, substr(scope, 7) || '.' || name, value, unit FROM stats WHERE scope GLOB 'frame/*';

-- Vendor counter names for figures that have a well-known one, and their values per run. Only
-- names that exist in the vendors' tools, each with its source; value = metric x scale + offset.
--   PowerVR: the Imagination PowerVR counters of Android GPU Inspector
--     (https://developer.android.com/agi/refdocs/counters-imagination), as PVRTune names them;
--   Mali: Arm's counter definitions for Streamline as Mesa carries them
--     (src/panfrost/perf/G52.xml: name="...", counter="...").
-- approximate = 1 where tbdrsim's figure is close to, not the same as, the vendor's (note says how).
DROP VIEW IF EXISTS v_counter_alias;
CREATE VIEW v_counter_alias AS
SELECT column1 AS vendor, column2 AS counter, column3 AS unit, column4 AS metric, column5 AS scale,
  column6 AS offset, column7 AS approximate, column8 AS note, column9 AS source FROM (VALUES
  ('PowerVR', 'Triangles In', 'triangles', 'geometry.primitives_in', 1, 0, 0,
   'triangles submitted to the tiling hardware', 'Android GPU Inspector, Imagination PowerVR counters'),
  ('PowerVR', 'Triangles Out', 'triangles', 'geometry.primitives_out', 1, 0, 0,
   'triangles left after back-face, off-screen and sub-pixel culling', 'Android GPU Inspector, Imagination PowerVR counters'),
  ('PowerVR', 'Geometry Load', '%', 'unit.binning.utilization', 100, 0, 0,
   'share of the time the tile binning hardware spent processing primitives', 'Android GPU Inspector, Imagination PowerVR counters'),
  ('PowerVR', 'ISP Pixel Load', '%', 'unit.isp.utilization', 100, 0, 1,
   'share of the time the rasterisation hardware was busy; tbdrsim''s ISP busy time includes primitive setup',
   'Android GPU Inspector, Imagination PowerVR counters'),
  ('PowerVR', 'Overdraw', '%', 'shaded_fragments_per_pixel', 100, -100, 0,
   'on-screen pixels drawn more than once: 0 % = every pixel shaded once, 100 % = twice',
   'Android GPU Inspector, Imagination PowerVR counters'),
  ('Mali', 'GPU active', 'cycles', 'cycles', 1, 0, 1,
   'cycles the GPU had work queued: the frame''s cycles (one frame, no idle gaps)', 'Mesa src/panfrost/perf/G52.xml GPU_ACTIVE'),
  ('Mali', 'Tiler active', 'cycles', 'unit.binning.busy_cycles', 1, 0, 1,
   'cycles the tiler had work queued; tbdrsim counts the binning engine''s busy cycles (stalls excluded)',
   'Mesa src/panfrost/perf/G52.xml TILER_ACTIVE'),
  ('Mali', 'Triangle primitives', 'primitives', 'geometry.primitives_in', 1, 0, 0,
   'input triangle primitives', 'Mesa src/panfrost/perf/G52.xml TRIANGLES'),
  ('Mali', 'Visible primitives', 'primitives', 'geometry.primitives_out', 1, 0, 0,
   'primitives visible after culling', 'Mesa src/panfrost/perf/G52.xml PRIM_VISIBLE'),
  ('Mali', 'Tiles', 'tiles', 'isp.tiles_rendered', 1, 0, 1,
   'tiles processed by the shader cores; tbdrsim''s tiles are tiling.tile_width x tile_height pixels',
   'Mesa src/panfrost/perf/G52.xml FRAG_PTILES'));

DROP VIEW IF EXISTS v_vendor_counter;
CREATE VIEW v_vendor_counter AS
SELECT m.run_id, a.vendor, a.counter, m.value * a.scale + a.offset AS value, a.unit, a.metric, a.approximate
FROM v_counter_alias a JOIN v_metric m ON m.metric = a.metric
WHERE m.value IS NOT NULL;

-- Any figure against any parameter, finished runs only: filter on key and metric, e.g.
--   SELECT value_num, avg(metric_value) FROM v_sensitivity
--   WHERE key = 'tiling.tile_width' AND metric = 'frame_time_ms' GROUP BY value_num;
DROP VIEW IF EXISTS v_sensitivity;
CREATE VIEW v_sensitivity AS
SELECT p.run_id, r.technique, r.scene, r.config_name, p.key, p.value, p.value_num,
  m.metric, m.value AS metric_value, m.unit AS metric_unit
FROM v_param p
JOIN runs r ON r.id = p.run_id AND r.status = 'ok'
JOIN v_metric m ON m.run_id = p.run_id;

-- Techniques side by side: one row per (hardware config, scene, resolution, samples, lights,
-- technique) over finished runs, repetitions averaged, with each technique's rank in its group
-- (1 = fastest / least DRAM traffic at the devices / least energy).
DROP VIEW IF EXISTS v_technique_comparison;
CREATE VIEW v_technique_comparison AS
SELECT config_name, min(config_label) AS config_label, config_hash, scene, width, height, samples_per_pixel, lights,
  technique, count(*) AS runs,
  avg(frame_time_ms) AS frame_time_ms, avg(cycles) AS cycles,
  avg(dram_total_mb) AS dram_total_mb, avg(dram_read_mb) AS dram_read_mb, avg(dram_write_mb) AS dram_write_mb,
  avg(requested_total_mb) AS requested_total_mb,
  avg(dram_parameter_buffer_read_mb + dram_parameter_buffer_write_mb) AS dram_parameter_buffer_mb,
  avg(dram_vertices_read_mb + dram_vertices_write_mb) AS dram_vertices_mb,
  avg(dram_indices_read_mb + dram_indices_write_mb) AS dram_indices_mb,
  avg(dram_textures_read_mb + dram_textures_write_mb) AS dram_textures_mb,
  avg(dram_color_read_mb + dram_color_write_mb) AS dram_color_mb,
  avg(dram_depth_stencil_read_mb + dram_depth_stencil_write_mb) AS dram_depth_stencil_mb,
  avg(dram_gbuffer_read_mb + dram_gbuffer_write_mb) AS dram_gbuffer_mb,
  avg(dram_visibility_read_mb + dram_visibility_write_mb) AS dram_visibility_mb,
  avg(dram_light_data_read_mb + dram_light_data_write_mb) AS dram_light_data_mb,
  avg(dram_light_lists_read_mb + dram_light_lists_write_mb) AS dram_light_lists_mb,
  avg(dram_work_lists_read_mb + dram_work_lists_write_mb) AS dram_work_lists_mb,
  avg(dram_spill_read_mb + dram_spill_write_mb) AS dram_spill_mb,
  avg(dram_other_read_mb + dram_other_write_mb) AS dram_other_mb,
  avg(energy_total_mj) AS energy_total_mj,
  avg(energy_at_period_mj) AS energy_at_period_mj,
  avg(overshading) AS overshading, avg(shaded_fragments_per_pixel) AS shaded_fragments_per_pixel,
  avg(lights_per_pixel) AS lights_per_pixel,
  rank() OVER (PARTITION BY config_hash, scene, width, height, samples_per_pixel, lights
               ORDER BY avg(frame_time_ms) IS NULL, avg(frame_time_ms)) AS rank_frame_time,
  rank() OVER (PARTITION BY config_hash, scene, width, height, samples_per_pixel, lights
               ORDER BY avg(dram_total_mb) IS NULL, avg(dram_total_mb)) AS rank_dram,
  rank() OVER (PARTITION BY config_hash, scene, width, height, samples_per_pixel, lights
               ORDER BY avg(energy_total_mj) IS NULL, avg(energy_total_mj)) AS rank_energy
FROM v_run_summary
WHERE status = 'ok'
GROUP BY config_hash, scene, width, height, samples_per_pixel, lights, technique;
-- )tbdr_views"_tbdr_sql
