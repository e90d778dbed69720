#!/usr/bin/env bash
# DRAM presets against their memspecs (prints figures): for every shipped DRAM preset, the
# bandwidth efficiency and energy per bit of a streaming and a random read microbenchmark
# (models/dram_microbench) beside the timing arithmetic and the memspec's figures (DRAMPower's
# formulas on the memspec's currents, models/dram_memspec); then the timing microbenchmarks of
# bench/dram_micro.sh (refresh, tFAW/tRRD, turnaround). The arithmetic is in the comments of
# tests/test_dram_presets.cpp, which also pins it. Usage: bash bench/dram.sh [build-dir]
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD=${1:-build}
out=$("$BUILD/tbdrsim_tests" --gtest_filter='DramMemspec.*:DramPresets.*:DramBankGroups.*:DramPowerDown.*' 2>&1) || { echo "$out"; exit 1; }
echo "Each preset: 4 MiB read as a stream and 16384 random 64 B lines from 1 GiB, one in-order read"
echo "stream per channel, refresh on. Timing arithmetic of the stream: 1 - (tRP + tRFC + tRCD + RL) / tREFI"
echo "(with bank groups: x burst / tCCD_L for lines of one group .. x 2 burst / (tCCD_L + burst) for lines"
echo "alternating between groups, since a 64 B line's two bursts stay tCCD_L apart). Memspec figures: read + I/O"
echo "+ activate / bits per activate + dies x active standby / bit rate + dies x refresh / tREFI / bit"
echo "rate, the random bit rate being one line per max(tRRD, tFAW / 4, tRC / banks, burst)."
echo
echo "$out" | grep -E "figures" | sed 's/\[ figures  \] /  /'
echo
echo "$(echo "$out" | grep -cE '^\[       OK \]') of $(echo "$out" | grep -cE '^\[ RUN      \]') DRAM preset tests passed (memspec arithmetic, bank groups tCCD_L / tCCD_S, power-down and tXP)."
echo
bash bench/dram_micro.sh "$BUILD"
