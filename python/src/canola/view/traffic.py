# SPDX-License-Identifier: Apache-2.0
"""The bus as ``canola view`` shows it: load, frames per second by COB-ID group, and the
last frames for the candump-style list.

Load is the bits of the frames of the last second over the bit rate given (the bus does not
tell it): a data frame is 47 bits plus 8 per data byte with an 11-bit identifier, 67 plus 8
with a 29-bit one, stuff bits left out (they add up to about a fifth more), so the figure
is a lower bound.
"""

from __future__ import annotations

from collections import deque
from typing import Any

from canola.view.ring import Ring

__all__ = ["GROUPS", "Traffic"]

#: The decoder's event kinds, grouped as the page counts them.
GROUPS: dict[str, str] = {
    "nmt": "NMT", "sync": "SYNC", "emcy": "EMCY", "time": "TIME", "pdo": "PDO",
    "sdo": "SDO", "heartbeat": "error control", "bootup": "error control",
    "guard": "error control", "lss": "LSS", "unknown": "other",
}

#: How long the rates are averaged over (seconds).
RATE_WINDOW_S = 2.0


class Traffic:
    def __init__(self, bitrate: int, raw_frames: int = 2000) -> None:
        self.bitrate = bitrate
        self.total = 0
        self.raw: Ring[list[Any]] = Ring(raw_frames)
        self._recent: deque[tuple[float, str, int]] = deque()  # (time, group, bits)

    def feed(self, t: float, can_id: int, data: bytes, *, rtr: bool, extended: bool,
             kind: str, node: int | None, text: str) -> None:
        self.total += 1
        bits = (67 if extended else 47) + (0 if rtr else 8 * len(data))
        self._recent.append((t, GROUPS.get(kind, "other"), bits))
        self.raw.add([round(t, 6), can_id, "R" if rtr else data.hex().upper(), extended,
                      kind, node, text])

    def stats(self, now: float) -> dict[str, Any]:
        recent = self._recent
        while recent and recent[0][0] < now - RATE_WINDOW_S:
            recent.popleft()
        fps: dict[str, float] = {}
        bits = 0
        for _, group, n in recent:
            fps[group] = fps.get(group, 0) + 1 / RATE_WINDOW_S
            bits += n
        return {"total": self.total, "bitrate": self.bitrate,
                "load_pct": round(100 * bits / RATE_WINDOW_S / self.bitrate, 2),
                "fps": {g: round(v, 1) for g, v in sorted(fps.items())},
                "fps_all": round(len(recent) / RATE_WINDOW_S, 1)}
