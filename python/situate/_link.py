"""Plumbing shared by the sequencer client and the remote-skill server.

Zenoh's Python API is blocking; :mod:`situate.client` runs the blocking
functions off the event loop, and sends its requests with :func:`send`,
whose answer comes back through a callback. Nothing here is public: the
protocol itself is ``docs/protocol.md``.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import os
import re
import secrets
import threading
import time
from collections.abc import Callable, Mapping, Sequence
from typing import Any, TypeVar, Union

import zenoh

from .errors import (
    AmbiguousRobot,
    BadReply,
    NotRunning,
    OtherRobots,
    SituateError,
    from_reply,
)

#: Where a manager listens unless its robot file says otherwise.
DEFAULT_ENDPOINT = "tcp/127.0.0.1:7447"

#: The protocol version this package speaks.
PROTOCOL = 1

Endpoints = Union[str, Sequence[str]]
"""One endpoint such as ``"tcp/127.0.0.1:7447"``, or several."""


def default_endpoints() -> list[str]:
    """``$SITUATE_CONNECT`` (comma-separated) if set, else the default endpoint.

    The ``situate`` program reads the same variable, so one setting serves both.
    """
    env = os.environ.get("SITUATE_CONNECT", "").strip()
    return [e.strip() for e in env.split(",") if e.strip()] if env else [DEFAULT_ENDPOINT]


def endpoint_list(endpoints: Endpoints | None) -> list[str]:
    """``endpoints`` as a non-empty list (``None``: :func:`default_endpoints`)."""
    if endpoints is None:
        return default_endpoints()
    if isinstance(endpoints, str):
        return [endpoints]
    listed = list(endpoints)
    if not listed:
        raise ValueError("at least one endpoint is needed, e.g. 'tcp/127.0.0.1:7447'")
    return listed


ZenohSettings = Mapping[str, Any]
"""Further Zenoh configuration (TLS, user and password, ...), as in Zenoh's configuration file."""


def _merge(base: dict[str, Any], extra: Mapping[str, Any]) -> dict[str, Any]:
    """``extra`` merged into ``base``, mappings member by member (as the manager does)."""
    out = dict(base)
    for key, value in extra.items():
        if isinstance(value, Mapping) and isinstance(out.get(key), dict):
            out[key] = _merge(out[key], value)
        else:
            out[key] = value
    return out


def zenoh_config(
    *,
    connect: Sequence[str] = (),
    listen: Sequence[str] = (),
    mode: str = "client",
    extra: ZenohSettings | None = None,
) -> zenoh.Config:
    """A Zenoh configuration that discovers nothing: multicast and gossip scouting off.

    A sequencer or a remote skill is a ``client`` that connects to the
    manager's endpoint and listens on nothing (``docs/protocol.md``, "Session").
    ``extra`` is merged last: TLS certificates (``transport.link.tls``),
    credentials (``transport.auth.usrpwd``) for a manager with access control.
    """
    config: dict[str, Any] = {
        "mode": mode,
        "connect": {"endpoints": list(connect)},
        "listen": {"endpoints": list(listen)},
        "scouting": {"multicast": {"enabled": False}, "gossip": {"enabled": False}},
    }
    if extra:
        config = _merge(config, extra)
    parsed: zenoh.Config = zenoh.Config.from_json5(json.dumps(config))
    return parsed


#: A source location some Zenoh errors end with: `` at /home/…/zenoh/src/x.rs:447.``.
_SOURCE_AT = re.compile(r"\s+at\s+\S*\.rs:\d+\.?")


def zenoh_error(e: BaseException) -> str:
    """A Zenoh error's text without the build machine's source paths it may carry."""
    return _SOURCE_AT.sub("", str(e)).rstrip()


