# SPDX-License-Identifier: Apache-2.0
"""PDO signals over time for ``canola view``'s plots: each mapped entry of a decoded PDO
(number or boolean) is a signal, named by its mapping (the EDS/DCF's entry name, or the
name the mapping was given), with its unit when the EDS entry has one (``Unit=``, a key
some device files carry beyond CiA 306).

A reader takes the points added since its last look; more than ``limit`` of them are thinned
to every n-th point, the newest always kept (the page says how many it did not get).
"""

from __future__ import annotations

import itertools
from collections import deque
from dataclasses import dataclass
from typing import Any

from canola.formats.eds import ObjectDictionary
from canola.pdomap import Pdo

__all__ = ["Signal", "SignalStore"]


@dataclass
class Signal:
    id: str
    node: int
    pdo: str
    name: str
    unit: str
    points: deque[tuple[float, float]]
    added: int = 0  # points ever added: the sequence number of the newest

    def meta(self) -> dict[str, Any]:
        return {"id": self.id, "node": self.node, "pdo": self.pdo, "name": self.name,
                "unit": self.unit}


def _unit(od: ObjectDictionary | None, index: int, sub: int) -> str:
    obj = None if od is None else od.objects.get(index)
    var = None if obj is None else obj.subs.get(sub)
    if var is None:
        return ""
    for key, value in var.extra.items():
        if key.lower() == "unit":
            return value.strip()
    return ""


class SignalStore:
    def __init__(self, keep: int = 20000) -> None:
        self.keep = keep
        self.signals: dict[str, Signal] = {}
        self.version = 0  # changes when a signal is added (readers send the list again)

    def feed(self, t: float, node: int, pdo: Pdo, values: dict[str, Any],
             od: ObjectDictionary | None) -> None:
        for m in pdo.entries:
            value = values.get(m.name)
            if isinstance(value, bool):
                value = int(value)
            if not isinstance(value, int | float):
                continue
            key = f"{node}/{pdo.name}/{m.name}"
            sig = self.signals.get(key)
            if sig is None:
                sig = self.signals[key] = Signal(key, node, pdo.name, m.name,
                                                 _unit(od, m.index, m.sub),
                                                 deque(maxlen=self.keep))
                self.version += 1
            sig.points.append((round(t, 6), value))
            sig.added += 1

    def since(self, seen: dict[str, int], limit: int) -> tuple[dict[str, list[Any]], int]:
        """The points of every signal after the number in ``seen`` (updated), each thinned
        to at most ``limit``: ({id: [times, values]}, points left out)."""
        out: dict[str, list[Any]] = {}
        dropped = 0
        for key, sig in self.signals.items():
            new = min(sig.added - seen.get(key, 0), len(sig.points))
            seen[key] = sig.added
            if new <= 0:
                continue
            pts = list(itertools.islice(reversed(sig.points), new))[::-1]
            if len(pts) > limit:
                step = -(-len(pts) // limit)
                kept = pts[len(pts) - 1::-step][::-1]  # every step-th, counted from the newest
                dropped += len(pts) - len(kept)
                pts = kept
            out[key] = [[p[0] for p in pts], [p[1] for p in pts]]
        return out, dropped
