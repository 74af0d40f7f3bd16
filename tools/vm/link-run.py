#!/usr/bin/env python3
"""The VM stage's helpers (tools/vm/serial-stage.sh): one run of liftd's DCP link over a serial
line, measured the way liftd itself reports it, and what joins the host and the guest.

  link-run.py run --name NAME --device DEV --out DIR --seconds S --liftd BIN --config JSON
                  (--encoder-socket PATH | --encoder-port DEV)
      Starts liftd (drive.device DEV, a real DCP lift, not --simulate) with its socket, record
      and flight recorder files in a new tmpfs folder, plays the I/O board (machine inputs every
      100 ms), waits for the link, then travels between floors for S seconds and writes
      DIR/NAME.json: the travels and their outcome, liftd's stats and status, the cycle thread's
      wake-ups, the reply times of the flight recorder, and liftd's own lines about the serial
      device (liftd's log: DIR/NAME.liftd.log). The car's position comes from the drive
      simulator's shaft encoder (position.source "can"): --encoder-socket is its Unix endpoint
      (on the host), --encoder-port a virtio serial port that carries its frames into the guest,
      served here to liftd on a Unix endpoint of this run's own.
  link-run.py pty-pair DIR
      Two pseudo-terminals joined by this process, as QEMU joins a guest UART to a host pty:
      writes DIR/liftd-end and DIR/drive-end (their slave paths) and copies bytes between their
      masters until killed. The host run's line.
  link-run.py encoder-host SIM_SOCKET QEMU_SOCKET
      Carries the simulator's encoder frames (SOCK_SEQPACKET, one CAN frame each) over QEMU's
      virtio serial port's host socket (a byte stream) into the guest, until killed.
  link-run.py table DIR NAME... / judge DIR BOUND NAME...
      The figures of the named runs as a table / their judgement (exit 1 on a failure).
"""
import json
import os
import pty
import select
import signal
import socket
import struct
import subprocess
import sys
import tempfile
import threading
import time
import tty

CAN_FRAME = 16  # struct can_frame: the record of liftd's Unix CAN endpoint (lib/can/socket.hpp)
ENCODER_ID = 0x190  # dcp-drive-sim's encoder frame (position.can_id 400)
CYCLE_S = 0.015  # DCP 7.2: one master frame every 15 ms
DEADLINE_US = 13625  # DCP 7.2: the reply complete 13.625 ms after the frame began


def realtime(priority):
    """SCHED_FIFO at priority, where allowed: the helpers stand for hardware (drive, encoder, I/O
    board) one step below liftd's cycle (80), as the systemd stage's drive runs."""
    try:
        os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param(priority))
    except (PermissionError, OSError):
        pass


# ---------------------------------------------------------------- joining lines
def pty_pair(folder):
    realtime(79)
    ends = {}
    for name in ("liftd-end", "drive-end"):
        master, slave = pty.openpty()
        tty.setraw(slave)
        ends[name] = (master, slave)
        path = os.ttyname(slave)
        with open(os.path.join(folder, name + ".tmp"), "w") as f:
            f.write(path + "\n")
        os.replace(os.path.join(folder, name + ".tmp"), os.path.join(folder, name))
    a, b = ends["liftd-end"][0], ends["drive-end"][0]
    peer = {a: b, b: a}
    poller = select.poll()
    for fd in (a, b):
        os.set_blocking(fd, False)
        poller.register(fd, select.POLLIN)
    # The slaves stay open here too: a master whose slave has no opener reports POLLHUP (EIO on
    # read) and would spin; the programs at the ends open and close them as they like.
    while True:
        for fd, _ in poller.poll(1000):
            try:
                data = os.read(fd, 4096)
            except (BlockingIOError, OSError):
                continue
            if data:
                try:
                    os.write(peer[fd], data)
                except OSError:
                    pass


def encoder_host(sim_socket, qemu_socket):
    realtime(78)
    while True:
        try:
            sim = socket.socket(socket.AF_UNIX, socket.SOCK_SEQPACKET)
            sim.connect(sim_socket)
            guest = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
            guest.connect(qemu_socket)
        except OSError:
            time.sleep(0.2)
            continue
        try:
            while True:
                record = sim.recv(64)
                if not record:
                    break
                if len(record) == CAN_FRAME:
                    guest.sendall(record)
        except OSError:
            pass
        sim.close()
        guest.close()
        time.sleep(0.2)


