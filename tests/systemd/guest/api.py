#!/usr/bin/env python3
"""A small API client for the stage's checks.

  api.py hello                 connect, print the first line (greeting or error); exit 3 when
                               the connection is refused (the error on stderr)
  api.py access                print the greeting's access list, comma-separated
  api.py req JSON              one request; print the reply line
  api.py get PATH              status, print one field (dotted path), JSON-encoded
  api.py hold FILE             connect, send status; when FILE appears, send status again on the
                               same connection, then once more on a new one; print what happened
"""
import json
import os
import socket
import sys
import time

SOCK = os.environ.get("LIFTD_SOCKET", "/run/liftd/api.sock")


def connect(timeout=10):
    s = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    s.settimeout(timeout)
    s.connect(SOCK)
    return s, s.makefile("r")


def request(s, f, obj):
    s.sendall((json.dumps(obj) + "\n").encode())
    while True:
        line = f.readline()
        if not line:
            return None
        reply = json.loads(line)
        if "event" not in reply:
            return reply


def main():
    mode = sys.argv[1]
    try:
        s, f = connect()
    except OSError as e:
        print(f"connect: {e.strerror}", file=sys.stderr)
        print(f"connect: {e.strerror}")
        return 3
    first = f.readline()
    if mode == "hello":
        print(first.strip())
        return 0
    hello = json.loads(first) if first else {}
    if mode == "access":
        if hello.get("event") == "hello":
            print(",".join(hello["data"]["access"]))
        else:
            print(first.strip())
        return 0
    if mode == "req":
        print(json.dumps(request(s, f, json.loads(sys.argv[2]))))
        return 0
    if mode == "get":
        reply = request(s, f, {"cmd": "status", "id": 1})
        value = reply["result"]
        for key in sys.argv[2].split("."):
            value = value[key]
        print(json.dumps(value))
        return 0
    if mode == "hold":
        ok = request(s, f, {"cmd": "status", "id": 1})
        print("first", "ok" if ok and ok.get("ok") else "failed", flush=True)
        while not os.path.exists(sys.argv[2]):
            time.sleep(0.05)
        try:
            again = request(s, f, {"cmd": "status", "id": 2})
            print("same connection", "answered" if again else "closed", flush=True)
        except OSError as e:
            print("same connection", e.strerror or e, flush=True)
        s2, f2 = connect(30)
        f2.readline()
        answer = request(s2, f2, {"cmd": "status", "id": 3})
        print("next request", "answered" if answer and answer.get("ok") else "not answered")
        return 0
    return 2


sys.exit(main())
