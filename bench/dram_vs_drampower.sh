#!/usr/bin/env bash
# tbdrsim's DRAM energy against DRAMPower (prints figures; docs/dram-cross-check.md): the DRAM
# command stream of four request streams (streaming reads, random reads, the DRAM traffic of a
# deferred and a forward_plus frame), exported from tbdrsim (`--memory-trace-format drampower`) and
# priced by DRAMPower, beside tbdrsim's own DRAM energy for the same run, per command class
# (ACT/PRE, RD, WR, REF, background) and in total (core: tbdrsim's I/O energy and DRAMPower's
# interface energy are printed apart).
#   LPDDR4-3200: DRAMPower 5 (its drampower_cli, the CSV trace as exported, one rank per channel)
#     on the memspec MICRON_6Gb_LPDDR4-3200_32bit_A written below from the memspec's figures.
#   LPDDR3-1600: DRAMPower 5 has no LPDDR3 model; given DRAMPOWER4_DIR (a build of DRAMPower 4.x,
#     the last with LPDDR3 and its XML memspecs), each channel's commands converted to its
#     "cycle,CMD,bank" trace and priced on memspecs/MICRON_4Gb_LPDDR3-1600_32bit_A.xml (the die of
#     tbdrsim's default preset).
# Usage: bash bench/dram_vs_drampower.sh DRAMPOWER_BUILD_DIR [DRAMPOWER4_DIR] [tbdrsim-build-dir] [work-dir]
#   DRAMPOWER_BUILD_DIR holds bin/drampower_cli (DRAMPower 5 configured with -DDRAMPOWER_BUILD_CLI=ON).
set -euo pipefail
cd "$(dirname "$0")/.."
. bench/dram_cross_check_common.sh
DP=${1:?usage: bench/dram_vs_drampower.sh DRAMPOWER_BUILD_DIR [DRAMPOWER4_DIR] [tbdrsim-build-dir] [work-dir]}
DP4=${2:-}
BUILD=${3:-build}
WORK=${4:-}
CLI=$DP/bin/drampower_cli
[ -x "$CLI" ] || { echo "dram_vs_drampower.sh: no bin/drampower_cli in $DP" >&2; exit 2; }
if [ -n "$DP4" ] && [ ! -x "$DP4/drampower" ]; then echo "dram_vs_drampower.sh: no drampower in $DP4" >&2; exit 2; fi
if [ -z "$WORK" ]; then WORK=$(mktemp -d); trap 'rm -rf "$WORK"' EXIT; fi
mkdir -p "$WORK"
dcc_traces "$BUILD" "$WORK"
py() { /usr/bin/python3 bench/dram_cross_check.py "$@"; }
pct() { awk -v a="$1" -v b="$2" 'BEGIN { if (b == 0) print "-"; else printf "%+.1f", (a - b) / b * 100 }'; }

# MICRON_6Gb_LPDDR4-3200_32bit_A (DRAMSys / DRAMPower memspec; the figures tbdrsim's
# models/dram_memspec.cpp transcribes): one x16 die, currents in A, timings in cycles of 0.625 ns.
# One rank per tbdrsim channel (2). The impedances only feed DRAMPower's interface model, which
# is not compared (placeholders as in DRAMPower's own test memspec).
cat > "$WORK/lpddr4_3200.json" <<'JSON'
{ "memspec": {
  "memoryId": "MICRON_6Gb_LPDDR4-3200_32bit_A x16 channel", "memoryType": "LPDDR4",
  "memarchitecturespec": { "nbrOfChannels": 1, "nbrOfColumns": 1024, "nbrOfRows": 32768, "width": 16,
    "burstLength": 16, "maxBurstLength": 16, "dataRate": 2, "nbrOfBankGroups": 1, "nbrOfBanks": 8,
    "nbrOfRanks": 2, "nbrOfDevices": 1 },
  "mempowerspec": { "vdd1": 1.8, "idd01": 3.5e-3, "idd2n1": 2.0e-3, "idd3n1": 2.25e-3, "idd4r1": 2.25e-3,
    "idd4w1": 2.25e-3, "idd51": 10.0e-3, "idd5pb1": 0, "idd61": 0, "idd2p1": 1.2e-3, "idd3p1": 1.2e-3,
    "vdd2": 1.1, "idd02": 45.0e-3, "idd2n2": 27.0e-3, "idd3n2": 30.0e-3, "idd4r2": 275.0e-3, "idd4w2": 210.0e-3,
    "idd52": 90.0e-3, "idd5pb2": 0, "idd62": 0, "idd2p2": 3.0e-3, "idd3p2": 9.0e-3, "vddq": 1.1 },
  "memtimingspec": { "tCK": 0.625e-9, "CKE": 12, "ESCKE": 3, "CMDCKE": 3, "RAS": 68, "RCD": 29, "RL": 28,
    "REFM": 1, "REFI": 6246, "REFIpb": 780, "RFCpb": 224, "RFCab": 448, "RPpb": 29, "RPab": 34, "RCpb": 97,
    "RCab": 102, "PPD": 4, "FAW": 64, "RRD": 16, "CCD": 8, "CCDMW": 32, "RPST": 1, "DQSCK": 6, "RTP": 12,
    "WL": 14, "DQSS": 1, "DQS2DQ": 2, "WR": 29, "WPRE": 2, "WTR": 16, "XP": 12, "SR": 24, "XSR": 460, "RTRS": 1 },
  "bankwisespec": { "factRho": 1.0, "factSigma": 1.0, "pasrMode": 0, "hasPASR": false },
  "memimpedancespec": { "C_total_ck": 1.0e-12, "C_total_cb": 1.0e-12, "C_total_rb": 1.0e-12, "C_total_wb": 1.0e-12,
    "C_total_dqs": 1.0e-12, "R_eq_ck": 1.0e6, "R_eq_cb": 1.0e6, "R_eq_rb": 1.0e6, "R_eq_wb": 1.0e6, "R_eq_dqs": 1.0e6 }
} }
JSON

