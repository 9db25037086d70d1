# SPDX-License-Identifier: Apache-2.0
"""PDOs as their communication and mapping parameters describe them (CiA 301 7.5.2.35..38):
from an EDS/DCF, read from a device by SDO, configured by the re-mapping procedure, and the
values of a PDO frame by its mapping.

    pdos = pdos_from_od(od)                     # every PDO the file defines
    values = decode(pdos[0], frame_data)        # [(Mapped, value), ...]
    pdo = read_pdo(master.sdo(5), "TPDO1", od)  # the device's own view
    configure_pdo(master.sdo(5), "TPDO1", [mapped_entry(od, "Statusword")],
                  transmission_type=255, event_timer_ms=100)

A PDO is named ``TPDO1``..``TPDO512`` or ``RPDO1``..``RPDO512``; its communication
parameter is at 0x1800 (0x1400) + n - 1, its mapping at 0x1A00 (0x1600) + n - 1.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from typing import Protocol

from canola.errors import Error, SdoAbort
from canola.formats import values
from canola.formats.datatypes import DATA_TYPES, type_bits
from canola.formats.eds import ObjectDictionary, Variable
from canola.odnames import entry_name, find_entry, parse_address

__all__ = ["Mapped", "Pdo", "PdoConfigError", "PdoError", "configure_pdo", "decode",
           "describe", "mapped_entry", "parse_pdo_name", "pdos_from_od", "read_pdo",
           "read_pdos", "type_bits"]

#: What the PDOs of a device without an EDS are probed for (the pre-defined set).
DEFAULT_PDOS = ("RPDO1", "RPDO2", "RPDO3", "RPDO4", "TPDO1", "TPDO2", "TPDO3", "TPDO4")
_MISSING = (0x06020000, 0x06090011)  # object / sub-index does not exist

_COMM_BASE = {"RPDO": 0x1400, "TPDO": 0x1800}
_MAP_OFFSET = 0x200
_COB_INVALID = 1 << 31
_COB_NO_RTR = 1 << 30


class PdoError(Error):
    """A PDO name, mapping or configuration that does not work (one-line message)."""


class SdoAccess(Protocol):
    """What this module needs of an SDO client (canola.master.SdoClient)."""

    def upload(self, index: int, sub: int, *, timeout: float | None = None) -> bytes: ...

    def download(self, index: int, sub: int, data: bytes, *,
                 timeout: float | None = None) -> None: ...


@dataclass(frozen=True)
class Mapped:
    """One mapped entry: ``bits`` long; ``name`` and ``data_type`` from the EDS when it has
    the entry (else the address and None)."""

    index: int
    sub: int
    bits: int
    name: str
    data_type: int | None = None

    @property
    def word(self) -> int:
        """The mapping parameter's value (index << 16 | sub << 8 | bits)."""
        return self.index << 16 | self.sub << 8 | self.bits


@dataclass
class Pdo:
    kind: str  # "TPDO" or "RPDO"
    number: int  # 1-based
    cob_id: int  # the 11-bit CAN-ID
    valid: bool = True
    rtr_allowed: bool = True
    transmission_type: int | None = None
    inhibit_100us: int | None = None
    event_timer_ms: int | None = None
    sync_start: int | None = None
    entries: list[Mapped] = field(default_factory=list)

    @property
    def name(self) -> str:
        return f"{self.kind}{self.number}"

    @property
    def comm_index(self) -> int:
        return _COMM_BASE[self.kind] + self.number - 1

    @property
    def map_index(self) -> int:
        return self.comm_index + _MAP_OFFSET


def parse_pdo_name(text: str) -> tuple[str, int]:
    """``TPDO1`` / ``rpdo4`` as ("TPDO", 1). Raises PdoError."""
    m = re.fullmatch(r"([TR])PDO(\d{1,3})", text.strip().upper())
    if m is None or not 1 <= int(m.group(2)) <= 512:
        raise PdoError(f"bad PDO {text!r}: TPDO1..TPDO512 or RPDO1..RPDO512")
    return f"{m.group(1)}PDO", int(m.group(2))


def _number(var: Variable | None) -> int | None:
    """A DCF's ParameterValue, else the EDS default, when an integer."""
    if var is None:
        return None
    value = var.value if var.value is not None else var.default
    return value if isinstance(value, int) and not isinstance(value, bool) else None


