# SPDX-License-Identifier: Apache-2.0
"""Waits on another process that end: a dead or silent process fails the test, never hangs
it (a forked device that died once left ``readline()`` waiting for 28 minutes).

- :func:`first_line`: the first line a process writes to a pipe, within a time;
- :class:`Lines`: every line of a pipe, read by a thread of its own, each within a time.
"""

from __future__ import annotations

import queue
import select
import threading
from typing import IO


def first_line(stream: IO[str] | None, what: str, timeout: float = 60.0) -> str:
    """The first line on ``stream`` (a pipe nothing was read from yet) within ``timeout``
    seconds; an AssertionError naming ``what`` when nothing came ("" at its end)."""
    assert stream is not None, what
    ready, _, _ = select.select([stream], [], [], timeout)
    assert ready, f"{what}: nothing within {timeout:g} s"
    return stream.readline()  # a line is written whole: its end follows at once


class Lines:
    """The lines of ``stream``, read as they come by a daemon thread (which also keeps the
    writer from blocking on a full pipe)."""

    def __init__(self, stream: IO[str] | None, what: str) -> None:
        assert stream is not None, what
        self.what = what
        self._lines: queue.Queue[str] = queue.Queue()
        threading.Thread(target=self._read, args=(stream,), daemon=True).start()

    def _read(self, stream: IO[str]) -> None:
        try:
            for line in stream:
                self._lines.put(line)
        except (OSError, ValueError):  # closed under the thread: the end as well
            pass
        self._lines.put("")

    def line(self, timeout: float = 60.0) -> str:
        """The next line ("" at the end of the stream) within ``timeout`` seconds."""
        try:
            return self._lines.get(timeout=timeout)
        except queue.Empty:
            raise AssertionError(f"{self.what}: no line within {timeout:g} s") from None
