# SPDX-License-Identifier: Apache-2.0
"""CAN frames to CANopen meaning (``canola dump``, ``canola monitor``).

:class:`Decoder` reads frames of the pre-defined connection set (CiA 301) one by one and
returns an :class:`Event` per frame: its kind, the node it concerns and a line of text such
as ``node 5 heartbeat OPERATIONAL``, ``SDO upload 0x1018:01 = 0x00000004 (node 5)`` or
``EMCY node 3 0x4210 temperature``. SDO is decoded with state per node, so segmented and
block transfers end in one line with the whole value. The decoder never raises on frame
content: what it cannot place is an event of kind ``"unknown"`` or a ``"bad"`` SDO frame.
"""

from __future__ import annotations

import datetime
from dataclasses import dataclass, field
from typing import Any

from canola import pdomap
from canola.emcycodes import emcy_class, emcy_line, emcy_text, register_text
from canola.errors import ABORT_TEXT
from canola.formats.values import TIME_EPOCH, TimeOfDay, Value
from canola.formats.values import untyped_text as format_value
from canola.nodedicts import NodeDictionaries
from canola.odnames import entry_name, value_text
from canola.pdomap import Pdo, pdos_from_od

__all__ = ["STATE_NAMES", "Decoder", "Event", "emcy_text", "format_value"]

#: NMT states as carried by heartbeats (upper case for dump lines).
STATE_NAMES: dict[int, str] = {0x00: "BOOT-UP", 0x04: "STOPPED", 0x05: "OPERATIONAL",
                               0x7F: "PRE-OPERATIONAL"}

_NMT_COMMANDS = {0x01: "start", 0x02: "stop", 0x80: "preop", 0x81: "reset-node",
                 0x82: "reset-comm"}


def _shown(value: Value) -> str:
    """A decoded PDO value in a line: integers also in hex, bytes in hex."""
    if isinstance(value, bool):
        return str(value).lower()
    if isinstance(value, int):
        return str(value) if value <= 9 else f"{value} (0x{value:X})"
    if isinstance(value, bytes):
        return value.hex(" ").upper()
    if isinstance(value, TimeOfDay):
        return f"{value.ms} ms day {value.days}"
    return repr(value) if isinstance(value, str) else str(value)


def _json_value(value: Value) -> Any:
    if isinstance(value, bytes):
        return value.hex()
    if isinstance(value, TimeOfDay):
        return [value.ms, value.days]
    return value


@dataclass(frozen=True)
class Event:
    """The meaning of one frame. ``fields`` holds the decoded values (JSON-friendly)."""

    kind: str
    node: int | None
    text: str
    fields: dict[str, Any] = field(default_factory=dict)


@dataclass
class _Sdo:
    """One SDO transfer in progress (per server node)."""

    upload: bool
    index: int
    sub: int
    size: int | None = None
    data: bytearray = field(default_factory=bytearray)
    block: bool = False
    phase: str = "init"  # block: init, data, end
    subblock: list[bytes] = field(default_factory=list)

    @property
    def verb(self) -> str:
        return "upload" if self.upload else "download"


