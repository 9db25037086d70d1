# SPDX-License-Identifier: Apache-2.0
"""What ``canola view`` knows about the bus: every frame decoded once
(:class:`canola.decode.Decoder`) into the node table, the event log, the PDO signals and
the traffic figures, and what each open page has not been sent yet.

The bus thread feeds frames (:meth:`BusModel.feed`), the server reads
(:meth:`BusModel.update`); one lock keeps them apart. Per page a :class:`Cursor` says what
it has; an update carries at most :data:`LIMITS` of each kind, and says how many it left
out: the page keeps up at any frame rate because it is sent a bounded amount, not every
frame.
"""

from __future__ import annotations

import threading
from dataclasses import dataclass, field
from typing import Any

from canola.decode import Decoder, Event
from canola.nodedicts import NodeDictionaries
from canola.view.nodes import NodeTable
from canola.view.ring import Ring
from canola.view.signals import SignalStore
from canola.view.traffic import Traffic

__all__ = ["LIMITS", "BusModel", "Cursor"]

#: Most of each kind one update carries to a page (updates go out several times a second).
LIMITS = {"events": 500, "frames": 250, "points": 200}

#: Function codes of the frames a node sends (EMCY, TPDO1..4, SDO response, error control).
_FROM_NODE = frozenset({0x080, 0x180, 0x280, 0x380, 0x480, 0x580, 0x700})


@dataclass
class Cursor:
    """What one page has been sent."""

    events: int = 0
    frames: int = 0
    points: dict[str, int] = field(default_factory=dict)
    signal_version: int = -1


class BusModel:
    def __init__(self, decoder: Decoder | None = None,
                 dictionaries: NodeDictionaries | None = None, *, bitrate: int = 500_000,
                 events: int = 5000, raw_frames: int = 2000) -> None:
        self.lock = threading.Lock()
        self.dictionaries = dictionaries or NodeDictionaries()
        self.decoder = decoder or Decoder(self.dictionaries)
        self.nodes = NodeTable(self.dictionaries)
        self.events: Ring[list[Any]] = Ring(events)
        self.signals = SignalStore()
        self.traffic = Traffic(bitrate, raw_frames)
        self.bus_state = "waiting for the bus"

    def note(self, t: float, kind: str, node: int | None, text: str) -> None:
        """An entry of the event log (under the lock)."""
        self.events.add([round(t, 6), kind, node, text])

    def feed(self, t: float, can_id: int, data: bytes, *, rtr: bool = False,
             extended: bool = False) -> Event:
        """One frame received at time ``t`` (seconds since the epoch); takes the lock."""
        with self.lock:
            event = self.decoder.decode(can_id, data, rtr=rtr, extended=extended)
            self.traffic.feed(t, can_id, data, rtr=rtr, extended=extended, kind=event.kind,
                              node=event.node, text=event.text)
            if event.kind == "nmt":  # before what it does to the node table
                self.note(t, "nmt", event.node, event.text)
            from_node = not extended and (can_id & 0x780) in _FROM_NODE
            for kind, node, text in self.nodes.feed(t, event, from_node):
                self.note(t, kind, node, text)
            if event.kind == "emcy":
                self.note(t, "emcy", event.node, event.text)
            elif event.kind == "sdo" and "abort" in event.fields:
                self.note(t, "sdo", event.node, event.text)
            elif event.kind == "pdo" and "values" in event.fields and event.node is not None:
                mapped = self.decoder.pdo_of(can_id)
                if mapped is not None:
                    self.signals.feed(t, event.node, mapped[1], event.fields["values"],
                                      self.dictionaries.get(mapped[0]))
        return event

    def check(self, now: float) -> None:
        """Time-based changes: nodes whose heartbeat stopped."""
        with self.lock:
            for kind, node, text in self.nodes.check(now):
                self.note(now, kind, node, text)

    def update(self, cursor: Cursor, now: float) -> dict[str, Any]:
        """What the page of ``cursor`` has not had yet (``cursor`` moves on), with the node
        table and the traffic figures as they are now."""
        with self.lock:
            events, cursor.events, events_left = self.events.since(cursor.events,
                                                                   LIMITS["events"])
            frames, cursor.frames, frames_left = self.traffic.raw.since(cursor.frames,
                                                                       LIMITS["frames"])
            points, points_left = self.signals.since(cursor.points, LIMITS["points"])
            out: dict[str, Any] = {
                "type": "update", "now": round(now, 3), "bus_state": self.bus_state,
                "nodes": self.nodes.rows(now), "traffic": self.traffic.stats(now),
                "events": events, "frames": frames, "points": points,
                "left_out": {"events": events_left, "frames": frames_left,
                             "points": points_left},
            }
            if cursor.signal_version != self.signals.version:
                cursor.signal_version = self.signals.version
                out["signals"] = [s.meta() for s in self.signals.signals.values()]
        return out
