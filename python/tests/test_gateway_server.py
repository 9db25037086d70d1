# SPDX-License-Identifier: Apache-2.0
"""The gateway server against a fake master: sessions, concurrency, limits, disconnects."""

from __future__ import annotations

import asyncio
import base64
import os
import tempfile

from gateway_helpers import Client, FakeMaster, eventually, run, start_gateway

from canola.gateway import Executor, GatewayServer, parse_listen
from canola.gateway.backend import BootUp, Emcy, Heartbeat, HeartbeatLost
from canola.gateway.events import EventHub
from canola.gateway.server import LineSplitter, Listen


def _master() -> FakeMaster:
    m = FakeMaster(node_id=1)
    m.objects[5, 0x1000, 0] = (0x191).to_bytes(4, "little")
    m.objects[6, 0x1000, 0] = (0x192).to_bytes(4, "little")
    m.objects[1, 0x1017, 0] = b"\0\0"
    m.objects[1, 0x1018, 1] = (0xCA0).to_bytes(4, "little")
    return m


def test_listen_specs() -> None:
    assert parse_listen("tcp:127.0.0.1:6000") == Listen("tcp", "127.0.0.1", 6000)
    assert parse_listen("tcp:[::1]:7") == Listen("tcp", "::1", 7)
    assert parse_listen("tcp:6001") == Listen("tcp", "127.0.0.1", 6001)
    assert parse_listen("unix:/run/canola.sock") == Listen("unix", path="/run/canola.sock")
    assert parse_listen("stdio") == Listen("stdio")
    assert str(parse_listen("tcp:[::1]:7")) == "tcp:[::1]:7"
    for bad in ("udp:1", "tcp:host:port", "unix:", "tcp:1:99999"):
        try:
            parse_listen(bad)
        except ValueError:
            continue
        raise AssertionError(bad)


def test_line_splitter() -> None:
    s = LineSplitter(10)
    assert s.feed(b"[1] a\n[2] b") == [b"[1] a"]
    assert s.feed(b"\n") == [b"[2] b"]
    assert s.feed(b"[3] 0123456789") == [(3,)]
    assert s.feed(b"more more more") == []
    assert s.feed(b"\n[4] ok\n") == [b"[4] ok"]
    assert s.feed(b"0123456789ab\nx") == [(None,)]
    assert s.tail() == b"x"


def test_basic_replies_and_sequence_numbers() -> None:
    async def main() -> None:
        m = _master()
        server, address = await start_gateway(m)
        a = await Client.connect(address)
        b = await Client.connect(address)
        assert await a.ask("[1] 5 r 0x1000 0 u32") == "[1] 401"
        assert await b.ask("[77] 6 r 0x1000 0 x32") == "[77] 0x00000192"
        assert await a.ask("[2] 5 r 0x1000 0") == "[2] 91 01 00 00"
        assert await a.ask("[3] 5 r 0x2000 0 u8") == "[3] ERROR:0x06020000"
        assert await a.ask("[4] r 0x1000 0") == "[4] ERROR:105"
        assert await a.ask("[5] set node 6") == "[5] OK"
        assert await a.ask("[6] r 0x1000 0 u16") == "[6] ERROR:0x06070010"
        assert await a.ask("[7] r 0x1000 0 u32") == "[7] 402"
        assert await b.ask("[8] r 0x1000 0") == "[8] ERROR:105"  # b has its own defaults
        assert await a.ask("[9] 2 5 r 0x1000 0") == "[9] ERROR:106"
        assert await a.ask("[10] set network 2") == "[10] ERROR:106"
        assert await a.ask("[11] 128 r 0x1000 0") == "[11] ERROR:107"
        assert await a.ask("[12] 99 r 0x1000 0") == "[12] ERROR:0x05040000"
        assert await a.ask("[13] 5 w 0x2000 0 u16 0x1234") == "[13] OK"
        assert m.objects[5, 0x2000, 0] == b"\x34\x12"
        assert await a.ask("[14] set sdo_timeout 1500") == "[14] OK"
        assert await a.ask("[15] set sdo_block 1") == "[15] OK"
        assert await a.ask("[16] 5 r 0x2000 0 u16") == "[16] 4660"
        assert m.calls[-1] == ("up", 5, True, 1500)
        assert await a.ask("[17] lss_switch_glob 1") == "[17] ERROR:100"
        assert await a.ask("[18] 5 enable guarding 100 3") == "[18] ERROR:100"
        assert await a.ask("[19] init 2") == "[19] ERROR:100"
        assert await a.ask("[20] set id 3") == "[20] ERROR:100"
        await a.close()
        await b.close()
        await server.close()

    run(main())


