"""Unit tests of the runner's rules (tools/dispatcher/group.py and doors.py) on fake cars: who
gets in where, which car a hall call goes to, how the door operator holds a queue back and
reopens the doors. Fast, no liftd, no clock: the times are given."""

import os
import sys
import unittest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)),
                                "..", "..", "tools", "dispatcher"))

import group  # noqa: E402
import traffic  # noqa: E402
from car import ApiError  # noqa: E402

LEVELS = [0, 3000, 6000, 9000, 12000, 15000]
PROFILE = {"speed_mm_s": 1000.0, "acceleration_mm_s2": 500.0, "overhead_s": 2.0,
           "travels_measured": 0}


class FakeCar:
    """What the runner uses of car.Car, with the calls queue of docs/api.md "`calls`"."""

    def __init__(self, name, floor):
        self.name = name
        self.drive_kind = "dcp"
        self.levels_mm = LEVELS
        self.sims = []
        self.state = {"car": {"floor": floor, "position_mm": LEVELS[floor], "doors": "locked"},
                      "travel": {"state": "idle", "target_floor": None, "calls": []},
                      "service": {"in_service": True, "reason": None}}

    @property
    def calls(self):
        return self.state["travel"]["calls"]

    def eta(self, floor=None, position=None):
        here = self.state["car"]["position_mm"]
        s = abs(LEVELS[floor] - here) / 1000.0 + 8.0 * len(self.calls)
        return {"in_service": True, "reason": None, "stops": [], "floors": [],
                "with": {"floor": floor, "position": len(self.calls), "s": s, "learned": False,
                         "delays": []},
                "basis": {"up": PROFILE, "down": PROFILE, "stop_s": 1.0, "start_s": 0.0}}

    def calls_add(self, floor):
        if floor not in self.calls:
            self.calls.append(floor)
        return {}

    def calls_cancel(self, floor):
        if floor not in self.calls:
            raise ApiError("calls", "bad_request", "floor is not queued")
        self.calls.remove(floor)
        return {}

    def calls_set(self, floors):
        self.calls[:] = list(floors)
        return {}

    def request(self, cmd, **args):
        assert cmd == "calls" and not args
        return {"calls": list(self.calls)}

    def sim(self, action, **args):
        self.sims.append(action)
        return {"doors": "opening"}


def passenger(number, origin, destination):
    return traffic.Passenger(number, 0.0, origin, destination)


def building(*cars):
    return group.Building(list(cars), capacity=8, dwell_s=2.0, transfer_s=1.2,
                          log=lambda text: None)


class Assignment(unittest.TestCase):
    def test_a_hall_call_goes_to_the_nearer_idle_car(self):
        a, b = FakeCar("A", 5), FakeCar("B", 1)
        house = building(a, b)
        house.arrive(passenger(1, 0, 4), now=10.0)
        self.assertEqual(b.calls, [0])
        self.assertEqual(a.calls, [])
        self.assertEqual(house.hall_calls[(0, "up")].car, "B")

    def test_a_second_passenger_joins_the_lit_hall_call(self):
        a, b = FakeCar("A", 5), FakeCar("B", 1)
        house = building(a, b)
        house.arrive(passenger(1, 0, 4), now=10.0)
        house.arrive(passenger(2, 0, 3), now=11.0)
        self.assertEqual(len(house.hall_calls), 1)
        self.assertEqual(b.calls, [0])


