#!/usr/bin/env bash
# Benchmark (prints figures): CPU seconds of the timing model alone (run_timing on one frame's
# work, repeated), for a trace, against a build directory's libraries. Compiles
# bench/timing_model_bench.cpp into BUILD/timing_model_bench first.
# Usage: bash bench/timing_model_bench.sh BUILD TRACE [reps]
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD=$(realpath "${1:?build dir}"); TRACE=${2:?trace}; REPS=${3:-3}
INC=$(sed -n 's/^CXX_INCLUDES = //p' "$BUILD/CMakeFiles/tbdrsim.dir/flags.make")
DEF=$(sed -n 's/^CXX_DEFINES = //p' "$BUILD/CMakeFiles/tbdrsim.dir/flags.make")
LIBS=$(sed -n 's/.*-o tbdrsim *//p' "$BUILD/CMakeFiles/tbdrsim.dir/link.txt")
if [ ! -x "$BUILD/timing_model_bench" ] || [ "$BUILD/libtbdrsim_models.a" -nt "$BUILD/timing_model_bench" ] ||
   [ bench/timing_model_bench.cpp -nt "$BUILD/timing_model_bench" ]; then
  (cd "$BUILD" && c++ -O3 -DNDEBUG -std=c++20 $DEF $INC "$OLDPWD/bench/timing_model_bench.cpp" -o timing_model_bench $LIBS)
fi
"$BUILD/timing_model_bench" "$TRACE" "$REPS"
