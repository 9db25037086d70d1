# SPDX-License-Identifier: Apache-2.0
"""Values in CiA 309-3 text form: one parser and one formatter per gateway data type.

The type names are those of CiA 309-3 (``b``, ``i8``..``i64``, ``u8``..``u64``, ``r32``,
``r64``, ``t``, ``td``, ``vs``, ``os``, ``us``, ``d``) plus the two that CANopenNode's
``cocomm`` users know: ``x8``..``x64`` (unsigned, shown in hexadecimal) and ``hex`` (raw
bytes as hexadecimal pairs).

- Integers are read as C writes them: decimal, ``0x`` hexadecimal or ``0`` octal, with a
  sign for the signed types; they are shown in decimal (``x*``: ``0x`` and hex digits).
- ``vs`` is shown between double quotes; a double quote inside is doubled, CR, LF, the
  backslash and the other control characters are escaped (``\\r``, ``\\n``, ``\\\\``,
  ``\\xHH``), so that no value can break the line protocol; a TAB stays a TAB. A single
  word may be written without quotes; ``\\t`` and ``\\"`` are read too.
- ``os``, ``us`` (the UTF-16LE bytes) and ``d`` are base64 (RFC 2045 alphabet, one line).
- ``t`` and ``td`` (TIME_OF_DAY / TIME_DIFFERENCE) are ``<ms> <days>``: milliseconds
  after midnight and days since 1984-01-01, in the order of the wire.

:func:`parse_value` raises :class:`ValueError` for text that is not a value of the type;
:func:`format_value` raises :class:`ValueError` when the byte count does not fit the type.
"""

from __future__ import annotations

import base64
import binascii
import math
import re
import struct
from dataclasses import dataclass

__all__ = ["TYPES", "TypeSpec", "format_value", "parse_int", "parse_value"]


@dataclass(frozen=True)
class TypeSpec:
    """One gateway data type: CiA 301 type code, size in bytes (0: any), kind."""

    name: str
    code: int
    size: int
    kind: str  # "bool", "int", "uint", "hex", "real", "time", "vs", "b64", "raw"