def _mapped(od: ObjectDictionary | None, word: int) -> Mapped:
    index, sub, bits = word >> 16, (word >> 8) & 0xFF, word & 0xFF
    name = entry_name(od, index, sub) if od is not None else None
    var = od.objects[index].subs[sub] if name is not None and od is not None else None
    return Mapped(index, sub, bits, name or f"0x{index:04X}:{sub:02X}",
                  None if var is None else var.data_type)


def pdos_from_od(od: ObjectDictionary) -> list[Pdo]:
    """Every PDO ``od`` defines, with the values of a DCF (else the defaults)."""
    found = []
    for kind, base in _COMM_BASE.items():
        for n in range(512):
            comm, mapping = od.objects.get(base + n), od.objects.get(base + _MAP_OFFSET + n)
            if comm is None or mapping is None:
                continue
            cob = _number(comm.subs.get(1))
            if cob is None:
                continue
            count = _number(mapping.subs.get(0)) or 0
            words = [_number(mapping.subs.get(i)) for i in range(1, min(count, 64) + 1)]
            found.append(Pdo(kind, n + 1, cob & 0x7FF, not cob & _COB_INVALID,
                             not cob & _COB_NO_RTR, _number(comm.subs.get(2)),
                             _number(comm.subs.get(3)), _number(comm.subs.get(5)),
                             _number(comm.subs.get(6)),
                             [_mapped(od, w) for w in words if w]))
    return found


