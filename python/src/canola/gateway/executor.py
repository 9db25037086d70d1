"""Runs parsed gateway requests against a master (:class:`~canola.gateway.backend.Backend`).

One :class:`Session` per client holds what CiA 309-3 makes per-connection: default
network and node, SDO time-out, block transfer on/off, and which events it receives.
:meth:`Executor.execute` turns one request into its reply lines (without line ends):
``[seq] OK``, ``[seq] <value>``, ``[seq] ERROR:0x<abort code>`` or
``[seq] ERROR:<gateway error>``.

Concurrency: requests of different clients run concurrently; SDO transfers to one node
take turns (one lock per node), so a long block transfer to one node does not hold up
requests to any other node. SDO requests to the gateway's own node-ID are served from
its own dictionary without a frame on the bus; NMT commands to its own node-ID apply to
itself.
"""

from __future__ import annotations

import asyncio
import logging
from collections.abc import Callable
from dataclasses import dataclass, field

from canola import __version__
from canola.errors import Error, SdoAbort
from canola.gateway.backend import Backend
from canola.gateway.codes import GatewayError, GatewayFailure
from canola.gateway.events import EVENT_KINDS, EventHub
from canola.gateway.formats import TYPES, format_value
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

__all__ = ["GATEWAY_CLASS", "HELP", "PROTOCOL_VERSION", "Executor", "Session",
           "error_reply"]

#: CiA 309-1 gateway class and CiA 309-3 protocol version that ``info version`` reports.
GATEWAY_CLASS = 2
PROTOCOL_VERSION = (3, 0)
ABORT_TIMEOUT = 0x05040000

log = logging.getLogger("canola.gateway")

HELP = """\
canola CiA 309-3 gateway. Requests: [<seq>] [[<net>] <node>] <command>; replies
[<seq>] OK | <value> | ERROR:0x<SDO abort code> | ERROR:<gateway error code>.
  r[ead] <index> <sub> [<type>]           SDO upload (no type: hex bytes)
  w[rite] <index> <sub> <type> <value>    SDO download
  start | stop | preop[erational]         NMT
  reset node | reset comm[unication]      NMT
  enable heartbeat <ms> | disable heartbeat   watch a node's heartbeat
  [<net>] set network|node <n>            defaults of this connection
  [<net>] set sdo_timeout <ms>            SDO time-out per answer (default: --sdo-timeout)
  [<net>] set sdo_block 0|1               SDO block transfer
  [<net>] set heartbeat <ms>              the gateway's own heartbeat
  [<net>] set events 0|1                  all events to this connection
  [<net>] boot_up_indication Enable|Disable
  [<net>] set rpdo|tpdo[x] ... | r[ead] p[do] <n> | w[rite] p[do] <n> <count> <values>
  info version | help [datatype|lss]
Events (without sequence number): <net> <node> BOOT_UP | <net> <node> ERROR 203
  (heartbeat lost) | <net> <node> ERROR 202 | <net> <node> EMCY <code> <reg> <5 bytes>
  | <net> pdo <num> <count> <values> (the gateway's RPDO received)
'#' starts a comment."""

HELP_DATATYPE = """\
b boolean; i8 i16 i24 i32 i40 i48 i56 i64 signed; u8 .. u64 unsigned;
x8 .. x64 unsigned shown in hex; r32 r64 real; t td time of day / difference
as '<ms> <days>'; vs visible string ("quoted", "" for a quote); os us d octet string,
unicode string, domain as base64; hex raw bytes as hex pairs."""

HELP_LSS = """\
LSS (CiA 305) through the gateway's LSS master; all start with [<seq>] [<net>]:
  lss_switch_glob 0|1                     switch state global (0 waiting, 1 configuration)
  lss_switch_sel <vendor> <product> <revision> <serial>   switch state selective
  lss_set_node <node>                     configure node-ID (1..127, 255: none)
  lss_store                               store configuration
  lss_inquire_addr [0..3]                 inquire vendor, product, revision, serial (all 4)
  lss_get_node                            inquire node-ID
  _lss_fastscan [<timeout ms>]            fastscan one device without node-ID: its address
                                          (it stays in configuration)
  lss_allnodes [<timeout ms> [<first node> <store 0|1> [0 <v> 0 <p> 0 <r> 0 <s>]]]
                                          give every device without node-ID the next one
  lss_conf_bitrate, lss_activate_bitrate, lss_identity, lss_ident_nonconf: ERROR:100
Errors: 103 no answer, 501 refused, 502 node-ID refused, 504 store refused."""

