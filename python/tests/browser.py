# SPDX-License-Identifier: Apache-2.0
"""Headless Chromium driven over the DevTools protocol (a WebSocket, aiohttp's client), for
the browser tests of ``canola view``: open a page, evaluate JavaScript in it, poll the DOM
until a condition holds, take a screenshot. Every wait has a time limit; :meth:`close`
ends the browser and its profile whatever happened.

Chromium is Debian's (``/usr/bin/chromium``, or ``CANOLA_CHROMIUM``), started with the
flags that keep it off the network (this machine has none: without them it hangs on
connections) and with a fresh profile.
"""

from __future__ import annotations

import asyncio
import base64
import contextlib
import itertools
import json
import os
import shutil
import signal
import subprocess
import tempfile
import time
import urllib.request
from pathlib import Path
from typing import Any

import aiohttp

FLAGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
         "--disable-background-networking", "--disable-component-update", "--disable-sync",
         "--disable-default-apps", "--disable-extensions", "--mute-audio",
         "--window-size=1400,1800", "--remote-debugging-port=0"]


def chromium() -> str | None:
    """The Chromium to use, or None when there is none."""
    named = os.environ.get("CANOLA_CHROMIUM")
    if named:
        return named if Path(named).exists() else None
    return shutil.which("chromium") or shutil.which("chromium-browser")


class BrowserError(Exception):
    pass


class Browser:
    def __init__(self, start_timeout: float = 90.0) -> None:
        exe = chromium()
        if exe is None:
            raise BrowserError("no chromium")
        self.profile = Path(tempfile.mkdtemp(prefix="canola-chromium-"))
        self.log = (self.profile / "chromium.log").open("wb")
        self.proc = subprocess.Popen([exe, *FLAGS, f"--user-data-dir={self.profile}",
                                      "about:blank"], stdin=subprocess.DEVNULL,
                                     stdout=self.log, stderr=self.log,
                                     start_new_session=True)  # its helpers: one group
        self.loop = asyncio.new_event_loop()
        self._ids = itertools.count(1)
        self.session: aiohttp.ClientSession | None = None
        self.ws: aiohttp.ClientWebSocketResponse | None = None
        try:
            port = self._port(start_timeout)
            target = self._page_target(port, start_timeout)
            self.loop.run_until_complete(self._connect(target))
        except BaseException:
            self.close()
            raise

    def _port(self, timeout: float) -> int:
        marker = self.profile / "DevToolsActivePort"
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            if self.proc.poll() is not None:
                raise BrowserError(f"chromium exited with {self.proc.returncode}")
            if marker.exists():
                first = marker.read_text().split("\n", 1)[0].strip()
                if first.isdigit():
                    return int(first)
            time.sleep(0.1)
        raise BrowserError(f"chromium gave no DevTools port within {timeout:.0f} s")

    def _page_target(self, port: int, timeout: float) -> str:
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            with urllib.request.urlopen(f"http://127.0.0.1:{port}/json/list",
                                        timeout=10) as r:
                pages = [t for t in json.load(r) if t.get("type") == "page"]
            if pages:
                return str(pages[0]["webSocketDebuggerUrl"])
            time.sleep(0.2)
        raise BrowserError("chromium has no page")

    async def _connect(self, url: str) -> None:
        self.session = aiohttp.ClientSession()
        self.ws = await self.session.ws_connect(url, max_msg_size=0)

    async def _call(self, method: str, params: dict[str, Any], timeout: float) -> Any:
        assert self.ws is not None
        ident = next(self._ids)
        await self.ws.send_str(json.dumps({"id": ident, "method": method, "params": params}))
        async with asyncio.timeout(timeout):
            while True:
                msg = await self.ws.receive()
                if msg.type != aiohttp.WSMsgType.TEXT:
                    raise BrowserError(f"DevTools connection ended ({msg.type})")
                data = json.loads(msg.data)
                if data.get("id") == ident:
                    if "error" in data:
                        raise BrowserError(f"{method}: {data['error']}")
                    return data.get("result", {})

    def call(self, method: str, timeout: float = 60.0, **params: Any) -> Any:
        """One DevTools command; its result."""
        return self.loop.run_until_complete(self._call(method, params, timeout))

    def open(self, url: str) -> None:
        self.call("Page.navigate", url=url)

    def js(self, expression: str, timeout: float = 60.0) -> Any:
        """The value of ``expression`` in the page (promises awaited)."""
        result = self.call("Runtime.evaluate", timeout, expression=expression,
                           returnByValue=True, awaitPromise=True)
        if "exceptionDetails" in result:
            raise BrowserError(f"{expression}: {result['exceptionDetails']}")
        return result.get("result", {}).get("value")

    def wait_for(self, expression: str, timeout: float = 60.0, what: str = "") -> Any:
        """Poll ``expression`` until it is truthy (its value), at most ``timeout`` s."""
        end = time.monotonic() + timeout
        value = None
        while time.monotonic() < end:
            try:
                value = self.js(expression)
            except BrowserError:
                value = None  # the page is still loading
            if value:
                return value
            time.sleep(0.25)
        raise BrowserError(f"not within {timeout:.0f} s: {what or expression} "
                           f"(last value {value!r})")

    def screenshot(self, path: Path) -> None:
        """The whole page (beyond the window) as a PNG file. The capture lays the page out
        as tall as its content, without a scroll bar: the window's whole width."""
        height = self.call("Page.getLayoutMetrics")["cssContentSize"]["height"]
        clip = {"x": 0, "y": 0, "width": self.js("window.innerWidth"), "height": height,
                "scale": 1}
        data = self.call("Page.captureScreenshot", format="png", captureBeyondViewport=True,
                         clip=clip)
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_bytes(base64.b64decode(data["data"]))

    def close(self) -> None:
        if self.ws is not None or self.session is not None:
            async def shut() -> None:
                if self.ws is not None:
                    await self.ws.close()
                if self.session is not None:
                    await self.session.close()
            with contextlib.suppress(TimeoutError, aiohttp.ClientError, OSError):
                self.loop.run_until_complete(asyncio.wait_for(shut(), 10))
        self.loop.close()
        if self.proc.poll() is None:
            self.proc.terminate()
            try:
                self.proc.wait(15)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait(15)
        with contextlib.suppress(ProcessLookupError, PermissionError):
            os.killpg(self.proc.pid, signal.SIGKILL)  # helpers left behind, if any
        self.log.close()
        shutil.rmtree(self.profile, ignore_errors=True)
