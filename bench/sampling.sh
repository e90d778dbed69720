#!/usr/bin/env bash
# Benchmark (prints figures): sampled simulation of a long sequence against simulating every frame
# (docs/sequences.md, "Sampled simulation"). For each technique: a FRAMES-frame sequence of the
# atrium (detail 3, entrance, camera and lights orbiting) at WIDTHxHEIGHT with LIGHTS lights,
# replayed in full and with `--sample K`, both on one thread. Prints the sequence's cycles, DRAM
# bytes (what reached the devices) and energy from both, the sampled run's error against the full
# one and its own error estimate (+-), and the host CPU seconds of each (user + system, from
# /usr/bin/time: trace reading and scene loading included) with their ratio.
# Usage: bash bench/sampling.sh [build-dir] [WIDTHxHEIGHT] [frames] [K] [lights] [technique...]
# Defaults: build 1920x1080 300 10 256 forward_plus. A full 1080p frame costs 0.4 to 0.6 CPU s: the
# default full run takes 2 to 3 CPU minutes per technique (measured: 122.6 s forward_plus, 182.4 s
# light_prepass).
set -euo pipefail
cd "$(dirname "$0")/.."
. bench/common.sh
BUILD=${1:-build}
RES=${2:-1920x1080}
FRAMES=${3:-300}
K=${4:-10}
LIGHTS=${5:-256}
shift $(( $# < 5 ? $# : 5 ))
TECHNIQUES=("$@")
[ ${#TECHNIQUES[@]} -gt 0 ] || TECHNIQUES=(forward_plus)
bench_positive_int bench/sampling.sh frames "$FRAMES"
bench_positive_int bench/sampling.sh K "$K"
bench_positive_int bench/sampling.sh lights "$LIGHTS"
bench_scratch
q() {  # db sql
  sqlite3 "$1" "$2"
}
echo "atrium:3 entrance, $RES, $LIGHTS lights, $FRAMES frames (camera and lights orbit), --sample $K; $("$BUILD/tbdrsim" --version 2>/dev/null | head -1)"
printf "%-22s %-7s %14s %14s %11s %8s %8s\n" "technique" "run" "cycles" "DRAM MB" "energy mJ" "CPU s" "peak MB"
for t in "${TECHNIQUES[@]}"; do
  "$BUILD/tbdrsim" trace --technique "$t" --scene atrium:3 --camera entrance --lights "$LIGHTS" --resolution "$RES" \
    --frames "$FRAMES" --camera-path orbit --light-motion orbit --out "$TMP/s.trace" > /dev/null
  /usr/bin/time -o "$TMP/full.time" -f "%U %S %M" \
    "$BUILD/tbdrsim" run --trace "$TMP/s.trace" --db "$TMP/$t.full.db" --threads 1 --quiet
  /usr/bin/time -o "$TMP/sampled.time" -f "%U %S %M" \
    "$BUILD/tbdrsim" run --trace "$TMP/s.trace" --db "$TMP/$t.sampled.db" --threads 1 --quiet --sample "$K"
  fc=$(q "$TMP/$t.full.db" "SELECT value FROM stats WHERE scope = 'frame/timing' AND name = 'frame_cycles'")
  fb=$(q "$TMP/$t.full.db" "SELECT sum(value) FROM stats WHERE scope LIKE 'sequence/frame%' AND name = 'dram_interval_bytes'")
  fe=$(q "$TMP/$t.full.db" "SELECT value * 1e-9 FROM stats WHERE scope = 'frame/energy' AND name = 'total_pj'")
  sv() { q "$TMP/$t.sampled.db" "SELECT value FROM stats WHERE scope = 'sampling/summary' AND name = '$1'"; }
  awk -v t="$t" -v fc="$fc" -v fb="$fb" -v fe="$fe" \
      -v sc="$(sv total_cycles)" -v sce="$(sv total_cycles_error_pct)" -v sb="$(sv dram_bytes)" -v sbe="$(sv dram_bytes_error_pct)" \
      -v se="$(sv energy_mj)" -v see="$(sv energy_error_pct)" -v sim="$(sv frames_simulated)" \
      -v ft="$(cat "$TMP/full.time")" -v st="$(cat "$TMP/sampled.time")" 'BEGIN {
    split(ft, a, " "); split(st, b, " ");
    fcpu = a[1] + a[2]; scpu = b[1] + b[2];
    printf "%-22s %-7s %14.0f %14.2f %11.3f %8.1f %8.0f\n", t, "full", fc, fb / 1e6, fe, fcpu, a[3] / 1024;
    printf "%-22s %-7s %14.0f %14.2f %11.3f %8.1f %8.0f   (%d frames simulated)\n", "", "sampled", sc, sb / 1e6, se, scpu, b[3] / 1024, sim;
    printf "%-22s %-7s %+13.2f%% %+13.2f%% %+10.2f%% %7.1fx\n", "", "error", 100 * (sc / fc - 1), 100 * (sb / fb - 1), 100 * (se / fe - 1), fcpu / scpu;
    printf "%-22s %-7s %13.2f%% %13.2f%% %10.2f%%\n", "", "+-", sce, sbe, see;
  }'
done
