"""In-process Python skills: ``@situate.skill`` bodies that run inside the manager's cycle.

A skill written in Python is declared by decorating its body — a function, or
a class with a ``step`` method and state — and listed in a robot file's
``python:`` section. The ``situate`` program of this package imports the file
and runs the skill in the cycle like any Rust skill: its inputs, outputs and
parameters are wired by name and type, its priority arbitrates resources, and
the sequencer switches it on and off::

    from typing import Annotated

    import numpy as np

    import situate

    @situate.skill(name="py.runaway", priority=50, outputs={"drive": "{v: f64, w: f64}"})
    def runaway(
        sonar_range: Annotated[np.ndarray, situate.port("f32[24]", signal="sonar.range")],
        safe_distance: float = situate.param(0.5, min=0.1, max=3.0, unit="m"),
    ) -> dict[str, object] | None:
        ...

How the declaration is read from the body's signature:

- an argument **without a default** is an **input**; its signal type comes from
  its annotation (``float`` → ``f64``, ``int`` → ``i64``, ``bool``, ``str`` →
  ``string``, ``bytes``, or ``Annotated[..., "f32[24]"]`` /
  ``Annotated[..., situate.port("f32[24]", signal="sonar.range")]``) or from
  ``inputs={"name": "type" | situate.port(...)}``;
- an argument whose default is ``None`` is an **optional input** (``None`` when
  nobody wrote it this cycle);
- an argument with any other default is a **parameter**: ``situate.param(default,
  min=, max=, unit=, doc=)`` or a plain ``bool``/``int``/``float``/``str``
  default (or ``params={"name": ...}``);
- **outputs** are declared with ``outputs={"name": "type" | situate.port(...)}``;
  the body returns a ``dict`` of the outputs it writes this cycle (``None``:
  none).

Numeric array inputs arrive as read-only numpy arrays sharing the signal's
memory (no copy). Whatever the body prints goes to the skill's own prints
(shown by ``situate skills``/``skill`` queries, and as print events when the
skill is verbose). An exception faults the skill with its traceback; a wrongly
typed output faults it naming the port, the expected and the given type.

A class skill may also define ``activate(self)`` and ``deactivate(self)``: the
manager calls ``activate`` once when the skill is switched on, before its first
run after that, and ``deactivate`` once when it is switched off, after its last
run (see ``docs/python.md``, "Switched on and off"). An exception in
``activate`` faults the skill; one in ``deactivate`` is a warning and one of the
skill's prints, and the skill is off anyway.
"""

from __future__ import annotations

import inspect
import typing
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any, Union, overload

from . import _native

__all__ = [
    "Param",
    "Port",
    "Skill",
    "SkillDeclarationError",
    "param",
    "port",
    "skill",
]


class MissingResource(LookupError):
    """A class skill's ``__init__`` needs a resource the program did not provide."""


class SkillDeclarationError(TypeError):
    """A ``@situate.skill`` declaration that cannot be built; the message names the skill."""


@dataclass(frozen=True)
class Port:
    """A port's signal type and, optionally, its signal (default: the port's name)."""

    type: str
    signal: str | None = None
    optional: bool = False
    doc: str = ""


@dataclass(frozen=True)
class Param:
    """A typed parameter: default, range, unit, documentation (see :func:`param`)."""

    default: Any
    min: float | None = None
    max: float | None = None
    unit: str = ""
    doc: str = ""
    type: str | None = None


def port(type: str, *, signal: str | None = None, optional: bool = False, doc: str = "") -> Port:
    """A port of type ``type`` (as in robot files: ``"f64"``, ``"f32[24]"``, ``"{v: f64}"``).

    ``signal`` is the signal it connects to when the robot file does not remap it
    (default: the port's name).
    """
    return Port(type, signal, optional, doc)


