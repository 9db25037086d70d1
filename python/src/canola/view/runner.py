# SPDX-License-Identifier: Apache-2.0
"""``canola view`` running: a thread that reads the bus into the model, and the web server
in a thread of its own (its own asyncio loop), so that the caller's thread stays free (the
demo runs its network there).

The reader never stops on a bad bus: a bus that cannot be opened, or whose connection is
lost, is shown on the page and opened again every :data:`RETRY_S` seconds. :meth:`View.stop`
ends both threads within a few seconds, open pages or not.
"""

from __future__ import annotations

import asyncio
import contextlib
import threading
import time
from collections.abc import Callable

import can
from aiohttp import web

from canola.bus.open import connection_lost
from canola.errors import Error
from canola.view.actions import ActionError, BusActions
from canola.view.model import BusModel
from canola.view.server import ViewServer

__all__ = ["RETRY_S", "BusReader", "View"]

RETRY_S = 2.0
#: How often the reader looks for nodes gone silent, frames or not (seconds).
CHECK_S = 0.25


class BusReader:
    """Feeds every frame of the bus ``open_bus`` gives to ``model``, in a thread."""

    def __init__(self, model: BusModel, open_bus: Callable[[], can.BusABC]) -> None:
        self.model = model
        self._open = open_bus
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="canola-view-bus", daemon=True)

    def start(self) -> None:
        self._thread.start()

    def stop(self, timeout: float = 5.0) -> None:
        self._stop.set()
        self._thread.join(timeout)

    def _state(self, text: str, *, log: bool = True) -> None:
        with self.model.lock:
            if self.model.bus_state != text and log:
                self.model.note(time.time(), "bus", None, f"bus: {text}")
            self.model.bus_state = text

    def _run(self) -> None:
        while not self._stop.is_set():
            try:
                bus = self._open()
            except Error as exc:
                self._state(f"cannot open: {exc}")
                self._stop.wait(RETRY_S)
                continue
            self._state("receiving")
            try:
                self._receive(bus)
            except (can.CanError, OSError, ValueError) as exc:
                self._state(f"lost: {exc}")
            finally:
                bus.shutdown()
            self._stop.wait(RETRY_S)

    def _receive(self, bus: can.BusABC) -> None:
        model = self.model
        next_check = 0.0
        while not self._stop.is_set():
            msg = bus.recv(CHECK_S)
            now = time.time()
            if msg is None and connection_lost(bus):
                self._state("lost: the server closed the connection")
                return
            if msg is not None and not msg.is_error_frame and not msg.is_fd:
                model.feed(now, msg.arbitration_id,
                           b"" if msg.is_remote_frame else bytes(msg.data),
                           rtr=msg.is_remote_frame, extended=msg.is_extended_id)
            if now >= next_check:
                next_check = now + CHECK_S
                model.check(now)


class View:
    """The reader and the server of one ``canola view``."""

    def __init__(self, model: BusModel, actions: BusActions,
                 open_bus: Callable[[], can.BusABC], *, host: str, port: int,
                 allow_write: bool, token: str, loopback_only: bool) -> None:
        self.model = model
        self.actions = actions
        self.reader = BusReader(model, open_bus)
        self.server = ViewServer(model, actions, allow_write=allow_write, token=token,
                                 loopback_only=loopback_only)
        self.host, self.port = host, port
        self._loop = asyncio.new_event_loop()
        self._ready = threading.Event()
        self._done: asyncio.Event | None = None
        self._failed: BaseException | None = None
        self._thread = threading.Thread(target=self._serve, name="canola-view-http",
                                        daemon=True)

    def start(self, timeout: float = 30.0) -> int:
        """Start serving and reading; the port bound. Raises Error when it cannot bind."""
        self._thread.start()
        if not self._ready.wait(timeout):
            raise Error(f"the web server did not start within {timeout:.0f} s")
        if self._failed is not None:
            raise Error(f"cannot listen on {self.host}:{self.port}: "
                        f"{getattr(self._failed, 'strerror', None) or self._failed}")
        self.reader.start()
        return self.port

    def _serve(self) -> None:
        asyncio.set_event_loop(self._loop)
        try:
            self._loop.run_until_complete(self._main())
        finally:
            self._loop.close()

    async def _main(self) -> None:
        self._done = asyncio.Event()
        runner = web.AppRunner(self.server.app, access_log=None, shutdown_timeout=2.0)
        try:
            await runner.setup()
            site = web.TCPSite(runner, self.host, self.port)
            await site.start()
            self.port = runner.addresses[0][1]
        except OSError as exc:
            self._failed = exc
            self._ready.set()
            await runner.cleanup()
            return
        self._ready.set()
        await self._done.wait()
        await self.server.close_pages()
        await runner.cleanup()

    def read_pdos(self, node: int) -> None:
        """Read ``node``'s PDO mappings in the background (the event log says how it went)."""
        async def read() -> None:
            with contextlib.suppress(ActionError):
                await self.server.load_pdos(node)
        asyncio.run_coroutine_threadsafe(read(), self._loop)

    def stop(self, timeout: float = 10.0) -> None:
        """End the server (its pages closed), the reader and the master of the actions."""
        if self._done is not None and self._loop.is_running():
            self._loop.call_soon_threadsafe(self._done.set)
        self._thread.join(timeout)
        self.reader.stop()
        self.actions.close()
