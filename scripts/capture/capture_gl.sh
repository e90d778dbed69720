#!/usr/bin/env bash
# Captures one frame of an OpenGL application as Vulkan: Mesa's zink (GL on Vulkan) on lavapipe,
# headless under Xvfb, with RenderDoc's Vulkan capture layer (no other layer). Writes OUT.rdc and
# the frame's presented image OUT.final.png, prints OUT.rdc's path. Exit 2 with one line on failure.
#
# usage: capture_gl.sh OUT.rdc [--after S | --frame N] [--count N] [--timeout S] [--screen WxHxD] -- APP [ARGS...]
#   --count N    N consecutive frames, one capture each: OUT_0.rdc ... (a sequence for tbdrsim import)
#   --after S    capture the frame after S seconds (default 5; zink on lavapipe starts slowly)
#   --frame N    capture frame N (counted in presents) instead
#   --timeout S  give up S seconds after asking for the frame (default 300)
#   --screen     Xvfb's screen (default 1280x720x24); without DISPLAY the script starts its own Xvfb
#                (stopped at the end), with DISPLAY set it uses that display
# Examples:
#   scripts/capture/capture_gl.sh /work/captures/glmark2_shading.rdc -- \
#       glmark2 --size 320x240 -b shading:shading=phong:duration=60
#   scripts/capture/capture_gl.sh /work/captures/stk_race.rdc --after 100 --timeout 400 -- \
#       /usr/games/supertuxkart --no-start-screen --race-now --track=lighthouse --kart=tux --numkarts=2 \
#       --laps=1 --screensize=320x240 --windowed --disable-texture-compression --disable-dynamic-lights
#   (STK's deferred pipeline, its default, never finished a race frame on lavapipe in 10 minutes)
# The environment (set by capture_frame.py --gl, checked with glxinfo -B before the launch):
#   LIBGL_ALWAYS_SOFTWARE=1 MESA_LOADER_DRIVER_OVERRIDE=zink
#   VK_ICD_FILENAMES=/usr/share/vulkan/icd.d/lvp_icd.x86_64.json ENABLE_VULKAN_RENDERDOC_CAPTURE=1
# Packages: scripts/install_capture_deps.sh (the example applications: --examples).
set -euo pipefail
prog=capture_gl.sh
here=$(cd "$(dirname "$0")" && pwd)
die() { echo "$prog: $*" >&2; exit 2; }

[ $# -ge 3 ] || die "usage: $prog OUT.rdc [--after S | --frame N] [--timeout S] [--screen WxHxD] -- APP [ARGS...]"
out=$1
shift
case "$out" in *.rdc) ;; *) die "OUT must end in .rdc: $out" ;; esac
when=(--after 5)
count=()
timeout=300
screen=1280x720x24
while [ $# -gt 0 ] && [ "$1" != "--" ]; do
  [ $# -ge 2 ] || die "option $1 needs a value"
  case "$1" in
    --after) when=(--after "$2") ;;
    --frame) when=(--frame "$2") ;;
    --count) count=(--count "$2") ;;
    --timeout) timeout=$2 ;;
    --screen) screen=$2 ;;
    *) die "unknown option $1" ;;
  esac
  shift 2
done
[ $# -ge 2 ] || die "no application after --"
shift
[ -x /usr/bin/python3 ] || die "/usr/bin/python3 missing"
[ -d "$(dirname "$out")" ] || die "folder $(dirname "$out") does not exist"
png=${out%.rdc}.final.png
cmd=(/usr/bin/python3 "$here/capture_frame.py" "$out" --gl "${when[@]}" ${count[@]+"${count[@]}"} --timeout "$timeout" --final-png "$png" -- "$@")
if [ -z "${DISPLAY:-}" ]; then
  # our own Xvfb rather than xvfb-run: xvfb-run leaves its Xvfb running when its own clean-up fails
  # (exit 5, "problem while cleaning up temporary directory", seen twice)
  command -v Xvfb >/dev/null || die "Xvfb missing (xvfb; scripts/install_capture_deps.sh)"
  fdfile=$(mktemp)
  Xvfb -displayfd 3 -screen 0 "$screen" -nolisten tcp 3>"$fdfile" 2>/dev/null &
  xvfb=$!
  trap 'kill "$xvfb" 2>/dev/null; wait "$xvfb" 2>/dev/null; rm -f "$fdfile"' EXIT
  for _ in $(seq 100); do
    [ -s "$fdfile" ] && break
    kill -0 "$xvfb" 2>/dev/null || break
    sleep 0.1
  done
  [ -s "$fdfile" ] || die "Xvfb did not start"
  DISPLAY=:$(head -n 1 "$fdfile")
  export DISPLAY
fi
rc=0
"${cmd[@]}" || rc=$?
exit "$rc"
