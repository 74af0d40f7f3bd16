#!/usr/bin/env bash
# The real-UART stage of tools/test.sh: liftd's DCP link on a real kernel's serial drivers. Runs
# liftd (a real DCP lift, not --simulate) against the project's drive simulator
# (dcp-drive-sim) over four lines, LIFTD_VM_SECONDS of travels each (default 45), and prints the
# link figures liftd itself reports, one line each:
#   pty          liftd and the drive both on this host over a pseudo-terminal pair (as the
#                ordinary tests run): the reference
#   16550a       liftd in a QEMU virtual machine on the emulated 16550A UART (/dev/ttyS1, the
#                guest's 8250 driver); the drive on the host end of it (QEMU's -chardev pty)
#   16550a-echo  the same, the line echoing (dcp-drive-sim --echo: each byte the master sent comes
#                back before the reply, as on an auto-direction USB-RS485 adapter): liftd's
#                drive.echo auto must find it
#   usb          liftd in the VM on QEMU's usb-serial (an FTDI chip behind an xHCI controller,
#                the guest's ftdi_sio driver: /dev/ttyUSB0), whose latency timer liftd sets to 1 ms
# The guest boots Debian 12's own kernel (tools/vm/kernel.sh, fetched, never installed) on this
# machine's files over 9p (tools/vm/boot.sh). The car's position comes from the simulator's shaft
# encoder, carried into the guest on a virtio serial port.
# Judged as the other stages judge a link: every travel arrives (car at the target floor, the run
# not aborted), no link fault (DCP 7.3), missing replies at most LIFTD_VM_MISSING_BOUND per 1000
# cycles (default 2), reply p99 within DCP 7.2's 13.625 ms, the echo found where the line echoes
# and only there. Exits 1 when a judgement fails.
# The accelerator: KVM where /dev/kvm runs Debian's kernel. Where it cannot (no /dev/kvm, or a
# /dev/kvm that runs only paravirtual guests, as kvm-pvm) the guest runs under QEMU's software
# emulation (TCG): the kernel's drivers are still the real ones, so what does not depend on time
# is judged (the link comes up, the echo found, the driver, rx_trig_bytes and latency timer liftd
# reports, the adapter's latency timer 1 ms while liftd runs), and the timing judgement of the VM
# lines is SKIPPED with a framed message (an emulated CPU cannot keep a 15 ms cycle on a shared
# host: measured here, hundreds of skipped cycles a minute); the pty line is judged in full.
# Where QEMU cannot boot the guest at all it prints SKIPPED and exits 0.
#   tools/vm/serial-stage.sh [BUILD_DIR]   (default build, with liftd, liftctl and dcp-drive-sim built)
#   LIFTD_VM_SECONDS=N        travel time per line (default 45; under TCG 20 for the VM lines)
#   LIFTD_VM_LINES="..."      which lines (default "pty 16550a 16550a-echo usb")
#   LIFTD_VM_ACCEL=kvm|tcg    force the accelerator (default: KVM where it runs the guest, else TCG)
#   LIFTD_VM_MISSING_BOUND=F  missing replies allowed per 1000 cycles (default 2)
set -euo pipefail
cd "$(dirname "$0")/../.."
build=$(cd "${1:-build}" && pwd)
seconds=${LIFTD_VM_SECONDS:-45}
vm_seconds=$seconds
lines=${LIFTD_VM_LINES:-pty 16550a 16550a-echo usb}
bound=${LIFTD_VM_MISSING_BOUND:-2}
start=$SECONDS

tools/install-deps.sh --vm

skip() {
  echo "############################################################################" >&2
  echo "### SKIPPED: the real-UART stage did not run: $*" >&2
  echo "### (liftd on a kernel's 8250 and ftdi_sio drivers is NOT tested on this machine)" >&2
  echo "############################################################################" >&2
  exit 0
}
for bin in liftd dcp-drive-sim; do
  [ -x "$build/bin/$bin" ] || { echo "serial-stage: no $build/bin/$bin (build it first)" >&2; exit 1; }
done

out=$build/vm/serial
rm -rf "$out"
mkdir -p "$out"
pids=()
stop_all() {  # only what this script started, by its PID
  local p
  for p in "${pids[@]}"; do kill "$p" 2>/dev/null || true; done
  for p in "${pids[@]}"; do wait "$p" 2>/dev/null || true; done
  pids=()
}
trap stop_all EXIT
# The drive and the helpers standing for hardware run real-time where allowed, one step below
# liftd's cycle (SCHED_FIFO 80), as the systemd stage's drive does.
rt=()
[ "$(id -u)" = 0 ] && command -v chrt >/dev/null && rt=(chrt -f 79)

