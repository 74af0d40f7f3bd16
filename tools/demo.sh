#!/usr/bin/env bash
# The demo command: installs what is missing, builds, and runs liftd against its built-in
# simulated lift (simulated DCP4 drive on a pseudo-terminal, simulated car and I/O board) in the
# foreground with readable logs. Ctrl-C stops it.
#   tools/demo.sh              DCP4 drive
#   tools/demo.sh --config F   your own configuration (floors, sim.dcp = 3, ...) with --simulate
set -euo pipefail
cd "$(dirname "$0")/.."

tools/install-deps.sh
cmake --preset default >/dev/null
cmake --build --preset default --parallel "${LIFTD_JOBS:-$(nproc)}" --target liftd liftctl

runtime=${XDG_RUNTIME_DIR:-$PWD}
socket="$runtime/liftd-sim.sock"
for arg in "$@"; do
  [ "$arg" = "--config" ] && socket="(api.socket of your config)"
done
cat <<INFO

liftd is starting against a simulated lift. In another terminal, try:

  build/bin/liftctl --socket $socket status
  build/bin/liftctl --socket $socket watch
  build/bin/liftctl --socket $socket travel 3
  build/bin/liftctl --socket $socket calls add 5
  build/bin/liftctl --socket $socket key 1 && build/bin/liftctl --socket $socket display

Ctrl-C stops liftd.

INFO
exec build/bin/liftd --simulate "$@"
