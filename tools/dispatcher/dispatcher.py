"""Assignment of hall calls to cars by estimated time to destination (ETD).

For a new hall call (a passenger at `origin` going to `destination`) every car is asked `eta`
with `floor` = origin (docs/api.md "`eta`"). Its reply gives:

- `with.s`: how long until that car could stand at the origin, with the origin added to its
  calls queue at `with.position`;
- `with.delays[].s`: how much later each stop it already has would be reached because of it;
- `basis`: the car's own measured motion profile, per direction.

The cost of a car is the time until it stands at the origin, plus the delays it adds to the
stops it already has, plus the ride from origin to destination on that car's profile. The car
with the least cost gets the call. Cars whose `eta` says they are out of service (`in_service`
false) are skipped, and so are full cars. This is the idea of destination-based group control
(estimated time to destination, as in Smith and Peters, "ETD algorithm with destination
dispatch and booster options", Elevator World 2002); here it is the simplest form of it.

`add_stop` is the one place that puts a floor into a car's queue. Today the queue only appends
(`calls add`, strictly first in first out, each floor once: docs/api.md "`calls`"), so
`stop_position` asks about the end of the queue. Once the queue can insert, change these two
functions and the rest of the dispatcher stays as it is.
"""

import math


def stop_position(eta_calls):
    """Where in the car's queue a new stop would go. Append-only today: the end (None makes
    `eta` assume the end, its default)."""
    return None


def add_stop(car, floor):
    """Queue `floor` on `car` (append; a floor already queued stays where it is)."""
    return car.calls_add(floor)


def sweep_order(queue, floor, direction):
    """The queued floors in the order of one sweep from `floor` going `direction` (None: the
    way of the first queued floor): those ahead nearest first, then the rest on the way back,
    nearest first again. The order a collective control serves its car calls in."""
    if not queue:
        return []
    if direction is None:
        direction = "up" if queue[0] > floor else "down"
    if direction == "up":
        ahead = sorted(f for f in queue if f > floor)
        back = sorted((f for f in queue if f <= floor), reverse=True)
    else:
        ahead = sorted((f for f in queue if f < floor), reverse=True)
        back = sorted(f for f in queue if f >= floor)
    return ahead + back


def ride_s(basis, from_mm, to_mm):
    """Time of one travel from `from_mm` to `to_mm` on the car's fitted profile (`eta` basis):
    accelerate, run at speed, decelerate alike (a triangle when too short), plus the overhead
    of a travel (start, levelling, stop), plus the stop at the origin (`stop_s`)."""
    profile = basis["up" if to_mm > from_mm else "down"]
    distance = abs(to_mm - from_mm)
    v = max(profile["speed_mm_s"], 1.0)
    a = max(profile["acceleration_mm_s2"], 1.0)
    if distance >= v * v / a:
        motion = distance / v + v / a
    else:
        motion = 2.0 * math.sqrt(distance / a)
    return motion + profile["overhead_s"] + basis.get("stop_s", 0.0)


def cost(eta_reply, levels_mm, origin, destination):
    """The ETD cost of giving this hall call to the car that gave `eta_reply`, or None when
    the car cannot take it (out of service)."""
    if not eta_reply.get("in_service") or eta_reply.get("with") is None:
        return None
    with_ = eta_reply["with"]
    delays = sum(d["s"] for d in with_.get("delays", []))
    ride = ride_s(eta_reply["basis"], levels_mm[origin], levels_mm[destination])
    return with_["s"] + delays + ride


def cost_queued(eta_reply, levels_mm, origin, destination):
    """The cost for the car that has the origin queued already: when its plan stands there
    (`floors`), plus the ride. None when out of service."""
    if not eta_reply.get("in_service") or not eta_reply.get("floors"):
        return None
    at = next(f["s"] for f in eta_reply["floors"] if f["floor"] == origin)
    return at + ride_s(eta_reply["basis"], levels_mm[origin], levels_mm[destination])


def choose(candidates, levels_mm, origin, destination):
    """Pick the car for a hall call.

    `candidates`: (name, eta_reply, full) per car; `full` is true when the car has no room.
    Returns (name, cost) of the cheapest car, or (None, None) when no car can take it. Ties go
    to the first candidate, so the choice is repeatable.
    """
    best = (None, None)
    for name, eta_reply, full in candidates:
        if full:
            continue
        c = cost(eta_reply, levels_mm, origin, destination)
        if c is None:
            continue
        if best[1] is None or c < best[1]:
            best = (name, c)
    return best
