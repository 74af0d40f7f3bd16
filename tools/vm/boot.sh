#!/usr/bin/env bash
# Runs one command inside a KVM virtual machine (QEMU, Debian 12's kernel from tools/vm/kernel.sh)
# whose root file system is this machine's own "/", read-only over 9p, and returns the command's
# exit code. Programs, libraries and the build tree are the host's files; the guest's kernel and
# its devices (the emulated UART, USB host controller and adapter) are its own.
#
#   tools/vm/boot.sh [--out DIR] [--timeout S] [--mem MB] [--smp N] [--qemu ARG]...
#                    [--env NAME]... -- COMMAND [ARG...]
#
#   --out DIR     where the guest writes guest.log (the command's stdout and stderr) and rc (its
#                 exit code), and QEMU its own messages (qemu.log: "char device redirected to
#                 /dev/pts/N (label L)" names each pty chardev's host end) and the guest
#                 console (console.log). The guest may write anything below DIR (a 9p share);
#                 it sees DIR and the caller's working directory at the same paths as the host.
#   --timeout S   QEMU is killed after S seconds (default 600)
#   --mem MB      guest memory (default 1024)
#   --smp N       guest CPUs (default 2)
#   --qemu ARG    one more argument for qemu-system-x86_64 (repeatable): the devices of the run,
#                 e.g. --qemu -chardev --qemu pty,id=drive --qemu -device --qemu isa-serial,chardev=drive
#   --env NAME    pass the host's NAME=value into the guest (repeatable); the guest starts with
#                 PATH, HOME and TZ only, in the caller's working directory
#
# Exit codes: the command's own; 124 when the timeout killed QEMU; 125 when QEMU did not run, or
# the guest never wrote its exit code (the console's end is printed then).
# Inside the guest: proc, sysfs, devtmpfs on /dev (the guest's own devices: /dev/ttyS1,
# /dev/ttyUSB0 appear as its drivers bind), devpts, tmpfs on /run, /tmp and /dev/shm. The root is
# read-only: the command writes below --out or in a tmpfs. The kernel's modules are the fetched
# kernel's, not the host's: `modprobe -d "$LIFTD_VM_KERNEL_DIR" NAME` loads one (the variable is
# set in the guest).
set -euo pipefail

# LIFTD_VM_ACCEL: kvm (default) or tcg (QEMU's software emulation, where /dev/kvm cannot run
# the guest; tools/vm/serial-stage.sh decides).
accel=${LIFTD_VM_ACCEL:-kvm} cpu=host
[ "$accel" = kvm ] || cpu=max
out="" timeout_s=600 mem=1024 smp=2 qemu_args=() envs=()
while [ $# -gt 0 ]; do
  case $1 in
    --out) out=$2; shift 2 ;;
    --timeout) timeout_s=$2; shift 2 ;;
    --mem) mem=$2; shift 2 ;;
    --smp) smp=$2; shift 2 ;;
    --qemu) qemu_args+=("$2"); shift 2 ;;
    --env) envs+=("$2"); shift 2 ;;
    --) shift; break ;;
    *) echo "vm boot: unknown option $1" >&2; exit 2 ;;
  esac
