#!/usr/bin/env bash
# Benchmark (prints figures): the on-chip cliff. Traditional deferred on the atrium at 1920x1080
# with 256 lights, its G-buffer pass widened one 32-bit target at a time (96 .. 288 bits per pixel
# of color targets), on the default GPU (128 bits per pixel on chip) and with 256 bits per pixel,
# beside the GX6250 measurements of Imagination, PowerVR Performance Recommendations, "On-Chip Memory Performance" (ms per frame: 20, 21, 23, 24, 28, 29, 39).
# Usage: bash bench/onchip_cliff.sh [build-dir]
set -euo pipefail
cd "$(dirname "$0")/.."
. bench/common.sh
BUILD=${1:-build}
bench_scratch
gx6250=(20 21 23 24 28 29 39)
layout="rgba8,rgba8"
printf "%-12s %-50s %-16s %-16s %-10s\n" "bits/pixel" "G-buffer" "ms @128 on chip" "ms @256 on chip" "GX6250 ms"
for k in 3 4 5 6 7 8 9; do
  # k 32-bit G-buffer targets (albedo, normal, then extra targets that only cost bandwidth).
  if [ "$k" -le 8 ]; then
    layout=$(printf 'rgba8%.0s,' $(seq 1 $k) | sed 's/,$//')
  else  # at most 8 targets: 7 x rgba8 + one 64-bit rgba16f = 288 bits
    layout="rgba8,rgba8,rgba8,rgba8,rgba8,rgba8,rgba8,rgba16f"
  fi
  "$BUILD/tbdrsim" trace --technique deferred --scene atrium:3 --lights 256 --resolution 1920x1080 \
    --option gbuffer="$layout" --out "$TMP/d$k.trace" > /dev/null
  ms=()
  for bits in 128 256; do
    "$BUILD/tbdrsim" run --trace "$TMP/d$k.trace" --db "$TMP/c$bits.db" --set pls.tile_buffer_bits_per_pixel=$bits --quiet
    ms+=("$(sqlite3 "$TMP/c$bits.db" "SELECT printf('%.2f', value) FROM stats WHERE run_id = (SELECT max(id) FROM runs) AND scope = 'frame/timing' AND name = 'frame_time_ms'")")
  done
  printf "%-12s %-50s %-16s %-16s %-10s\n" "$((32 * k))" "$layout" "${ms[0]}" "${ms[1]}" "${gx6250[$((k - 3))]}"
done