def param(
    default: Any,
    *,
    min: float | None = None,
    max: float | None = None,
    unit: str = "",
    doc: str = "",
    type: str | None = None,
) -> Any:
    """A parameter's declaration, used as the body argument's default.

    The type is the default's (``bool``, ``int`` → ``i64``, ``float`` → ``f64``,
    ``str`` → ``string``) unless ``type`` says otherwise; ``min``/``max`` bound
    numbers (the manager refuses values outside). Typed ``Any`` so that
    ``gain: float = situate.param(2.0)`` type-checks.
    """
    return Param(default, min, max, unit, doc, type)


_SCALARS: dict[Any, str] = {float: "f64", int: "i64", bool: "bool", str: "string", bytes: "bytes"}


def _annotation_type(annotation: Any) -> tuple[str | None, Port | None, bool]:
    """(type string, port, optional) from an annotation; (None, None, False) if it says nothing."""
    optional = False
    origin = typing.get_origin(annotation)
    if origin is typing.Annotated:
        args = typing.get_args(annotation)
        for meta in args[1:]:
            if isinstance(meta, Port):
                return meta.type, meta, meta.optional
            if isinstance(meta, str):
                return meta, None, False
        annotation = args[0]
        origin = typing.get_origin(annotation)
    if origin is Union or type(annotation).__name__ == "UnionType":
        members = [a for a in typing.get_args(annotation) if a is not type(None)]
        if len(members) == 1 and len(typing.get_args(annotation)) == 2:  # Optional[X]
            inner, p, _ = _annotation_type(members[0])
            return inner, p, True
    if annotation in _SCALARS:
        return _SCALARS[annotation], None, optional
    return None, None, optional


def _describe_annotation(annotation: Any) -> str:
    if isinstance(annotation, type):
        return annotation.__name__
    return str(annotation).replace("typing.", "")


def _param_type(name: str, spec: Param, annotation: Any) -> str:
    if spec.type is not None:
        return spec.type
    if annotation is float and isinstance(spec.default, int) and not isinstance(spec.default, bool):
        return "f64"
    for cls in (bool, int, float, str):
        if isinstance(spec.default, cls):
            return _SCALARS[cls]
    raise SkillDeclarationError(
        f"parameter `{name}`: a default of type {type(spec.default).__name__} is not a parameter "
        "type (bool, int, float, str)"
    )


#: A class skill's optional methods the manager calls when it is switched on and off.
_HOOKS = ("activate", "deactivate")


def _check_hook(cls: object, name: str) -> None:
    """Refuses a class's ``activate``/``deactivate`` that cannot be called as ``obj.name()``.

    The manager calls the hook of each instance with no arguments (besides
    ``self``) and does not await it. A class without the method has no hook.
    """
    hook = getattr(cls, name, None)
    if hook is None:
        return
    if not callable(hook):
        raise SkillDeclarationError(
            f"`{name}` must be a method taking only self, not a {type(hook).__name__}"
        )
    if inspect.iscoroutinefunction(hook):
        raise SkillDeclarationError(
            f"`{name}` is an async def: the manager calls it without awaiting it; "
            "make it a plain method"
        )
    try:
        arguments = list(inspect.signature(hook).parameters.values())
    except (TypeError, ValueError):  # no signature to read (a builtin): the call will tell
        return
    if inspect.isfunction(inspect.getattr_static(cls, name)):
        # A plain method: its first argument receives the instance.
        if arguments and arguments[0].kind in (
            inspect.Parameter.POSITIONAL_ONLY,
            inspect.Parameter.POSITIONAL_OR_KEYWORD,
        ):
            arguments = arguments[1:]
        elif not any(a.kind is inspect.Parameter.VAR_POSITIONAL for a in arguments):
            raise SkillDeclarationError(
                f"`{name}` takes no `self`: write `def {name}(self) -> None:`"
            )
    required = [
        a.name
        for a in arguments
        if a.default is inspect.Parameter.empty
        and a.kind not in (inspect.Parameter.VAR_POSITIONAL, inspect.Parameter.VAR_KEYWORD)
    ]
    if required:
        needs = ", ".join(f"`{n}`" for n in required)
        raise SkillDeclarationError(
            f"`{name}` is called with no arguments besides self, but it needs {needs}"
        )


