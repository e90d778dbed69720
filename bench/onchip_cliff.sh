#!/usr/bin/env bash
# Benchmark (prints figures): the on-chip cliff, beside Imagination's GX6250 measurements
# (PowerVR Performance Recommendations, "On-Chip Memory Performance": the PowerVR SDK's Deferred
# Shading example modified to keep growing G-buffers on chip; ms per frame 20, 21, 23, 24, 28, 29,
# 39 for 96 .. 288 bits per pixel, depth separate; 256 bits on chip).
# Here: deferred with gbuffer_storage=onchip (one render pass with subpasses: colour stored, the
# G-buffer transient, the light volumes reading it by framebuffer fetch) on the atrium, the colour
# target plus 2 .. 7 G-buffer targets (96 .. 288 bits per pixel of colour-like storage; the 288-bit
# layout ends in one rgba16f target because a shader writes at most 8 outputs), on the GX6250 preset
# (configs/series6xt_gx6250.ini: 2 USCs, 256 bits on chip) under each pls.over_budget policy.
# The columns "step" are the change from the row above (split_render, the default); "x" is the
# last step over the mean of the earlier steps.
# Usage: bash bench/onchip_cliff.sh [build-dir] [WIDTHxHEIGHT] [scene] [lights]
set -euo pipefail
cd "$(dirname "$0")/.."
. bench/common.sh
BUILD=${1:-build}
RES=${2:-960x540}
SCENE=${3:-atrium:2}
LIGHTS=${4:-256}
bench_scratch
gx6250=(20 21 23 24 28 29 39)
ms() {  # db
  sqlite3 "$1" "SELECT printf('%.4f', value) FROM stats WHERE run_id = (SELECT max(id) FROM runs) AND scope = 'frame/timing' AND name = 'frame_time_ms'"
}
echo "deferred gbuffer_storage=onchip, $SCENE, $RES, $LIGHTS lights, configs/series6xt_gx6250.ini"
printf "%-6s %-46s %14s %10s %10s %14s %10s %10s\n" "bits" "G-buffer targets (+ colour rgba8)" "split_render" "step" "spill" "smaller_tiles" "GX6250" "GX step"
prev=""
steps=()
for k in 2 3 4 5 6 7 8; do
  if [ "$k" -le 7 ]; then
    layout=$(printf 'rgba8%.0s,' $(seq 1 "$k") | sed 's/,$//')
  else
    layout="rgba8,rgba8,rgba8,rgba8,rgba8,rgba8,rgba16f"
  fi
  "$BUILD/tbdrsim" trace --technique deferred --scene "$SCENE" --lights "$LIGHTS" --resolution "$RES" \
    --option gbuffer="$layout" --option gbuffer_storage=onchip --out "$TMP/d.trace" > /dev/null
  row=()
  for policy in split_render spill smaller_tiles; do
    "$BUILD/tbdrsim" run --trace "$TMP/d.trace" --config configs/series6xt_gx6250.ini \
      --set pls.over_budget=$policy --db "$TMP/$policy.db" --quiet
    row+=("$(ms "$TMP/$policy.db")")
  done
  step="-"
  if [ -n "$prev" ]; then
    step=$(awk -v a="${row[0]}" -v b="$prev" 'BEGIN { printf "%+.4f", a - b }')
    steps+=("$step")
  fi
  i=$((k - 2))
  gstep="-"
  [ "$i" -gt 0 ] && gstep=$(printf "%+d" $((gx6250[i] - gx6250[i - 1])))
  printf "%-6s %-46s %14s %10s %10s %14s %10s %10s\n" "$((32 * (k + 1)))" "$layout" "${row[0]}" "$step" "${row[1]}" "${row[2]}" "${gx6250[$i]}" "$gstep"
  prev=${row[0]}
done
last=${steps[${#steps[@]}-1]}
mean=$(printf '%s\n' "${steps[@]:0:${#steps[@]}-1}" | awk '{ s += $1 } END { printf "%.4f", s / NR }')
awk -v l="$last" -v m="$mean" 'BEGIN { printf "last step %+.4f ms = %.1f x the mean earlier step (%+.4f ms); GX6250: +10 ms = 5.6 x (+1.8 ms)\n", l, l / m, m }'
