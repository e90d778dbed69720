# Shared by the bench scripts (source it from the repository root: `. bench/common.sh`).

# bench_scratch: a fresh scratch folder in $TMP, removed when the script exits.
bench_scratch() {
  TMP=$(mktemp -d)
  trap 'rm -rf "$TMP"' EXIT
}

# bench_reference_frame DEFAULT_REPS [build-dir] [repetitions]: sets BUILD (default build), REPS
# (default DEFAULT_REPS) and a scratch TMP, and writes the benchmarks' reference frame to
# $TMP/pf.trace: plain forward on the atrium (detail 3, entrance camera) at 1920x1080, 256 lights.
bench_reference_frame() {
  BUILD=${2:-build}
  REPS=${3:-$1}
  bench_scratch
  "$BUILD/tbdrsim" trace --technique plain_forward --scene atrium:3 --lights 256 --camera entrance \
    --resolution 1920x1080 --out "$TMP/pf.trace" > /dev/null
}

# bench_positive_int SCRIPT OPTION VALUE: exits 2 with a message naming the option unless VALUE is
# a positive integer.
bench_positive_int() {
  case "$3" in ''|*[!0-9]*|0) echo "$1: $2 expects a positive integer, got '$3'" >&2; exit 2 ;; esac
}