# ---- which accelerator
kvm_problem() {
  [ -c /dev/kvm ] || { echo "no /dev/kvm"; return; }
  if [ ! -r /dev/kvm ] || [ ! -w /dev/kvm ]; then
    echo "/dev/kvm is not readable and writable for $(id -un)"
    return
  fi
  # kvm-pvm (pagetable-based virtual machine) is a KVM for guests built as PVM guests: a stock
  # kernel under it is emulated a few instructions at a time (measured here: Debian's kernel
  # 38 s into its early boot after 2 minutes, none of it reaching user space).
  [ ! -d /sys/module/kvm_pvm ] || { echo "/dev/kvm is kvm-pvm, which runs only PVM guest kernels (Debian's kernel crawls under it)"; return; }
  if ! LIFTD_VM_ACCEL=kvm tools/vm/boot.sh --out "$out/probe-kvm" --timeout 90 -- true >/dev/null 2>&1; then
    echo "a KVM guest did not boot within 90 s ($(tail -1 "$out/probe-kvm/qemu.log" 2>/dev/null))"
  fi
}
accel=${LIFTD_VM_ACCEL:-}
if [ -z "$accel" ]; then
  problem=$(kvm_problem)
  if [ -z "$problem" ]; then
    accel=kvm
  else
    accel=tcg
  fi
fi
if [ "$accel" = tcg ]; then
  {
    echo "############################################################################"
    echo "### SKIPPED: the real-UART stage's TIMING judgement of the VM lines: ${problem:-LIFTD_VM_ACCEL=tcg}."
    echo "### The guest runs under QEMU's software emulation (TCG): its drivers are the real"
    echo "### ones and are judged; its timing is an emulated CPU's and is only reported."
    echo "############################################################################"
  } >&2
  vm_seconds=${LIFTD_VM_SECONDS:-20}
fi
export LIFTD_VM_ACCEL=$accel
set +e
tools/vm/boot.sh --out "$out/probe" --timeout 180 -- uname -r >/dev/null 2>"$out/probe.err"
probe=$?
set -e
case $probe in
  0) echo "serial-stage: QEMU ($accel) boots Debian's kernel $(cat "$out/probe/guest.log") in the guest" ;;
  124 | 125) skip "QEMU could not boot the guest here ($accel, boot exit $probe: $(tail -3 "$out/probe.err" | tr '\n' ' '))" ;;
  *) echo "serial-stage: the probe boot failed (exit $probe):" >&2; cat "$out/probe/guest.log" "$out/probe.err" >&2; exit 1 ;;
esac

# ---- one line
# The drive simulator at the host end of DEVICE, its encoder on FOLDER/encoder.sock; prints the PID.
start_drive() {  # start_drive FOLDER DEVICE [--echo]
  local folder=$1 device=$2
  shift 2
  "${rt[@]}" "$build/bin/dcp-drive-sim" --device "$device" --encoder "unix:$folder/encoder.sock" \
    --reconnect --quiet "$@" >"$folder/drive.log" 2>&1 &
  echo $!
}
wait_file() {  # wait_file SECONDS PATH
  local end=$((SECONDS + $1))
  until [ -s "$2" ]; do
    [ $SECONDS -lt $end ] || return 1
    sleep 0.1
  done
}

run_pty() {
  local folder=$out/pty rc=0
  mkdir -p "$folder"
  "${rt[@]}" python3 tools/vm/link-run.py pty-pair "$folder" &
  pids+=($!)
  if ! wait_file 10 "$folder/drive-end" || ! wait_file 10 "$folder/liftd-end"; then
    echo "serial-stage: no pty pair" >&2
    return 1
  fi
  pids+=("$(start_drive "$folder" "$(cat "$folder/drive-end")")")
  wait_file 10 "$folder/encoder.sock" || true
  python3 tools/vm/link-run.py run --name pty --device "$(cat "$folder/liftd-end")" --out "$out" \
    --seconds "$seconds" --liftd "$build/bin/liftd" --config config/liftd.json \
    --encoder-socket "$folder/encoder.sock" >"$folder/run.log" 2>&1 || rc=$?
  stop_all
  return $rc
}

