"""The door operator of one car, played by the runner through `sim` actions.

The simulated machine of `liftd --simulate` moves its doors only when told (docs/api.md "`sim`":
`open_doors`, `close_doors`, `door_reversal`); liftd itself never opens them. A real lift's
door operator is the controller's job; here the runner does it:

1. After a stop at a served call liftd waits `travel.call_stop_ms` (1.5 s) before it starts the
   next queued travel, then for the doors locked; the runner opens them within that time.
   Opening the doors while the car still stops (`open_doors` sent while it moves) ends the
   arriving travel on a DCP drive (`aborted`, cause `doors_not_locked`, which empties the
   queue), so they open only at `call_served`. The runner also takes the floors queued behind
   a stop out of the queue while the car arrives (within `HOLD_WITHIN_MM` of its target) and
   puts them back (`calls add`, same order) once the doors are open, as it did before liftd
   had that wait; floors the dispatcher adds meanwhile wait with them.
2. At the stop (`call_served`), `sim open_doors`.
3. When the doors begin to open at a level, the building lets passengers out and in; the doors
   stay open for the dwell: the time the doors take to open (2 s on the simulated machine,
   docs/api.md "`sim`"), a base dwell, and a transfer time for each passenger alighting or
   boarding. Then `sim close_doors`.
4. A passenger who reaches the landing while the doors close and may board reopens them
   (`sim door_reversal`, as the light curtain would) and the dwell starts again, unless the
   car has stood there for `REOPEN_WITHIN_S` already: under a steady stream (up-peak at the
   main terminal) the doors would otherwise never close, and those in the car wait for the
   late ones. The late passenger waits for the next car.
5. Before the doors close, the queue is put in sweep order (`_sweep`, one `calls set`).
6. liftd starts the travel to the next queued floor by itself once the doors are locked.

Figures: passenger transfer time about 1.2 s per passenger (Barney, "Elevator Traffic Handbook",
2003, for an office with a wide entrance) and a door dwell of about 2 to 3 s after the
doors opened (the same source's door dwell for landing and car calls). Both are arguments of the
runner.
"""

import time

import dispatcher
from car import ApiError

DOOR_OPERATE_S = 2.0   # the simulated doors take 2 s to open or to close (docs/api.md "`sim`")
LOCK_S = 0.3           # and lock 300 ms after they closed (docs/api.md "`sim`" close_doors)
REOPEN_WITHIN_S = 10.0  # no reversal for a late passenger once the car stood this long at a stop
HOLD_WITHIN_MM = 2500  # hold the queue behind the target from this far before it


class DoorOperator:
    """The doors of one car at its stops: phase `idle` (locked, or the car travels), `dwell`
    (opening, then open for the passengers), `closing` (close_doors sent, until locked)."""

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
        self.opened_at = 0.0       # when the doors began to open at this stop
        self.holding = False
        self.held = []             # floors taken out of the car's queue while it arrives
        self.released = []         # the floors last put back: the car's way on from the stop
        self.open_off_level_since = None
        self.travels = 0
        self.aborted = 0

    # -- from the car's events ----------------------------------------------------------

    def on_state(self, state, now):
        car = state["car"]
        travel = state["travel"]
        doors = car["doors"]
        position = car["position_mm"]
        target = travel["target_floor"]
        if (travel["state"] != "idle" and target is not None and position is not None
                and not self.holding
                and abs(self.car.levels_mm[target] - position) <= HOLD_WITHIN_MM):
            self._hold(target, travel["calls"])

        if self.phase == "idle" and doors not in ("locked", None) and travel["state"] == "idle":
            if car["floor"] is not None:
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
            self._locked(now)

    def _locked(self, now):
        self.phase = "idle"
        floor, self.floor, self.direction = self.floor, None, None
        self.building.doors_locked(self, floor, now)

    def on_call_served(self, floor, now):
        state = self.car.state or {}
        doors = (state.get("car") or {}).get("doors")
        if self.phase == "idle" and doors == "locked":
            self._sim("open_doors")

    # -- the queue behind the stop ----------------------------------------------------------

    def add_stop(self, floor):
        """Queue `floor` on the car: held back while the car arrives at a stop (above)."""
        if self.holding:
            if floor not in self.held:
                self.held.append(floor)
            return
        dispatcher.add_stop(self.car, floor)

    def _hold(self, target, calls):
        self.holding = True
        for floor in calls:
            if floor == target:
                continue
            try:
                self.car.calls_cancel(floor)
            except ApiError:
                continue  # served or gone meanwhile
            if floor not in self.held:
                self.held.append(floor)

    def _sweep(self):
        """Put the queue in the order of one sweep before the doors close: the floors ahead in
        the car's way nearest first, then the others on the way back. The queue is served in
        order (docs/api.md "`calls`"), so passengers who got in one after the other would
        otherwise ride to each other's floors in the order they pressed. One `calls set`
        replaces it whole; the car cannot leave while its doors are open."""
        try:
            queue = self.car.request("calls")["calls"]
        except ApiError:
            return
        order = dispatcher.sweep_order(queue, self.floor, self.direction)
        if order == queue:
            return
        try:
            self.car.calls_set(order)
        except ApiError as error:
            self.log(f"car {self.car.name}: calls set {order}: {error}")

    def _release(self):
        held, self.held, self.holding = self.held, [], False
        self.released = held
        for floor in held:
            try:
                dispatcher.add_stop(self.car, floor)
            except ApiError as error:
                self.log(f"car {self.car.name}: calls add {floor}: {error}")

    def on_travel(self, data):
        if data["event"] == "finished":
            self.travels += 1
        elif data["event"] == "aborted":
            self.aborted += 1
            self._release()
            self.log(f"car {self.car.name}: travel aborted ({data['cause']})")

    # -- the stop ---------------------------------------------------------------------------

    def _opening(self, floor, now):
        self.phase = "dwell"
        self.floor = floor
        self.opened_at = now
        self._release()
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
        if now - self.opened_at > REOPEN_WITHIN_S:
            return False  # the car has stood here long enough: the next car takes them
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
            self._sweep()
            self._sim("close_doors")
            self.phase = "closing"
        elif self.phase == "closing":
            # A `state` event comes only with a change: doors that were locked already when
            # close_doors went out send none.
            if ((self.car.state or {}).get("car") or {}).get("doors") == "locked":
                self._locked(now)

    def _sim(self, action):
        try:
            return self.car.sim(action)
        except Exception as error:  # the runner goes on; the next state event tells the truth
            self.log(f"car {self.car.name}: sim {action}: {error}")
            return None


def now():
    return time.monotonic()
