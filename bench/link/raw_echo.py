"""The raw baseline of benchmark 2: a trivial Zenoh pub/sub echo, eclipse-zenoh only.

A Zenoh *client* connected to the harness's peer, exactly as ``situate
serve-skill`` is, that republishes every sample of ``<prefix>/ping`` on
``<prefix>/pong`` from the subscriber callback, adding its receive time
(``time.monotonic_ns()``, CLOCK_MONOTONIC, shared by all processes), with no
JSON decoding of the body beyond that: the lower bound of a remote-skill hop
through Zenoh in Python.

    python raw_echo.py --connect tcp/127.0.0.1:PORT --prefix hopbench/raw
"""

from __future__ import annotations

import argparse
import json
import signal
import threading
import time

import zenoh


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--connect", required=True)
    ap.add_argument("--prefix", default="hopbench/raw")
    ap.add_argument("--max-s", type=float, default=600.0)
    opts = ap.parse_args()
    config = {
        "mode": "client",
        "connect": {"endpoints": [opts.connect]},
        "listen": {"endpoints": []},
        "scouting": {"multicast": {"enabled": False}, "gossip": {"enabled": False}},
    }
    session = zenoh.open(zenoh.Config.from_json5(json.dumps(config)))
    pong = session.declare_publisher(f"{opts.prefix}/pong")

    def on_ping(sample: zenoh.Sample) -> None:
        recv_ns = time.monotonic_ns()
        msg = json.loads(sample.payload.to_bytes())
        msg["recv_ns"] = recv_ns
        pong.put(json.dumps(msg))

    sub = session.declare_subscriber(f"{opts.prefix}/ping", on_ping)
    done = threading.Event()
    signal.signal(signal.SIGTERM, lambda *_: done.set())
    signal.signal(signal.SIGINT, lambda *_: done.set())
    done.wait(opts.max_s)
    sub.undeclare()
    pong.undeclare()
    session.close()


if __name__ == "__main__":
    main()
