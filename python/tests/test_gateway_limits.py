# SPDX-License-Identifier: Apache-2.0
"""The gateway's bounds (docs/security.md), tried as a hostile client would, on loopback:
parse time, other clients while one parses, idle clients, client slots, shutdown, the
SYNC period of its own dictionary."""

from __future__ import annotations

import asyncio
import itertools
import logging
import signal
import socket
import subprocess
import sys
import textwrap
import threading
import time
from pathlib import Path

import pytest
from gateway_helpers import Client, FakeMaster, eventually, gateway_process, run, start_gateway
from test_gateway_master import GW, _sim, serve

from canola.gateway import connection
from canola.gateway.server import MAX_LINE

PARSE_BOUND_S = 5.0  # per 4 MiB line; it takes well under a second (docs/security.md)

# Lines of MAX_LINE bytes that cost a naive parser super-linear time, one or more per
# command family: (name, head, repeated unit, tail).
_HOSTILE = [
    ("r32 digits", "[7] 2 w 0x2000 0 r32 ", "1", "x"),
    ("r64 fraction", "[7] 2 w 0x2000 0 r64 1.", "1", "e"),
    ("decimal", "[7] 2 w 0x2000 0 u32 ", "1", ""),
    ("hexadecimal", "[7] 2 w 0x2000 0 u64 0x", "f", ""),
    ("lss_switch_sel words", "[1] lss_switch_sel ", "1 ", ""),
    ("lss_allnodes words", "[1] lss_allnodes ", "0 ", ""),
    ("vs doubled quotes", '[1] 2 w 0x2000 0 vs "', '""', '"'),
    ("vs escapes", '[1] 2 w 0x2000 0 vs "', '\\\\\\"""', '"'),
    ("vs unclosed", '[1] 2 w 0x2000 0 vs "', "a", ""),
    ("comment marks in words", "[1] 2 w 0x2000 0 vs ", "a#", ""),
    ("quotes and comment marks", "[1] 2 w 0x2000 0 vs ", '" #', ""),
    ("hex pairs", "[1] 2 w 0x2000 0 hex ", "0a ", ""),
    ("base64", "[1] 2 w 0x2000 0 d ", "QUJD", ""),
    ("time", "[1] 2 w 0x2000 0 t ", "1 ", ""),
    ("pdo values", "[1] w p 1 64 ", "1 ", ""),
    ("pdo mapping", "[1] set rpdo 1 0x201 event 64 ", "0x2000 0 u8 ", ""),
    ("numbers before the command", "[1] ", "1 ", ""),
    ("blanks", "[1] 5 r", " ", "x"),
    ("blanks before [seq]", "", " ", "[1] 5 start"),
    ("one word", "[1] ", "a", ""),
    ("NUL characters", "[1] 5 start", "\0", ""),
]

_TIMER = textwrap.dedent("""
    import json, sys, time
    from canola.gateway.parser import ParseError, parse_line
    size, cases = int(sys.argv[1]), json.loads(sys.stdin.read())
    for name, head, unit, tail in cases:
        line = head + unit * ((size - len(head) - len(tail)) // len(unit)) + tail
        began = time.process_time()
        try:
            parse_line(line)
        except ParseError:
            pass
        print(name, time.process_time() - began, flush=True)
""")


def test_every_line_parses_in_time_linear_in_its_length() -> None:
    """A 4 MiB line of each hostile shape parses within a generous bound (CPU time, in a
    process of its own: a parser that backtracks would not end, and is killed)."""
    import json  # noqa: PLC0415

    done = subprocess.run([sys.executable, "-c", _TIMER, str(MAX_LINE)],
                          input=json.dumps(_HOSTILE), capture_output=True, text=True,
                          timeout=len(_HOSTILE) * PARSE_BOUND_S + 60, check=True)
    took = {line.rsplit(" ", 1)[0]: float(line.rsplit(" ", 1)[1])
            for line in done.stdout.splitlines()}
    assert set(took) == {name for name, *_ in _HOSTILE}
    slow = {name: s for name, s in took.items() if s > PARSE_BOUND_S}
    assert not slow, slow


def _master() -> FakeMaster:
    m = FakeMaster(node_id=1)
    m.objects[5, 0x1000, 0] = (0x191).to_bytes(4, "little")
    return m