class Decoder:
    """Stateful CANopen decoder (one per bus). With ``dictionaries`` (the EDS/DCF of the
    nodes) SDO lines name their entries and show typed values, and PDOs are decoded by
    their mapping; ``pdos`` (node -> PDOs, e.g. read from the devices) come before the
    files' mappings."""

    def __init__(self, dictionaries: NodeDictionaries | None = None,
                 pdos: dict[int, list[Pdo]] | None = None) -> None:
        self._sdo: dict[int, _Sdo] = {}
        self._dicts = dictionaries or NodeDictionaries()
        self._given = dict(pdos or {})
        self._by_cob: dict[int, tuple[int, Pdo] | None] = {}
        self._file_pdos: dict[int, list[Pdo]] = {}

    # ---- what the dictionaries say

    def _at(self, node: int, index: int, sub: int) -> str:
        """An entry in a line: its address, and its name when a dictionary has one."""
        od = self._dicts.get(node)
        name = None if od is None else entry_name(od, index, sub)
        return f"0x{index:04X}:{sub:02X}" + (f" {name}" if name else "")

    def _of(self, node: int, t: _Sdo) -> str:
        return self._at(node, t.index, t.sub)

    def _value(self, node: int, index: int, sub: int, data: bytes) -> str:
        od = self._dicts.get(node)
        obj = None if od is None else od.objects.get(index)
        return value_text(None if obj is None else obj.subs.get(sub), data)

    def _mapped_pdo(self, can_id: int) -> tuple[int, Pdo] | None:
        """The (node, PDO) whose valid COB-ID is ``can_id``: the PDOs given first, then
        the dictionary of node ``can_id & 0x7F`` (pre-defined connection set), then every
        node's own file."""
        if can_id not in self._by_cob:
            found = None
            candidates = [*self._given.items(),
                          *((n, self._pdos_of(n)) for n in
                            (can_id & 0x7F, *sorted(self._dicts.per_node)) if n)]
            for node, pdos in candidates:
                for pdo in pdos:
                    if pdo.valid and pdo.cob_id == can_id and found is None:
                        found = (node, pdo)
            self._by_cob[can_id] = found
        return self._by_cob[can_id]

    def pdo_of(self, can_id: int) -> tuple[int, Pdo] | None:
        """The (node, PDO) whose mapping decodes the frames of ``can_id``, or None."""
        return self._mapped_pdo(can_id) if (self._dicts or self._given) else None

    def use_pdos(self, node: int, pdos: list[Pdo]) -> None:
        """Decode ``node``'s PDOs by ``pdos`` from now on (e.g. read from the device),
        before what its file says."""
        self._given[node] = pdos
        self._by_cob.clear()

    def _pdos_of(self, node: int) -> list[Pdo]:
        if node not in self._file_pdos:
            od = self._dicts.get(node)
            self._file_pdos[node] = [] if od is None else pdos_from_od(od)
        return self._file_pdos[node]

    def decode(self, can_id: int, data: bytes, *, rtr: bool = False,
               extended: bool = False) -> Event:
        """The meaning of one frame."""
        if extended:
            return Event("unknown", None, "29-bit frame (not CANopen CC)")
        fn, node = can_id & 0x780, can_id & 0x7F
        if can_id == 0x000:
            return self._nmt(data)
        mapped = self._mapped_pdo(can_id) if (self._dicts or self._given) else None
        if mapped is not None:
            return self._decoded_pdo(*mapped, data, rtr)
        if can_id == 0x080:
            if not data:
                return Event("sync", None, "SYNC")
            return Event("sync", None, f"SYNC counter {data[0]}", {"counter": data[0]})
        if fn == 0x080 and node:
            return self._emcy(node, data)
        if can_id == 0x100:
            return self._time(data)
        if 0x180 <= can_id <= 0x57F and node:
            return self._pdo(can_id, node, data, rtr)
        if fn == 0x580 and node:
            return self._sdo_frame(node, data, from_server=True)
        if fn == 0x600 and node:
            return self._sdo_frame(node, data, from_server=False)
        if fn == 0x700 and node:
            return self._error_control(node, data, rtr)
        if can_id in (0x7E4, 0x7E5):
            who = "slave" if can_id == 0x7E4 else "master"
            cs = f" cs 0x{data[0]:02X}" if data else ""
            return Event("lss", None, f"LSS {who}{cs} {data.hex(' ').upper()}".rstrip(),
                         {"from": who})
        return Event("unknown", None, f"COB-ID 0x{can_id:03X}")

    # ---- simple services

    def _nmt(self, data: bytes) -> Event:
        if len(data) != 2:
            return Event("nmt", None, f"NMT bad length {len(data)}")
        name = _NMT_COMMANDS.get(data[0], f"command 0x{data[0]:02X}")
        target = "all" if data[1] == 0 else f"node {data[1]}"
        return Event("nmt", data[1] or None, f"NMT {name} {target}",
                     {"command": name, "target": data[1]})

    def _emcy(self, node: int, data: bytes) -> Event:
        if len(data) < 3:
            return Event("emcy", node, f"EMCY node {node} bad length {len(data)}")
        code = int.from_bytes(data[0:2], "little")
        reg = data[2]
        extra = data[3:8].hex(" ").upper()
        return Event("emcy", node, f"EMCY node {node} {emcy_line(code, reg, data[3:8])}",
                     {"code": code, "register": reg, "data": extra,
                      "class": emcy_class(code), "meaning": emcy_text(code),
                      "register_bits": register_text(reg)})

    def _time(self, data: bytes) -> Event:
        if len(data) != 6:
            return Event("time", None, f"TIME bad length {len(data)}")
        ms = int.from_bytes(data[0:4], "little") & 0x0FFFFFFF
        days = int.from_bytes(data[4:6], "little")
        when = TIME_EPOCH + datetime.timedelta(days=days, milliseconds=ms)
        stamp = when.strftime("%Y-%m-%d %H:%M:%S.") + f"{when.microsecond // 1000:03d}"
        return Event("time", None, f"TIME {stamp}", {"days": days, "ms": ms})

    def _pdo(self, can_id: int, node: int, data: bytes, rtr: bool) -> Event:
        base = can_id & 0x780
        number = (base - 0x180) // 0x100 + 1
        kind = "TPDO" if (base - 0x180) % 0x100 == 0 else "RPDO"
        name = f"{kind}{number}"
        if rtr:
            return Event("pdo", node, f"{name} node {node} remote request", {"pdo": name})
        shown = data.hex(" ").upper() or "(empty)"
        return Event("pdo", node, f"{name} node {node} {shown}",
                     {"pdo": name, "data": data.hex()})

    def _decoded_pdo(self, node: int, pdo: Pdo, data: bytes, rtr: bool) -> Event:
        if rtr:
            return Event("pdo", node, f"{pdo.name} node {node} remote request",
                         {"pdo": pdo.name})
        decoded = pdomap.decode(pdo, data)
        shown = ", ".join(f"{m.name} = {_shown(v)}" for m, v in decoded)
        bits = sum(m.bits for m in pdo.entries)
        if bits != 8 * len(data):  # the mapping known is not the one the sender uses
            shown += f" ({len(data)} bytes, the mapping has {bits} bits)"
        return Event("pdo", node, f"{pdo.name} node {node} {shown or data.hex(' ').upper()}",
                     {"pdo": pdo.name, "data": data.hex(),
                      "values": {m.name: _json_value(v) for m, v in decoded}})

    def _error_control(self, node: int, data: bytes, rtr: bool) -> Event:
        if rtr:
            return Event("guard", node, f"node {node} guarding request")
        if len(data) != 1:
            return Event("heartbeat", node, f"node {node} error control bad length {len(data)}")
        state = data[0] & 0x7F
        name = STATE_NAMES.get(state, f"state 0x{state:02X}")
        if data[0] == 0:
            return Event("bootup", node, f"node {node} boot-up", {"state": 0})
        if data[0] & 0x80:
            return Event("guard", node, f"node {node} guarding {name} toggle 1",
                         {"state": state, "toggle": 1})
        return Event("heartbeat", node, f"node {node} heartbeat {name}",
                     {"state": state, "state_name": name})

    # ---- SDO

    def _sdo_frame(self, node: int, data: bytes, *, from_server: bool) -> Event:
        side = "response" if from_server else "request"
        if len(data) != 8:
            self._sdo.pop(node, None)
            return Event("sdo", node, f"SDO bad {side} length {len(data)} (node {node})",
                         {"bad": True})
        t = self._sdo.get(node)
        if t is not None and t.block and t.phase == "data" and data[0] != 0x80 and (
                from_server == t.upload):
            return self._block_segment(node, t, data)
        cmd = data[0]
        spec = cmd >> 5
        if spec == 4:
            return self._abort(node, data, from_server)
        return (self._server(node, data, spec) if from_server
                else self._client(node, data, spec))

    def _where(self, data: bytes) -> tuple[int, int]:
        return int.from_bytes(data[1:3], "little"), data[3]

    def _ev(self, node: int, text: str, **fields: Any) -> Event:
        return Event("sdo", node, f"{text} (node {node})", fields)

    def _abort(self, node: int, data: bytes, from_server: bool) -> Event:
        index, sub = self._where(data)
        code = int.from_bytes(data[4:8], "little")
        self._sdo.pop(node, None)
        by = "server" if from_server else "client"
        return self._ev(node, f"SDO abort {self._at(node, index, sub)} 0x{code:08X} "
                        f"{ABORT_TEXT.get(code, 'unknown abort code')} by {by}",
                        index=index, sub=sub, abort=code)

    def _expedited(self, node: int, data: bytes, direction: str, index: int,
                   sub: int) -> Event:
        """An expedited initiate frame (download request, upload response): its data (the
        size in the command byte, else all 4 bytes) is the whole transfer, which ends."""
        cmd = data[0]
        n = 4 - ((cmd >> 2) & 3) if cmd & 0x01 else 4
        value = data[4:4 + n]
        self._sdo.pop(node, None)
        return self._ev(node, f"SDO {direction} {self._at(node, index, sub)} = "
                        f"{self._value(node, index, sub, value)}", index=index, sub=sub,
                        value=value.hex())

    def _client(self, node: int, data: bytes, ccs: int) -> Event:
        cmd = data[0]
        t = self._sdo.get(node)
        if ccs == 1:  # initiate download
            index, sub = self._where(data)
            if cmd & 0x02:  # expedited
                return self._expedited(node, data, "download", index, sub)
            size = int.from_bytes(data[4:8], "little") if cmd & 0x01 else None
            self._sdo[node] = _Sdo(False, index, sub, size)
            return self._ev(node, f"SDO download {self._at(node, index, sub)} start"
                            + (f", {size} bytes" if size is not None else ""),
                            index=index, sub=sub, size=size)
        if ccs == 0:  # download segment
            if t is None or t.upload or t.block:
                return self._ev(node, "SDO download segment outside a transfer", bad=True)
            n = 7 - ((cmd >> 1) & 7)
            t.data += data[1:1 + n]
            if cmd & 0x01:
                return self._done(node, t)
            return self._ev(node, f"SDO download {self._of(node, t)} segment, "
                            f"{len(t.data)} bytes so far")
        if ccs == 2:  # initiate upload
            index, sub = self._where(data)
            self._sdo[node] = _Sdo(True, index, sub)
            return self._ev(node, f"SDO upload {self._at(node, index, sub)} request",
                            index=index, sub=sub)
        if ccs == 3:  # upload segment request
            where = self._of(node, t) if t is not None else "?"
            return self._ev(node, f"SDO upload {where} segment request")
        if ccs == 5:  # block upload: initiate, start, ack, end response
            sub_cmd = cmd & 0x03
            if sub_cmd == 0:
                index, sub = self._where(data)
                self._sdo[node] = _Sdo(True, index, sub, block=True)
                return self._ev(node, f"SDO block upload {self._at(node, index, sub)} request, "
                                f"block size {data[4]}", index=index, sub=sub)
            if t is None or not t.block:
                return self._ev(node, "SDO block upload frame outside a transfer", bad=True)
            if sub_cmd == 3:
                t.phase = "data"
                return self._ev(node, f"SDO block upload {self._of(node, t)} start")
            if sub_cmd == 2:
                return self._ack(node, t, data)
            self._sdo.pop(node, None)
            return self._ev(node, f"SDO block upload {self._of(node, t)} end confirmed")
        if ccs == 6:  # block download: initiate, end
            if cmd & 0x01 == 0:
                index, sub = self._where(data)
                size = int.from_bytes(data[4:8], "little") if cmd & 0x02 else None
                self._sdo[node] = _Sdo(False, index, sub, size, block=True)
                return self._ev(node, f"SDO block download {self._at(node, index, sub)} start"
                                + (f", {size} bytes" if size is not None else ""),
                                index=index, sub=sub, size=size)
            if t is None or not t.block:
                return self._ev(node, "SDO block download end outside a transfer", bad=True)
            del t.data[len(t.data) - ((cmd >> 2) & 7):]
            return self._done(node, t, keep=True)
        return self._ev(node, f"SDO request 0x{cmd:02X}", bad=True)

    def _server(self, node: int, data: bytes, scs: int) -> Event:
        cmd = data[0]
        t = self._sdo.get(node)
        if scs == 2:  # initiate upload response
            index, sub = self._where(data)
            if cmd & 0x02:
                return self._expedited(node, data, "upload", index, sub)
            size = int.from_bytes(data[4:8], "little") if cmd & 0x01 else None
            if t is None or t.block:  # also: a block upload switched to segmented
                t = self._sdo[node] = _Sdo(True, index, sub)
            t.size = size
            return self._ev(node, f"SDO upload {self._at(node, index, sub)} segmented"
                            + (f", {size} bytes" if size is not None else ""),
                            index=index, sub=sub, size=size)
        if scs == 0:  # upload segment
            if t is None or not t.upload:
                return self._ev(node, "SDO upload segment outside a transfer", bad=True)
            n = 7 - ((cmd >> 1) & 7)
            t.data += data[1:1 + n]
            if cmd & 0x01:
                return self._done(node, t)
            return self._ev(node, f"SDO upload {self._of(node, t)} segment, "
                            f"{len(t.data)} bytes so far")
        if scs == 3:  # initiate download response
            index, sub = self._where(data)
            if t is None or t.index != index or t.sub != sub:
                return self._ev(node, f"SDO download {self._at(node, index, sub)} ok",
                                index=index, sub=sub)
            return self._ev(node, f"SDO download {self._of(node, t)} accepted")
        if scs == 1:  # download segment response
            where = self._of(node, t) if t is not None else "?"
            return self._ev(node, f"SDO download {where} segment ok")
        if scs == 5:  # block download: initiate response, ack, end response
            sub_cmd = cmd & 0x03
            if t is None or not t.block:
                return self._ev(node, "SDO block download response outside a transfer",
                                bad=True)
            if sub_cmd == 0:
                t.phase = "data"
                return self._ev(node, f"SDO block download {self._of(node, t)} accepted, "
                                f"block size {data[4]}")
            if sub_cmd == 2:
                return self._ack(node, t, data)
            self._sdo.pop(node, None)
            return self._ev(node, f"SDO block download {self._of(node, t)} done")
        if scs == 6:  # block upload: initiate response, end
            if t is None or not t.block:
                return self._ev(node, "SDO block upload response outside a transfer", bad=True)
            if cmd & 0x01 == 0:
                t.size = int.from_bytes(data[4:8], "little") if cmd & 0x02 else None
                return self._ev(node, f"SDO block upload {self._of(node, t)}"
                                + (f", {t.size} bytes" if t.size is not None else ""))
            del t.data[len(t.data) - ((cmd >> 2) & 7):]
            return self._done(node, t, keep=True)
        return self._ev(node, f"SDO response 0x{cmd:02X}", bad=True)

    def _block_segment(self, node: int, t: _Sdo, data: bytes) -> Event:
        seq = data[0] & 0x7F
        if seq == len(t.subblock) + 1:
            t.subblock.append(bytes(data[1:8]))
        last = bool(data[0] & 0x80)
        if last:
            t.phase = "end"
        return self._ev(node, f"SDO block {t.verb} {self._of(node, t)} segment {seq}"
                        + (" (last)" if last else ""))

    def _ack(self, node: int, t: _Sdo, data: bytes) -> Event:
        ackseq = data[1]
        for chunk in t.subblock[:ackseq]:
            t.data += chunk
        t.subblock.clear()
        if t.phase != "end":
            t.phase = "data"
        return self._ev(node, f"SDO block {t.verb} {self._of(node, t)} ack {ackseq}, "
                        f"{len(t.data)} bytes so far")

    def _done(self, node: int, t: _Sdo, keep: bool = False) -> Event:
        if not keep:
            self._sdo.pop(node, None)
        value = bytes(t.data)
        kind = "block " if t.block else ""
        return self._ev(node, f"SDO {kind}{t.verb} {self._of(node, t)} = "
                        f"{self._value(node, t.index, t.sub, value)}",
                        index=t.index, sub=t.sub, value=value.hex(), size=len(value))
