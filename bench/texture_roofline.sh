#!/usr/bin/env bash
# Benchmark (prints figures): the texture-bound roofline. One full-screen triangle at 1024x1024
# shaded with 16 bilinear fetches and A ALU ops per fragment (no lights, no texture addresses: the
# fetches read on-chip-sized data, so memory never binds), A swept so the ALU ops : filtered texels
# ratio crosses the knee. Printed beside the two bounds of the default GPU:
#   texture: pixels x 16 filtered texels / (texture.units x texture.texels_per_clock)
#   ALU:     pixels x A / (usc.count x usc.lanes x usc.alu_ops_per_lane_per_clock)
# The knee is where they meet: A / 16 = ALU rate / texture rate (128 / 8 = 16 ops per filtered
# texel on the default GPU); a second column set with texture.units doubled moves it to 8.
# Usage: bash bench/texture_roofline.sh [build-dir]
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD=${1:-build}
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT
W=1024
H=1024
FETCHES=16
PIXELS=$((W * H))
write_trace() {  # $1 = ALU ops per fragment, $2 = output
  cat > "$2" <<EOF
tbdrsim-trace 1
scene atrium detail=1
frame width=$W height=$H samples=1
camera eye=0,1.7,0 target=1,1.7,0 up=0,1,0 fov_y_deg=60 near=0.1 far=40
shader roofline alu_ops=$1 tex_fetches=$FETCHES varyings=2 light_alu_ops=0 light_source=none color_outputs=1
pipeline p shader=roofline depth_test=no depth_write=no blend=off cull=none
pass main
  attachment color format=rgba8 samples=1 load=dont_care store=store usage=color
  draw fullscreen pipeline=p
end
EOF
}
cycles() {  # $1 = trace, rest = --set overrides
  local trace=$1
  shift
  local db="$TMP/r.db"
  rm -f "$db"
  "$BUILD/tbdrsim" run --trace "$trace" --db "$db" --quiet "$@"
  sqlite3 "$db" "SELECT printf('%.0f', value) FROM stats WHERE scope = 'frame/timing' AND name = 'frame_cycles'"
}
printf "%-10s %-14s | %-12s %-12s %-12s | %-12s %-12s %-12s\n" "ALU ops" "ops/filt.texel" \
  "cycles" "tex bound" "ALU bound" "cycles 4TPU" "tex bound" "ALU bound"
for A in 16 64 96 128 160 192 224 256 320 384 512 1024; do
  write_trace "$A" "$TMP/a$A.trace"
  c2=$(cycles "$TMP/a$A.trace")
  c4=$(cycles "$TMP/a$A.trace" --set texture.units=4)
  # Default GPU: 2 units x 4 filtered texels, 4 USCs x 16 lanes x 2 ops.
  tex2=$((PIXELS * FETCHES / 8))
  tex4=$((PIXELS * FETCHES / 16))
  alu=$((PIXELS * A / 128))
  printf "%-10s %-14s | %-12s %-12s %-12s | %-12s %-12s %-12s\n" "$A" "$(awk -v a=$A -v f=$FETCHES 'BEGIN{printf "%.2f", a/f}')" \
    "$c2" "$tex2" "$alu" "$c4" "$tex4" "$alu"
done
