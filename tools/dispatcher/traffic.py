"""The seeded passenger stream: who arrives at which landing, when, and where they go.

Three traffic modes as the classic lift traffic studies name them (Barney, "Elevator Traffic
Handbook", 2003; CIBSE Guide D, "Transportation systems in buildings"):

- `up-peak`: the morning arrival. Everyone enters at the main terminal (floor 0) and goes to an
  upper floor; a floor with more people receives more of them (weighted by population).
- `down-peak`: the evening departure, the reverse: from an upper floor, weighted by
  population, to floor 0.
- `interfloor`: movement between floors: origin and destination are any two different floors,
  each floor equally likely.

Arrivals form a Poisson process (exponential gaps between passengers), the arrival model the
classic up-peak calculation rests on (Barney 2003). The rate is given the way handling
capacity is quoted in lift traffic design: a percentage of the building's population arriving
in five minutes. A typical office design figure is 12 % in five minutes (British Council for
Offices guide, 2014, up-peak); older guidance used 15 % (CIBSE Guide D).

Everything comes from one `random.Random(seed)`: the same seed, mode, rate, floors and
population give the same passengers.
"""

import random
from dataclasses import dataclass, field

MODES = ("up-peak", "down-peak", "interfloor")
FIVE_MINUTES_S = 300.0


@dataclass
class Passenger:
    number: int
    arrival_s: float          # time of arrival at the landing, from the start of the stream
    origin: int
    destination: int
    # Filled in by the runner:
    arrived_at: float = None  # monotonic clock when the passenger reached the landing
    car: str = None           # the car boarded
    boarded_at: float = None  # doors of the boarding car open at the origin
    delivered_at: float = None  # doors open at the destination
    hall_call: object = field(default=None, repr=False)

    @property
    def direction(self):
        return "up" if self.destination > self.origin else "down"


def arrivals_per_second(rate_percent, population):
    """Mean arrival rate for `rate_percent` % of `population` in five minutes."""
    return rate_percent / 100.0 * sum(population) / FIVE_MINUTES_S


def stream(mode, rate_percent, population, minutes, seed):
    """The passengers of `minutes` of traffic, in order of arrival.

    `population[i]` is the number of people working on floor i; floor 0, the main terminal,
    usually has none. The number of floors is len(population).
    """
    if mode not in MODES:
        raise ValueError(f"mode must be one of {', '.join(MODES)}")
    floors = len(population)
    if floors < 2:
        raise ValueError("a building needs at least two floors")
    upper = list(range(1, floors))
    weights = [population[f] for f in upper]
    if mode != "interfloor" and sum(weights) <= 0:
        raise ValueError("the upper floors have no population")
    rate = arrivals_per_second(rate_percent, population)
    if rate <= 0:
        return []
    rng = random.Random(seed)
    passengers = []
    t = 0.0
    end = minutes * 60.0
    while True:
        t += rng.expovariate(rate)
        if t >= end:
            return passengers
        if mode == "up-peak":
            origin, destination = 0, rng.choices(upper, weights)[0]
        elif mode == "down-peak":
            origin, destination = rng.choices(upper, weights)[0], 0
        else:
            origin, destination = rng.sample(range(floors), 2)
        passengers.append(Passenger(len(passengers) + 1, round(t, 3), origin, destination))


def parse_population(text, floors):
    """`--population`: one number for every upper floor ("60"), or one per floor, floor 0 first
    ("0,60,60,40"). Floor 0 is the main terminal and gets 0 with the single-number form."""
    parts = [int(p) for p in text.split(",")]
    if len(parts) == 1:
        return [0] + parts * (floors - 1)
    if len(parts) != floors:
        raise ValueError(f"--population: {len(parts)} numbers for {floors} floors")
    return parts
