#!/bin/sh
# Inside user-mode Linux (tools/uml/boot-hostfs.sh runs this as the guest's command, the CAN
# modules already loaded): vcan0 up, then every test labelled "vcan" of build folder $1 with
# LIFTD_TEST_CAN=vcan0. Output goes to the guest log the stage prints.
set -eu
build=${1:-build}
echo "guest: kernel $(uname -r), $(nproc) CPU"
ip link add dev vcan0 type vcan
ip link set vcan0 up
ip -details link show vcan0
export LIFTD_TEST_CAN=vcan0
exec ctest --test-dir "$build" -L vcan --output-on-failure --timeout 600
