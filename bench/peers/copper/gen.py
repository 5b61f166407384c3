"""Writes the copper-rs task graphs of the peers benchmark: ``chain<N>.ron``.

A chain of N tasks (a source, N - 2 adders, a sink that adds too), passing ``[f32; 24]``.
Run from bench/peers: ``python3 copper/gen.py``.
"""

from pathlib import Path


def chain(n: int) -> str:
    """The task graph of a chain of ``n`` tasks, in copper-rs's RON."""
    ids = ["g0", *(f"a{j}" for j in range(1, n))]
    types = ["Gen", *(["Add"] * (n - 2)), "Sink"]
    tasks = ",\n".join(
        f'        (id: "{i}", type: "crate::copper::{t}")' for i, t in zip(ids, types, strict=True)
    )
    cnx = ",\n".join(
        f'        (src: "{a}", dst: "{b}", msg: "crate::copper::Arr")'
        for a, b in zip(ids, ids[1:], strict=False)
    )
    return (
        "(\n    logging: (enable_task_logging: false),\n"
        f"    tasks: [\n{tasks},\n    ],\n    cnx: [\n{cnx},\n    ],\n)\n"
    )


if __name__ == "__main__":
    for n in (10, 100, 1000):
        Path(f"copper/chain{n}.ron").write_text(chain(n))
