# SPDX-License-Identifier: Apache-2.0
"""A transfer progress bar on stderr, fed from the SDO server's frames.

The master's SDO client does not report progress, so :class:`SdoProgress` watches the
server's answers (COB-ID 0x580 + node, via ``Master.on_frame``): the size announced by an
initiate response, then 7 bytes per upload segment or, for a block download, 7 bytes per
sub-block frame the server acknowledges. Only drawn when enabled (a terminal, or
``--progress``), at most ten times a second. :class:`ProgressLine` and :func:`bar_text` are
what it shares with ``canola flash``'s bar.
"""

from __future__ import annotations

import abc
import sys
import threading
import time
from typing import Any, TextIO

__all__ = ["ProgressLine", "SdoProgress", "bar_text"]


def bar_text(done: int, total: int, rate: float) -> str:
    """``[#####     ]  52.0% 53248/102400 B 11.2 kB/s`` (``rate`` in kB/s; a total of 0 is
    100%)."""
    share = done / total if total else 1.0
    return (f"[{'#' * int(share * 30):<30}] {share * 100:5.1f}% {done}/{total} B "
            f"{rate:.1f} kB/s")


class ProgressLine(abc.ABC):
    """One line of progress on ``stream`` (stderr by default), drawn only when ``enabled``,
    at most ten times a second unless forced; a subclass says what the line reads."""

    def __init__(self, *, enabled: bool, stream: TextIO | None = None) -> None:
        self.done = 0
        self.enabled = enabled
        self.stream = stream if stream is not None else sys.stderr
        self._started = time.monotonic()
        self._drawn = 0.0

    @abc.abstractmethod
    def _text(self, rate: float) -> str:
        """The line for ``self.done`` bytes at ``rate`` kB/s."""
        raise NotImplementedError

    def _draw(self, *, force: bool) -> None:
        now = time.monotonic()
        if not self.enabled or (not force and now - self._drawn < 0.1):
            return
        self._drawn = now
        rate = self.done / max(now - self._started, 1e-6) / 1000
        self.stream.write("\r" + self._text(rate))
        self.stream.flush()

    def _end(self) -> None:
        """The last draw and the end of the line (when enabled)."""
        self._draw(force=True)
        if self.enabled:
            self.stream.write("\n")
            self.stream.flush()


class SdoProgress(ProgressLine):
    def __init__(self, *, upload: bool, total: int | None, enabled: bool,
                 stream: TextIO | None = None) -> None:
        super().__init__(enabled=enabled, stream=stream)
        self.upload = upload
        self.total = total
        self._answered = False
        self._lock = threading.Lock()

    def frame(self, frame: Any) -> None:
        """``Master.on_frame`` callback for COB-ID 0x580 + node."""
        data: bytes = frame.data
        if len(data) != 8:
            return
        cmd = data[0]
        with self._lock:
            first = not self._answered
            self._answered = True
            if self.upload:
                if first:  # initiate response: block (0xC6/0xC4) or segmented (0x41/0x45)
                    if (cmd & 0xE3 == 0xC2) or (cmd & 0xE3 == 0x41):
                        self.total = int.from_bytes(data[4:8], "little")
                else:  # segments (the block end frame is capped below)
                    self.done += 7
            elif cmd == 0xA2:  # block download: sub-block acknowledged
                self.done += 7 * data[1]
            elif cmd & 0xE0 == 0x20:  # segmented download: segment acknowledged
                self.done += 7
            if self.total is not None:
                self.done = min(self.done, self.total)
            self._draw(force=False)

    def finish(self) -> None:
        with self._lock:
            if self.total is not None:
                self.done = self.total
            self._end()

    def _text(self, rate: float) -> str:
        if self.total:
            return bar_text(self.done, self.total, rate)
        return f"{self.done} B {rate:.1f} kB/s"
