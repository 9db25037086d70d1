# SPDX-License-Identifier: Apache-2.0
"""CANopen basic data types (CiA 301) and the number syntax of CiA 306 files."""

from __future__ import annotations

import re
from dataclasses import dataclass

__all__ = [
    "DATA_TYPES",
    "INTEGER_TYPES",
    "REAL_TYPES",
    "DataTypeInfo",
    "NumberError",
    "parse_integer",
    "parse_value",
    "type_bits",
]

Value = int | float | str


@dataclass(frozen=True)
class DataTypeInfo:
    """Name of a basic data type and, for integers, its width in bits and signedness."""

    name: str
    bits: int = 0
    signed: bool = False

    @property
    def min(self) -> int:
        return -(1 << (self.bits - 1)) if self.signed else 0

    @property
    def max(self) -> int:
        return (1 << (self.bits - 1)) - 1 if self.signed else (1 << self.bits) - 1


DATA_TYPES: dict[int, DataTypeInfo] = {
    0x0001: DataTypeInfo("BOOLEAN", 1),
    0x0002: DataTypeInfo("INTEGER8", 8, True),
    0x0003: DataTypeInfo("INTEGER16", 16, True),
    0x0004: DataTypeInfo("INTEGER32", 32, True),
    0x0005: DataTypeInfo("UNSIGNED8", 8),
    0x0006: DataTypeInfo("UNSIGNED16", 16),
    0x0007: DataTypeInfo("UNSIGNED32", 32),
    0x0008: DataTypeInfo("REAL32"),
    0x0009: DataTypeInfo("VISIBLE_STRING"),
    0x000A: DataTypeInfo("OCTET_STRING"),
    0x000B: DataTypeInfo("UNICODE_STRING"),
    0x000C: DataTypeInfo("TIME_OF_DAY"),
    0x000D: DataTypeInfo("TIME_DIFFERENCE"),
    0x000F: DataTypeInfo("DOMAIN"),
    0x0010: DataTypeInfo("INTEGER24", 24, True),
    0x0011: DataTypeInfo("REAL64"),
    0x0012: DataTypeInfo("INTEGER40", 40, True),
    0x0013: DataTypeInfo("INTEGER48", 48, True),
    0x0014: DataTypeInfo("INTEGER56", 56, True),
    0x0015: DataTypeInfo("INTEGER64", 64, True),
    0x0016: DataTypeInfo("UNSIGNED24", 24),
    0x0018: DataTypeInfo("UNSIGNED40", 40),
    0x0019: DataTypeInfo("UNSIGNED48", 48),
    0x001A: DataTypeInfo("UNSIGNED56", 56),
    0x001B: DataTypeInfo("UNSIGNED64", 64),
}
INTEGER_TYPES = frozenset(code for code, info in DATA_TYPES.items() if info.bits)
REAL_TYPES = frozenset({0x0008, 0x0011})
#: Sizes in bits of the types whose DATA_TYPES entry has none (0: no fixed size).
_FIXED_BITS = {0x01: 1, 0x08: 32, 0x11: 64, 0x0C: 48, 0x0D: 48}


def type_bits(code: int | None) -> int | None:
    """The size in bits a value of data type ``code`` takes (in a PDO), None when the type
    has no fixed size (strings, DOMAIN) or is unknown."""
    if code is None or code not in DATA_TYPES:
        return None
    return _FIXED_BITS.get(code, DATA_TYPES[code].bits) or None

_NODEID = re.compile(r"\$nodeid", re.IGNORECASE)
_TERM = re.compile(r"\s*([+-]?)\s*(\$nodeid|0x[0-9a-f]+|[0-9]+)\s*", re.IGNORECASE)


class NumberError(ValueError):
    """A text that is not a CiA 306 number (the message says why)."""


#: The longest number literal read (digits and prefix): 64 bits need at most 22 octal
#: digits; the bound leaves room for leading zeros and keeps every number small enough to
#: print (Python refuses to turn an int of more than 4,300 decimal digits into text).
MAX_LITERAL = 64


def _show(text: str) -> str:
    """``text`` quoted for a message, cut to a readable length."""
    return repr(text) if len(text) <= 40 else repr(text[:40]) + f"... ({len(text)} characters)"


def _literal(text: str) -> int:
    if len(text) > MAX_LITERAL:
        raise NumberError(f"a number of {len(text)} digits (at most {MAX_LITERAL})")
    low = text.lower()
    if low.startswith("0x"):
        return int(low[2:], 16)
    if len(low) > 1 and low.startswith("0"):
        if all(c in "01234567" for c in low):
            return int(low, 8)
        raise NumberError(f"{_show(text)} has a leading 0 (octal) but digits 8 or 9")
    return int(low, 10)


def parse_integer(text: str, node_id: int | None = 0) -> int | None:
    """Evaluate a CiA 306 integer: decimal, ``0x`` hex, leading-``0`` octal, an optional sign,
    and sums with ``$NODEID`` (any case, any side, ``+`` or ``-``).

    Returns None when the text uses ``$NODEID`` and ``node_id`` is None. Raises
    :class:`NumberError` when the text is not such a number.
    """
    pos = 0
    total = 0
    uses_node = False
    stripped = text.strip()
    if not stripped:
        raise NumberError("empty number")
    while pos < len(stripped):
        m = _TERM.match(stripped, pos)
        if m is None or (pos > 0 and not m.group(1)):
            raise NumberError(f"{_show(text)} is not a number")
        sign = -1 if m.group(1) == "-" else 1
        if _NODEID.fullmatch(m.group(2)):
            uses_node = True
            total += sign * (node_id or 0)
        else:
            total += sign * _literal(m.group(2))
        pos = m.end()
    if uses_node and node_id is None:
        return None
    return total


def parse_value(text: str, data_type: int | None, node_id: int | None = 0) -> Value | None:
    """Evaluate a DefaultValue/ParameterValue/limit for ``data_type``.

    Integers (and BOOLEAN) give int, REAL32/REAL64 give float, every other type keeps the
    text. An empty text gives None, and so does ``$NODEID`` when ``node_id`` is None.
    Raises :class:`NumberError` for a numeric type whose text is not a number.
    """
    text = text.strip()
    if text == "":
        return None
    if data_type in INTEGER_TYPES:
        if data_type == 0x0001 and text.lower() in ("true", "false"):
            return int(text.lower() == "true")
        return parse_integer(text, node_id)
    if data_type in REAL_TYPES:
        try:
            return parse_integer(text, node_id)
        except NumberError:
            pass
        if len(text) > MAX_LITERAL:
            raise NumberError(f"a number of {len(text)} characters (at most {MAX_LITERAL})")
        try:
            return float(text)
        except ValueError:
            raise NumberError(f"{_show(text)} is not a number") from None
    return text


def fit_signed(value: int, text: str, data_type: int) -> int:
    """Map a hex bit pattern (``0xFFFF`` for INTEGER16) to the signed value it encodes."""
    info = DATA_TYPES[data_type]
    hex_pattern = "0x" in text.lower() and not text.strip().startswith("-")
    if info.signed and hex_pattern and info.max < value < (1 << info.bits):
        return value - (1 << info.bits)
    return value
