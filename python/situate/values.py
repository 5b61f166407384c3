"""Signal values between Python and the link's JSON (``docs/protocol.md``, "Values").

A value's JSON form follows its signal type. Most of it maps to Python
directly (``bool``, ``int``, ``str``, lists, and records as ``dict``); two
things need care, and this module does them:

* ``bytes`` travel as ``{"$bytes": "<base64>"}``;
* non-finite floats travel as the strings ``"inf"``, ``"-inf"`` and ``"nan"``.

Where the type is known (a :class:`~situate.Reading` carries it, a remote
skill declares its ports) :func:`decode` reads a value exactly by its type,
so a ``string`` signal holding the text ``"nan"`` stays a string. Where the
protocol sends a value without its type (events and telemetry),
:func:`decode_untyped` decodes ``$bytes`` objects and reads the three
non-finite spellings as floats.

Types are written as in robot files::

    >>> parse_type("{x: f64, y: f64}")
    Record(fields=(('x', Scalar(name='f64')), ('y', Scalar(name='f64'))))
    >>> decode([0.5, "inf"], parse_type("f32[2]"))
    [0.5, inf]
    >>> encode({"raw": bytes([0, 255]), "x": float("nan")})
    {'raw': {'$bytes': 'AP8='}, 'x': 'nan'}
"""

from __future__ import annotations

import base64
import functools
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any, Union

__all__ = [
    "Array",
    "Record",
    "Scalar",
    "SignalType",
    "TypeSyntaxError",
    "decode",
    "decode_untyped",
    "encode",
    "parse_type",
]

_NON_FINITE = {"inf": math.inf, "-inf": -math.inf, "nan": math.nan}
_SCALARS = {
    "bool": "bool",
    "i64": "i64",
    "int": "i64",
    "f64": "f64",
    "float": "f64",
    "string": "string",
    "str": "string",
    "bytes": "bytes",
}
_ELEMENTS = {"f32": "f32", "f64": "f64", "float": "f64", "i64": "i64", "int": "i64"}


@dataclass(frozen=True)
class Scalar:
    """``bool``, ``i64``, ``f64``, ``string`` or ``bytes``."""

    name: str

    def __str__(self) -> str:
        return self.name


@dataclass(frozen=True)
class Array:
    """``f32[]``, ``f64[24]``, ``i64[]``: numbers, of a fixed length or not."""

    elem: str
    length: int | None = None

    def __str__(self) -> str:
        return f"{self.elem}[{'' if self.length is None else self.length}]"


@dataclass(frozen=True)
class Record:
    """``{x: f64, y: f64}``: named fields, in order."""

    fields: tuple[tuple[str, SignalType], ...]

    def __str__(self) -> str:
        return "{" + ", ".join(f"{n}: {t}" for n, t in self.fields) + "}"


SignalType = Union[Scalar, Array, Record]
"""A parsed signal type."""


class TypeSyntaxError(ValueError):
    """A type string that does not parse; ``column`` is 1-based."""

    def __init__(self, text: str, column: int, message: str) -> None:
        super().__init__(f"type {text!r}, column {column}: {message}")
        self.column = column


class _TypeParser:
    def __init__(self, text: str) -> None:
        self.text = text
        self.pos = 0

    def fail(self, message: str) -> TypeSyntaxError:
        return TypeSyntaxError(self.text, self.pos + 1, message)

    def skip_ws(self) -> None:
        while self.pos < len(self.text) and self.text[self.pos].isspace():
            self.pos += 1

    def eat(self, char: str) -> bool:
        self.skip_ws()
        if self.text.startswith(char, self.pos):
            self.pos += 1
            return True
        return False

    def ident(self) -> str:
        self.skip_ws()
        start = self.pos
        while self.pos < len(self.text) and (
            self.text[self.pos].isalnum() or self.text[self.pos] == "_"
        ):
            self.pos += 1
        return self.text[start : self.pos]

    def parse(self) -> SignalType:
        if self.eat("{"):
            fields: list[tuple[str, SignalType]] = []
            if self.eat("}"):
                return Record(())
            while True:
                name = self.ident()
                if not name:
                    raise self.fail("expected a field name")
                if not self.eat(":"):
                    raise self.fail("expected `:` after the field name")
                fields.append((name, self.parse()))
                if self.eat(","):
                    if self.eat("}"):
                        break
                    continue
                if self.eat("}"):
                    break
                raise self.fail("expected `,` or `}`")
            return Record(tuple(fields))
        start = self.pos
        name = self.ident()
        if self.eat("["):
            if name not in _ELEMENTS:
                self.pos = start
                raise self.fail(f"arrays hold f32, f64 or i64, not `{name}`")
            self.skip_ws()
            digits_start = self.pos
            while self.pos < len(self.text) and self.text[self.pos].isdigit():
                self.pos += 1
            digits = self.text[digits_start : self.pos]
            if not self.eat("]"):
                raise self.fail("expected `]`")
            return Array(_ELEMENTS[name], int(digits) if digits else None)
        if name not in _SCALARS:
            self.pos = start
            raise self.fail(f"unknown type `{name}`")
        return Scalar(_SCALARS[name])


