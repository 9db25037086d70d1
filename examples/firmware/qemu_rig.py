#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""A QEMU example image on canola's software bus: QEMU runs the image with the board's first
serial port on a TCP port, a socketcand hub (canola.bus.hub) serves the bus, and the UART is
joined to the hub's channel as an SLCAN adapter (canola.bus.bridge over python-can's slcan
interface), so every canola command, the gateway and python-canopen reach the firmware at
``socketcand://127.0.0.1:PORT/CHANNEL``.

As a program (``make run-firmware``)::

    qemu_rig.py [--board mps2-an386|microbit] [--port PORT] [--channel CH] ELF

prints ``bus: socketcand://127.0.0.1:PORT/can0`` and runs until Ctrl-C or SIGTERM, then
stops everything it started (exit 0); exit 1 when QEMU or the bridge ends by itself.

As a module (tests/firmware): ``with Rig(board, elf) as rig:`` then ``rig.url``,
``rig.reset()`` (QEMU's system_reset: the emulated board resets, the firmware starts
again), ``rig.alive()``. Every wait is bounded; QEMU's output goes to ``log``.

QEMU starts the board only once the bridge has connected to its serial port
(``server=on,wait=on``), so the firmware's boot-up frame reaches the hub.
"""

from __future__ import annotations

import argparse
import os
import signal
import socket
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path
from typing import IO, Any

import can

from canola.bus.bridge import Bridge, BridgeSide, shutdown
from canola.bus.hub import HubThread
from canola.bus.open import BusError, open_bus

BOARDS = ("mps2-an386", "microbit")
START_TIMEOUT_S = 30.0  # QEMU listening, the bridge connected: a starved machine meets it


class RigError(Exception):
    """The rig could not start (one line)."""


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


class Rig:
    """QEMU + hub + bridge; start() / stop(), or ``with``."""

    def __init__(self, board: str, elf: str | os.PathLike[str], *, channel: str = "can0",
                 hub_port: int = 0, log: IO[Any] | None = None) -> None:
        if board not in BOARDS:
            raise RigError(f"unknown board {board!r}: {', '.join(BOARDS)}")
        self.board = board
        self.elf = Path(elf)
        self.channel = channel
        self._hub_port = hub_port
        self._log = log
        self._tmp = tempfile.TemporaryDirectory(prefix="canola-rig-")
        self._monitor = os.path.join(self._tmp.name, "monitor")
        self.hub: HubThread | None = None
        self.qemu: subprocess.Popen[bytes] | None = None
        self.bridge: Bridge | None = None
        self._buses: list[can.BusABC] = []

    @property
    def url(self) -> str:
        assert self.hub is not None
        return f"socketcand://127.0.0.1:{self.hub.port}/{self.channel}"

    def start(self) -> Rig:
        if not self.elf.is_file():
            raise RigError(f"no image at {self.elf} (make firmware builds it)")
        try:
            self.hub = HubThread(port=self._hub_port).start()
            far = self._start_qemu()
            self._buses.append(far)
            near = open_bus(url=self.url)
            self._buses.append(near)
            self.bridge = Bridge(BridgeSide(far, f"{self.board}'s UART (slcan)"),
                                 BridgeSide(near, self.url)).start()
        except BaseException:
            self.stop()
            raise
        return self

    def _start_qemu(self) -> can.BusABC:
        """QEMU started, and its serial port joined (retrying on the few failures a start
        can have: a port another process took since we probed it, a socket not listening
        yet). The probe is the join itself: QEMU takes the first connection as the UART."""
        for _ in range(5):
            port = _free_port()
            cmd = ["qemu-system-arm", "-M", self.board, "-display", "none", "-nodefaults",
                   "-serial", f"tcp:127.0.0.1:{port},server=on,wait=on",
                   "-monitor", f"unix:{self._monitor},server=on,wait=off",
                   "-kernel", str(self.elf)]
            self.qemu = subprocess.Popen(cmd, stdin=subprocess.DEVNULL,
                                         stdout=self._log or subprocess.DEVNULL,
                                         stderr=self._log or subprocess.DEVNULL)
            deadline = time.monotonic() + START_TIMEOUT_S
            while self.qemu.poll() is None:
                try:
                    return open_bus(url=f"slcan://127.0.0.1:{port}")
                except BusError as exc:
                    if time.monotonic() > deadline:
                        raise RigError(f"cannot join QEMU's serial port 127.0.0.1:{port} "
                                       f"within {START_TIMEOUT_S:g} s: {exc}") from None
                    time.sleep(0.1)
        raise RigError(f"QEMU exited at start (exit {self.qemu.returncode if self.qemu else '?'})")

    def alive(self) -> bool:
        """QEMU runs and the bridge carries frames."""
        return (self.qemu is not None and self.qemu.poll() is None
                and self.bridge is not None and self.bridge.running)

    def reset(self) -> None:
        """Reset the emulated board (QEMU's system_reset, as a reset button would)."""
        with socket.socket(socket.AF_UNIX) as s:
            s.settimeout(10)
            s.connect(self._monitor)
            s.sendall(b"system_reset\n")
            end = time.monotonic() + 2
            while time.monotonic() < end:  # the monitor echoes the command once done
                try:
                    if b"system_reset" in s.recv(4096):
                        break
                except TimeoutError:
                    break

    def stop(self) -> None:
        if self.bridge is not None:
            self.bridge.stop()
        for bus in self._buses:
            shutdown(bus)
        self._buses.clear()
        if self.qemu is not None and self.qemu.poll() is None:
            self.qemu.terminate()
            try:
                self.qemu.wait(10)
            except subprocess.TimeoutExpired:
                self.qemu.kill()
                self.qemu.wait(10)
        if self.hub is not None:
            self.hub.stop()
        self._tmp.cleanup()

    def __enter__(self) -> Rig:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.stop()


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="qemu_rig.py", description=__doc__.split("\n\n")[0])
    p.add_argument("elf", help="the firmware image (build-fw/BOARD/firmware.elf)")
    p.add_argument("--board", default="mps2-an386", choices=BOARDS)
    p.add_argument("--port", type=int, default=0, help="the hub's TCP port (0: a free one)")
    p.add_argument("--channel", default="can0")
    args = p.parse_args(argv)
    ended = threading.Event()
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, lambda *_: ended.set())
    try:
        rig = Rig(args.board, args.elf, channel=args.channel, hub_port=args.port).start()
    except (RigError, BusError, OSError) as exc:
        print(f"qemu_rig: {exc}", file=sys.stderr)
        return 1
    try:
        print(f"bus: {rig.url}", flush=True)
        while not ended.wait(0.5):
            if not rig.alive():
                why = rig.bridge.error if rig.bridge and rig.bridge.error else "QEMU exited"
                print(f"qemu_rig: {why}", file=sys.stderr)
                return 1
    finally:
        rig.stop()
    return 0


if __name__ == "__main__":
    sys.exit(main())
