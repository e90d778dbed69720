#!/usr/bin/env bash
# tbdrsim's DRAM model against DRAMsim3 (prints figures; docs/dram-cross-check.md): for LPDDR3-1600
# and LPDDR4-3200, four request streams (streaming reads, random reads, the DRAM traffic of a
# deferred and a forward_plus frame) exported from tbdrsim (`--memory-trace-format dramsim3`) and
# replayed by DRAMsim3's trace front end, beside tbdrsim's own figures for the same stream:
# achieved bandwidth, mean and 99th-percentile read latency, row-buffer hit rate per burst, refresh share.
# Usage: bash bench/dram_vs_dramsim3.sh DRAMSIM3_BUILD_DIR [tbdrsim-build-dir] [work-dir]
#   DRAMSIM3_BUILD_DIR holds dramsim3main (the user's build of DRAMsim3); its configs/ are read from
#   DRAMSIM3_BUILD_DIR/../configs (or $DRAMSIM3_CONFIGS).
set -euo pipefail
cd "$(dirname "$0")/.."
. bench/dram_cross_check_common.sh
DS3=${1:?usage: bench/dram_vs_dramsim3.sh DRAMSIM3_BUILD_DIR [tbdrsim-build-dir] [work-dir]}
BUILD=${2:-build}
WORK=${3:-}
[ -x "$DS3/dramsim3main" ] || { echo "dram_vs_dramsim3.sh: no dramsim3main in $DS3" >&2; exit 2; }
CONFIGS=${DRAMSIM3_CONFIGS:-$DS3/../configs}
[ -d "$CONFIGS" ] || { echo "dram_vs_dramsim3.sh: no DRAMsim3 configs/ at $CONFIGS (set DRAMSIM3_CONFIGS)" >&2; exit 2; }
if [ -z "$WORK" ]; then WORK=$(mktemp -d); trap 'rm -rf "$WORK"' EXIT; fi
mkdir -p "$WORK"
dcc_traces "$BUILD" "$WORK"

py() { /usr/bin/python3 bench/dram_cross_check.py "$@"; }

# The frames are also replayed by bench/dramsim3_replay.cpp, a front end of our own linked with the
# user's libdramsim3 (reads and writes in queues of their own, unlike dramsim3main's in-order one):
# docs/dram-cross-check.md, "Frames". Built here from DRAMsim3's src/ and its libdramsim3.so.
DS3_SRC=${DRAMSIM3_SRC:-$DS3/../src}
DS3_LIB=$(dirname "$(ls "$DS3"/libdramsim3.so "$DS3"/../libdramsim3.so 2>/dev/null | head -1)" 2>/dev/null || true)
REPLAY=""
if [ -f "$DS3_SRC/dramsim3.h" ] && [ -n "$DS3_LIB" ] && [ -f "$DS3_LIB/libdramsim3.so" ]; then
  REPLAY="$WORK/dramsim3_replay"
  g++ -O2 -std=c++17 -I"$DS3_SRC" bench/dramsim3_replay.cpp -L"$DS3_LIB" -ldramsim3 -Wl,-rpath,"$DS3_LIB" -o "$REPLAY"
else
  echo "dram_vs_dramsim3.sh: no DRAMsim3 src/dramsim3.h or libdramsim3.so beside $DS3: the split-front-end replays are skipped" >&2
fi
pct() { awk -v a="$1" -v b="$2" 'BEGIN { if (b == 0) print "-"; else printf "%+.1f", (a - b) / b * 100 }'; }

