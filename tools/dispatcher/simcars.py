#!/usr/bin/env python3
"""Simulated cars for a group: one configuration, socket and runtime directory per car.

    simcars.py configs DIR dcp,sch001,uss     write DIR/car-A/liftd.json ... and print their paths

Each car's configuration is the project's example for its drive kind (config/liftd.json,
config/hydraulic.json, config/uss.json) with what lets it run beside the others as an ordinary
user, as tools/demo.sh does for one car: its own API socket in its own directory (liftd puts the
simulated SCH001 card's socket `sch001-card.sock`, the record database `record.db` and the
flight recorder's trace files beside the API socket unless RUNTIME_DIRECTORY is set, so one
directory per car keeps them apart), no group ownership, no real-time requirement, no locked
memory, a car name (A, B, ...), the same floors for every car, and the time a stop takes
(`eta.stop_ms`) with the door cycle the runner plays.

`start()` and `stop()` run them as processes for the tests.
"""

import json
import os
import signal
import subprocess
import sys
import time

KINDS = {"dcp": "liftd.json", "sch001": "hydraulic.json", "uss": "uss.json"}
ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
# Six floors 3 m apart, the floors of config/liftd.json.
FLOORS = [{"name": str(i), "level_mm": 3000 * i} for i in range(6)]


def car_config(kind, name, directory, floors=FLOORS):
    with open(os.path.join(ROOT, "config", KINDS[kind])) as f:
        config = json.load(f)
    api = config.setdefault("api", {})
    api["socket"] = os.path.join(directory, "api.sock")
    for group in ("socket_group", "read_group", "control_group", "inputs_group"):
        api[group] = ""
    api["car_name"] = name
    rt = config.setdefault("rt", {})
    rt["require_realtime"] = False
    rt["lock_memory"] = False
    config["floors"] = floors
    config.setdefault("record", {})["path"] = os.path.join(directory, "record.db")
    # The door operator (doors.py) holds the queue back while the car stands at a stop, so
    # the car never measures how long it stands at a queued stop: tell its `eta` what a stop
    # with a door cycle costs (2 s opening, 2 s dwell, 2 s closing, locking, a passenger).
    config.setdefault("eta", {})["stop_ms"] = 7500
    return config


def write_configs(directory, kinds):
    """Write one directory and configuration per car; return [(name, kind, config, socket)]."""
    cars = []
    for i, kind in enumerate(kinds):
        if kind not in KINDS:
            raise ValueError(f"unknown drive kind {kind!r}: {', '.join(KINDS)}")
        name = chr(ord("A") + i)
        car_dir = os.path.join(directory, f"car-{name}")
        os.makedirs(car_dir, exist_ok=True)
        path = os.path.join(car_dir, "liftd.json")
        config = car_config(kind, name, car_dir)
        with open(path, "w") as f:
            json.dump(config, f, indent=2)
        cars.append((name, kind, path, config["api"]["socket"]))
    return cars


def start(liftd, directory, kinds):
    """Start one `liftd --simulate` per kind; return [(process, socket)]."""
    env = dict(os.environ)
    env.pop("RUNTIME_DIRECTORY", None)
    running = []
    for name, kind, path, sock in write_configs(directory, kinds):
        with open(os.path.join(os.path.dirname(path), "liftd.log"), "w") as log:
            process = subprocess.Popen([liftd, "--simulate", "--config", path], stdout=log,
                                       stderr=subprocess.STDOUT, env=env)
        running.append((process, sock))
    return running


def stop(running, timeout_s=30):
    """SIGTERM every car and wait for it; a car that does not stop in time is killed."""
    for process, _ in running:
        if process.poll() is None:
            process.send_signal(signal.SIGTERM)
    deadline = time.monotonic() + timeout_s
    codes = []
    for process, _ in running:
        try:
            codes.append(process.wait(max(0.1, deadline - time.monotonic())))
        except subprocess.TimeoutExpired:
            process.kill()
            codes.append(process.wait())
    return codes


def main(argv):
    if len(argv) != 3 or argv[0] != "configs":
        sys.exit(__doc__.split("\n\n")[1])
    for name, kind, path, sock in write_configs(argv[1], argv[2].split(",")):
        print(name, kind, path, sock)


if __name__ == "__main__":
    main(sys.argv[1:])