def test_a_hostile_line_holds_up_no_other_client(tmp_path: Path) -> None:
    """The r32 line that froze every client (a gateway process of its own: a frozen one
    is killed, not waited for)."""
    with gateway_process("--bus", f"virtual://gw-{tmp_path.name}") as (_, address):
        async def main() -> None:
            hostile = await Client.connect(address)
            other = await Client.connect(address)
            hostile.writer.write(b"[7] 5 w 0x2000 0 r32 " + b"1" * (MAX_LINE - 40) + b"x\r\n")
            for seq in range(5):
                assert await other.ask(f"[{seq}] {GW} r 0x1000 0 u32", timeout=10) == \
                    f"[{seq}] 0"
            assert await hostile.line() == "[7] ERROR:101"
            await hostile.close()
            await other.close()

        run(main())


def test_long_lines_are_parsed_off_the_event_loop(monkeypatch: pytest.MonkeyPatch) -> None:
    """A long line's parse is held until another client (a thread of its own, with its
    own time-out) was served: that can only happen when the parse does not run on the
    event loop."""
    started, release = threading.Event(), threading.Event()
    parse = connection._parse
    served: list[bytes] = []

    def held(raw: bytes) -> object:
        if b"held" in raw:
            started.set()
            release.wait(30)
        return parse(raw)

    def other(port: int) -> None:
        try:
            started.wait(20)
            with socket.create_connection(("127.0.0.1", port), timeout=10) as sock:
                sock.sendall(b"[2] 5 r 0x1000 0 u32\r\n")
                served.append(sock.makefile("rb").readline())
        except OSError:
            pass
        finally:
            release.set()

    monkeypatch.setattr(connection, "_parse", held)

    async def main() -> None:
        server, address = await start_gateway(_master())
        thread = threading.Thread(target=other, args=(int(address.rsplit(":", 1)[1]),))
        thread.start()
        slow = await Client.connect(address)
        await slow.send("[1] 5 r 0x1000 0 u32 # held " + "." * connection.INLINE_PARSE)
        assert await slow.line(timeout=40) == "[1] 401"
        await asyncio.to_thread(thread.join, 40)
        assert served == [b"[2] 401\r\n"]
        await slow.close()
        await server.close()

    run(main())


async def _closed(c: Client) -> bool:
    """Whether the gateway closed the connection (reads until the end, bounded)."""
    try:
        async with asyncio.timeout(20):
            while await c.reader.read(65536):
                pass
    except (ConnectionError, TimeoutError):
        return False
    return True


def test_idle_clients_are_dropped_and_logged(caplog: pytest.LogCaptureFixture) -> None:
    """Silent, and one byte now and then without a line end: dropped after the idle
    time-out, with a log line that says why. A client waiting for a long request or for
    events is not idle."""
    caplog.set_level(logging.INFO, logger="canola.gateway")

    async def main() -> None:
        m = _master()
        m.gates[5] = asyncio.Event()
        server, address = await start_gateway(m, idle_timeout=0.5)
        silent = await Client.connect(address)
        trickle = await Client.connect(address)
        waiting = await Client.connect(address)
        listener = await Client.connect(address)
        assert await listener.ask("[1] set events 1") == "[1] OK"
        await waiting.send("[1] 5 r 0x1000 0 u32")  # held at the gate
        await eventually(lambda: 5 in m.started)

        async def drip() -> None:
            for _ in range(400):
                trickle.writer.write(b"x")
                await asyncio.sleep(0.05)

        dripping = asyncio.create_task(drip())
        assert await _closed(silent)
        assert await _closed(trickle)
        dripping.cancel()
        m.gates[5].set()  # the request ran past the time-out: it was not idle
        assert await waiting.line() == "[1] 401"
        assert await listener.ask("[2] 5 r 0x1000 0 u32") == "[2] 401"
        drops = {r.getMessage().split(" (")[0]: r.getMessage() for r in caplog.records
                 if "dropped" in r.getMessage()}
        for name in ("client 1", "client 2"):  # silent, trickle
            assert "idle for" in drops[name] and "(time-out 0.5 s)" in drops[name], drops
        assert "client 4" not in drops  # the listener
        for c in (waiting, listener):
            await c.close()
        await server.close()

    run(main())


