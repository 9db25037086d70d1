# SPDX-License-Identifier: Apache-2.0
"""What the demo's nodes report while it runs: the master's boot-up, heartbeat and EMCY
events, the CANopen manager's reports and the TPDOs it receives (kept for the checks), the
RPDO values the devices apply, all turned into lines of the trace at the time they happened.

Callbacks run in the nodes' bus threads on python-can, so the data is kept under a lock and
the lines wait in a queue until :meth:`Observer.tick` prints them, in time order with the
frames seen on the bus.
"""

from __future__ import annotations

import threading
from collections import deque
from dataclasses import dataclass, field

from canola.decode import emcy_text
from canola.demo.devices import DEVICES, DeviceSpec, unpack
from canola.demo.network import Network, TraceFrame
from canola.demo.trace import Trace
from canola.device import Device
from canola.manager import BootEvent
from canola.master import EmcyEvent, Frame, HeartbeatEvent, Master

__all__ = ["Observer", "Seen"]

_Note = tuple[float, str, str]


@dataclass
class Seen:
    """What the master's callbacks saw."""

    bootups: set[int] = field(default_factory=set)
    heartbeat: list[HeartbeatEvent] = field(default_factory=list)
    emcy: list[EmcyEvent] = field(default_factory=list)
    tpdos: dict[int, list[bytes]] = field(default_factory=dict)


class Observer:
    """Watches ``master`` and the devices for the trace on ``net``."""

    def __init__(self, net: Network, trace: Trace) -> None:
        self.net = net
        self.trace = trace
        self.specs = {spec.node_id: spec for spec in DEVICES}
        self.lock = threading.Lock()
        self.seen = Seen()
        self.mapped = False  # PDO payloads are decoded once the master mapped them
        self._notes: deque[_Note] = deque()
        trace.annotate = self._annotate

    def name(self, node: int) -> str:
        spec = self.specs.get(node)
        return f"node {node} ({spec.role})" if spec else f"node {node}"

    def note(self, who: str, text: str) -> None:
        """A line for the trace, shown at the next tick (any thread)."""
        self._notes.append((self.net.now(), who, text))

    def say(self, who: str, text: str) -> None:
        """A line of the scenario itself, after what happened so far."""
        self.tick()
        self.trace.note(self.net.now(), who, text)

    def tick(self) -> None:
        """Show the frames and the lines since the last tick, in time order."""
        items: list[tuple[float, int, TraceFrame | _Note]] = [
            (f.t, 0, f) for f in self.net.drain()]
        while self._notes:
            note = self._notes.popleft()
            items.append((note[0], 1, note))
        for _, _, item in sorted(items, key=lambda i: (i[0], i[1])):
            if isinstance(item, TraceFrame):
                self.trace.frame(item)
            else:
                self.trace.note(*item)

    # ---- the master

    def manager_event(self, ev: BootEvent) -> None:
        """A report of the CANopen manager (its ``on_event``)."""
        if ev.kind == "network-started":
            text = "network started"
        elif ev.kind == "network-halted":
            text = f"network halted: mandatory {self.name(ev.node)} failed"
        else:
            text = f"{self.name(ev.node)} {ev.kind}"
            detail = str(ev).split(f": {ev.kind}", 1)[1]
            if detail:
                text += detail
        self.note("manager", text)

    def watch_master(self, master: Master) -> None:
        seen = self.seen

        def bootup(node: int) -> None:
            with self.lock:
                seen.bootups.add(node)
            self.note("master", f"boot-up of {self.name(node)}")

        def heartbeat(ev: HeartbeatEvent) -> None:
            with self.lock:
                seen.heartbeat.append(ev)
            if ev.kind == "lost":
                text = f"HEARTBEAT LOST of {self.name(ev.node)} (last state {ev.state})"
            elif ev.kind == "started":
                text = f"heartbeat of {self.name(ev.node)} monitored, {ev.state}"
            else:
                text = f"{self.name(ev.node)} heartbeat {ev.kind}: {ev.state}"
            self.note("master", text)

        def emcy(ev: EmcyEvent) -> None:
            with self.lock:
                seen.emcy.append(ev)
            self.note("master", f"EMCY from {self.name(ev.node)}: 0x{ev.code:04X} "
                      f"{emcy_text(ev.code)}, error register 0x{ev.register:02X}")

        def tpdo(frame: Frame) -> None:
            with self.lock:
                seen.tpdos.setdefault(frame.can_id - 0x180, []).append(frame.data)

        master.on_bootup(bootup)
        master.on_heartbeat(heartbeat)
        master.on_emcy(emcy)
        for node in self.specs:
            master.on_frame(tpdo, cob_id=0x180 + node)

    def bootups(self) -> set[int]:
        with self.lock:
            return set(self.seen.bootups)

    def heartbeat_events(self, since: int = 0) -> list[HeartbeatEvent]:
        with self.lock:
            return self.seen.heartbeat[since:]

    def emcys(self, since: int = 0) -> list[EmcyEvent]:
        with self.lock:
            return self.seen.emcy[since:]

    def tpdo_counts(self) -> dict[int, int]:
        with self.lock:
            return {n: len(self.seen.tpdos.get(n, [])) for n in self.specs}

    def last_tpdo(self, node: int) -> dict[str, int]:
        """The last TPDO of ``node`` the master received, by mapped name ({} if none)."""
        with self.lock:
            frames = self.seen.tpdos.get(node, [])
            data = frames[-1] if frames else b""
        return unpack(self.specs[node].tpdo, data) or {}

    # ---- the devices

    def watch_device(self, spec: DeviceSpec, dev: Device) -> None:
        """A line whenever the network changes an object of ``spec``'s RPDO."""
        mapped = {(m.index, m.sub): m for m in spec.rpdo}
        last: dict[tuple[int, int], object] = {}

        def written(index: int, sub: int, value: object) -> None:
            m = mapped.get((index, sub))
            if m is None or last.get((index, sub), 0) == value:
                return
            was = last.get((index, sub), 0)
            last[index, sub] = value
            shown = (f"0x{value:04X}" if m.name == "controlword" and isinstance(value, int)
                     else str(value))
            self.note(self.name(spec.node_id),
                      f"RPDO applied: 0x{index:04X}:{sub:02X} {m.name} = {shown} (was {was})")

        dev.on_write(written)

    def _annotate(self, can_id: int, data: bytes) -> str | None:
        if not self.mapped:
            return None
        node, base = can_id & 0x7F, can_id & 0x780
        spec = self.specs.get(node)
        if spec is None or base not in (0x180, 0x200):
            return None
        values = unpack(spec.tpdo if base == 0x180 else spec.rpdo, data)
        if values is None:
            return None
        return ", ".join(f"{k} 0x{v:04X}" if k in ("statusword", "controlword")
                         else f"{k} 0x{v:02X}" if k in ("inputs", "outputs")
                         else f"{k} {v / 100:.2f} degC" if k == "temperature"
                         else f"{k} {v}" for k, v in values.items())
