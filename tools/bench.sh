#!/usr/bin/env bash
# Runs every benchmark in tools/bench/ briefly and prints one table of the ratios to read:
# liftd's cycle against a bare reference loop, the DCP engine against the echo engine, the
# cycle with and without API load, API throughput against the real daemon, and how many
# cycles events and commands take. Each benchmark's full output is kept in the log folder.
#   tools/bench.sh                 build (default preset) if needed, then run (about 4 min)
#   LIFTD_BENCH_CYCLES=N ...       cycles per cycle-bench run (default 2000 = 30 s)
# Run as root on a quiet machine (SCHED_FIFO and memory locking need it).
set -euo pipefail
cd "$(dirname "$0")/.."

bin=build/bin
cycles=${LIFTD_BENCH_CYCLES:-2000}
logs=$(mktemp -d /tmp/liftd-bench-XXXXXX)
if [ ! -x "$bin/cycle-bench" ] || [ ! -x "$bin/liftd" ]; then
  cmake --preset default >/dev/null
  cmake --build --preset default --target liftd cycle-bench api-load-bench api-bench \
    event-bench travel-bench
fi

run() {  # run NAME COMMAND...: output to $logs/NAME.txt, a line on progress
  local name=$1
  shift
  echo "bench.sh: $name ..." >&2
  "$@" >"$logs/$name.txt" 2>&1 || { echo "bench.sh: $name failed, see $logs/$name.txt" >&2; exit 1; }
}

# field FILE PATTERN N: the Nth whitespace-separated field of the first line matching PATTERN.
field() { awk -v n="$3" "/$2/ { print \$n; exit }" "$1"; }

run cycle-dcp "$bin/cycle-bench" --cycles "$cycles"
run cycle-echo "$bin/cycle-bench" --engine echo --cycles "$cycles"
run api-load "$bin/api-load-bench" --seconds 5
run event "$bin/event-bench" --travels 4
run travel "$bin/travel-bench"

# api-bench against the real daemon with the simulated lift.
sock_dir=$(mktemp -d /tmp/liftd-bench-sock-XXXXXX)
XDG_RUNTIME_DIR=$sock_dir "$bin/liftd" --simulate >"$logs/liftd.txt" 2>&1 &
liftd_pid=$!
trap 'kill "$liftd_pid" 2>/dev/null || true; rm -rf "$sock_dir"' EXIT
for _ in $(seq 100); do
  [ -S "$sock_dir/liftd-sim.sock" ] && break
  sleep 0.1
done
sleep 2  # the link comes up
run api-socket "$bin/api-bench" --socket "$sock_dir/liftd-sim.sock" --seconds 3
kill "$liftd_pid"
wait "$liftd_pid" 2>/dev/null || true

dcp_cpu=$(sed -n 's/.*liftd cycle thread \([0-9.]*\) us.*/\1/p' "$logs/cycle-dcp.txt")
echo_cpu=$(sed -n 's/.*liftd cycle thread \([0-9.]*\) us.*/\1/p' "$logs/cycle-echo.txt")
ratio_p99=$(field "$logs/cycle-dcp.txt" "ratio liftd\\/reference" 4)
skipped=$(sed -n 's/.*skipped \([0-9]*\),.*/\1/p' "$logs/cycle-dcp.txt")
late=$(sed -n 's/.*sent [0-9]* (late \([0-9]*\)).*/\1/p' "$logs/cycle-dcp.txt")
load_p99=$(sed -n 's/^lateness ratio 8 clients \/ quiet: p99 \([0-9.]*\),.*/\1/p' "$logs/api-load.txt")
api8=$(awk '$1 == 8 { print $2; exit }' "$logs/api-socket.txt")
api8_p99=$(awk '$1 == 8 { print $4; exit }' "$logs/api-socket.txt")
ev_p50=$(field "$logs/event.txt" "drive reply -> watcher" 10)
ev_max=$(field "$logs/event.txt" "drive reply -> watcher" 12)
cmd_p50=$(field "$logs/event.txt" "travel request -> ok" 12)
cmd_max=$(field "$logs/event.txt" "travel request -> ok" 14)
cpu_ratio=$(awk -v a="$dcp_cpu" -v b="$echo_cpu" 'BEGIN { if (b > 0) printf "%.2f", a / b; else print "n/a" }')

printf '\n%-50s %12s   %s\n' "figure" "value" "target"
printf '%-50s %12s   %s\n' "wake-up lateness p99, liftd / reference loop" "$ratio_p99" "about 1"
printf '%-50s %12s   %s\n' "skipped cycles (late sends) in $cycles cycles" "$skipped ($late)" "0 while lateness <= 1375 us"
printf '%-50s %12s   %s\n' "CPU per cycle, DCP / echo engine (us: $dcp_cpu / $echo_cpu)" "$cpu_ratio" "<= 1.3"
printf '%-50s %12s   %s\n' "cycle lateness p99, 8 API clients / quiet" "$load_p99" "<= 1.1"
printf '%-50s %12s   %s\n' "API status req/s, 8 clients, liftd --simulate" "$api8" ">= 50000"
printf '%-50s %12s   %s\n' "API status p99 (us), 8 clients, liftd --simulate" "$api8_p99" "< 1000"
printf '%-50s %12s   %s\n' "drive reply -> watcher event, cycles p50 / max" "$ev_p50 / $ev_max" "<= 1 / <= 2"
printf '%-50s %12s   %s\n' "travel request -> taken by the cycle, cycles p50 / max" "$cmd_p50 / $cmd_max" "(measured; the next frame acts)"
echo
echo "full outputs: $logs"
