"""Concise DCF (the 0x1F22 format of CiA 302): what the CANopen manager downloads to a
slave.

Layout: u32 number of records, then per record u16 index, u8 sub-index, u32 size and the
value's wire bytes, all little-endian. :func:`from_dcf` takes the entries of a DCF that
carry a ``ParameterValue`` and that the network may write (not ``ro``/``const``), in
index order.
"""

from __future__ import annotations

import struct
from collections.abc import Iterable

from canola import eds, values
from canola.datatypes import DATA_TYPES, INTEGER_TYPES, NumberError, fit_signed, parse_value
from canola.errors import EdsError

__all__ = ["Record", "build", "from_dcf", "parse"]

#: One entry of a concise DCF: (index, sub-index, wire bytes).
Record = tuple[int, int, bytes]

_STRINGS = {0x09: "latin-1", 0x0B: "utf-16-le"}
_OCTETS = (0x0A, 0x0F)


def build(records: Iterable[Record]) -> bytes:
    """The concise DCF of ``records``."""
    items = list(records)
    out = [struct.pack("<I", len(items))]
    for index, sub, data in items:
        out.append(struct.pack("<HBI", index, sub, len(data)))
        out.append(bytes(data))
    return b"".join(out)


def parse(data: bytes) -> list[Record]:
    """The records of a concise DCF; ValueError when it is not whole."""
    if len(data) < 4:
        raise ValueError("a concise DCF starts with a 4-byte record count")
    (count,) = struct.unpack_from("<I", data, 0)
    pos = 4
    records: list[Record] = []
    for _ in range(count):
        if pos + 7 > len(data):
            raise ValueError(f"record {len(records) + 1} of {count} is cut short")
        index, sub, size = struct.unpack_from("<HBI", data, pos)
        pos += 7
        if pos + size > len(data):
            raise ValueError(f"record {len(records) + 1} of {count} is cut short")
        records.append((index, sub, data[pos:pos + size]))
        pos += size
    if pos != len(data):
        raise ValueError(f"{len(data) - pos} byte(s) after the last record")
    return records


def _wire(var: eds.Variable, node_id: int | None) -> bytes:
    """The wire bytes of the variable's ParameterValue; ValueError when it has none."""
    code = var.data_type
    text = var.parameter_value or ""
    if code in _STRINGS:
        return text.encode(_STRINGS[code])
    if code in _OCTETS:
        digits = "".join(text.split())
        if digits.lower().startswith("0x"):
            digits = digits[2:]
        return bytes.fromhex(digits)
    if code is None or code not in DATA_TYPES:
        raise ValueError("unknown data type")
    try:
        value = parse_value(text, code, node_id)
    except NumberError as exc:
        raise ValueError(str(exc)) from None
    if value is None:
        raise ValueError("$NODEID without a node-ID" if text.strip() else "empty")
    if isinstance(value, int) and code in INTEGER_TYPES:
        value = fit_signed(value, text, code)
    elif isinstance(value, int):
        value = float(value)
    return values.encode(code, value)


def from_dcf(model: eds.ObjectDictionary) -> list[Record]:
    """The records of a parsed DCF: every writable entry with a ParameterValue. Raises
    :class:`~canola.errors.EdsError` (file, section) for a value that cannot be encoded."""
    records: list[Record] = []
    for index in sorted(model.objects):
        obj = model.objects[index]
        for sub in sorted(obj.subs):
            var = obj.subs[sub]
            if var.parameter_value is None or var.access_type in ("ro", "const"):
                continue
            section = (f"{index:04X}" if obj.object_type == eds.ObjectType.VAR
                       else f"{index:04X}sub{sub:X}")
            try:
                data = _wire(var, model.node_id)
            except (ValueError, UnicodeEncodeError) as exc:
                raise EdsError(f"{var.parameter_value!r} cannot be downloaded: {exc}",
                               file=model.file, line=var.line, section=section,
                               key="ParameterValue") from None
            records.append((index, sub, data))
    return records
