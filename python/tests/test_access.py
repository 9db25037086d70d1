# SPDX-License-Identifier: Apache-2.0
"""Who may connect (canola.access): the hub and the gateway refuse to listen beyond
loopback without a token, and with one every client proves it before anything else; on
loopback without a token both work as before."""

from __future__ import annotations

import asyncio
import os
import select
import socket
import subprocess
import sys
import time
from pathlib import Path

import can
import pytest
from gateway_helpers import Client, FakeMaster, run, start_gateway

from canola.access import check_token, exposed_addresses, same_token, token_from, unguarded
from canola.bus.hub import HubThread
from canola.bus.open import BusError, open_bus
from canola.bus.socketcand_bus import SocketcandBus
from canola.cli import main as canola_main
from canola.gateway import connection

TOKEN = "Zm9vYmFyLXRva2VuLTIwMjQ"
SAMPLE = Path(__file__).parent / "golden" / "sample.eds"


def test_tokens_and_addresses(monkeypatch: pytest.MonkeyPatch) -> None:
    assert check_token(TOKEN) == TOKEN
    for bad in ("short", "x" * 65, "has space 0123456789", "angle<bracket>0123456789", ""):
        with pytest.raises(ValueError, match=r"16\.\.64 characters"):
            check_token(bad)
    monkeypatch.delenv("CANOLA_TOKEN", raising=False)
    assert token_from(None) is None
    monkeypatch.setenv("CANOLA_TOKEN", TOKEN)
    assert token_from(None) == TOKEN
    assert token_from("another-token-0123456789") == "another-token-0123456789"
    monkeypatch.setenv("CANOLA_TOKEN", "bad")
    with pytest.raises(ValueError, match="CANOLA_TOKEN must be"):
        token_from(None)
    assert same_token(TOKEN, TOKEN) and not same_token(TOKEN[:-1], TOKEN)
    assert not same_token("é" * 20, TOKEN)
    for loopback in ("127.0.0.1", "::1", "localhost"):
        assert exposed_addresses(loopback) == [] and unguarded(loopback, None) is None
    assert exposed_addresses("0.0.0.0") == ["0.0.0.0"]
    assert unguarded("0.0.0.0", TOKEN) is None
    assert "which is not loopback: set a token" in (unguarded("192.0.2.7", None) or "")


# ---- the hub


def _raw(port: int, *elements: str) -> str:
    """Connect, send ``elements`` one after the other, and return all the hub sent until
    it closed the connection (bounded)."""
    with socket.create_connection(("127.0.0.1", port), timeout=10) as s:
        for element in elements:
            s.sendall(element.encode())
        got = b""
        end = time.monotonic() + 10
        while time.monotonic() < end:
            ready, _, _ = select.select([s], [], [], 0.2)
            if ready:
                chunk = s.recv(4096)
                if not chunk:
                    return got.decode()
                got += chunk
        raise AssertionError(f"the hub did not close the connection: {got!r}")


def test_hub_with_a_token_refuses_clients_that_do_not_prove_it() -> None:
    """Nothing before ``< auth TOKEN >`` (before: open and rawmode worked for anyone),
    and not another token: ``< error ... >``, then closed. With the token: the bus."""
    with HubThread(token=TOKEN) as hub:
        assert _raw(hub.port, "< open can0 >") == (
            "< hi >< error authentication required: ( auth TOKEN ) first >")
        assert _raw(hub.port, "< auth not-the-token-0123456789 >", "< open can0 >") == (
            "< hi >< error wrong token >")
        with pytest.raises(can.CanInitializationError, match="authentication required"):
            SocketcandBus("127.0.0.1", hub.port, "can0", timeout=5)
        with pytest.raises(can.CanInitializationError, match="wrong token"):
            SocketcandBus("127.0.0.1", hub.port, "can0", timeout=5,
                          token="not-the-token-0123456789")
        a = SocketcandBus("127.0.0.1", hub.port, "can0", timeout=5, token=TOKEN)
        b = SocketcandBus("127.0.0.1", hub.port, "can0", timeout=5, token=TOKEN)
        try:
            a.send(can.Message(arbitration_id=0x123, data=b"\x01", is_extended_id=False))
            msg = b.recv(10)
            assert msg is not None and msg.arbitration_id == 0x123
        finally:
            a.shutdown()
            b.shutdown()


