"""Remote skills: an asynchronous cskill whose body is a Python function in another process.

The skill manager runs its cycle in Rust; a *remote skill* lets one of its
computational skills live in a Python process instead — a planner, a
learned policy, anything slow or written in Python. To the cycle it is an
*asynchronous* cskill: the manager hands over the skill's latest inputs and
never waits; the skill computes when it can, and its latest result is taken
at the skill's place in the next cycle (``docs/protocol.md``, "Remote
skills").

Write the body as a plain function, declare its ports and parameters::

    import situate

    @situate.remote_skill(inputs={"x": "f64"}, outputs={"y": "f64"}, params={"gain": 2.0})
    def doubler(x: float, gain: float) -> dict[str, object]:
        \"\"\"Doubles its input (or multiplies it by `gain`).\"\"\"
        return {"y": x * gain}

and serve it, naming the robot and the skill's name in the robot file::

    situate.serve_skill(doubler, robot="toybot", name="doubler")

or from the shell: ``situate serve-skill mymodule:doubler --robot toybot``.

Each call gets the inputs and the parameters as keyword arguments (an
optional input nobody wrote is ``None``) and returns a mapping of output
ports to values — only the outputs it writes this time; ``None`` writes
none. If it raises, the traceback is reported to the manager, which faults
the skill. What the function prints is captured and sent along: the
manager shows it like a local skill's prints (as ``print`` events when the
skill is verbose).

The server always computes on the *latest* inputs: when the function is
slower than the cycle, the inputs of the cycles it missed are dropped, never
queued, exactly like a local asynchronous cskill.
"""

from __future__ import annotations

import contextlib
import inspect
import io
import json
import sys
import threading
import traceback
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import zenoh

from . import _link
from .values import SignalType, decode, decode_untyped, encode, parse_type

__all__ = ["RemoteSkill", "RemoteSkillServer", "ServerStats", "remote_skill", "serve_skill"]


class RemoteSkill:
    """A Python function declared as a skill: its body, input and output ports, parameters.

    Made by :func:`remote_skill`. Calling it calls the function unchanged,
    so the body can be tested as plain Python.
    """

    def __init__(
        self,
        fn: Callable[..., Mapping[str, Any] | None],
        *,
        inputs: Mapping[str, str],
        outputs: Mapping[str, str],
        params: Mapping[str, Any],
        name: str | None = None,
    ) -> None:
        self.fn = fn
        #: The skill's default name (the function's).
        self.name: str = name or fn.__name__
        self.doc: str = inspect.getdoc(fn) or ""
        #: Input port → type (as written in robot files).
        self.inputs: dict[str, str] = dict(inputs)
        #: Output port → type.
        self.outputs: dict[str, str] = dict(outputs)
        #: Parameter → default value.
        self.params: dict[str, Any] = dict(params)
        # A trailing `?` marks an optional input (as in manifests): `None` when nobody wrote it.
        self._input_types: dict[str, SignalType] = {
            k: parse_type(t.strip().removesuffix("?")) for k, t in inputs.items()
        }
        self._output_types: dict[str, SignalType] = {k: parse_type(t) for k, t in outputs.items()}
        self._check_signature()

    def _check_signature(self) -> None:
        clash = set(self.inputs) & set(self.params)
        if clash:
            raise TypeError(f"{self.name}: {sorted(clash)} are both inputs and parameters")
        try:
            signature = inspect.signature(self.fn)
        except (TypeError, ValueError):  # a builtin without a signature: trust it
            return
        accepted = signature.parameters.values()
        if any(p.kind is inspect.Parameter.VAR_KEYWORD for p in accepted):
            return
        names = {
            p.name
            for p in accepted
            if p.kind in (inspect.Parameter.POSITIONAL_OR_KEYWORD, inspect.Parameter.KEYWORD_ONLY)
        }
        missing = [n for n in [*self.inputs, *self.params] if n not in names]
        if missing:
            raise TypeError(
                f"{self.name}: the function takes no argument named {', '.join(missing)}; "
                "it is called with every input and parameter as a keyword argument"
            )

    def __call__(self, **kwargs: Any) -> Mapping[str, Any] | None:
        """Calls the function itself (for testing the body as plain Python)."""
        return self.fn(**kwargs)

    @property
    def manifest(self) -> dict[str, Any]:
        """The skill's manifest, as a robot file's ``remote:`` entry takes it.

        ``{"doc": ..., "inputs": {port: type}, "outputs": {port: type},
        "params": {name: default}}``; write it under the skill's ``remote:`` key.
        """
        manifest: dict[str, Any] = {
            "inputs": dict(self.inputs),
            "outputs": dict(self.outputs),
            "params": {k: encode(v) for k, v in self.params.items()},
        }
        if self.doc:
            manifest = {"doc": self.doc, **manifest}
        return manifest

    def decode_inputs(self, inputs: Mapping[str, Any]) -> dict[str, Any]:
        """The call's input arguments from a message's ``inputs`` (absent ones are ``None``)."""
        return {port: decode(inputs.get(port), ty) for port, ty in self._input_types.items()}

    def decode_params(self, params: Mapping[str, Any]) -> dict[str, Any]:
        """The call's parameter arguments: the message's values over the defaults.

        A parameter is read by its default's type: a ``float`` default makes
        ``"inf"`` a float, a ``str`` default keeps ``"inf"`` a string.
        """
        out: dict[str, Any] = {}
        for name, default in self.params.items():
            if name not in params:
                out[name] = default
            elif isinstance(default, float):
                out[name] = decode(params[name], "f64")
            elif isinstance(default, (bool, int, str)):
                out[name] = params[name]
            elif isinstance(default, bytes):
                out[name] = decode(params[name], "bytes")
            else:
                out[name] = decode_untyped(params[name])
        return out

    def compute(self, message: Mapping[str, Any]) -> dict[str, Any]:
        """Runs the body on one inputs message and returns the outputs message to publish.

        This is the whole protocol step, without any networking: the reply
        is ``{"cycle", "outputs"}``, or ``{"cycle", "error"}`` with the
        traceback when the body raised or returned something unusable, plus
        ``"prints"`` when it printed.
        """
        cycle = message.get("cycle", 0)
        reply: dict[str, Any] = {"cycle": cycle}
        captured = io.StringIO()
        try:
            kwargs = self.decode_inputs(message.get("inputs") or {})
            kwargs.update(self.decode_params(message.get("params") or {}))
            with contextlib.redirect_stdout(captured):
                result = self.fn(**kwargs)
            reply["outputs"] = self._encode_outputs(result)
        except Exception:
            reply.pop("outputs", None)
            reply["error"] = traceback.format_exc()
        prints = captured.getvalue().splitlines()
        if prints:
            reply["prints"] = prints
        return reply

    def _encode_outputs(self, result: Mapping[str, Any] | None) -> dict[str, Any]:
        if result is None:
            return {}
        if not isinstance(result, Mapping):
            raise TypeError(
                f"skill `{self.name}` returned a {type(result).__name__}; "
                f"return a dict of outputs ({', '.join(self.outputs) or 'none declared'})"
            )
        unknown = [k for k in result if k not in self.outputs]
        if unknown:
            raise KeyError(
                f"skill `{self.name}` returned unknown output {', '.join(map(repr, unknown))}; "
                f"its outputs are {', '.join(self.outputs) or 'none'}"
            )
        return {str(k): encode(v) for k, v in result.items()}


