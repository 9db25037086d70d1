# SPDX-License-Identifier: Apache-2.0
"""The node table of ``canola view``: every node heard, from decoded frames.

Per node: NMT state (heartbeat, boot-up, guarding answers), name (0x1008 when an SDO upload
of it went by, else the ProductName of its EDS), identity (0x1018 sub 1..4 as uploaded),
heartbeat period (measured between the last two, and 0x1017 as written by SDO), boot-ups
counted, time last seen, and whether it went silent: a node that sent heartbeats is lost
when none came for three of its periods (at least :data:`LOST_AFTER_MIN_S`).
:meth:`NodeTable.feed` and :meth:`NodeTable.check` return what changed as log entries.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from canola.decode import STATE_NAMES, Event
from canola.nodedicts import NodeDictionaries

__all__ = ["LOST_AFTER_MIN_S", "NodeTable"]

#: A node is never called lost sooner than this after its last heartbeat (seconds): a
#: loaded machine delivers late, and a short period alone should not flap the mark.
LOST_AFTER_MIN_S = 1.0

_IDENTITY = {1: "vendor", 2: "product", 3: "revision", 4: "serial"}
#: Where an NMT command puts a node (a reset: unknown until its boot-up).
_NMT_STATES = {"start": "OPERATIONAL", "stop": "STOPPED", "preop": "PRE-OPERATIONAL"}

Note = tuple[str, int, str]  # kind, node, text: one entry for the event log


@dataclass
class _Node:
    node: int
    first_seen: float
    last_seen: float
    state: str = "?"
    state_by: str = ""  # heartbeat, boot-up, guard (answers), NMT (a command it was sent)
    name: str = ""
    name_from: str = ""
    identity: dict[str, int] = field(default_factory=dict)
    last_heartbeat: float | None = None
    period_s: float | None = None
    configured_ms: int | None = None
    bootups: int = 0
    lost: bool = False
    emcys: int = 0


class NodeTable:
    def __init__(self, dictionaries: NodeDictionaries | None = None) -> None:
        self._dicts = dictionaries or NodeDictionaries()
        self._nodes: dict[int, _Node] = {}

    def _node(self, node: int, t: float) -> _Node:
        n = self._nodes.get(node)
        if n is None:
            n = self._nodes[node] = _Node(node, t, t)
            od = self._dicts.get(node)
            product = None if od is None else od.device_info.get("ProductName")
            if product:
                n.name, n.name_from = product, "EDS"
        return n

    def feed(self, t: float, event: Event, from_node: bool) -> list[Note]:
        """Take one decoded frame; ``from_node``: the node sent it (not a request to it)."""
        if event.kind == "nmt":
            return self._nmt(event)
        if event.node is None or event.kind in ("lss", "unknown"):
            return []
        n = self._node(event.node, t)
        if from_node:
            n.last_seen = t
        notes: list[Note] = []
        if event.kind == "bootup":  # then in pre-operational (CiA 301 7.3.2.2)
            n.bootups += 1
            n.last_heartbeat, n.period_s = t, None
            notes.append(("bootup", n.node, f"node {n.node} boot-up (#{n.bootups})"))
            notes += self._state(n, "PRE-OPERATIONAL", "boot-up")
            n.lost = False
        elif event.kind in ("heartbeat", "guard") and "state" in event.fields:
            if event.kind == "heartbeat":
                if n.last_heartbeat is not None:
                    n.period_s = t - n.last_heartbeat
                n.last_heartbeat = t
            state = event.fields["state"]
            notes += self._state(n, STATE_NAMES.get(state, f"0x{state:02X}"), event.kind)
            if n.lost:
                n.lost = False
                notes.append(("heartbeat", n.node, f"node {n.node} heard again ({n.state})"))
        elif event.kind == "emcy":
            n.emcys += 1
        elif event.kind == "sdo" and "value" in event.fields:
            self._sdo_value(n, event)
        return notes

    def _state(self, n: _Node, state: str, by: str) -> list[Note]:
        n.state_by = by
        if state == n.state:
            return []
        before, n.state = n.state, state
        how = " (NMT command; it sends no heartbeat)" if by == "NMT" else ""
        if before == "?":
            return [("state", n.node, f"node {n.node} is {state}{how}")]
        return [("state", n.node, f"node {n.node} {before} -> {state}{how}")]

    def _nmt(self, event: Event) -> list[Note]:
        """A node that sends no heartbeat is taken to be where an NMT command puts it."""
        state = _NMT_STATES.get(str(event.fields.get("command")))
        target = event.fields.get("target")
        notes: list[Note] = []
        for n in self._nodes.values():
            if target in (0, n.node) and n.period_s is None:
                notes += self._state(n, state or "?", "NMT")
        return notes

    def _sdo_value(self, n: _Node, event: Event) -> None:
        index, sub = event.fields.get("index"), event.fields.get("sub")
        data = bytes.fromhex(event.fields["value"])
        upload = event.text.startswith(("SDO upload", "SDO block upload"))
        if upload and index == 0x1008 and sub == 0 and data:
            n.name, n.name_from = data.split(b"\0")[0].decode("latin-1"), "0x1008"
        elif upload and index == 0x1018 and sub in _IDENTITY and len(data) == 4:
            n.identity[_IDENTITY[sub]] = int.from_bytes(data, "little")
        elif not upload and index == 0x1017 and sub == 0 and len(data) == 2:
            n.configured_ms = int.from_bytes(data, "little")

    def check(self, now: float) -> list[Note]:
        """Mark the nodes whose heartbeat stopped (once each)."""
        notes: list[Note] = []
        for n in self._nodes.values():
            if n.lost or n.last_heartbeat is None or n.state == "?":
                continue
            period = n.period_s or (n.configured_ms or 0) / 1000
            if period <= 0:
                continue
            if now - n.last_heartbeat > max(3 * period, LOST_AFTER_MIN_S):
                n.lost = True
                notes.append(("heartbeat", n.node,
                              f"node {n.node} heartbeat lost: silent for "
                              f"{now - n.last_heartbeat:.1f} s (period {period * 1000:.0f} ms), "
                              f"last state {n.state}"))
        return notes

    def rows(self, now: float) -> list[dict[str, Any]]:
        return [{
            "node": n.node, "state": n.state, "state_by": n.state_by, "name": n.name,
            "name_from": n.name_from,
            "identity": dict(n.identity), "bootups": n.bootups, "lost": n.lost,
            "period_ms": None if n.period_s is None else round(n.period_s * 1000, 1),
            "configured_ms": n.configured_ms, "emcys": n.emcys,
            "seen_ago_s": round(now - n.last_seen, 2),
            "heartbeat_ago_s": None if n.last_heartbeat is None
            else round(now - n.last_heartbeat, 2),
        } for _, n in sorted(self._nodes.items())]
