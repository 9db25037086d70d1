# SPDX-License-Identifier: Apache-2.0
"""Recorded traces of real CANopenNode devices (python/tests/data/traces/*.log), for the tests
of canola.conformance: RECORDED, NOT MODELLED (canopennode_models.py is the model).

A trace is ``candump -L`` of vcan0 while ``canola conformance`` ran against the device (the
header of each file says which device, which upstream commits, how it was run). Two uses:

- :func:`load` gives the frames, for tests that assert from them what the device did (the
  abort code it sent, the state in its heartbeat after NMT start and when, 0x1017 after
  reset communication, the register byte of its EMCY);
- :class:`ReplayNode` answers the tester's SDO requests on the simulated bus with what the
  real device answered to the same request in the trace (the n-th time a request comes, the
  n-th recorded answer to it), so the tester's own judging logic runs on the device's frames.
  Between requests it keeps only what the tester needs to see the node: its NMT state and
  a heartbeat at the 0x1017 period the replayed answers accepted.
"""

from __future__ import annotations

import re
from collections import defaultdict, deque
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from canola import Master
from canola.core import SimBus
from canola.master import Frame

TRACES = Path(__file__).resolve().parent / "data" / "traces"
NODE = 5
TESTER = 127
_LINE = re.compile(r"^\((\d+\.\d+)\) \S+ ([0-9A-Fa-f]{3})#([0-9A-Fa-f]*)$")
_STATES = {0x01: 0x05, 0x02: 0x04, 0x80: 0x7F}


@dataclass(frozen=True, slots=True)
class Recorded:
    """A frame of a trace: its bus time (s), COB-ID and data."""

    t: float
    cob: int
    data: bytes

    @property
    def text(self) -> str:
        return f"{self.cob:03X}#{self.data.hex().upper()}"


def load(name: str) -> list[Recorded]:
    """The frames of ``data/traces/NAME.log`` (lines starting with ``#`` are its header)."""
    frames = []
    for number, line in enumerate((TRACES / f"{name}.log").read_text().splitlines(), 1):
        if not line or line.startswith("#"):
            continue
        match = _LINE.match(line)
        if match is None:
            raise ValueError(f"{name}.log:{number}: not a candump -L line: {line!r}")
        frames.append(Recorded(float(match[1]), int(match[2], 16), bytes.fromhex(match[3])))
    return frames


def header(name: str) -> str:
    """The comment lines at the top of the trace."""
    lines = (TRACES / f"{name}.log").read_text().splitlines()
    return "\n".join(line for line in lines if line.startswith("#"))


def from_tester(frame: Recorded) -> bool:
    """A frame the tester sent (requests, NMT, SYNC, TIME, RPDOs, its heartbeat)."""
    return frame.cob in (0x000, 0x080, 0x100, 0x600 + NODE, 0x700 + TESTER) or (
        0x200 <= frame.cob < 0x580 and (frame.cob & 0x7F) == NODE and frame.cob >> 7 in (
            4, 6, 8, 10))


def answers(frames: list[Recorded]) -> dict[bytes, deque[list[bytes]]]:
    """For each SDO request of the tester, the device's SDO frames that followed it (before
    the tester's next SDO request), once per time it was sent, in order."""
    table: dict[bytes, deque[list[bytes]]] = defaultdict(deque)
    current: list[bytes] | None = None
    for frame in frames:
        if frame.cob == 0x600 + NODE:
            current = []
            table[frame.data].append(current)
        elif frame.cob == 0x580 + NODE and current is not None:
            current.append(frame.data)
    return table


