#!/usr/bin/env bash
# The systemd stage: the installed service as an operator meets it. Boots Debian 12 with systemd
# as PID 1 under user-mode Linux (an ext4 image from build-rootfs.sh, cached), installs the
# package built from BUILD with apt, and runs guest/guest.sh there: the service against a
# simulated DCP drive on a serial line (UML lines ttyS1 and ttyS2 joined by a host socketpair),
# restart, reload, faults in the journal, stop during a travel, group access, bad starts, the
# watchdog, a stalled line. Each check prints "ok - ..." or "FAIL - ..."; exits 1 on any FAIL or
# when the guest did not finish, 0 otherwise. Where user-mode Linux cannot run it says SKIPPED
# and exits 0.
#   tests/systemd/stage.sh [BUILD]        (default build; needs root for the image and apt)
#   LIFTD_UML_CACHE=DIR                   where the root file system is cached (/var/cache/liftd-uml)
#   LIFTD_STAGE_DEB=FILE                  install this package instead of one built from BUILD
#                                         (e.g. an older version, to see which checks it fails)
set -uo pipefail
{  # read to the end before running: an edit while it runs cannot change what runs
here=$(cd "$(dirname "$0")" && pwd)
repo=$(cd "$here/../.." && pwd)
build=$(cd "${1:-$repo/build}" && pwd)
start=$SECONDS
took() { echo "systemd stage: took $((SECONDS - start)) s${1:+ ($1)}"; }
skip() {
  echo "SKIPPED: systemd stage: $*"
  echo "SKIPPED: systemd stage: $*" >&2
  took
  exit 0
}
die() {
  echo "FAIL - systemd stage: $*"
  took
  exit 1
}

[ "$(id -u)" = 0 ] || skip "needs root (the root file system image, apt inside it)"
"$repo/tools/install-deps.sh" --uml-systemd || die "cannot install user-mode-linux, mmdebstrap, e2fsprogs"
# Can user-mode Linux run here? A kernel that boots prints its panic when init exits.
probe=$(timeout 30 linux.uml mem=64M root=/dev/root rootfstype=hostfs rootflags=/ ro init=/bin/true \
  con=null con0=null,fd:1 ssl=null 2>&1 | tr -d '\r')
echo "$probe" | grep -q "Attempted to kill init" ||
  skip "user-mode Linux does not boot on this machine: $(echo "$probe" | tail -3 | tr '\n' ' ')"
kernel=$(echo "$probe" | sed -n 's/.*Linux version \([^ ]*\).*/\1/p' | head -1)

image=$("$here/build-rootfs.sh") || die "no root file system image"
work=$(mktemp -d /var/tmp/liftd-systemd-stage-XXXXXX)
trap 'rm -rf "$work"' EXIT
mkdir "$work/share"
if [ -n "${LIFTD_STAGE_DEB:-}" ]; then
  cp "$LIFTD_STAGE_DEB" "$work/share/liftd_stage_test.deb" || die "no $LIFTD_STAGE_DEB"
else
  (cd "$build" && cpack -G DEB -B "$work/deb" >"$work/cpack.log" 2>&1) ||
    { cat "$work/cpack.log"; die "cpack failed"; }
  cp "$work"/deb/liftd_*.deb "$work/share/" || die "no package"
fi
cp "$here"/guest/guest.sh "$here"/guest/api.py "$here"/guest/ioboard.py "$work/share/"
cp --sparse=always "$image" "$work/root.img"
prep=$((SECONDS - start))

# Two serial lines joined on the host: liftd gets ttyS1, the simulated drive ttyS2.
timeout 660 python3 - "$work/root.img" "$work/share" "$work/console.log" <<'PY'
import os, signal, socket, subprocess, sys, threading, time
image, share, console = sys.argv[1:4]
liftd_end, drive_end = socket.socketpair()
umid = f"liftd-stage-{os.getpid()}"
# Ahead of other work on the host (compilers): the guest runs liftd's 15 ms cycle, whose
# wake-ups a starved guest misses (the drive link then fails and travels end short).
args = ["nice", "-n", "-10", "linux.uml", "mem=1024M", f"ubd0={image}", "root=/dev/ubda", "rw",
        "init=/lib/systemd/systemd", "con=null", "con0=null,fd:2", "ssl=null",
        f"ssl1=fd:{liftd_end.fileno()}", f"ssl2=fd:{drive_end.fileno()}", f"umid={umid}",
        f"liftd.share={share}", "systemd.show_status=0", "quiet"]
with open(console, "w") as out:
    # A session of its own: the kernel's helper processes end with it, whatever happens here.
    guest = subprocess.Popen(args, stdin=subprocess.DEVNULL, stdout=out, stderr=out,
                             pass_fds=(liftd_end.fileno(), drive_end.fileno()),
                             start_new_session=True)
    # The 6.1 kernel's idle loop sleeps only while its host timer is armed. Now and then (about
    # one stage in eight here) the guest loses a timer event: its clock event thinks an expiry is
    # programmed, the host timer is not, the idle loop spins in system calls (the kernel process
    # at 100 % system time, its guest CPU idle) and no guest timer fires again. A SIGALRM is what
    # the host timer would have sent: the guest's timer interrupt runs its expired timers and
    # programs the next one. A spurious one changes nothing (the interrupt finds nothing due), so
    # the watcher sends one whenever the kernel process spent most of 3 s in system calls and
    # little running guest code, and counts them (kicks.txt, printed by the stage).
    def kick_lost_timers():
        def times():
            try:
                with open(f"/proc/{guest.pid}/stat") as f:
                    fields = f.read().rsplit(")", 1)[1].split()
                return int(fields[11]), int(fields[12])  # utime, stime in clock ticks
            except (OSError, IndexError, ValueError):
                return None
        hz = os.sysconf("SC_CLK_TCK")
        window = 3.0
        samples = []
        while guest.poll() is None:
            time.sleep(1.0)
            if not os.path.exists(os.path.join(share, "guest.log")):
                continue  # booting: the kernel's own signal handlers may not be there yet
            now = times()
            if now is None:
                return
            samples = (samples + [(time.monotonic(), now)])[-4:]
            (t0, (u0, s0)), (t1, (u1, s1)) = samples[0], samples[-1]
            if t1 - t0 < window - 0.5:
                continue
            span = (t1 - t0) * hz
            if s1 - s0 >= 0.8 * span and u1 - u0 <= 0.2 * span:
                os.kill(guest.pid, signal.SIGALRM)
                with open(os.path.join(share, "kicks.txt"), "a") as k:
                    k.write(f"{time.strftime('%H:%M:%S')} system {(s1 - s0) / hz:.2f} s, guest "
                            f"code {(u1 - u0) / hz:.2f} s of {t1 - t0:.1f} s: SIGALRM sent\n")
                samples = []
    threading.Thread(target=kick_lost_timers, daemon=True).start()
    try:
        sys.exit(guest.wait(timeout=600))
    except subprocess.TimeoutExpired:
        # A guest that stopped making progress: what its kernel and the host say about it goes
        # to hang.txt beside the guest's logs, then the whole guest goes. Not `sysrq t`: the 6.1
        # UML kernel panics in it ("Segfault with no mm" in print_worker_info).
        with open(os.path.join(share, "hang.txt"), "w") as report:
            def mconsole(*words):
                r = subprocess.run(["uml_mconsole", umid, *words], capture_output=True, text=True,
                                   timeout=20, check=False)
                report.write(f"### uml_mconsole {' '.join(words)}\n{r.stdout}{r.stderr}\n")
            mconsole("sysrq", "w")  # blocked tasks, to the console log
            for name in ("loadavg", "stat", "interrupts", "timer_list"):
                mconsole("proc", name)
            time.sleep(2)  # does the guest's time move, do its timers fire?
            mconsole("proc", "timer_list")
            ps = subprocess.run(["ps", "-o", "pid,stat,pcpu,time,wchan:30,args", "--sid",
                                 str(guest.pid)], capture_output=True, text=True, check=False)
            report.write(f"### host processes of the guest\n{ps.stdout}\n")
            for line in ps.stdout.splitlines()[1:]:
                pid = line.split()[0]
                for what in ("stack", "syscall"):
                    try:
                        with open(f"/proc/{pid}/{what}") as f:
                            report.write(f"### host /proc/{pid}/{what}\n{f.read()}\n")
                    except OSError as e:
                        report.write(f"### host /proc/{pid}/{what}: {e}\n")
        os.killpg(guest.pid, signal.SIGKILL)
        guest.wait()
        print("systemd stage: the guest had not finished after 600 s (a run takes 3 to 5 "
              "minutes); what it and the host said about it is in hang.txt", file=sys.stderr)
        sys.exit(124)
PY
rc=$?
echo "systemd stage: kernel $kernel, image $(basename "$image")"
if [ -s "$work/share/kicks.txt" ]; then
  echo "systemd stage: the guest's timer was kicked $(wc -l <"$work/share/kicks.txt") times (a lost timer event):"
  cat "$work/share/kicks.txt"
fi
cat "$work/share/results.txt" 2>/dev/null
if [ ! -s "$work/share/guest.rc" ]; then
  echo "--- guest log (tail)"
  tail -40 "$work/share/guest.log" 2>/dev/null
  echo "--- console (tail)"
  tail -40 "$work/console.log"
  if [ -s "$work/share/hang.txt" ]; then
    echo "--- the hung guest's load, host processes and timers (head of hang.txt)"
    grep -A3 -E "^### (uml_mconsole proc loadavg|host processes)" "$work/share/hang.txt"
    grep -m2 -E "^now at" "$work/share/hang.txt"
  fi
  keep=/var/tmp/liftd-systemd-stage-failed
  rm -rf "$keep" && cp -r "$work/share" "$keep" && cp "$work/console.log" "$keep/" &&
    rm -f "$keep"/*.deb && echo "--- the guest's logs and its console are in $keep"
  die "the guest did not finish (user-mode Linux exit $rc)"
fi
oks=$(grep -c '^ok - ' "$work/share/results.txt")
fails=$(grep -c '^FAIL - ' "$work/share/results.txt")
if [ "$fails" != 0 ] || [ "$(cat "$work/share/guest.rc")" != 0 ]; then
  echo "--- guest log (tail)"
  tail -60 "$work/share/guest.log"
  keep=/var/tmp/liftd-systemd-stage-failed
  rm -rf "$keep" && cp -r "$work/share" "$keep" && rm -f "$keep"/*.deb &&
    echo "--- the guest's log and journal are in $keep"
  took "$oks ok, $fails FAIL; preparation $prep s"
  exit 1
fi
took "$oks checks ok; preparation $prep s"
exit 0
}
