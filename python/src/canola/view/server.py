# SPDX-License-Identifier: Apache-2.0
"""The web server of ``canola view`` (aiohttp): the page and its files, a WebSocket per open
page carrying the updates of :class:`~canola.view.model.BusModel`, and the page's requests
(object tree, SDO read and write, NMT, PDO mappings).

Safety: every string reaches the page as JSON data and the page writes it as text (never as
HTML), under a Content-Security-Policy that allows no inline script. Only the page's own
origin may open the WebSocket or post a request (``Origin``), requests must be JSON (so a
form on another site cannot post one), and a page reached through a loopback address must
also name it in ``Host`` (no DNS rebinding). Writes and NMT commands need ``allow_write``
and either a loopback client or the ``token`` (header ``X-Canola-Token``).
"""

from __future__ import annotations

import contextlib
import hmac
import ipaddress
import json
import time
import urllib.parse
from importlib import resources
from pathlib import Path
from typing import Any

from aiohttp import WSMsgType, web

from canola.odnames import EntryError, find_entry, parse_address
from canola.view.actions import ActionError, BusActions, od_tree
from canola.view.model import BusModel, Cursor

__all__ = ["ViewServer", "is_loopback"]

STATIC = Path(str(resources.files("canola") / "view" / "static"))
#: How often an open page gets an update (seconds).
UPDATE_S = 0.25
_CSP = ("default-src 'self'; script-src 'self'; style-src 'self'; img-src 'self' data:; "
        "connect-src 'self'; base-uri 'none'; form-action 'none'; frame-ancestors 'none'")
_HEADERS = {"Content-Security-Policy": _CSP, "X-Content-Type-Options": "nosniff",
            "Referrer-Policy": "no-referrer", "Cache-Control": "no-store"}


def is_loopback(host: str | None) -> bool:
    """Whether ``host`` (an address or a name, without port) is this machine's loopback."""
    if not host:
        return False
    host = host.strip("[]")
    if host.lower() == "localhost":
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


def _host_name(request: web.Request) -> str | None:
    """The name or address in the request's ``Host`` header, without the port."""
    try:
        return urllib.parse.urlsplit("//" + request.host).hostname
    except ValueError:  # a malformed Host
        return None


def _refuse(status: int, message: str) -> web.Response:
    return web.json_response({"error": message}, status=status, headers=_HEADERS)


