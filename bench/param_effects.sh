#!/usr/bin/env bash
# Benchmark (prints a markdown table): what every hardware parameter moves. For each parameter that
# `tbdrsim params` lists (read from the tool, so new parameters are included), six techniques on the
# atrium (detail 1, 320x180, 64 lights) replay at a low and a high value (half and twice the default
# inside the declared range; booleans both ways; choices every choice) through `tbdrsim run --set`,
# and the table gives the relative change (first to last value; for three or more choices smallest to
# largest) of frame time, DRAM bytes at the device and frame energy, each the largest over the workloads,
# the other statistic that moved most, and the direction. docs/parameter-effects.md holds a run.
# Usage: bash bench/param_effects.sh [build-dir] [jobs] [extra options of bench/param_effects.py,
#        e.g. --only '^dram\.' --resolution 640x360]
set -euo pipefail
cd "$(dirname "$0")/.."
. bench/common.sh
BUILD=${1:-build}
JOBS=${2:-2}
bench_positive_int "$0" jobs "$JOBS"
shift $(( $# < 2 ? $# : 2 ))
exec /usr/bin/python3 bench/param_effects.py --build "$BUILD" --jobs "$JOBS" "$@"
