# Shared by bench/dram_vs_dramsim3.sh and bench/dram_vs_drampower.sh (source it from the repository
# root): the two DRAMs checked, the four request streams and the tbdrsim runs that export them.
# docs/dram-cross-check.md explains every setting.

# dcc_device lpddr3|lpddr4: sets
#   TB_DRAM     tbdrsim --config argument of the DRAM (configs/crosscheck/, beside the default GPU)
#   TB_MATCH    further --config arguments matching tbdrsim's timing to the DRAMsim3 config (timing runs only)
#   DS3_INI     the DRAMsim3 config it starts from (in DRAMsim3's configs/) and DS3_SETS the keys changed
#   TCK_NS, TRFC_CYCLES, TRFC_NS, BURST_BYTES
dcc_device() {
  case "$1" in
    lpddr3)
      # The default preset, LPDDR3-1600 2x32 (one MICRON_4Gb_LPDDR3-1600_32bit_A die per channel),
      # and for the timing runs DRAMsim3's timings (configs/crosscheck/*.ini say why).
      TB_DRAM=(--config configs/crosscheck/lpddr3_1600.ini)
      TB_MATCH=(--config configs/crosscheck/lpddr3_1600_dramsim3_timing.ini)
      DS3_INI=LPDDR3_8Gb_x32_1600.ini
      # Two 32-bit channels of one x32 die each (the stock config: one 64-bit channel of two dies),
      # one rank, tbdrsim's address mapping (row | bank | channel | 4 KiB row), the refresh interval
      # under the key DRAMsim3 reads (the stock file spells it REFI, which DRAMsim3 ignores, falling
      # back to 7800 cycles), a read queue of 32 transactions: with DRAMsim3's per-bank command
      # queues (8 each) behind it, as many reads in flight as tbdrsim's 32-line queue (64 bursts)
      # holds (docs/dram-cross-check.md: 68 vs 67 per channel on the random stream; 64 gives ~101).
      DS3_SETS=(system.channels=2 system.bus_width=32 system.channel_size=1024
                system.address_mapping=rorabgbachco timing.tREFI=3120 system.trans_queue_size=32)
      TCK_NS=1.25 TRFC_CYCLES=168 TRFC_NS=210 BURST_BYTES=32
      ;;
    lpddr4)
      # LPDDR4-3200 2x16: one MICRON_6Gb_LPDDR4-3200_32bit_A x16 die per channel, its memspec's
      # timings and energies (configs/crosscheck/lpddr4_3200_x16.ini has the arithmetic).
      TB_DRAM=(--config configs/crosscheck/lpddr4_3200_x16.ini)
      TB_MATCH=()
      # DRAMsim3 has no LPDDR4-3200 config: configs/LPDDR4_8Gb_x16_2400.ini with the same memspec
      # timings in cycles at 0.625 ns, 8 banks in one group (LPDDR4 has no bank groups; the stock
      # file has 2 x 4 with tCCD_L 6), tCCD 8 (BL16 on the bus), two 16-bit channels of one die,
      # one rank, tbdrsim's mapping (row | bank | channel | 2 KiB row), 32-transaction queues (as for LPDDR3).
      DS3_INI=LPDDR4_8Gb_x16_2400.ini
      DS3_SETS=(dram_structure.bankgroups=1 dram_structure.banks_per_group=8 timing.tCK=0.625 timing.CL=28
                timing.CWL=14 timing.tRCD=29 timing.tRP=29 timing.tRAS=68 timing.tRFC=448 timing.tREFI=6246
                timing.tRRD_S=16 timing.tRRD_L=16 timing.tWTR_S=16 timing.tWTR_L=16 timing.tFAW=64 timing.tWR=29
                timing.tRTP=12 timing.tCCD_S=8 timing.tCCD_L=8 timing.tXP=12 system.channels=2 system.bus_width=16
                system.channel_size=1024 system.address_mapping=rorabgbachco system.trans_queue_size=32)
      TCK_NS=0.625 TRFC_CYCLES=448 TRFC_NS=280 BURST_BYTES=32
      ;;
    *) echo "unknown device $1" >&2; return 2 ;;
  esac
}

# The four streams: 65536 streaming and 16384 random 64 B reads (models/dram_microbench), and the
# DRAM traffic of two frames: deferred and forward_plus on atrium:3 at 1920x1080 with 256 lights.
DCC_STREAMS=(stream random deferred forward_plus)

# dcc_traces BUILD DIR: writes the two frames' command traces to DIR (once).
dcc_traces() {
  for t in deferred forward_plus; do
    [ -f "$2/$t.trace" ] || "$1/tbdrsim" trace --technique "$t" --scene atrium:3 --lights 256 \
      --resolution 1920x1080 --out "$2/$t.trace" > /dev/null
  done
}

# dcc_export BUILD DIR STREAM FORMAT OUT [--set ...]: runs STREAM on tbdrsim with the given DRAM
# settings, exporting FORMAT to OUT; tbdrsim's own figures go to OUT.tb (key value lines).
dcc_export() {
  local build=$1 dir=$2 stream=$3 format=$4 out=$5
  shift 5
  case "$stream" in
    stream|random)
      local lines=65536
      [ "$stream" = random ] && lines=16384
      "$build/tbdrsim" dram-bench --pattern "$stream" --lines "$lines" "$@" \
        --memory-trace "$out" --memory-trace-format "$format" > "$out.tb"
      ;;
    *)
      rm -f "$out.db"
      "$build/tbdrsim" run --trace "$dir/$stream.trace" --db "$out.db" -q "$@" \
        --memory-trace "$out" --memory-trace-format "$format"
      /usr/bin/python3 bench/dram_cross_check.py tbdrsim-db "$out.db" "$BURST_BYTES" "$TRFC_NS" > "$out.tb"
      ;;
  esac
}

# dcc_get FILE KEY: the value of KEY in a key value file.
dcc_get() { awk -v k="$2" '$1 == k { print $2; exit }' "$1"; }