def _typed(m: Mapped, raw: int) -> values.Value:
    """A mapped entry's bits as its EDS type: a BOOLEAN of any size, a type whose size
    is the mapping's, a string or DOMAIN of whole bytes; else the unsigned number."""
    if m.data_type == 0x01:
        return bool(raw)
    if m.data_type is None or m.bits % 8 or type_bits(m.data_type) not in (m.bits, None):
        return raw
    try:
        return values.decode(m.data_type, raw.to_bytes(m.bits // 8, "little"))
    except values.ValueFormatError:
        return raw


def decode(pdo: Pdo, data: bytes) -> list[tuple[Mapped, values.Value]]:
    """The values of PDO frame ``data`` by the mapping of ``pdo``: typed when the EDS gives
    a type that fills the mapped bits, else unsigned integers. Entries beyond the frame's
    length are left out."""
    number = int.from_bytes(data, "little")
    out: list[tuple[Mapped, values.Value]] = []
    offset = 0
    for m in pdo.entries:
        if offset + m.bits > 8 * len(data):
            break
        raw = (number >> offset) & ((1 << m.bits) - 1)
        offset += m.bits
        if m.index < 0x1000 and m.index in DATA_TYPES:  # dummy mapping: a gap
            continue
        out.append((m, _typed(m, raw)))
    return out


def mapped_entry(od: ObjectDictionary | None, text: str) -> Mapped:
    """The entry ``text`` names (a name with ``od``, or INDEX:SUB) as a mapping of its
    type's full size; ``INDEX:SUB:BITS`` gives the size itself. Raises Error."""
    head, _, bits_text = text.rpartition(":") if text.count(":") == 2 else (text, "", "")
    if od is None:
        var = None
        address = parse_address(head)
        if address is None:
            raise PdoError(f"bad entry {text!r}: INDEX:SUB[:BITS] (names need --eds FILE)")
        index, sub = address
    else:
        var = find_entry(od, head)
        index, sub = var.index, var.subindex
        if not var.pdo_mapping:
            raise PdoError(f"{entry_name(od, index, sub)} (0x{index:04X}:{sub:02X}) "
                           "may not be mapped into a PDO (PDOMapping=0)")
    if bits_text:
        try:
            bits = int(bits_text, 0)
        except ValueError:
            bits = 0
    else:
        bits = (None if var is None else type_bits(var.data_type)) or 0
    if not 1 <= bits <= 64:
        raise PdoError(f"{text!r}: give its size in bits (INDEX:SUB:BITS, 1..64)")
    return _mapped(od, index << 16 | sub << 8 | bits)


def _u(sdo: SdoAccess, index: int, sub: int, timeout: float | None) -> int:
    return int.from_bytes(sdo.upload(index, sub, timeout=timeout), "little")


def _put(sdo: SdoAccess, index: int, sub: int, value: int, size: int, *,
         timeout: float | None) -> None:
    sdo.download(index, sub, value.to_bytes(size, "little"), timeout=timeout)


def read_pdo(sdo: SdoAccess, name: str, od: ObjectDictionary | None = None, *,
             timeout: float | None = None) -> Pdo:
    """PDO ``name`` as the device has it, read by SDO (sub-indices the device lacks are
    left None). Raises SdoAbort/SdoTimeout from the client, PdoError for a bad name."""
    kind, number = parse_pdo_name(name)
    pdo = Pdo(kind, number, 0)
    cob = _u(sdo, pdo.comm_index, 1, timeout)
    pdo.cob_id, pdo.valid, pdo.rtr_allowed = (cob & 0x7FF, not cob & _COB_INVALID,
                                              not cob & _COB_NO_RTR)
    for sub, attr in ((2, "transmission_type"), (3, "inhibit_100us"), (5, "event_timer_ms"),
                      (6, "sync_start")):
        try:
            setattr(pdo, attr, _u(sdo, pdo.comm_index, sub, timeout))
        except SdoAbort as exc:
            if exc.code not in (*_MISSING, 0x06010001):
                raise
    count = _u(sdo, pdo.map_index, 0, timeout)
    pdo.entries = [_mapped(od, _u(sdo, pdo.map_index, i, timeout))
                   for i in range(1, min(count, 64) + 1)]
    return pdo


def read_pdos(sdo: SdoAccess, od: ObjectDictionary | None = None,
              names: list[str] | None = None, *, timeout: float | None = None) -> list[Pdo]:
    """The PDOs ``names`` (default: those ``od`` defines, else the pre-defined set's
    RPDO1..4 and TPDO1..4) as the device has them; those it lacks are left out."""
    if names is None:
        names = ([p.name for p in pdos_from_od(od)] if od is not None else list(DEFAULT_PDOS))
    found = []
    for name in names:
        try:
            found.append(read_pdo(sdo, name, od, timeout=timeout))
        except SdoAbort as exc:
            if exc.code not in _MISSING:
                raise
    return found


_TRANSMISSION = {0: "synchronous, acyclic", 252: "synchronous, on RTR only",
                 253: "on RTR only", 254: "event-driven (manufacturer)",
                 255: "event-driven (profile)"}


def transmission_text(kind: int | None) -> str:
    if kind is None:
        return "?"
    if 1 <= kind <= 240:
        return f"{kind} (every {kind}. SYNC)" if kind > 1 else "1 (every SYNC)"
    return f"{kind} ({_TRANSMISSION.get(kind, 'reserved')})"


def describe(pdo: Pdo) -> list[str]:
    """``pdo`` as the lines ``canola pdo show`` prints."""
    state = "valid" if pdo.valid else "not valid"
    parts = [f"{pdo.name}  COB-ID 0x{pdo.cob_id:03X} {state}",
             f"transmission type {transmission_text(pdo.transmission_type)}"]
    if pdo.inhibit_100us is not None:
        parts.append(f"inhibit {pdo.inhibit_100us * 100} us")
    if pdo.event_timer_ms is not None:
        parts.append(f"event timer {pdo.event_timer_ms} ms")
    lines = [", ".join(parts)]
    lines.extend(f"  {i}  0x{m.index:04X}:{m.sub:02X} {m.bits:>2} bits  {m.name}"
                 for i, m in enumerate(pdo.entries, 1))
    if not pdo.entries:
        lines.append("  (nothing mapped)")
    return lines


class PdoConfigError(PdoError):
    """A re-mapping that failed half-way (an abort, or no answer): ``cause`` is the SDO
    error, ``step`` what was being written, ``state`` what the PDO was left as (restored
    to the configuration it had, or, when that failed too, its COB-ID and mapping count as
    last written)."""

    def __init__(self, name: str, cause: SdoAbort, step: str, state: str) -> None:
        super().__init__(f"{name}: {cause} (writing {step}); {state}")
        self.cause, self.step, self.state = cause, step, state


def _cob_text(cob: int) -> str:
    return f"COB-ID 0x{cob:08X} ({'invalid' if cob & _COB_INVALID else 'valid'})"


class _Remap:
    """The writes of one re-mapping, each noted, so that a failure can say where it
    stopped and what the PDO holds."""

    def __init__(self, sdo: SdoAccess, pdo: Pdo, timeout: float | None) -> None:
        self.sdo, self.pdo, self.timeout = sdo, pdo, timeout
        self.cob: int | None = None  # the COB-ID and mapping count as last written
        self.count: int | None = None
        self.step = ""

    def put(self, index: int, sub: int, value: int, size: int) -> None:
        self.step = f"0x{index:04X}:{sub:02X} = 0x{value:0{2 * size}X}"
        _put(self.sdo, index, sub, value, size, timeout=self.timeout)
        if (index, sub) == (self.pdo.comm_index, 1):
            self.cob = value
        elif (index, sub) == (self.pdo.map_index, 0):
            self.count = value

    def apply(self, cob: int, comm: dict[int, tuple[int, int]], words: list[int]) -> None:
        """CiA 301's order: invalid, communication parameters, count 0, entries, count,
        valid (``cob`` as given)."""
        self.put(self.pdo.comm_index, 1, cob | _COB_INVALID, 4)
        for sub, (value, size) in comm.items():
            self.put(self.pdo.comm_index, sub, value, size)
        self.put(self.pdo.map_index, 0, 0, 1)
        for i, word in enumerate(words, 1):
            self.put(self.pdo.map_index, i, word, 4)
        self.put(self.pdo.map_index, 0, len(words), 1)
        self.put(self.pdo.comm_index, 1, cob, 4)

    def left(self, cob: int) -> str:
        """What the PDO holds after a failed undo, from the writes that succeeded."""
        now = cob if self.cob is None else self.cob
        count = "as before" if self.count is None else str(self.count)
        return (f"restoring failed ({self.step}): {self.pdo.name} is left with "
                f"{_cob_text(now)} and mapping count {count}")


def configure_pdo(sdo: SdoAccess, name: str, entries: list[Mapped], *,
                  transmission_type: int | None = None, event_timer_ms: int | None = None,
                  inhibit_100us: int | None = None, timeout: float | None = None) -> Pdo:
    """Configure PDO ``name`` by the CiA 301 re-mapping procedure: invalidate it (COB-ID
    bit 31), set the communication parameters given, mapping count 0, the entries, the
    count, and make it valid again with its COB-ID. Returns the PDO as configured.

    The configuration it had is read first. When a step fails (an abort: the device
    refuses an entry, say; or no answer), that configuration is written back by the same
    procedure and :class:`PdoConfigError` says what failed and that the PDO was restored,
    or, when the undo failed too, the COB-ID (valid or not) and mapping count it was left
    with. A failure while reading changes nothing and is raised as it is (SdoAbort)."""
    kind, number = parse_pdo_name(name)
    if sum(m.bits for m in entries) > 64:
        raise PdoError(f"{name}: the entries take {sum(m.bits for m in entries)} bits, "
                       "a PDO holds 64")
    pdo = Pdo(kind, number, 0, entries=list(entries))
    cob = _u(sdo, pdo.comm_index, 1, timeout)
    sizes = {2: 1, 3: 2, 5: 2}
    asked = {sub: value for sub, value in ((2, transmission_type), (3, inhibit_100us),
                                           (5, event_timer_ms)) if value is not None}
    old_comm = {sub: (_u(sdo, pdo.comm_index, sub, timeout), sizes[sub]) for sub in asked}
    old_count = min(_u(sdo, pdo.map_index, 0, timeout), 64)
    old_words = [_u(sdo, pdo.map_index, i, timeout) for i in range(1, old_count + 1)]
    remap = _Remap(sdo, pdo, timeout)
    try:
        remap.apply(cob & ~_COB_INVALID, {sub: (value, sizes[sub]) for sub, value in
                                          asked.items()}, [m.word for m in entries])
    except SdoAbort as exc:
        step = remap.step
        undo = _Remap(sdo, pdo, timeout)
        undo.cob, undo.count = remap.cob, remap.count
        try:
            undo.apply(cob, old_comm, old_words)
            state = (f"the previous configuration is restored ({_cob_text(cob)}, "
                     f"{old_count} entries)")
        except SdoAbort:
            state = undo.left(cob)
        raise PdoConfigError(name, exc, step, state) from exc
    pdo.cob_id, pdo.rtr_allowed = cob & 0x7FF, not cob & _COB_NO_RTR
    pdo.transmission_type, pdo.event_timer_ms = transmission_type, event_timer_ms
    pdo.inhibit_100us = inhibit_100us
    return pdo
