# SPDX-License-Identifier: Apache-2.0
"""Runs parsed gateway requests against a master (:class:`~canola.gateway.backend.Backend`).

One :class:`Session` per client holds what CiA 309-3 makes per-connection: default
network and node, SDO time-out, block transfer on/off, and which events it receives.
:meth:`Executor.execute` turns one request into its reply (without line end): ``[seq] OK``,
``[seq] <value>``, ``[seq] ERROR:0x<abort code>`` or ``[seq] ERROR:<gateway error>``; a
reply of several lines (help, ``lss_allnodes``) has them joined with LF.

Concurrency: requests of different clients run concurrently; SDO transfers to one node
take turns (one lock per node), so a long block transfer to one node does not hold up
requests to any other node. SDO requests to the gateway's own node-ID are served from
its own dictionary without a frame on the bus, as the network would see it, except that
a SYNC period (0x1006) shorter than :data:`SYNC_PERIOD_MIN_US` is refused (abort
0x06090030): a SYNC every microsecond would flood the bus and starve the gateway's own
SDO traffic. NMT commands to its own node-ID or to all nodes (0) are sent on the bus and
applied to itself (as CANopenNode's gateway does); while its node is not in a state that
allows SDO (STOPPED), SDO requests to other nodes are answered ``ERROR:204`` naming the
state (:mod:`canola.gateway.ownnode`). Network 0 is the gateway's own network.
"""

from __future__ import annotations

import asyncio
import logging
from collections.abc import Awaitable, Callable
from dataclasses import dataclass, field
from typing import TypeVar

from canola import __version__
from canola.errors import Error, SdoAbort
from canola.gateway.backend import Backend
from canola.gateway.codes import GatewayError, GatewayFailure
from canola.gateway.events import EVENT_KINDS, EventHub
from canola.gateway.formats import TYPES, format_value
from canola.gateway.helptext import TOPICS
from canola.gateway.lsscommands import LssCommands
from canola.gateway.ownnode import SDO_STATES
from canola.gateway.parser import ParseError
from canola.gateway.pdo import mapped_entries, mapped_values
from canola.gateway.requests import (
    BootUpIndication,
    DisableGuarding,
    DisableHeartbeat,
    EnableGuarding,
    EnableHeartbeat,
    Help,
    InfoVersion,
    Init,
    Lss,
    Nmt,
    PdoRead,
    PdoWrite,
    Request,
    SdoRead,
    SdoWrite,
    Set,
    SetRpdo,
    SetTpdo,
)

__all__ = ["GATEWAY_CLASS", "PROTOCOL_VERSION", "SYNC_PERIOD_MIN_US", "Executor", "Session",
           "error_reply"]

#: CiA 309-1 gateway class and CiA 309-3 protocol version that ``info version`` reports.
GATEWAY_CLASS = 2
PROTOCOL_VERSION = (3, 0)
ABORT_TIMEOUT = 0x05040000
#: What the SDO client ends a transfer with when its own node leaves the SDO states.
ABORT_DEVICE_STATE = 0x08000022
ABORT_VALUE_RANGE = 0x06090030
#: The shortest SYNC period (us) the gateway's own 0x1006 takes from a client (0: off).
#: A SYNC frame lasts up to ~55 us at 1 Mbit/s and ~440 us at 125 kbit/s: at 1 ms the bus
#: keeps room for everything else even at 125 kbit/s.
SYNC_PERIOD_MIN_US = 1000

log = logging.getLogger("canola.gateway")
T = TypeVar("T")


def error_reply(seq: int, code: int, *, abort: bool = False, note: str = "") -> str:
    """``[seq] ERROR:<code>`` (``abort``: ``ERROR:0x<abort code>``), ``note`` after it as
    a comment (`` #note``)."""
    text = f"ERROR:0x{code:08X}" if abort else f"ERROR:{code}"
    return f"[{seq}] {text}" + (f" #{note}" if note else "")


