"""Values between Python and the protocol's JSON (docs/protocol.md, "Values"), no network."""

from __future__ import annotations

import json
import math

import pytest

from situate.values import (
    Array,
    Record,
    Scalar,
    TypeSyntaxError,
    decode,
    decode_untyped,
    encode,
    parse_type,
)


def test_types_parse_as_written_in_robot_files() -> None:
    assert parse_type("f64") == Scalar("f64")
    assert parse_type("float") == Scalar("f64")
    assert parse_type("f32[24]") == Array("f32", 24)
    assert parse_type("i64[]") == Array("i64", None)
    t = parse_type("{x: f64, y: f64, tag: {id: i64, raw: bytes}}")
    assert isinstance(t, Record)
    assert str(t) == "{x: f64, y: f64, tag: {id: i64, raw: bytes}}"


@pytest.mark.parametrize(
    ("text", "column"), [("quux", 1), ("{x: f64, y: quux}", 13), ("f64[", 5), ("bool[3]", 1)]
)
def test_bad_types_point_at_the_column(text: str, column: int) -> None:
    with pytest.raises(TypeSyntaxError) as e:
        parse_type(text)
    assert e.value.column == column


def test_values_decode_by_their_type() -> None:
    assert decode([0.5, "inf", "-inf"], "f32[3]") == [0.5, math.inf, -math.inf]
    assert math.isnan(decode("nan", "f64"))
    assert decode("nan", "string") == "nan"  # a string stays a string
    assert decode(2, "f64") == 2.0
    assert isinstance(decode(2, "f64"), float)
    assert decode({"$bytes": "AP8H"}, "bytes") == b"\x00\xff\x07"
    assert decode({"x": 1, "raw": {"$bytes": ""}}, "{x: f64, raw: bytes}") == {"x": 1.0, "raw": b""}
    assert decode(None, "f64") is None


def test_untyped_values_decode_bytes_and_non_finite_numbers_anywhere() -> None:
    assert decode_untyped({"a": ["inf", 1], "b": {"$bytes": "AA=="}}) == {
        "a": [math.inf, 1],
        "b": b"\x00",
    }


def test_python_values_encode_to_the_protocol_json() -> None:
    value = {"r": [0.5, math.inf], "raw": b"\x00\xff\x07", "ok": True, "n": 3, "t": (1, 2)}
    j = encode(value)
    assert j == {"r": [0.5, "inf"], "raw": {"$bytes": "AP8H"}, "ok": True, "n": 3, "t": [1, 2]}
    json.dumps(j, allow_nan=False)  # valid strict JSON
    assert decode(j["raw"], "bytes") == value["raw"]
    with pytest.raises(TypeError, match="no JSON form"):
        encode(object())
