"""dora echo node: returns each ping with the time it arrived (CLOCK_MONOTONIC, ns)."""

import time

import pyarrow as pa
from dora import Node


def main() -> None:
    node = Node()
    for event in node:
        if event["type"] == "INPUT" and event["id"] == "ping":
            recv_ns = time.monotonic_ns()
            seq, sent_ns = event["value"].to_pylist()[:2]
            node.send_output("pong", pa.array([seq, sent_ns, recv_ns], type=pa.int64()))
        elif event["type"] == "STOP":
            break


if __name__ == "__main__":
    main()
