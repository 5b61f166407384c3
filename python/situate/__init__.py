"""situate from Python: sequence a robot's skills, and write skills in Python.

Situate is the reactive layer of a robot: a skill manager runs *skills* in a
periodic data-flow cycle. This package is a *sequencer*'s side of it — it
connects to a running manager over the link (``docs/protocol.md``) and
switches skills on and off, tunes their parameters, queries signals and
waits for conditions — and the home of *remote skills*, asynchronous skills
whose body is a Python function in another process.

Sequencing, with asyncio::

    async with situate.connect("toybot") as robot:
        await robot.activate("wander", "runaway")
        await robot.set_param("runaway", "safe_distance", 0.3)
        event = await robot.when("sonar.range[0] < 0.25", timeout=30)

A remote skill::

    @situate.remote_skill(inputs={"x": "f64"}, outputs={"y": "f64"}, params={"gain": 2.0})
    def doubler(x: float, gain: float) -> dict[str, object]:
        return {"y": x * gain}

    situate.serve_skill(doubler, robot="toybot", name="doubler")

An in-process skill, run inside the manager's cycle (list its file in the
robot file's ``python:`` section)::

    @situate.skill(name="py.doubler", outputs={"y": "f64"})
    def doubler(x: float, gain: float = situate.param(2.0, min=0.0)) -> dict[str, float]:
        return {"y": x * gain}

    result = situate.run("robot.yaml", cycles=100, clock="simulated", record=["y"])

The ``situate`` command installed with this package is the same program as
the Rust build's (``situate run robot.yaml``, ``situate skills``, ...), plus
``situate serve-skill MODULE:ATTR``. The user guide is ``docs/python.md``.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

from .client import DEFAULT_ENDPOINT, Connector, Robot, Stream, connect
from .errors import (
    AmbiguousRobot,
    BadCondition,
    BadParam,
    BadReply,
    BadRequest,
    Interrupted,
    Invalid,
    MissingProviders,
    NoSession,
    NotOwner,
    NotRunning,
    OtherRobots,
    ProtocolMismatch,
    SituateError,
    Unavailable,
    UnknownMonitor,
    UnknownParam,
    UnknownSignal,
    UnknownSkill,
    UnknownVerb,
)
from .events import (
    ActivationApplied,
    Event,
    ManagerStarted,
    ManagerStopped,
    MonitorCancelled,
    MonitorEvent,
    MonitorFired,
    OtherEvent,
    ParamChanged,
    Phase,
    Print,
    PriorityChanged,
    SkillFaulted,
    Telemetry,
    WorkerFailed,
)
from .info import (
    Graph,
    GraphSignal,
    GraphSkill,
    Hello,
    MonitorInfo,
    ParamInfo,
    PortInfo,
    Reading,
    SkillInfo,
    Stats,
    Timing,
    Winner,
)
from .skill import MissingResource, Param, Port, Skill, SkillDeclarationError, param, port, skill

if TYPE_CHECKING:
    from ._cli import data_dir
    from ._loader import SkillLoadError
    from .local import LocalRobot, RunResult, run
    from .remote import RemoteSkill, RemoteSkillServer, remote_skill, serve_skill

#: Names imported on first use, and their modules: running a robot in-process
#: and serving remote skills cost a sequencer nothing when it starts.
_LAZY = {
    "SkillLoadError": "._loader",
    "data_dir": "._cli",
    "LocalRobot": ".local",
    "RunResult": ".local",
    "run": ".local",
    "RemoteSkill": ".remote",
    "RemoteSkillServer": ".remote",
    "remote_skill": ".remote",
    "serve_skill": ".remote",
}

if not TYPE_CHECKING:  # type checkers see the imports above (and no catch-all)

    def __getattr__(name: str) -> Any:
        module = _LAZY.get(name)
        if module is None:
            raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
        value = getattr(importlib.import_module(module, __name__), name)
        globals()[name] = value
        return value

    def __dir__() -> list[str]:
        return sorted({*globals(), *_LAZY})


def version() -> str:
    """The version of the ``situate`` program built into this package."""
    from . import _native

    return _native.version()


#: The package's version (that of the ``situate`` program built into it).
__version__: str = version()


__all__ = [
    "DEFAULT_ENDPOINT",
    "ActivationApplied",
    "AmbiguousRobot",
    "BadCondition",
    "BadParam",
    "BadReply",
    "BadRequest",
    "Connector",
    "Event",
    "Graph",
    "GraphSignal",
    "GraphSkill",
    "Hello",
    "Interrupted",
    "Invalid",
    "LocalRobot",
    "ManagerStarted",
    "ManagerStopped",
    "MissingProviders",
    "MissingResource",
    "MonitorCancelled",
    "MonitorEvent",
    "MonitorFired",
    "MonitorInfo",
    "NoSession",
    "NotOwner",
    "NotRunning",
    "OtherEvent",
    "OtherRobots",
    "Param",
    "ParamChanged",
    "ParamInfo",
    "Phase",
    "Port",
    "PortInfo",
    "Print",
    "PriorityChanged",
    "ProtocolMismatch",
    "Reading",
    "RemoteSkill",
    "RemoteSkillServer",
    "Robot",
    "RunResult",
    "SituateError",
    "Skill",
    "SkillDeclarationError",
    "SkillFaulted",
    "SkillInfo",
    "SkillLoadError",
    "Stats",
    "Stream",
    "Telemetry",
    "Timing",
    "Unavailable",
    "UnknownMonitor",
    "UnknownParam",
    "UnknownSignal",
    "UnknownSkill",
    "UnknownVerb",
    "Winner",
    "WorkerFailed",
    "__version__",
    "connect",
    "data_dir",
    "param",
    "port",
    "remote_skill",
    "run",
    "serve_skill",
    "skill",
    "version",
]
