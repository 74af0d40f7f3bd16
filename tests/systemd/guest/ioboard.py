#!/usr/bin/env python3
"""The stage's drive and I/O board inside the guest.

Runs dcp-drive-sim on /dev/ttyS2 (the far end of liftd's /dev/ttyS1) and, as the I/O board's
daemon would, keeps an API connection that sends liftd the machine inputs (safety chain and
doors closed and locked) with the car position the simulated drive reports. Files under
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
# The drive's newest position (mm), speed (m/s) and when its line was read: the position sent
# is extrapolated to the moment of sending (by at most 50 ms), as an encoder would have it.
position = [0.0, 0.0, time.monotonic()]


def log(text):
    with open(f"{RUN}/io.log", "a") as f:
        f.write(f"{time.monotonic():.3f} {text}\n")


def read_sim(sim):
    with open(f"{RUN}/sim.log", "a") as out:
        for line in sim.stdout:
            m = STATUS.search(line)
            if m:
                position[:] = [float(m.group(1)), float(m.group(2)), time.monotonic()]
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
    sim = subprocess.Popen([SIM, "--device", "/dev/ttyS2", "--status", "0.01", "--reconnect"],
                           stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True, bufsize=1)
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
        pos, speed, seen = position
        now_mm = pos + speed * 1000.0 * min(time.monotonic() - seen, 0.05)
        request = ('{"cmd":"inputs","safety_chain":true,"doors_closed":true,"doors_locked":true,'
                   f'"zone_level":false,"position_mm":{round(now_mm)}}}\n')
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
