#!/usr/bin/env bash
# Builds the libFuzzer harnesses of tests/fuzz (trace, config, sweep, glTF readers) with clang,
# AddressSanitizer and UndefinedBehaviorSanitizer, and runs each for SECONDS (default 60) on its
# seed corpus (tests/fuzz/corpus/NAME, read only; new inputs go to build-san/fuzz/NAME/corpus).
#   bash scripts/fuzz.sh [SECONDS] [NAME ...]      NAME: trace config sweep gltf (default: all)
#   bash scripts/fuzz.sh --minutes N [NAME ...]    the long run: N minutes per harness
# Prints per harness: executions, coverage (cov: edges, ft: features), corpus size and findings;
# exits 1 if any harness found a crash (its reproducer: build-san/fuzz/NAME/crash-*, also copied
# into the seed corpus tests/fuzz/corpus/NAME/finding-*, which every later run replays first:
# commit it with the fix as the regression test). CI runs `bash scripts/fuzz.sh 30` (docs/fuzzing.md).
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/sanitizer_build.sh
seconds=60
if [ "${1:-}" = "--minutes" ]; then
  minutes=${2:-}
  if ! [[ $minutes =~ ^[1-9][0-9]*$ ]]; then echo "fuzz.sh: --minutes '$minutes' is not a whole number > 0" >&2; exit 2; fi
  seconds=$((minutes * 60))
  shift 2
elif [ $# -gt 0 ]; then
  seconds=$1
  shift
fi
names=("$@")
[ ${#names[@]} -eq 0 ] && names=(trace config sweep gltf)
for n in "${names[@]}"; do
  case $n in trace|config|sweep|gltf) ;; *) echo "fuzz.sh: no harness '$n' (trace config sweep gltf)" >&2; exit 2 ;; esac
done
if ! [[ $seconds =~ ^[1-9][0-9]*$ ]]; then echo "fuzz.sh: SECONDS '$seconds' is not a whole number > 0" >&2; exit 2; fi

san_configure fuzz.sh
targets=()
for n in "${names[@]}"; do targets+=("fuzz_$n"); done
san_build "${targets[@]}"

root=$(pwd)
status=0
for n in "${names[@]}"; do
  out="$root/$san_build/fuzz/$n"
  mkdir -p "$out/corpus"
  log="$out/fuzz.log"
  # -max_len: 64 KiB, past every nesting limit (a glTF nested 15,000 deep, 30 KB, crashed the JSON
  # parser before docs/limits.md's 256) and a few times the largest seed; -rss_limit_mb: the
  # readers' declared limits keep far below.
  if (cd "$out" && "$root/$san_build/tests/fuzz/fuzz_$n" -max_total_time="$seconds" -max_len=65536 \
        -rss_limit_mb=2048 -timeout=20 -print_final_stats=1 corpus "$root/tests/fuzz/corpus/$n" >"$log" 2>&1); then
    found=0
  else
    found=1
    status=1
  fi
  execs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$log" | grep -o '[0-9]*$' || echo "?")
  last=$(grep -E '^#[0-9]+' "$log" | tail -1 || true)
  cov=$(grep -o 'cov: [0-9]*' <<<"$last" | grep -o '[0-9]*' || echo "?")
  ft=$(grep -o 'ft: [0-9]*' <<<"$last" | grep -o '[0-9]*' || echo "?")
  corpus=$(find "$out/corpus" -type f | wc -l)
  crashes=$(find "$out" -maxdepth 1 -regextype egrep -regex '.*/(crash|leak|timeout|oom)-.*' | wc -l)
  printf 'fuzz %-7s %6s s  execs %-10s cov %-6s ft %-7s corpus %-5s findings %s\n' "$n" "$seconds" "$execs" "$cov" \
    "$ft" "$corpus" "$([ $found -eq 0 ] && echo 0 || echo "$crashes (see $log)")"
  if [ $found -ne 0 ]; then
    tail -n 40 "$log" >&2
    for f in $(find "$out" -maxdepth 1 -regextype egrep -regex '.*/(crash|leak|timeout|oom)-.*'); do
      keep="tests/fuzz/corpus/$n/finding-$(sha1sum "$f" | cut -c1-16)"
      cp "$f" "$keep"
      echo "fuzz.sh: kept $f as $keep (commit it with the fix: the seed corpus is replayed first)" >&2
    done
  fi
done
exit $status
