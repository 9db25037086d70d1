# SPDX-License-Identifier: Apache-2.0
"""Concise DCF (the 0x1F22 format of CiA 302): what the CANopen manager downloads to a
slave.

Layout: u32 number of records, then per record u16 index, u8 sub-index, u32 size and the
value's wire bytes, all little-endian. :func:`from_dcf` takes the entries of a DCF that
carry a ``ParameterValue`` and that the network may write (not ``ro``/``const``), in
index order, except PDOs: :func:`pdo_order` puts each PDO's entries in the order of the
CiA 301 re-mapping procedure, which devices enforce (CANopenNode's refuse a mapping
while the PDO is valid, and a valid PDO without mapping).
"""

from __future__ import annotations

import struct
from collections.abc import Iterable

from canola.errors import EdsError
from canola.formats import eds, values
from canola.formats.datatypes import DATA_TYPES, INTEGER_TYPES, NumberError, fit_signed, parse_value

__all__ = ["Record", "build", "from_dcf", "parse", "pdo_order", "wire"]

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


def wire(code: int | None, text: str, node_id: int | None) -> bytes:
    """The wire bytes of a value written in a DCF (``text``, a ParameterValue or
    DefaultValue) for data type ``code``; ValueError (or UnicodeEncodeError) when it has
    none: empty, not of the type, out of its range, or ``$NODEID`` with ``node_id`` None."""
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


def _pdo_of(index: int) -> tuple[int, bool] | None:
    """(communication parameter index, is the mapping) of a PDO object, None for others."""
    if 0x1400 <= index <= 0x15FF or 0x1800 <= index <= 0x19FF:
        return index, False
    if 0x1600 <= index <= 0x17FF or 0x1A00 <= index <= 0x1BFF:
        return index - 0x200, True
    return None


def pdo_order(records: Iterable[Record], cob_ids: dict[int, bytes] | None = None
              ) -> list[Record]:
    """``records`` with each PDO's entries in the CiA 301 re-mapping order: its COB-ID
    with bit 31 set (not valid), the mapping count 0, the mapping entries, the count, the
    other communication parameters, and the COB-ID as given last. The PDOs (RPDOs, then
    TPDOs, by number) take the place of the first PDO entry; other records keep theirs.
    ``cob_ids`` gives the COB-ID (wire bytes) of PDOs whose records lack one (a DCF's
    DefaultValue): without one the PDO is not switched off around its changes."""
    pdos: dict[int, tuple[dict[int, bytes], dict[int, bytes]]] = {}
    out: list[Record] = []
    placed = False
    for index, sub, data in records:
        pdo = _pdo_of(index)
        if pdo is None:
            out.append((index, sub, data))
            continue
        if not placed:
            out.append((-1, 0, b""))  # where the PDOs go
            placed = True
        comm, is_mapping = pdo
        pdos.setdefault(comm, ({}, {}))[is_mapping][sub] = data
    ordered: list[Record] = []
    for comm in sorted(pdos):
        params, mapping = pdos[comm]
        cob = params.pop(1, None)
        first = cob if cob is not None else (cob_ids or {}).get(comm)
        if first is not None:
            off = int.from_bytes(first[:4].ljust(4, b"\0"), "little") | 0x80000000
            ordered.append((comm, 1, off.to_bytes(4, "little")))
        if mapping:
            count = mapping.pop(0, None)
            ordered.append((comm + 0x200, 0, b"\x00"))
            ordered += [(comm + 0x200, sub, mapping[sub]) for sub in sorted(mapping)]
            if count is None:
                count = bytes([max(mapping, default=0)])
            ordered.append((comm + 0x200, 0, count))
        ordered += [(comm, sub, params[sub]) for sub in sorted(params)]
        if first is not None:
            ordered.append((comm, 1, first))
    return [r for record in out for r in (ordered if record[0] < 0 else [record])]


def from_dcf(model: eds.ObjectDictionary) -> list[Record]:
    """The records of a parsed DCF: every writable entry with a ParameterValue, PDOs in
    the re-mapping order (:func:`pdo_order`). Raises :class:`~canola.errors.EdsError`
    (file, section) for a value that cannot be encoded."""
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
                data = wire(var.data_type, var.parameter_value, model.node_id)
            except (ValueError, UnicodeEncodeError) as exc:
                raise EdsError(f"{var.parameter_value!r} cannot be downloaded: {exc}",
                               file=model.file, line=var.line, section=section,
                               key="ParameterValue") from None
            records.append((index, sub, data))
    return pdo_order(records, _default_cob_ids(model, records))


def _default_cob_ids(model: eds.ObjectDictionary, records: list[Record]) -> dict[int, bytes]:
    """The power-on COB-IDs (DefaultValue of sub1) of the PDOs the records change."""
    cob_ids: dict[int, bytes] = {}
    for index, _, _ in records:
        pdo = _pdo_of(index)
        obj = model.objects.get(pdo[0]) if pdo else None
        var = obj.subs.get(1) if obj is not None else None
        if pdo is None or var is None or var.default_value is None:
            continue
        try:
            value = parse_value(var.default_value, 0x07, model.node_id)
        except NumberError:
            continue
        if isinstance(value, int):
            cob_ids[pdo[0]] = (value & 0xFFFFFFFF).to_bytes(4, "little")
    return cob_ids
