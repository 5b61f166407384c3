"""dora source node: ping-pong with `echo`, one message in flight, paced like situate's hop.

Reads its settings from the JSON file named by $LINKBENCH_DORA_CONFIG:
  {"samples": int, "warmup": int, "gap_ms": [lo, hi], "seed": int, "out": path,
   "reply_timeout_s": float}
After each reply it sleeps a random gap in [lo, hi] ms (the same gaps as the
situate side), then sends the next ping. Writes {"rt_us": [...], "fwd_us": [...],
"back_us": [...], "lost": n} to `out` and exits, which ends the dataflow.
"""

import json
import os
import random
import time

import pyarrow as pa
from dora import Node


def main() -> None:
    with open(os.environ["LINKBENCH_DORA_CONFIG"]) as f:
        cfg = json.load(f)
    rng = random.Random(cfg["seed"])
    lo, hi = cfg["gap_ms"]
    total = cfg["warmup"] + cfg["samples"]
    node = Node()
    rt, fwd, back = [], [], []
    lost = 0
    seq = 0
    while seq < total:
        time.sleep(rng.uniform(lo, hi) / 1000.0)
        sent_ns = time.monotonic_ns()
        node.send_output("ping", pa.array([seq, sent_ns, 0], type=pa.int64()))
        while True:
            event = node.next(timeout=cfg["reply_timeout_s"])
            if event is None:  # timeout, or the echo is gone: count it lost, send the next one
                lost += 1
                break
            if event["type"] == "STOP":
                seq = total
                break
            if event["type"] != "INPUT" or event["id"] != "pong":
                continue
            now = time.monotonic_ns()
            r_seq, r_sent, r_recv = event["value"].to_pylist()
            if r_seq != seq:  # a late reply to a ping counted lost
                continue
            if seq >= cfg["warmup"]:
                rt.append((now - r_sent) / 1e3)
                fwd.append((r_recv - r_sent) / 1e3)
                back.append((now - r_recv) / 1e3)
            break
        seq += 1
    with open(cfg["out"], "w") as f:
        json.dump({"rt_us": rt, "fwd_us": fwd, "back_us": back, "lost": lost}, f)


if __name__ == "__main__":
    main()
