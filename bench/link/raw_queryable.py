"""The raw baseline of benchmark 1: a trivial Zenoh queryable, eclipse-zenoh only.

A Zenoh *peer* listening on one loopback endpoint, as the skill manager is
(docs/protocol.md, "Session"), answering every get on
``situate/<robot>/req/**`` at once from the callback: ``hello`` with a
hello result (so ``situate.connect`` accepts it and the benchmark can send
its gets through the very code path the sequencer uses), anything else with
``{"ok": null}``. It parses nothing and computes nothing.

    python raw_queryable.py --listen tcp/127.0.0.1:PORT --robot rawbench

Runs until SIGINT/SIGTERM, or until ``--max-s`` seconds have passed.
"""

from __future__ import annotations

import argparse
import json
import signal
import threading

import zenoh


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--listen", required=True)
    ap.add_argument("--robot", default="rawbench")
    ap.add_argument("--max-s", type=float, default=600.0)
    opts = ap.parse_args()
    config = {
        "mode": "peer",
        "listen": {"endpoints": [opts.listen]},
        "connect": {"endpoints": []},
        "scouting": {"multicast": {"enabled": False}, "gossip": {"enabled": False}},
    }
    session = zenoh.open(zenoh.Config.from_json5(json.dumps(config)))
    hello = json.dumps({"ok": {"protocol": 1, "robot": opts.robot, "version": "raw-zenoh"}})
    ok = json.dumps({"ok": None})
    hello_key = f"situate/{opts.robot}/req/hello"

    def on_query(query: zenoh.Query) -> None:
        key = str(query.key_expr)
        query.reply(query.key_expr, hello if key == hello_key else ok)

    queryable = session.declare_queryable(f"situate/{opts.robot}/req/**", on_query)
    done = threading.Event()
    signal.signal(signal.SIGTERM, lambda *_: done.set())
    signal.signal(signal.SIGINT, lambda *_: done.set())
    print("raw queryable ready", flush=True)
    done.wait(opts.max_s)
    queryable.undeclare()
    session.close()


if __name__ == "__main__":
    main()
