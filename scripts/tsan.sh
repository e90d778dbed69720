#!/usr/bin/env bash
# Builds the simulator and its tests with clang and ThreadSanitizer (build-tsan/; TBDRSIM_TSAN_BUILD)
# and runs the tests of what runs on several threads (docs/fuzzing.md): the tile pool, the in-order
# merge and the WorkFeed between the functional run and the timing model, at 1, 2 and 7 threads.
#   bash scripts/tsan.sh            the thread tests (ctest regex 'Threads|WorkFeed|ThreadPool')
#   bash scripts/tsan.sh REGEX      the tests matching a ctest regex
# Any data race a test triggers fails it (halt_on_error). Not in CI: the instrumented build takes
# about 15 minutes on 2 cores; run it after changing anything threads share.
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/sanitizer_build.sh  # san_find_clang
build=${TBDRSIM_TSAN_BUILD:-build-tsan}
san_find_clang tsan.sh
cmake -S . -B "$build" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_COMPILER="$san_cxx" -DCMAKE_C_COMPILER="$san_cc" \
  -DCMAKE_CXX_FLAGS="-O1 -g -fno-omit-frame-pointer -fsanitize=thread" -DCMAKE_EXE_LINKER_FLAGS="-fsanitize=thread" >/dev/null
start=$(date +%s)
cmake --build "$build" -j2 --target tbdrsim tbdrsim_tests
echo "tsan.sh: building took $(( $(date +%s) - start )) s"
export TSAN_OPTIONS=halt_on_error=1:second_deadlock_stack=1
start=$(date +%s)
ctest --test-dir "$build" -j2 --output-on-failure --timeout 1800 -R "${1:-Threads|WorkFeed|ThreadPool}" -E '^sanitized\.'
echo "tsan.sh: the tests took $(( $(date +%s) - start )) s"
