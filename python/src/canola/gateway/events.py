# SPDX-License-Identifier: Apache-2.0
"""Network events to the clients that asked for them, in CiA 309-3 event syntax.

Lines (no sequence number; ``<net>`` is the gateway's network number)::

    <net> <node> BOOT_UP                                    boot-up received
    <net> <node> ERROR 203                                  heartbeat lost
    <net> <node> ERROR 202                                  heartbeat (re)started
    <net> <node> EMCY <code> <register> <b0> <b1> <b2> <b3> <b4>
    <net> pdo <num> <n> <value>...                          the gateway's RPDO received

EMCY code and register in hexadecimal (4 and 2 digits), the five manufacturer-specific
bytes in decimal; PDO values in hexadecimal (``0x``). The hub also is the heartbeat
consumer of ``enable heartbeat``: one timer per watched node, restarted by each
heartbeat, that reports the loss once.
Backend listeners may run on any thread; the hub moves every event to its event loop.
"""

from __future__ import annotations

import asyncio
from collections.abc import Callable
from dataclasses import dataclass, field

from canola.gateway.backend import (
    Backend,
    BootUp,
    Emcy,
    Event,
    Heartbeat,
    HeartbeatLost,
    Rpdo,
)
from canola.gateway.codes import GatewayError

__all__ = ["EVENT_KINDS", "EventHub", "format_event"]

#: Kinds a client can subscribe to: boot-ups, error control (heartbeat), EMCY, RPDOs.
EVENT_KINDS = frozenset({"boot", "error", "emcy", "pdo"})


def format_event(net: int, event: Event) -> tuple[str, str] | None:
    """(kind, line) of an event, None for events that are not reported as such."""
    if isinstance(event, BootUp):
        return "boot", f"{net} {event.node} BOOT_UP"
    if isinstance(event, HeartbeatLost):
        return "error", f"{net} {event.node} ERROR {int(GatewayError.HEARTBEAT_LOST)}"
    if isinstance(event, Emcy):
        data = " ".join(str(b) for b in event.data[:5].ljust(5, b"\0"))
        return "emcy", f"{net} {event.node} EMCY {event.code:04X} {event.register:02X} {data}"
    if isinstance(event, Rpdo):
        values = "".join(f" 0x{v:X}" for v in event.values)
        return "pdo", f"{net} pdo {event.num} {len(event.values)}{values}"
    return None


@dataclass
class _Watch:
    ms: int
    timer: asyncio.TimerHandle | None = None
    lost: bool = False


@dataclass
class _Sink:
    deliver: Callable[[str], None]
    kinds: set[str] = field(default_factory=set)


class EventHub:
    """Fan-out of one backend's events to client sinks; heartbeat consumer timers."""

    def __init__(self, backend: Backend, net: int = 1) -> None:
        self.net = net
        self._loop = asyncio.get_running_loop()
        self._sinks: dict[int, _Sink] = {}
        self._next = 0
        self._watches: dict[int, _Watch] = {}
        self._unsubscribe = backend.subscribe(self._from_backend)

    # ---- clients

    def add_sink(self, deliver: Callable[[str], None], kinds: set[str] | None = None) -> int:
        """Register a client; returns its token. ``kinds`` defaults to none."""
        self._next += 1
        self._sinks[self._next] = _Sink(deliver, set(kinds or ()))
        return self._next

    def set_kinds(self, token: int, kinds: set[str]) -> None:
        self._sinks[token].kinds = set(kinds)

    def kinds(self, token: int) -> set[str]:
        return set(self._sinks[token].kinds)

    def remove_sink(self, token: int) -> None:
        self._sinks.pop(token, None)

    # ---- heartbeat consumer

    def watch_heartbeat(self, node: int, ms: int) -> None:
        """Expect a heartbeat of ``node`` at least every ``ms`` (0: stop watching)."""
        self.unwatch_heartbeat(node)
        if ms > 0:
            self._watches[node] = _Watch(ms)
            self._arm(node)

    def unwatch_heartbeat(self, node: int) -> None:
        watch = self._watches.pop(node, None)
        if watch is not None and watch.timer is not None:
            watch.timer.cancel()

    @property
    def watched(self) -> dict[int, int]:
        return {node: w.ms for node, w in self._watches.items()}

    def _arm(self, node: int) -> None:
        watch = self._watches[node]
        if watch.timer is not None:
            watch.timer.cancel()
        watch.timer = self._loop.call_later(watch.ms / 1000, self._expired, node)

    def _expired(self, node: int) -> None:
        watch = self._watches.get(node)
        if watch is None or watch.lost:
            return
        watch.lost = True
        watch.timer = None
        self._dispatch(HeartbeatLost(node))

    # ---- events

    def _from_backend(self, event: Event) -> None:
        try:
            running = asyncio.get_running_loop()
        except RuntimeError:
            running = None
        if running is self._loop:
            self._handle(event)
        elif not self._loop.is_closed():
            self._loop.call_soon_threadsafe(self._handle, event)

    def _handle(self, event: Event) -> None:
        if isinstance(event, Heartbeat | BootUp) and event.node in self._watches:
            watch = self._watches[event.node]
            if watch.lost:
                watch.lost = False
                self._send("error", f"{self.net} {event.node} ERROR "
                                    f"{int(GatewayError.HEARTBEAT_STARTED)}")
            self._arm(event.node)
        if isinstance(event, HeartbeatLost):
            lost = self._watches.get(event.node)
            if lost is not None:
                if lost.lost:
                    return
                lost.lost = True
        self._dispatch(event)

    def _dispatch(self, event: Event) -> None:
        formatted = format_event(self.net, event)
        if formatted is not None:
            self._send(*formatted)

    def _send(self, kind: str, line: str) -> None:
        for sink in list(self._sinks.values()):
            if kind in sink.kinds:
                sink.deliver(line)

    def close(self) -> None:
        self._unsubscribe()
        for node in list(self._watches):
            self.unwatch_heartbeat(node)
        self._sinks.clear()
