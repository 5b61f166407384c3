"""The sequencer client: drive a running skill manager from asyncio.

In the paper's three tiers a *sequencer* turns skills on and off, tunes
them and waits for conditions, while the skill manager runs the skills in
its periodic cycle. :func:`connect` gives a sequencer a :class:`Robot`, one
coroutine per request of ``docs/protocol.md``::

    import asyncio
    import situate

    async def main() -> None:
        async with situate.connect("toybot") as robot:
            await robot.activate("wander", "runaway")
            await robot.set_param("runaway", "safe_distance", 0.3)
            event = await robot.when("sonar.range[0] < 0.25", timeout=30)
            print("obstacle ahead at cycle", event.cycle, event.values)
            await robot.deactivate("wander")

    asyncio.run(main())

How it works
------------
The robot is reached over Zenoh: the client opens a session in *client*
mode that connects to the manager's endpoint (default
``tcp/127.0.0.1:7447``, or ``$SITUATE_CONNECT``) and discovers nothing
else. A request is a Zenoh ``get`` on ``situate/<robot>/req/<verb>``, sent
at once without blocking the event loop; its reply, events and telemetry
arrive on Zenoh's threads and are handed to the loop with
``call_soon_threadsafe``. Requests are handled in the order they are sent,
so several can be sent before awaiting their replies (:meth:`Robot.send`).

Changes take effect from the manager's *next* cycle; queries answer with
the state at the end of the last one. A refused request raises a
:class:`~situate.SituateError` subclass carrying the manager's message word
for word, and changes nothing.
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import os
import secrets
from collections.abc import Callable, Generator, Mapping, Sequence
from types import TracebackType
from typing import Any, Generic, TypeVar

import zenoh

from . import _link
from .errors import BadReply, NotRunning, SituateError, UnknownVerb, from_reply
from .events import Event, MonitorFired, Telemetry, parse_event, parse_telemetry
from .info import Graph, Hello, MonitorInfo, Reading, SkillInfo, Stats, Winner, monitor_target
from .values import decode_untyped, encode

__all__ = ["DEFAULT_ENDPOINT", "Connector", "Robot", "Stream", "connect"]

DEFAULT_ENDPOINT = _link.DEFAULT_ENDPOINT

#: The monitor modes of ``monitor_add``.
MONITOR_MODES = ("once", "edge", "level")

#: Most requests one ``batch`` query carries (the manager's cap, docs/protocol.md).
MAX_BATCH = 64

#: Most signals one ``query_many`` reads (the manager's cap, docs/protocol.md).
MAX_QUERY_SIGNALS = 256

#: A request waiting to leave: its verb, its encoded arguments, its reply's future.
_Outgoing = tuple[str, dict[str, Any], "asyncio.Future[Any]"]

#: The verbs that carry this connection's session secret (docs/protocol.md, "Sessions").
_SESSION_VERBS = frozenset({"monitor_add", "monitor_cancel"})

T = TypeVar("T")


class Stream(Generic[T]):
    """A subscription whose messages are awaited one by one: ``async for item in stream``.

    The subscription is declared when the stream is made, so nothing
    published after that is missed, even before the first ``await``.
    Messages queue up until read (the queue is unbounded: read what you
    subscribe to, or :meth:`close` the stream). The stream ends when it is
    closed or its :class:`Robot` is closed; ``async with`` closes it.
    """

    def __init__(
        self,
        robot: Robot,
        keys: Sequence[str],
        parse: Callable[[dict[str, Any]], T],
    ) -> None:
        self._robot = robot
        self._parse = parse
        self._loop = asyncio.get_running_loop()
        self._queue: asyncio.Queue[T | None] = asyncio.Queue()
        self._closed = False
        self._ended = False
        # The callback runs on Zenoh's own thread, not on one more thread per subscriber.
        handler = zenoh.handlers.Callback(self._on_sample, indirect=False)
        self._subscribers = [robot._session.declare_subscriber(k, handler) for k in keys]
        robot._streams.add(self)

    def _on_sample(self, sample: zenoh.Sample) -> None:
        # Runs on a Zenoh thread: parse here, then hand over to the loop.
        try:
            data = json.loads(sample.payload.to_bytes())
        except ValueError:
            return
        if not isinstance(data, dict):
            return
        try:
            item = self._parse(data)
        except (KeyError, TypeError, ValueError):  # not the protocol's shape: drop it
            return
        with contextlib.suppress(RuntimeError):  # the loop is closed: nobody is listening
            self._loop.call_soon_threadsafe(self._queue.put_nowait, item)

    def close(self) -> None:
        """Ends the subscription; an ``async for`` over the stream then ends."""
        if self._closed:
            return
        self._closed = True
        for subscriber in self._subscribers:
            _link.undeclare(subscriber)
        self._robot._streams.discard(self)
        self._queue.put_nowait(None)

    def __aiter__(self) -> Stream[T]:
        return self

    async def __anext__(self) -> T:
        # After close(), what had arrived is still handed out, then the stream ends for good.
        if self._ended:
            raise StopAsyncIteration
        item = await self._queue.get()
        if item is None:
            self._ended = True
            raise StopAsyncIteration
        return item

    async def next(self, timeout: float | None = None) -> T:
        """The next message, waiting at most ``timeout`` seconds (``TimeoutError``)."""
        return await asyncio.wait_for(self.__anext__(), timeout)

    def drain(self) -> list[T]:
        """The messages that have arrived and were not read yet, oldest first, without waiting.

        For a loop that polls (steps the cycle, then looks at what happened) rather than
        awaits. Empty when none is there; after :meth:`close`, what had arrived, then nothing.
        """
        items: list[T] = []
        while not self._ended:
            try:
                item = self._queue.get_nowait()
            except asyncio.QueueEmpty:
                break
            if item is None:
                self._ended = True
                break
            items.append(item)
        return items

    async def __aenter__(self) -> Stream[T]:
        return self

    async def __aexit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self.close()


class Robot:
    """A connection to one robot's skill manager. Make one with :func:`connect`.

    Every request is a coroutine; arguments and results are those of
    ``docs/protocol.md``, with results as dataclasses (:mod:`situate.info`)
    and values decoded (:mod:`situate.values`).
    """

    def __init__(
        self,
        session: zenoh.Session,
        hello: Hello,
        *,
        endpoints: Sequence[str],
        timeout: float,
        client_session: tuple[str, str, zenoh.LivelinessToken],
    ) -> None:
        self._session = session
        self._endpoints = list(endpoints)
        self._streams: set[Stream[Any]] = set()
        #: The name this connection gives itself, shown with its monitors (a label, not an
        #: identity).
        self.client_id: str = f"py-{os.getpid()}-{secrets.token_hex(4)}"
        # The session that holds this connection's monitors (docs/protocol.md, "Sessions"):
        # its secret goes with monitor_add/monitor_cancel, its token lives as long as this
        # connection; when it goes, the manager removes this connection's monitors.
        self._session_secret, public_id, self._session_token = client_session
        #: This connection's session as the manager shows it (``MonitorInfo.session``,
        #: ``MonitorCancelled.session``): only this connection cancels its monitors.
        self.session_id: str = public_id
        #: What the manager said in ``hello``: protocol, robot name, version.
        self.hello: Hello = hello
        #: The robot's name (its robot file's ``robot:``).
        self.name: str = hello.robot
        #: Seconds to wait for each reply before :class:`~situate.NotRunning`.
        self.timeout: float = timeout
        #: Requests sent since the loop last ran: they leave together (see `send`).
        self._outbox: list[_Outgoing] = []
        #: Whether the manager takes ``batch`` (a manager older than it does not).
        self._batches = True

    def __repr__(self) -> str:
        return f"<situate.Robot {self.name!r} at {', '.join(self._endpoints)}>"

    # ----- plumbing --------------------------------------------------------------

    async def request(self, verb: str, **args: Any) -> Any:
        """Sends any request verb with its arguments and returns the raw ``ok`` result.

        The typed methods below are built on this; use it for verbs a newer
        manager adds. Argument values are encoded with :func:`situate.values.encode`.
        """
        return await self.send(verb, **args)

    def send(self, verb: str, **args: Any) -> asyncio.Future[Any]:
        """Sends a request and returns a future of its raw ``ok`` result (or error).

        Like :meth:`request`, but without waiting: the request leaves as soon as
        the calling coroutine next yields to the loop, and the manager handles
        requests in the order they were sent. A sequencer can send several
        changes and then await them all, paying for one round trip instead of
        one each::

            sent = [robot.send("set_param", skill="avoid", param="distance", value=0.5),
                    robot.send("activate", skills=["avoid"])]
            await asyncio.gather(*sent)

        Requests sent before the loop runs again travel together, as one
        ``batch`` query (docs/protocol.md): each is still answered on its own,
        exactly as if it had been sent alone. Await every future (a refused
        request raises there), from a coroutine of the loop that sent it.
        """
        loop = asyncio.get_running_loop()
        future: asyncio.Future[Any] = loop.create_future()
        if not self._outbox:
            loop.call_soon(self._send_outbox)
        if verb in _SESSION_VERBS and "session" not in args:
            args["session"] = self._session_secret
        self._outbox.append((verb, {k: encode(v) for k, v in args.items()}, future))
        return future

    def _send_outbox(self) -> None:
        """Sends the requests waiting to leave: alone, or together as ``batch`` queries."""
        outbox, self._outbox = self._outbox, []
        if len(outbox) == 1 or not self._batches:
            for verb, args, future in outbox:
                self._send_one(verb, args, future)
            return
        for start in range(0, len(outbox), MAX_BATCH):
            self._send_batch(outbox[start : start + MAX_BATCH])

    def _send_one(self, verb: str, args: dict[str, Any], future: asyncio.Future[Any]) -> None:
        loop = future.get_loop()

        def done(result: Any, error: BaseException | None) -> None:
            # On a Zenoh thread: hand the outcome over to the loop.
            with contextlib.suppress(RuntimeError):  # the loop is closed: nobody waits
                loop.call_soon_threadsafe(_settle, future, result, error)

        try:
            _link.send(
                self._session,
                self.name,
                verb,
                args,
                timeout=self.timeout,
                endpoints=self._endpoints,
                done=done,
            )
        except SituateError as e:
            _settle(future, None, e)

    def _send_batch(self, batch: list[_Outgoing]) -> None:
        loop = batch[0][2].get_loop()

        def settle_all(result: Any, error: BaseException | None) -> None:
            # On the loop: each request's own reply, in order.
            if isinstance(error, UnknownVerb) and self._batches:
                # A manager older than `batch`: each request on its own, from now on.
                self._batches = False
                for verb, args, future in batch:
                    self._send_one(verb, args, future)
                return
            if error is None and not (isinstance(result, list) and len(result) == len(batch)):
                error = BadReply(f"`batch`: not a list of {len(batch)} replies: {result!r}")
            for n, (_verb, _args, future) in enumerate(batch):
                if error is not None:
                    _settle(future, None, error)
                    continue
                reply = result[n]
                if isinstance(reply, dict) and "ok" in reply:
                    _settle(future, reply["ok"], None)
                elif isinstance(reply, dict) and isinstance(reply.get("error"), dict):
                    _settle(future, None, from_reply(reply["error"]))
                else:
                    _settle(future, None, BadReply(f"`batch`: reply {n} is {reply!r}"))

        def done(result: Any, error: BaseException | None) -> None:
            with contextlib.suppress(RuntimeError):  # the loop is closed: nobody waits
                loop.call_soon_threadsafe(settle_all, result, error)

        requests = [{"verb": verb, "args": args} for verb, args, _future in batch]
        try:
            _link.send(
                self._session,
                self.name,
                "batch",
                {"requests": requests},
                timeout=self.timeout,
                endpoints=self._endpoints,
                done=done,
            )
        except SituateError as e:
            settle_all(None, e)

    async def close(self) -> None:
        """Ends every stream, lets go of this connection's monitors and closes the Zenoh session."""
        for stream in list(self._streams):
            stream.close()
        # The session's token goes first: the manager then removes this connection's monitors.
        await asyncio.to_thread(_link.undeclare, self._session_token)
        await asyncio.to_thread(_link.close_session, self._session)

    async def __aenter__(self) -> Robot:
        return self

    async def __aexit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        await self.close()

    # ----- activation ------------------------------------------------------------

    async def activate(self, *skills: str, with_providers: bool = False) -> list[str]:
        """Switches skills on from the next cycle; returns those whose state changed.

        A skill whose required inputs nobody active would provide is refused
        with :class:`~situate.MissingProviders` (it names the signals and the
        skills that could provide them); ``with_providers=True`` switches those
        providers on too.
        """
        result = await self.request("activate", skills=list(skills), with_providers=with_providers)
        return [str(s) for s in result["changed"]]

    async def deactivate(self, *skills: str) -> list[str]:
        """Switches skills off from the next cycle; returns those whose state changed."""
        result = await self.request("deactivate", skills=list(skills))
        return [str(s) for s in result["changed"]]

    async def set_priority(self, skill: str, priority: int) -> None:
        """Sets a skill's priority (the higher wins a contested resource)."""
        await self.request("set_priority", skill=skill, priority=priority)

    async def set_verbose(self, skill: str, verbose: bool = True) -> None:
        """Makes a skill's prints arrive as :class:`~situate.Print` events (or stop)."""
        await self.request("set_verbose", skill=skill, verbose=verbose)

    async def phase(self, text: str, client: str | None = None) -> None:
        """Says which phase or step of its mission the sequencer is in (``"leaving the lab"``).

        The robot's GUI shows it on its timeline's mission lane, recordings keep it, and it
        arrives as a :class:`~situate.Phase` event. One line of 1 to 200 characters, else
        :class:`~situate.Invalid`. ``client`` names the sequencer (shown with it).
        """
        if client is None:
            await self.request("phase", text=text)
        else:
            await self.request("phase", text=text, client=client)

    # ----- parameters ------------------------------------------------------------

    async def set_param(self, skill: str, param: str, value: Any) -> None:
        """Sets a parameter from the next cycle.

        A wrong type or a value out of range is :class:`~situate.BadParam`.
        """
        await self.request("set_param", skill=skill, param=param, value=value)

    async def get_param(self, skill: str, param: str) -> Any:
        """A parameter's current value."""
        return decode_untyped(await self.request("get_param", skill=skill, param=param))

    # ----- queries ---------------------------------------------------------------

    async def query(self, signal: str) -> Reading:
        """A signal's value at the end of the last cycle.

        ``signal`` is a leaf (``sonar.range``) or a whole record (``odom``).
        """
        return Reading.from_json(await self.request("query", signal=signal))

    async def query_many(self, *signals: str) -> list[Reading]:
        """Several signals' values, all at the end of the same cycle, in one request.

        One :class:`Reading` per name, in the order given (a name given twice is read
        twice), each as :meth:`query` would give it, all taken between the same two cycles.
        1 to `MAX_QUERY_SIGNALS` (256) names; an unknown one refuses the whole request
        (:class:`~situate.UnknownSignal`, naming it), too many or none is
        :class:`~situate.BadRequest`.
        """
        result = await self.request("query_many", signals=list(signals))
        if not (isinstance(result, list) and len(result) == len(signals)):
            raise BadReply(f"`query_many`: not a list of {len(signals)} readings: {result!r}")
        return [Reading.from_json(r) for r in result]

    async def skill(self, name: str) -> SkillInfo:
        """Everything about one skill: state, parameters, ports, timing, recent prints."""
        return SkillInfo.from_json(await self.request("skill", skill=name))

    async def skills(self) -> list[SkillInfo]:
        """Every skill of the robot, devices first, in robot-file order."""
        return [SkillInfo.from_json(s) for s in await self.request("skills")]

    async def winners(self) -> list[Winner]:
        """For each contested signal (resource), who wrote it and who won."""
        return [Winner.from_json(w) for w in await self.request("winners")]

    async def graph(self) -> Graph:
        """The data-flow graph: skills with their signals, signals with writers and readers."""
        return Graph.from_json(await self.request("graph"))

    async def stats(self) -> Stats:
        """Cycle statistics: cycle number, clock, running or not, cycle times, active skills."""
        return Stats.from_json(await self.request("stats"))

    # ----- the cycle -------------------------------------------------------------

    async def run(self) -> None:
        """Starts (or resumes) the periodic cycle."""
        await self.request("run")

    async def stop(self) -> None:
        """Stops the cycle after the current one; requests are still answered."""
        await self.request("stop")

    async def step(self, cycles: int = 1) -> None:
        """Runs exactly ``cycles`` cycles (1 to 1,000,000) on a stopped manager."""
        await self.request("step", cycles=cycles)

    # ----- monitors and events ---------------------------------------------------

    async def monitor(
        self,
        condition: str | None = None,
        mode: str = "once",
        *,
        any: Sequence[str] | None = None,
        pause: bool = False,
        report: Sequence[str] = (),
    ) -> int:
        """Registers a monitor and returns its id; it fires :class:`~situate.MonitorFired` events.

        It watches ``condition``, or ``any`` of several conditions (a list of
        1 to 64, instead of ``condition``): it then holds in a cycle where at
        least one of them does, the mode applies to that, and each event's
        ``held`` lists the indexes of those that held in its cycle — e.g.
        ``monitor(any=["target.seen", "battery.low", "time > 120"])``.
        A bad one of them is :class:`~situate.BadCondition` whose ``index``
        says which. ``mode`` is ``"once"`` (the first cycle the condition holds, then the
        monitor is gone), ``"edge"`` (each cycle it becomes true) or
        ``"level"`` (every cycle it holds). With ``pause``, the manager also
        stops its cycle at the end of the cycle the monitor fires in, until
        :meth:`run`: the sequencer then acts at exactly that cycle, however
        slow the link. A condition that does not parse is
        :class:`~situate.BadCondition`, whose ``pointer`` shows where.
        The event's ``values`` hold every name the condition reads, and those
        of ``report`` too (signal leaves, whole records as their leaves,
        ``skill.param``, ``time``, ``cycle``), as of the cycle it fired in: what
        the sequencer reads next comes with the event, without a query. An
        unknown name in ``report`` is :class:`~situate.UnknownSignal`.
        Subscribe with :meth:`events` *before* registering, or use :meth:`when`.
        """
        args: dict[str, Any] = {**monitor_target(condition, any), "mode": mode}
        args["client"] = self.client_id
        if pause:
            args["pause"] = True
        if report:
            args["report"] = list(report)
        result = await self.request("monitor_add", **args)
        return int(result["monitor"])

    async def cancel_monitor(self, monitor: int) -> None:
        """Removes one of this connection's monitors.

        An unknown id is :class:`~situate.UnknownMonitor`; another session's monitor is
        :class:`~situate.NotOwner` (only the session that added a monitor cancels it).
        A connection's monitors are removed when it closes, or when its process dies.
        """
        await self.request("monitor_cancel", monitor=monitor)

    async def monitors(self) -> list[MonitorInfo]:
        """The registered monitors."""
        return [MonitorInfo.from_json(m) for m in await self.request("monitor_list")]

    def events(self, *kinds: str) -> Stream[Event]:
        """A stream of the robot's events: all of them, or only ``kinds`` (``"print"``, ...).

        Must be called with an event loop running (from a coroutine). The
        subscription starts now, so an event caused by a request sent after
        this call is never missed.
        """
        keys = [f"situate/{self.name}/events/{k}" for k in kinds]
        return Stream(self, keys or [f"situate/{self.name}/events/**"], parse_event)

    async def when(
        self,
        condition: str,
        *,
        timeout: float | None = None,
        pause: bool = False,
        report: Sequence[str] = (),
    ) -> MonitorFired:
        """Waits until ``condition`` holds and returns the :class:`~situate.MonitorFired` event.

        A ``once`` monitor is registered for it; if the wait ends another way
        (``timeout`` seconds pass: ``TimeoutError``; the task is cancelled)
        the monitor is cancelled, so nothing is left behind on the robot.
        With ``pause`` the cycle stops where the condition held (see
        :meth:`monitor`); resume it with :meth:`run`. ``report``: as for :meth:`monitor`.
        """
        _, fired = await self.first(condition, timeout=timeout, pause=pause, report=report)
        return fired

    async def first(
        self,
        *conditions: str,
        timeout: float | None = None,
        pause: bool = False,
        report: Sequence[str] = (),
    ) -> tuple[int, MonitorFired]:
        """Waits until one of ``conditions`` holds: returns its index and the event.

        The way a sequencer waits for "done, or failed, or too late": e.g.
        ``first("target.seen", "time > 120")``: one ``once`` monitor on
        ``any`` of them (up to 64), and the index is the first of those that
        held in the cycle it fired (``event.held`` has them all).
        ``timeout`` is in seconds of wall time (``TimeoutError``); for time
        on the robot's clock use the ``time`` name in a condition. If the wait
        ends another way the monitor is cancelled.
        """
        if not conditions:
            raise ValueError("first() needs at least one condition")
        async with self.events("monitor_fired") as stream:
            if len(conditions) == 1:
                monitor = await self.monitor(conditions[0], "once", pause=pause, report=report)
            else:
                monitor = await self.monitor(any=conditions, pause=pause, report=report)
            try:
                fired = await asyncio.wait_for(_fired_any(stream, [monitor]), timeout)
            except BaseException:
                with contextlib.suppress(SituateError):
                    await self.cancel_monitor(monitor)
                raise
            return (fired.held[0] if fired.held else 0), fired

    # ----- telemetry -------------------------------------------------------------

    async def telemetry(self, signals: Sequence[str], rate_hz: float | None = None) -> None:
        """Chooses the signals telemetry carries and, optionally, its rate (0.01 to 100 Hz)."""
        args: dict[str, Any] = {"signals": list(signals)}
        if rate_hz is not None:
            args["rate_hz"] = rate_hz
        await self.request("telemetry", **args)

    def telemetry_stream(self) -> Stream[Telemetry]:
        """A stream of :class:`~situate.Telemetry` samples (call from a coroutine)."""
        return Stream(self, [f"situate/{self.name}/telemetry"], parse_telemetry)


