#!/usr/bin/env bash
# The real-SocketCAN stage of tools/test.sh: boots user-mode Linux (Debian's linux.uml, an
# ordinary process) on this machine's own files, loads the CAN modules (can, can-raw, can-dev,
# vcan), brings up vcan0 and runs every test labelled "vcan" of the default build inside it:
# the CAN endpoint on the kernel's SocketCAN (tests/can/real_socket_test.cpp) and liftd on the
# bus judged from candump (tests/e2e/vcan_test.cpp). Prints the kernel it ran and how long it
# took. Where this machine cannot run user-mode Linux it says so loudly and exits 0 (skipped).
#   tools/uml/can-stage.sh [BUILD_DIR]     (default: build, already built)
set -euo pipefail
cd "$(dirname "$0")/../.."
build=${1:-build}
start=$SECONDS

tools/install-deps.sh --uml-can

skip() {
  echo "############################################################################" >&2
  echo "### SKIPPED: the real-SocketCAN stage did not run: $*" >&2
  echo "### (the CAN endpoint and liftd on a CAN bus are NOT tested on this machine)" >&2
  echo "############################################################################" >&2
  exit 0
}

out=$PWD/$build/uml/can
mkdir -p "$out"
modules=net/can/can.ko,net/can/can-raw.ko,drivers/net/can/dev/can-dev.ko,drivers/net/can/vcan.ko
# A first boot that only loads the modules tells "cannot run user-mode Linux here" apart from a
# failing test.
set +e
tools/uml/boot-hostfs.sh --out "$out/probe" --timeout 120 --modules "$modules" -- uname -r
probe=$?
set -e
if [ $probe != 0 ]; then
  case $probe in
    124 | 125) skip "this machine cannot boot user-mode Linux (boot-hostfs exit $probe; see $out/probe/console.log)" ;;
    126) echo "can-stage: the guest could not load the CAN modules:" >&2; cat "$out/probe/guest.log" >&2; exit 1 ;;
    *) echo "can-stage: the probe boot failed (exit $probe):" >&2; cat "$out/probe/guest.log" >&2; exit 1 ;;
  esac
fi
echo "can-stage: user-mode Linux $(cat "$out/probe/guest.log") ($(command -v linux.uml)) boots; CAN modules loaded"

set +e
tools/uml/boot-hostfs.sh --out "$out/tests" --timeout 1200 --modules "$modules" -- \
  tools/uml/can-guest.sh "$build"
rc=$?
set -e
cat "$out/tests/guest.log"
echo "can-stage: kernel $(cat "$out/probe/guest.log"), exit $rc, $((SECONDS - start)) s (guest log: $out/tests/guest.log)"
exit $rc
