#!/usr/bin/env python3
"""The group runner: a seeded passenger stream, a group of liftd cars, the dispatcher between.

    tools/dispatcher/group.py --car A.sock --car B.sock --mode up-peak --minutes 5 \\
        --rate 12 --seed 1 --svg group.svg

It connects to every car (docs/api.md section 8), closes their doors, then plays the building
in real time: passengers arrive at the landings (traffic.py), each new hall call goes to the
car with the least estimated time to destination (dispatcher.py), the runner opens and closes
the doors of each car as its door operator (doors.py), passengers get in and out, and their
destinations go into the car's calls queue. After the stream ends it runs on until every
passenger has arrived, or fails loudly after --drain-timeout seconds.

It prints a line per passenger delivered and a summary: waiting time (arrival at the landing
until the doors of the car taken begin to open there) and journey time (arrival until the doors
begin to open at the destination), as the lift traffic literature defines them (Barney,
"Elevator Traffic Handbook", 2003: passenger waiting time and time to destination), the
average, 95th percentile and longest of each, passengers generated and delivered, and the
travels each car made. Exit status 0 when every passenger arrived, 1 otherwise.
"""

import argparse
import os
import selectors
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import dispatcher  # noqa: E402
import svg  # noqa: E402
import traffic  # noqa: E402
import uppeak  # noqa: E402
from car import ApiError, CarGone, connect  # noqa: E402
from doors import DoorOperator  # noqa: E402


REASSESS_AFTER_S = 5.0   # a hall call waiting this long is costed again ...
REASSESS_EVERY_S = 3.0   # ... this often,
REASSIGN_MARGIN_S = 5.0  # and moves to a car this much better only: no flapping
PARK_AFTER_S = 3.0       # up-peak: a car idle this long goes back to the main terminal


class HallCall:
    """Passengers waiting at `floor` to go `direction`, and the car that will come for them."""

    def __init__(self, floor, direction, since):
        self.floor = floor
        self.direction = direction
        self.since = since
        self.car = None
        self.reassessed = since


