# SPDX-License-Identifier: Apache-2.0
"""Python values <-> CANopen data types (CiA 301 wire form, CiA 309-3 type names).

One place for the conversion that ``canola.Device.od``, the ``canola`` command and the
CiA 309-3 gateway share::

    >>> encode("u16", 0x1234)
    b'4\\x12'
    >>> decode(parse_type("INTEGER8"), b"\\xff")
    -1

Types are named by their CiA 301 code (``0x0007``), their CiA 301 name (``"UNSIGNED32"``)
or their CiA 309-3 name (``"u32"``); :func:`parse_type` turns any of those into the code.

Python forms: BOOLEAN ``bool``; integers ``int``; REAL32/REAL64 ``float``;
VISIBLE_STRING and UNICODE_STRING ``str``; OCTET_STRING and DOMAIN ``bytes``;
TIME_OF_DAY and TIME_DIFFERENCE :class:`TimeOfDay` (milliseconds, days).

Every bad value or name raises :class:`ValueFormatError` (a :class:`canola.Error` and a
:class:`ValueError`) with a message that says what was expected.
"""

from __future__ import annotations

import datetime
import math
import struct
from typing import NamedTuple

from canola.errors import Error
from canola.formats.datatypes import DATA_TYPES

__all__ = [
    "CIA309_NAMES",
    "TIME_EPOCH",
    "TimeOfDay",
    "Value",
    "ValueFormatError",
    "decode",
    "encode",
    "from_text",
    "parse_type",
    "to_text",
    "type_name",
    "untyped_text",
    "visible_text",
]


class ValueFormatError(Error, ValueError):
    """A value that does not fit its CANopen data type, or an unknown type name."""


class TimeOfDay(NamedTuple):
    """TIME_OF_DAY / TIME_DIFFERENCE: milliseconds after midnight and days (since
    1984-01-01 for TIME_OF_DAY)."""

    ms: int
    days: int


Value = bool | int | float | str | bytes | TimeOfDay

#: Day 0 of TIME_OF_DAY (CiA 301).
TIME_EPOCH = datetime.datetime(1984, 1, 1, tzinfo=datetime.UTC)

#: CiA 309-3 data type names -> CiA 301 type code.
CIA309_NAMES: dict[str, int] = {
    "b": 0x01,
    "i8": 0x02, "i16": 0x03, "i24": 0x10, "i32": 0x04, "i40": 0x12, "i48": 0x13,
    "i56": 0x14, "i64": 0x15,
    "u8": 0x05, "u16": 0x06, "u24": 0x16, "u32": 0x07, "u40": 0x18, "u48": 0x19,
    "u56": 0x1A, "u64": 0x1B,
    "r32": 0x08, "r64": 0x11,
    "t": 0x0C, "td": 0x0D,
    "vs": 0x09, "os": 0x0A, "us": 0x0B, "d": 0x0F,
}
_SHORT = {code: name for name, code in CIA309_NAMES.items()}
_BY_NAME = {info.name: code for code, info in DATA_TYPES.items()}
_TIME_TYPES = (0x0C, 0x0D)


def parse_type(name: str | int) -> int:
    """The CiA 301 code of a type given by code, CiA 301 name or CiA 309-3 name
    (case-insensitive). Raises ValueFormatError for an unknown one."""
    if isinstance(name, bool) or not isinstance(name, int | str):
        raise ValueFormatError(f"a data type is a name or a code, not {name!r}")
    if isinstance(name, int):
        if name not in DATA_TYPES:
            raise ValueFormatError(f"unknown data type code 0x{name:04X}")
        return name
    key = name.strip()
    if key.lower() in CIA309_NAMES:
        return CIA309_NAMES[key.lower()]
    if key.upper() in _BY_NAME:
        return _BY_NAME[key.upper()]
    try:
        code = int(key, 0)
    except ValueError:
        pass
    else:
        return parse_type(code)
    raise ValueFormatError(f"unknown data type {name!r} (CiA 309-3 names: "
                           f"{', '.join(CIA309_NAMES)})")


def type_name(code: int, *, short: bool = False) -> str:
    """The CiA 301 name of a type code ("UNSIGNED8"), or its CiA 309-3 name ("u8")."""
    code = parse_type(code)
    return _SHORT[code] if short else DATA_TYPES[code].name


