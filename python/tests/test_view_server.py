# SPDX-License-Identifier: Apache-2.0
"""``canola view``'s server without a browser: who may write, what other origins and hosts
get, several pages at once, a page or a bus that goes away, and the command line."""

from __future__ import annotations

import asyncio
import json
import os
import signal
import socket
import time
import urllib.error
import urllib.request
from collections.abc import Iterator
from pathlib import Path
from typing import Any
from unittest import mock

import aiohttp
import can
import pytest
from aiohttp.test_utils import make_mocked_request
from cli_helpers import cli, one_line_error
from view_helpers import CanolaProcess

from canola.bus.hub import HubThread
from canola.bus.open import BusError, open_bus
from canola.errors import Error
from canola.master import Master
from canola.nodedicts import NodeDictionaries
from canola.view.actions import ActionError, BusActions
from canola.view.launch import parse_listen, start_view
from canola.view.model import BusModel
from canola.view.runner import View
from canola.view.server import ViewServer, is_loopback

pytestmark = pytest.mark.realtime  # threads, sockets, a little wall-clock time

WAIT_S = 30.0  # generous: a loaded 2-core machine


def _virtual(channel: str) -> can.BusABC:
    return can.Bus(interface="virtual", channel=channel)


@pytest.fixture
def channel() -> str:
    return f"view-test-{os.getpid()}-{time.monotonic_ns()}"


def _start(channel: str, *, allow_write: bool, tmp_path: Path) -> View:
    with (tmp_path / "view.out").open("w") as out:
        return start_view(open_bus=lambda: _virtual(channel),
                          open_master=lambda: Master(_virtual(channel), announce=False),
                          dictionaries=NodeDictionaries(), listen="127.0.0.1:0",
                          allow_write=allow_write, out=out)


@pytest.fixture
def view(channel: str, tmp_path: Path) -> Iterator[View]:
    v = _start(channel, allow_write=False, tmp_path=tmp_path)
    yield v
    v.stop()


@pytest.fixture
def writable(channel: str, tmp_path: Path) -> Iterator[View]:
    v = _start(channel, allow_write=True, tmp_path=tmp_path)
    yield v
    v.stop()


def _request(view: View, path: str, body: Any = None, **headers: str) -> tuple[int, Any]:
    data = None if body is None else json.dumps(body).encode()
    req = urllib.request.Request(f"http://127.0.0.1:{view.port}{path}", data=data,
                                 method="GET" if body is None else "POST")
    req.add_header("Content-Type", "application/json")
    for key, value in headers.items():
        req.add_header(key.replace("_", "-"), value)
    try:
        with urllib.request.urlopen(req, timeout=WAIT_S) as r:
            raw = r.read()
            return r.status, (json.loads(raw) if r.headers.get_content_type()
                              == "application/json" else r.headers)
    except urllib.error.HTTPError as exc:
        return exc.code, json.loads(exc.read())


def test_the_page_and_its_files_with_a_strict_policy(view: View) -> None:
    status, headers = _request(view, "/")
    assert status == 200
    assert "script-src 'self'" in headers["Content-Security-Policy"]
    assert "unsafe-inline" not in headers["Content-Security-Policy"]
    for name in ("view.js", "view.css", "uPlot.iife.min.js", "uPlot.min.css"):
        assert _request(view, f"/static/{name}")[0] == 200


def test_writes_and_nmt_refused_without_allow_write(view: View) -> None:
    status, body = _request(view, "/api/sdo/write",
                            {"node": 5, "entry": "0x1017:0", "value": "100"})
    assert status == 403 and body["error"].startswith("writes are off")
    status, body = _request(view, "/api/nmt", {"node": 0, "command": "stop"})
    assert status == 403 and body["error"].startswith("writes are off")


def test_other_origins_hosts_and_forms_refused(writable: View) -> None:
    nmt = {"node": 0, "command": "stop"}
    status, body = _request(writable, "/api/nmt", nmt, Origin="http://evil.example")
    assert status == 403 and "another origin" in body["error"]
    status, body = _request(writable, "/api/nmt", nmt, Host="evil.example")  # DNS rebinding
    assert status == 403 and "loopback" in body["error"]
    status, body = _request(writable, "/api/nmt", nmt, Content_Type="text/plain")
    assert status == 415
    status, body = _request(writable, "/api/nmt", {"node": 200, "command": "stop"})
    assert (status, body["error"]) == (400, "bad node 200: 0..127")


