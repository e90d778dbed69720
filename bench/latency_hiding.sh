#!/usr/bin/env bash
# Benchmark (prints figures): the latency-hiding curve. Traditional deferred (texture- and
# G-buffer-read heavy) and plain forward on the atrium at 960x540 with 256 lights, with
# usc.tasks_in_flight (resident tasks per USC) swept from 1 to 112: frame time, the USCs' cycles
# stalled on memory and the texture client's mean read latency. Time falls as tasks grow, until
# the ALU, texture-rate or DRAM bound.
# Usage: bash bench/latency_hiding.sh [build-dir]
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD=${1:-build}
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT
q() { sqlite3 "$1" "SELECT printf('%.3f', value) FROM stats WHERE run_id = (SELECT max(id) FROM runs) AND scope = '$2' AND name = '$3'"; }
printf "%-14s %-6s %-10s %-14s %-14s\n" "technique" "tasks" "frame ms" "usc stalled" "tex lat ns"
for tech in deferred plain_forward; do
  "$BUILD/tbdrsim" trace --technique "$tech" --scene atrium:3 --lights 256 --resolution 960x540 --out "$TMP/$tech.trace" > /dev/null
  for tasks in 1 2 4 8 16 32 56 112; do
    db="$TMP/$tech.$tasks.db"
    "$BUILD/tbdrsim" run --trace "$TMP/$tech.trace" --db "$db" --set usc.tasks_in_flight=$tasks --quiet
    printf "%-14s %-6s %-10s %-14s %-14s\n" "$tech" "$tasks" "$(q "$db" frame/timing frame_time_ms)" \
      "$(q "$db" frame/unit.usc stalled_cycles)" "$(q "$db" mem/client.texture avg_latency_ns)"
  done
done