class ReplayNode:
    """Node :data:`NODE` on ``bus`` answering SDO requests as the recorded device did.
    ``missed`` lists the requests the trace has no (more) answer for: they stay unanswered,
    as a request a device ignores would."""

    def __init__(self, bus: SimBus, frames: list[Recorded]) -> None:
        self.table = answers(frames)
        self.missed: list[bytes] = []
        self.state = 0x7F
        self.period_ms = 0
        self._timer: Any = None
        self.port = Master(bus, 100)
        self.port.on_frame(self._sdo, cob_id=0x600 + NODE)
        self.port.on_frame(self._nmt, cob_id=0x000)

    def start(self) -> None:
        self.port.start()
        self.port.send(0x700 + NODE, b"\0")

    def _sdo(self, frame: Frame) -> None:
        request = bytes(frame.data)
        queue = self.table.get(request)
        if not queue:
            self.missed.append(request)
            return
        replies = queue.popleft()
        for reply in replies:
            self.port.send(0x580 + NODE, reply)
        if request[:4] == b"\x2b\x17\x10\x00" and replies and replies[-1][0] == 0x60:
            self._heartbeat(int.from_bytes(request[4:6], "little"))

    def _nmt(self, frame: Frame) -> None:
        if len(frame.data) != 2 or frame.data[1] not in (0, NODE):
            return
        if frame.data[0] in (0x81, 0x82):
            self.state = 0x7F
            self.port.send(0x700 + NODE, b"\0")
        else:
            self.state = _STATES.get(frame.data[0], self.state)

    def _heartbeat(self, period_ms: int) -> None:
        engine = self.port._engine
        if self._timer is not None:
            engine.remove_timer(self._timer)
            self._timer = None
        self.period_ms = period_ms
        if period_ms:
            self._timer = engine.add_timer(period_ms * 1000, self._beat)

    def _beat(self) -> None:
        self.port.send(0x700 + NODE, bytes([self.state]))
        self._heartbeat(self.period_ms)


# ---- canopend's dictionary (CANopenNode's example DS301 profile, as its EDS gives it: the
# objects, types, access and defaults, which the tester's requests follow)

def _section(name: str, keys: list[tuple[str, str]]) -> str:
    return f"[{name}]\n" + "".join(f"{k}={v}\n" for k, v in keys) + "\n"


def _var(name: str, title: str, datatype: str, access: str, default: str, *,
         pdo: str = "0") -> str:
    return _section(name, [("ParameterName", title), ("ObjectType", "0x7"),
                           ("DataType", datatype), ("AccessType", access),
                           ("DefaultValue", default), ("PDOMapping", pdo)])


def _head(name: str, title: str, object_type: str, subs: int) -> str:
    return _section(name, [("ParameterName", title), ("ObjectType", object_type),
                           ("SubNumber", hex(subs))])


def _pdo_mapping(index: str, kind: str) -> str:
    text = _head(index, f"{kind} mapping parameter", "0x9", 9)
    text += _var(f"{index}sub0", "Number of mapped application objects in PDO", "0x0005",
                 "rw", "0")
    for k in range(1, 9):
        text += _var(f"{index}sub{k}", f"Application object {k}", "0x0007", "rw",
                     "0x00000000")
    return text


