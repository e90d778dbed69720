#!/usr/bin/env bash
# Builds the test suite with clang, AddressSanitizer and UndefinedBehaviorSanitizer (build-san/,
# the same build as scripts/fuzz.sh) and runs it, or the tests matching a ctest regex.
#   bash scripts/sanitize.sh                 all tests
#   bash scripts/sanitize.sh 'Trace|Gltf'    a named subset (ctest -R)
# Leaks are reported (detect_leaks=1); any sanitizer report fails the test that triggered it.
set -euo pipefail
cd "$(dirname "$0")/.."
cxx=$(command -v clang++-14 || command -v clang++ || true)
cc=$(command -v clang-14 || command -v clang || true)
if [ -z "$cxx" ]; then echo "sanitize.sh: clang++ not found (apt install clang)" >&2; exit 2; fi
build=build-san
flags="-O1 -g -fno-omit-frame-pointer -fsanitize=address,undefined,fuzzer-no-link -fno-sanitize-recover=undefined"
cmake -S . -B "$build" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_COMPILER="$cxx" -DCMAKE_C_COMPILER="$cc" \
  -DCMAKE_CXX_FLAGS="$flags" -DCMAKE_EXE_LINKER_FLAGS="-fsanitize=address,undefined" -DTBDRSIM_FUZZ=ON >/dev/null
start=$(date +%s)
cmake --build "$build" -j2 --target tbdrsim tbdrsim_tests
echo "sanitize.sh: build took $(( $(date +%s) - start )) s"
export ASAN_OPTIONS=detect_leaks=1:abort_on_error=1
export UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
if [ $# -gt 0 ]; then
  ctest --test-dir "$build" -j2 --output-on-failure --timeout 1200 -R "$1"
else
  ctest --test-dir "$build" -j2 --output-on-failure --timeout 1200
fi
