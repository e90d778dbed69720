#!/usr/bin/env bash
# Benchmark (prints figures, issue 15): per technique, CPU seconds (user + sys of one `tbdrsim run`,
# median of N) and wall seconds (median of N) of the atrium frame (atrium:3, entrance camera,
# 1920x1080, 1024 lights, no images), pixels x lights simulated per CPU second, and the ratio of the
# CPU seconds to the figures stored in bench/speed_baseline.txt (below 1: faster than the baseline).
#
# Usage: bash bench/speed.sh [options] [build-dir]
#   -n N             repetitions per technique (median taken; default 3)
#   --quick          960x540 instead of 1920x1080 (for iteration; compared with the quick baseline)
#   --images         also write the images (--images DIR) and print the cost of writing them
#   --against DIR    a second build measured side by side (interleaved run by run, same load):
#                    prints both and the ratio of this build's CPU seconds to DIR's
#   --techniques L   comma-separated subset (default: all 13)
#   --multipass-lpp K  forward_multipass lights per pass (default 64, the study's batch: the
#                    technique's own default of 1 light per pass is 1024 passes, tens of minutes)
#   --record         rewrite this mode's rows of bench/speed_baseline.txt with the figures measured
#                    (with --against: DIR's figures, i.e. DIR is the baseline)
# The machine is shared and noisy: compare builds with --against rather than across days.
set -euo pipefail
cd "$(dirname "$0")/.."
. bench/common.sh

REPS=3
MODE=full
RES=1920x1080
IMAGES=no
AGAINST=
RECORD=no
LPP=64
TECHS=
BUILD=build
while [ $# -gt 0 ]; do
  case "$1" in
    -n) REPS=$2; shift 2 ;;
    --quick) MODE=quick; RES=960x540; shift ;;
    --images) IMAGES=yes; shift ;;
    --against) AGAINST=$2; shift 2 ;;
    --techniques) TECHS=$2; shift 2 ;;
    --multipass-lpp) LPP=$2; shift 2 ;;
    --record) RECORD=yes; shift ;;
    -h|--help) sed -n '2,20p' "$0"; exit 0 ;;
    -*) echo "speed.sh: unknown option $1" >&2; exit 2 ;;
    *) BUILD=$1; shift ;;
  esac
done
case "$REPS" in ''|*[!0-9]*|0) echo "speed.sh: -n expects a positive integer, got '$REPS'" >&2; exit 2 ;; esac
for b in "$BUILD" $AGAINST; do
  [ -x "$b/tbdrsim" ] || { echo "speed.sh: no tbdrsim in '$b' (build it first)" >&2; exit 2; }
