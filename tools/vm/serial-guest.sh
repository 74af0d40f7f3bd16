#!/bin/bash
# Inside the VM (tools/vm/boot.sh runs this as the guest's command): loads the drivers of the
# line under test from the guest kernel's own modules, finds its device and the virtio serial
# port that carries the shaft encoder's frames, says what the kernel reports of the device
# before liftd touches it, then runs one measured link run (tools/vm/link-run.py run).
#   tools/vm/serial-guest.sh LINE SECONDS OUT BUILD
#   LINE: 16550a or 16550a-echo (the emulated 16550A on /dev/ttyS1, 8250 driver), usb (QEMU's
#   usb-serial, an FTDI chip behind an xHCI controller, ftdi_sio driver: /dev/ttyUSB0)
set -euo pipefail
line=$1 seconds=$2 out=$3 build=$4
here=$(cd "$(dirname "$0")" && pwd)
load() { modprobe -d "$LIFTD_VM_KERNEL_DIR" "$@"; }
# wait_for SECONDS TEST...: polls every 0.1 s.
wait_for() {
  local end=$((SECONDS + $1))
  shift
  until "$@"; do
    [ $SECONDS -lt $end ] || return 1
    sleep 0.1
  done
}
echo "guest: kernel $(uname -r), $(nproc) CPUs, line $line"

case $line in
  16550a*) device=/dev/ttyS1 ;;
  usb)
    load xhci_pci
    load ftdi_sio
    device=/dev/ttyUSB0
    ;;
  *) echo "guest: unknown line $line" >&2; exit 2 ;;
esac
wait_for 20 test -c "$device" || { echo "guest: no $device" >&2; ls /dev/tty[SU]* >&2 || true; exit 1; }
tty=$(basename "$device")
sys=/sys/class/tty/$tty
if [ "$line" = usb ]; then
  # QEMU's emulated FTDI chip answers the latency timer's first read with 0; a real FT232 comes
  # up with 16 ms, which is what liftd must find and set to 1 ms (docs/operations.md, "The
  # serial line"). The adapter starts here as a real one would.
  echo "guest: latency_timer as QEMU's chip reports it: $(cat "$sys/device/latency_timer"); set to 16 (a real FT232's default)"
  echo 16 >"$sys/device/latency_timer"
fi
echo "guest: $device: driver $(basename "$(readlink -f "$sys/device/driver")")," \
  "type $(cat "$sys/type" 2>/dev/null || echo -), uartclk $(cat "$sys/uartclk" 2>/dev/null || echo -)," \
  "rx_trig_bytes $(cat "$sys/rx_trig_bytes" 2>/dev/null || echo -)," \
  "latency_timer $(cat "$sys/device/latency_timer" 2>/dev/null || echo -) (before liftd)"
[ "$line" != usb ] || grep -hv "Host Controller" /sys/bus/usb/devices/*/product 2>/dev/null | sed 's/^/guest: usb product: /'

# The encoder's frames come in on the virtio serial port named "encoder" (no udev here to make
# /dev/virtio-ports/encoder: the name is in sysfs).
load virtio_console
port=
find_port() {
  local p
  for p in /sys/class/virtio-ports/*; do
    [ "$(cat "$p/name" 2>/dev/null)" = encoder ] && port=/dev/$(basename "$p") && return 0
  done
  return 1
}
wait_for 10 find_port || { echo "guest: no virtio serial port named encoder" >&2; exit 1; }
wait_for 5 test -c "$port"

exec python3 "$here/link-run.py" run --name "$line" --device "$device" --out "$out" \
  --seconds "$seconds" --liftd "$build/bin/liftd" --config "$here/../../config/liftd.json" \
  --encoder-port "$port"
