"""The benchmark's trivial Python skill: one f64 in, one f64 out (twin of Rust `bench.double`)."""

from __future__ import annotations

import situate


@situate.skill(name="py.double", outputs={"y": "f64"})
def double(x: float) -> dict[str, float]:
    """Returns y = 2·x."""
    return {"y": 2.0 * x}