def test_a_failing_master_costs_one_reply() -> None:
    async def main() -> None:
        m = _master()

        async def broken(*args: object, **kwargs: object) -> bytes:
            raise RuntimeError("a bug")

        server, address = await start_gateway(m)
        c = await Client.connect(address)
        m.sdo_upload = broken  # type: ignore[method-assign]
        assert await c.ask("[1] 5 r 0x1000 0") == "[1] ERROR:102"
        assert await c.ask("[2] 5 w 0x2000 0 u8 1") == "[2] OK"
        await c.close()
        await server.close()

    run(main())


def test_local_node_and_nmt() -> None:
    async def main() -> None:
        m = _master()
        server, address = await start_gateway(m)
        c = await Client.connect(address)
        assert await c.ask("[1] 1 r 0x1018 1 u32") == "[1] 3232"
        assert await c.ask("[2] 1 w 0x1017 0 u16 100") == "[2] OK"
        assert m.objects[1, 0x1017, 0] == b"\x64\x00"
        assert await c.ask("[3] set heartbeat 250") == "[3] OK"
        assert m.objects[1, 0x1017, 0] == (250).to_bytes(2, "little")
        assert not [call for call in m.calls if call[1] == 1]  # nothing on the bus
        assert await c.ask("[4] 5 start") == "[4] OK"
        assert await c.ask("[5] 0 reset comm") == "[5] OK"
        assert await c.ask("[6] 1 stop") == "[6] OK"
        assert await c.ask("[7] 5 preop") == "[7] OK"
        assert await c.ask("[8] 5 reset node") == "[8] OK"
        assert await c.ask("[9] 1 reset comm") == "[9] OK"
        # to its own node-ID or to all: on the bus (as CANopenNode's gateway) and applied
        # to itself
        assert m.nmt_sent == [(5, "start"), (0, "reset_comm"), (1, "stop"), (5, "preop"),
                              (5, "reset_node"), (1, "reset_comm")]
        assert m.local_nmt_done == ["reset_comm", "stop", "reset_comm"]
        assert (await c.ask("[10] info version")).startswith("[10] 3232 0 0.0 0 2 3.0 ")
        await c.close()
        await server.close()

    run(main())


def test_malformed_lines_keep_the_connection() -> None:
    async def main() -> None:
        m = _master()
        server, address = await start_gateway(m)
        c = await Client.connect(address)
        # a line without [seq]: the last sequence number of this client (0 before any), as
        # CANopenNode's gateway answers it (cocomm takes a reply without one for a value)
        assert await c.ask("hello") == "[0] ERROR:101"
        assert await c.ask("[1] 5 explode") == "[1] ERROR:100"
        assert await c.ask("[2] 5 r 0xZZ 0") == "[2] ERROR:101"
        assert await c.ask("[3] 5 w 0x2000 0 u8 300") == "[3] ERROR:101"
        assert await c.ask("") == ""  # empty lines and comments: an empty reply
        assert await c.ask("  # a comment") == ""
        c.writer.write(b"\xff\xfe[4] \x00\x01\r\n")
        assert await c.line() == "[3] ERROR:101"
        assert await c.ask("[5] 5 r 0x1000 0 u32") == "[5] 401"
        assert await c.ask("5 start") == "[5] ERROR:101"
        await c.close()
        await server.close()

    run(main())