def test_hub_without_a_token_serves_everyone_on_loopback(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """As before; ``< auth ... >`` is answered ``< ok >`` whatever it holds, so a client
    with CANOLA_TOKEN set still connects; and open_bus sends CANOLA_TOKEN to a hub that
    asks for it."""
    with HubThread() as hub:
        bus = SocketcandBus("127.0.0.1", hub.port, "can0", timeout=5, token=TOKEN)
        bus.shutdown()
        bus = SocketcandBus("127.0.0.1", hub.port, "can0", timeout=5)
        bus.shutdown()
    with HubThread(token=TOKEN) as hub:
        url = f"socketcand://127.0.0.1:{hub.port}/can0"
        monkeypatch.delenv("CANOLA_TOKEN", raising=False)
        with pytest.raises(BusError, match="authentication required"):
            open_bus(url=url, timeout=5)
        monkeypatch.setenv("CANOLA_TOKEN", TOKEN)
        open_bus(url=url, timeout=5).shutdown()


# ---- the gateway


def _master() -> FakeMaster:
    m = FakeMaster(node_id=1)
    m.objects[5, 0x1000, 0] = (0x191).to_bytes(4, "little")
    return m


async def _closed(c: Client) -> bool:
    try:
        return await asyncio.wait_for(c.reader.read(), 10) == b""
    except ConnectionError:
        return True


def test_gateway_with_a_token_refuses_clients_that_do_not_prove_it(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """The first line must be ``[seq] auth TOKEN``: a request first (before: served), a
    wrong token or silence get ERROR:102 saying why, and the connection closes. With the
    token: OK, then requests are served."""
    monkeypatch.setattr(connection, "AUTH_S", 0.5)

    async def main() -> None:
        server, address = await start_gateway(_master(), token=TOKEN)  # type: ignore[arg-type]
        c = await Client.connect(address)
        assert await c.ask("[1] 5 r 0x1000 0 u32") == (
            "[1] ERROR:102 #authentication required: send '[<seq>] auth <token>' first")
        assert await _closed(c)
        c = await Client.connect(address)
        assert await c.ask("[7] auth not-the-token-0123456789") == "[7] ERROR:102 #wrong token"
        assert await _closed(c)
        c = await Client.connect(address)
        assert await _closed(c)  # silent: closed after AUTH_S
        c = await Client.connect(address)
        assert await c.ask(f"[1] auth {TOKEN}") == "[1] OK"
        assert await c.ask("[2] 5 r 0x1000 0 u32") == "[2] 401"
        assert await c.ask("[3] auth not-the-token-0123456789") == "[3] ERROR:102 #wrong token"
        assert await c.ask("[4] 5 r 0x1000 0 u32") == "[4] 401"  # proved once: stays
        await c.close()
        await server.close()

    run(main())


def test_gateway_without_a_token_serves_everyone_and_answers_auth() -> None:
    async def main() -> None:
        server, address = await start_gateway(_master())
        c = await Client.connect(address)
        assert await c.ask("[1] 5 r 0x1000 0 u32") == "[1] 401"
        assert await c.ask("[2] auth anything-at-all-0123") == "[2] OK"
        await c.close()
        await server.close()

    run(main())


def test_gateway_command_refuses_a_non_loopback_listen_without_token(
        capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.delenv("CANOLA_TOKEN", raising=False)
    sim = ["--simulate", str(SAMPLE)]
    for where in ("tcp:0.0.0.0:0", "tcp:192.0.2.7:6000", "tcp:[::]:0"):
        assert canola_main(["gateway", "--listen", where, *sim]) == 2
        err = capsys.readouterr().err
        host = where.split(":", 1)[1].rsplit(":", 1)[0].strip("[]")
        assert err.startswith(f"canola gateway: --listen {host} listens on "), err
        assert "which is not loopback: set a token (--token or CANOLA_TOKEN)" in err
        assert len(err.splitlines()) == 1
    assert canola_main(["gateway", "--listen", "tcp:0.0.0.0:0", "--token", "short", *sim]) == 2
    assert "--token must be 16..64 characters" in capsys.readouterr().err


def _stderr_lines(proc: subprocess.Popen[bytes], count: int, timeout: float = 60) -> list[str]:
    """The first ``count`` lines the process writes on stderr (bounded wait)."""
    assert proc.stderr is not None
    fd = proc.stderr.fileno()
    data = b""
    end = time.monotonic() + timeout
    while data.count(b"\n") < count:
        ready, _, _ = select.select([fd], [], [], max(end - time.monotonic(), 0))
        assert ready, f"no more output from the gateway: {data!r}"
        chunk = os.read(fd, 4096)
        assert chunk, f"the gateway ended: {data!r}"
        data += chunk
    return data.decode().splitlines()[:count]


@pytest.mark.slow
def test_gateway_command_beyond_loopback_with_a_token() -> None:
    """``--listen tcp:0.0.0.0:0`` with CANOLA_TOKEN: it listens, says the traffic is not
    encrypted, and serves a client that proves the token."""
    env = {**os.environ, "CANOLA_TOKEN": TOKEN}
    proc = subprocess.Popen([sys.executable, "-m", "canola.gateway", "--simulate",
                             str(SAMPLE), "--sim-node", "2", "--listen", "tcp:0.0.0.0:0"],
                            stderr=subprocess.PIPE, env=env)
    try:
        note, listening = _stderr_lines(proc, 2)
        assert "is not loopback: clients must send the token; the traffic is not encrypted" \
            in note
        assert listening.startswith("canola gateway: listening on tcp:0.0.0.0:"), listening
        port = int(listening.rsplit(":", 1)[1])

        async def main() -> None:
            c = await Client.connect(f"tcp:127.0.0.1:{port}")
            assert await c.ask("[1] 2 r 0x1000 0 u32") == (
                "[1] ERROR:102 #authentication required: send '[<seq>] auth <token>' first")
            c = await Client.connect(f"tcp:127.0.0.1:{port}")
            assert await c.ask(f"[1] auth {TOKEN}") == "[1] OK"
            assert await c.ask("[2] 2 r 0x1000 0 u32") == "[2] 401"
            await c.close()

        run(main())
    finally:
        proc.kill()
        proc.wait(timeout=20)
        if proc.stderr is not None:
            proc.stderr.close()
