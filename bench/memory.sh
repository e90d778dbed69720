#!/usr/bin/env bash
# Benchmark (prints figures, issue 15): peak memory (maximum resident set, /usr/bin/time's %M) and
# CPU seconds of one `tbdrsim run` without images, per technique, in the three cases issue 15 bounds
# at 1 GiB:
#   atrium5   atrium:5 (about 2.4M triangles), 1920x1080, 1024 lights
#   uhd       atrium:3, 3840x2160, 1024 lights
#   multipass forward_multipass at atrium:3, 1920x1080, 1024 lights, one light per pass (its
#             textbook form: 1024 additive passes)
# Each row says whether the run stayed within 1 GiB (1,048,576 KiB).
#
# Usage: bash bench/memory.sh [--cases L] [--techniques L] [--threads N] [build-dir]
#   --cases L       comma-separated subset of atrium5,uhd,multipass (default: all three)
#   --techniques L  techniques of the atrium5 and uhd cases (default: all 13; forward_multipass at
#                   64 lights per pass there: the multipass case runs its one-light-per-pass form)
#   --threads N     threads inside each run (default 1: memory grows with per-thread scratch)
set -euo pipefail
cd "$(dirname "$0")/.."
. bench/common.sh

CASES=atrium5,uhd,multipass
TECHS=plain_forward,forward_multipass,forward_plus,forward_light_stack,clustered_forward,practical_clustered_forward,cascaded_clustered_forward,deferred,deferred_tile_store,light_prepass,tiled_deferred,clustered_deferred,visibility_buffer
THREADS=1
BUILD=build
while [ $# -gt 0 ]; do
  case "$1" in
    --cases) CASES=$2; shift 2 ;;
    --techniques) TECHS=$2; shift 2 ;;
    --threads) THREADS=$2; shift 2 ;;
    -h|--help) sed -n '2,18p' "$0"; exit 0 ;;
    -*) echo "memory.sh: unknown option $1" >&2; exit 2 ;;
    *) BUILD=$1; shift ;;
  esac
done
bench_positive_int memory.sh --threads "$THREADS"
[ -x "$BUILD/tbdrsim" ] || { echo "memory.sh: no tbdrsim in '$BUILD' (build it first)" >&2; exit 2; }
IFS=, read -r -a CASE_LIST <<< "${CASES%,}"
IFS=, read -r -a TECH_LIST <<< "${TECHS%,}"
for c in "${CASE_LIST[@]}"; do
  case "$c" in atrium5|uhd|multipass) ;; *) echo "memory.sh: unknown case '$c' (atrium5, uhd, multipass)" >&2; exit 2 ;; esac
done
bench_scratch
readonly GIB_KIB=1048576

echo "tbdrsim memory: peak resident set of one run without images, $THREADS thread(s); limit 1 GiB = $GIB_KIB KiB"
echo "build: $BUILD ($("$BUILD/tbdrsim" --version 2>/dev/null | sed "s/^tbdrsim //")); host $(hostname), $(nproc) cores, load $(cut -d' ' -f1-3 /proc/loadavg)"
printf '%-10s %-28s %-22s %12s %9s %s\n' case technique setup peak_KiB cpu_s within_1GiB

# row CASE TECHNIQUE SCENE RESOLUTION [trace options...]: generate, run, print one row.
row() {
  local case=$1 t=$2 scene=$3 res=$4; shift 4
  "$BUILD/tbdrsim" trace --technique "$t" --scene "$scene" --lights 1024 --camera entrance --resolution "$res" \
    "$@" --out "$TMP/t.trace" > /dev/null
  rm -f "$TMP/r.db"
  /usr/bin/time -f '%M %U %S' -o "$TMP/time.out" "$BUILD/tbdrsim" run --trace "$TMP/t.trace" --db "$TMP/r.db" \
    --quiet --threads "$THREADS" > /dev/null
  read -r kib user sys < "$TMP/time.out"
  awk -v c="$case" -v t="$t" -v s="$scene $res" -v k="$kib" -v u="$user" -v y="$sys" -v g="$GIB_KIB" \
    'BEGIN { printf "%-10s %-28s %-22s %12d %9.2f %s\n", c, t, s, k, u + y, (k <= g ? "yes" : "NO") }'
}

for c in "${CASE_LIST[@]}"; do
  case "$c" in
    atrium5|uhd)
      for t in "${TECH_LIST[@]}"; do
        opts=()
        [ "$t" = forward_multipass ] && opts=(--option lights_per_pass=64)
        if [ "$c" = atrium5 ]; then row "$c" "$t" atrium:5 1920x1080 "${opts[@]}"; else row "$c" "$t" atrium:3 3840x2160 "${opts[@]}"; fi
      done ;;
    multipass) row multipass forward_multipass atrium:3 1920x1080 --option lights_per_pass=1 ;;
  esac
done
