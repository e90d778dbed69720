#!/usr/bin/env bash
# DRAM microbenchmarks (prints figures): a streaming read with and without refresh, a row-miss
# stream bound by tFAW / tRRD / the data bus, read/write turnaround, and each DRAM preset's energy
# per bit on a streaming read beside the memspec arithmetic. The arithmetic of each figure is in
# the comment of its test in tests/test_memory_system.cpp (which also pins it); here the tests are
# run for their printed figures. Usage: bash bench/dram_micro.sh [build-dir]
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD=${1:-build}
filter='DramTest.BandwidthBoundStreamWithinFivePercent:DramTest.StreamingWithRefresh*:DramTest.RowMissStream*'
filter+=':DramTest.ReadAfterWrite*:DramTest.PresetEnergyPerBit*'
out=$("$BUILD/tbdrsim_tests" --gtest_filter="$filter" 2>&1) || { echo "$out"; exit 1; }
echo "Test configuration: 1 GHz DRAM clock, 2 x 6.4 GB/s, tRCD 18, tRP 18, RL 15, tRAS 42, tRRD 10, tFAW 50,"
echo "tWTR 10, tRTW 4 ns; refresh tREFI 3900 ns, tRFC 130 ns when on."
echo
echo "Streaming (1 MiB, one stream per channel). Arithmetic: refresh off, the data bus: 100 %;"
echo "refresh on, each refresh idles the bus tRP + tRFC + tRCD + RL = 181 ns per tREFI 3900 ns: 95.4 %"
echo "(tRFC / tREFI alone would leave 96.7 %)."
echo "$out" | grep -E "figures.*(sequential stream|stream with refresh)" | sed 's/\[ figures  \] /  /'
echo
echo "Row-miss stream (800 reads, each a new row of the next bank). Arithmetic: one read per"
echo "max(tRRD, tFAW / 4, tRC / banks, burst) = max(10, 12.5, 7.5, 10) = 12.5 ns; tRRD 15: 15 ns;"
echo "tRRD = tFAW = 0: the data bus, 10 ns."
echo "$out" | grep -E "figures.*row-miss" | sed 's/\[ figures  \] /  /'
echo
echo "Turnaround: read after write pays tWTR + RL of idle bus, write after read tRTW (pinned exactly:"
echo "$(echo "$out" | grep -cE "^\[       OK \] DramTest.ReadAfterWrite") test passed)."
echo
echo "Energy per bit, streaming reads at full bandwidth, refresh on, against the arithmetic of the preset's own"
echo "[dram]/[energy] figures (bench/dram.sh prices them from the memspec instead): core read"
echo "+ I/O + activate / row bits + channels x active standby / bit rate + refresh_nj / tREFI / bit rate."
echo "$out" | grep -E "figures.*pJ/bit" | sed 's/\[ figures  \] /  /'