def _hints(body: Callable[..., Any], arguments: list[inspect.Parameter]) -> dict[str, Any]:
    """The arguments' annotations, evaluated (string annotations included).

    When the whole set does not evaluate (``X | None`` on Python 3.9, say, or a
    return annotation naming something undefined), each argument's is tried on
    its own; one that still fails is left out (and reported if it was needed).
    """
    try:
        return typing.get_type_hints(body, include_extras=True)
    except Exception:
        pass
    namespace = dict(getattr(body, "__globals__", {}))
    hints: dict[str, Any] = {}
    for a in arguments:
        annotation = a.annotation
        if isinstance(annotation, str):
            try:
                annotation = eval(annotation, namespace)  # what get_type_hints does
            except Exception:
                continue
        if annotation is not inspect.Parameter.empty:
            hints[a.name] = annotation
    return hints


class Skill:
    """A ``@situate.skill`` type: its declaration and its body.

    Calling it calls the decorated function (or makes an instance of the
    decorated class), so the body can be tested as plain Python.
    """

    def __init__(
        self,
        target: Callable[..., Any],
        *,
        name: str | None = None,
        kind: str = "sync",
        priority: int = 0,
        inputs: Mapping[str, str | Port] | None = None,
        outputs: Mapping[str, str | Port] | None = None,
        params: Mapping[str, Any] | None = None,
        doc: str | None = None,
    ) -> None:
        self.target = target
        #: The type name robot files use.
        self.name: str = name or str(getattr(target, "__name__", "skill"))
        self.kind = kind
        self.priority = priority
        self.doc: str = doc if doc is not None else (inspect.getdoc(target) or "")
        #: Input port → type; output port → type; parameter → default.
        self.inputs: dict[str, str] = {}
        self.outputs: dict[str, str] = {}
        self.params: dict[str, Any] = {}
        self._is_class = isinstance(target, type)
        #: A class skill's resources: its ``__init__``'s arguments, each ``(name, required)``.
        self.resources: tuple[tuple[str, bool], ...] = ()
        try:
            self._declaration = self._declare(inputs or {}, outputs or {}, params or {})
        except SkillDeclarationError as e:
            raise SkillDeclarationError(f"skill `{self.name}`: {e}") from None
        except ValueError as e:  # the native declaration's checks (types, ranges)
            raise SkillDeclarationError(str(e)) from None

    def _body_signature(self) -> tuple[Callable[..., Any], list[inspect.Parameter]]:
        if self._is_class:
            step = getattr(self.target, "step", None)
            if not callable(step):
                raise SkillDeclarationError("a skill class needs a `step` method (its body)")
            try:
                init = inspect.signature(self.target)
            except (TypeError, ValueError):
                init = None
            if init is not None:
                # Each named argument is a resource the program provides (by that name).
                resources: list[tuple[str, bool]] = []
                for p in init.parameters.values():
                    if p.kind == p.POSITIONAL_ONLY:
                        raise SkillDeclarationError(
                            f"__init__'s argument `{p.name}` is positional-only: a class skill"
                            " is made with its resources by name"
                        )
                    if p.kind in (p.VAR_POSITIONAL, p.VAR_KEYWORD):
                        continue
                    resources.append((p.name, p.default is inspect.Parameter.empty))
                self.resources = tuple(resources)
            for hook in _HOOKS:
                _check_hook(self.target, hook)
            sig = inspect.signature(step)
            return step, list(sig.parameters.values())[1:]  # without self
        if not callable(self.target):
            raise SkillDeclarationError("@situate.skill decorates a function or a class")
        return self.target, list(inspect.signature(self.target).parameters.values())

    def _declare(
        self,
        inputs: Mapping[str, str | Port],
        outputs: Mapping[str, str | Port],
        params: Mapping[str, Any],
    ) -> Any:
        if self.kind not in ("sync", "async"):
            raise SkillDeclarationError(f'kind must be "sync" or "async", got {self.kind!r}')
        body, arguments = self._body_signature()
        hints = _hints(body, arguments)
        ins: list[tuple[str, str, str, bool, str]] = []
        prms: list[tuple[str, str, Any, float | None, float | None, str, str]] = []
        call: list[tuple[str, str]] = []
        positional = True
        var_keyword = False
        for a in arguments:
            if a.kind is a.VAR_POSITIONAL:
                raise SkillDeclarationError(f"*{a.name}: the body is called with named arguments")
            if a.kind is a.VAR_KEYWORD:
                var_keyword = True
                continue
            if a.kind is a.KEYWORD_ONLY:
                positional = False
            annotation = hints.get(a.name, inspect.Parameter.empty)
            if (
                a.name in params
                or isinstance(a.default, Param)
                or (
                    a.name not in inputs
                    and a.default is not inspect.Parameter.empty
                    and a.default is not None
                )
            ):
                given = params.get(a.name, a.default)
                spec = given if isinstance(given, Param) else Param(given)
                prms.append(self._param(a.name, spec, annotation))
                call.append(("param", a.name))
            else:
                optional_default = a.default is None
                ins.append(self._input(a.name, inputs.get(a.name), annotation, optional_default))
                call.append(("in", a.name))
        declared = {n for _, n in call}
        for extra in [*inputs, *params]:
            if extra in declared:
                continue
            if not var_keyword:
                raise SkillDeclarationError(
                    f"the body takes no argument named `{extra}`; it is called with every "
                    "input and parameter"
                )
            positional = False
            if extra in params:
                given = params[extra]
                spec = given if isinstance(given, Param) else Param(given)
                prms.append(self._param(extra, spec, inspect.Parameter.empty))
                call.append(("param", extra))
            else:
                ins.append(self._input(extra, inputs[extra], inspect.Parameter.empty, False))
                call.append(("in", extra))
        outs: list[tuple[str, str, str, str]] = []
        for out_name, spec_out in outputs.items():
            p = spec_out if isinstance(spec_out, Port) else Port(spec_out)
            if not isinstance(p.type, str):
                raise SkillDeclarationError(f"output `{out_name}`: the type must be a string")
            outs.append((out_name, p.type, p.signal or "", p.doc))
            self.outputs[out_name] = p.type
        for n, ty, *_ in ins:
            self.inputs[n] = ty
        for n, _ty, default, *_ in prms:
            self.params[n] = default
        return _native.declare(
            self.name, self.kind, self.priority, self.doc, ins, outs, prms, call, positional
        )

    def _input(
        self, name: str, given: str | Port | None, annotation: Any, optional_default: bool
    ) -> tuple[str, str, str, bool, str]:
        p: Port | None = given if isinstance(given, Port) else None
        ty: str | None = given if isinstance(given, str) else (p.type if p else None)
        optional = optional_default or (p.optional if p else False)
        if annotation is not inspect.Parameter.empty:
            a_ty, a_port, a_opt = _annotation_type(annotation)
            optional = optional or a_opt
            if ty is None:
                ty, p = a_ty, p or a_port
        if ty is None:
            if annotation is inspect.Parameter.empty:
                raise SkillDeclarationError(
                    f"input `{name}` has no type: annotate it (`{name}: float`) or declare "
                    f'inputs={{"{name}": "f64"}}'
                )
            raise SkillDeclarationError(
                f"input `{name}`: cannot tell its signal type from the annotation "
                f"`{_describe_annotation(annotation)}`; write "
                f'Annotated[{_describe_annotation(annotation)}, "f32[24]"] (the signal type) or '
                f'inputs={{"{name}": "..."}}'
            )
        if not isinstance(ty, str):
            raise SkillDeclarationError(f"input `{name}`: the type must be a string")
        return (name, ty, (p.signal if p else None) or "", optional, p.doc if p else "")

    def _param(
        self, name: str, spec: Param, annotation: Any
    ) -> tuple[str, str, Any, float | None, float | None, str, str]:
        ty = _param_type(name, spec, annotation)
        default = spec.default
        if ty in ("f64", "float") and isinstance(default, int) and not isinstance(default, bool):
            default = float(default)
        return (name, ty, default, spec.min, spec.max, spec.unit, spec.doc)

    def _make_body(
        self, resources: Mapping[str, Any] | None = None
    ) -> tuple[Callable[..., Any], Callable[[], Any] | None, Callable[[], Any] | None]:
        """One new instance's body and hooks: ``(step, activate, deactivate)``.

        A class: a new object's ``step``, ``activate`` and ``deactivate`` (``None``
        for a hook the class does not define), the object made with the
        ``resources`` its ``__init__`` names (:class:`MissingResource` when one
        without a default is not there). A function: the function, without hooks.
        """
        if self._is_class:
            given = resources or {}
            kwargs: dict[str, Any] = {}
            for name, required in self.resources:
                if name in given:
                    kwargs[name] = given[name]
                elif required:
                    provided = (
                        "it provides " + ", ".join(f"`{n}`" for n in sorted(given))
                        if given
                        else "it provides no resources"
                    )
                    raise MissingResource(
                        f"`{self.name}` needs the resource `{name}` (an argument of its"
                        f" __init__), and the program provides none of that name ({provided})"
                    )
            instance = self.target(**kwargs)
            step: Callable[..., Any] = instance.step
            activate: Callable[[], Any] | None = getattr(instance, "activate", None)
            deactivate: Callable[[], Any] | None = getattr(instance, "deactivate", None)
            return step, activate, deactivate
        return self.target, None, None

    def describe(self) -> str:
        """The declaration in words (ports, parameters with their ranges)."""
        text: str = self._declaration.describe()
        return text

    def __call__(self, *args: Any, **kwargs: Any) -> Any:
        """Calls the function itself (or makes an instance of the class), for testing."""
        return self.target(*args, **kwargs)

    def __repr__(self) -> str:
        return f"<situate.Skill {self.name!r} ({self.kind}, priority {self.priority})>"