done
[ $# -gt 0 ] || { echo "vm boot: no command given" >&2; exit 2; }
here=$(cd "$(dirname "$0")" && pwd)

qemu=$(command -v qemu-system-x86_64 || true)
[ -n "$qemu" ] || { echo "vm boot: qemu-system-x86_64 not found (Debian package qemu-system-x86)" >&2; exit 125; }
mapfile -t kernel < <("$here/kernel.sh") || true
[ ${#kernel[@]} = 3 ] || { echo "vm boot: no kernel (tools/vm/kernel.sh failed)" >&2; exit 125; }
vmlinuz=${kernel[0]} initrd=${kernel[1]} kernel_dir=${kernel[2]}

if [ -z "$out" ]; then
  mkdir -p "$PWD/build/vm"
  out=$(mktemp -d "$PWD/build/vm/run-XXXXXX")
fi
mkdir -p "$out"
out=$(cd "$out" && pwd)
rm -f "$out/rc" "$out/guest.log" "$out/console.log" "$out/qemu.log"

# The run's init, run by the initramfs's PID 1 (busybox sh) with the host's "/" at /newroot and
# this run's folder at /out. Folders the guest's tmpfs would hide (the caller's working directory
# and --out, where they lie below /tmp or /run) are bound aside first and put back on top.
init=$out/init.sh
q() { printf %q "$1"; }
# shellcheck disable=SC2016  # $R in single quotes: the guest's shell expands it
{
  echo 'R=/newroot'
  echo 'mount -t proc proc $R/proc; mount -t sysfs sysfs $R/sys; mount -t devtmpfs devtmpfs $R/dev'
  echo 'mkdir -p $R/dev/pts $R/dev/shm; mount -t devpts -o ptmxmode=0666 devpts $R/dev/pts; mount -t tmpfs tmpfs $R/dev/shm'
  n=0
  for dir in "$PWD" "$out"; do
    case $dir/ in
      /tmp/* | /run/*) echo "mkdir -p /keep/$n; mount --bind \$R$(q "$dir") /keep/$n" ;;
    esac
    n=$((n + 1))
  done
  echo 'mount -t tmpfs tmpfs $R/run; mount -t tmpfs tmpfs $R/tmp'
  n=0
  for dir in "$PWD" "$out"; do
    case $dir/ in
      /tmp/* | /run/*) echo "mkdir -p \$R$(q "$dir"); mount --move /keep/$n \$R$(q "$dir")" ;;
    esac
    n=$((n + 1))
  done
  # The output share writable at its own path (the read-only root shows it there read-only).
  echo "mount --bind /out \$R$(q "$out")"
  {
    echo 'export PATH=/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin HOME=/root TZ=UTC'
    echo "export LIFTD_VM_KERNEL_DIR=$(q "$kernel_dir")"
    for name in "${envs[@]}"; do
      [ -n "${!name+x}" ] && echo "export $name=$(q "${!name}")"
    done
    echo "cd $(q "$PWD") || exit 125"
    printf 'exec'
    printf ' %q' "$@"
    echo
  } >"$out/command.sh"
  echo "chroot \$R /bin/sh $(q "$out/command.sh") >/out/guest.log 2>&1"
  echo 'echo $? >/out/rc'
  echo 'sync'
  echo 'poweroff -f'
} >"$init"

# Ahead of other work on the host (compilers) where allowed, as the systemd stage's guest: the
# guest runs liftd's 15 ms cycle, whose wake-ups a starved guest misses.
nice=()
[ "$(id -u)" = 0 ] && nice=(nice -n -10)
# No default devices (no network card, no VGA): only what the run asks for. The guest console
# goes to console.log; panic=-1 with -no-reboot ends QEMU on a kernel panic instead of a reboot.
set +e
timeout --kill-after=10 "$timeout_s" "${nice[@]}" "$qemu" -machine q35,accel="$accel" -cpu "$cpu" -m "$mem" \
  -smp "$smp" -nodefaults -no-user-config -display none -no-reboot \
  -kernel "$vmlinuz" -initrd "$initrd" \
  -append "console=ttyS0 panic=-1 loglevel=4" \
  -chardev file,id=console,path="$out/console.log" -serial chardev:console \
  -virtfs local,path=/,mount_tag=host,security_model=none,readonly=on,multidevs=remap \
  -virtfs local,path="$out",mount_tag=out,security_model=none,multidevs=remap \
  "${qemu_args[@]}" </dev/null >"$out/qemu.log" 2>&1
qemu_rc=$?
set -e
if [ $qemu_rc = 124 ] || [ $qemu_rc = 137 ]; then
  echo "vm boot: the guest did not finish within $timeout_s s" >&2
  tail -20 "$out/console.log" >&2 || true
  exit 124
fi
if [ ! -s "$out/rc" ]; then
  echo "vm boot: the guest did not run the command (QEMU exit $qemu_rc); QEMU said:" >&2
  tail -10 "$out/qemu.log" >&2 || true
  echo "vm boot: the console's end:" >&2
  tail -30 "$out/console.log" >&2 || true
  exit 125
fi
exit "$(cat "$out/rc")"
