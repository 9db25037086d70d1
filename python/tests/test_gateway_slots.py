# SPDX-License-Identifier: Apache-2.0
"""Who loses a client slot when a new client comes and every slot is taken: the silent,
the stuck and the idle, never a client with a request running or recent traffic."""

from __future__ import annotations

import asyncio
import collections
import contextlib
import logging
from dataclasses import dataclass

import pytest
from gateway_helpers import Client, FakeMaster, run, start_gateway

from canola.gateway.slots import victim


def _master() -> FakeMaster:
    m = FakeMaster(node_id=1)
    m.objects[5, 0x1000, 0] = (0x191).to_bytes(4, "little")
    return m


async def _legit(address: str, seconds: float, replies: list[str]) -> None:
    """A client reading every 100 ms on one connection for ``seconds``; "dropped" in
    ``replies`` each time the gateway closed it (then it connects again)."""
    c = await Client.connect(address)
    loop = asyncio.get_running_loop()
    end = loop.time() + seconds
    i = 0
    while loop.time() < end:
        i += 1
        try:
            replies.append(await c.ask(f"[{i}] 5 r 0x1000 0 u32"))
        except (asyncio.IncompleteReadError, ConnectionError):
            replies.append("dropped")
            c.writer.transport.abort()
            c = await Client.connect(address)
        await asyncio.sleep(0.1)
    await c.close()


async def _churn(address: str, count: int) -> int:
    """Open ``count`` connections as fast as the gateway accepts them, each held (silent)
    until 64 newer ones are open: the slots stay full of fresh connections. How many
    connected."""
    host, _, port = address.removeprefix("tcp:").rpartition(":")
    held: collections.deque[asyncio.StreamWriter] = collections.deque()
    done = 0
    for _ in range(count):
        with contextlib.suppress(OSError):
            held.append((await asyncio.open_connection(host, int(port)))[1])
            done += 1
        if len(held) > 64:
            held.popleft().transport.abort()
        await asyncio.sleep(0)
    for writer in held:
        writer.transport.abort()
    return done


async def _idle(address: str, per_second: float, seconds: float) -> list[asyncio.StreamWriter]:
    """Open ``per_second`` connections a second that never send anything."""
    host, _, port = address.removeprefix("tcp:").rpartition(":")
    held = []
    loop = asyncio.get_running_loop()
    end = loop.time() + seconds
    while loop.time() < end:
        with contextlib.suppress(OSError):
            held.append((await asyncio.open_connection(host, int(port)))[1])
        await asyncio.sleep(1 / per_second)
    return held


@pytest.mark.slow
def test_a_reading_client_survives_churn_and_idle_floods(
        caplog: pytest.LogCaptureFixture) -> None:
    """A client reading every 100 ms keeps its connection (and gets every reply) while an
    attacker churns 2,000 connections and opens 40 idle ones a second, 16 slots in all.
    (Before, the reading client's slot went to newcomers again and again: between two
    reads it counted as idle, and a new connection as busy.)"""
    caplog.set_level(logging.INFO, logger="canola.gateway")

    async def main() -> None:
        server, address = await start_gateway(_master())
        replies: list[str] = []
        legit = asyncio.create_task(_legit(address, 6.0, replies))
        await asyncio.sleep(0.3)
        churned, held = await asyncio.gather(_churn(address, 2000), _idle(address, 40, 5.0))
        await legit
        for writer in held:
            writer.transport.abort()
        assert churned > 1000
        assert len(replies) >= 10
        assert replies.count("dropped") == 0, replies
        assert all(r.endswith("] 401") for r in replies), replies
        dropped = [r.getMessage() for r in caplog.records
                   if r.getMessage().startswith("client 1 ")]
        assert dropped == [], dropped[:3]
        await server.close()

    run(main(), timeout=120)


@dataclass
class Sim:
    """A client as the slot rules see it."""

    name: str
    connected_at: float
    last_line_at: float | None = None
    last_reply_at: float | None = None
    unwritten_since: float | None = None
    running: bool = False
    listening: bool = False


def test_the_rules_in_order() -> None:
    now = 100.0
    reading = Sim("reading", 0.0, last_line_at=99.9, last_reply_at=99.95)
    running = Sim("running", 0.0, last_line_at=10.0, running=True)
    listener = Sim("listener", 0.0, last_line_at=50.0, last_reply_at=50.0, listening=True)
    quiet = Sim("quiet", 0.0, last_line_at=80.0, last_reply_at=85.0)
    quieter = Sim("quieter", 0.0, last_line_at=60.0, last_reply_at=60.0)
    stuck = Sim("stuck", 0.0, last_line_at=99.0, unwritten_since=85.0)
    silent_old = Sim("silent, old", 90.0)
    silent_new = Sim("silent, new", 99.9)
    clients = [reading, running, listener, quiet, quieter, stuck, silent_old, silent_new]
    order = []
    while (chosen := victim(clients, now)) is not None:
        order.append((chosen[0].name, chosen[1]))
        clients.remove(chosen[0])
    assert order == [("silent, old", "silent since it connected 10.0 s ago"),
                     ("silent, new", "silent since it connected 0.1 s ago"),
                     ("stuck", "its replies unread for 15.0 s"),
                     ("quieter", "quiet for 40.0 s"), ("quiet", "quiet for 15.0 s"),
                     ("listener", "quiet for 50.0 s")]
    assert [c.name for c in clients] == ["reading", "running"]  # never picked
    assert victim([Sim("busy", 0.0, last_line_at=1.0, unwritten_since=0.5, running=True)],
                  now) is None


def test_floods_of_new_connections_only_replace_themselves() -> None:
    """The accept loop in simulated time, 20 s, 16 slots: a client reading every 100 ms
    (5 ms per request), 3,071 churned connections, 40 idle connections a second, and a
    client that sent one line then stopped reading. Only the new silent connections ever
    lose their slots; the one that stopped reading goes first once they are gone."""
    reader = Sim("reader", 0.0, last_line_at=0.0, last_reply_at=0.0)
    stuck = Sim("stuck", 0.0, last_line_at=0.5, unwritten_since=0.5)
    slots: list[Sim] = [reader, stuck]
    arrivals = sorted([(i * 20.0 / 3071, "churn") for i in range(3071)] +
                      [(i / 40, "idle") for i in range(800)])
    lost: list[tuple[float, str]] = []
    refused = 0
    for t, kind in arrivals:
        # the reader's line at each 100 ms tick, its reply 5 ms later
        tick = int(t * 10) / 10
        reader.last_line_at = tick
        reader.running = t - tick < 0.005
        reader.last_reply_at = tick - 0.095 if reader.running else tick + 0.005
        if len(slots) >= 16:
            chosen = victim(slots, t)
            if chosen is None:
                refused += 1
                continue
            lost.append((t, chosen[0].name))
            slots.remove(chosen[0])
        slots.append(Sim(f"{kind} {t:.3f}", t))
    assert {name.split()[0] for _, name in lost} == {"churn", "idle"}  # silent ones first
    assert refused == 0
    assert reader in slots and stuck in slots
    # the flood over, the next newcomer takes the stuck client's slot
    slots = [c for c in slots if c in (reader, stuck)] + [
        Sim(f"quiet {i}", 0.0, last_line_at=19.0, last_reply_at=19.0) for i in range(14)]
    assert victim(slots, 20.0) == (stuck, "its replies unread for 19.5 s")