def encoder_guest(port, listen_path):
    """Serves the encoder frames arriving on the virtio serial port to liftd's Unix CAN endpoint
    (SOCK_SEQPACKET). The stream may begin mid-frame: frames are found by the encoder's
    identifier and length."""
    listener = socket.socket(socket.AF_UNIX, socket.SOCK_SEQPACKET)
    listener.bind(listen_path)
    listener.listen(1)
    peers = []

    def accept():
        while True:
            conn, _ = listener.accept()
            peers[:] = [conn]

    threading.Thread(target=accept, daemon=True).start()
    fd = os.open(port, os.O_RDWR)
    head = struct.pack("<IB", ENCODER_ID, 4)
    buffer = b""
    while True:
        buffer += os.read(fd, 4096)
        while len(buffer) >= CAN_FRAME:
            at = buffer.find(head)
            if at < 0:
                buffer = buffer[-4:]
                break
            if len(buffer) - at < CAN_FRAME:
                buffer = buffer[at:]
                break
            frame, buffer = buffer[at:at + CAN_FRAME], buffer[at + CAN_FRAME:]
            for conn in list(peers):
                try:
                    conn.send(frame)
                except OSError:
                    peers.remove(conn)


# ---------------------------------------------------------------- the API
class Api:
    def __init__(self, path, timeout=10):
        self.sock = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        self.sock.settimeout(timeout)
        self.sock.connect(path)
        self.file = self.sock.makefile("r")
        self.file.readline()  # the greeting
        self.next_id = 0

    def __call__(self, cmd, **args):
        self.next_id += 1
        request = {"cmd": cmd, "id": self.next_id, **args}
        self.sock.sendall((json.dumps(request) + "\n").encode())
        while True:
            line = self.file.readline()
            if not line:
                raise OSError("liftd closed the API connection")
            reply = json.loads(line)
            if reply.get("id") == self.next_id:
                return reply

    def result(self, cmd, **args):
        reply = self(cmd, **args)
        if not reply.get("ok"):
            raise RuntimeError(f"{cmd}: {reply.get('error')}")
        return reply["result"]


def io_board(socket_path, stop):
    """The I/O board's daemon: safety chain closed, doors closed and locked, every 100 ms (liftd
    ends any travel when inputs are older than inputs.timeout_ms, 500): every 100 ms."""
    realtime(70)
    api = None
    while not stop.is_set():
        try:
            if api is None:
                api = Api(socket_path)
            api("inputs", safety_chain=True, doors_closed=True, doors_locked=True)
        except (OSError, ValueError):
            api = None
        stop.wait(0.1)


def wait_for(what, seconds, step=0.1):
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        value = what()
        if value:
            return value
        time.sleep(step)
    return what()


def thread_switches(pid, name="liftd-cycle"):
    for tid in os.listdir(f"/proc/{pid}/task"):
        try:
            with open(f"/proc/{pid}/task/{tid}/comm") as f:
                if f.read().strip() != name:
                    continue
            fields = {}
            with open(f"/proc/{pid}/task/{tid}/status") as f:
                for line in f:
                    key, _, value = line.partition(":")
                    fields[key] = value.strip()
            return int(fields["voluntary_ctxt_switches"]), int(fields["nonvoluntary_ctxt_switches"])
        except OSError:
            continue
    return None


def reply_times(trace_file):
    """Microseconds from each frame's send to the look that found its good reply complete (the
    flight recorder's tx and rx records)."""
    times = []
    sent = None
    with open(trace_file) as f:
        for line in f:
            if line.startswith("#"):
                continue
            words = line.split()
            if len(words) < 3:
                continue
            t = float(words[0])
            flags = line.split("|")[0].split()[-1]
            if words[1] == "tx" and "sent" in flags:
                sent = t
            elif words[1] == "rx" and sent is not None:
                if flags == "reply":
                    times.append((t - sent) * 1e6)
                sent = None
    return times


def percentile(values, p):
    if not values:
        return None
    ordered = sorted(values)
    return ordered[min(len(ordered) - 1, int(p / 100.0 * len(ordered)))]


