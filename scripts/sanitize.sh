#!/usr/bin/env bash
# Builds unit tests with clang, AddressSanitizer and UndefinedBehaviorSanitizer (build-san/, the
# same build as scripts/fuzz.sh) and runs them (docs/fuzzing.md):
#   bash scripts/sanitize.sh --subset        the named subset CI runs: the event kernel and reader
#                                            tests, built with the reader libraries only
#                                            (tbdrsim_reader_tests, tests/fuzz/CMakeLists.txt)
#   bash scripts/sanitize.sh                 the whole suite (the whole simulator instrumented)
#   bash scripts/sanitize.sh 'Trace|Gltf'    the whole suite's tests matching a ctest regex
# Leaks are reported (detect_leaks=1); any sanitizer report fails the test that triggered it.
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/sanitizer_build.sh
san_configure sanitize.sh
if [ "${1:-}" = "--subset" ]; then
  san_build tbdrsim_reader_tests
  start=$(date +%s)
  ctest --test-dir "$san_build" -j2 --output-on-failure -R '^sanitized\.'
  echo "sanitize.sh: the subset's tests took $(( $(date +%s) - start )) s"
  exit 0
fi
san_build tbdrsim tbdrsim_tests
# Sanitized code runs several times slower than a Release build: each test gets 1200 s, not 300 s.
if [ $# -gt 0 ]; then
  ctest --test-dir "$san_build" -j2 --output-on-failure --timeout 1200 -R "$1" -E '^sanitized\.'
else
  ctest --test-dir "$san_build" -j2 --output-on-failure --timeout 1200 -E '^sanitized\.'
fi