def canopend_eds() -> str:
    """The EDS text of canopend's dictionary (no manufacturer objects; 0x1003 of 16)."""
    u8, u16, u32 = "0x0005", "0x0006", "0x0007"
    text = ("[FileInfo]\nFileName=DS301_profile.eds\nEDSVersion=4.0\n\n[DeviceInfo]\n"
            "ProductName=New Product\nNrOfRXPDO=4\nNrOfTXPDO=4\nLSS_Supported=1\n\n"
            "[MandatoryObjects]\nSupportedObjects=3\n1=0x1000\n2=0x1001\n3=0x1018\n\n")
    text += _var("1000", "Device type", u32, "ro", "0x00000000")
    text += _var("1001", "Error register", u8, "ro", "0x00", pdo="1")
    text += _head("1018", "Identity", "0x9", 5)
    text += _var("1018sub0", "Highest sub-index supported", u8, "ro", "0x04")
    for sub, title in enumerate(("Vendor-ID", "Product code", "Revision number",
                                 "Serial number"), 1):
        text += _var(f"1018sub{sub}", title, u32, "ro", "0x00000000")
    optional = [0x1003, 0x1005, 0x1006, 0x1007, 0x1010, 0x1011, 0x1012, 0x1014, 0x1015,
                0x1016, 0x1017, 0x1019, 0x1200, 0x1280, *range(0x1400, 0x1404),
                *range(0x1600, 0x1604), *range(0x1800, 0x1804), *range(0x1A00, 0x1A04)]
    text += (f"[OptionalObjects]\nSupportedObjects={len(optional)}\n"
             + "".join(f"{n}=0x{i:04X}\n" for n, i in enumerate(optional, 1)) + "\n")
    text += _head("1003", "Pre-defined error field", "0x8", 0x11)
    text += _var("1003sub0", "Number of errors", u8, "rw", "")
    for sub in range(1, 17):
        text += _var(f"1003sub{sub:X}", "Standard error field", u32, "ro", "")
    text += _var("1005", "COB-ID SYNC message", u32, "rw", "0x00000080")
    text += _var("1006", "Communication cycle period", u32, "rw", "0")
    text += _var("1007", "Synchronous window length", u32, "rw", "0")
    for index, verb, what in (("1010", "Save", "Store parameters"),
                              ("1011", "Restore", "Restore default parameters")):
        text += _head(index, what, "0x8", 5)
        text += _var(f"{index}sub0", "Highest sub-index supported", u8, "ro", "0x04")
        for sub, group in enumerate(("all", "communication", "application",
                                     "manufacturer defined"), 1):
            text += _var(f"{index}sub{sub}", f"{verb} {group} parameters", u32, "rw",
                         "0x00000001")
    text += _var("1012", "COB-ID time stamp object", u32, "rw", "0x00000100")
    text += _var("1014", "COB-ID EMCY", u32, "rw", "0x80+$NODEID")
    text += _var("1015", "Inhibit time EMCY", u16, "rw", "0")
    text += _head("1016", "Consumer heartbeat time", "0x8", 9)
    text += _var("1016sub0", "Highest sub-index supported", u8, "ro", "0x08")
    for sub in range(1, 9):
        text += _var(f"1016sub{sub}", "Consumer heartbeat time", u32, "rw", "0x00000000")
    text += _var("1017", "Producer heartbeat time", u16, "rw", "0")
    text += _var("1019", "Synchronous counter overflow value", u8, "rw", "0")
    text += _head("1200", "SDO server parameter", "0x9", 3)
    text += _var("1200sub0", "Highest sub-index supported", u8, "ro", "2")
    text += _var("1200sub1", "COB-ID client to server (rx)", u32, "ro", "0x600+$NODEID", pdo="1")
    text += _var("1200sub2", "COB-ID server to client (tx)", u32, "ro", "0x580+$NODEID", pdo="1")
    text += _head("1280", "SDO client parameter", "0x9", 4)
    text += _var("1280sub0", "Highest sub-index supported", u8, "ro", "0x03")
    text += _var("1280sub1", "COB-ID client to server (tx)", u32, "rw", "0x80000000", pdo="1")
    text += _var("1280sub2", "COB-ID server to client (rx)", u32, "rw", "0x80000000", pdo="1")
    text += _var("1280sub3", "Node-ID of the SDO server", u8, "rw", "0x01")
    for i in range(4):
        index = f"140{i}"
        text += _head(index, "RPDO communication parameter", "0x9", 4)
        text += _var(f"{index}sub0", "Highest sub-index supported", u8, "ro", "0x05")
        text += _var(f"{index}sub1", "COB-ID used by RPDO", u32, "rw",
                     f"0x80000{i + 2}00+$NODEID")
        text += _var(f"{index}sub2", "Transmission type", u8, "rw", "254")
        text += _var(f"{index}sub5", "Event timer", u16, "rw", "0")
    for i in range(4):
        text += _pdo_mapping(f"160{i}", "RPDO")
    for i in range(4):
        index = f"180{i}"
        text += _head(index, "TPDO communication parameter", "0x9", 6)
        text += _var(f"{index}sub0", "Highest sub-index supported", u8, "ro", "0x06")
        text += _var(f"{index}sub1", "COB-ID used by TPDO", u32, "rw",
                     f"0xC0000{i + 1}80+$NODEID")
        text += _var(f"{index}sub2", "Transmission type", u8, "rw", "254")
        text += _var(f"{index}sub3", "Inhibit time", u16, "rw", "0")
        text += _var(f"{index}sub5", "Event timer", u16, "rw", "0")
        text += _var(f"{index}sub6", "SYNC start value", u8, "rw", "0")
    for i in range(4):
        text += _pdo_mapping(f"1A0{i}", "TPDO")
    return text
