#!/usr/bin/env bash
# Sweep throughput: the same small sweep (tiny traces, 3 tile sizes x 4 tile memory budgets x 3
# traces = 36 points) run with -j1 and with -j2 into fresh databases; prints points per second of
# each and their ratio (goal: at least 1.8x on 2 idle cores).
#   bash bench/sweep_bench.sh [path/to/tbdrsim] [resolution]    (defaults: build/tbdrsim, 320x180)
set -euo pipefail
cd "$(dirname "$0")/.."
TBDRSIM=${1:-build/tbdrsim}
RES=${2:-320x180}
WORK=$(mktemp -d /tmp/tbdrsim_sweep_bench.XXXXXX)
trap 'rm -rf "$WORK"' EXIT

for seed in 1 2 3; do
  "$TBDRSIM" trace --technique plain_forward --scene atrium:1 --lights 64 --light-seed $seed \
    --resolution "$RES" --out "$WORK/t$seed.trace" > /dev/null
done
cat > "$WORK/bench.ini" <<'EOF'
[sweep]
name = bench
trace = t*.trace
[vary]
pls.tile_buffer_bits_per_pixel = 64..256 step 64
[zip.tile]
tiling.tile_width = 16, 32, 64
tiling.tile_height = 16, 32, 64
EOF

# Prints "points/s points seconds cores-used" of one sweep run (cores used = CPU time of the sweep
# and its workers / wall time: near 2 at -j2 when two cores are free for it).
rate() {
  local jobs=$1
  rm -f "$WORK/j$jobs.db"*
  /usr/bin/time -f "%e %U %S" -o "$WORK/time$jobs" \
    "$TBDRSIM" sweep "$WORK/bench.ini" --db "$WORK/j$jobs.db" -j "$jobs" --progress none > /dev/null
  local n
  n=$(sqlite3 "$WORK/j$jobs.db" "SELECT count(*) FROM runs WHERE status = 'ok'")
  awk -v n="$n" '{ printf "%.2f %d %.2f %.2f\n", n / $1, n, $1, ($2 + $3) / $1 }' "$WORK/time$jobs"
}

echo "sweep throughput: 36 points (plain_forward, atrium:1, 64 lights, $RES), $(nproc) cores," \
  "load average before: $(cut -d' ' -f1 /proc/loadavg)"
read -r r1 n1 s1 c1 < <(rate 1)
echo "  -j1: $n1 points in $s1 s = $r1 points/s (cores used $c1)"
read -r r2 n2 s2 c2 < <(rate 2)
echo "  -j2: $n2 points in $s2 s = $r2 points/s (cores used $c2)"
awk -v a="$r1" -v b="$r2" 'BEGIN { printf "  speedup -j2 / -j1: %.2fx (goal >= 1.8x on 2 idle cores)\n", b / a }'
if awk -v c="$c2" 'BEGIN { exit !(c < 1.6) }'; then
  echo "  note: -j2 got only $c2 cores' worth of CPU: other processes are using the machine"
fi