class Boarding(unittest.TestCase):
    def test_only_passengers_going_the_cars_way_get_in(self):
        a = FakeCar("A", 2)
        a.calls.append(4)  # going up from floor 2
        house = building(a)
        up, down = passenger(1, 2, 5), passenger(2, 2, 0)
        house.waiting[2] += [up, down]
        up.arrived_at = down.arrived_at = 0.0
        door = house.doors["A"]
        a.state["car"]["doors"] = "open"
        door.on_state(a.state, now=5.0)
        self.assertEqual(door.direction, "up")
        self.assertEqual(house.inside["A"], [up])
        self.assertEqual(house.waiting[2], [down])
        self.assertEqual(a.calls, [4, 5])
        self.assertEqual(up.boarded_at, 5.0)

    def test_passengers_leave_at_their_floor_and_the_journey_ends_there(self):
        a = FakeCar("A", 3)
        house = building(a)
        rider = passenger(1, 0, 3)
        rider.arrived_at, rider.boarded_at, rider.car = 0.0, 4.0, "A"
        house.inside["A"].append(rider)
        a.state["car"]["doors"] = "open"
        house.doors["A"].on_state(a.state, now=30.0)
        self.assertEqual(house.delivered, [rider])
        self.assertEqual(rider.delivered_at, 30.0)
        self.assertEqual(house.inside["A"], [])

    def test_an_idle_car_takes_the_way_of_the_first_passenger(self):
        a = FakeCar("A", 3)
        house = building(a)
        first, second = passenger(1, 3, 0), passenger(2, 3, 5)
        first.arrived_at, second.arrived_at = 1.0, 2.0
        house.waiting[3] += [first, second]
        a.state["car"]["doors"] = "open"
        house.doors["A"].on_state(a.state, now=5.0)
        self.assertEqual(house.inside["A"], [first])
        self.assertEqual(a.calls, [0])

    def test_a_full_car_leaves_the_rest_waiting(self):
        a = FakeCar("A", 0)
        house = building(a)
        house.capacity = 2
        for n in range(3):
            p = passenger(n + 1, 0, 3)
            p.arrived_at = float(n)
            house.waiting[0].append(p)
        a.state["car"]["doors"] = "open"
        house.doors["A"].on_state(a.state, now=5.0)
        self.assertEqual(len(house.inside["A"]), 2)
        self.assertEqual(len(house.waiting[0]), 1)


class Doors(unittest.TestCase):
    def test_the_queue_behind_the_target_is_held_until_the_doors_open(self):
        a = FakeCar("A", 0)
        house = building(a)
        door = house.doors["A"]
        a.calls[:] = [3, 5]
        a.state["car"].update(floor=None, position_mm=7000)
        a.state["travel"].update(state="distance", target_floor=3)
        door.on_state(a.state, now=1.0)
        self.assertEqual(a.calls, [3])     # the car stops at 3 with nothing behind it
        door.add_stop(1)                   # a floor added meanwhile waits too
        self.assertEqual(a.calls, [3])
        a.calls.remove(3)                  # arrived: the floor left the queue
        a.state["car"].update(floor=3, position_mm=9000)
        a.state["travel"].update(state="idle", target_floor=None)
        door.on_call_served(3, now=2.0)
        self.assertEqual(a.sims, ["open_doors"])
        a.state["car"]["doors"] = "open"
        door.on_state(a.state, now=2.1)
        self.assertEqual(a.calls, [5, 1])  # back in, in their order
        self.assertEqual(door.phase, "dwell")

    def test_closing_doors_reopen_for_a_passenger_going_the_same_way(self):
        a = FakeCar("A", 0)
        house = building(a)
        door = house.doors["A"]
        a.state["car"]["doors"] = "open"
        a.calls.append(4)
        door.on_state(a.state, now=0.0)
        door.tick(now=100.0)
        self.assertEqual(a.sims[-1], "close_doors")
        self.assertEqual(door.phase, "closing")
        late = passenger(1, 0, 2)
        house.arrive(late, now=0.5)  # within REOPEN_WITHIN_S of the opening
        self.assertEqual(a.sims[-1], "door_reversal")
        self.assertEqual(door.phase, "dwell")
        self.assertEqual(house.inside["A"], [late])

    def test_the_queue_is_put_in_sweep_order_before_the_doors_close(self):
        a = FakeCar("A", 2)
        house = building(a)
        door = house.doors["A"]
        a.calls[:] = [5, 3]
        a.state["car"]["doors"] = "open"
        door.on_state(a.state, now=0.0)
        door.tick(now=100.0)
        self.assertEqual(a.calls, [3, 5])


if __name__ == "__main__":
    unittest.main()