def _settle(future: asyncio.Future[Any], result: Any, error: BaseException | None) -> None:
    """Completes a request's future (unless its waiter gave up on it)."""
    if future.done():
        return
    if error is not None:
        future.set_exception(error)
    else:
        future.set_result(result)


async def _fired_any(stream: Stream[Event], monitors: list[int]) -> MonitorFired:
    async for event in stream:
        if isinstance(event, MonitorFired) and event.monitor in monitors:
            return event
    raise NotRunning(f"the connection closed before monitor {monitors} fired")


class Connector:
    """What :func:`connect` returns: use it with ``async with``, or ``await`` it.

    ``async with situate.connect(...) as robot`` closes the connection at
    the end of the block; ``robot = await situate.connect(...)`` leaves that
    to you (``await robot.close()``).
    """

    def __init__(
        self,
        robot: str | None,
        endpoints: list[str],
        timeout: float,
        zenoh_config: _link.ZenohSettings | None,
    ) -> None:
        self._robot = robot
        self._endpoints = endpoints
        self._timeout = timeout
        self._zenoh_config = zenoh_config
        self._opened: Robot | None = None

    async def _open(self) -> Robot:
        session = await asyncio.to_thread(_link.open_session, self._endpoints, self._zenoh_config)
        try:
            hello = await asyncio.to_thread(
                _link.hello,
                session,
                self._robot,
                timeout=self._timeout,
                endpoints=self._endpoints,
            )
        except BaseException:
            await asyncio.to_thread(_link.close_session, session)
            raise
        try:
            client_session = await asyncio.to_thread(
                _link.open_client_session, session, str(hello["robot"])
            )
        except BaseException:
            await asyncio.to_thread(_link.close_session, session)
            raise
        return Robot(
            session,
            Hello.from_json(hello),
            endpoints=self._endpoints,
            timeout=self._timeout,
            client_session=client_session,
        )

    def __await__(self) -> Generator[Any, None, Robot]:
        return self._open().__await__()

    async def __aenter__(self) -> Robot:
        self._opened = await self._open()
        return self._opened

    async def __aexit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        if self._opened is not None:
            await self._opened.close()
            self._opened = None