def test_writes_from_another_machine_need_the_token(channel: str) -> None:
    model = BusModel()
    actions = BusActions(lambda: Master(_virtual(channel), announce=False), NodeDictionaries())
    server = ViewServer(model, actions, allow_write=True, token="secret-token",
                        loopback_only=False)

    def request(**headers: str) -> Any:
        transport = mock.Mock()
        transport.get_extra_info.side_effect = lambda key, default=None: (
            ("192.0.2.7", 40000) if key == "peername" else default)
        return make_mocked_request("POST", "/api/nmt", headers={"Host": "192.0.2.1:8080",
                                                                 **headers},
                                   transport=transport)

    assert server._may_write(request()) is not None
    assert "token" in str(server._may_write(request(**{"X-Canola-Token": "wrong"})))
    assert server._may_write(request(**{"X-Canola-Token": "secret-token"})) is None
    assert not is_loopback("192.0.2.7") and is_loopback("127.0.0.1") and is_loopback("[::1]")


def test_a_write_and_a_command_from_this_machine(writable: View, channel: str) -> None:
    listener = _virtual(channel)
    try:
        status, body = _request(writable, "/api/nmt", {"node": 7, "command": "start"})
        assert (status, body) == (200, {"sent": "start"})
        msg = listener.recv(WAIT_S)
        assert msg is not None and (msg.arbitration_id, bytes(msg.data)) == (0, b"\x01\x07")
        # no node 5 on the bus: the SDO write times out, and says so
        status, body = _request(writable, "/api/sdo/write",
                                {"node": 5, "entry": "0x6200:1", "value": "0A"})
        assert status == 400 and "no response from node 5" in body["error"]
    finally:
        listener.shutdown()


async def _pages(port: int, pages: int) -> list[dict[str, Any]]:
    """Updates of ``pages`` pages open at once (their third each)."""
    async with aiohttp.ClientSession() as session:
        sockets = [await session.ws_connect(f"http://127.0.0.1:{port}/ws",
                                            origin=f"http://127.0.0.1:{port}")
                   for _ in range(pages)]
        got = []
        for ws in sockets:
            async with asyncio.timeout(WAIT_S):
                for _ in range(3):
                    got.append(json.loads((await ws.receive()).data))
        for ws in sockets:
            await ws.close()
        return got


def test_several_pages_at_once_each_with_its_updates(view: View, channel: str) -> None:
    sender = _virtual(channel)
    try:
        sender.send(can.Message(arbitration_id=0x705, data=b"\x05", is_extended_id=False))
        got = asyncio.run(_pages(view.port, 3))
    finally:
        sender.shutdown()
    hellos = [m for m in got if m["type"] == "hello"]
    updates = [m for m in got if m["type"] == "update"]
    assert len(hellos) == 3 and all(h["local"] and not h["allow_write"] for h in hellos)
    assert max(u["pages"] for u in updates) == 3
    assert all(u["nodes"][0]["node"] == 5 for u in updates if u["nodes"])


def test_a_page_of_another_origin_gets_no_websocket(view: View) -> None:
    async def attempt() -> int:
        async with aiohttp.ClientSession() as session:
            try:
                await session.ws_connect(f"http://127.0.0.1:{view.port}/ws",
                                         origin="http://evil.example")
            except aiohttp.WSServerHandshakeError as exc:
                return exc.status
        return 101
    assert asyncio.run(attempt()) == 403


def test_a_closed_page_and_a_dead_bus_leave_the_server_serving(tmp_path: Path) -> None:
    with HubThread() as hub:
        url = f"socketcand://127.0.0.1:{hub.port}/can0"
        with (tmp_path / "out").open("w") as out:
            view = start_view(open_bus=lambda: open_bus(url=url),
                              open_master=lambda: Master(open_bus(url=url), announce=False),
                              dictionaries=NodeDictionaries(), listen="127.0.0.1:0", out=out)
        try:
            end = time.monotonic() + WAIT_S
            while view.model.bus_state != "receiving" and time.monotonic() < end:
                time.sleep(0.05)
            assert view.model.bus_state == "receiving"

            async def open_and_drop() -> None:  # a tab closed without a goodbye
                reader, writer = await asyncio.open_connection("127.0.0.1", view.port)
                writer.write(f"GET /ws HTTP/1.1\r\nHost: 127.0.0.1:{view.port}\r\n"
                             "Upgrade: websocket\r\nConnection: Upgrade\r\n"
                             "Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\n"
                             "Sec-WebSocket-Version: 13\r\n\r\n".encode())
                await asyncio.wait_for(reader.readuntil(b"\r\n\r\n"), WAIT_S)
                writer.transport.abort()
            asyncio.run(open_and_drop())
            end = time.monotonic() + WAIT_S
            while view.server._sockets and time.monotonic() < end:
                time.sleep(0.05)
            assert not view.server._sockets  # the server let the page go
        finally:
            hub.stop()
        end = time.monotonic() + WAIT_S
        while view.model.bus_state == "receiving" and time.monotonic() < end:
            time.sleep(0.05)
        try:
            assert view.model.bus_state.startswith(("lost", "cannot open")), \
                view.model.bus_state
            assert _request(view, "/")[0] == 200  # still serving
            began = time.monotonic()
        finally:
            view.stop()
        assert time.monotonic() - began < WAIT_S
        assert not view._thread.is_alive()


