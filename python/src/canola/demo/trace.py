# SPDX-License-Identifier: Apache-2.0
"""The demo's trace: every frame decoded by :class:`canola.decode.Decoder`, the master's
reports and the devices' applications in between, one line each.

To keep the story readable, repetitions are left out unless ``every_frame``: a heartbeat
is shown when its node's state changes, SDO confirmations that carry nothing new (``ok``,
upload requests) are not shown, and once the first ``full_cycles`` SYNC cycles have been
shown, SYNCs are no longer shown and a PDO only when its data changed. The count of
frames not shown is in :attr:`Trace.hidden`.
"""

from __future__ import annotations

import sys
from collections.abc import Callable
from typing import TextIO

from canola.decode import Decoder, Event
from canola.demo.network import TraceFrame

__all__ = ["Trace"]

Annotate = Callable[[int, bytes], str | None]


class Trace:
    """Prints frames and notes to ``out`` (nothing when ``out`` is None)."""

    def __init__(self, out: TextIO | None = sys.stdout, *, every_frame: bool = False,
                 full_cycles: int = 3, annotate: Annotate | None = None) -> None:
        self.out = out
        self.every_frame = every_frame
        self.full_cycles = full_cycles
        self.annotate = annotate
        self.decoder = Decoder()
        self.master_id: int | None = None  # its boot-up/heartbeat: the master's online status
        self.frames = 0
        self.hidden = 0
        self.events: list[tuple[TraceFrame, Event]] = []
        self._syncs = 0
        self._last_data: dict[int, bytes] = {}
        self._hb_state: dict[int, int] = {}

    def _print(self, text: str) -> None:
        if self.out is not None:
            self.out.write(text + "\n")
            self.out.flush()

    def heading(self, text: str) -> None:
        self._print(f"\n== {text}")

    def note(self, t: float, who: str, text: str) -> None:
        """A line that is not a frame: a report of the master or of a device."""
        self._print(f"({t:10.6f}) {'':20} {who}: {text}")

    def frames_seen(self, frames: list[TraceFrame]) -> None:
        for frame in frames:
            self.frame(frame)

    def frame(self, frame: TraceFrame) -> None:
        self.frames += 1
        event = self.decoder.decode(frame.can_id, frame.data, rtr=frame.rtr)
        self.events.append((frame, event))
        if not self.every_frame and not self._shown(frame, event):
            self.hidden += 1
            return
        payload = "R" if frame.rtr else frame.data.hex().upper()
        text = event.text
        if event.kind in ("bootup", "heartbeat") and event.node == self.master_id:
            text += ": the master's online status"
        extra = self.annotate(frame.can_id, frame.data) if self.annotate else None
        if extra:
            text += f"  [{extra}]"
        self._print(f"({frame.t:10.6f}) {frame.can_id:03X}#{payload:<16} {text}")

    def _shown(self, frame: TraceFrame, event: Event) -> bool:
        if event.kind == "sync":
            self._syncs += 1
            return self._syncs <= self.full_cycles
        if event.kind == "heartbeat" and event.node is not None:
            state = frame.data[0] if frame.data else -1
            changed = self._hb_state.get(event.node) != state
            self._hb_state[event.node] = state
            return changed
        if event.kind == "bootup" and event.node is not None:
            self._hb_state[event.node] = 0
            return True
        if event.kind == "sdo":
            return not (event.text.split(" (node")[0].endswith((" ok", " request"))
                        and "abort" not in event.text)
        if event.kind == "pdo":
            changed = self._last_data.get(frame.can_id) != frame.data
            self._last_data[frame.can_id] = frame.data
            return changed or self._syncs <= self.full_cycles
        return True
