#!/usr/bin/env bash
# The demo command: installs what is missing, builds, and runs liftd against its built-in
# simulated lift (simulated DCP4 drive on a pseudo-terminal, simulated car and I/O board) in the
# foreground with readable logs. Ctrl-C stops it.
#   tools/demo.sh              DCP4 drive
#   tools/demo.sh --hydraulic  hydraulic lift: the SCH001 card over CAN (config/hydraulic.json)
#   tools/demo.sh --uss        USS drive on an 8E1 pseudo-terminal (config/uss.json)
#   tools/demo.sh --config F   your own configuration (floors, sim.dcp = 3, ...) with --simulate
#   tools/demo.sh --group N    N simulated cars and the reference group dispatcher
#                              (tools/dispatcher) with passengers; more options below
# A group: tools/demo.sh --group 4 [--kinds dcp,sch001,uss,...] [--mode up-peak|down-peak|
#   interfloor] [--minutes M] [--rate PERCENT] [--seed S] [--svg FILE] [other options of
#   tools/dispatcher/group.py]. Each car gets its configuration, socket and runtime directory
#   in a temporary directory; the cars stop (SIGTERM) when the dispatcher ends.
# LIFTD_BIN=path/to/liftd runs that binary and builds nothing (default: build, then
# build/bin/liftd).
set -euo pipefail
[ -z "${LIFTD_BIN:-}" ] || LIFTD_BIN=$(realpath "$LIFTD_BIN")
cd "$(dirname "$0")/.."

if [ -z "${LIFTD_BIN:-}" ]; then
  tools/install-deps.sh
  cmake --preset default >/dev/null
  cmake --build --preset default --parallel "${LIFTD_JOBS:-$(nproc)}" --target liftd liftctl
fi
liftd=${LIFTD_BIN:-build/bin/liftd}

group=0
kinds=""
for ((i = 1; i <= $#; i++)); do
  case "${!i}" in
    --group) j=$((i + 1)); group=${!j} ;;
    --kinds) j=$((i + 1)); kinds=${!j} ;;
  esac
done
if [ "$group" != 0 ] || [ -n "$kinds" ]; then
  # The group demo: N cars (default a mix of the three drive kinds), then the dispatcher.
  if [ -z "$kinds" ]; then
    mix=(dcp sch001 uss)
    for ((i = 0; i < group; i++)); do kinds+="${kinds:+,}${mix[i % 3]}"; done
  fi
  IFS=, read -ra kind_list <<<"$kinds"
  if [ "$group" != 0 ] && [ "${#kind_list[@]}" != "$group" ]; then
    echo "demo.sh: --group $group but --kinds names ${#kind_list[@]} cars" >&2
    exit 2
  fi
  dispatcher_args=()
  skip=0
  for arg in "$@"; do
    if [ $skip = 1 ]; then skip=0; continue; fi
    case "$arg" in
      --group|--kinds) skip=1 ;;
      *) dispatcher_args+=("$arg") ;;
    esac
  done
  work=$(mktemp -d "${TMPDIR:-/tmp}/liftd-group.XXXXXX")
  pids=()
  stop_cars() {
    [ "${#pids[@]}" = 0 ] || kill -TERM "${pids[@]}" 2>/dev/null || true
    for pid in "${pids[@]}"; do wait "$pid" 2>/dev/null || true; done
    pids=()
  }
  trap stop_cars EXIT
  trap 'exit 130' INT TERM
  car_args=()
  while read -r name kind config socket; do
    # RUNTIME_DIRECTORY unset: each car keeps its card socket, record and traces beside its
    # own API socket.
    env -u RUNTIME_DIRECTORY "$liftd" --simulate --config "$config" \
      >"$(dirname "$config")/liftd.log" 2>&1 &
    pids+=($!)
    car_args+=(--car "$socket")
    echo "car $name: $kind, $config (log: $(dirname "$config")/liftd.log)"
  done < <(python3 tools/dispatcher/simcars.py configs "$work" "$kinds")
  status=0
  python3 tools/dispatcher/group.py "${car_args[@]}" "${dispatcher_args[@]}" || status=$?
  stop_cars
  echo "the cars' configurations and logs: $work"
  exit $status
fi

runtime=${XDG_RUNTIME_DIR:-$PWD}
socket="$runtime/liftd-sim.sock"
args=()
for arg in "$@"; do
  if [ "$arg" = "--hydraulic" ] || [ "$arg" = "--uss" ]; then
    # config/hydraulic.json or config/uss.json with the API socket where the demo's user may
    # create it.
    kind=${arg#--}
    demo_config="$runtime/liftd-$kind-demo.json"
    sed -E -e "s#\"socket\": \"/run/liftd/api.sock\"#\"socket\": \"$socket\"#" \
        -e 's#"(socket|read|control|inputs)_group": "[^"]*"#"\1_group": ""#' \
        -e 's#"require_realtime": true, "lock_memory": true#"require_realtime": false, "lock_memory": false#' \
        "config/$kind.json" >"$demo_config"
    args+=(--config "$demo_config")
    continue
  fi
  [ "$arg" = "--config" ] && socket="(api.socket of your config)"
  args+=("$arg")
done
cat <<INFO

liftd is starting against a simulated lift. In another terminal, try:

  build/bin/liftctl --socket $socket status
  build/bin/liftctl --socket $socket watch
  build/bin/liftctl --socket $socket travel 3
  build/bin/liftctl --socket $socket calls add 2
  build/bin/liftctl --socket $socket key 1 && build/bin/liftctl --socket $socket display   (DCP only)
  build/bin/liftctl --socket $socket raw '{"cmd":"sim","action":"sink"}'   (hydraulic: the car sinks, liftd relevels)
  build/bin/liftctl --socket $socket uss-read 52        (USS: a parameter of the drive)
  build/bin/liftctl --socket $socket counters           (the lift's record: $runtime/record.db,
  build/bin/liftctl --socket $socket history            kept from one demo to the next)

Ctrl-C stops liftd.

INFO
exec "$liftd" --simulate "${args[@]}"