@overload
def skill(target: Callable[..., Any], /) -> Skill: ...


@overload
def skill(
    *,
    name: str | None = None,
    kind: str = "sync",
    priority: int = 0,
    inputs: Mapping[str, str | Port] | None = None,
    outputs: Mapping[str, str | Port] | None = None,
    params: Mapping[str, Any] | None = None,
    doc: str | None = None,
) -> Callable[[Callable[..., Any]], Skill]: ...


def skill(
    target: Callable[..., Any] | None = None,
    /,
    *,
    name: str | None = None,
    kind: str = "sync",
    priority: int = 0,
    inputs: Mapping[str, str | Port] | None = None,
    outputs: Mapping[str, str | Port] | None = None,
    params: Mapping[str, Any] | None = None,
    doc: str | None = None,
) -> Skill | Callable[[Callable[..., Any]], Skill]:
    """Declares a function (or a class with a ``step`` method) as an in-process skill.

    Args:
        target: The body (when used as a bare ``@situate.skill``).
        name: The type name robot files use (default: the function's or class's name).
        kind: ``"sync"`` (runs in the cycle when its inputs are fresh) or ``"async"``
            (runs on its own thread on the latest inputs; the cycle never waits).
        priority: Priority for contested outputs (higher wins).
        inputs: Input port → type or :func:`port`, for arguments without a usable annotation.
        outputs: Output port → type or :func:`port`.
        params: Parameter → default or :func:`param`, instead of argument defaults.
        doc: Documentation (default: the docstring).

    Raises:
        SkillDeclarationError: The declaration cannot be built (the message names
            the skill and the port or parameter).
    """

    def wrap(t: Callable[..., Any]) -> Skill:
        return Skill(
            t,
            name=name,
            kind=kind,
            priority=priority,
            inputs=inputs,
            outputs=outputs,
            params=params,
            doc=doc,
        )

    if target is not None:
        return wrap(target)
    return wrap
