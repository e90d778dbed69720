#!/usr/bin/env bash
# Benchmark (prints figures): wall time and simulated samples per second of the plain forward
# atrium frame at 1920x1080 with 256 lights on the default GPU. Goal (issue 4): under 2 s.
# Usage: bash bench/frame_bench.sh [build-dir] [repetitions]
set -euo pipefail
cd "$(dirname "$0")/.."
. bench/common.sh
bench_reference_frame 3 "$@"
for i in $(seq 1 "$REPS"); do
  start=$(date +%s.%N)
  "$BUILD/tbdrsim" run --trace "$TMP/pf.trace" --db "$TMP/bench.db" --quiet
  end=$(date +%s.%N)
  echo "run $i: process wall $(echo "$end - $start" | bc) s"
done
sqlite3 -separator ' ' "$TMP/bench.db" "
  SELECT 'simulation wall time (s, per run):', group_concat(printf('%.3f', value), ' ')
    FROM stats WHERE scope = 'frame/host' AND name = 'simulation_wall_seconds';
  SELECT 'samples rasterised per run:', CAST(max(value) AS INTEGER) FROM stats WHERE scope = 'frame/isp' AND name = 'samples_rasterised';
  SELECT 'simulated samples per second (best run):', printf('%.3g', max(r.value / w.value))
    FROM stats r JOIN stats w ON r.run_id = w.run_id
   WHERE r.scope = 'frame/isp' AND r.name = 'samples_rasterised' AND w.scope = 'frame/host' AND w.name = 'simulation_wall_seconds';"
