#!/usr/bin/env bash
# Fuzz campaigns beyond the short CI runs, and the line coverage each target reaches.
#   tools/fuzz.sh [--seconds N] [--merge] [--coverage] [TARGET...]
#     --seconds N   run each target for N seconds (default 600), two at a time (one per core)
#     --merge       afterwards, merge what the campaign found into the committed seed corpus
#                   (tests/fuzz/corpus/TARGET, minimised by libFuzzer's -merge=1)
#     --coverage    afterwards, build the targets with clang source coverage, replay each corpus
#                   and print the line coverage of the code each target exists to test
#     --seconds 0   no campaign (e.g. --seconds 0 --coverage: coverage of the committed seeds)
# Without TARGET: every target. Prints one table: executions, executions per second, corpus
# size, and for each crash the file to turn into a regression input (see tests/fuzz/README.md).
set -euo pipefail
cd "$(dirname "$0")/.."

seconds=600
merge=0
coverage=0
targets=()
while [ $# -gt 0 ]; do
  case $1 in
    --seconds) seconds=$2; shift 2 ;;
    --merge) merge=1; shift ;;
    --coverage) coverage=1; shift ;;
    -h | --help) sed -n '2,12p' "$0"; exit 0 ;;
    -*) echo "fuzz.sh: unknown option $1 (see --help)" >&2; exit 2 ;;
    *) targets+=("$1"); shift ;;
  esac
done
case $seconds in '' | *[!0-9]*) echo "fuzz.sh: --seconds needs a whole number" >&2; exit 2 ;; esac

