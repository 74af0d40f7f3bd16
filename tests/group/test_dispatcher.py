"""Unit tests of the assignment (tools/dispatcher/dispatcher.py): a table of `eta` replies in,
the chosen car out. Fast, no liftd."""

import os
import sys
import unittest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)),
                                "..", "..", "tools", "dispatcher"))

import dispatcher  # noqa: E402
import uppeak  # noqa: E402

LEVELS = [0, 3000, 6000, 9000, 12000, 15000]


def profile(speed=1000.0, acceleration=500.0, overhead=2.0):
    return {"speed_mm_s": speed, "acceleration_mm_s2": acceleration, "overhead_s": overhead,
            "travels_measured": 5}


def eta(s, delays=(), in_service=True, speed=1000.0):
    """An `eta` reply as docs/api.md "`eta`" shows it, with what the dispatcher reads."""
    if not in_service:
        return {"in_service": False, "reason": "fault", "stops": [], "floors": None,
                "basis": {"up": profile(), "down": profile(), "stop_s": 1.0}}
    return {"in_service": True, "reason": None, "stops": [], "floors": [],
            "with": {"floor": 2, "position": 0, "s": s, "learned": False,
                     "delays": [{"floor": f, "s": d} for f, d in delays]},
            "basis": {"up": profile(speed), "down": profile(speed), "stop_s": 1.0,
                      "start_s": 0.0}}


class Choice(unittest.TestCase):
    def test_the_nearest_idle_car(self):
        table = [("A", eta(12.0), False), ("B", eta(4.0), False), ("C", eta(9.0), False)]
        self.assertEqual(dispatcher.choose(table, LEVELS, 2, 5)[0], "B")

    def test_delays_to_queued_stops_count(self):
        # B is sooner at the origin but makes two queued stops 10 s later each.
        table = [("A", eta(12.0), False), ("B", eta(4.0, [(4, 10.0), (5, 10.0)]), False)]
        self.assertEqual(dispatcher.choose(table, LEVELS, 2, 5)[0], "A")

    def test_the_ride_to_the_destination_counts(self):
        # Same time to the origin: the faster car (a traction car beside a hydraulic one) wins.
        table = [("hyd", eta(5.0, speed=300.0), False), ("dcp", eta(5.0, speed=1600.0), False)]
        self.assertEqual(dispatcher.choose(table, LEVELS, 0, 5)[0], "dcp")

    def test_out_of_service_and_full_cars_are_skipped(self):
        table = [("A", eta(1.0, in_service=False), False), ("B", eta(2.0), True),
                 ("C", eta(30.0), False)]
        self.assertEqual(dispatcher.choose(table, LEVELS, 2, 0)[0], "C")

    def test_no_car(self):
        table = [("A", eta(1.0, in_service=False), False), ("B", eta(2.0), True)]
        self.assertEqual(dispatcher.choose(table, LEVELS, 2, 0), (None, None))

    def test_tie_goes_to_the_first(self):
        table = [("A", eta(5.0), False), ("B", eta(5.0), False)]
        self.assertEqual(dispatcher.choose(table, LEVELS, 1, 3)[0], "A")

    def test_cost_is_the_sum(self):
        reply = eta(7.0, [(3, 2.5), (4, 1.5)], speed=1000.0)
        # 6 m at 1 m/s with 0.5 m/s2: 6 s at speed + 2 s of ramps, 2 s overhead, 1 s stop.
        self.assertAlmostEqual(dispatcher.cost(reply, LEVELS, 1, 3), 7.0 + 4.0 + 11.0)

    def test_short_ride_is_a_triangle(self):
        basis = {"up": profile(2000.0, 500.0, 0.0), "down": profile(), "stop_s": 0.0}
        # 3 m never reaches 2 m/s at 0.5 m/s2 (that takes 8 m): 2 * sqrt(3000 / 500).
        self.assertAlmostEqual(dispatcher.ride_s(basis, 0, 3000), 2 * 6 ** 0.5)


class Sweep(unittest.TestCase):
    def test_ahead_nearest_first_then_back(self):
        self.assertEqual(dispatcher.sweep_order([5, 1, 3, 0], 2, "up"), [3, 5, 1, 0])
        self.assertEqual(dispatcher.sweep_order([5, 1, 3, 0], 2, "down"), [1, 0, 3, 5])

    def test_without_direction_the_first_queued_floor_sets_it(self):
        self.assertEqual(dispatcher.sweep_order([1, 4, 3], 2, None), [1, 3, 4])
        self.assertEqual(dispatcher.sweep_order([], 2, None), [])


class UpPeak(unittest.TestCase):
    def test_equal_floors_give_the_textbook_s_and_h(self):
        # Equal populations: S = N (1 - (1 - 1/N)^P), H = N - sum (i/N)^P for i < N.
        n, p = 5, 6.4
        s, h = uppeak.stops_and_reversal([0] + [60] * n, p)
        self.assertAlmostEqual(s, n * (1 - (1 - 1 / n) ** p))
        self.assertAlmostEqual(h, n - sum((i / n) ** p for i in range(1, n)))

    def test_a_faster_car_carries_more(self):
        basis = {"up": profile(1600.0), "down": profile(1600.0), "stop_s": 1.0}
        slow = {"up": profile(500.0), "down": profile(500.0), "stop_s": 1.0}
        per_car, percent = uppeak.handling_capacity([basis, slow], LEVELS, [0] + [60] * 5,
                                                    8, 2.0, 1.2)
        self.assertGreater(per_car[0][1], per_car[1][1])
        self.assertAlmostEqual(percent, 100 * (per_car[0][1] + per_car[1][1]) / 300)


if __name__ == "__main__":
    unittest.main()