class Building:
    """Landings, hall calls, passengers in cars: what the runner knows besides the cars."""

    def __init__(self, cars, capacity, dwell_s, transfer_s, log, park_floor=None):
        self.cars = cars
        self.park_floor = park_floor
        self.parking_since = {}
        self.capacity = capacity
        self.log = log
        self.levels_mm = cars[0].levels_mm
        self.doors = {c.name: DoorOperator(c, self, dwell_s, transfer_s, log) for c in cars}
        self.inside = {c.name: [] for c in cars}
        self.waiting = {f: [] for f in range(len(self.levels_mm))}
        self.hall_calls = {}       # (floor, direction) -> HallCall
        self.delivered = []
        self.hall_marks = []       # (t, floor, direction) for the plot
        self.idle_since = {}       # car name -> when it was first seen idle with work to redo

    # -- passengers arrive --------------------------------------------------------------

    def arrive(self, passenger, now):
        passenger.arrived_at = now
        self.waiting[passenger.origin].append(passenger)
        # A car already standing here with open doors going that way takes them at once.
        for door in self.doors.values():
            if door.standing_at(passenger.origin) and self._may_board(door, passenger):
                if door.reopen(now):
                    self._board(door, [passenger], now)
                    door.passengers_entered(1, now)
                    return
        key = (passenger.origin, passenger.direction)
        if key in self.hall_calls:
            return  # the hall call is lit already: the passenger joins it
        call = HallCall(passenger.origin, passenger.direction, now)
        self.hall_calls[key] = call
        self.hall_marks.append((now, passenger.origin, passenger.direction))
        self.assign(call, passenger.destination)

    def assign(self, call, destination=None, reassess=False):
        """Give a hall call to the car with the least ETD cost (dispatcher.py). With
        `reassess`, a call already given to a car moves only to a car that is clearly better
        (REASSIGN_MARGIN_S): the car it has may have been held up since, or another become
        free."""
        waiting = [p for p in self.waiting[call.floor] if p.direction == call.direction]
        if destination is None:
            if not waiting:
                self.hall_calls.pop((call.floor, call.direction), None)
                return
            destination = waiting[0].destination
        candidates = []
        current_cost = None
        for car in self.cars:
            try:
                if reassess and car.name == call.car:
                    # Its queue has the floor already: the time it stands there, and the ride.
                    reply = car.eta()
                    current_cost = dispatcher.cost_queued(reply, self.levels_mm, call.floor,
                                                          destination)
                    continue
                queue = (car.state or {}).get("travel", {}).get("calls", [])
                reply = car.eta(call.floor, dispatcher.stop_position(queue))
            except ApiError as error:
                self.log(f"car {car.name}: eta: {error}")
                continue
            full = len(self.inside[car.name]) >= self.capacity
            candidates.append((car.name, reply, full))
        name, cost = dispatcher.choose(candidates, self.levels_mm, call.floor, destination)
        if reassess:
            if name is None or (current_cost is not None
                                and cost + REASSIGN_MARGIN_S >= current_cost):
                return
            old = self._car(call.car)
            self.log(f"hall call {call.floor} {call.direction}: car {call.car} -> car {name} "
                     f"({current_cost if current_cost is None else round(current_cost)} s -> "
                     f"{round(cost)} s)")
            call.car = name
            self._cancel_if_unneeded(old, call.floor)
        call.car = name
        if name is None:
            return  # no car can take it now: tried again each tick
        try:
            self.doors[name].add_stop(call.floor)
        except ApiError as error:
            self.log(f"car {name}: calls add {call.floor}: {error}")
            call.car = None

    # -- the doors of a car at a level ----------------------------------------------------

    def doors_opening(self, door, floor, now):
        """The doors of `door`'s car begin to open at `floor`: out, then in. Returns how many
        passengers got out or in (the dwell grows with them)."""
        name = door.car.name
        leaving = [p for p in self.inside[name] if p.destination == floor]
        for p in leaving:
            p.delivered_at = now
            self.inside[name].remove(p)
            self.delivered.append(p)
            self.log(f"P{p.number:<4} {p.origin}->{p.destination} car {name}  "
                     f"wait {p.boarded_at - p.arrived_at:6.1f} s  "
                     f"journey {p.delivered_at - p.arrived_at:6.1f} s")
        door.direction = self._way_on(door, floor)
        if door.direction is None:
            # Nothing queued beyond this stop: the car goes the way of whoever waits longest,
            # the hall call given to this car first.
            here = sorted(self.waiting[floor],
                          key=lambda p: (self._call_car(p) != name, p.arrived_at))
            door.direction = here[0].direction if here else None
        boarding = [p for p in self.waiting[floor] if self._may_board(door, p)]
        room = self.capacity - len(self.inside[name])
        boarding = boarding[:max(room, 0)]
        self._board(door, boarding, now)
        return len(leaving) + len(boarding)

    def doors_locked(self, door, floor, now):
        """The doors locked after a stop at `floor`: the car leaves. A hall call there given to
        this car whose passengers did not all get in (the car went the other way, or was full)
        goes out again."""
        for (f, direction), call in list(self.hall_calls.items()):
            if f == floor and call.car == door.car.name:
                self.assign(call)

    def _may_board(self, door, passenger):
        if len(self.inside[door.car.name]) >= self.capacity:
            return False
        if door.direction is None:
            door.direction = passenger.direction
        return passenger.direction == door.direction

    def _board(self, door, passengers, now):
        name = door.car.name
        floor = door.floor
        for p in passengers:
            self.waiting[floor].remove(p)
            p.car = name
            p.boarded_at = now
            self.inside[name].append(p)
        # Their destinations go into the queue, nearest first in the car's way (append-only
        # queue: docs/api.md "`calls`").
        destinations = sorted({p.destination for p in passengers},
                              reverse=(door.direction == "down"))
        for d in destinations:
            try:
                door.add_stop(d)
            except ApiError as error:
                self.log(f"car {name}: calls add {d}: {error} (tried again later)")
        for direction in ("up", "down"):
            key = (floor, direction)
            call = self.hall_calls.get(key)
            if call is None:
                continue
            if any(p.direction == direction for p in self.waiting[floor]):
                continue  # some still wait (the car was full): the call stays
            del self.hall_calls[key]
            if call.car not in (None, name):
                self._cancel_if_unneeded(self._car(call.car), floor)

    def _cancel_if_unneeded(self, car, floor):
        """Another car was coming for a hall call this car answered: take the floor out of its
        queue unless it stops there anyway (a passenger inside, another hall call)."""
        if any(p.destination == floor for p in self.inside[car.name]):
            return
        if any(c.car == car.name and c.floor == floor for c in self.hall_calls.values()):
            return
        door = self.doors[car.name]
        if floor in door.held:
            door.held.remove(floor)
            return
        travel = (car.state or {}).get("travel", {})
        if travel.get("target_floor") == floor:
            return  # already on its way there: it stops, opens and goes on
        try:
            car.calls_cancel(floor)
        except ApiError:
            pass  # not queued (served meanwhile): nothing to take out

    def _way_on(self, door, floor):
        calls = door.released or (door.car.state or {}).get("travel", {}).get("calls", [])
        calls = [f for f in calls if f != floor]
        if calls:
            return "up" if calls[0] > floor else "down"
        return None

    def _call_car(self, passenger):
        call = self.hall_calls.get((passenger.origin, passenger.direction))
        return call.car if call else None

    def _car(self, name):
        return next(c for c in self.cars if c.name == name)

    # -- housekeeping ---------------------------------------------------------------------

    def tick(self, now):
        for door in self.doors.values():
            door.tick(now)
        for call in list(self.hall_calls.values()):
            if call.car is None:
                self.assign(call)
            elif now - call.since > REASSESS_AFTER_S and now - call.reassessed > REASSESS_EVERY_S:
                call.reassessed = now
                if not self._answering(call):
                    self.assign(call, reassess=True)
        for car in self.cars:
            self._requeue(car, now)
            self._park(car, now)

    def _answering(self, call):
        """The car given the call stands at its floor with its doors open now."""
        return call.car is not None and self.doors[call.car].standing_at(call.floor)

    def _park(self, car, now):
        """Up-peak: a car with nothing to do goes back to the main terminal, where the
        passengers come from (the lobby return of up-peak group control, Barney 2003)."""
        if self.park_floor is None:
            return
        state = car.state or {}
        door = self.doors[car.name]
        owed = any(c.car == car.name for c in self.hall_calls.values()) or self.inside[car.name]
        free = (door.phase == "idle" and not door.holding and not owed
                and (state.get("service") or {}).get("in_service")
                and state.get("travel", {}).get("state") == "idle"
                and not state.get("travel", {}).get("calls")
                and state.get("car", {}).get("doors") == "locked"
                and state.get("car", {}).get("floor") not in (None, self.park_floor))
        if not free:
            self.parking_since.pop(car.name, None)
            return
        since = self.parking_since.setdefault(car.name, now)
        if now - since >= PARK_AFTER_S:
            self.parking_since.pop(car.name, None)
            self.log(f"car {car.name}: parks at floor {self.park_floor}")
            try:
                door.add_stop(self.park_floor)
            except ApiError as error:
                # Out of service since its last state event (a fault): it parks when it is
                # back, as any car with nothing to do.
                self.log(f"car {car.name}: not parked: {error}")

    def _requeue(self, car, now):
        """A car at rest with nothing queued but floors it owes (its travel was aborted, which
        empties the queue, or a `calls add` was refused): queue them again."""
        state = car.state or {}
        door = self.doors[car.name]
        owed = {p.destination for p in self.inside[car.name]}
        owed |= {c.floor for c in self.hall_calls.values() if c.car == car.name}
        at_rest = (door.phase == "idle" and not door.holding
                   and state.get("travel", {}).get("state") == "idle"
                   and not state.get("travel", {}).get("calls")
                   and state.get("car", {}).get("doors") == "locked")
        if not (owed and at_rest):
            self.idle_since.pop(car.name, None)
            return
        since = self.idle_since.setdefault(car.name, now)
        if now - since < 2.0:
            return
        self.idle_since.pop(car.name, None)
        here = state.get("car", {}).get("floor")
        position = state.get("car", {}).get("position_mm") or 0
        for floor in sorted(owed, key=lambda f: abs(self.levels_mm[f] - position)):
            self.log(f"car {car.name}: floor {floor} queued again (here: {here})")
            try:
                door.add_stop(floor)
            except ApiError as error:
                self.log(f"car {car.name}: calls add {floor}: {error}")

    def waiting_count(self):
        return sum(len(w) for w in self.waiting.values())

    def riding_count(self):
        return sum(len(i) for i in self.inside.values())