def connect(
    robot: str | None = None,
    *,
    endpoint: _link.Endpoints | None = None,
    timeout: float = 5.0,
    zenoh_config: Mapping[str, Any] | None = None,
) -> Connector:
    """Connects to a robot's skill manager.

    Args:
        robot: The robot's name (its robot file's ``robot:``). ``None``: the
            only robot answering ``situate/*/req/hello``
            (:class:`~situate.AmbiguousRobot` if several do).
        endpoint: The manager's endpoint, e.g. ``"tcp/127.0.0.1:7447"``, or a
            list of them; default ``$SITUATE_CONNECT`` or ``tcp/127.0.0.1:7447``.
        timeout: Seconds to wait for each reply. ``hello``, the first, is asked again while
            nothing answers it, until then: a robot still starting is waited for.
        zenoh_config: Further Zenoh configuration, merged last, for a manager
            that is not on loopback: TLS (``{"transport": {"link": {"tls":
            {...}}}}``) or credentials (``{"transport": {"auth": {"usrpwd":
            {"user": ..., "password": ...}}}}``); see ``docs/robot-files.md``, ``link``.

    Raises:
        NotRunning: nothing accepted the connection, or no manager answered ``hello``.
    """
    return Connector(robot, _link.endpoint_list(endpoint), timeout, zenoh_config)