tools/install-deps.sh
cmake --preset fuzz >/dev/null
cmake --build --preset fuzz --parallel "$(nproc)"
[ ${#targets[@]} -gt 0 ] || mapfile -t targets < <(ls tests/fuzz/corpus)
for t in "${targets[@]}"; do
  [ -x "build-fuzz/fuzz/$t" ] || { echo "fuzz.sh: no fuzz target $t (see tests/fuzz/corpus)" >&2; exit 2; }
done

campaign=build-fuzz/campaign
logs=$campaign/logs
mkdir -p "$logs"

dict_args() { [ -f "tests/fuzz/dict/$1.dict" ] && echo "-dict=tests/fuzz/dict/$1.dict"; true; }

run_one() {  # run_one TARGET: one campaign, output in $logs/TARGET.txt, crashes in $campaign/TARGET-crashes
  local t=$1
  mkdir -p "$campaign/$t" "$campaign/$t-crashes"
  # shellcheck disable=SC2046
  "build-fuzz/fuzz/$t" -max_total_time="$seconds" -print_final_stats=1 -rss_limit_mb=1024 \
    -artifact_prefix="$campaign/$t-crashes/" $(dict_args "$t") \
    "$campaign/$t" "tests/fuzz/corpus/$t" >"$logs/$t.txt" 2>&1 || true
}

if [ "$seconds" -gt 0 ]; then
  echo "fuzz.sh: ${#targets[@]} targets, $seconds s each, $(nproc) at a time; logs in $logs" >&2
  running=0
  for t in "${targets[@]}"; do
    run_one "$t" &
    running=$((running + 1))
    if [ "$running" -ge "$(nproc)" ]; then
      wait -n
      running=$((running - 1))
    fi
  done
  wait

  status=0
  printf '\n%-26s %14s %10s %8s  %s\n' target executions "exec/s" corpus crashes
  for t in "${targets[@]}"; do
    execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$logs/$t.txt" | tail -1)
    rate=$(sed -n 's/^stat::average_exec_per_sec: *//p' "$logs/$t.txt" | tail -1)
    size=$(find "$campaign/$t" "tests/fuzz/corpus/$t" -type f | wc -l)
    crashes=$(find "$campaign/$t-crashes" -type f | wc -l)
    printf '%-26s %14s %10s %8s  %s\n' "$t" "${execs:-?}" "${rate:-?}" "$size" "$crashes"
    [ "$crashes" -eq 0 ] || { status=1; find "$campaign/$t-crashes" -type f | sed 's/^/    /'; }
    [ -n "$execs" ] || { status=1; echo "    no final stats: see $logs/$t.txt"; }
  done
  if [ "$merge" = 1 ]; then
    for t in "${targets[@]}"; do
      "build-fuzz/fuzz/$t" -merge=1 "tests/fuzz/corpus/$t" "$campaign/$t" >"$logs/$t-merge.txt" 2>&1
    done
    echo "fuzz.sh: merged into tests/fuzz/corpus/ (git status shows what is new)" >&2
  fi
  [ "$status" = 0 ] || echo "fuzz.sh: a target crashed or did not finish" >&2
fi

if [ "$coverage" = 1 ]; then
  # The code each target exists to test: its coverage is the figure that matters.
  declare -A sources=(
    [api_handler_fuzz]="lib/api/dispatcher.cpp lib/api/schema.cpp lib/api/commands.cpp"
    [api_line_fuzz]="lib/api/dispatcher.cpp lib/api/result.cpp"
    [config_fuzz]="lib/config/load.cpp lib/config/schema.cpp lib/config/sections_service.cpp lib/config/sections_shaft.cpp lib/dcp/config/config_rules.cpp lib/uss/config/config_rules.cpp lib/sch001/config/config_rules.cpp"
    [config_file_fuzz]="lib/config/load.cpp"
    [dcp_api_handler_fuzz]="lib/dcp/host/commands.cpp"
    [dcp_channel_fuzz]="lib/dcp/channel.cpp lib/dcp/display.cpp"
    [dcp_frame_fuzz]="lib/dcp/frame.cpp"
    [dcp_master_link_fuzz]="lib/dcp/master_link.cpp"
    [dcp_messages_fuzz]="lib/dcp/messages.cpp lib/dcp/charset.cpp lib/dcp/display.cpp"
    [dcp_trace_fuzz]="lib/dcp/trace.cpp"
    [sim_drive_fuzz]="lib/dcp/sim/drive_sim.cpp lib/dcp/sim/drive_sim_travel.cpp lib/dcp/sim/drive_sim_channel.cpp"
    [sch001_link_fuzz]="lib/sch001/protocol.cpp lib/sch001/card_link.cpp"
    [travel_controller_fuzz]="lib/dcp/travel/controller.cpp lib/dcp/travel/dcp3_travel.cpp lib/dcp/travel/dcp4_travel.cpp lib/dcp/travel/gate.cpp"
    [uss_api_handler_fuzz]="lib/uss/host/commands.cpp"
    [uss_receiver_fuzz]="lib/uss/receiver.cpp lib/uss/telegram.cpp lib/uss/line.cpp"
  )
  llvm_bin=/usr/lib/llvm-16/bin
  [ -x "$llvm_bin/llvm-cov" ] || apt-get install -y -qq llvm-16 >/dev/null
  cov=build-fuzz-cov
  cmake -S . -B "$cov" -G Ninja -DCMAKE_BUILD_TYPE=Debug -DCMAKE_CXX_COMPILER=clang++-16 \
    -DCMAKE_C_COMPILER=clang-16 -DLIFTD_FUZZ=ON -DLIFTD_TESTS=OFF \
    -DCMAKE_CXX_FLAGS="-fprofile-instr-generate -fcoverage-mapping" >/dev/null
  cmake --build "$cov" --target fuzzers --parallel "$(nproc)"
  printf '\n%-26s %9s  %s\n' target "lines %" "of"
  for t in "${targets[@]}"; do
    corpora=("tests/fuzz/corpus/$t")
    [ -d "$campaign/$t" ] && corpora+=("$campaign/$t")
    rm -f "$cov/$t".profraw
    LLVM_PROFILE_FILE="$cov/$t.profraw" "$cov/fuzz/$t" -runs=0 "${corpora[@]}" >"$cov/$t.log" 2>&1 || true
    "$llvm_bin/llvm-profdata" merge -sparse "$cov/$t.profraw" -o "$cov/$t.profdata"
    # shellcheck disable=SC2086
    percent=$("$llvm_bin/llvm-cov" report "$cov/fuzz/$t" -instr-profile="$cov/$t.profdata" \
      ${sources[$t]:-} | awk '/^TOTAL/ { print $10 }')
    printf '%-26s %9s  %s\n' "$t" "${percent:-?}" "${sources[$t]:-every file}"
  done
fi