for dev in lpddr3 lpddr4; do
  dcc_device "$dev"
  ini="$WORK/$dev.ini"
  py ini "$CONFIGS/$DS3_INI" "$ini" "${DS3_SETS[@]}" other.epoch_period=1000 other.output_level=1
  echo "== $dev: DRAMsim3 $DS3_INI with ${DS3_SETS[*]}"
  echo "   tbdrsim: ${TB_DRAM[*]} ${TB_MATCH[*]}"
  printf "%-13s %-48s %12s %12s %8s\n" stream figure tbdrsim DRAMsim3 "diff %"
  for s in "${DCC_STREAMS[@]}"; do
    out="$WORK/$dev.$s.ds3"
    dcc_export "$BUILD" "$WORK" "$s" dramsim3 "$out" "${TB_DRAM[@]}" "${TB_MATCH[@]}"
    first=0
    if [ "$s" = stream ] || [ "$s" = random ]; then
      # A closed-loop benchmark: every request is ready at cycle 0 (DRAMsim3's front end issues
      # them as its queues accept, as tbdrsim's benchmark does).
      awk '{ print $1, $2, 0 }' "$out" > "$out.0" && mv "$out.0" "$out"
    else
      first=$(awk 'NR == 1 { print $3; exit }' "$out")
    fi
    last=$(awk 'END { print $3 }' "$out")
    # Simulate well past the last request: twice the tbdrsim span plus 100 us.
    span_ns=$(awk -v f="$out.tb" 'BEGIN { while ((getline l < f) > 0) { split(l, a, " "); if (a[1] == "elapsed_ns" || a[1] == "frame_ns") print a[2] } }' | head -1)
    cycles=$(awk -v l="$last" -v s="$span_ns" -v t="$TCK_NS" 'BEGIN { printf "%d", l + 2 * s / t + 100000 / t }')
    rm -rf "$out.d" && mkdir -p "$out.d"
    "$DS3/dramsim3main" "$ini" -c "$cycles" -t "$out" -o "$out.d" > "$out.d/log" 2>&1
    py dramsim3 "$out.d" "$TCK_NS" "$TRFC_CYCLES" "$first" > "$out.ds"
    # DRAMsim3 bandwidth: transactions x 32 B over first request to the epoch (1000 cycles) all were done.
    ds_bw=$(awk -v r="$(dcc_get "$out.ds" reads)" -v w="$(dcc_get "$out.ds" writes)" -v b="$BURST_BYTES" \
               -v ns="$(dcc_get "$out.ds" elapsed_ns)" 'BEGIN { printf "%.4f", (r + w) * b / ns }')
    tb_bw=$(dcc_get "$out.tb" achieved_bandwidth_gbps)
    row() { printf "%-13s %-48s %12.4g %12.4g %8s\n" "$s" "$1" "$2" "$3" "$(pct "$2" "$3")"; }
    row "bandwidth GB/s" "$tb_bw" "$ds_bw"
    row "read latency mean ns" "$(dcc_get "$out.summary" read_latency_mean_ns)" "$(dcc_get "$out.ds" read_latency_mean_ns)"
    row "read latency p99 ns" "$(dcc_get "$out.summary" read_latency_p99_ns)" "$(dcc_get "$out.ds" read_latency_p99_ns)"
    row "row hit rate per burst" "$(dcc_get "$out.tb" row_hit_rate_per_burst)" "$(dcc_get "$out.ds" row_hit_rate_per_burst)"
    row "refresh share" "$(dcc_get "$out.tb" refresh_share)" "$(dcc_get "$out.ds" refresh_share)"
    row "activates" "$(dcc_get "$out.tb" activates)" "$(dcc_get "$out.ds" activates)"
    row "transactions (32 B)" "$(dcc_get "$out.summary" request_lines)" "$(awk -v r="$(dcc_get "$out.ds" reads)" -v w="$(dcc_get "$out.ds" writes)" 'BEGIN { print r + w }')"
    if [ -n "$REPLAY" ] && [ "$s" != stream ] && [ "$s" != random ]; then
      # The same frame through the split front end: at a queue of 64 transactions (tbdrsim's 32
      # lines), and at 512, deep enough that no request waits outside DRAMsim3 (latency from the
      # request's arrival, as tbdrsim's acceptance time is).
      for q in 64 512; do
        sed "s/^trans_queue_size = .*/trans_queue_size = $q/" "$ini" > "$ini.q$q"
        rm -rf "$out.r$q" && mkdir -p "$out.r$q"
        "$REPLAY" "$ini.q$q" "$out" "$out.r$q" > "$out.r$q.kv"
      done
      row "read latency mean ns, split front end, queue 64" "$(dcc_get "$out.summary" read_latency_mean_ns)" "$(dcc_get "$out.r64.kv" read_latency_mean_ns)"
      row "read latency p99 ns, split front end, queue 64" "$(dcc_get "$out.summary" read_latency_p99_ns)" "$(dcc_get "$out.r64.kv" read_latency_p99_ns)"
      printf "%-13s %-48s %12s %12.4g\n" "$s" "mean wait outside DRAMsim3 ns, queue 64" "" \
        "$(awk -v a="$(dcc_get "$out.r64.kv" read_latency_from_arrival_mean_ns)" -v b="$(dcc_get "$out.r64.kv" read_latency_mean_ns)" 'BEGIN { print a - b }')"
      # Both tools replaying the same file open loop with deep queues (nothing waits outside either):
      # tbdrsim `dram-bench --replay` with 256-line read and write queues (as many bytes as
      # DRAMsim3's 512 transactions), as shipped (chains up to dram.max_chain_bytes) and with
      # every line its own entry (dram.max_chain_bytes=64, as DRAMsim3 queues each transaction).
      deep=(--set dram.read_queue_entries=256 --set dram.write_queue_entries=256)
      "$BUILD/tbdrsim" dram-bench "${TB_DRAM[@]}" "${TB_MATCH[@]}" "${deep[@]}" --replay "$out" > "$out.tbr"
      "$BUILD/tbdrsim" dram-bench "${TB_DRAM[@]}" "${TB_MATCH[@]}" "${deep[@]}" --set dram.max_chain_bytes=64 --replay "$out" > "$out.tbr64"
      row "read latency mean ns, both replaying, deep queues" "$(dcc_get "$out.tbr" read_latency_from_arrival_ns)" "$(dcc_get "$out.r512.kv" read_latency_from_arrival_mean_ns)"
      row "  the same, tbdrsim without burst chains" "$(dcc_get "$out.tbr64" read_latency_from_arrival_ns)" "$(dcc_get "$out.r512.kv" read_latency_from_arrival_mean_ns)"
    fi
  done
  echo
done
