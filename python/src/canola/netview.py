# SPDX-License-Identifier: Apache-2.0
"""What a monitor knows about every node, from decoded frames (:mod:`canola.decode`).

:class:`NetworkView` is fed frames with their time and keeps, per node: NMT state, time of
the last heartbeat (and the gap between the last two), the last EMCY, and per PDO the count
of frames, their rate over the last ``window`` seconds and, when the decoder knows its
mapping (an EDS/DCF), the last values. :meth:`NetworkView.rows` gives a
snapshot as plain data; :func:`render` makes the text table of ``canola monitor``.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass, field
from typing import Any

from canola.decode import STATE_NAMES, Decoder, Event

__all__ = ["NetworkView", "NodeView", "render"]


@dataclass
class NodeView:
    node: int
    state: str = "?"
    last_heartbeat: float | None = None
    heartbeat_gap: float | None = None
    last_emcy: str = ""
    emcy_count: int = 0
    pdos: dict[str, deque[float]] = field(default_factory=dict)
    pdo_total: dict[str, int] = field(default_factory=dict)
    pdo_values: dict[str, Any] = field(default_factory=dict)  # entry name -> last value
    pdo_text: dict[str, str] = field(default_factory=dict)  # PDO -> its last decoded line


class NetworkView:
    def __init__(self, window: float = 5.0, decoder: Decoder | None = None) -> None:
        self.window = window
        self.decoder = decoder or Decoder()
        self.nodes: dict[int, NodeView] = {}
        self.frames = 0

    def feed(self, t: float, can_id: int, data: bytes, *, rtr: bool = False,
             extended: bool = False) -> Event:
        event = self.decoder.decode(can_id, data, rtr=rtr, extended=extended)
        self.frames += 1
        node = event.node
        if node is None or event.kind in ("nmt",):
            return event
        view = self.nodes.setdefault(node, NodeView(node))
        if event.kind in ("heartbeat", "bootup", "guard") and "state" in event.fields:
            view.state = STATE_NAMES.get(event.fields["state"], f"0x{event.fields['state']:02X}")
            if view.last_heartbeat is not None:
                view.heartbeat_gap = t - view.last_heartbeat
            view.last_heartbeat = t
        elif event.kind == "emcy":
            view.emcy_count += 1
            view.last_emcy = event.text.removeprefix(f"EMCY node {node} ")
        elif event.kind == "pdo":
            name = str(event.fields.get("pdo", "PDO"))
            times = view.pdos.setdefault(name, deque())
            times.append(t)
            view.pdo_total[name] = view.pdo_total.get(name, 0) + 1
            if "values" in event.fields:  # decoded by its mapping
                view.pdo_values.update(event.fields["values"])
                view.pdo_text[name] = event.text.removeprefix(f"{name} node {node} ")
        return event

    def rows(self, now: float) -> list[dict[str, Any]]:
        out = []
        for node in sorted(self.nodes):
            v = self.nodes[node]
            rates = {}
            for name, times in sorted(v.pdos.items()):
                while times and times[0] < now - self.window:
                    times.popleft()
                rates[name] = round(len(times) / self.window, 2)
            out.append({
                "node": node, "state": v.state,
                "heartbeat_age": None if v.last_heartbeat is None
                else round(now - v.last_heartbeat, 3),
                "heartbeat_gap": None if v.heartbeat_gap is None
                else round(v.heartbeat_gap, 3),
                "last_emcy": v.last_emcy, "emcy_count": v.emcy_count,
                "pdo_rate": rates, "pdo_total": dict(sorted(v.pdo_total.items())),
                "pdo_values": dict(v.pdo_values),
                "pdo_text": dict(sorted(v.pdo_text.items())),
            })
        return out


def render(rows: list[dict[str, Any]], frames: int) -> str:
    lines = [f"{'node':>4}  {'state':<15}  {'hb age':>7}  {'last EMCY':<36}  PDO/s",
             "-" * 80]
    for r in rows:
        age = "-" if r["heartbeat_age"] is None else f"{r['heartbeat_age']:.1f}s"
        pdo = " ".join(f"{k}:{v:g}" for k, v in r["pdo_rate"].items()) or "-"
        emcy = r["last_emcy"].split(",")[0] or "-"  # code and meaning; in full below
        if r["emcy_count"] > 1:
            emcy += f" (x{r['emcy_count']})"
        lines.append(f"{r['node']:>4}  {r['state']:<15}  {age:>7}  {emcy[:36]:<36}  {pdo}")
        if r["last_emcy"]:
            lines.append(f"{'':6}EMCY: {r['last_emcy']}")
        lines.extend(f"{'':6}{name}: {text}" for name, text in r.get("pdo_text", {}).items())
    if not rows:
        lines.append("  (no node seen)")
    lines.append(f"{frames} frame(s)")
    return "\n".join(lines)
