"""Writes the copper-rs task graphs of the peers benchmark: chain<N>.ron, a
chain of N tasks (a source, N - 2 adders, a sink that adds too), passing
[f32; 24]. Run from bench/peers: python3 copper/gen.py"""

for n in (10, 100, 1000):
    ids = ["g0"] + [f"a{j}" for j in range(1, n - 1)] + [f"a{n - 1}"]
    types = ["Gen"] + ["Add"] * (n - 2) + ["Sink"]
    tasks = ",\n".join(f'        (id: "{i}", type: "crate::copper::{t}")' for i, t in zip(ids, types))
    cnx = ",\n".join(
        f'        (src: "{a}", dst: "{b}", msg: "crate::copper::Arr")' for a, b in zip(ids, ids[1:])
    )
    with open(f"copper/chain{n}.ron", "w") as f:
        f.write(f"(\n    logging: (enable_task_logging: false),\n    tasks: [\n{tasks},\n    ],\n    cnx: [\n{cnx},\n    ],\n)\n")
