#!/usr/bin/env bash
# The demo command: installs what is missing, builds, and runs liftd against its built-in
# simulated lift (simulated DCP4 drive on a pseudo-terminal, simulated car and I/O board) in the
# foreground with readable logs. Ctrl-C stops it.
#   tools/demo.sh              DCP4 drive
#   tools/demo.sh --hydraulic  hydraulic lift: the SCH001 card over CAN (config/hydraulic.json)
#   tools/demo.sh --uss        USS drive on an 8E1 pseudo-terminal (config/uss.json)
#   tools/demo.sh --config F   your own configuration (floors, sim.dcp = 3, ...) with --simulate
set -euo pipefail
cd "$(dirname "$0")/.."

tools/install-deps.sh
cmake --preset default >/dev/null
cmake --build --preset default --parallel "${LIFTD_JOBS:-$(nproc)}" --target liftd liftctl

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
exec build/bin/liftd --simulate "${args[@]}"