def test_line_length_limit() -> None:
    async def main() -> None:
        m = _master()
        server, address = await start_gateway(m, max_line=100)
        c = await Client.connect(address)
        assert await c.ask("[1] 5 w 0x2000 0 d " + "A" * 200) == "[1] ERROR:600"
        assert await c.ask("[2] 5 w 0x2000 0 d " + "QUJD") == "[2] OK"
        c.writer.write(b"[3] " + b"x" * 70000)  # long, in several reads, then the end
        await c.writer.drain()
        c.writer.write(b"y" * 70000 + b"\r\n")
        assert await c.line() == "[3] ERROR:600"
        assert await c.ask("[4] 5 r 0x2000 0 vs") == '[4] "ABC"'
        await c.close()
        await server.close()

    run(main())


def test_client_limit_when_every_client_is_busy() -> None:
    """Every slot has a request running: one more client is refused, with a sequence
    number (cocomm reads a reply without one as a value), and closed."""
    async def main() -> None:
        m = _master()
        m.gates[5] = asyncio.Event()
        server, address = await start_gateway(m, max_clients=2)
        a = await Client.connect(address)
        b = await Client.connect(address)
        await a.send("[1] 5 r 0x1000 0 u32")
        await b.send("[1] 5 r 0x1000 0 u32")
        await eventually(lambda: 5 in m.started and server.clients == 2)
        c = await Client.connect(address)
        assert await c.line() == "[0] ERROR:102"
        assert await asyncio.wait_for(c.reader.read(), 5) == b""  # closed
        m.gates[5].set()
        assert await a.line() == "[1] 401"
        assert await b.line() == "[1] 401"
        await a.close()
        await eventually(lambda: server.clients == 1)
        d = await Client.connect(address)
        assert await d.ask("[2] 6 r 0x1000 0 u32") == "[2] 402"
        await b.close()
        await d.close()
        await server.close()

    run(main())


def test_slow_transfer_does_not_stall_other_clients() -> None:
    async def main() -> None:
        m = _master()
        m.gates[5] = asyncio.Event()
        server, address = await start_gateway(m)
        a = await Client.connect(address)
        b = await Client.connect(address)
        await a.send("[1] set sdo_block 1")
        assert await a.line() == "[1] OK"
        await a.send("[2] 5 r 0x1000 0 u32")  # held until the gate opens
        await eventually(lambda: 5 in m.started)
        for seq in range(3):
            assert await b.ask(f"[{seq}] 6 r 0x1000 0 u32") == f"[{seq}] 402"
        assert await b.ask("[9] 6 start") == "[9] OK"
        m.gates[5].set()
        assert await a.line() == "[2] 401"
        await a.close()
        await b.close()
        await server.close()

    run(main())


def test_pipelined_requests_answer_in_order() -> None:
    async def main() -> None:
        m = _master()
        server, address = await start_gateway(m)
        c = await Client.connect(address)
        c.writer.write(b"".join(f"[{i}] {5 + i % 2} r 0x1000 0 u32\r\n".encode()
                                for i in range(50)))
        await c.writer.drain()
        for i in range(50):
            assert await c.line() == f"[{i}] {401 + i % 2}"
        await c.close()
        await server.close()

    run(main())


def test_client_that_does_not_read_stalls_nobody() -> None:
    async def main() -> None:
        m = _master()
        server, address = await start_gateway(m)
        flood = await Client.connect(address)
        other = await Client.connect(address)
        assert await flood.ask("[0] set events 1") == "[0] OK"
        flood.writer.write(b"".join(f"[{i}] 5 r 0x1000 0 x32 # {'.' * 60}\r\n".encode()
                                    for i in range(40000)))  # and never reads a reply
        for _ in range(2000):
            m.emit(BootUp(9))  # events for the flooder too: dropped once its queue is full
        await asyncio.sleep(0.2)
        for seq in range(5):
            assert await other.ask(f"[{seq}] 6 r 0x1000 0 u32", timeout=5) == f"[{seq}] 402"
        await flood.close()
        await eventually(lambda: server.clients == 1)
        assert await other.ask("[9] 6 r 0x1000 0 u32") == "[9] 402"
        await other.close()
        await server.close()

    run(main())


