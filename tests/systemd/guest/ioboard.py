#!/usr/bin/env python3
"""The stage's drive and I/O board inside the guest.

Runs dcp-drive-sim on /dev/ttyS2 (the far end of liftd's /dev/ttyS1), which is also the shaft's
absolute encoder (CAN frames on the Unix endpoint /run/stage/encoder.sock, liftd's
can.interface), and, as the I/O board's daemon would, keeps an API connection that sends liftd
the machine inputs (safety chain and doors closed and locked). Files under
/run/stage steer it: sim.cmd (a FIFO: lines for the drive's stdin, e.g. "fault on"),
io.pause (while it exists: no API connection), io.pause-at-end (becomes io.pause when the
connection ends: liftd stopped), sim.stop (end the drive for good). It writes
sim.log (the drive's lines), sim.status (its newest status line) and io.log.
"""
import os
import re
import socket
import subprocess
import sys
import threading
import time

RUN = "/run/stage"
SIM = sys.argv[1] if len(sys.argv) > 1 else "/usr/bin/dcp-drive-sim"
STATUS = re.compile(r"pos (-?[0-9.]+) mm v ([-+0-9.]+) m/s")
ENCODER = f"{RUN}/encoder.sock"


def log(text):
    with open(f"{RUN}/io.log", "a") as f:
        f.write(f"{time.monotonic():.3f} {text}\n")


def read_sim(sim):
    with open(f"{RUN}/sim.log", "a") as out:
        for line in sim.stdout:
            m = STATUS.search(line)
            if m:
                with open(f"{RUN}/sim.status.tmp", "w") as f:
                    f.write(line)
                os.replace(f"{RUN}/sim.status.tmp", f"{RUN}/sim.status")
            else:
                out.write(line)
                out.flush()


def forward_commands(sim):
    while True:
        with open(f"{RUN}/sim.cmd") as fifo:
            for line in fifo:
                sim.stdin.write(line)
                sim.stdin.flush()


def main():
    os.makedirs(RUN, exist_ok=True)
    if not os.path.exists(f"{RUN}/sim.cmd"):
        os.mkfifo(f"{RUN}/sim.cmd")
    # The encoder's socket is for liftd's user too (umask 0: connecting needs write access).
    # The drive and its encoder are separate hardware on a real lift: real-time, one step below
    # liftd's cycle (SCHED_FIFO 80), as `liftd --simulate` runs its own simulators. At normal
    # priority a guest busy with other work starved them: the encoder's frames went stale and
    # liftd rightly ended a travel with position_lost.
    sim = subprocess.Popen(["chrt", "-f", "79", SIM, "--device", "/dev/ttyS2", "--status", "0.01",
                            "--reconnect", "--encoder", f"unix:{ENCODER}"],
                           stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True, bufsize=1,
                           preexec_fn=lambda: os.umask(0))
    threading.Thread(target=read_sim, args=(sim,), daemon=True).start()
    threading.Thread(target=forward_commands, args=(sim,), daemon=True).start()
    conn = None
    while True:
        if os.path.exists(f"{RUN}/sim.stop"):
            sim.terminate()
            sim.wait()
            log("drive stopped")
            return
        if os.path.exists(f"{RUN}/io.pause"):
            if conn:
                conn.close()
                conn = None
                log("paused")
            time.sleep(0.05)
            continue
        if conn is None:
            try:
                conn = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
                conn.settimeout(2)
                conn.connect("/run/liftd/api.sock")
                conn.setblocking(False)
                log("connected")
            except OSError as e:
                log(f"connect: {e}")
                conn = None
                time.sleep(0.2)
                continue
        request = ('{"cmd":"inputs","safety_chain":true,"doors_closed":true,"doors_locked":true,'
                   '"zone_level":false}\n')
        try:
            conn.send(request.encode())
            while True:
                data = conn.recv(65536)
                if not data:
                    raise OSError("closed by liftd")
        except BlockingIOError:
            pass
        except OSError as e:
            log(f"connection ended: {e}")
            conn.close()
            conn = None
            if os.path.exists(f"{RUN}/io.pause-at-end"):
                os.rename(f"{RUN}/io.pause-at-end", f"{RUN}/io.pause")
        time.sleep(0.01)


main()