def test_a_bus_that_does_not_open_is_shown_not_fatal(tmp_path: Path) -> None:
    def broken() -> can.BusABC:
        raise BusError("cannot open socketcan://nothing: No such device")

    with (tmp_path / "out").open("w") as out:
        view = start_view(open_bus=broken, open_master=lambda: Master(broken()),
                          dictionaries=NodeDictionaries(), listen="127.0.0.1:0", out=out)
    try:
        end = time.monotonic() + WAIT_S
        while not view.model.bus_state.startswith("cannot open") and time.monotonic() < end:
            time.sleep(0.05)
        assert view.model.bus_state == ("cannot open: cannot open socketcan://nothing: "
                                        "No such device")
        status, body = _request(view, "/api/sdo/read", {"node": 5, "entry": "0x1000"})
        assert status == 400 and body["error"].startswith("cannot reach the bus")
    finally:
        view.stop()


def test_a_request_after_close_opens_no_master() -> None:
    """Ctrl-C while --read-pdos still waits for its worker: the worker must not open a new
    master after the view closed its own (the process then waited for its reads to end)."""
    opened: list[int] = []

    def open_master() -> Master:
        opened.append(1)
        raise AssertionError("a master opened after close")

    actions = BusActions(open_master, NodeDictionaries())
    actions.close()
    with pytest.raises(ActionError, match="the view is stopping"):
        asyncio.run(actions.pdos(5))
    assert opened == []


def test_listen_addresses() -> None:
    assert parse_listen("127.0.0.1:8080") == ("127.0.0.1", 8080)
    assert parse_listen("[::1]:0") == ("::1", 0)
    for bad in ("8080", "127.0.0.1:", "127.0.0.1:99999", ":80"):
        with pytest.raises(Error):
            parse_listen(bad)


def test_cli_bad_arguments(capsys: pytest.CaptureFixture[str]) -> None:
    code, _, err = cli(capsys, "view", "--bus", "virtual://x", "--listen", "nowhere")
    assert code == 2 and "bad --listen 'nowhere'" in err
    one_line_error(err)
    code, _, err = cli(capsys, "view", "--bus", "virtual://x", "--bitrate", "5")
    assert code == 2 and "bad --bitrate 5" in err
    code, _, err = cli(capsys, "demo", "--allow-write")
    assert code == 2 and "go with --view" in err
    code, _, err = cli(capsys, "view", "--bus", "nothing://x")
    assert code == 1 and "unknown bus URL" in err


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM], ids=["SIGINT", "SIGTERM"])
def test_cli_stops_on_a_signal_whichever_thread_it_lands_on(sig: int) -> None:
    # A fresh-clone run hung here: Ctrl-C landed on the web server's thread while the main
    # thread sat in an untimed wait, which Python then never left to run the handler.
    view = CanolaProcess("view", "--bus", "virtual://view-signal", "--listen", "127.0.0.1:0")
    try:
        view.wait_line("canola view: writes and NMT commands are off", 120)
        view.signal_another_thread(sig)
        code = view.proc.wait(60)  # a bound, not a wait: it ends within a second here
    finally:
        view.stop()
    assert code == 0


def test_cli_serves_until_ctrl_c_and_warns_off_loopback() -> None:
    view = CanolaProcess("view", "--bus", "virtual://view-cli", "--listen", "0.0.0.0:0")
    try:
        warning = view.wait_line("canola view: warning: listening on 0.0.0.0:", 120)
        assert "not on a loopback address" in warning
        # 0.0.0.0 is no address to open: the page on loopback, and by the machine's name
        url = view.wait_line("canola view: http://127.0.0.1:", 60)
        view.wait_line("canola view: writes and NMT commands are off", 60)
        port = int(url.split("http://127.0.0.1:")[1].split("/")[0])
        assert f"(on every address: http://{socket.gethostname()}:{port}/," in url
        with urllib.request.urlopen(f"http://127.0.0.1:{port}/", timeout=WAIT_S) as r:
            assert r.status == 200
    finally:
        code = view.stop()
    assert code == 0