def _ints() -> dict[str, TypeSpec]:
    codes_signed = {8: 0x02, 16: 0x03, 24: 0x10, 32: 0x04, 40: 0x12, 48: 0x13, 56: 0x14,
                    64: 0x15}
    codes_unsigned = {8: 0x05, 16: 0x06, 24: 0x16, 32: 0x07, 40: 0x18, 48: 0x19, 56: 0x1A,
                      64: 0x1B}
    out: dict[str, TypeSpec] = {}
    for bits, code in codes_signed.items():
        out[f"i{bits}"] = TypeSpec(f"i{bits}", code, bits // 8, "int")
    for bits, code in codes_unsigned.items():
        out[f"u{bits}"] = TypeSpec(f"u{bits}", code, bits // 8, "uint")
        out[f"x{bits}"] = TypeSpec(f"x{bits}", code, bits // 8, "hex")
    return out


#: Every type name the gateway knows.
TYPES: dict[str, TypeSpec] = {
    "b": TypeSpec("b", 0x01, 1, "bool"),
    **_ints(),
    "r32": TypeSpec("r32", 0x08, 4, "real"),
    "r64": TypeSpec("r64", 0x11, 8, "real"),
    "t": TypeSpec("t", 0x0C, 6, "time"),
    "td": TypeSpec("td", 0x0D, 6, "time"),
    "vs": TypeSpec("vs", 0x09, 0, "vs"),
    "os": TypeSpec("os", 0x0A, 0, "b64"),
    "us": TypeSpec("us", 0x0B, 0, "b64"),
    "d": TypeSpec("d", 0x0F, 0, "b64"),
    "hex": TypeSpec("hex", 0x0F, 0, "raw"),
}

_HEX_RE = re.compile(r"[0-9a-fA-F]*+")
_INT_RE = re.compile(r"([+-]?)(0[xX][0-9a-fA-F]+|0[0-7]*|[1-9][0-9]*)\Z")


def parse_int(text: str) -> int:
    """An integer in C syntax (decimal, 0x hexadecimal, 0 octal), optionally signed."""
    m = _INT_RE.match(text)
    if m is None:
        raise ValueError(f"not an integer: {text[:40]!r}")
    sign, digits = m.groups()
    if digits[:2] in ("0x", "0X"):
        value = int(digits[2:], 16)
    elif digits.startswith("0"):
        value = int(digits, 8)
    else:
        value = int(digits, 10)
    return -value if sign == "-" else value


# vs text. Shown: a double quote doubled, CR, LF and the backslash escaped, other control
# characters as \xHH; a TAB stays a TAB (as CANopenNode's gateway shows it).
_QUOTE_TABLE = str.maketrans({'"': '""', "\\": "\\\\", "\n": "\\n", "\r": "\\r",
                              **{chr(c): f"\\x{c:02X}" for c in (*range(0x20), 0x7F)
                                 if c not in (0x09, 0x0A, 0x0D)}})
# Read: a single word (no blank, no quote), or between double quotes with "" for a quote;
# in both, the escapes \\ \n \r \t \" (quoted only) and \xHH. Possessive patterns: no
# backtracking, so checking a value is linear in its length.
_ESCAPE = r'\\(?:x[0-9a-fA-F]{2}|[\\nrt])'
_VS_WORD = re.compile(rf'(?:[^\s"\\]++|{_ESCAPE})++')
_VS_QUOTED = re.compile(rf'"((?:[^"\\]++|""|\\"|{_ESCAPE})*+)"')


def _quote(text: str) -> str:
    return f'"{text.translate(_QUOTE_TABLE)}"'


def _unescape(body: str) -> str:
    """``body`` (checked by _VS_WORD or _VS_QUOTED) with its doubled quotes and escapes
    resolved in a few passes over the text, none of them a Python loop per character.

    Halving the runs of double quotes first is right: in a checked body a run is either
    pairs, or one escaped quote (after an escaping backslash) and pairs, and halving keeps
    each run after the character it followed. The escapes left are Python's own; every
    other non-ASCII character goes through as a Python escape too."""
    if "\\" not in body:
        return body.replace('""', '"')
    ascii_text = body.replace('""', '"').encode("ascii", "backslashreplace")
    return ascii_text.decode("unicode_escape")


def _unquote(text: str) -> str:
    if text.startswith('"'):
        m = _VS_QUOTED.fullmatch(text)
        if m is None:
            raise ValueError('a quoted string ends with a lone double quote ("" for a quote; '
                             'escapes \\\\ \\n \\r \\t \\" \\xHH)')
        return _unescape(m.group(1))
    if _VS_WORD.fullmatch(text) is None:
        raise ValueError("a string with blanks or quotes must be between double quotes "
                         "(escapes \\\\ \\n \\r \\t \\xHH)")
    return _unescape(text)


def _b64decode(text: str) -> bytes:
    try:
        return base64.b64decode(text, validate=True)
    except binascii.Error as exc:
        raise ValueError(f"not base64: {exc}") from None


# C's strtod syntax without hexadecimal floats: [sign] (inf | infinity | nan | digits with
# an optional point and exponent). Possessive: linear whatever the text.
_REAL_RE = re.compile(r"[+-]?+(?:inf(?:inity)?+|nan|(?:[0-9]++(?:\.[0-9]*+)?+|\.[0-9]++)"
                      r"(?:[eE][+-]?+[0-9]++)?+)", re.IGNORECASE)


def parse_value(type_name: str, text: str) -> bytes:
    """The wire bytes (little-endian) of ``text`` read as a value of ``type_name``."""
    spec = TYPES.get(type_name.lower())
    if spec is None:
        raise ValueError(f"unknown data type {type_name!r}")
    text = text.strip()
    kind = spec.kind
    if kind in ("bool", "int", "uint", "hex"):
        value = parse_int(text)
        if kind == "bool":
            if value not in (0, 1):
                raise ValueError("a boolean is 0 or 1")
            return bytes([value])
        bits = spec.size * 8
        if kind == "int":
            lo, hi = -(1 << (bits - 1)), (1 << (bits - 1)) - 1
        else:
            lo, hi = 0, (1 << bits) - 1
        if not lo <= value <= hi:
            raise ValueError(f"{value} is out of range for {spec.name}")
        return value.to_bytes(spec.size, "little", signed=kind == "int")
    if kind == "real":
        if _REAL_RE.fullmatch(text) is None:
            raise ValueError(f"not a real number: {text[:40]!r}")
        number = float(text)
        if spec.size == 4:
            if math.isfinite(number) and abs(number) > 3.4028235677973366e38:
                raise ValueError(f"{text[:40]} is out of range for r32")
            return struct.pack("<f", number)
        return struct.pack("<d", number)
    if kind == "time":
        parts = text.split(maxsplit=2)
        if len(parts) != 2:
            raise ValueError("a time is '<ms> <days>'")
        ms, days = parse_int(parts[0]), parse_int(parts[1])
        if not 0 <= ms < (1 << 28) or not 0 <= days <= 0xFFFF:
            raise ValueError("time out of range (ms < 2^28, days < 65536)")
        return ms.to_bytes(4, "little") + days.to_bytes(2, "little")
    if kind == "vs":
        try:
            return _unquote(text).encode("utf-8")
        except UnicodeEncodeError:
            raise ValueError("a string that is not Unicode text (a lone surrogate)") from None
    if kind == "b64":
        return _b64decode(text)
    # raw hexadecimal pairs, blanks allowed between bytes
    digits = "".join(text.split())
    if len(digits) % 2 or _HEX_RE.fullmatch(digits) is None:
        raise ValueError("hex data is pairs of hexadecimal digits")
    return bytes.fromhex(digits)


def _format_real(data: bytes, size: int) -> str:
    value = struct.unpack("<d" if size == 8 else "<f", data)[0]
    if math.isnan(value):  # repr drops a NaN's sign; "-nan" reads back with it
        return "-nan" if data[-1] & 0x80 else "nan"
    if size == 8 or not math.isfinite(value):
        return repr(value)
    for digits in range(1, 10):  # the shortest text that reads back as the same r32
        text = f"{value:.{digits}g}"
        if struct.pack("<f", float(text)) == data:
            return text
    return repr(value)


def format_value(type_name: str | None, data: bytes) -> str:
    """The text of ``data`` as a value of ``type_name`` (None: ``hex``)."""
    spec = TYPES.get((type_name or "hex").lower())
    if spec is None:
        raise ValueError(f"unknown data type {type_name!r}")
    if spec.size and len(data) != spec.size:
        raise ValueError(f"{len(data)} bytes for {spec.name} ({spec.size} bytes)")
    kind = spec.kind
    if kind == "bool":
        return str(data[0])
    if kind in ("int", "uint"):
        return str(int.from_bytes(data, "little", signed=kind == "int"))
    if kind == "hex":
        return f"0x{int.from_bytes(data, 'little'):0{spec.size * 2}X}"
    if kind == "real":
        return _format_real(data, spec.size)
    if kind == "time":
        ms = int.from_bytes(data[:4], "little") & 0x0FFFFFFF
        return f"{ms} {int.from_bytes(data[4:6], 'little')}"
    if kind == "vs":
        return _quote(data.decode("utf-8", "replace"))
    if kind == "b64":
        return base64.b64encode(data).decode("ascii")
    return " ".join(f"{b:02X}" for b in data)
