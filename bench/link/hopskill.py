"""The remote skill of benchmark 2, served by the real ``situate serve-skill``.

It echoes the sequence number and the send time it gets as inputs, and adds
the time its body ran (``time.monotonic_ns()``: CLOCK_MONOTONIC is one clock
for every process of the machine, so the harness can split the round trip
into its two one-way hops).

    situate serve-skill hopskill:echo --robot hopbench --name echo --connect tcp/127.0.0.1:PORT
"""

from __future__ import annotations

import time
from typing import Any

import situate


@situate.remote_skill(
    inputs={"seq": "i64", "sent_ns": "i64"},
    outputs={"seq": "i64", "sent_ns": "i64", "recv_ns": "i64"},
)
def echo(seq: int, sent_ns: int) -> dict[str, Any]:
    """Echoes `seq` and `sent_ns` with the time the body ran."""
    return {"seq": seq, "sent_ns": sent_ns, "recv_ns": time.monotonic_ns()}
