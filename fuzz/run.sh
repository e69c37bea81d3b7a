#!/usr/bin/env bash
# Runs fuzz targets one after the other, single process each (no -jobs, no
# -fork), for 1,000,000 executions or 30 minutes, whichever comes first;
# prints the figures of fuzz/README.md's table.
# Usage: fuzz/run.sh [TARGET...]   (default: every target; corpora from seeds.sh)
set -euo pipefail
cd "$(dirname "$0")"
[ -d corpus ] || ./seeds.sh
targets=("$@")
[ ${#targets[@]} -gt 0 ] || targets=($(ls fuzz_targets | sed 's/\.rs$//'))
mkdir -p logs
# The mission_log target writes each input to a temporary file: in memory
# (/dev/shm) that costs 0.04 ms, on this machine's disk 5 ms.
[ -d /dev/shm ] && export TMPDIR=/dev/shm
for t in "${targets[@]}"; do
    start=$(date +%s)
    cargo +nightly fuzz run -s none "$t" "corpus/$t" -- \
        -runs=1000000 -max_total_time=1800 -timeout=10 -rss_limit_mb=2048 \
        -print_final_stats=1 >"logs/$t.log" 2>&1 || { echo "$t: FAILED, see fuzz/logs/$t.log"; exit 1; }
    end=$(date +%s)
    execs=$(grep -oE 'stat::number_of_executed_units: *[0-9]+' "logs/$t.log" | grep -oE '[0-9]+$')
    rate=$(grep -oE 'stat::average_exec_per_sec: *[0-9]+' "logs/$t.log" | grep -oE '[0-9]+$')
    printf '%-12s %9s executions %6s s %7s exec/s  corpus %s\n' "$t" "$execs" "$((end - start))" "$rate" "$(ls "corpus/$t" | wc -l)"
done
