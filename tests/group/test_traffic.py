"""Unit tests of the passenger stream (tools/dispatcher/traffic.py): fast, no liftd."""

import os
import sys
import unittest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)),
                                "..", "..", "tools", "dispatcher"))

import traffic  # noqa: E402

POPULATION = [0, 60, 60, 40, 80, 60]  # 300 people above the main terminal


def trips(passengers):
    return [(p.arrival_s, p.origin, p.destination) for p in passengers]


class PassengerStream(unittest.TestCase):
    def test_same_seed_same_passengers(self):
        for mode in traffic.MODES:
            a = traffic.stream(mode, 12, POPULATION, 10, seed=7)
            b = traffic.stream(mode, 12, POPULATION, 10, seed=7)
            self.assertTrue(a, mode)
            self.assertEqual(trips(a), trips(b), mode)

    def test_another_seed_other_passengers(self):
        a = traffic.stream("interfloor", 12, POPULATION, 10, seed=7)
        b = traffic.stream("interfloor", 12, POPULATION, 10, seed=8)
        self.assertNotEqual(trips(a), trips(b))

    def test_rate_is_the_percentage_of_the_population_in_five_minutes(self):
        # 12 % of 300 people in 5 minutes = 36 per 5 minutes; over 50 hours 21600 expected.
        # A Poisson count has a standard deviation of sqrt(21600) = 147: 3 % is over 4 of them.
        for rate in (5, 12):
            passengers = traffic.stream("up-peak", rate, POPULATION, 3000, seed=1)
            expected = rate / 100 * 300 * 3000 / 5
            self.assertAlmostEqual(len(passengers) / expected, 1.0, delta=0.03, msg=rate)

    def test_up_peak_from_the_main_terminal_weighted_by_population(self):
        passengers = traffic.stream("up-peak", 12, POPULATION, 3000, seed=3)
        self.assertTrue(all(p.origin == 0 for p in passengers))
        self.assertTrue(all(1 <= p.destination < len(POPULATION) for p in passengers))
        share4 = sum(p.destination == 4 for p in passengers) / len(passengers)
        share3 = sum(p.destination == 3 for p in passengers) / len(passengers)
        self.assertAlmostEqual(share4, 80 / 300, delta=0.02)
        self.assertAlmostEqual(share3, 40 / 300, delta=0.02)

    def test_down_peak_to_the_main_terminal(self):
        passengers = traffic.stream("down-peak", 12, POPULATION, 600, seed=3)
        self.assertTrue(passengers)
        self.assertTrue(all(p.destination == 0 and p.origin >= 1 for p in passengers))

    def test_interfloor_two_different_floors(self):
        passengers = traffic.stream("interfloor", 12, POPULATION, 600, seed=3)
        self.assertTrue(passengers)
        self.assertTrue(all(p.origin != p.destination for p in passengers))
        self.assertEqual({p.origin for p in passengers}, set(range(len(POPULATION))))

    def test_arrivals_in_order_within_the_minutes(self):
        passengers = traffic.stream("up-peak", 12, POPULATION, 5, seed=4)
        times = [p.arrival_s for p in passengers]
        self.assertEqual(times, sorted(times))
        self.assertTrue(all(0 < t < 300 for t in times))
        self.assertEqual([p.number for p in passengers], list(range(1, len(passengers) + 1)))

    def test_population_argument(self):
        self.assertEqual(traffic.parse_population("60", 4), [0, 60, 60, 60])
        self.assertEqual(traffic.parse_population("0,10,20", 3), [0, 10, 20])
        with self.assertRaises(ValueError):
            traffic.parse_population("1,2", 3)


if __name__ == "__main__":
    unittest.main()