def test_a_new_client_takes_the_slot_of_the_idlest(caplog: pytest.LogCaptureFixture) -> None:
    caplog.set_level(logging.INFO, logger="canola.gateway")

    async def main() -> None:
        server, address = await start_gateway(_master(), max_clients=2, idle_timeout=0,
                                              quiet_s=0.5)
        oldest = await Client.connect(address)
        assert await oldest.ask("[1] 5 r 0x1000 0 u32") == "[1] 401"
        await asyncio.sleep(0.6)  # quiet: its slot may go
        newer = await Client.connect(address)
        assert await newer.ask("[1] 5 r 0x1000 0 u32") == "[1] 401"
        third = await Client.connect(address)
        assert await third.ask("[1] 5 r 0x1000 0 u32") == "[1] 401"
        assert await _closed(oldest)
        assert await newer.ask("[2] 5 r 0x1000 0 u32") == "[2] 401"
        assert server.clients == 2
        assert any("client 1 " in r.getMessage() and "its slot goes to client 3" in
                   r.getMessage() for r in caplog.records)
        for c in (newer, third):
            await c.close()
        await server.close()

    run(main())


def test_sigterm_and_sigint_stop_it_whatever_the_clients_do(tmp_path: Path) -> None:
    """With a client that sends a 4 MiB hostile line, one that floods without reading, one
    in the middle of a line and one waiting for a node that is not there (60 s per answer,
    on python-can's virtual bus): the gateway ends within a generous bound (it takes a few
    tenths of a second)."""
    for sig in (signal.SIGTERM, signal.SIGINT):
        with gateway_process("--bus", f"virtual://gw-{tmp_path.name}-{sig.name}",
                             "--sdo-timeout", "60000") as (proc, address):
            async def signal_and_wait(address: str = address,
                                      sig: signal.Signals = sig) -> float:
                held = [await Client.connect(address) for _ in range(4)]
                hostile, flood, half, waiting = held
                hostile.writer.write(b"[1] 2 w 0x2000 0 r32 " + b"1" * (MAX_LINE - 40) + b"x\n")
                flood.writer.write(b"[1] 2 r 0x1000 0 u32\r\n" * 20000)
                half.writer.write(b"[1] 2 r 0x1000")
                await waiting.send("[1] 42 r 0x1000 0 u32")
                await asyncio.sleep(0.5)  # let the gateway be busy with them
                began = time.monotonic()
                proc.send_signal(sig)
                while proc.poll() is None and time.monotonic() - began < 60:
                    await asyncio.sleep(0.01)
                for c in held:
                    c.writer.transport.abort()
                return time.monotonic() - began

            took = run(signal_and_wait())
            assert proc.wait(timeout=300) == 0
            assert took < 20.0, f"{sig.name}: {took:.1f} s"  # tenths of a second, unloaded
            assert proc.stderr is not None and "Traceback" not in proc.stderr.read()


def test_sync_period_the_bus_cannot_carry_is_refused() -> None:
    async def main() -> None:
        bus, master, _ = _sim()
        async with serve(master) as (address, _):
            c = await Client.connect(address)
            for seq, period in enumerate((1, 999), start=1):
                assert await c.ask(f"[{seq}] {GW} w 0x1006 0 u32 {period}") == \
                    f"[{seq}] ERROR:0x06090030"
            assert await c.ask(f"[3] {GW} r 0x1006 0 u32") == "[3] 0"
            assert await c.ask(f"[4] {GW} w 0x1005 0 u32 0x40000080") == "[4] OK"
            before = len(bus.trace)
            assert await c.ask(f"[5] {GW} w 0x1006 0 u32 1000") == "[5] OK"
            bus.run_for(100_000)
            at = [float(line.split()[0].strip("()")) for line in bus.trace[before:]
                  if line.split()[-1] == "080#"]
            assert len(at) >= 90
            assert min(b - a for a, b in itertools.pairwise(at)) > 0.000999
            assert await c.ask(f"[6] {GW} w 0x1006 0 u32 0") == "[6] OK"
            await c.close()

    run(main())