def test_disconnect_mid_transfer_aborts() -> None:
    async def main() -> None:
        m = _master()
        m.gates[5] = asyncio.Event()
        server, address = await start_gateway(m)
        a = await Client.connect(address)
        await a.send("[1] 5 w 0x2200 0 d " + "QUJD" * 1000)
        await eventually(lambda: 5 in m.started)
        await a.close()
        await eventually(lambda: m.aborted == [(5, 0x2200, 0)])
        await eventually(lambda: server.clients == 0)
        b = await Client.connect(address)  # the node is free again
        del m.gates[5]
        assert await b.ask("[1] 5 r 0x1000 0 u32") == "[1] 401"
        await b.close()
        await server.close()

    run(main())


def test_events_to_subscribed_clients() -> None:
    async def main() -> None:
        m = _master()
        server, address = await start_gateway(m)
        quiet = await Client.connect(address)
        boots = await Client.connect(address)
        every = await Client.connect(address)
        assert await boots.ask("[1] boot_up_indication Enable") == "[1] OK"
        assert await every.ask("[1] set events 1") == "[1] OK"
        assert await every.ask("[2] 7 enable heartbeat 400") == "[2] OK"
        m.emit(BootUp(7))
        assert await boots.line() == "1 7 BOOT_UP"
        assert await every.line() == "1 7 BOOT_UP"
        m.emit(Emcy(7, 0x8130, 0x11, b"\x01\x02\x03\x04\x05"))
        assert await every.line() == "1 7 EMCY 8130 11 1 2 3 4 5"
        for _ in range(3):
            m.emit(Heartbeat(7, 0x05))
            await asyncio.sleep(0.01)
        assert await every.line(timeout=5) == "1 7 ERROR 203"  # no heartbeat for 400 ms
        m.emit(Heartbeat(7, 0x05))
        assert await every.line() == "1 7 ERROR 202"
        m.emit(HeartbeatLost(8))  # reported by the master itself
        assert await every.line() == "1 8 ERROR 203"
        assert await every.ask("[3] 7 disable heartbeat") == "[3] OK"
        assert await every.ask("[4] set events 0") == "[4] OK"
        m.emit(BootUp(9))
        assert await boots.line() == "1 9 BOOT_UP"
        assert await quiet.ask("[1] 5 r 0x1000 0 u32") == "[1] 401"  # no event before it
        assert await every.ask("[5] 5 r 0x1000 0 u32") == "[5] 401"
        for c in (quiet, boots, every):
            await c.close()
        await server.close()

    run(main())


def test_one_mib_domain_block_mode() -> None:
    async def main() -> None:
        m = _master()
        server, address = await start_gateway(m)
        c = await Client.connect(address)
        data = os.urandom(1024 * 1024)
        text = base64.b64encode(data).decode()
        assert await c.ask("[1] set sdo_block 1") == "[1] OK"
        assert await c.ask(f"[2] 5 w 0x2200 0 d {text}") == "[2] OK"
        assert m.objects[5, 0x2200, 0] == data
        assert m.calls[-1] == ("down", 5, True, 0)  # 0: the gateway's own time-out
        assert await c.ask("[3] 5 r 0x2200 0 d") == f"[3] {text}"
        assert m.calls[-1] == ("up", 5, True, 0)
        await c.close()
        await server.close()

    run(main())


