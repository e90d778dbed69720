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
#        bash bench/tag_buffers.sh [build-dir] reference
# The second form prints the reference set (every technique, atrium:1 entrance, 320x180, 32 lights,
# as TagBuffersReferenceSet runs it) with 1, 2, 4 tag buffers: tag flushes, ISP busy cycles and
# frame cycles (docs/hsr-and-tag-buffers.md, "Frame cycles and the order of DRAM traffic").
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD=${1:-build}
RES=${2:-960x540}
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT
stat() {  # db scope name
  sqlite3 "$1" "SELECT value FROM stats WHERE run_id = (SELECT max(id) FROM runs) AND scope = '$2' AND name = '$3'"
}
if [ "$RES" = reference ]; then
  printf "%-28s %-20s %-26s %s\n" "technique" "flushes 1/2/4" "ISP busy cycles 1/2/4" "frame cycles 1/2/4"
  for t in $("$BUILD/tbdrsim" trace --list | awk '/^[a-z_]+:/ { sub(":", "", $1); print $1 }'); do
    "$BUILD/tbdrsim" trace --technique "$t" --scene atrium:1 --camera entrance --lights 32 --resolution 320x180 \
      --out "$TMP/r.trace" > /dev/null
    fl="" isp="" frame=""
    for n in 1 2 4; do
      db="$TMP/r.$t.$n.db"
      "$BUILD/tbdrsim" run --trace "$TMP/r.trace" --db "$db" --set isp.tag_buffers=$n --quiet
      fl="$fl/$(stat "$db" frame/isp tag_flushes | awk '{ printf "%.0f", $1 }')"
      isp="$isp/$(stat "$db" frame/unit.isp busy_cycles | awk '{ printf "%.0f", $1 }')"
      frame="$frame/$(stat "$db" frame/timing frame_cycles | awk '{ printf "%.0f", $1 }')"
    done
    printf "%-28s %-20s %-26s %s\n" "$t" "${fl#/}" "${isp#/}" "${frame#/}"
  done
  exit 0
fi
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
