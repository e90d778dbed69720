#!/usr/bin/env bash
# Benchmark (prints figures): hidden surface removal against Imagination's anchor. Imagination,
# PowerVR Architecture Guide, "Hidden Surface Removal Efficiency"
# (https://docs.imgtec.com/starter-guides/powervr-architecture/html/topics/hidden-surface-removal-efficiency.html):
# in a captured frame of MadFinger Games' Shadowgun, 4.7 fragments are coloured per screen pixel
# ignoring early-Z or HSR, and 1.2 on PowerVR after HSR (75 % fewer; blended UI keeps it above 1).
# Here: plain_forward on the atrium, rasterised fragments per pixel, fragments shaded per pixel by
# a GPU without early-Z (gpu.mode=tbr isp.early_z=0: every rasterised fragment; the figure to set
# beside Shadowgun's 4.7), shaded fragments per pixel with gpu.mode=tbr (per-tile early-Z, draws in the
# trace's order: opaque in scene order, then masked, then blended back to front) and with
# gpu.mode=tbdr (tag-buffer HSR), and the ratios. The street view (outside the south facade; the
# interior behind it is submitted) at detail 4 (denser foliage) has the game-like depth
# complexity (about 3.9 per pixel); the other views are for contrast. late/TBDR is the figure to
# set beside Shadowgun's 4.7 / 1.2; TBR/TBDR shows how much per-tile early-Z already removes when
# draws come in the trace's order (opaque in scene order first, so much hidden geometry arrives
# after what hides it).
# A second table shows the TBR figure across submission orders (draw_order near_to_far, pass,
# far_to_near): early-Z removes more when near geometry comes first; a third with forward pixel
# kill windows (isp.forward_pixel_kill_window).
# Usage: bash bench/hsr_anchor.sh [build-dir] [WIDTHxHEIGHT] [scene]
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD=${1:-build}
RES=${2:-960x540}
SCENE=${3:-atrium:4}
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT
W=${RES%x*}
H=${RES#*x}
stat() {  # db scope name
  sqlite3 "$1" "SELECT value FROM stats WHERE run_id = (SELECT max(id) FROM runs) AND scope = '$2' AND name = '$3'"
}
printf "%-10s %10s %12s %12s %12s %10s %10s %10s %10s %10s\n" "view" "raster/px" "late-Z sh/px" "TBR sh/px" "TBDR sh/px" "TBR/TBDR" "late/TBDR" "late ms" "TBR ms" "TBDR ms"
for view in street entrance aisle gallery; do
  "$BUILD/tbdrsim" trace --technique plain_forward --scene "$SCENE" --camera "$view" --lights 64 --resolution "$RES" \
    --out "$TMP/$view.trace" > /dev/null
  for mode in tbr tbdr; do
    "$BUILD/tbdrsim" run --trace "$TMP/$view.trace" --db "$TMP/$mode.db" --set gpu.mode=$mode --quiet
  done
  # A GPU without early-Z (isp.early_z=0: tests after the shader) shades every rasterised fragment.
  "$BUILD/tbdrsim" run --trace "$TMP/$view.trace" --db "$TMP/late.db" --set gpu.mode=tbr --set isp.early_z=0 --quiet
  awk -v px=$((W * H)) -v view="$view" \
    -v rast="$(stat "$TMP/tbdr.db" frame/isp samples_rasterised)" \
    -v late="$(stat "$TMP/late.db" frame/tsp shader_invocations)" \
    -v tbr="$(stat "$TMP/tbr.db" frame/tsp shader_invocations)" \
    -v tbdr="$(stat "$TMP/tbdr.db" frame/tsp shader_invocations)" \
    -v late_ms="$(stat "$TMP/late.db" frame/timing frame_time_ms)" \
    -v tbr_ms="$(stat "$TMP/tbr.db" frame/timing frame_time_ms)" \
    -v tbdr_ms="$(stat "$TMP/tbdr.db" frame/timing frame_time_ms)" \
    'BEGIN { printf "%-10s %10.2f %12.2f %12.2f %12.2f %10.2f %10.2f %10.2f %10.2f %10.2f\n", view, rast / px, late / px, tbr / px, tbdr / px, tbr / tbdr, late / tbdr, late_ms, tbr_ms, tbdr_ms }'
done
printf "%-10s %10s %12.2f %12s %12.2f %10s %10.2f\n" "Shadowgun" "-" 4.7 "-" 1.2 "-" "$(awk 'BEGIN { print 4.7 / 1.2 }')"
echo "(Shadowgun: Imagination's figures, no early-Z/HSR -> PowerVR HSR; its TBR/early-Z figure is not published)"
echo
echo "TBR's per-tile early-Z depends on the submission order (street view; plain_forward draw_order):"
printf "%-12s %12s %12s %12s\n" "draw_order" "TBR shad/px" "TBDR shad/px" "TBR/TBDR"
for order in near_to_far pass far_to_near; do
  "$BUILD/tbdrsim" trace --technique plain_forward --scene "$SCENE" --camera street --lights 64 --resolution "$RES" \
    --option draw_order=$order --out "$TMP/o.trace" > /dev/null
  for mode in tbr tbdr; do
    "$BUILD/tbdrsim" run --trace "$TMP/o.trace" --db "$TMP/o$mode.db" --set gpu.mode=$mode --quiet
  done
  awk -v px=$((W * H)) -v order="$order" -v tbr="$(stat "$TMP/otbr.db" frame/tsp shader_invocations)" \
    -v tbdr="$(stat "$TMP/otbdr.db" frame/tsp shader_invocations)" \
    'BEGIN { printf "%-12s %12.2f %12.2f %12.2f\n", order, tbr / px, tbdr / px, tbr / tbdr }'
done
echo "(sorting is per sub-mesh: the depth complexity inside one sub-mesh keeps its triangle order)"
echo
echo "TBR with forward pixel kill (Arm Mali; isp.forward_pixel_kill_window primitives queued behind early-Z), street view, draw_order=pass:"
printf "%-8s %12s %14s\n" "window" "TBR shad/px" "killed/px"
"$BUILD/tbdrsim" trace --technique plain_forward --scene "$SCENE" --camera street --lights 64 --resolution "$RES" \
  --out "$TMP/f.trace" > /dev/null
for window in 0 4 16 64; do
  "$BUILD/tbdrsim" run --trace "$TMP/f.trace" --db "$TMP/fpk.db" --set gpu.mode=tbr --set isp.forward_pixel_kill_window=$window --quiet
  awk -v px=$((W * H)) -v window="$window" -v tbr="$(stat "$TMP/fpk.db" frame/tsp shader_invocations)" \
    -v killed="$(stat "$TMP/fpk.db" frame/isp forward_pixel_kill_samples)" \
    'BEGIN { printf "%-8s %12.2f %14.2f\n", window, tbr / px, killed / px }'
done
