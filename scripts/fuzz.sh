#!/usr/bin/env bash
# Builds the libFuzzer harnesses of tests/fuzz (trace, config, sweep, glTF readers) with clang,
# AddressSanitizer and UndefinedBehaviorSanitizer, and runs each for SECONDS (default 60) on its
# seed corpus (tests/fuzz/corpus/NAME, read only; new inputs go to build-san/fuzz/NAME/corpus).
#   bash scripts/fuzz.sh [SECONDS] [NAME ...]      NAME: trace config sweep gltf (default: all)
# Prints per harness: executions, coverage (cov: edges, ft: features), corpus size and findings;
# exits 1 if any harness found a crash (its reproducer: build-san/fuzz/NAME/crash-*).
# Needs clang and libclang_rt.fuzzer (Debian 12: clang-14 or clang, which pull in libclang-rt-14-dev).
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:-60}
shift || true
names=("$@")
[ ${#names[@]} -eq 0 ] && names=(trace config sweep gltf)

cxx=$(command -v clang++-14 || command -v clang++ || true)
cc=$(command -v clang-14 || command -v clang || true)
if [ -z "$cxx" ]; then echo "fuzz.sh: clang++ not found (apt install clang)" >&2; exit 2; fi
build=build-san
flags="-O1 -g -fno-omit-frame-pointer -fsanitize=address,undefined,fuzzer-no-link -fno-sanitize-recover=undefined"
cmake -S . -B "$build" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_COMPILER="$cxx" -DCMAKE_C_COMPILER="$cc" \
  -DCMAKE_CXX_FLAGS="$flags" -DCMAKE_EXE_LINKER_FLAGS="-fsanitize=address,undefined" -DTBDRSIM_FUZZ=ON >/dev/null
targets=()
for n in "${names[@]}"; do targets+=("fuzz_$n"); done
start=$(date +%s)
cmake --build "$build" -j2 --target "${targets[@]}"
echo "fuzz.sh: build took $(( $(date +%s) - start )) s"

export ASAN_OPTIONS=detect_leaks=1:abort_on_error=1
export UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
status=0
for n in "${names[@]}"; do
  out="$build/fuzz/$n"
  mkdir -p "$out/corpus"
  log="$out/fuzz.log"
  # -max_len: a few times the largest seed; -rss_limit_mb: the readers' declared limits keep far below.
  if (cd "$out" && "../../tests/fuzz/fuzz_$n" -max_total_time="$seconds" -max_len=16384 -rss_limit_mb=2048 \
        -timeout=20 -print_final_stats=1 corpus "../../../tests/fuzz/corpus/$n" >"fuzz.log" 2>&1); then
    found=0
  else
    found=1
    status=1
  fi
  execs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$log" | grep -o '[0-9]*$' || echo "?")
  last=$(grep -E '^#[0-9]+' "$log" | tail -1 || true)
  cov=$(grep -o 'cov: [0-9]*' <<<"$last" | grep -o '[0-9]*' || echo "?")
  ft=$(grep -o 'ft: [0-9]*' <<<"$last" | grep -o '[0-9]*' || echo "?")
  corpus=$(ls "$out/corpus" | wc -l)
  crashes=$(ls "$out" | grep -c -E '^(crash|leak|timeout|oom)-' || true)
  printf 'fuzz %-7s %6s s  execs %-10s cov %-6s ft %-7s corpus %-5s findings %s\n' "$n" "$seconds" "$execs" "$cov" "$ft" "$corpus" \
    "$([ $found -eq 0 ] && echo 0 || echo "$crashes (see $log)")"
done
exit $status
