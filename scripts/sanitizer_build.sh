# Sourced by scripts/fuzz.sh and scripts/sanitize.sh: the one clang + AddressSanitizer +
# UndefinedBehaviorSanitizer build both use (docs/fuzzing.md).
#   san_find_clang SCRIPT   picks clang (san_cxx, san_cc; scripts/tsan.sh uses it too)
#   san_configure SCRIPT    picks clang, configures $san_build (default build-san; TBDRSIM_SAN_BUILD)
#   san_build TARGET...     builds the targets with -j2 and prints how long it took
# and exports the sanitizers' options: any report aborts (a finding), leaks included.
# Needs clang and libclang-rt (scripts/install_deps.sh installs clang-14 and libclang-rt-14-dev).

san_build=${TBDRSIM_SAN_BUILD:-build-san}
# -O1: the sanitizers' recommended level (fast enough, stacks still readable); fuzzer-no-link
# instruments every object for libFuzzer's coverage, and each harness links -fsanitize=fuzzer.
san_flags="-O1 -g -fno-omit-frame-pointer -fsanitize=address,undefined,fuzzer-no-link -fno-sanitize-recover=undefined"
export ASAN_OPTIONS=detect_leaks=1:abort_on_error=1
export UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1

# san_find_clang SCRIPT: sets san_cxx and san_cc to clang 14 (or clang), or exits 2 naming SCRIPT.
san_find_clang() {
  san_cxx=$(command -v clang++-14 || command -v clang++ || true)
  san_cc=$(command -v clang-14 || command -v clang || true)
  if [ -z "$san_cxx" ] || [ -z "$san_cc" ]; then
    echo "$1: clang not found (bash scripts/install_deps.sh installs it)" >&2
    exit 2
  fi
}

san_configure() {
  local script=$1
  san_find_clang "$script"
  cmake -S . -B "$san_build" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_COMPILER="$san_cxx" -DCMAKE_C_COMPILER="$san_cc" \
    -DCMAKE_CXX_FLAGS="$san_flags" -DCMAKE_EXE_LINKER_FLAGS="-fsanitize=address,undefined" -DTBDRSIM_FUZZ=ON >/dev/null
  san_script=$script
}

san_build() {
  local start
  start=$(date +%s)
  cmake --build "$san_build" -j2 --target "$@"
  echo "$san_script: building $* took $(( $(date +%s) - start )) s"
}