def sysfs(path):
    try:
        with open(path) as f:
            return f.read().strip()
    except OSError:
        return None


def run(args):
    out = args.out
    name = args.name
    base = "/run" if os.access("/run", os.W_OK) else tempfile.gettempdir()
    runtime = tempfile.mkdtemp(prefix="liftd-vm-", dir=base)
    result = {"name": name, "device": args.device, "seconds": args.seconds, "travels": [],
              "travel_errors": [],
              "errors": []}
    log_path = os.path.join(out, f"{name}.liftd.log")
    liftd = None
    stop = threading.Event()
    try:
        if args.encoder_port:
            encoder = os.path.join(runtime, "encoder.sock")
            threading.Thread(target=encoder_guest, args=(args.encoder_port, encoder),
                             daemon=True).start()
        else:
            encoder = args.encoder_socket
        with open(args.config) as f:
            config = json.load(f)
        config["log"] = {"level": "info"}
        config["drive"].update(kind="dcp", device=args.device, echo="auto")
        config["api"].update(socket=os.path.join(runtime, "api.sock"), socket_group="",
                             read_group="", control_group="", inputs_group="")
        config["record"].update(enabled=True, path=os.path.join(runtime, "record.db"))
        # The flight recorder holds the whole run (at most 300 s): the reply times come from it.
        config["rt"]["flight_recorder_s"] = max(30, min(300, int(args.seconds) + 30))
        config["position"].update(source="can", can_signed=True)
        config["can"]["interface"] = f"unix:{encoder}"
        config_path = os.path.join(runtime, "liftd.json")
        with open(config_path, "w") as f:
            json.dump(config, f, indent=2)
        with open(os.path.join(out, f"{name}.config.json"), "w") as f:
            json.dump(config, f, indent=2)
        check = subprocess.run([args.liftd, "--check-config", config_path], capture_output=True,
                               text=True)
        if check.returncode != 0:
            raise RuntimeError(f"liftd --check-config: {check.stdout}{check.stderr}")
        env = dict(os.environ, RUNTIME_DIRECTORY=runtime)
        log = open(log_path, "w")
        liftd = subprocess.Popen([args.liftd, "--config", config_path], stdout=log,
                                 stderr=subprocess.STDOUT, env=env)
        sock = config["api"]["socket"]
        if not wait_for(lambda: os.path.exists(sock) or liftd.poll() is not None, 30):
            raise RuntimeError("liftd made no API socket in 30 s")
        if liftd.poll() is not None:
            raise RuntimeError(f"liftd exited ({liftd.returncode})")
        threading.Thread(target=io_board, args=(sock, stop), daemon=True).start()
        api = Api(sock)

        def status():
            return api.result("status")

        def ready():
            s = status()
            return s if s["drive"]["state"] == "ready" and s["car"]["position_mm"] is not None else None

        start = time.monotonic()
        if not wait_for(ready, 60, step=0.25):
            raise RuntimeError(f"the drive was not ready after 60 s: {status()}")
        result["link_up_s"] = round(time.monotonic() - start, 1)
        switches0 = thread_switches(liftd.pid)
        stats0 = api.result("stats")
        t0 = time.monotonic()
        floors = [f["level_mm"] for f in config["floors"]]
        plan = [2, 0, 3, 1, 4, 0]
        n = 0
        while time.monotonic() - t0 < args.seconds:
            target = plan[n % len(plan)]
            n += 1
            if not wait_for(ready, 20, step=0.25):
                result["travel_errors"].append(f"travel {n}: the drive was not ready: {status()}")
                break
            def newest():
                runs = api.result("travels", last=1)["travels"]
                return runs[-1] if runs else {"id": 0, "cause": None}

            before = newest()["id"]
            began = time.monotonic()
            reply = api("travel", floor=target)
            if not reply.get("ok"):
                result["travel_errors"].append(f"travel {n} to {target}: refused: {reply.get('error')}")
                break
            # Ended: the sequencer idle and the drive standing, and then a run newer than the one
            # before with its cause. `travels` carries the run's curve (hundreds of samples):
            # asked for only once the status says the run is over, to keep the guest's load low.
            def over():
                s = status()
                if s["travel"]["state"] != "idle" or s["drive"]["state"] == "travelling":
                    return None
                r = newest()
                return r if r["id"] > before and r["cause"] is not None else None

            ended = wait_for(over, 60, step=0.25)
            s = status()
            cause = ended["cause"] if ended else None
            travel = {"floor": target, "seconds": round(time.monotonic() - began, 2),
                      "cause": cause, "car_floor": s["car"]["floor"],
                      "position_mm": s["car"]["position_mm"], "faults": s["faults"]}
            result["travels"].append(travel)
            if cause != "arrived" or s["car"]["floor"] != target or s["faults"]:
                result["travel_errors"].append(f"travel {n} to floor {target} (level {floors[target]} mm): "
                                        f"{travel}")
                break
        elapsed = time.monotonic() - t0
        stats1 = api.result("stats")
        switches1 = thread_switches(liftd.pid)
        final = status()
        result["elapsed_s"] = round(elapsed, 1)
        result["stats_start"] = stats0
        result["stats"] = stats1
        result["status"] = final
        if switches0 and switches1:
            result["cycle_thread"] = {"voluntary": switches1[0] - switches0[0],
                                      "nonvoluntary": switches1[1] - switches0[1]}
        saved = api("trace", count=1, save=True)
        if saved.get("ok") and saved["result"].get("file"):
            times = reply_times(saved["result"]["file"])
            result["trace_replies"] = len(times)
            result["reply_us"] = {"p50": percentile(times, 50), "p99": percentile(times, 99),
                                  "max": max(times) if times else None}
        else:
            result["errors"].append(f"trace save: {saved}")
        tty_name = (stats1.get("dcp", {}).get("serial") or {}).get("tty")
        if tty_name:
            result["sysfs"] = {
                "latency_timer": sysfs(f"/sys/class/tty/{tty_name}/device/latency_timer"),
                "rx_trig_bytes": sysfs(f"/sys/class/tty/{tty_name}/rx_trig_bytes"),
                "low_latency_flags": sysfs(f"/sys/class/tty/{tty_name}/flags"),
            }
    except Exception as e:  # noqa: BLE001: whatever went wrong is the run's result
        result["errors"].append(f"{type(e).__name__}: {e}")
    finally:
        stop.set()
        if liftd is not None and liftd.poll() is None:
            liftd.send_signal(signal.SIGTERM)
            try:
                liftd.wait(15)
            except subprocess.TimeoutExpired:
                liftd.kill()
                liftd.wait()
        if liftd is not None:
            result["liftd_exit"] = liftd.returncode
        # What liftd said about the line: its serial_device, serial_latency_* and line_echo lines.
        lines = []
        try:
            with open(log_path) as f:
                for line in f:
                    if any(k in line for k in ("serial device", "latency", "echo", "overrun",
                                               "link fault", "link_fault", "skipp")):
                        lines.append(line.rstrip())
        except OSError:
            pass
        result["liftd_lines"] = lines[:40]
        with open(os.path.join(out, f"{name}.json"), "w") as f:
            json.dump(result, f, indent=1)
        subprocess.run(["rm", "-rf", runtime], check=False)
    return 0 if not result["errors"] and not result["travel_errors"] else 1