def _pdo_master() -> FakeMaster:
    m = _master()
    for base in (0x1400, 0x1800):
        m.objects[1, base, 1] = (0x80000000).to_bytes(4, "little")
        m.objects[1, base, 2] = b"\xff"
    for sub in (3, 5):
        m.objects[1, 0x1800, sub] = b"\0\0"
    m.objects[1, 0x1800, 6] = b"\0"
    for base in (0x1600, 0x1A00):
        m.objects[1, base, 0] = b"\0"
        for sub in (1, 2):
            m.objects[1, base, sub] = b"\0\0\0\0"
    m.objects[1, 0x2000, 0] = b"\0"
    m.objects[1, 0x2001, 0] = b"\0\0"
    return m


def test_pdo_configuration_and_data() -> None:
    async def main() -> None:
        m = _pdo_master()
        sent: list[int] = []

        async def pdo_send(num: int) -> None:
            sent.append(num)

        m.pdo_send = pdo_send  # type: ignore[attr-defined]
        server, address = await start_gateway(m)
        c = await Client.connect(address)
        assert await c.ask("[1] set rpdo 1 0x205 event 2 0x2000 0 u8 0x2001 0 u16") == "[1] OK"
        assert m.objects[1, 0x1400, 1] == (0x205).to_bytes(4, "little")
        assert m.objects[1, 0x1400, 2] == b"\xff"
        assert m.objects[1, 0x1600, 0] == b"\x02"
        assert m.objects[1, 0x1600, 1] == (0x20000008).to_bytes(4, "little")
        assert m.objects[1, 0x1600, 2] == (0x20010010).to_bytes(4, "little")
        m.objects[1, 0x2000, 0] = b"\x2a"
        m.objects[1, 0x2001, 0] = b"\x34\x12"
        assert await c.ask("[2] r p 1") == "[2] 1 pdo 2 0x2A 0x1234"
        assert await c.ask("[3] set tpdox 1 0x185 event 20 500 2 0x2000 0 u8 0x2001 0 u16") \
            == "[3] OK"
        assert m.objects[1, 0x1800, 3] == (20).to_bytes(2, "little")
        assert m.objects[1, 0x1800, 5] == (500).to_bytes(2, "little")
        assert await c.ask("[4] w p 1 2 7 0x55AA") == "[4] OK"
        assert m.objects[1, 0x2000, 0] == b"\x07"
        assert m.objects[1, 0x2001, 0] == b"\xaa\x55"
        assert sent == [1]
        assert await c.ask("[5] w p 1 2 256 0") == "[5] ERROR:401"
        assert await c.ask("[6] w p 1 1 0") == "[6] ERROR:101"
        assert await c.ask("[7] r p 2") == "[7] ERROR:0x06020000"
        assert await c.ask("[8] set tpdo 3 0x187 sync1 0") == "[8] ERROR:0x06020000"
        assert await c.ask("[9] 2 r p 1") == "[9] ERROR:106"
        await c.close()
        await server.close()

    run(main())


def test_unix_socket() -> None:
    async def main() -> None:
        m = _master()
        hub = EventHub(m)
        server = GatewayServer(Executor(m, hub), hub)
        with tempfile.TemporaryDirectory() as tmp:
            path = os.path.join(tmp, "gw.sock")
            srv = await server.start(parse_listen(f"unix:{path}"))
            assert GatewayServer.address(srv) == f"unix:{path}"
            c = await Client.connect(f"unix:{path}")
            assert await c.ask("[1] 5 r 0x1000 0 u32") == "[1] 401"
            await c.close()
            await server.close()

    run(main())


def test_stream_end_finishes_pending_requests() -> None:
    async def main() -> None:
        m = _master()
        server = GatewayServer(Executor(m))
        script = [b"[1] 5 r 0x1000 0 u32\n[2] 6 r 0x1000 0 u32\n", b"[3] bogus"]
        written: list[bytes] = []

        async def read() -> bytes:
            return script.pop(0) if script else b""

        async def write(data: bytes) -> None:
            written.append(data)

        await server.serve_stream(read, write, eof_cancels=False)
        assert b"".join(written) == b"[1] 401\r\n[2] 402\r\n[3] ERROR:100\r\n"

    run(main())
