"""A client of one car: one connection to one liftd, as docs/api.md section 8 describes it.

Connects to the car's API socket, reads the `hello` greeting (the car's name, drive kind and
floors), sends requests with unique ids and matches the replies by id, and keeps every event that
arrives in between in a list for the runner. It keeps the last `state` event (the `status`
result) so the runner can read position, doors, travel and calls without asking.

The requests are synchronous: `request()` writes one line and reads until its reply comes. Events
that arrive meanwhile are kept, never lost. `pump()` reads what the socket holds without waiting,
for a select() loop over many cars.
"""

import json
import socket
import time


class ApiError(Exception):
    """A reply with "ok": false. `code` is the API's error code (docs/api.md section 5)."""

    def __init__(self, cmd, code, message):
        super().__init__(f"{cmd}: {code}: {message}")
        self.code = code
        self.message = message


class CarGone(Exception):
    """The car closed its connection (liftd stopped, or dropped us)."""


class Car:
    """One car of the group, reached through its API socket."""

    def __init__(self, socket_path, timeout_s=10.0):
        self.socket_path = socket_path
        self.timeout_s = timeout_s
        self.sock = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        self.sock.settimeout(timeout_s)
        self.sock.connect(socket_path)
        self._buffer = b""
        self._next_id = 1
        self.events = []      # events not yet taken by the runner, oldest first
        self.state = None     # the last `state` event's data (the `status` result)
        hello = self._read_message()
        if hello.get("event") != "hello":
            # An error reply with "id": null instead of the greeting (docs/api.md, "Greeting").
            raise ApiError("hello", hello.get("error", {}).get("code"), str(hello))
        if hello["data"]["api"] != 3:
            raise ApiError("hello", "api", f"API {hello['data']['api']}, this client speaks 3")
        car = hello["data"]["car"]
        self.name = car["name"] or socket_path
        self.drive_kind = car["drive_kind"]
        self.floors = car["floors"]
        self.levels_mm = [f["level_mm"] for f in self.floors]

    def fileno(self):
        return self.sock.fileno()

    # -- reading ----------------------------------------------------------------------------

    def _take_line(self):
        """One complete line from the buffer, or None."""
        end = self._buffer.find(b"\n")
        if end < 0:
            return None
        line, self._buffer = self._buffer[:end], self._buffer[end + 1:]
        return line

    def _fill(self, block):
        self.sock.setblocking(block)
        if block:
            self.sock.settimeout(self.timeout_s)
        try:
            data = self.sock.recv(65536)
        except BlockingIOError:
            return False
        except socket.timeout:
            raise CarGone(f"{self.socket_path}: no answer within {self.timeout_s} s")
        if not data:
            raise CarGone(f"{self.socket_path}: connection closed")
        self._buffer += data
        return True

    def _read_message(self):
        while True:
            line = self._take_line()
            if line is not None:
                if line.strip():
                    return json.loads(line)
                continue
            self._fill(block=True)

    def _keep_event(self, message):
        if message.get("event") == "state":
            self.state = message["data"]
        self.events.append(message)

    def pump(self):
        """Read whatever the socket holds now (no waiting) and keep the events."""
        while self._fill(block=False):
            pass
        while True:
            line = self._take_line()
            if line is None:
                return
            if line.strip():
                message = json.loads(line)
                if "event" in message:
                    self._keep_event(message)
                # A reply nobody waits for cannot happen: request() waits for each of its own.

    def take_events(self):
        events, self.events = self.events, []
        return events

    # -- requests ---------------------------------------------------------------------------

    def request(self, cmd, **args):
        """Send one request and return its `result`; raise ApiError on "ok": false."""
        request_id = self._next_id
        self._next_id += 1
        line = json.dumps({"cmd": cmd, "id": request_id, **args}, separators=(",", ":"))
        self.sock.setblocking(True)
        self.sock.sendall(line.encode() + b"\n")
        while True:
            message = self._read_message()
            if "event" in message:
                self._keep_event(message)
                continue
            if message.get("id") != request_id:
                continue  # not ours: cannot happen with one request in flight
            if not message["ok"]:
                error = message["error"]
                raise ApiError(cmd, error["code"], error["message"])
            return message["result"]

    def status(self):
        self.state = self.request("status")
        return self.state

    def watch(self):
        self.request("watch", enable=True)
        return self.status()

    def eta(self, floor=None, position=None):
        """The `eta` command (docs/api.md "`eta`"): arrival times, and with `floor` the cost
        of adding that floor to the calls queue at `position` (default: the end)."""
        args = {}
        if floor is not None:
            args["floor"] = floor
        if position is not None:
            args["position"] = position
        return self.request("eta", **args)

    def calls_add(self, floor):
        return self.request("calls", action="add", floor=floor)

    def calls_cancel(self, floor):
        return self.request("calls", action="cancel", floor=floor)

    def calls_set(self, floors):
        """Replace the whole queue in one request (docs/api.md "`calls`" set)."""
        return self.request("calls", action="set", floors=list(floors))

    def sim(self, action, **args):
        """A `sim` action (only `liftd --simulate` serves them): here the door operator's hands."""
        return self.request("sim", action=action, **args)

    def close(self):
        try:
            self.sock.close()
        except OSError:
            pass


def connect(socket_path, wait_s=30.0):
    """Connect to a car, retrying while its liftd is still starting (no socket yet)."""
    deadline = time.monotonic() + wait_s
    while True:
        try:
            return Car(socket_path)
        except (FileNotFoundError, ConnectionRefusedError):
            if time.monotonic() > deadline:
                raise
            time.sleep(0.2)