def percentile(values, fraction):
    """The nearest-rank percentile of `values` (fraction 0..1)."""
    ordered = sorted(values)
    if not ordered:
        return 0.0
    rank = max(1, -(-len(ordered) * fraction // 1))
    return ordered[int(rank) - 1]


def summary(passengers, building, args, plan):
    delivered = [p for p in passengers if p.delivered_at is not None]
    waits = [p.boarded_at - p.arrived_at for p in delivered]
    journeys = [p.delivered_at - p.arrived_at for p in delivered]
    lines = ["", "== summary ==",
             f"mode {args.mode}, rate {args.rate} % of {sum(plan)} people in 5 min, "
             f"{args.minutes} min, seed {args.seed}, {len(building.cars)} cars",
             f"passengers generated {len(passengers)}, delivered {len(delivered)}"]
    for label, values in (("wait", waits), ("journey", journeys)):
        if values:
            lines.append(f"{label:8} average {sum(values) / len(values):6.1f} s   "
                         f"p95 {percentile(values, 0.95):6.1f} s   max {max(values):6.1f} s")
    for car in building.cars:
        door = building.doors[car.name]
        carried = sum(1 for p in delivered if p.car == car.name)
        lines.append(f"car {car.name} ({car.drive_kind}): {door.travels} travels, "
                     f"{door.aborted} aborted, {carried} passengers")
    try:
        bases = [car.eta()["basis"] for car in building.cars]
        per_car, percent = uppeak.handling_capacity(bases, building.levels_mm, plan,
                                                    args.capacity, args.dwell, args.transfer)
        lines.append(f"up-peak handling capacity (classic round trip, {args.capacity} "
                     f"passengers a car, 80 % loaded): {percent:.0f} % of {sum(plan)} people "
                     f"in 5 min; round trip " + ", ".join(
                         f"{c.name} {rtt:.0f} s" for c, (rtt, _) in zip(building.cars, per_car)))
    except (ApiError, CarGone, ZeroDivisionError, KeyError) as error:
        lines.append(f"up-peak handling capacity: not computed ({error})")
    print("\n".join(lines), flush=True)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--car", action="append", required=True, metavar="SOCKET",
                        help="API socket of a car (repeat for each car)")
    parser.add_argument("--mode", choices=traffic.MODES, default="up-peak")
    parser.add_argument("--minutes", type=float, default=5.0, help="minutes of traffic (default 5)")
    parser.add_argument("--rate", type=float, default=12.0,
                        help="arrivals in %% of the population per five minutes (default 12)")
    parser.add_argument("--seed", type=int, default=1,
                        help="seed of the passenger stream (default 1)")
    parser.add_argument("--population", default="60",
                        help="people per upper floor, or per floor from floor 0 (default 60)")
    parser.add_argument("--capacity", type=int, default=8, help="passengers per car (default 8)")
    parser.add_argument("--dwell", type=float, default=2.0, help="door dwell, s (default 2)")
    parser.add_argument("--transfer", type=float, default=1.2,
                        help="transfer time per passenger in or out, s (default 1.2)")
    parser.add_argument("--drain-timeout", type=float, default=300.0,
                        help="after the stream: longest wait for the last passengers, "
                        "s (default 300)")
    parser.add_argument("--no-park", action="store_true",
                        help="up-peak: leave idle cars where they are (default: back to floor 0)")
    parser.add_argument("--svg", help="write the plot of the run to this file")
    parser.add_argument("--quiet", action="store_true", help="no line per passenger")
    args = parser.parse_args(argv)

    def log(text):
        if not args.quiet or not text.startswith("P"):
            print(f"{time.monotonic() - start:8.1f}  {text}", flush=True)

    start = time.monotonic()
    cars = [connect(path) for path in args.car]
    names = [c.name for c in cars]
    if len(set(names)) != len(names):
        sys.exit(f"cars need distinct names (api.car_name): {names}")
    levels = cars[0].levels_mm
    for car in cars[1:]:
        if car.levels_mm != levels:
            sys.exit(f"car {car.name} has other floors than car {cars[0].name}")
    plan = traffic.parse_population(args.population, len(levels))
    passengers = traffic.stream(args.mode, args.rate, plan, args.minutes, args.seed)
    print(f"{len(cars)} cars ({', '.join(f'{c.name}: {c.drive_kind}' for c in cars)}), "
          f"{len(levels)} floors, {len(passengers)} passengers in {args.minutes} min "
          f"({args.mode}, {args.rate} % of {sum(plan)} people in 5 min, seed {args.seed})",
          flush=True)

    building = Building(cars, args.capacity, args.dwell, args.transfer, log,
                        park_floor=0 if args.mode == "up-peak" and not args.no_park else None)
    traces = {c.name: [] for c in cars}
    selector = selectors.DefaultSelector()
    for car in cars:
        car.watch()
        car.sim("close_doors")
        selector.register(car.sock, selectors.EVENT_READ, car)
    # Wait until every car is in service with its doors locked.
    deadline = time.monotonic() + 120
    while True:
        states = [c.status() for c in cars]
        if all(s["service"]["in_service"] and s["car"]["doors"] == "locked" for s in states):
            break
        if time.monotonic() > deadline:
            sys.exit("cars not in service with locked doors after 120 s: "
                     + ", ".join(f"{c.name}: {s['service']}" for c, s in zip(cars, states)))
        time.sleep(0.2)
    for car in cars:
        car.take_events()

    start = time.monotonic()
    pending = list(passengers)
    stream_end = start + args.minutes * 60.0
    next_tick = start
    failed = None
    try:
        while True:
            now = time.monotonic()
            while pending and start + pending[0].arrival_s <= now:
                building.arrive(pending.pop(0), now)
            if now >= next_tick:
                building.tick(now)
                next_tick = now + 0.25
            if not pending and len(building.delivered) == len(passengers):
                break
            if not pending and now > stream_end + args.drain_timeout:
                failed = (f"{len(passengers) - len(building.delivered)} passengers not "
                          f"delivered {args.drain_timeout:.0f} s after the stream ended "
                          f"({building.waiting_count()} waiting, "
                          f"{building.riding_count()} in cars)")
                break
            wake = next_tick
            if pending:
                wake = min(wake, start + pending[0].arrival_s)
            for key, _ in selector.select(max(0.0, wake - time.monotonic())):
                key.data.pump()
            now = time.monotonic()
            for car in cars:
                car.pump()
                for message in car.take_events():
                    handle(building, traces, car, message, now - start, now)
    except CarGone as error:
        failed = f"lost a car: {error}"
    except KeyboardInterrupt:
        failed = "interrupted"

    summary(passengers, building, args, plan)
    if args.svg:
        svg.write(args.svg, traces, [(t - start, f, d) for t, f, d in building.hall_marks],
                  levels, [c.name for c in cars], title=f"{args.mode}, {args.rate} %, "
                  f"seed {args.seed}, {len(cars)} cars")
        print(f"plot: {args.svg}", flush=True)
    for car in cars:
        car.close()
    if failed:
        print(f"FAILED: {failed}", file=sys.stderr, flush=True)
        for p in passengers:
            if p.delivered_at is None:
                where = f"in car {p.car}" if p.car else "waiting"
                print(f"  P{p.number} {p.origin}->{p.destination} {where}", file=sys.stderr)
        return 1
    return 0


def handle(building, traces, car, message, t, now):
    event = message.get("event")
    data = message.get("data")
    door = building.doors[car.name]
    if event == "state":
        position = data["car"]["position_mm"]
        trace = traces[car.name]
        if position is not None and (not trace or trace[-1][1] != position):
            trace.append((t, position))
        door.on_state(data, now)
    elif event == "call_served":
        door.on_call_served(data["floor"], now)
    elif event == "travel":
        door.on_travel(data)
    elif event == "missed":
        car.status()  # fell behind: catch up (docs/api.md section 4)
        door.on_state(car.state, now)
    elif event == "stopping":
        raise CarGone(f"car {car.name} is stopping ({data['reason']})")


if __name__ == "__main__":
    sys.exit(main())
