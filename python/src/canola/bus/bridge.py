# SPDX-License-Identifier: Apache-2.0
"""Two buses joined: every frame received on one is sent on the other (``canola bus bridge``).

Its use: a serial SLCAN adapter, or the UART of canola's firmware images in QEMU
(``slcan://HOST:PORT``, QEMU's ``-serial tcp:``), joined to a channel of the ``canola bus
serve`` hub, so that every canola command, the gateway and python-canopen (python-can's
socketcand interface) reach the device behind it.

One thread per direction, each waiting at most ``poll`` seconds at a time. The bridge ends
when :meth:`Bridge.stop` is called or a side fails or is closed by its far end (a QEMU
that exited, a hub that stopped); :attr:`Bridge.error` then says which, in one line.
Neither side echoes a frame to its sender, so nothing circulates.
"""

from __future__ import annotations

import contextlib
import threading
from dataclasses import dataclass

import can

from canola.bus.open import connection_lost

__all__ = ["Bridge", "BridgeSide", "shutdown"]


@dataclass
class BridgeSide:
    """One side: the bus, its name for messages, and the frames taken from it."""

    bus: can.BusABC
    name: str
    frames: int = 0


class Bridge:
    """Joins ``a`` and ``b`` once :meth:`start` is called (``with Bridge(...) as bridge``)."""

    def __init__(self, a: BridgeSide, b: BridgeSide, poll: float = 0.1) -> None:
        self.sides = (a, b)
        self._poll = poll
        self._stop = threading.Event()
        self._lock = threading.Lock()
        #: Why the bridge ended by itself (None: it runs, or stop() ended it).
        self.error: str | None = None
        self._threads = [threading.Thread(target=self._carry, args=(src, dst), daemon=True,
                                          name=f"canola-bridge-{src.name}")
                         for src, dst in ((a, b), (b, a))]

    def start(self) -> Bridge:
        for thread in self._threads:
            thread.start()
        return self

    @property
    def running(self) -> bool:
        return not self._stop.is_set()

    def wait(self, timeout: float) -> bool:
        """Wait until the bridge ends, at most ``timeout`` seconds; True when it ended."""
        return self._stop.wait(timeout)

    def stop(self) -> None:
        """End both directions (each within ``poll`` seconds)."""
        self._stop.set()
        for thread in self._threads:
            if thread is not threading.current_thread() and thread.is_alive():
                thread.join(self._poll + 5)

    def __enter__(self) -> Bridge:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.stop()

    def _fail(self, message: str) -> None:
        with self._lock:
            if self.error is None and not self._stop.is_set():
                self.error = message
        self._stop.set()

    def _carry(self, src: BridgeSide, dst: BridgeSide) -> None:
        while not self._stop.is_set():
            try:
                msg = src.bus.recv(timeout=self._poll)
            except (can.CanError, OSError, ValueError) as exc:
                self._fail(f"{src.name}: {_reason(exc)}")
                return
            if msg is None:
                if connection_lost(src.bus):
                    self._fail(f"{src.name}: the connection was closed")
                    return
                continue
            if msg.is_error_frame:
                continue
            try:
                dst.bus.send(msg)
            except (can.CanError, OSError, ValueError) as exc:
                self._fail(f"{dst.name}: {_reason(exc)}")
                return
            src.frames += 1


def shutdown(bus: can.BusABC) -> None:
    """Shut ``bus`` down, whatever state its far end left it in (python-can's slcan bus
    sends ``C`` as it closes, which fails on a socket the adapter closed)."""
    with contextlib.suppress(can.CanError, OSError, ValueError):
        bus.shutdown()


def _reason(exc: BaseException) -> str:
    text = str(exc).strip().splitlines()
    return text[0] if text else type(exc).__name__