run_vm() {  # run_vm LINE
  local line=$1 folder=$out/$1 rc=0 device qemu=() drive_args=()
  mkdir -p "$folder"
  case $line in
    16550a | 16550a-echo)
      # ttyS0 is the console (boot.sh); this is the second UART: ttyS1, a 16550A at 0x2f8.
      qemu=(-chardev "pty,id=drive" -serial "chardev:drive") ;;
    usb)
      qemu=(-device "qemu-xhci,id=xhci" -chardev "pty,id=drive" -device "usb-serial,chardev=drive,bus=xhci.0") ;;
  esac
  [ "$line" != 16550a-echo ] || drive_args=(--echo)
  # The encoder's frames: QEMU listens on encoder-qemu.sock, a virtio serial port named
  # "encoder" in the guest.
  qemu+=(-device virtio-serial-pci -chardev "socket,id=encoder,path=$folder/encoder-qemu.sock,server=on,wait=off"
    -device "virtserialport,chardev=encoder,name=encoder")
  local args=()
  for a in "${qemu[@]}"; do args+=(--qemu "$a"); done
  tools/vm/boot.sh --out "$folder/vm" --timeout $((vm_seconds + 300)) "${args[@]}" -- \
    tools/vm/serial-guest.sh "$line" "$vm_seconds" "$folder/vm" "$build" &
  local boot=$!
  pids+=("$boot")
  # QEMU names the pty it made: "char device redirected to /dev/pts/N (label drive)".
  local end=$((SECONDS + 30))
  device=
  while [ -z "$device" ] && [ $SECONDS -lt $end ]; do
    device=$(sed -n 's/.*redirected to \(\/dev\/pts\/[0-9]*\) (label drive).*/\1/p' "$folder/vm/qemu.log" 2>/dev/null || true)
    [ -n "$device" ] || sleep 0.1
  done
  if [ -z "$device" ]; then
    echo "serial-stage: QEMU named no pty for the drive line" >&2
    stop_all
    return 1
  fi
  pids+=("$(start_drive "$folder" "$device" "${drive_args[@]}")")
  wait_file 10 "$folder/encoder.sock" || true
  "${rt[@]}" python3 tools/vm/link-run.py encoder-host "$folder/encoder.sock" "$folder/encoder-qemu.sock" &
  pids+=($!)
  wait "$boot" || rc=$?
  stop_all
  # The guest wrote its results into the run's share (the only folder it may write).
  for f in "$folder/vm/$line".*; do [ -e "$f" ] && mv "$f" "$out/"; done
  return $rc
}

names=()
for line in $lines; do
  took=$seconds
  [ "$line" = pty ] || took=$vm_seconds
  echo "=== serial-stage: line $line, $took s of travels ($([ "$line" = pty ] && echo host || echo "$accel")) ==="
  rc=0
  case $line in
    pty) run_pty || rc=$? ;;
    16550a | 16550a-echo | usb) run_vm "$line" || rc=$? ;;
    *) echo "serial-stage: unknown line $line" >&2; exit 2 ;;
  esac
  [ ! -f "$out/$line/vm/guest.log" ] || grep '^guest:' "$out/$line/vm/guest.log" || true
  [ $rc = 0 ] || echo "serial-stage: line $line: the run exited $rc (logs: $out/$line)"
  names+=("$line")
done

echo "=== serial-stage: the link as liftd reports it (VM lines: $accel; $(nproc) host CPUs) ==="
echo "(reply: frame start to the cycle's look that found the reply complete; p99 from liftd's stats,"
echo " p50 and max from its flight recorder, whose reply record is written just after that look: a"
echo " stall of the cycle thread in between shows in max, even beyond 13625 us, as a good reply;"
echo " miss/1000: dcp.missing_replies per 1000 cycles;"
echo " bad: checksum errors and echo collisions; wake/cyc: the liftd-cycle thread's voluntary"
echo " context switches per cycle; lat ms: a USB adapter's latency timer after liftd's start)"
python3 tools/vm/link-run.py table "$out" "${names[@]}"
echo "--- what liftd said about each line (its log):"
for line in "${names[@]}"; do
  python3 - "$out/$line.json" "$line" <<'PY' || true
import json, sys
r = json.load(open(sys.argv[1]))
for l in r.get("liftd_lines", []):
    if any(k in l for k in ("serial device", "latency", "echo")):
        print(f"{sys.argv[2]}: {l.split(' ', 2)[-1]}")
if r.get("sysfs"):
    print(f"{sys.argv[2]}: sysfs after the run: {r['sysfs']}")
PY
done
set +e
marks=()
for line in "${names[@]}"; do
  case $line in *echo*) marks+=(--echo "$line") ;; esac
  [ "$accel" = kvm ] || [ "$line" = pty ] || marks+=(--functional "$line")
done
python3 tools/vm/link-run.py judge "$out" "$bound" "${marks[@]}" "${names[@]}"
verdict=$?
set -e
echo "serial-stage: $accel, $((SECONDS - start)) s, results and logs in $out"
exit $verdict