# ---------------------------------------------------------------- figures and judgement
def figures(folder, name):
    with open(os.path.join(folder, f"{name}.json")) as f:
        r = json.load(f)
    d0 = r.get("stats_start", {}).get("dcp", {})
    d1 = r.get("stats", {}).get("dcp", {})
    c0 = r.get("stats_start", {}).get("cycle", {}).get("cycles", 0)
    c1 = r.get("stats", {}).get("cycle", {}).get("cycles", 0)
    cycles = c1 - c0

    def delta(key):
        return d1.get(key, 0) - d0.get(key, 0) if d1 else None

    serial = d1.get("serial") or {}
    echo = ((r.get("status") or {}).get("dcp") or {}).get("line_echo") or {}
    wake = r.get("cycle_thread", {}).get("voluntary")
    reply = r.get("reply_us") or {}
    return {
        "name": name, "errors": r.get("errors", []), "travel_errors": r.get("travel_errors", []),
        "liftd_exit": r.get("liftd_exit"), "link_up_s": r.get("link_up_s"),
        "driver_reported": serial.get("driver"), "travels": len(r.get("travels", [])),
        "arrived": sum(1 for t in r.get("travels", []) if t["cause"] == "arrived"),
        "seconds": r.get("elapsed_s"), "cycles": cycles,
        "cycles_by_time": round(r["elapsed_s"] / CYCLE_S) if r.get("elapsed_s") else None,
        "p50": reply.get("p50"), "p99_trace": reply.get("p99"), "max": reply.get("max"),
        "p99": d1.get("reply_p99_us"),
        "missing": delta("missing_replies"),
        "missing_per_1000": (1000.0 * delta("missing_replies") / cycles) if cycles > 0 else None,
        "skipped": delta("skipped_cycles"), "overruns": delta("overruns"),
        "checksum": delta("checksum_errors"), "collisions": delta("echo_collisions"),
        "repeats": delta("repeats"), "link_losses": delta("link_losses"),
        "longest_run": d1.get("longest_error_run"),
        "wakeups": (wake / cycles) if wake is not None and cycles > 0 else None,
        "echo": echo.get("state"), "driver": serial.get("driver") or "pty",
        "latency_timer": serial.get("latency_timer_ms"), "rx_trig": serial.get("rx_trig_bytes"),
        "sysfs": r.get("sysfs", {}), "lines": r.get("liftd_lines", []),
        "faults": (r.get("status") or {}).get("faults"),
        "link": ((r.get("status") or {}).get("link") or {}).get("state"),
    }