done
LIGHTS=1024
BASELINE=bench/speed_baseline.txt
[ -n "$TECHS" ] || TECHS=plain_forward,forward_multipass,forward_plus,forward_light_stack,clustered_forward,practical_clustered_forward,cascaded_clustered_forward,deferred,deferred_tile_store,light_prepass,tiled_deferred,clustered_deferred,visibility_buffer
IFS=, read -r -a TECH_LIST <<< "${TECHS%,}"
bench_scratch
W=${RES%x*}
H=${RES#*x}

# measure BIN TRACE TAG: one run; appends "cpu wall" to $TMP/TAG.times.
measure() {
  local bin=$1 trace=$2 tag=$3 extra=()
  if [ "$IMAGES" = yes ]; then
    rm -rf "$TMP/img"
    extra=(--images "$TMP/img")
  fi
  /usr/bin/time -f '%U %S %e' -o "$TMP/time.out" "$bin" run --trace "$trace" --db "$TMP/$tag.db" --quiet "${extra[@]}" > /dev/null
  awk '{ printf "%.3f %.3f\n", $1 + $2, $3 }' "$TMP/time.out" >> "$TMP/$tag.times"
}
# median COLUMN FILE
median() { cut -d' ' -f"$1" "$2" | sort -g | awk '{ v[NR] = $1 } END { print (NR % 2) ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2 }'; }
# baseline_cpu TECH: the stored CPU seconds of this mode, or empty.
baseline_cpu() { [ -f "$BASELINE" ] && awk -v m="$MODE" -v t="$1" '$1 == m && $2 == t { print $3 }' "$BASELINE" || true; }

echo "tbdrsim speed: atrium:3, entrance, $RES, $LIGHTS lights, images $IMAGES, median of $REPS; forward_multipass $LPP lights per pass"
echo "build: $BUILD${AGAINST:+ (against $AGAINST, interleaved)}; host $(hostname), $(nproc) cores, load $(cut -d' ' -f1-3 /proc/loadavg)"
if [ -n "$AGAINST" ]; then
  printf '%-28s %9s %9s %9s %9s %8s %12s\n' technique cpu_s wall_s base_cpu base_wall ratio px*lights/s
else
  printf '%-28s %9s %9s %12s %9s %8s\n' technique cpu_s wall_s px*lights/s base_cpu ratio
fi
: > "$TMP/record.txt"
total=0
for t in "${TECH_LIST[@]}"; do
  opt=()
  [ "$t" = forward_multipass ] && opt=(--option "lights_per_pass=$LPP")
  "$BUILD/tbdrsim" trace --technique "$t" --scene atrium:3 --lights "$LIGHTS" --camera entrance --resolution "$RES" \
    "${opt[@]}" --out "$TMP/$t.trace" > /dev/null
  : > "$TMP/new.times"
  : > "$TMP/old.times"
  for _ in $(seq 1 "$REPS"); do
    measure "$BUILD/tbdrsim" "$TMP/$t.trace" new
    [ -n "$AGAINST" ] && measure "$AGAINST/tbdrsim" "$TMP/$t.trace" old
  done
  cpu=$(median 1 "$TMP/new.times")
  wall=$(median 2 "$TMP/new.times")
  rate=$(awk -v w="$W" -v h="$H" -v l="$LIGHTS" -v c="$cpu" 'BEGIN { printf "%.3g", (c > 0 ? w * h * l / c : 0) }')
  if [ -n "$AGAINST" ]; then
    bcpu=$(median 1 "$TMP/old.times")
    bwall=$(median 2 "$TMP/old.times")
    ratio=$(awk -v a="$cpu" -v b="$bcpu" 'BEGIN { printf "%.2f", (b > 0 ? a / b : 0) }')
    printf '%-28s %9s %9s %9s %9s %8s %12s\n' "$t" "$cpu" "$wall" "$bcpu" "$bwall" "$ratio" "$rate"
    echo "$MODE $t $bcpu $bwall" >> "$TMP/record.txt"
  else
    bcpu=$(baseline_cpu "$t")
    ratio=$(awk -v a="$cpu" -v b="$bcpu" 'BEGIN { if (b > 0) printf "%.2f", a / b; else print "-" }')
    printf '%-28s %9s %9s %12s %9s %8s\n' "$t" "$cpu" "$wall" "$rate" "${bcpu:--}" "$ratio"
    echo "$MODE $t $cpu $wall" >> "$TMP/record.txt"
  fi
  total=$(awk -v a="$total" -v b="$cpu" 'BEGIN { print a + b }')
done
echo "sum of medians: $total CPU s"
if [ "$RECORD" = yes ]; then
  {
    if [ -f "$BASELINE" ]; then
      grep -v -E "^($MODE |# $MODE:)" "$BASELINE"
    else
      echo "# bench/speed.sh baseline: mode technique cpu_seconds wall_seconds (median of N runs)"
    fi
    echo "# $MODE: recorded $(date -u +%Y-%m-%dT%H:%MZ) on $(hostname) ($(nproc) cores, shared, noisy), $RES, median of $REPS"
    cat "$TMP/record.txt"
  } > "$BASELINE.new"
  mv "$BASELINE.new" "$BASELINE"
  echo "recorded $MODE rows in $BASELINE"
fi
