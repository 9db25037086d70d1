# SPDX-License-Identifier: Apache-2.0
"""canola.values: Python values <-> CANopen wire bytes, by CiA 301 / CiA 309-3 type names."""

from __future__ import annotations

import math

import pytest

from canola import Error
from canola.formats.values import (
    CIA309_NAMES,
    TimeOfDay,
    ValueFormatError,
    decode,
    encode,
    from_text,
    parse_type,
    to_text,
    type_name,
)


@pytest.mark.parametrize(("name", "value", "wire"), [
    ("b", True, b"\x01"), ("b", False, b"\x00"),
    ("i8", -1, b"\xff"), ("i16", -2, b"\xfe\xff"), ("i24", -8388608, b"\x00\x00\x80"),
    ("i32", 0x12345678, b"\x78\x56\x34\x12"), ("i40", -1, b"\xff" * 5),
    ("i48", 1, b"\x01" + b"\0" * 5), ("i56", -(2**55), b"\0" * 6 + b"\x80"),
    ("i64", -(2**63), b"\0" * 7 + b"\x80"),
    ("u8", 255, b"\xff"), ("u16", 0xBEEF, b"\xef\xbe"), ("u24", 0xFFFFFF, b"\xff" * 3),
    ("u32", 7, b"\x07\0\0\0"), ("u40", 2**40 - 1, b"\xff" * 5), ("u48", 0, b"\0" * 6),
    ("u56", 2**56 - 1, b"\xff" * 7), ("u64", 2**64 - 1, b"\xff" * 8),
    ("r32", 1.5, b"\x00\x00\xc0\x3f"), ("r64", -2.0, b"\0" * 7 + b"\xc0"),
    ("vs", "abc", b"abc"), ("os", b"\x00\x01", b"\x00\x01"), ("us", "ż", b"\x7c\x01"),
    ("d", b"\xde\xad", b"\xde\xad"), ("t", TimeOfDay(1000, 2), b"\xe8\x03\0\0\x02\0"),
    ("td", TimeOfDay(0, 1), b"\0\0\0\0\x01\0"),
])
def test_round_trip(name: str, value: object, wire: bytes) -> None:
    assert encode(name, value) == wire  # type: ignore[arg-type]
    assert decode(name, wire) == value
    assert from_text(name, to_text(name, decode(name, wire))) == value


def test_every_cia309_name_and_code() -> None:
    assert len(CIA309_NAMES) == 25
    for name, code in CIA309_NAMES.items():
        assert parse_type(name) == parse_type(name.upper()) == code
        assert parse_type(type_name(code)) == code
        assert type_name(code, short=True) == name
    assert parse_type("UNSIGNED32") == parse_type("0x7") == parse_type(7) == 7


@pytest.mark.parametrize(("name", "value", "message"), [
    ("u8", 256, "outside UNSIGNED8"), ("i8", -129, "outside INTEGER8"),
    ("u16", 1.0, "takes an int"), ("u16", True, "takes an int"), ("b", 2, "BOOLEAN"),
    ("r32", 1e39, "does not fit REAL32"), ("vs", b"x", "takes a str"),
    ("vs", "\ud800", "cannot hold"), ("os", "x", "takes bytes"), ("t", (1, 2, 3), "TimeOfDay"),
    ("t", TimeOfDay(2**28, 0), "ms must be"),
])
def test_encode_errors(name: str, value: object, message: str) -> None:
    with pytest.raises(ValueFormatError, match=message) as exc:
        encode(name, value)  # type: ignore[arg-type]
    assert isinstance(exc.value, Error) and isinstance(exc.value, ValueError)


def test_decode_and_parse_errors() -> None:
    with pytest.raises(ValueFormatError, match="has 2 byte"):
        decode("u16", b"\x01")
    with pytest.raises(ValueFormatError, match="unknown data type 'u7'"):
        parse_type("u7")
    with pytest.raises(ValueFormatError, match="unknown data type code 0x0020"):
        parse_type(0x20)
    with pytest.raises(ValueFormatError, match="not a UNSIGNED8 value"):
        from_text("u8", "ten")
    with pytest.raises(ValueFormatError, match="not hex"):
        from_text("os", "zz")
    with pytest.raises(ValueFormatError, match="MS DAYS"):
        from_text("t", "12:00")


def test_text_forms() -> None:
    assert from_text("u16", "0x10") == 16
    assert from_text("b", "true") is True and from_text("b", "0") is False
    assert from_text("os", "01 ff") == b"\x01\xff"
    assert math.isnan(float(from_text("r64", "nan")))  # type: ignore[arg-type]
    assert decode("vs", b"ab\0cd") == "ab"  # a terminator ends a visible string


def test_visible_string_utf8() -> None:
    assert encode("vs", "2 €") == b"2 \xe2\x82\xac"
    assert decode("vs", b"2 \xe2\x82\xac\x00\x00") == "2 €"
    assert decode("vs", b"caf\xe9") == "café"  # not UTF-8: a character per byte
    assert decode("vs", encode("vs", "Größe")) == "Größe"
