#!/usr/bin/env bash
# Benchmark (prints figures): frame sequences with one and two frames in flight (docs/sequences.md).
# Every technique on the atrium (detail 2, entrance, orbiting camera and lights) for FRAMES frames,
# replayed with gpu.frames_in_flight = 1 and 2. Columns: the first frame (cold, nothing before it);
# the steady frame interval (after the warm-up frame, before the drain frame) with 1 and 2 frames in
# flight and what the second saves; the first pass's binning of frame 1 with one frame in flight
# (what a second frame in flight can hide: an upper bound on the saving); DRAM MB per steady frame
# with 1 and 2; host CPU seconds of the two runs.
# Usage: bash bench/sequences.sh [build-dir] [WIDTHxHEIGHT] [frames] [lights]
set -euo pipefail
cd "$(dirname "$0")/.."
. bench/common.sh
BUILD=${1:-build}
RES=${2:-960x540}
FRAMES=${3:-8}
LIGHTS=${4:-256}
bench_positive_int bench/sequences.sh frames "$FRAMES"
bench_positive_int bench/sequences.sh lights "$LIGHTS"
bench_scratch
stat() {  # db scope name
  sqlite3 "$1" "SELECT value FROM stats WHERE run_id = (SELECT max(id) FROM runs) AND scope = '$2' AND name = '$3'"
}
mhz=$("$BUILD/tbdrsim" params | awk '$1 == "gpu.core_clock_mhz" { v = $2 } END { print v }')
echo "atrium:2 entrance, $RES, $LIGHTS lights, $FRAMES frames (camera and lights orbit); default hardware ($mhz MHz)"
printf "%-28s %9s %9s %9s %8s %10s %8s %8s %7s\n" "technique" "frame0 ms" "steady 1" "steady 2" "saved" "bin1 ms" "MB/f 1" "MB/f 2" "CPU s"
for t in $("$BUILD/tbdrsim" trace --list | awk '/^[a-z_]+:/ { sub(":", "", $1); print $1 }'); do
  "$BUILD/tbdrsim" trace --technique "$t" --scene atrium:2 --camera entrance --lights "$LIGHTS" --resolution "$RES" \
    --frames "$FRAMES" --camera-path orbit --light-motion orbit --out "$TMP/s.trace" > /dev/null
  : > "$TMP/cpu"
  for n in 1 2; do
    /usr/bin/time -a -o "$TMP/cpu" -f "%U %S" \
      "$BUILD/tbdrsim" run --trace "$TMP/s.trace" --db "$TMP/$t.$n.db" --set gpu.frames_in_flight=$n --threads 1 --quiet
  done
  cpu=$(awk '{ s += $1 + $2 } END { print s }' "$TMP/cpu")
  # The first pass of frame 1 with one frame in flight: from its start to its binning's end.
  first=$(sqlite3 "$TMP/$t.1.db" "SELECT scope FROM stats WHERE run_id = 1 AND scope LIKE 'frame1.%/timing' AND name = 'start_cycle' ORDER BY value LIMIT 1")
  bin=$(sqlite3 "$TMP/$t.1.db" "SELECT max(0, e.value - s.value) FROM stats s JOIN stats e ON e.run_id = s.run_id AND e.scope = s.scope
        WHERE s.run_id = 1 AND s.scope = '$first' AND s.name = 'start_cycle' AND e.name = 'binning_end_cycle'")
  awk -v t="$t" -v mhz="$mhz" -v cpu="$cpu" \
    -v f0="$(stat "$TMP/$t.1.db" sequence/frame0 interval_ms)" \
    -v s1="$(stat "$TMP/$t.1.db" sequence/summary steady_interval_ms)" \
    -v s2="$(stat "$TMP/$t.2.db" sequence/summary steady_interval_ms)" \
    -v bin="$bin" \
    -v m1="$(stat "$TMP/$t.1.db" sequence/summary steady_dram_mb_per_frame)" \
    -v m2="$(stat "$TMP/$t.2.db" sequence/summary steady_dram_mb_per_frame)" \
    'BEGIN { printf "%-28s %9.3f %9.3f %9.3f %7.1f%% %10.3f %8.2f %8.2f %7.1f\n", t, f0, s1, s2, 100 * (s1 - s2) / s1, bin / mhz / 1000, m1, m2, cpu }'
done
