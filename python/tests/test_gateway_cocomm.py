# SPDX-License-Identifier: Apache-2.0
"""The gateway as ``cocomm`` and CANopenDemo's scripts see it: replies framed and numbered
as CANopenNode's gateway frames them (fake master; the LSS codes are in
test_gateway_lss.py, NMT frames on a bus in test_gateway_master.py)."""

from __future__ import annotations

import asyncio

from gateway_helpers import Client, FakeMaster, run, start_gateway

from canola.gateway import GatewayServer
from canola.gateway.helptext import TOPICS


async def _start(master: FakeMaster) -> tuple[GatewayServer, Client]:
    server, address = await start_gateway(master)
    return server, await Client.connect(address)


def _master() -> FakeMaster:
    m = FakeMaster(node_id=1)
    m.objects[5, 0x1000, 0] = (0x191).to_bytes(4, "little")
    m.objects[5, 0x2013, 0] = b"a\tb"
    return m


async def _cocomm_reply(c: Client) -> bytes:
    """A reply as cocomm reads it: everything up to the first CR LF."""
    return await asyncio.wait_for(c.reader.readuntil(b"\r\n"), 20)


def test_multi_line_replies_end_with_one_crlf() -> None:
    """help, help datatype and help lss: LF between the lines, one CR LF at the end, so
    the reply to the next request is the next thing cocomm reads."""
    async def main() -> None:
        server, c = await _start(_master())
        c.writer.write(b"[1] help\r\n[2] help datatype\r\n[3] help lss\r\n"
                       b"[4] 5 r 0x1000 0 u32\r\n")
        for seq, topic in ((1, ""), (2, "datatype"), (3, "lss")):
            reply = (await _cocomm_reply(c)).decode()
            assert reply == f"[{seq}] {TOPICS[topic]}\r\n"
            assert reply.count("\n") == TOPICS[topic].count("\n") + 1 > 3
        assert await _cocomm_reply(c) == b"[4] 401\r\n"
        await c.close()
        await server.close()

    run(main())


def test_network_zero_is_the_default_network() -> None:
    async def main() -> None:
        server, c = await _start(_master())
        assert await c.ask("[1] 0 5 r 0x1000 0 u32") == "[1] 401"
        assert await c.ask("[2] 0 set node 5") == "[2] OK"
        assert await c.ask("[3] r 0x1000 0 u32") == "[3] 401"
        assert await c.ask("[4] set network 0") == "[4] OK"
        assert await c.ask("[5] r 0x1000 0 u32") == "[5] 401"
        assert await c.ask("[6] 1 5 r 0x1000 0 u32") == "[6] 401"  # its own number too
        assert await c.ask("[7] 2 5 r 0x1000 0 u32") == "[7] ERROR:106"  # another one
        assert await c.ask("[8] set network 2") == "[8] ERROR:106"
        await c.close()
        await server.close()

    run(main())


def test_tab_in_a_visible_string_is_a_tab() -> None:
    async def main() -> None:
        m = _master()
        server, c = await _start(m)
        assert await c.ask("[1] 5 r 0x2013 0 vs") == '[1] "a\tb"'
        assert await c.ask('[2] 5 w 0x2013 0 vs "c\td e"') == "[2] OK"
        assert m.objects[5, 0x2013, 0] == b"c\td e"
        assert await c.ask("[3] 5 r 0x2013 0 vs") == '[3] "c\td e"'
        m.objects[5, 0x2013, 0] = b"line\r\nbreak"  # what would break the line stays escaped
        assert await c.ask("[4] 5 r 0x2013 0 vs") == '[4] "line\\r\\nbreak"'
        await c.close()
        await server.close()

    run(main())


def test_set_values_out_of_range_are_syntax_errors() -> None:
    """As CANopenNode's gateway answers them: 101; ``set heartbeat`` (a canola extra, the
    gateway's own producer time) the same way."""
    async def main() -> None:
        m = _master()
        m.objects[1, 0x1017, 0] = b"\0\0"
        server, c = await _start(m)
        for seq, line in enumerate(["set node 0", "set node 128", "set sdo_timeout 0",
                                    "set sdo_block 2", "set heartbeat 65536", "set heartbeat",
                                    "set heartbeat 1 2", "set heartbeat -1"], start=1):
            assert await c.ask(f"[{seq}] {line}") == f"[{seq}] ERROR:101", line
        assert await c.ask("[20] set heartbeat 500") == "[20] OK"
        assert m.objects[1, 0x1017, 0] == (500).to_bytes(2, "little")
        assert await c.ask("[21] set nothing 1") == "[21] ERROR:100"
        await c.close()
        await server.close()

    run(main())
