"""The program `situate demo` runs (demo/deliver.py): its arguments, the run, its signals.

It reads the arguments `situate demo` passes (the link's endpoint, the mode, the mission's
section of the map, the task, the run's seed), connects to the robot and runs the task with
the design the mode names: the sequencer (`sequenced.delivery.Delivery`, also for
``all-active``) or the reactive robot (`reactive.rules.Reactive`). Ctrl-C, SIGTERM and SIGHUP
end the run with one line and status 128 + the signal's number.
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import os
import sys
from collections.abc import Sequence
from signal import SIGHUP, SIGINT, SIGTERM, Signals
from signal import signal as set_signal_handler

import situate
from courier.link import EVENT_KINDS, OutOfTime, PhaseFailed
from courier.mission import Mission, Stop, parse_task
from courier.sequenced.delivery import PHASES, Delivery

#: What ``--help`` says the program is.
DESCRIPTION = (
    "The message delivery of the paper's section 6: the mission's narrative, phase by phase."
)


async def main(argv: Sequence[str] | None = None) -> int:
    """Parses the arguments `situate demo` passes, runs the mission; the exit status."""
    p = argparse.ArgumentParser(description=DESCRIPTION)
    p.add_argument("--connect", default=os.environ.get("SITUATE_CONNECT", "tcp/127.0.0.1:7447"))
    p.add_argument("--robot", default=None)
    p.add_argument("--mode", choices=["sequenced", "all-active", "reactive"], default="sequenced")
    p.add_argument("--limit-s", type=float, default=1800.0, help="give up after this (simulated)")
    p.add_argument("--mission", required=True, help="the map's mission section, as JSON")
    p.add_argument(
        "--from",
        dest="first",
        choices=PHASES,
        default=os.environ.get("DELIVER_FROM") or PHASES[0],
        help="start at this phase (the scenario maps start the robot there; env DELIVER_FROM)",
    )
    p.add_argument(
        "--to",
        dest="last",
        choices=PHASES,
        default=os.environ.get("DELIVER_TO") or PHASES[-1],
        help="stop after this phase (env DELIVER_TO)",
    )
    p.add_argument(
        "--task",
        default="office",
        help="stops where the message is said, in order: office, lobby:FLOOR (comma-separated)",
    )
    p.add_argument("--quiet", action="store_true")
    p.add_argument("--seed", type=int, default=1, help="seeds the wander paths (the run's seed)")
    a = p.parse_args(argv)
    mission = Mission.from_json(a.mission)
    try:
        stops = parse_task(a.task, mission)
    except ValueError as e:
        p.error(str(e))
    async with situate.connect(a.robot, endpoint=a.connect, timeout=30) as robot:
        if a.mode == "reactive":
            return await run_reactive(robot, mission, stops, a)
        seq = Delivery(robot, mission, mode=a.mode, limit_s=a.limit_s, quiet=a.quiet, seed=a.seed)
        try:
            await seq.run(a.first, a.last, stops)
        except (PhaseFailed, OutOfTime) as e:
            await seq.say(f"mission failed: {e}")
            with contextlib.suppress(situate.SituateError):
                await robot.stop()
            return 1
        except (asyncio.CancelledError, KeyboardInterrupt):
            # Interrupted (`run`): one line, whatever --quiet says, and the cycle stopped.
            where = f" in phase {seq.phase_no} ({seq.phase_text})" if seq.phase_no else ""
            name = Signals(INTERRUPTED.get("signal", SIGINT)).name
            print(f"[{seq.t:7.1f} s] interrupted ({name}){where}, message not delivered")
            INTERRUPTED["said"] = 1
            with contextlib.suppress(situate.SituateError, asyncio.TimeoutError):
                await asyncio.wait_for(robot.stop(), 2)
            raise
        with contextlib.suppress(situate.SituateError):
            await robot.stop()
    return 0


async def run_reactive(
    robot: situate.Robot, mission: Mission, stops: list[Stop], a: argparse.Namespace
) -> int:
    """The experiment's reactive robot (`reactive.rules`) on the same task; the exit status."""
    # Imported only when asked for: the sequencer's runs do without it.
    from courier.reactive.rules import Reactive

    seq = Reactive(robot, mission, stops, limit_s=a.limit_s, quiet=a.quiet, seed=a.seed)
    try:
        async with robot.events(*EVENT_KINDS) as stream:
            seq.stream = stream  # read for faults only (`Link.take_faults`)
            await seq.run_task()
    except (OutOfTime, PhaseFailed) as e:
        await seq.say(f"mission failed: {e}")
        with contextlib.suppress(situate.SituateError):
            await robot.stop()
        return 1
    with contextlib.suppress(situate.SituateError):
        await robot.stop()
    return 0


#: How the run was interrupted: ``signal`` (its number) and whether the outcome was ``said``.
INTERRUPTED: dict[str, int] = {}


async def _main_stopping_on_signals(argv: Sequence[str] | None) -> int:
    """:func:`main`, cancelled by SIGTERM or SIGHUP as by Ctrl-C (``asyncio.run``'s own)."""
    task = asyncio.current_task()
    assert task is not None

    def stop(sig: int) -> None:
        if "signal" in INTERRUPTED:  # a second one: at once
            sys.stdout.flush()
            os._exit(128 + sig)
        INTERRUPTED["signal"] = sig
        task.cancel()

    loop = asyncio.get_running_loop()

    def on_signal(sig: int, _frame: object) -> None:
        # A plain handler, not `loop.add_signal_handler`: that one makes the signal write to the
        # loop's wakeup pipe, and a signal landing while `asyncio.run` closes the loop (the demo
        # passes Ctrl-C on as SIGTERM) printed a traceback ("Bad file descriptor").
        with contextlib.suppress(RuntimeError):  # the loop is closed: the run is ending anyway
            loop.call_soon_threadsafe(stop, sig)

    for sig in (SIGTERM, SIGHUP):
        with contextlib.suppress(ValueError, AttributeError):  # not on Windows
            set_signal_handler(sig, on_signal)
    return await main(argv)


def run(argv: Sequence[str] | None = None) -> int:
    """Runs :func:`main`; the exit status.

    Ctrl-C, SIGTERM and SIGHUP end the mission with one line (the time and the phase) and
    status 128 + the signal's number (130 for Ctrl-C), without a traceback; a second signal
    ends the program at once.
    """
    try:
        return asyncio.run(_main_stopping_on_signals(argv))
    except (KeyboardInterrupt, asyncio.CancelledError):
        sig = INTERRUPTED.get("signal", SIGINT)
        if not INTERRUPTED.get("said"):
            print(f"interrupted ({Signals(sig).name}) before the mission started")
        return 128 + sig