@dataclass
class Session:
    """Per-client state."""

    net: int = 1
    node: int | None = None
    sdo_timeout_ms: int = 0  # 0: the gateway's own (canola gateway --sdo-timeout)
    sdo_block: bool = False
    command_timeout_ms: int = 0
    command_size: int = 0
    events: set[str] = field(default_factory=set)
    on_events_changed: Callable[[set[str]], None] | None = None

    def set_events(self, kinds: set[str]) -> None:
        self.events = set(kinds)
        if self.on_events_changed is not None:
            self.on_events_changed(self.events)


class Executor:
    """Executes requests for any number of sessions against one backend."""

    def __init__(self, backend: Backend, hub: EventHub | None = None, *, net: int = 1) -> None:
        self.backend = backend
        self.hub = hub
        self.net = net
        self._locks: dict[int, asyncio.Lock] = {}
        self._lss = LssCommands(backend)

    def new_session(self) -> Session:
        return Session(net=self.net)

    async def execute(self, session: Session, request: Request) -> str:
        """The reply to ``request``; never raises for a request that fails."""
        seq = request.seq
        try:
            if session.command_timeout_ms > 0:
                async with asyncio.timeout(session.command_timeout_ms / 1000):
                    return await self._run(session, request)
            return await self._run(session, request)
        except SdoAbort as exc:
            return error_reply(seq, exc.code, abort=True)
        except GatewayFailure as exc:
            return error_reply(seq, exc.code, note=exc.note)
        except ParseError as exc:
            return error_reply(seq, exc.code)
        except TimeoutError:
            return error_reply(seq, GatewayError.TIMEOUT)
        except Error as exc:
            log.info("request %d: %s", seq, exc)
            return error_reply(seq, GatewayError.INTERNAL_STATE)
        except Exception:  # a bug must cost one reply, not the connection
            log.exception("request %d failed", seq)
            return error_reply(seq, GatewayError.INTERNAL_STATE)

    # ---- helpers

    def _net(self, session: Session, request: Request) -> int:
        net = request.net if request.net is not None else session.net
        if net == 0:  # CANopenNode's default network
            net = self.net
        if net != self.net:
            raise GatewayFailure(GatewayError.UNSUPPORTED_NET, f"network {net}")
        return net

    def _node(self, session: Session, request: Request, *, allow_all: bool = False) -> int:
        self._net(session, request)
        node = request.node if request.node is not None else session.node
        if node is None:
            raise GatewayFailure(GatewayError.NO_DEFAULT_NODE)
        if not (0 if allow_all else 1) <= node <= 127:
            raise GatewayFailure(GatewayError.UNSUPPORTED_NODE, f"node {node}")
        return node

    def _lock(self, node: int) -> asyncio.Lock:
        lock = self._locks.get(node)
        if lock is None:
            lock = self._locks[node] = asyncio.Lock()
        return lock

    async def _upload(self, session: Session, node: int, index: int, sub: int) -> bytes:
        if node == self.backend.node_id:
            return self.backend.local_read(index, sub)
        return await self._remote(node, lambda: self.backend.sdo_upload(
            node, index, sub, block=session.sdo_block, timeout_ms=session.sdo_timeout_ms))

    async def _download(self, session: Session, node: int, index: int, sub: int,
                        data: bytes) -> None:
        if node == self.backend.node_id:
            self._check_local(index, sub, data)
            self.backend.local_write(index, sub, data)
            return
        await self._remote(node, lambda: self.backend.sdo_download(
            node, index, sub, data, block=session.sdo_block,
            timeout_ms=session.sdo_timeout_ms))

    async def _remote(self, node: int, transfer: Callable[[], Awaitable[T]]) -> T:
        """One SDO transfer to another node, in turn with the others to ``node``, while the
        gateway's own node allows SDO (else ERROR:204)."""
        async with self._lock(node):
            closings = self.backend.sdo_closings
            self._check_own_state()
            try:
                return await transfer()
            except TimeoutError:
                raise SdoAbort(ABORT_TIMEOUT) from None
            except Error as exc:  # the device's abort, or the gateway's own stop?
                ours = not isinstance(exc, SdoAbort) or exc.code == ABORT_DEVICE_STATE
                if ours and self.backend.sdo_closings != closings:
                    raise self._wrong_state("was stopped or reset during the transfer, "
                                            "now") from None
                if ours:
                    self._check_own_state()
                raise

    def _check_own_state(self) -> None:
        if self.backend.nmt_state not in SDO_STATES:
            raise self._wrong_state("is")

    def _wrong_state(self, what: str) -> GatewayFailure:
        state = self.backend.nmt_state
        note = (f"the gateway's node {self.backend.node_id} {what} {state}: no SDO "
                "until it is started (CiA 301)")
        return GatewayFailure(GatewayError.WRONG_NMT_STATE, note, note=note)

    @staticmethod
    def _check_local(index: int, sub: int, data: bytes) -> None:
        """What the gateway refuses in its own dictionary beyond the entry's own limits."""
        if (index, sub) == (0x1006, 0) and len(data) == 4:
            period = int.from_bytes(data, "little")
            if 0 < period < SYNC_PERIOD_MIN_US:
                raise SdoAbort(ABORT_VALUE_RANGE)

    def _local_uint(self, index: int, sub: int) -> int:
        return int.from_bytes(self.backend.local_read(index, sub), "little")

    def _local_put(self, index: int, sub: int, value: int, size: int) -> None:
        self.backend.local_write(index, sub, value.to_bytes(size, "little"))

    # ---- requests

    async def _run(self, session: Session, request: Request) -> str:
        seq = request.seq
        ok = f"[{seq}] OK"
        if isinstance(request, SdoRead):
            node = self._node(session, request)
            data = await self._upload(session, node, request.index, request.sub)
            try:
                text = format_value(request.type, data)
            except ValueError:
                raise SdoAbort(0x06070010) from None  # length does not match the type
            return f"[{seq}] {text}"
        if isinstance(request, SdoWrite):
            node = self._node(session, request)
            await self._download(session, node, request.index, request.sub, request.data)
            return ok
        if isinstance(request, Nmt):
            node = self._node(session, request, allow_all=True)
            await self.backend.nmt(node, request.command)
            if node in (0, self.backend.node_id):  # it is a node of the network too
                await self.backend.local_nmt(request.command)
            return ok
        if isinstance(request, Set):
            return self._set(session, request)
        if isinstance(request, EnableHeartbeat | DisableHeartbeat):
            node = self._node(session, request)
            if self.hub is None:
                raise GatewayFailure(GatewayError.REQUEST_NOT_SUPPORTED)
            if isinstance(request, EnableHeartbeat):
                self.hub.watch_heartbeat(node, request.ms)
            else:
                self.hub.unwatch_heartbeat(node)
            return ok
        if isinstance(request, EnableGuarding | DisableGuarding):
            self._node(session, request)
            raise GatewayFailure(GatewayError.REQUEST_NOT_SUPPORTED, "node guarding")
        if isinstance(request, BootUpIndication):
            self._net(session, request)
            kinds = set(session.events)
            if request.enable:
                kinds.add("boot")
            else:
                kinds.discard("boot")
            session.set_events(kinds)
            return ok
        if isinstance(request, SetRpdo | SetTpdo):
            self._net(session, request)
            self._configure_pdo(request)
            return ok
        if isinstance(request, PdoRead):
            self._net(session, request)
            values = mapped_values(self.backend.local_read, 0x1600 + request.num - 1)
            text = " ".join(f"0x{v:X}" for v in values)
            return f"[{seq}] {self.net} pdo {len(values)}" + (f" {text}" if text else "")
        if isinstance(request, PdoWrite):
            self._net(session, request)
            await self._pdo_write(request)
            return ok
        if isinstance(request, InfoVersion):
            return f"[{seq}] {self._version()}"
        if isinstance(request, Help):
            return f"[{seq}] {TOPICS[request.topic]}"
        if isinstance(request, Init):
            self._net(session, request)
            raise GatewayFailure(GatewayError.REQUEST_NOT_SUPPORTED, "init")
        if isinstance(request, Lss):
            self._net(session, request)
            return await self._lss.run(request)
        raise GatewayFailure(GatewayError.REQUEST_NOT_SUPPORTED, type(request).__name__)

    def _set(self, session: Session, request: Set) -> str:
        ok = f"[{request.seq}] OK"
        what, value = request.what, request.value
        if what == "network":
            if value not in (0, self.net):
                raise GatewayFailure(GatewayError.UNSUPPORTED_NET, f"network {value}")
            session.net = self.net
            return ok
        self._net(session, request)
        if what == "node":
            session.node = value
        elif what == "sdo_timeout":
            session.sdo_timeout_ms = value
        elif what == "sdo_block":
            session.sdo_block = bool(value)
        elif what == "command_timeout":
            session.command_timeout_ms = value
        elif what == "command_size":
            session.command_size = value
        elif what == "events":
            session.set_events(set(EVENT_KINDS) if value else set())
        elif what == "heartbeat":
            self._local_put(0x1017, 0, value, 2)
        else:  # "id": the master's node-ID is fixed at start-up
            raise GatewayFailure(GatewayError.REQUEST_NOT_SUPPORTED, f"set {what}")
        return ok

    def _version(self) -> str:
        ident = []
        for sub in (1, 2, 3, 4):
            try:
                ident.append(self._local_uint(0x1018, sub))
            except SdoAbort:
                ident.append(0)
        vendor, product, revision, serial = ident
        major, minor = (int(p) for p in [*__version__.split("."), "0", "0"][:2])
        return (f"{vendor} {product} {revision >> 16}.{revision & 0xFFFF} {serial} "
                f"{GATEWAY_CLASS} {PROTOCOL_VERSION[0]}.{PROTOCOL_VERSION[1]} {major}.{minor}")

    def _configure_pdo(self, request: SetRpdo | SetTpdo) -> None:
        tpdo = isinstance(request, SetTpdo)
        comm = (0x1800 if tpdo else 0x1400) + request.num - 1
        mapping = (0x1A00 if tpdo else 0x1600) + request.num - 1
        cob_id = self._local_uint(comm, 1)
        self._local_put(comm, 1, cob_id | 0x80000000, 4)  # not valid while changing
        self._local_put(comm, 2, request.transmission, 1)
        if isinstance(request, SetTpdo):
            if request.transmission >= 0xFE:
                self._local_put(comm, 3, request.inhibit, 2)
            if request.transmission >= 0xFD:
                self._local_put(comm, 5, request.event, 2)
            elif request.sync:
                self._local_put(comm, 6, request.sync, 1)
        self._local_put(mapping, 0, 0, 1)
        for i, entry in enumerate(request.mapping, start=1):
            self._local_put(mapping, i, entry, 4)
        self._local_put(mapping, 0, len(request.mapping), 1)
        self._local_put(comm, 1, request.cob_id, 4)

    async def _pdo_write(self, request: PdoWrite) -> None:
        entries = mapped_entries(self.backend.local_read, 0x1A00 + request.num - 1)
        if len(entries) != len(request.values):
            raise GatewayFailure(GatewayError.SYNTAX, "value count differs from the mapping")
        for (index, sub, bits), value in zip(entries, request.values, strict=True):
            if value >> max(bits, 1):
                raise GatewayFailure(GatewayError.PDO_LENGTH_EXCEEDED, f"0x{value:X}")
            self._local_put(index, sub, value, max(1, (bits + 7) // 8))
        send = getattr(self.backend, "pdo_send", None)
        if send is not None:
            await send(request.num)


def type_names() -> list[str]:
    """The data type names requests accept (for help and tests)."""
    return sorted(TYPES)