class ViewServer:
    def __init__(self, model: BusModel, actions: BusActions, *, allow_write: bool,
                 token: str, loopback_only: bool) -> None:
        self.model = model
        self.actions = actions
        self.allow_write = allow_write
        self.token = token
        self.loopback_only = loopback_only  # bound to a loopback address
        self._sockets: set[web.WebSocketResponse] = set()  # the open pages
        self.app = web.Application(client_max_size=64 * 1024,
                                   middlewares=[self._guard])
        self.app.router.add_get("/", self._index)
        self.app.router.add_get("/ws", self._ws)
        self.app.router.add_get("/api/od/{node}", self._od)
        self.app.router.add_post("/api/sdo/read", self._sdo_read)
        self.app.router.add_post("/api/sdo/write", self._sdo_write)
        self.app.router.add_post("/api/nmt", self._nmt)
        self.app.router.add_post("/api/pdos", self._pdos)
        self.app.router.add_static("/static/", STATIC, follow_symlinks=False)

    # ---- who may do what

    @staticmethod
    def _local(request: web.Request) -> bool:
        """A client on this machine that reached the server by a loopback name."""
        return is_loopback(request.remote) and is_loopback(_host_name(request))

    def _may_write(self, request: web.Request) -> str | None:
        """None when ``request`` may write, else why not."""
        if not self.allow_write:
            return "writes are off: canola view was started without --allow-write"
        if self._local(request):
            return None
        given = request.headers.get("X-Canola-Token", "")
        if given and hmac.compare_digest(given.encode(), self.token.encode()):
            return None
        return ("writes from another machine need the token canola view printed "
                "(open the page by the URL it printed)")

    @web.middleware
    async def _guard(self, request: web.Request, handler: Any) -> web.StreamResponse:
        if self.loopback_only and not is_loopback(_host_name(request)):
            return _refuse(403, "this server answers to its loopback address only")
        origin = request.headers.get("Origin")
        if origin is not None and urllib.parse.urlsplit(origin).netloc != request.host:
            return _refuse(403, "a page of another origin may not use this server")
        if request.method == "POST" and request.content_type != "application/json":
            return _refuse(415, "requests are JSON (Content-Type: application/json)")
        response: web.StreamResponse = await handler(request)
        return response

    # ---- the page

    async def _index(self, _request: web.Request) -> web.StreamResponse:
        return web.FileResponse(STATIC / "index.html", headers=_HEADERS)

    async def _ws(self, request: web.Request) -> web.StreamResponse:
        ws = web.WebSocketResponse(heartbeat=20, max_msg_size=4096)
        await ws.prepare(request)
        self._sockets.add(ws)
        try:
            await ws.send_json({"type": "hello", "allow_write": self.allow_write,
                                "local": self._local(request),
                                "dictionary_nodes": sorted(self.model.dictionaries.per_node)})
            cursor = Cursor()
            due = 0.0
            while not ws.closed:
                wait = due - time.monotonic()
                if wait > 0:
                    try:
                        msg = await ws.receive(timeout=wait)
                    except TimeoutError:
                        msg = None
                    if msg is not None and msg.type in (WSMsgType.CLOSE, WSMsgType.CLOSING,
                                                        WSMsgType.CLOSED, WSMsgType.ERROR):
                        break
                    continue
                due = time.monotonic() + UPDATE_S
                update = self.model.update(cursor, time.time())
                update["pages"] = len(self._sockets)
                await ws.send_str(json.dumps(update, separators=(",", ":")))
        except (ConnectionError, RuntimeError):  # the tab went away mid-send
            pass
        finally:
            self._sockets.discard(ws)
            await ws.close()
        return ws

    async def close_pages(self) -> None:
        """Close every open page's WebSocket (the server is ending)."""
        for ws in list(self._sockets):
            await ws.close(message=b"canola view ended")

    # ---- the page's requests

    @staticmethod
    async def _body(request: web.Request) -> dict[str, Any]:
        try:
            body = await request.json()
        except ValueError:
            raise ActionError("the request is not JSON") from None
        if not isinstance(body, dict):
            raise ActionError("the request is not a JSON object")
        return body

    @staticmethod
    def _int(body: dict[str, Any], key: str, low: int, high: int) -> int:
        value = body.get(key)
        if isinstance(value, str):
            with contextlib.suppress(ValueError):
                value = int(value, 0)
        if isinstance(value, bool) or not isinstance(value, int) or not low <= value <= high:
            raise ActionError(f"bad {key} {value!r}: {low}..{high}")
        return value

    def _entry(self, body: dict[str, Any]) -> tuple[int, int, int]:
        """Node, index and sub-index of a request: ``entry`` as INDEX:SUB or a name of the
        node's EDS ("Identity object.Vendor-ID"), else ``index`` and ``sub``."""
        node = self._int(body, "node", 1, 127)
        text = body.get("entry")
        if not isinstance(text, str):
            return node, self._int(body, "index", 0, 0xFFFF), self._int(body, "sub", 0, 0xFF)
        address = parse_address(text)
        if address is not None:
            return node, *address
        od = self.model.dictionaries.get(node)
        if od is None:
            raise ActionError(f"bad entry {text!r}: INDEX:SUB, e.g. 0x1018:1 (names need the "
                              "node's EDS)")
        try:
            var = find_entry(od, text)
        except EntryError as exc:
            raise ActionError(str(exc)) from None
        return node, var.index, var.subindex

    def _note(self, node: int | None, text: str) -> None:
        with self.model.lock:
            self.model.note(time.time(), "view", node, text)

    def _log(self, request: web.Request, node: int | None, text: str) -> None:
        self._note(node, f"{text} (from {request.remote})")

    async def _answer(self, request: web.Request, work: Any, *, write: bool = False,
                      what: str = "") -> web.Response:
        if write:
            why = self._may_write(request)
            if why is not None:
                self._log(request, None, f"refused: {what or request.path}: {why}")
                return _refuse(403, why)
        try:
            result = await work()
        except ActionError as exc:
            return web.json_response({"error": str(exc)}, status=400, headers=_HEADERS)
        return web.json_response(result, headers=_HEADERS)

    async def _od(self, request: web.Request) -> web.Response:
        async def work() -> dict[str, Any]:
            node = self._int({"node": request.match_info["node"]}, "node", 1, 127)
            file = self.model.dictionaries.file(node)
            od = self.model.dictionaries.get(node) if file else None
            return {"node": node, "file": Path(file).name if file else None,
                    "objects": od_tree(od)}
        return await self._answer(request, work)

    async def _sdo_read(self, request: web.Request) -> web.Response:
        async def work() -> dict[str, Any]:
            node, index, sub = self._entry(await self._body(request))
            return await self.actions.read(node, index, sub)
        return await self._answer(request, work)

    async def _sdo_write(self, request: web.Request) -> web.Response:
        body = await self._body_or_empty(request)

        async def work() -> dict[str, Any]:
            node, index, sub = self._entry(body)
            text = body.get("value")
            if not isinstance(text, str):
                raise ActionError("no value to write")
            result = await self.actions.write(node, index, sub, text)
            self._log(request, node, f"SDO write 0x{index:04X}:{sub:02X} = {text} to node "
                                     f"{node}")
            return result
        return await self._answer(request, work, write=True, what="SDO write")

    async def _nmt(self, request: web.Request) -> web.Response:
        body = await self._body_or_empty(request)

        async def work() -> dict[str, Any]:
            node = self._int(body, "node", 0, 127)
            command = str(body.get("command", ""))
            await self.actions.nmt(node, command)
            self._log(request, node or None,
                      f"NMT {command} to {'all' if node == 0 else f'node {node}'}")
            return {"sent": command}
        return await self._answer(request, work, write=True, what="NMT command")

    async def load_pdos(self, node: int) -> dict[str, Any]:
        """Read ``node``'s PDO mappings by SDO and decode its PDOs by them from now on."""
        try:
            pdos = await self.actions.pdos(node)
        except ActionError as exc:
            self._note(node, f"PDO mappings of node {node} not read: {exc}")
            raise
        with self.model.lock:
            self.model.decoder.use_pdos(node, pdos)
        shown = [f"{p.name} ({', '.join(m.name for m in p.entries) or 'empty'})"
                 for p in pdos if p.valid]
        self._note(node, f"PDO mappings of node {node} read: {'; '.join(shown) or 'none valid'}")
        return {"node": node, "pdos": [
            {"name": p.name, "cob_id": p.cob_id, "valid": p.valid,
             "entries": [m.name for m in p.entries]} for p in pdos]}

    async def _pdos(self, request: web.Request) -> web.Response:
        async def work() -> dict[str, Any]:
            return await self.load_pdos(self._int(await self._body(request), "node", 1, 127))
        return await self._answer(request, work)

    async def _body_or_empty(self, request: web.Request) -> dict[str, Any]:
        try:
            return await self._body(request)
        except ActionError:
            return {}
