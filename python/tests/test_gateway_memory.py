# SPDX-License-Identifier: Apache-2.0
"""The bytes the gateway holds for its clients are bounded per client and in total: a
request line past either bound is answered ERROR:600 and nothing accepted before it is
lost; a client that does not read its replies stops having requests run (fake master,
its node 5 held back by a gate while the lines pile up)."""

from __future__ import annotations

import asyncio
import base64
import os
import tracemalloc

from gateway_helpers import Client, FakeMaster, eventually, run, start_gateway

from canola.gateway import GatewayServer

KIB = 1024
MIB = 1024 * KIB
LIMITS = {"max_line": 512 * KIB, "max_queued": 1 * MIB, "max_queued_total": 2 * MIB}


def _lines_read(server: GatewayServer, count: int) -> bool:
    return all(conn.last_seq == count for conn in server._connections)


def test_queued_lines_are_bounded_per_client_and_in_total() -> None:
    """Four clients each pipeline 40 domain writes of 300 kB (400 kB lines) to a node
    that does not answer yet: 16 MB a client. At most 1 MiB a client and 2 MiB in all
    are held; the Python heap grows by far less than the 48 MB the lines carry (before:
    every line was parsed and queued, 160 requests, the heap past 50 MB). Once the node
    answers, every line gets its reply in order: OK for each line accepted (its data
    written, none lost), ERROR:600 for the others; then the bounds are free again."""
    async def main() -> None:
        m = FakeMaster(node_id=1)
        m.gates[5] = asyncio.Event()
        server, address = await start_gateway(m, **LIMITS)  # type: ignore[arg-type]
        payloads = [os.urandom(300_000) for _ in range(4)]
        clients = [await Client.connect(address) for _ in range(4)]
        tracemalloc.start()
        try:
            async def pipeline(c: Client, k: int) -> None:
                text = base64.b64encode(payloads[k]).decode()
                for i in range(1, 41):
                    await c.send(f"[{i}] 5 w 0x2000 {k * 40 + i} d {text}")

            await asyncio.gather(*(pipeline(c, k) for k, c in enumerate(clients)))
            await eventually(lambda: _lines_read(server, 40), 60)
            assert server.budget.used <= 2 * MIB
            assert all(conn.share.used <= MIB for conn in server._connections)
            _, peak = tracemalloc.get_traced_memory()
        finally:
            tracemalloc.stop()
        assert peak < 16 * MIB, f"{peak / MIB:.1f} MiB"
        m.gates[5].set()
        accepted = 0
        for k, c in enumerate(clients):
            replies = [await c.line() for _ in range(40)]
            for i, reply in enumerate(replies, start=1):
                if reply == f"[{i}] OK":
                    accepted += 1
                    assert m.objects[5, 0x2000, k * 40 + i] == payloads[k]
                else:
                    assert reply.startswith(f"[{i}] ERROR:600 #"), reply
                    assert (5, 0x2000, k * 40 + i) not in m.objects
            assert replies[0] == "[1] OK"  # each client got its share
        assert 4 <= accepted <= 2 * MIB // 400_000 + 4  # running ones hold bytes too
        await eventually(lambda: server.budget.used == 0)
        assert await clients[0].ask("[41] 5 w 0x2000 0 u8 1") == "[41] OK"
        for c in clients:
            await c.close()
        await server.close()

    run(main(), timeout=120)


def test_a_client_that_does_not_read_stops_having_requests_run() -> None:
    """40 reads of a 300 kB domain (400 kB replies) from a client that reads nothing:
    requests stop running once its unread replies reach its 1 MiB, and its lines that
    come meanwhile are refused (ERROR:600: wait for the replies) (before: all 40 ran,
    16 MB of replies held for it). When it reads, it gets every reply in order, and the
    lines it sends then run again."""
    async def main() -> None:
        m = FakeMaster(node_id=1)
        data = os.urandom(300_000)
        m.objects[5, 0x2100, 0] = data
        server, address = await start_gateway(m, **LIMITS)  # type: ignore[arg-type]
        c = await Client.connect(address)
        c.writer.transport.pause_reading()
        for i in range(1, 41):
            await c.send(f"[{i}] 5 r 0x2100 0 d")
        await eventually(lambda: _lines_read(server, 40))
        await asyncio.sleep(0.5)  # what could run has run
        ran = len(m.calls)
        # 1 MiB of replies held here, and those the kernel's socket buffers took (on
        # loopback they grow to a few MB)
        assert ran <= 24, ran
        assert server.budget.used <= MIB + 400 * KIB + 40 * 30
        c.writer.transport.resume_reading()
        text = base64.b64encode(data).decode()
        replies = [await c.line() for _ in range(40)]
        served = [i for i, reply in enumerate(replies, start=1) if reply == f"[{i}] {text}"]
        assert served == list(range(1, len(served) + 1))  # first come, first served
        assert all(reply.startswith(f"[{i}] ERROR:600 #") for i, reply in
                   enumerate(replies[len(served):], start=len(served) + 1))
        assert len(m.calls) == len(served) >= ran
        for i in range(41, 44):  # reading now: served again
            assert await c.ask(f"[{i}] 5 r 0x2100 0 d") == f"[{i}] {text}"
        await c.close()
        await server.close()

    run(main(), timeout=120)