def remote_skill(
    *,
    inputs: Mapping[str, str] | None = None,
    outputs: Mapping[str, str] | None = None,
    params: Mapping[str, Any] | None = None,
    name: str | None = None,
) -> Callable[[Callable[..., Mapping[str, Any] | None]], RemoteSkill]:
    """Declares a function as a remote skill.

    Args:
        inputs: Input port → signal type, written as in robot files (``"f64"``,
            ``"f32[24]"``, ``"{x: f64, y: f64}"``).
        outputs: Output port → signal type.
        params: Parameter → default value (the robot file or ``set_param`` may
            change it; the manager sends the current values with each input).
        name: The skill's default name (default: the function's name).

    The function must accept every input and parameter as a keyword argument.
    """

    def wrap(fn: Callable[..., Mapping[str, Any] | None]) -> RemoteSkill:
        return RemoteSkill(
            fn, inputs=inputs or {}, outputs=outputs or {}, params=params or {}, name=name
        )

    return wrap


@dataclass
class ServerStats:
    """Counters of a :class:`RemoteSkillServer`, for monitoring and tests."""

    #: Inputs messages received.
    received: int = 0
    #: Calls of the function (each on the latest inputs at the time).
    computed: int = 0
    #: Inputs messages dropped because newer ones arrived first.
    dropped: int = 0
    #: Calls that raised.
    errors: int = 0
    #: The cycles computed, latest last (the last 100).
    cycles: list[int] = field(default_factory=list)


