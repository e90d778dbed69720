#!/usr/bin/env bash
# Reference runs for refactoring: a redesign must not change what the simulator computes.
#
#   bash bench/reference_runs.sh capture [build-dir] OUT_DIR   # run the reference set, dump every figure
#   bash bench/reference_runs.sh compare BEFORE_DIR AFTER_DIR  # name-by-name comparison, exit 1 on a difference
#
# The reference set (issue 11): all 13 techniques on the atrium (detail 3) at 640x360 with 256 lights,
# on both presets (configs/series6xt_gx6450.ini, configs/mobile_16x16_lpddr4x.ini), plus one
# plain_forward run with MSAA 4x. For each run, capture writes <technique>.<preset>.tsv: every row
# of the stats table (scope, name, value, unit), of tile_stats and of run_params, sorted. Host timings
# (scope frame/host) are left out: they are the only figures allowed to differ between two builds.
set -euo pipefail
cd "$(dirname "$0")/.."
. bench/common.sh
ROOT=$(pwd)
mode=${1:-}
case "$mode" in
  capture)
    if [ $# -eq 3 ]; then BUILD=$2; OUT=$3; else BUILD=build; OUT=${2:?usage: capture [build-dir] OUT_DIR}; fi
    case "$BUILD" in /*) BIN="$BUILD/tbdrsim" ;; *) BIN="$ROOT/$BUILD/tbdrsim" ;; esac
    [ -x "$BIN" ] || { echo "reference_runs: no binary at $BIN" >&2; exit 2; }
    mkdir -p "$OUT"
    OUT=$(cd "$OUT" && pwd)
    bench_scratch
    cp "$BIN" "$TMP/tbdrsim"  # one binary for every run, even if the build folder is rebuilt meanwhile
    BIN="$TMP/tbdrsim"
    techniques=(plain_forward forward_multipass deferred tiled_deferred clustered_deferred forward_plus
                clustered_forward practical_clustered_forward cascaded_clustered_forward
                deferred_tile_store forward_light_stack visibility_buffer light_prepass)
    dump() {  # db -> tsv
      sqlite3 -separator $'\t' "$1" "
        SELECT 'stat', scope, name, printf('%.17g', value), unit FROM stats WHERE scope <> 'frame/host'
        UNION ALL SELECT 'tile', pass, tile_x || ',' || tile_y, printf('%.17g|%.17g|%.17g', cycles, samples, dram_bytes), ''
          FROM tile_stats
        UNION ALL SELECT 'param', key, value, origin, '' FROM run_params
        ORDER BY 1, 2, 3;"
    }
    run_one() {  # technique preset config extra-trace-args...
      local t=$1 preset=$2 cfg=$3; shift 3
      "$BIN" trace --technique "$t" --scene atrium:3 --lights 256 --camera entrance \
        --resolution 640x360 "$@" --out "$TMP/$t.$preset.trace" > /dev/null
      rm -f "$TMP/r.db"
      "$BIN" run --config "$cfg" --trace "$TMP/$t.$preset.trace" --db "$TMP/r.db" --quiet
      # The trace's scratch folder differs from capture to capture: name it once for all.
      dump "$TMP/r.db" | sed "s|$TMP/|TRACES/|g" > "$OUT/$t.$preset.tsv"
      echo "captured $t.$preset ($(wc -l < "$OUT/$t.$preset.tsv") rows)"
    }
    for preset in series6xt_gx6450 mobile_16x16_lpddr4x; do
      for t in "${techniques[@]}"; do run_one "$t" "$preset" "$ROOT/configs/$preset.ini"; done
    done
    run_one plain_forward msaa4_series6xt_gx6450 "$ROOT/configs/series6xt_gx6450.ini" --samples 4
    ;;
  compare)
    A=${2:?usage: compare BEFORE_DIR AFTER_DIR}; B=${3:?usage: compare BEFORE_DIR AFTER_DIR}
    status=0
    for f in "$A"/*.tsv; do
      n=$(basename "$f")
      if [ ! -f "$B/$n" ]; then echo "MISSING in $B: $n"; status=1; continue; fi
      if ! cmp -s "$f" "$B/$n"; then
        status=1
        for kind in stat tile param; do
          d=$(diff <(grep "^$kind"$'\t' "$f") <(grep "^$kind"$'\t' "$B/$n") | grep -c '^[<>]' || true)
          [ "$d" -eq 0 ] || echo "DIFFERS: $n: $d $kind lines"
        done
        diff "$f" "$B/$n" | head -12 || true
      fi
    done
    for f in "$B"/*.tsv; do
      [ -f "$A/$(basename "$f")" ] || { echo "EXTRA in $B: $(basename "$f")"; status=1; }
    done
    runs=$(ls "$A"/*.tsv | wc -l)
    rows=$(cat "$A"/*.tsv | wc -l)
    if [ $status -eq 0 ]; then echo "identical: $runs runs, $rows rows (stats, tile rows, parameters)"; fi
    exit $status
    ;;
  *)
    sed -n 2,10p "$0"; exit 2 ;;
esac
