"""The ``situate`` console script of the Python package.

Every command is the Rust program's (``situate_cli``, built into
:mod:`situate._native`), so ``situate run``, ``situate skills`` and the rest
behave exactly as with the Rust install. One command is Python's own, since
it runs Python code: ``situate serve-skill MODULE:ATTR --robot ROBOT`` (a skill *type*,
``situate serve-skill c.runaway --library ...``, is the Rust program's again).

Signals are handled as by the Rust program: where a command waits (``run``, ``demo``,
``serve-skill``, ``monitor``, ``events``), SIGINT, SIGTERM and SIGHUP ask for a clean stop and a
second signal ends it at once (status 128 + the signal); elsewhere they end the program.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import signal
import sys
import threading
from collections.abc import Callable, Sequence
from pathlib import Path
from types import FrameType
from typing import Any, Union

_Handler = Union[Callable[[int, Union[FrameType, None]], Any], int, None]

__all__ = ["data_dir", "main", "serve_skill_main"]


def main(argv: Sequence[str] | None = None) -> None:
    """Runs ``situate`` with ``argv`` (default ``sys.argv``) and exits with its status."""
    args = list(sys.argv if argv is None else argv)
    if len(args) > 1 and args[1] == "serve-skill" and _names_python_function(args[2:]):
        sys.exit(serve_skill_main(args[2:]))
    from . import _native

    sys.stdout.flush()
    # The program installs its own handlers where it waits. Python's SIGINT handler would also
    # run (they are chained) and raise KeyboardInterrupt once the program has returned.
    with contextlib.suppress(ValueError):  # not the main thread: leave them
        signal.signal(signal.SIGINT, signal.SIG_DFL)
    data = data_dir()
    sys.exit(
        _native.main(
            ["situate", *args[1:]],
            interpreter=sys.executable or None,
            data_dir=str(data) if data is not None else None,
        )
    )


def data_dir() -> Path | None:
    """The package data: ``demo/``, ``maps/``, ``examples/``, ``cmake/`` and ``include/``.

    As the wheel ships them; ``situate cmake-dir`` prints its ``cmake/`` (the CMake package for
    C/C++ skills, whose ``../include`` holds ``situate.h`` and ``situate.hpp``).

    ``None`` when the package runs from a checkout without them (``situate demo`` then uses the
    checkout's ``demo/``).
    """
    path = Path(__file__).resolve().parent / "_data"
    return path if (path / "demo" / "robot.yaml").is_file() else None


def _names_python_function(argv: Sequence[str]) -> bool:
    """Whether ``serve-skill``'s arguments name a ``MODULE:FUNCTION`` (served here, in Python).

    Anything else names a skill type (``c.runaway``), which the Rust program serves, loading
    ``--library`` and ``--python`` files itself.
    """
    takes_value = {
        "--robot",
        "--name",
        "--connect",
        "--timeout",
        "--library",
        "--python",
        "--zenoh",
    }
    skip = False
    for arg in argv:
        if skip:
            skip = False
        elif arg in takes_value:
            skip = True
        elif not arg.startswith("-"):
            return ":" in arg
    return False


def serve_skill_main(argv: Sequence[str]) -> int:
    """Runs ``situate serve-skill MODULE:ATTR [--robot R] [--name N] [--connect E]``.

    Returns the exit status.
    """
    from . import _link
    from .errors import SituateError
    from .remote import RemoteSkillServer, load_skill

    parser = argparse.ArgumentParser(
        prog="situate serve-skill",
        description="Serve a Python function decorated with @situate.remote_skill as a robot's "
        "remote skill, until interrupted.",
    )
    parser.add_argument("skill", metavar="MODULE:ATTR", help="e.g. mybot.skills:doubler")
    parser.add_argument(
        "--robot", help="the robot's name (default: the only robot answering)", default=None
    )
    parser.add_argument(
        "--name", help="the skill's name in the robot file (default: the function's)"
    )
    parser.add_argument(
        "--connect",
        action="append",
        help="the manager's endpoint (default: $SITUATE_CONNECT or tcp/127.0.0.1:7447)",
    )
    parser.add_argument(
        "--timeout", type=float, default=5.0, help="seconds to wait for the robot's answer"
    )
    opts = parser.parse_args(list(argv))
    endpoints = _link.endpoint_list(opts.connect)
    try:
        skill = load_skill(opts.skill, search=[os.getcwd()])
    except (ImportError, AttributeError, TypeError, ValueError) as e:
        print(f"error: {e}", file=sys.stderr)
        return 1
    stop = _StopOnSignals(opts.skill)
    try:
        robot = opts.robot or _find_robot(endpoints, opts.timeout)
        server = RemoteSkillServer(skill, robot=robot, name=opts.name, endpoint=endpoints)
        print(
            f"situate: serving remote skill `{server.name}` of robot `{robot}` "
            f"({server.inputs_key}) via {', '.join(endpoints)}; Ctrl-C stops",
            file=sys.stderr,
            flush=True,
        )
        server.serve(stop.event)
    except SituateError as e:
        print(f"error: {e}", file=sys.stderr)
        return 1
    finally:
        stop.restore()
    s = server.stats
    how = f" ({signal.Signals(stop.signal).name})" if stop.signal else ""
    print(
        f"situate: stopped{how}; {s.received} inputs received, {s.computed} runs, "
        f"{s.dropped} dropped as stale, {s.errors} errors",
        file=sys.stderr,
        flush=True,
    )
    return 0


def _stop_bound() -> float:
    """How long a stop may take before the program exits without what has not stopped, s."""
    try:
        bound = float(os.environ.get("SITUATE_STOP_TIMEOUT_S", "2"))
    except ValueError:
        return 2.0
    return bound if 0 <= bound < float("inf") else 2.0


class _StopOnSignals:
    """SIGINT, SIGTERM and SIGHUP set :attr:`event`, as in the Rust program's ``serve-skill``.

    A second signal ends the program at once (status 128 + the signal); a function that does
    not return within the stop bound (``$SITUATE_STOP_TIMEOUT_S``, 2 s) is left behind.
    """

    def __init__(self, what: str) -> None:
        self.what = what
        self.event = threading.Event()
        self.signal = 0
        self._previous: dict[int, _Handler] = {}
        self._timer: threading.Timer | None = None
        for sig in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP):
            with contextlib.suppress(ValueError, AttributeError):  # not the main thread
                self._previous[sig] = signal.signal(sig, self._on_signal)

    def _on_signal(self, sig: int, _frame: FrameType | None) -> None:
        if self.signal:
            print(
                f"\nsituate: {signal.Signals(sig).name} while stopping: exiting at once",
                file=sys.stderr,
                flush=True,
            )
            os._exit(128 + sig)
        self.signal = sig
        print(
            f"situate: {signal.Signals(sig).name}: stopping (again to exit at once)",
            file=sys.stderr,
            flush=True,
        )
        self.event.set()
        self._timer = threading.Timer(_stop_bound(), self._stuck)
        self._timer.daemon = True
        self._timer.start()

    def _stuck(self) -> None:
        print(
            f"situate: `{self.what}` did not return within {_stop_bound():g} s of the stop "
            "request; exiting without it",
            file=sys.stderr,
            flush=True,
        )
        os._exit(1)

    def restore(self) -> None:
        """Puts the previous handlers back; the function returned."""
        if self._timer is not None:
            self._timer.cancel()
        for sig, previous in self._previous.items():
            signal.signal(sig, previous)


def _find_robot(endpoints: list[str], timeout: float) -> str:
    from . import _link

    session = _link.open_session(endpoints)
    try:
        return str(_link.hello(session, None, timeout=timeout, endpoints=endpoints)["robot"])
    finally:
        _link.close_session(session)


if __name__ == "__main__":
    main()