def fmt(value, spec="{:.0f}"):
    return "-" if value is None else spec.format(value)


def table(folder, names):
    head = ("line", "travels", "cycles", "p50 us", "p99 us", "max us", "miss/1000", "skipped",
            "bad", "wake/cyc", "echo", "driver", "lat ms", "rx_trig")
    rows = [head]
    for name in names:
        try:
            g = figures(folder, name)
        except (OSError, ValueError) as e:
            rows.append((name, f"no result ({e})") + ("",) * (len(head) - 2))
            continue
        bad = None if g["checksum"] is None else g["checksum"] + (g["collisions"] or 0)
        rows.append((name, f"{g['arrived']}/{g['travels']}", fmt(g["cycles"]), fmt(g["p50"]),
                     fmt(g["p99"]), fmt(g["max"]), fmt(g["missing_per_1000"], "{:.2f}"),
                     fmt(g["skipped"]), fmt(bad), fmt(g["wakeups"], "{:.2f}"), g["echo"] or "-",
                     g["driver"], fmt(g["latency_timer"]), fmt(g["rx_trig"])))
    widths = [max(len(str(row[i])) for row in rows) for i in range(len(head))]
    for row in rows:
        print("  ".join(str(c).ljust(w) for c, w in zip(row, widths)).rstrip())


# The driver the kernel binds to each line: the q35 machine's second UART is an ACPI PNP0501
# device, so the 8250 driver's PNP front end ("serial") holds it; on a board it may be the
# platform front end ("serial8250") or a SoC's own 8250 variant.
DRIVERS = {"16550a": ("serial", "serial8250"), "16550a-echo": ("serial", "serial8250"),
           "usb": ("ftdi_sio",), "pty": (None,)}