def open_session(endpoints: Sequence[str], extra: ZenohSettings | None = None) -> zenoh.Session:
    """Opens a client session to ``endpoints``; :class:`NotRunning` if none accepts."""
    try:
        return zenoh.open(zenoh_config(connect=endpoints, extra=extra))
    except zenoh.ZError as e:
        where = ", ".join(endpoints)
        raise NotRunning(
            f"no skill manager answered at {where}: could not connect ({zenoh_error(e)}); "
            "is `situate run` running and reachable there, and does it accept these "
            "credentials (user and password, certificates)?"
        ) from e


def payload_json(payload: zenoh.ZBytes) -> Any:
    """A payload's JSON, or :class:`BadReply` saying what came instead."""
    raw = payload.to_bytes()
    try:
        return json.loads(raw)
    except ValueError as e:
        raise BadReply(f"a reply that is not JSON: {raw[:80]!r}") from e


def _result(key: str, reply: zenoh.Reply, timeout: float, endpoints: Sequence[str]) -> Any:
    """The ``ok`` result of one reply to ``key``, or the reply's error raised."""
    if reply.ok is None:
        detail = reply.err.payload.to_string().strip() if reply.err is not None else ""
        if detail.lower() == "timeout":
            # Zenoh ends a query nobody finished in time with this reply: a robot that
            # took the request and did not answer (a stuck cycle, a busy machine).
            raise _no_answer(key, timeout, endpoints)
        raise BadReply(f"the network refused `{key}`: {detail or 'no reason given'}")
    body = payload_json(reply.ok.payload)
    if not isinstance(body, dict):
        raise BadReply(f"`{key}`: a reply that is not a JSON object: {body!r}")
    if "ok" in body:
        return body["ok"]
    error = body.get("error")
    if isinstance(error, dict):
        raise from_reply(error)
    raise BadReply(f"`{key}`: a reply with neither `ok` nor `error`: {body!r}")


def _no_answer(
    key: str, timeout: float, endpoints: Sequence[str], started: float | None = None
) -> NotRunning:
    """No reply to ``key``; ``started`` (`time.monotonic`) is when the request was sent."""
    waited = None if started is None else time.monotonic() - started
    if waited is not None and waited < timeout / 2:
        # Zenoh ends a query at once when nothing on the link takes that key: no manager of
        # that name is connected now, the connection to it was just lost, or the robot's
        # access rules drop this client's request.
        return NotRunning(
            f"no skill manager answered `{key}`: the request ended after {waited:.1f} s "
            f"unanswered (this client waits up to {timeout:g} s for one that took it), so "
            f"nothing on the link at {', '.join(endpoints)} took it: no robot of that name "
            "is connected now, the connection to it was lost, or it refused this client's "
            "credentials or access rules"
        )
    return NotRunning(
        f"no skill manager answered `{key}` within {timeout:g} s "
        f"(is `situate run` running and reachable at {', '.join(endpoints)}, "
        "is its cycle stuck, or did it refuse this client's credentials or access rules?)"
    )


def request(
    session: zenoh.Session,
    robot: str,
    verb: str,
    args: dict[str, Any],
    *,
    timeout: float,
    endpoints: Sequence[str],
) -> Any:
    """Sends one request and returns its ``ok`` result, or raises the reply's error.

    Blocks for at most ``timeout`` seconds; no answer at all is :class:`NotRunning`.
    """
    key = f"situate/{robot}/req/{verb}"
    started = time.monotonic()
    reply = _first_reply(session, key, json.dumps(args), timeout)
    if reply is None:
        raise _no_answer(key, timeout, endpoints, started)
    return _result(key, reply, timeout, endpoints)


def _first_reply(
    session: zenoh.Session, key: str, payload: str, timeout: float
) -> zenoh.Reply | None:
    """The first reply to a get on ``key``, or None when none came."""
    try:
        replies = session.get(key, payload=payload, timeout=timeout)
    except zenoh.ZError as e:
        raise NotRunning(f"could not send `{key}`: {zenoh_error(e)}") from e
    return next(iter(replies), None)


Done = Callable[[Any, Union[BaseException, None]], None]
"""Called once with a request's outcome: ``(result, None)`` or ``(None, error)``."""


