#!/usr/bin/env bash
# Benchmark (prints figures): what more tag buffers buy. plain_forward on the atrium at 960x540
# with 64 lights, isp.tag_buffers = 1, 2, 4, 8, on four workloads:
#   pass/entrance     draws sorted opaque, masked, blended (what the study runs)
#   submesh/entrance  one draw per sub-mesh in scene order (draw_order=submesh): opaque geometry
#                     (handrails, pots) follows glass, banners and leaves
#   submesh/banners   the same from under the banners
#   submesh/street    the same outside the facade (deep interior behind it)
# Columns: frame ms; ISP busy ms (rasterisation + waits for punch-through depth resolves); USC
# busy ms; fragment shader invocations; tag flushes; resolve flushes (the ISP waited); pending
# tags removed by HSR. Model: models/isp.hpp (layers after Imagination's US 8,446,409).
# Usage: bash bench/tag_buffers.sh [build-dir] [WIDTHxHEIGHT]
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD=${1:-build}
RES=${2:-960x540}
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT
stat() {  # db scope name
  sqlite3 "$1" "SELECT value FROM stats WHERE run_id = (SELECT max(id) FROM runs) AND scope = '$2' AND name = '$3'"
}
mhz=$("$BUILD/tbdrsim" params | awk '$1 == "gpu.core_clock_mhz" { v = $2 } END { print v }')
printf "%-18s %4s %9s %9s %9s %12s %8s %8s %12s\n" "workload" "tags" "frame ms" "ISP ms" "USC ms" "invocations" "flushes" "resolves" "HSR removed"
for w in pass/entrance submesh/entrance submesh/banners submesh/street; do
  order=${w%/*}
  view=${w#*/}
  "$BUILD/tbdrsim" trace --technique plain_forward --scene atrium:3 --camera "$view" --lights 64 --resolution "$RES" \
    --option draw_order="$order" --out "$TMP/w.trace" > /dev/null
  for n in 1 2 4 8; do
    db="$TMP/$order.$view.$n.db"
    "$BUILD/tbdrsim" run --trace "$TMP/w.trace" --db "$db" --set isp.tag_buffers=$n --quiet
    awk -v w="$w" -v n=$n -v mhz="$mhz" \
      -v ms="$(stat "$db" frame/timing frame_time_ms)" \
      -v isp="$(stat "$db" frame/unit.isp busy_cycles)" \
      -v usc="$(stat "$db" frame/unit.usc busy_cycles)" \
      -v inv="$(stat "$db" frame/tsp shader_invocations)" \
      -v fl="$(stat "$db" frame/isp tag_flushes)" \
      -v rf="$(stat "$db" frame/isp resolve_flushes)" \
      -v hsr="$(stat "$db" frame/isp hsr_removed_samples)" \
      'BEGIN { printf "%-18s %4d %9.3f %9.3f %9.3f %12d %8d %8d %12d\n", w, n, ms, isp / mhz / 1000, usc / mhz / 1000, inv, fl, rf, hsr }'
  done
done