def judge(folder, bound, names, echo_names, functional_names):
    """Every line: liftd stopped cleanly, the link came up, the echo found where the line echoes
    and only there, the serial device as the kernel has it (driver; a 16550's receive FIFO
    trigger; a USB adapter's latency timer 1 ms once liftd opened it). The timing judgement
    (every travel arrived, no link fault, missing replies within the bound on the VM lines, reply
    p99 within DCP 7.2) for every line not named functional (a guest under software emulation: its timing is
    the emulator's)."""
    failed = 0
    for name in names:
        try:
            g = figures(folder, name)
        except (OSError, ValueError) as e:
            print(f"FAIL - {name}: no result ({e})")
            failed += 1
            continue
        problems = list(g["errors"])
        if g["liftd_exit"] != 0:
            problems.append(f"liftd exited {g['liftd_exit']}")
        if g["link_up_s"] is None:
            problems.append("the link never came up")
        want_echo = "present" if name in echo_names else "absent"
        if g["echo"] != want_echo:
            problems.append(f"line echo {g['echo']}, the line's is {want_echo} (drive.echo auto)")
        if name in DRIVERS and g["driver_reported"] not in DRIVERS[name]:
            problems.append(f"liftd says driver {g['driver_reported']}, not {'/'.join(map(str, DRIVERS[name]))}")
        if name.startswith("16550a") and g["rx_trig"] is None:
            problems.append("no rx_trig_bytes reported for a 16550A")
        if name == "usb":
            if g["latency_timer"] != 1:
                problems.append(f"liftd reports the adapter's latency timer {g['latency_timer']} ms, "
                                "not the 1 ms it sets")
            if not any("serial_latency_set" in line for line in g["lines"]):
                problems.append("liftd did not say it set the latency timer (serial_latency_set)")
            if g["sysfs"].get("latency_timer") != "1":
                problems.append(f"the adapter's latency timer is {g['sysfs'].get('latency_timer')} ms "
                                "while liftd runs, not 1")
        timing = []
        if g["travel_errors"]:
            timing += g["travel_errors"]
        if g["travels"] == 0 or g["arrived"] != g["travels"]:
            timing.append(f"{g['arrived']} of {g['travels']} travels arrived")
        if g["link_losses"]:
            timing.append(f"{g['link_losses']} link faults (DCP 7.3)")
        if g["link"] != "up" or g["faults"]:
            timing.append(f"link {g['link']}, faults {g['faults']}")
        # The host pty line is the reference the VM lines are compared with: its missing
        # replies are the host's own (reported, not bounded here; the default tests judge it).
        if name != "pty" and (g["missing_per_1000"] is None or g["missing_per_1000"] > bound):
            timing.append(f"missing replies {fmt(g['missing_per_1000'], '{:.2f}')} per 1000 cycles "
                          f"(bound {bound})")
        if g["p99"] is None or g["p99"] > DEADLINE_US:
            timing.append(f"reply p99 {g['p99']} us beyond DCP 7.2's {DEADLINE_US} us")
        functional = name in functional_names
        if not functional:
            problems += timing
        summary = (f"{g['arrived']}/{g['travels']} travels arrived, {g['missing']} missing replies "
                   f"in {g['cycles']} cycles, reply p99 {fmt(g['p99'])} us, echo {g['echo']}, "
                   f"driver {g['driver']}")
        if problems:
            failed += 1
            print(f"FAIL - {name}: " + "; ".join(problems))
        elif functional:
            print(f"ok - {name} (drivers and echo only; timing NOT judged: {'; '.join(timing) or 'it would have passed'}): {summary}")
        else:
            print(f"ok - {name}: {summary}")
    return 1 if failed else 0


def main():
    import argparse
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    sub = p.add_subparsers(dest="mode", required=True)
    r = sub.add_parser("run")
    r.add_argument("--name", required=True)
    r.add_argument("--device", required=True)
    r.add_argument("--out", required=True)
    r.add_argument("--seconds", type=float, default=45)
    r.add_argument("--liftd", required=True)
    r.add_argument("--config", required=True)
    r.add_argument("--encoder-socket")
    r.add_argument("--encoder-port")
    q = sub.add_parser("pty-pair")
    q.add_argument("folder")
    e = sub.add_parser("encoder-host")
    e.add_argument("sim_socket")
    e.add_argument("qemu_socket")
    t = sub.add_parser("table")
    t.add_argument("folder")
    t.add_argument("names", nargs="+")
    j = sub.add_parser("judge")
    j.add_argument("folder")
    j.add_argument("bound", type=float)
    j.add_argument("--echo", action="append", default=[])
    j.add_argument("--functional", action="append", default=[])
    j.add_argument("names", nargs="+")
    a = p.parse_args()
    if a.mode == "run":
        return run(a)
    if a.mode == "pty-pair":
        return pty_pair(a.folder)
    if a.mode == "encoder-host":
        return encoder_host(a.sim_socket, a.qemu_socket)
    if a.mode == "table":
        return table(a.folder, a.names)
    return judge(a.folder, a.bound, a.names, a.echo, a.functional)


if __name__ == "__main__":
    sys.exit(main())