def send(
    session: zenoh.Session,
    robot: str,
    verb: str,
    args: dict[str, Any],
    *,
    timeout: float,
    endpoints: Sequence[str],
    done: Done,
) -> None:
    """Sends one request now, without waiting for its answer.

    ``done`` is called exactly once, on a Zenoh thread, with the ``ok``
    result or the error :func:`request` would raise. Requests sent one after
    another on a session reach the manager, and are answered, in that order.
    Raises :class:`NotRunning` at once if the request cannot be sent.
    """
    key = f"situate/{robot}/req/{verb}"
    lock = threading.Lock()
    finished = False

    def finish(result: Any, error: BaseException | None) -> None:
        nonlocal finished
        with lock:
            if finished:
                return
            finished = True
        done(result, error)

    def on_reply(reply: zenoh.Reply) -> None:
        # Runs on a Zenoh thread: nothing may escape from here.
        try:
            result = _result(key, reply, timeout, endpoints)
        except Exception as e:  # handed over to `done`, not swallowed
            finish(None, e)
        else:
            finish(result, None)

    def on_end() -> None:
        # The query is over (all replies in, or the time-out): no reply means no manager.
        finish(None, _no_answer(key, timeout, endpoints, started))

    # Called on Zenoh's own thread (not one more thread per request): the
    # callbacks only decode the reply and hand it over.
    handler = zenoh.handlers.Callback(on_reply, on_end, indirect=False)
    started = time.monotonic()
    try:
        session.get(key, handler, payload=json.dumps(args), timeout=timeout)
    except zenoh.ZError as e:
        raise NotRunning(f"could not send `{key}`: {zenoh_error(e)}") from e


#: How often a ``hello`` is asked again while no manager has answered yet.
HELLO_RETRY_S = 0.05

#: How long a named robot finds nobody answering before the robots that do answer are asked (a
#: robot still starting declares its keys within this); the Rust client's ``NAMED_GRACE``.
NAMED_GRACE_S = 1.0

#: How long the robots that do answer are given, once a named one did not (only then).
OTHERS_S = 3.0


def _is_timeout(reply: zenoh.Reply) -> bool:
    """Whether ``reply`` is Zenoh's end of a query nobody answered in time."""
    if reply.ok is not None or reply.err is None:
        return False
    return bool(reply.err.payload.to_string().strip().lower() == "timeout")


_T = TypeVar("_T")


def _until_answered(timeout: float, ask: Callable[[float], _T | None]) -> _T | None:
    """Calls ``ask(seconds left)`` until it gives something (not None) or ``timeout`` is over.

    A session can connect to a program that has opened its endpoint but not yet declared its
    requests, and a Zenoh get that finds nobody to ask ends at once, with nothing delivered:
    so it is asked again every ``HELLO_RETRY_S``.
    """
    deadline = time.monotonic() + timeout
    while True:
        got = ask(max(0.001, deadline - time.monotonic()))
        if got is not None or time.monotonic() >= deadline:
            return got
        time.sleep(min(HELLO_RETRY_S, max(0.0, deadline - time.monotonic())))


def robots(session: zenoh.Session, *, timeout: float) -> list[dict[str, Any]]:
    """The ``hello`` results of every manager answering ``situate/*/req/hello``, by robot name.

    Asks again until one answers or ``timeout`` is over (see `_until_answered`).
    """
    found = _until_answered(timeout, lambda left: _robots_once(session, timeout=left) or None)
    return found or []


def _robots_once(session: zenoh.Session, *, timeout: float) -> list[dict[str, Any]]:
    found: dict[str, dict[str, Any]] = {}
    for reply in session.get("situate/*/req/hello", timeout=timeout):
        if reply.ok is None:
            continue
        try:
            body = payload_json(reply.ok.payload)
        except SituateError:
            continue
        hello = body.get("ok") if isinstance(body, dict) else None
        if isinstance(hello, dict) and isinstance(hello.get("robot"), str):
            found[hello["robot"]] = hello
    return [found[name] for name in sorted(found)]


