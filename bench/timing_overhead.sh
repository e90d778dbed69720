#!/usr/bin/env bash
# Benchmark (prints figures): what the timing and energy models add to the functional run of the
# plain forward atrium frame at 1920x1080 with 256 lights (goal, issue 5: at most 30 %). Reports
# host CPU time (less sensitive to other load than wall time), best of N runs.
# Usage: bash bench/timing_overhead.sh [build-dir] [repetitions]
set -euo pipefail
cd "$(dirname "$0")/.."
. bench/common.sh
bench_reference_frame 5 "$@"
for i in $(seq 1 "$REPS"); do "$BUILD/tbdrsim" run --trace "$TMP/pf.trace" --db "$TMP/b.db" --quiet; done
sqlite3 -separator ' ' "$TMP/b.db" "
  SELECT 'functional CPU s (best):', printf('%.3f', min(value)) FROM stats WHERE scope='frame/host' AND name='simulation_cpu_seconds';
  SELECT 'timing+energy CPU s (best):', printf('%.3f', min(value)) FROM stats WHERE scope='frame/host' AND name='timing_cpu_seconds';
  SELECT 'timing events:', CAST(max(value) AS INTEGER) FROM stats WHERE scope='frame/timing' AND name='timing_events';
  SELECT 'overhead (best timing / best functional):', printf('%.1f %%', 100.0 *
    (SELECT min(value) FROM stats WHERE scope='frame/host' AND name='timing_cpu_seconds') /
    (SELECT min(value) FROM stats WHERE scope='frame/host' AND name='simulation_cpu_seconds'));"
