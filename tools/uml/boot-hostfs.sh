#!/usr/bin/env bash
# Runs one command inside user-mode Linux (Debian's linux.uml, an ordinary process: no KVM, no
# root file system image) whose root file system is this machine's own "/" through hostfs, and
# returns the command's exit code. The guest's own kernel has what the host's may lack (AF_CAN,
# vcan); programs, libraries and the build tree are the host's files.
#
#   tools/uml/boot-hostfs.sh [--out DIR] [--timeout S] [--mem SIZE] [--modules M1,M2,...]
#                            [--env NAME]... -- COMMAND [ARG...]
#
#   --out DIR       where the guest writes guest.log (the command's stdout and stderr), rc
#                   (its exit code) and console.log (the kernel's console); default: a new
#                   folder under build/uml. It may lie under /tmp, /run or /dev/shm, as may the
#                   caller's working directory: see "Inside the guest" below.
#   --timeout S     the kernel is killed after S seconds (default 600)
#   --mem SIZE      guest memory (default 1024M)
#   --modules LIST  kernel modules to insmod in this order, as paths below the modules folder
#                   of the installed UML kernel (e.g. net/can/can.ko); modprobe finds nothing
#                   there, the modules are not under /lib/modules
#   --env NAME      pass the host's NAME=value into the guest (repeatable); the guest starts
#                   with PATH, HOME and TZ only, in the caller's working directory
#
# Exit codes: the command's own; 124 when the timeout killed the kernel; 125 when the kernel did
# not run or the guest never wrote its exit code (the console log is printed then).
# Inside the guest: proc, sysfs, devpts (a new pty instance), tmpfs on /run and /tmp (and
# /dev/shm), so that the tests' sockets, ptys' links and temporary files stay the guest's own.
# Those tmpfs hide the host's folders of the same name; the caller's working directory (the
# checkout, e.g. a clone in /tmp) and --out, where they lie below one of them, are mounted again
# from the host over hostfs at the same path, so the guest sees the build tree and the host sees
# what the guest writes.
# Nothing runs as PID 1 but the generated init: it runs the command and halts.
set -euo pipefail

out="" timeout_s=600 mem=1024M modules="" envs=()
while [ $# -gt 0 ]; do
  case $1 in
    --out) out=$2; shift 2 ;;
    --timeout) timeout_s=$2; shift 2 ;;
    --mem) mem=$2; shift 2 ;;
    --modules) modules=$2; shift 2 ;;
    --env) envs+=("$2"); shift 2 ;;
    --) shift; break ;;
    *) echo "boot-hostfs: unknown option $1" >&2; exit 2 ;;
  esac
done
[ $# -gt 0 ] || { echo "boot-hostfs: no command given" >&2; exit 2; }

kernel=$(command -v linux.uml || true)
if [ -z "$kernel" ]; then
  echo "boot-hostfs: linux.uml not found (Debian package user-mode-linux)" >&2
  exit 125
fi
version=$(ls /usr/lib/uml/modules 2>/dev/null | sort -V | tail -1)
moddir=/usr/lib/uml/modules/$version/kernel

if [ -z "$out" ]; then
  mkdir -p "$PWD/build/uml"
  out=$(mktemp -d "$PWD/build/uml/run-XXXXXX")
fi
mkdir -p "$out"
out=$(cd "$out" && pwd)
# Host folders the guest's tmpfs would hide: mounted again over hostfs (see above).
hidden=()
for dir in "$PWD" "$out"; do
  case $dir/ in /tmp/* | /run/* | /dev/shm/*) hidden+=("$dir") ;; esac
done
rm -f "$out/rc" "$out/guest.log" "$out/console.log"

# The guest's PID 1: a shell script on hostfs, written here with the caller's directory, the
# passed environment and the command baked in (the kernel command line carries none of them).
init=$out/init.sh
{
  echo '#!/bin/sh'
  echo 'export PATH=/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin HOME=/root TZ=UTC'
  echo 'mount -t proc proc /proc; mount -t sysfs sysfs /sys'
  echo 'mount -t tmpfs tmpfs /run; mount -t tmpfs tmpfs /tmp'
  echo '[ -d /dev/shm ] && mount -t tmpfs tmpfs /dev/shm'
  for dir in "${hidden[@]}"; do
    q=$(printf %q "$dir")
    echo "mkdir -p $q && mount -t hostfs -o $q hostfs $q || { echo 'boot-hostfs: cannot mount' $q 'from the host' >&2; exit 1; }"
  done
  echo 'mkdir -p /dev/pts; mount -t devpts -o newinstance,ptmxmode=0666 devpts /dev/pts'
  echo 'mount --bind /dev/pts/ptmx /dev/ptmx 2>/dev/null'
  echo 'ip link set lo up 2>/dev/null'
  echo "cd $(printf %q "$PWD")"
  for name in "${envs[@]}"; do
    [ -n "${!name+x}" ] && echo "export $name=$(printf %q "${!name}")"
  done
  echo '('
  IFS=, read -ra mods <<<"$modules"
  for m in "${mods[@]}"; do
    [ -n "$m" ] && echo "  insmod $(printf %q "$moddir/$m") || exit 126"
  done
  printf '  exec'
  printf ' %q' "$@"
  echo
  echo ") > $(printf %q "$out/guest.log") 2>&1"
  echo "echo \$? > $(printf %q "$out/rc")"
  echo 'sync'
  echo 'halt -f -f 2>/dev/null || poweroff -f -f 2>/dev/null || echo o > /proc/sysrq-trigger'
  echo 'sleep 5'
} >"$init"
chmod +x "$init"

# UML keeps the guest's memory in a file under TMPDIR; a unique umid keeps parallel guests apart.
umid=liftd-$$
set +e
timeout --kill-after=10 "$timeout_s" "$kernel" mem="$mem" umid="$umid" \
  root=/dev/root rootfstype=hostfs rootflags=/ rw init="$init" quiet \
  con=null con0=null,fd:2 </dev/null 2>"$out/console.log" >/dev/null
kernel_rc=$?
set -e
rm -rf "$HOME/.uml/$umid" 2>/dev/null || true
if [ $kernel_rc = 124 ] || [ $kernel_rc = 137 ]; then
  echo "boot-hostfs: the guest did not finish within $timeout_s s" >&2
  tail -20 "$out/console.log" >&2 || true
  exit 124
fi
if [ ! -s "$out/rc" ]; then
  echo "boot-hostfs: the guest did not run the command (kernel exit $kernel_rc); console:" >&2
  tail -30 "$out/console.log" >&2 || true
  exit 125
fi
exit "$(cat "$out/rc")"
