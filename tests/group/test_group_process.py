"""Process test of the group runner: two simulated cars of different drive kinds (a DCP car and
a hydraulic SCH001 car, each its own `liftd --simulate`), two minutes of up-peak traffic through
tools/dispatcher/group.py, then every passenger must have arrived and the summary be printed.

    python3 test_group_process.py /path/to/liftd

It judges outcomes only (every passenger delivered, the summary's lines, the cars stopping
cleanly), never how long anything took: the machine may be slow and shared.
"""

import os
import re
import subprocess
import sys
import tempfile
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
DISPATCHER = os.path.join(HERE, "..", "..", "tools", "dispatcher")
sys.path.insert(0, DISPATCHER)

import simcars  # noqa: E402

LIFTD = None


class GroupRun(unittest.TestCase):
    def test_two_cars_of_two_kinds_deliver_every_passenger(self):
        with tempfile.TemporaryDirectory(prefix="liftd-group-") as directory:
            cars = simcars.start(LIFTD, directory, ["dcp", "sch001"])
            try:
                run = subprocess.run(
                    [sys.executable, os.path.join(DISPATCHER, "group.py"),
                     "--car", cars[0][1], "--car", cars[1][1], "--mode", "up-peak",
                     "--minutes", "2", "--rate", "12", "--seed", "3",
                     "--svg", os.path.join(directory, "group.svg"),
                     # Generous: a loaded machine runs the cars' real time slower, never the
                     # passengers' arrivals; the drain only has to end, not end soon.
                     "--drain-timeout", "600"],
                    capture_output=True, text=True, timeout=1200)
            finally:
                codes = simcars.stop(cars)
            logs = ""
            for name in ("A", "B"):
                with open(os.path.join(directory, f"car-{name}", "liftd.log")) as f:
                    logs += f"--- car {name} ---\n" + f.read()[-3000:]
            report = f"stdout:\n{run.stdout}\nstderr:\n{run.stderr}\n{logs}"
            self.assertEqual(run.returncode, 0, report)
            self.assertIn("== summary ==", run.stdout, report)
            generated = re.search(r"passengers generated (\d+), delivered (\d+)", run.stdout)
            self.assertIsNotNone(generated, report)
            self.assertGreater(int(generated.group(1)), 0, report)
            self.assertEqual(generated.group(1), generated.group(2), report)
            self.assertRegex(run.stdout, r"wait +average .* p95 .* max", report)
            self.assertRegex(run.stdout, r"journey +average .* p95 .* max", report)
            self.assertRegex(run.stdout, r"car A \(dcp\): \d+ travels", report)
            self.assertRegex(run.stdout, r"car B \(sch001\): \d+ travels", report)
            lines = [line for line in run.stdout.splitlines() if re.search(r"\bP\d+ ", line)]
            self.assertEqual(len(lines), int(generated.group(1)), report)
            with open(os.path.join(directory, "group.svg")) as f:
                self.assertIn("<polyline", f.read())
            self.assertEqual(codes, [0, 0], report)


if __name__ == "__main__":
    if len(sys.argv) < 2:
        sys.exit("usage: test_group_process.py LIFTD_BINARY")
    LIFTD = os.path.abspath(sys.argv.pop(1))
    unittest.main()