class RemoteSkillServer:
    """Serves one :class:`RemoteSkill` for one robot: the skill's side of the protocol.

    It subscribes to ``situate/<robot>/remote/<name>/inputs`` and publishes on
    ``.../outputs``. :meth:`serve` blocks until :meth:`stop` (from any
    thread), the ``stop`` event, or Ctrl-C; it may also run in a thread.
    """

    def __init__(
        self,
        skill: RemoteSkill,
        *,
        robot: str,
        name: str | None = None,
        endpoint: _link.Endpoints | None = None,
        zenoh_config: Mapping[str, Any] | None = None,
    ) -> None:
        self.skill = skill
        self.zenoh_config = zenoh_config
        self.robot = robot
        self.name = name or skill.name
        self.endpoints = _link.endpoint_list(endpoint)
        self.stats = ServerStats()
        self._cond = threading.Condition()
        self._latest: dict[str, Any] | None = None
        self._stopping = False
        self._ready = threading.Event()

    @property
    def inputs_key(self) -> str:
        """Where the manager publishes the skill's inputs."""
        return f"situate/{self.robot}/remote/{self.name}/inputs"

    @property
    def outputs_key(self) -> str:
        """Where the skill publishes its results."""
        return f"situate/{self.robot}/remote/{self.name}/outputs"

    @property
    def alive_key(self) -> str:
        """The liveliness token this server holds while it serves."""
        return f"situate/{self.robot}/remote/{self.name}/alive"

    def wait_ready(self, timeout: float | None = None) -> bool:
        """Waits until the server is subscribed (from another thread); ``False`` on timeout."""
        return self._ready.wait(timeout)

    def stop(self) -> None:
        """Makes :meth:`serve` return after the call in progress, if any."""
        with self._cond:
            self._stopping = True
            self._cond.notify_all()

    def _on_inputs(self, sample: zenoh.Sample) -> None:
        try:
            message = json.loads(sample.payload.to_bytes())
        except ValueError:
            return
        if not isinstance(message, dict):
            return
        with self._cond:
            self.stats.received += 1
            if self._latest is not None:
                self.stats.dropped += 1
            self._latest = message
            self._cond.notify_all()

    def _next(self, stop: threading.Event | None) -> dict[str, Any] | None:
        """The latest unhandled inputs, waiting for some; ``None`` when it is time to stop."""
        with self._cond:
            while self._latest is None and not self._stopping:
                if stop is not None and stop.is_set():
                    return None
                # Waits are bounded only to notice an external `stop` event (and Ctrl-C).
                self._cond.wait(0.1 if stop is not None else 0.5)
            if self._stopping:
                return None
            message, self._latest = self._latest, None
            return message

    def serve(self, stop: threading.Event | None = None) -> None:
        """Serves until stopped: :meth:`stop`, ``stop.set()`` or ``KeyboardInterrupt``."""
        session = _link.open_session(self.endpoints, self.zenoh_config)
        try:
            publisher = session.declare_publisher(self.outputs_key)
            subscriber = session.declare_subscriber(self.inputs_key, self._on_inputs)
            # Withdrawn by Zenoh when this session ends, however it ends: the
            # manager then faults the skill instead of reusing a dead answer.
            token = session.liveliness().declare_token(self.alive_key)
            self._ready.set()
            try:
                while (message := self._next(stop)) is not None:
                    reply = self.skill.compute(message)
                    self.stats.computed += 1
                    self.stats.cycles = [*self.stats.cycles[-99:], int(reply.get("cycle", 0))]
                    if "error" in reply:
                        self.stats.errors += 1
                    publisher.put(json.dumps(reply))
            except KeyboardInterrupt:
                pass
            finally:
                with contextlib.suppress(zenoh.ZError):
                    token.undeclare()  # type: ignore[no-untyped-call]
                _link.undeclare(subscriber)
                _link.undeclare(publisher)
        finally:
            _link.close_session(session)


def serve_skill(
    skill: RemoteSkill,
    *,
    robot: str,
    name: str | None = None,
    endpoint: _link.Endpoints | None = None,
    stop: threading.Event | None = None,
    zenoh_config: Mapping[str, Any] | None = None,
) -> None:
    """Serves ``skill`` as robot ``robot``'s remote skill ``name``; blocks until stopped.

    Args:
        skill: A function decorated with :func:`remote_skill`.
        robot: The robot's name (its robot file's ``robot:``).
        name: The skill's name in the robot file (default: ``skill.name``).
        endpoint: The manager's endpoint (default ``$SITUATE_CONNECT`` or
            ``tcp/127.0.0.1:7447``).
        stop: Set it (from another thread) to make the server return.
        zenoh_config: Further Zenoh configuration (TLS, credentials), as for
            :func:`situate.connect`.

    Returns on ``stop`` or Ctrl-C. Raises :class:`~situate.NotRunning` if
    nothing accepts the connection.
    """
    server = RemoteSkillServer(
        skill, robot=robot, name=name, endpoint=endpoint, zenoh_config=zenoh_config
    )
    server.serve(stop)


def load_skill(spec: str, search: Sequence[str] = ()) -> RemoteSkill:
    """The :class:`RemoteSkill` named by ``"module:attr"`` (``"pkg.mod:attr"``), imported.

    ``search`` directories are tried first (the CLI puts the current one
    there, as ``python -m`` does).
    """
    import importlib

    module_name, sep, attr = spec.partition(":")
    if not sep or not module_name or not attr:
        raise ValueError(f"expected MODULE:ATTR (e.g. `mybot.skills:doubler`), got `{spec}`")
    for path in reversed(search):
        if path not in sys.path:
            sys.path.insert(0, path)
    module = importlib.import_module(module_name)
    obj: Any = module
    for part in attr.split("."):
        obj = getattr(obj, part)
    if not isinstance(obj, RemoteSkill):
        raise TypeError(
            f"`{spec}` is a {type(obj).__name__}, not a remote skill: "
            "decorate the function with @situate.remote_skill(...)"
        )
    return obj