#: Default time-out (ms) per LSS answer of ``_lss_fastscan`` and ``lss_allnodes``.
LSS_SCAN_TIMEOUT_MS = 100


def error_reply(seq: int | None, code: int, *, abort: bool = False) -> str:
    """``[seq] ERROR:...`` (no ``[seq]`` when the request had no readable one)."""
    text = f"ERROR:0x{code:08X}" if abort else f"ERROR:{code}"
    return text if seq is None else f"[{seq}] {text}"


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

    def new_session(self) -> Session:
        return Session(net=self.net)

    async def execute(self, session: Session, request: Request) -> list[str]:
        """The reply lines of ``request``; never raises for a request that fails."""
        seq = request.seq
        try:
            if session.command_timeout_ms > 0:
                async with asyncio.timeout(session.command_timeout_ms / 1000):
                    return await self._run(session, request)
            return await self._run(session, request)
        except SdoAbort as exc:
            return [error_reply(seq, exc.code, abort=True)]
        except GatewayFailure as exc:
            return [error_reply(seq, exc.code)]
        except ParseError as exc:
            return [error_reply(seq, exc.code)]
        except TimeoutError:
            return [error_reply(seq, GatewayError.TIMEOUT)]
        except Error as exc:
            log.info("request %d: %s", seq, exc)
            return [error_reply(seq, GatewayError.INTERNAL_STATE)]
        except Exception:  # a bug must cost one reply, not the connection
            log.exception("request %d failed", seq)
            return [error_reply(seq, GatewayError.INTERNAL_STATE)]

    # ---- helpers

    def _net(self, session: Session, request: Request) -> int:
        net = request.net if request.net is not None else session.net
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
        async with self._lock(node):
            try:
                return await self.backend.sdo_upload(node, index, sub, block=session.sdo_block,
                                                     timeout_ms=session.sdo_timeout_ms)
            except TimeoutError:
                raise SdoAbort(ABORT_TIMEOUT) from None

    async def _download(self, session: Session, node: int, index: int, sub: int,
                        data: bytes) -> None:
        if node == self.backend.node_id:
            self.backend.local_write(index, sub, data)
            return
        async with self._lock(node):
            try:
                await self.backend.sdo_download(node, index, sub, data, block=session.sdo_block,
                                                timeout_ms=session.sdo_timeout_ms)
            except TimeoutError:
                raise SdoAbort(ABORT_TIMEOUT) from None

    def _local_uint(self, index: int, sub: int) -> int:
        return int.from_bytes(self.backend.local_read(index, sub), "little")

    def _local_put(self, index: int, sub: int, value: int, size: int) -> None:
        self.backend.local_write(index, sub, value.to_bytes(size, "little"))

    # ---- requests

    async def _run(self, session: Session, request: Request) -> list[str]:
        seq = request.seq
        ok = [f"[{seq}] OK"]
        if isinstance(request, SdoRead):
            node = self._node(session, request)
            data = await self._upload(session, node, request.index, request.sub)
            try:
                text = format_value(request.type, data)
            except ValueError:
                raise SdoAbort(0x06070010) from None  # length does not match the type
            return [f"[{seq}] {text}"]
        if isinstance(request, SdoWrite):
            node = self._node(session, request)
            await self._download(session, node, request.index, request.sub, request.data)
            return ok
        if isinstance(request, Nmt):
            node = self._node(session, request, allow_all=True)
            if node == self.backend.node_id:
                await self.backend.local_nmt(request.command)
            else:
                await self.backend.nmt(node, request.command)
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
            return [f"[{seq}] {self.net} pdo {len(values)}" + (f" {text}" if text else "")]
        if isinstance(request, PdoWrite):
            self._net(session, request)
            await self._pdo_write(request)
            return ok
        if isinstance(request, InfoVersion):
            return [f"[{seq}] {self._version()}"]
        if isinstance(request, Help):
            text = {"": HELP, "datatype": HELP_DATATYPE, "lss": HELP_LSS}[request.topic]
            first, *rest = text.splitlines()
            return [f"[{seq}] {first}", *rest]
        if isinstance(request, Init):
            self._net(session, request)
            raise GatewayFailure(GatewayError.REQUEST_NOT_SUPPORTED, "init")
        if isinstance(request, Lss):
            self._net(session, request)
            return await self._lss(request)
        raise GatewayFailure(GatewayError.REQUEST_NOT_SUPPORTED, type(request).__name__)

    def _set(self, session: Session, request: Set) -> list[str]:
        ok = [f"[{request.seq}] OK"]
        what, value = request.what, request.value
        if what == "network":
            if value != self.net:
                raise GatewayFailure(GatewayError.UNSUPPORTED_NET, f"network {value}")
            session.net = value
            return ok
        self._net(session, request)
        if what == "node":
            session.node = value
        elif what == "sdo_timeout":
            if value == 0:
                raise GatewayFailure(GatewayError.SYNTAX, "time-out 0")
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

    async def _lss(self, request: Lss) -> list[str]:
        seq, args, command = request.seq, request.args, request.command
        lss = self.backend.lss

        def arity(*counts: int) -> None:
            if len(args) not in counts:
                raise GatewayFailure(GatewayError.SYNTAX, f"{command}: {len(args)} arguments")

        if command == "lss_switch_glob":
            arity(1)
            if args[0] > 1:
                raise GatewayFailure(GatewayError.SYNTAX, "lss_switch_glob 0|1")
            await lss("switch_global", args)
        elif command == "lss_switch_sel":
            arity(4)
            await lss("select", args)
        elif command == "lss_set_node":
            arity(1)
            if not (1 <= args[0] <= 127 or args[0] == 0xFF):
                raise GatewayFailure(GatewayError.LSS_NODE_ID_NOT_SUPPORTED, f"{args[0]}")
            await lss("set_node", args)
        elif command == "lss_store":
            arity(0)
            await lss("store")
        elif command == "lss_inquire_addr":
            arity(0, 1)
            if args and args[0] > 3:
                raise GatewayFailure(GatewayError.SYNTAX, "lss_inquire_addr 0..3")
            values = [(await lss("inquire", (sub,)))[0] for sub in (args or (0, 1, 2, 3))]
            return [f"[{seq}] " + " ".join(f"0x{v:08X}" for v in values)]
        elif command == "lss_get_node":
            arity(0)
            (node,) = await lss("inquire", (4,))
            return [f"[{seq}] 0x{node & 0xFF:02X}"]
        elif command == "_lss_fastscan":
            arity(0, 1)
            found = await lss("fastscan", (self._scan_timeout(args),))
            if not found:
                raise GatewayFailure(GatewayError.TIMEOUT, "no device without node-ID")
            return [f"[{seq}] " + " ".join(f"0x{v:08X}" for v in found)]
        elif command == "lss_allnodes":
            return await self._lss_allnodes(request)
        else:  # bit timing (not exposed by the LSS master), identify, slowscan
            raise GatewayFailure(GatewayError.REQUEST_NOT_SUPPORTED, command)
        return [f"[{seq}] OK"]

    @staticmethod
    def _scan_timeout(args: tuple[int, ...]) -> int:
        timeout = args[0] if args else LSS_SCAN_TIMEOUT_MS
        if not 1 <= timeout <= 0xFFFF:
            raise GatewayFailure(GatewayError.SYNTAX, f"LSS time-out {timeout} ms")
        return timeout

    async def _lss_allnodes(self, request: Lss) -> list[str]:
        """Fastscan, configure the next node-ID (skipping the gateway's), store if asked,
        switch to waiting (the device boots); until no device without node-ID answers."""
        args, lss = request.args, self.backend.lss
        if len(args) not in (0, 1, 3, 11):
            raise GatewayFailure(GatewayError.SYNTAX, f"lss_allnodes: {len(args)} arguments")
        timeout = self._scan_timeout(args)
        node, store = (args[1], args[2]) if len(args) >= 3 else (1, 0)
        if not 1 <= node <= 127 or store > 1:
            raise GatewayFailure(GatewayError.SYNTAX, "lss_allnodes: node 1..127, store 0|1")
        if len(args) == 11 and any(args[i] for i in (3, 5, 7, 9)):
            raise GatewayFailure(GatewayError.REQUEST_NOT_SUPPORTED, "scan types other than 0")
        lines: list[str] = []
        count = 0
        while True:
            if node == self.backend.node_id:
                node += 1
            if node > 127:
                lines.append("# Not all nodes scanned!")
                break
            found = await lss("fastscan", (timeout,))
            if not found:
                lines.append(f"# Found {count} nodes, search finished.")
                break
            try:
                await lss("set_node", (node,))
                if store:
                    await lss("store")
            finally:
                await lss("switch_global", (0,))
            lines.append(f"# Node-ID {node} assigned to: "
                         + " ".join(f"0x{v:08X}" for v in found))
            count += 1
            node += 1
        return [*lines, f"[{request.seq}] OK"]

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