def encode(data_type: str | int, value: Value) -> bytes:
    """The wire bytes (little-endian) of ``value`` as ``data_type``."""
    code = parse_type(data_type)
    info = DATA_TYPES[code]
    if code == 0x01:
        if value not in (0, 1) or isinstance(value, float | str | bytes):
            raise ValueFormatError(f"BOOLEAN takes True/False or 0/1, not {value!r}")
        return b"\x01" if value else b"\x00"
    if info.bits:
        if isinstance(value, bool) or not isinstance(value, int):
            raise ValueFormatError(f"{info.name} takes an int, not {value!r}")
        if not info.min <= value <= info.max:
            raise ValueFormatError(f"{value} is outside {info.name} ({info.min}..{info.max})")
        return value.to_bytes(info.bits // 8, "little", signed=info.signed)
    if code in (0x08, 0x11):
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise ValueFormatError(f"{info.name} takes a float, not {value!r}")
        try:
            return struct.pack("<f" if code == 0x08 else "<d", float(value))
        except OverflowError:
            raise ValueFormatError(f"{value} does not fit REAL32") from None
    if code == 0x09:
        if not isinstance(value, str):
            raise ValueFormatError(f"VISIBLE_STRING takes a str, not {value!r}")
        try:
            return value.encode("utf-8")
        except UnicodeEncodeError:
            raise ValueFormatError(f"{value!r} has characters a VISIBLE_STRING cannot hold") \
                from None
    if code == 0x0B:
        if not isinstance(value, str):
            raise ValueFormatError(f"UNICODE_STRING takes a str, not {value!r}")
        return value.encode("utf-16-le")
    if code in (0x0A, 0x0F):
        if not isinstance(value, bytes | bytearray | memoryview):
            raise ValueFormatError(f"{info.name} takes bytes, not {value!r}")
        return bytes(value)
    assert code in _TIME_TYPES
    if not (isinstance(value, tuple) and len(value) == 2
            and all(isinstance(v, int) and not isinstance(v, bool) for v in value)):
        raise ValueFormatError(f"{info.name} takes TimeOfDay(ms, days), not {value!r}")
    ms, days = value
    if not 0 <= ms < (1 << 28) or not 0 <= days <= 0xFFFF:
        raise ValueFormatError(f"{info.name}: ms must be 0..2**28-1 and days 0..65535")
    return ms.to_bytes(4, "little") + days.to_bytes(2, "little")


def visible_text(data: bytes) -> str:
    """A VISIBLE_STRING's text: UTF-8 where the bytes are UTF-8 (devices put it there,
    beyond CiA 301's ASCII), else one character per byte (Latin-1)."""
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError:
        return data.decode("latin-1")


def decode(data_type: str | int, data: bytes) -> Value:
    """The Python value of wire bytes ``data`` of ``data_type``. Numbers must have their
    exact size (a ValueFormatError says otherwise)."""
    code = parse_type(data_type)
    info = DATA_TYPES[code]
    data = bytes(data)
    size = {0x01: 1, 0x08: 4, 0x11: 8, 0x0C: 6, 0x0D: 6}.get(code, info.bits // 8)
    if size and len(data) != size:
        raise ValueFormatError(f"{info.name} has {size} byte(s), got {len(data)}")
    if code == 0x01:
        return data != b"\x00"
    if info.bits:
        return int.from_bytes(data, "little", signed=info.signed)
    if code == 0x08:
        return float(struct.unpack("<f", data)[0])
    if code == 0x11:
        return float(struct.unpack("<d", data)[0])
    if code == 0x09:
        return visible_text(data.split(b"\x00", 1)[0])
    if code == 0x0B:
        if len(data) % 2:
            data = data[:-1]
        text = data.decode("utf-16-le", "replace")
        return text.split("\x00", 1)[0]
    if code in (0x0A, 0x0F):
        return data
    return TimeOfDay(int.from_bytes(data[:4], "little") & 0x0FFFFFFF,
                     int.from_bytes(data[4:6], "little"))


def from_text(data_type: str | int, text: str) -> Value:
    """Parse a value as a user types it: integers in decimal or 0x-hex, reals, ``true``/
    ``false`` for BOOLEAN, strings as they are, OCTET_STRING/DOMAIN as hex digits
    (spaces allowed), TIME_OF_DAY as ``MS DAYS``."""
    code = parse_type(data_type)
    info = DATA_TYPES[code]
    stripped = text.strip()
    try:
        if code == 0x01:
            low = stripped.lower()
            if low in ("true", "false"):
                return low == "true"
            return bool(encode(code, int(stripped, 0))[0])
        if info.bits:
            return int(stripped, 0)
        if code in (0x08, 0x11):
            number = float(stripped)
            if not math.isfinite(number) and stripped.lower() not in ("inf", "-inf", "nan"):
                raise ValueError(stripped)
            return number
    except ValueError:
        raise ValueFormatError(f"{text!r} is not a {info.name} value") from None
    if code in (0x09, 0x0B):
        return text
    if code in (0x0A, 0x0F):
        try:
            return bytes.fromhex(stripped)
        except ValueError:
            raise ValueFormatError(f"{text!r} is not hex bytes") from None
    parts = stripped.split()
    if len(parts) != 2 or not all(p.isdigit() for p in parts):
        raise ValueFormatError(f"{info.name} is written 'MS DAYS', not {text!r}")
    return TimeOfDay(int(parts[0]), int(parts[1]))


def to_text(data_type: str | int, value: Value) -> str:
    """The inverse of :func:`from_text` (integers in decimal, bytes as hex)."""
    code = parse_type(data_type)
    if code == 0x01:
        return "true" if value else "false"
    if isinstance(value, bytes):
        return value.hex()
    if isinstance(value, TimeOfDay):
        return f"{value.ms} {value.days}"
    if code in (0x08, 0x11) and isinstance(value, float):
        return repr(value)
    return str(value)


def untyped_text(data: bytes) -> str:
    """A value of unknown type as dump and an untyped read print it: up to 4 bytes (what
    an expedited transfer carries, numbers in practice) a little-endian hex number, 5..8
    bytes too unless they read as text, printable (UTF-8) text quoted, other data as hex
    bytes (long data shortened)."""
    text = _as_text(data) if len(data) > 4 else None
    if 1 <= len(data) <= 8 and text is None:
        return f"0x{int.from_bytes(data, 'little'):0{2 * len(data)}X}"
    if text is not None:
        return repr(text if len(text) <= 80 else text[:80] + "...") + f" ({len(data)} bytes)"
    shown = data[:32].hex(" ").upper()
    return f"[{shown}{' ...' if len(data) > 32 else ''}] ({len(data)} bytes)"


def _as_text(data: bytes) -> str | None:
    """``data`` as text when it is printable UTF-8 of 3 characters or more (trailing NULs
    aside), else None."""
    try:
        text = data.rstrip(b"\0").decode("utf-8")
    except UnicodeDecodeError:
        return None
    return text if len(text) >= 3 and text.isprintable() else None
