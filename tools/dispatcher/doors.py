"""The door operator of one car, played by the runner through `sim` actions.

The simulated machine of `liftd --simulate` moves its doors only when told (docs/api.md "`sim`":
`open_doors`, `close_doors`, `door_reversal`); liftd itself never opens them. A real lift's
door operator is the controller's job; here the runner does it:

1. While the car travels to a queued floor, `sim open_doors` is sent once the car moves: the
   simulated doors then start to open the moment the car stops (`open_doors` "while the car
   moves: when it stops"). Sending it before the car moves would open the doors at once and
   liftd would end the travel (`aborted`, cause `doors_not_locked`). Opening on arrival also
   closes a race: after a stop liftd starts the travel to the next queued floor within a cycle
   or two if the doors are still locked.
2. A floor served at once (the car already stood there: `call_served` with the car at rest)
   gets `open_doors` right away.
3. When the doors begin to open at a level, the building lets passengers out and in; the doors
   stay open for the dwell: the time the doors take to open (2 s on the simulated machine,
   docs/api.md "`sim`"), a base dwell, and a transfer time for each passenger alighting or
   boarding. Then `sim close_doors`.
4. A passenger who reaches the landing while the doors close and may board reopens them
   (`sim door_reversal`, as the light curtain would) and the dwell starts again.
5. liftd starts the travel to the next queued floor by itself once the doors are locked.

Figures: passenger transfer time about 1.2 s per passenger (Barney, "Elevator Traffic Handbook",
2003, ch. 5, for an office with a wide entrance) and a door dwell of about 2 to 3 s after the
doors opened (the same source's door dwell for landing and car calls). Both are arguments of the
runner.
"""

import time

DOOR_OPERATE_S = 2.0   # the simulated doors take 2 s to open or to close (docs/api.md "`sim`")
PRE_OPEN_AFTER_MM = 30  # the car has moved: an `open_doors` now waits for the stop


class DoorOperator:
    """Door phases of one car: idle (doors locked or left alone), opening, dwell, closing."""

    def __init__(self, car, building, dwell_s, transfer_s, log):
        self.car = car
        self.building = building
        self.dwell_s = dwell_s
        self.transfer_s = transfer_s
        self.log = log
        self.phase = "idle"
        self.floor = None          # the level the doors serve while not idle
        self.direction = None      # the car's way on from this stop: "up", "down" or None
        self.close_at = None       # monotonic time to send close_doors
        self.travel_from_mm = None
        self.pre_opened = False
        self.open_off_level_since = None
        self.travels = 0
        self.aborted = 0

    # -- from the car's events ----------------------------------------------------------

    def on_state(self, state, now):
        car = state["car"]
        travel = state["travel"]
        doors = car["doors"]
        position = car["position_mm"]
        if travel["state"] != "idle" and travel["target_floor"] is not None:
            if self.travel_from_mm is None:
                self.travel_from_mm = position
            if (not self.pre_opened and position is not None and self.travel_from_mm is not None
                    and abs(position - self.travel_from_mm) > PRE_OPEN_AFTER_MM):
                self._sim("open_doors")
                self.pre_opened = True
        else:
            self.travel_from_mm = None
            self.pre_opened = False if doors == "locked" else self.pre_opened

        if self.phase == "idle" and doors not in ("locked", None) and travel["state"] == "idle":
            if car["floor"] is not None:
                self.pre_opened = False
                self.open_off_level_since = None
                self._opening(car["floor"], now)
            else:
                # Doors open between floors (an aborted travel stopped there): close them, and
                # liftd relevels or travels on.
                if self.open_off_level_since is None:
                    self.open_off_level_since = now
                elif now - self.open_off_level_since > 1.0:
                    self._sim("close_doors")
                    self.open_off_level_since = None
        elif self.phase == "closing" and doors == "locked":
            self.phase = "idle"
            floor, self.floor, self.direction = self.floor, None, None
            self.building.doors_locked(self, floor, now)

    def on_call_served(self, floor, now):
        state = self.car.state or {}
        doors = (state.get("car") or {}).get("doors")
        if self.phase == "idle" and doors == "locked" and not self.pre_opened:
            # Served at once: the car stood at that floor. Nothing moves: open now.
            self._sim("open_doors")

    def on_travel(self, data):
        if data["event"] == "finished":
            self.travels += 1
        elif data["event"] == "aborted":
            self.aborted += 1
            self.log(f"car {self.car.name}: travel aborted ({data['cause']})")

    # -- the stop ---------------------------------------------------------------------------

    def _opening(self, floor, now):
        self.phase = "dwell"
        self.floor = floor
        transfers = self.building.doors_opening(self, floor, now)
        self.close_at = now + DOOR_OPERATE_S + self.dwell_s + self.transfer_s * transfers

    def standing_at(self, floor):
        """The doors serve `floor` now (open, opening or closing): a passenger can still get in."""
        return self.phase in ("dwell", "closing") and self.floor == floor

    def reopen(self, now):
        """A passenger at the landing while the doors close: the light curtain reopens them
        (`sim door_reversal`). False when they had already locked: the car is leaving."""
        if self.phase != "closing":
            return self.phase == "dwell"
        result = self._sim("door_reversal")
        if result is None or result.get("doors") == "locked":
            return False
        self.phase = "dwell"
        self.close_at = now + DOOR_OPERATE_S + self.dwell_s
        return True

    def passengers_entered(self, count, now):
        """`count` more passengers got in at the open doors: they stay open that much longer."""
        self.close_at = max(self.close_at, now + self.transfer_s * count)

    def tick(self, now):
        if self.phase == "dwell" and now >= self.close_at:
            self._sim("close_doors")
            self.phase = "closing"

    def _sim(self, action):
        try:
            return self.car.sim(action)
        except Exception as error:  # the runner goes on; the next state event tells the truth
            self.log(f"car {self.car.name}: sim {action}: {error}")
            return None


def now():
    return time.monotonic()