def hello(
    session: zenoh.Session, robot: str | None, *, timeout: float, endpoints: Sequence[str]
) -> dict[str, Any]:
    """The ``hello`` of robot ``robot``, or of the only robot answering when ``None``."""
    if robot is not None:
        # Asked again while nobody is there to answer (see `_until_answered`). Once nobody has
        # served the name for `NAMED_GRACE_S`, the robots that do answer are asked (again each
        # `NAMED_GRACE_S` while none does): a misspelt name is then said at once, with the names
        # there are, and a robot still starting beside none other is still waited for.
        key = f"situate/{robot}/req/hello"
        next_ask = time.monotonic() + NAMED_GRACE_S

        def others(left: float) -> None:
            answering = [h["robot"] for h in _robots_once(session, timeout=left)]
            if answering and robot not in answering:
                raise OtherRobots(robot, answering)

        def ask(left: float) -> zenoh.Reply | None:
            nonlocal next_ask
            reply = _first_reply(session, key, "{}", left)
            if reply is None and time.monotonic() >= next_ask:
                others(min(left, 2.0))
                next_ask = time.monotonic() + NAMED_GRACE_S
            return reply

        reply = _until_answered(timeout, ask)
        # Nobody answered: no reply, or Zenoh's `Timeout` (on a busy machine a get that finds
        # nobody can end so). Before saying so, the robots that do answer are asked once more,
        # with time enough for a busy one: a name that is not there is said with those.
        if reply is None or _is_timeout(reply):
            others(OTHERS_S)
        if reply is None:
            raise _no_answer(key, timeout, endpoints)
        result = _result(key, reply, timeout, endpoints)
        if not isinstance(result, dict):
            raise BadReply(f"`hello`: expected an object, got {result!r}")
        return result
    answered = robots(session, timeout=timeout)
    if not answered:
        raise NotRunning(
            f"no skill manager answered `situate/*/req/hello` within {timeout:g} s "
            f"(is `situate run` running and reachable at {', '.join(endpoints)}, "
            "or did it refuse this client's credentials or access rules?)"
        )
    if len(answered) > 1:
        names = ", ".join(h["robot"] for h in answered)
        raise AmbiguousRobot(f"several robots answered ({names}); name one with robot=")
    return answered[0]


def session_public_id(secret: str) -> str:
    """A client session's public id: the first 16 bytes of its secret's SHA3-256, in hex.

    The manager shows only this id (``monitor_list``, events); the secret,
    sent with ``monitor_add`` and ``monitor_cancel``, proves the session
    (docs/protocol.md, "Sessions").
    """
    return hashlib.sha3_256(secret.encode()).hexdigest()[:32]


def open_client_session(
    session: zenoh.Session, robot: str
) -> tuple[str, str, zenoh.LivelinessToken]:
    """A new client session with ``robot``: its secret, public id and liveliness token.

    The token, on ``situate/<robot>/session/<id>``, lives until it is undeclared or the
    Zenoh session closes; then the manager removes the session's monitors.
    """
    secret = secrets.token_hex(16)
    public = session_public_id(secret)
    token = session.liveliness().declare_token(f"situate/{robot}/session/{public}")
    return secret, public, token


def undeclare(entity: zenoh.Subscriber[Any] | zenoh.Publisher | zenoh.LivelinessToken) -> None:
    """Undeclares a subscriber, publisher or token; one of a closed session is already gone."""
    with contextlib.suppress(zenoh.ZError):
        entity.undeclare()  # type: ignore[no-untyped-call]  # zenoh's stub lacks `-> None`


def close_session(session: zenoh.Session) -> None:
    """Closes a session; closing a closed one does nothing."""
    with contextlib.suppress(zenoh.ZError):
        session.close()  # type: ignore[no-untyped-call]  # zenoh's stub lacks `-> None`