def parse_type(text: str) -> SignalType:
    """Parses a type written as in robot files (``f64``, ``f32[24]``, ``{x: f64}``)."""
    parser = _TypeParser(text)
    parsed = parser.parse()
    parser.skip_ws()
    if parser.pos != len(text):
        raise parser.fail("unexpected text after the type")
    return parsed


@functools.lru_cache(maxsize=256)
def _parse_type_cached(text: str) -> SignalType:
    # Types are immutable and a robot has few of them: every reading of a
    # signal parses the same text.
    return parse_type(text)


def _float(j: Any) -> Any:
    if isinstance(j, str) and j in _NON_FINITE:
        return _NON_FINITE[j]
    if isinstance(j, (int, float)) and not isinstance(j, bool):
        return float(j)
    return j


def decode(j: Any, ty: SignalType | str) -> Any:
    """A value's Python form, read by its type; ``None`` (never written) stays ``None``.

    Values that do not match the type are handed back as they came rather
    than refused: a client should show what the manager sent.
    """
    if isinstance(ty, str):
        ty = _parse_type_cached(ty)
    if j is None:
        return None
    if isinstance(ty, Scalar):
        if ty.name == "f64":
            return _float(j)
        if ty.name == "bytes":
            return _bytes(j)
        return j
    if isinstance(ty, Array):
        if not isinstance(j, list):
            return j
        return [_float(x) for x in j] if ty.elem in ("f32", "f64") else list(j)
    if not isinstance(j, dict):
        return j
    types = dict(ty.fields)
    return {k: decode(v, types[k]) if k in types else decode_untyped(v) for k, v in j.items()}


def _bytes(j: Any) -> Any:
    if isinstance(j, dict) and set(j) == {"$bytes"} and isinstance(j["$bytes"], str):
        return base64.b64decode(j["$bytes"])
    return j


def decode_untyped(j: Any) -> Any:
    """A value's Python form when the protocol did not send its type (events, telemetry).

    ``{"$bytes": ...}`` becomes ``bytes`` and ``"inf"``, ``"-inf"``, ``"nan"``
    become floats, wherever they are; everything else is kept as it is.
    """
    if isinstance(j, str):
        return _NON_FINITE.get(j, j)
    if isinstance(j, list):
        return [decode_untyped(x) for x in j]
    if isinstance(j, dict):
        as_bytes = _bytes(j)
        if isinstance(as_bytes, bytes):
            return as_bytes
        return {k: decode_untyped(v) for k, v in j.items()}
    return j


def encode(value: Any) -> Any:
    """A Python value's JSON form (before ``json.dumps``).

    ``bytes`` become ``{"$bytes": ...}``, non-finite floats their strings,
    tuples and other sequences lists, mappings objects. Anything with a
    ``tolist()`` method (NumPy arrays and scalars) is converted through it.
    """
    if value is None or isinstance(value, (bool, int, str)):
        return value
    if isinstance(value, float):
        if math.isnan(value):
            return "nan"
        if math.isinf(value):
            return "inf" if value > 0 else "-inf"
        return value
    if isinstance(value, (bytes, bytearray, memoryview)):
        return {"$bytes": base64.b64encode(bytes(value)).decode("ascii")}
    if isinstance(value, Mapping):
        return {str(k): encode(v) for k, v in value.items()}
    tolist = getattr(value, "tolist", None)
    if callable(tolist):
        return encode(tolist())
    if isinstance(value, Sequence):
        return [encode(v) for v in value]
    raise TypeError(f"a {type(value).__name__} has no JSON form in the situate protocol")