row() { printf "%-13s %-22s %14.5g %14.5g %8s\n" "$1" "$2" "$3" "$4" "$(pct "$3" "$4")"; }
compare() {  # STREAM TBFILE DPFILE
  local tb=$2 dp=$3 g
  g() { dcc_get "$@"; }
  row "$1" "ACT/PRE pJ" "$(g "$tb" energy_activate_pj)" "$(g "$dp" act_pre_pj)"
  row "$1" "RD pJ" "$(g "$tb" energy_read_pj)" "$(g "$dp" rd_pj)"
  row "$1" "WR pJ" "$(g "$tb" energy_write_pj)" "$(g "$dp" wr_pj)"
  row "$1" "REF pJ" "$(g "$tb" energy_refresh_pj)" "$(g "$dp" ref_pj)"
  row "$1" "background pJ" "$(g "$tb" energy_background_pj)" "$(g "$dp" background_pj)"
  row "$1" "core total pJ" "$(awk -v a="$(g "$tb" energy_pj)" -v b="$(g "$tb" energy_io_pj)" 'BEGIN { print a - b }')" "$(g "$dp" core_total_pj)"
  printf "%-13s %-22s %14.5g %14.5g %8s\n" "$1" "I/O (not compared) pJ" "$(g "$tb" energy_io_pj)" "$(g "$dp" interface_pj 2>/dev/null || echo 0)" ""
}

for dev in lpddr4 lpddr3; do
  dcc_device "$dev"
  if [ "$dev" = lpddr3 ] && [ -z "$DP4" ]; then echo "== lpddr3: skipped (no DRAMPOWER4_DIR)"; continue; fi
  echo "== $dev: tbdrsim ${TB_DRAM[*]:-(default preset)}"
  printf "%-13s %-22s %14s %14s %8s\n" stream figure tbdrsim DRAMPower "diff %"
  for s in "${DCC_STREAMS[@]}"; do
    out="$WORK/$dev.$s.dp.csv"
    dcc_export "$BUILD" "$WORK" "$s" drampower "$out" "${TB_DRAM[@]}"
    if [ "$dev" = lpddr4 ]; then
      # DRAMPower 5.1's CLI once died with SIGSEGV on a frame trace and priced the same file on a
      # second try (its CSV reader parses on a thread): one retry.
      "$CLI" "$out" "$WORK/lpddr4_3200.json" --json "$out.json" > "$out.log" 2>&1 ||
        "$CLI" "$out" "$WORK/lpddr4_3200.json" --json "$out.json" > "$out.log" 2>&1
      py drampower5 "$out.json" > "$out.dp"
    else
      # DRAMPower 4 prices one rank: one trace per channel (rank), "cycle,CMD,bank", REFA -> REF.
      logs=()
      for ch in $(awk -F, '$2 != "END" { print $3 }' "$out" | sort -u); do
        awk -F, -v c="$ch" '$2 == "END" { print $1 ",END,0"; next } $3 == c { cmd = $2; if (cmd == "REFA") cmd = "REF"; print $1 "," cmd "," $5 }' \
          "$out" > "$out.ch$ch"
        "$DP4/drampower" -m "$DP4/memspecs/MICRON_4Gb_LPDDR3-1600_32bit_A.xml" -c "$out.ch$ch" > "$out.ch$ch.log" 2>&1
        logs+=("$out.ch$ch.log")
      done
      py drampower4 "${logs[@]}" > "$out.dp"
    fi
    compare "$s" "$out.tb" "$out.dp"
  done
  echo
done
