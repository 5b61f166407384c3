"""A client that connects while the program is still starting still finds its robot.

A Zenoh session can connect to a program that has opened its endpoint but not yet declared its
requests (`situate run` opens the session, then serves the link). A Zenoh get that finds nobody
to ask ends at once, with no answer: `hello` used to say "no skill manager answered" then, at
once, and `test_the_native_program_releases_the_gil_and_returns_its_exit_code` failed on a busy
machine (once in a fresh-clone `make test`). Here a stand-in program (a Zenoh peer, a test
double beside that test of the real program) declares its `hello` only after the client asked.
"""

from __future__ import annotations

import json
import threading
import time
from typing import Any

import pytest
import zenoh
from support import free_port

from situate import _link
from situate.errors import NotRunning


def _program(endpoint: str) -> zenoh.Session:
    conf = zenoh.Config()
    conf.insert_json5("mode", '"peer"')
    conf.insert_json5("listen/endpoints", json.dumps([endpoint]))
    conf.insert_json5("scouting/multicast/enabled", "false")
    return zenoh.open(conf)


def _answer(query: zenoh.Query) -> None:
    query.reply(query.key_expr, json.dumps({"ok": {"robot": "late", "protocol": 1}}))


@pytest.mark.parametrize("robot", [None, "late"])
def test_hello_waits_for_a_program_that_declares_its_requests_late(robot: str | None) -> None:
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    program = _program(endpoint)
    queryables: list[Any] = []
    try:
        session = _link.open_session([endpoint])
        got: list[Any] = []

        def ask() -> None:
            try:
                got.append(_link.hello(session, robot, timeout=60, endpoints=[endpoint]))
            except Exception as e:  # handed to the test's thread
                got.append(e)

        asker = threading.Thread(target=ask)
        asker.start()
        # The client asks before anything answers: nothing is declared yet.
        time.sleep(0.3)
        assert not got, got
        queryables.append(program.declare_queryable("situate/late/req/hello", _answer))
        asker.join(60)
        assert not asker.is_alive(), "hello did not return"
        assert isinstance(got[0], dict), got
        assert got[0]["robot"] == "late"
        _link.close_session(session)
    finally:
        for q in queryables:
            q.undeclare()
        program.close()  # type: ignore[no-untyped-call]


def test_hello_still_gives_up_after_its_timeout() -> None:
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    program = _program(endpoint)
    try:
        session = _link.open_session([endpoint])
        start = time.monotonic()
        with pytest.raises(NotRunning):
            _link.hello(session, None, timeout=0.5, endpoints=[endpoint])
        # It waited for its timeout, and not for ever.
        assert 0.5 <= time.monotonic() - start < 30
        _link.close_session(session)
    finally:
        program.close()  # type: ignore[no-untyped-call]
