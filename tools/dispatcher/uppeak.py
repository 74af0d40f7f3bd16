"""The classic up-peak calculation: what a group can carry in five minutes of up-peak.

The round trip of one car in up-peak (Barney, "Elevator Traffic Handbook", 2003; the
same equation is in CIBSE Guide D):

    RTT = 2 H tv + (S + 1) ts + 2 P tp

- P: passengers per trip, 80 % of the car's capacity (the design load of the calculation);
- S: expected number of stops above the main terminal, H: expected highest reversal floor, both
  for P passengers choosing floors in proportion to their population;
- tv: time to pass one floor at rated speed; ts: time lost at each stop (a one-floor flight
  less tv, plus door opening, dwell and closing); tp: transfer time of one passenger.

Handling capacity in five minutes: HC5 = 300 P / RTT per car, summed over the group, and as a
percentage of the population. Each car's speed, acceleration and overhead are its own, from
its `eta` basis (docs/api.md "`eta`"): measured on its own travels once it made some.
"""

import dispatcher
from doors import DOOR_OPERATE_S, LOCK_S


def stops_and_reversal(population, passengers):
    """(S, H) for `passengers` people leaving floor 0, floor i chosen with the probability
    population[i] / total (the unequal-population forms of S and H)."""
    upper = population[1:]
    total = float(sum(upper))
    shares = [u / total for u in upper]
    s = sum(1 - (1 - share) ** passengers for share in shares)
    cumulative = 0.0
    below = 0.0
    for share in shares[:-1]:
        cumulative += share
        below += cumulative ** passengers
    return s, len(upper) - below


def round_trip_s(basis, levels_mm, population, capacity, dwell_s, transfer_s):
    passengers = 0.8 * capacity
    s, h = stops_and_reversal(population, passengers)
    floor_mm = (levels_mm[-1] - levels_mm[0]) / (len(levels_mm) - 1)
    speed = basis["up"]["speed_mm_s"]
    tv = floor_mm / speed
    one_floor = dispatcher.ride_s(basis, 0, floor_mm) - basis.get("stop_s", 0.0)
    ts = one_floor - tv + 2 * DOOR_OPERATE_S + LOCK_S + dwell_s
    return 2 * h * tv + (s + 1) * ts + 2 * passengers * transfer_s


def handling_capacity(bases, levels_mm, population, capacity, dwell_s, transfer_s):
    """[(round trip s, persons per 5 min)] per car, and the group's percentage of the
    population in five minutes."""
    per_car = []
    for basis in bases:
        rtt = round_trip_s(basis, levels_mm, population, capacity, dwell_s, transfer_s)
        per_car.append((rtt, 300.0 * 0.8 * capacity / rtt))
    percent = 100.0 * sum(hc for _, hc in per_car) / sum(population)
    return per_car, percent
