# SPDX-License-Identifier: Apache-2.0
"""The SDO client channels of a master's C node and who uses them: :class:`canola.Master`
(one channel per server it talks to), the CANopen manager (one channel of its own) and
program download. They share the node's engine and this allocator, not the master."""

from __future__ import annotations

import logging
import threading
from typing import Any

from canola._c import CData, check, ffi, lib
from canola._engine import Engine
from canola.errors import Error

__all__ = ["CHANNELS", "SdoChannels", "Transfer"]

log = logging.getLogger("canola")

#: SDO client channels of the C node (0x1280..0x128F; CO_SDO_CLIENTS_MAX in the extension).
CHANNELS = 16

#: 0x1280 + channel, sub-indices 1 and 2: COB-ID not valid.
_INVALID = (0x80000000).to_bytes(4, "little")


class Transfer:
    """One SDO transfer of a client channel, as its completion (canola_py_sdo_done) left
    it: ``done``, ``abort`` (0: none) and ``length`` (bytes moved)."""

    def __init__(self) -> None:
        self.done = False
        self.abort = 0
        self.length = 0

    def notify(self) -> None:
        """Called (from the C completion) once ``done``, ``abort`` and ``length`` are set."""


@ffi.def_extern(onerror=lambda *_: log.exception("canola: SDO completion failed"))
def canola_py_sdo_done(ctx: Any, channel: int, abort: int, length: int) -> None:
    del channel
    t: Transfer = ffi.from_handle(ctx)
    t.abort = int(abort)
    t.length = int(length)
    t.done = True
    t.notify()


def server(node: CData, channel: int) -> int:
    """Whom client channel ``channel`` of the C node talks to now: node n, 0 for nobody,
    -1 for COB-IDs of someone else's choosing (see canola_py_sdo_client_server)."""
    return int(lib.canola_py_sdo_client_server(node, channel))


def unset(node: CData, channel: int) -> None:
    """Point client channel ``channel`` at no server (under the lock); co_sdo_client_setup()
    gives it one again."""
    for sub, data in ((1, _INVALID), (2, _INVALID), (3, b"\x00")):
        lib.canola_py_app_write(node, 0x1280 + channel, sub, data, len(data))


class SdoChannels:
    """The channel of each server (a memo of the core's channels, checked on every use: a
    reset communication of the node reloads 0x1280.. from their power-on values, and an SDO
    client may write them), the manager's reserved channel, and one lock per server: one
    transfer at a time to a server, whoever starts it."""

    def __init__(self, engine: Engine) -> None:
        self.engine = engine
        self.table: dict[int, int] = {}  # server node-ID -> channel; 0: the manager's
        self._locks: dict[int, threading.Lock] = {}

    @property
    def node_id(self) -> int:
        """The node-ID of the C node whose channels these are."""
        return int(lib.co_node_id(self.engine.node))

    def lock_of(self, server_id: int) -> threading.Lock:
        """The lock a transfer to ``server_id`` holds from its start to its end."""
        lock = self._locks.get(server_id)
        if lock is None:
            lock = self._locks.setdefault(server_id, threading.Lock())
        return lock

    def channel(self, node: CData, server_id: int) -> int:
        """The client channel talking to ``server_id``, set up if needed (under the lock)."""
        channel = self.table.get(server_id)
        if channel is not None and server(node, channel) == server_id:
            return channel
        self.table = {n: c for n, c in self.table.items()
                      if n == 0 or server(node, c) == n}  # 0: the manager's channel
        used = set(self.table.values())
        servers = {c: server(node, c) for c in range(CHANNELS) if c not in used}
        for c, talks_to in servers.items():  # set up to it by someone else (0x1280 written)
            if talks_to == server_id:
                self.table[server_id] = c
                return c
        free = [c for c, talks_to in servers.items() if talks_to == 0]
        if not free:  # take the channel of a node that has no transfer open
            for other, c in list(self.table.items()):
                if not lib.co_sdo_client_busy(node, c):
                    del self.table[other]
                    free = [c]
                    break
        if not free:
            raise Error(f"all {CHANNELS} SDO client channels are busy")
        channel = free[0]
        check(int(lib.co_sdo_client_setup(node, channel, server_id)), "co_sdo_client_setup")
        self.table[server_id] = channel
        return channel

    def abort(self, server_id: int) -> None:
        """End the transfer to ``server_id`` in progress, if any, with 0x05040000 (its
        completion runs)."""
        channel = self.table.get(server_id)
        if channel is None:
            return
        with self.engine.locked() as node:
            if lib.co_sdo_client_busy(node, channel):
                lib.co_sdo_client_abort(node, channel, 0x05040000)

    def release(self, node: CData, server_ids: list[int]) -> None:
        """Free the channels to ``server_ids`` (under the lock): a server is talked to by
        one client channel at a time, and the manager needs its own."""
        for server_id in server_ids:
            channel = self.table.get(server_id)
            if channel is None:
                continue
            if lib.co_sdo_client_busy(node, channel):
                raise Error(f"an SDO transfer to node {server_id} is in progress")
            unset(node, channel)
            del self.table[server_id]

    def reserve(self) -> int:
        """A channel for the manager (under the lock): the one kept under key 0 (no SDO
        server has node-ID 0), else a free one."""
        if 0 in self.table:
            return self.table[0]
        used = set(self.table.values())
        free = [c for c in range(CHANNELS) if c not in used]
        if not free:
            raise Error("no free SDO client channel for the manager")
        self.table[0] = free[-1]
        return free[-1]
