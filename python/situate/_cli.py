"""The ``situate`` console script of the Python package.

Every command is the Rust program's (``situate_cli``, built into
:mod:`situate._native`), so ``situate run``, ``situate skills`` and the rest
behave exactly as with the Rust install. One command is Python's own, since
it runs Python code: ``situate serve-skill MODULE:ATTR --robot ROBOT`` (a skill *type*,
``situate serve-skill c.runaway --library ...``, is the Rust program's again).
"""

from __future__ import annotations

import argparse
import os
import sys
from collections.abc import Sequence

__all__ = ["main", "serve_skill_main"]


def main(argv: Sequence[str] | None = None) -> None:
    """Runs ``situate`` with ``argv`` (default ``sys.argv``) and exits with its status."""
    args = list(sys.argv if argv is None else argv)
    if len(args) > 1 and args[1] == "serve-skill" and _names_python_function(args[2:]):
        sys.exit(serve_skill_main(args[2:]))
    from . import _native

    sys.stdout.flush()
    sys.exit(_native.main(["situate", *args[1:]]))


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
    try:
        robot = opts.robot or _find_robot(endpoints, opts.timeout)
        server = RemoteSkillServer(skill, robot=robot, name=opts.name, endpoint=endpoints)
        print(
            f"situate: serving remote skill `{server.name}` of robot `{robot}` "
            f"({server.inputs_key}) via {', '.join(endpoints)}",
            file=sys.stderr,
            flush=True,
        )
        server.serve()
    except SituateError as e:
        print(f"error: {e}", file=sys.stderr)
        return 1
    return 0


def _find_robot(endpoints: list[str], timeout: float) -> str:
    from . import _link

    session = _link.open_session(endpoints)
    try:
        return str(_link.hello(session, None, timeout=timeout, endpoints=endpoints)["robot"])
    finally:
        _link.close_session(session)


if __name__ == "__main__":
    main()
