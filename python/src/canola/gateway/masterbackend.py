# SPDX-License-Identifier: Apache-2.0
"""A :class:`~canola.gateway.backend.Backend` over :class:`canola.Master` (python-can bus
or simulated bus).

- SDO: the master's asyncio client (one client channel per node, so transfers to
  different nodes run at the same time); cancelling aborts the transfer on the bus. The
  time-out per answer is the client's ``set sdo_timeout`` (up to 65535 ms), else the
  master's ``sdo_timeout_ms`` (``canola gateway --sdo-timeout``). The whole transfer is
  not bounded (a 1 MiB block transfer takes seconds on a real bus).
- The gateway's own dictionary is read and written as the network would (access rights,
  lengths, limits), NMT commands to its own node-ID are applied to itself: both through
  the C core directly (canola.Master has no public call for either yet).
- LSS (CiA 305): ``master.lss``; a request blocks until the devices answered (on a SimBus
  it runs the bus in virtual time in the event loop's thread, on python-can it waits in a
  worker thread).
- Events: boot-ups, heartbeats (from the frames), EMCY (the master's EMCY consumer),
  the master's own heartbeat-consumer losses and its RPDOs (their mapped values).
- Its own node's NMT state (self-start, what it gates): :mod:`canola.gateway.ownnode`.
"""

from __future__ import annotations

import argparse
import asyncio
from collections.abc import Callable

from canola._c import ffi, lib
from canola._nodebase import EmcyEvent, HeartbeatEvent, nmt_command
from canola.core import SimBus
from canola.errors import Error, SdoAbort
from canola.gateway.backend import (
    BootUp,
    Emcy,
    Event,
    Heartbeat,
    HeartbeatLost,
    Listener,
    Listeners,
    LssOp,
    Rpdo,
)
from canola.gateway.codes import GatewayError, GatewayFailure
from canola.gateway.ownnode import OwnNode
from canola.gateway.pdo import mapped_values
from canola.gateway.requests import NmtCommand
from canola.master import Frame, Master

__all__ = ["MasterBackend", "open_master"]

#: Gateway NMT command -> canola.Master NMT command name.
_NMT_NAMES: dict[str, str] = {
    "start": "start",
    "stop": "stop",
    "preop": "pre-operational",
    "reset_node": "reset-node",
    "reset_comm": "reset-communication",
}


def _answer_s(timeout_ms: int) -> float | None:
    """A client's ``set sdo_timeout`` as canola.Master's ``answer_timeout`` (None: the
    master's own; above 65535 ms, 65.535 s: the longest the C client takes)."""
    return min(timeout_ms, 0xFFFF) / 1000 if timeout_ms else None

_INQUIRE = ("vendor", "product", "revision", "serial", "node_id")
_REFUSED = {"set_node": GatewayError.LSS_NODE_ID_NOT_SUPPORTED,
            "store": GatewayError.LSS_STORE_FAILED}


def _lss_error(op: LssOp, status: str, error: int) -> GatewayError:
    """The CiA 309-3 code of a failed LSS request, as CANopenNode's gateway gives it."""
    if status == "time-out":
        return GatewayError.TIMEOUT
    if status.startswith("refused"):
        if error == 0xFF:  # the device's own reason, in the manufacturer-specific byte
            return GatewayError.LSS_MANUFACTURER
        return _REFUSED.get(op, GatewayError.LSS_MANUFACTURER)
    return GatewayError.INTERNAL_STATE


class MasterBackend:
    """The gateway's master: a started :class:`canola.Master`."""

    def __init__(self, master: Master, *, upload_cap: int = 2 * 1024 * 1024,
                 on_close: Callable[[], None] | None = None) -> None:
        self.master = master
        self.upload_cap = upload_cap
        self._on_close = on_close
        self._listeners = Listeners()
        master.on_bootup(self._bootup)
        master.on_frame(self._frame)
        master.on_emcy(self._emcy)
        master.on_heartbeat(self._heartbeat)
        master.on_rpdo(self._rpdo)
        self.own = OwnNode(master, lambda: self._apply("start"))

    @property
    def node_id(self) -> int:
        return self.master.node_id

    @property
    def nmt_state(self) -> str:
        return self.own.state

    @property
    def sdo_closings(self) -> int:
        return self.own.sdo_closings

    @property
    def has_lss(self) -> bool:
        return True

    # ---- SDO

    async def sdo_upload(self, node: int, index: int, sub: int, *, block: bool,
                         timeout_ms: int) -> bytes:
        return await self.master.sdo(node).aupload(index, sub, block=block,
                                                   max_size=self.upload_cap,
                                                   answer_timeout=_answer_s(timeout_ms))

    async def sdo_download(self, node: int, index: int, sub: int, data: bytes, *,
                           block: bool, timeout_ms: int) -> None:
        await self.master.sdo(node).adownload(index, sub, data, block=block,
                                              answer_timeout=_answer_s(timeout_ms))

    def local_read(self, index: int, sub: int) -> bytes:
        buf = ffi.new("uint8_t[]", self.upload_cap)
        n = ffi.new("uint32_t *")
        with self.master.locked() as node:
            code = int(lib.co_node_read_net(node, index, sub, buf, self.upload_cap, n))
        if code:
            raise SdoAbort(code)
        return bytes(ffi.buffer(buf, int(n[0])))

    def local_write(self, index: int, sub: int, data: bytes) -> None:
        with self.master.locked() as node:
            code = int(lib.co_node_write_net(node, index, sub, bytes(data), len(data)))
        if code:
            raise SdoAbort(code)

    async def pdo_send(self, num: int) -> None:
        """Send the gateway's TPDO ``num`` (1-based) now, if it is event-driven."""
        with self.master.locked() as node:
            lib.co_tpdo_request(node, num - 1)

    # ---- NMT

    async def nmt(self, node: int, command: NmtCommand) -> None:
        self.master.nmt(node, _NMT_NAMES[command])

    async def local_nmt(self, command: NmtCommand) -> None:
        self._apply(command)

    def _apply(self, command: NmtCommand) -> None:
        spec = nmt_command(_NMT_NAMES[command])
        with self.master.locked() as node:
            lib.co_nmt_apply(node, spec)

    # ---- LSS

    async def lss(self, op: LssOp, args: tuple[int, ...] = ()) -> tuple[int, ...]:
        if isinstance(self.master.bus, SimBus):
            return self._lss(op, args)  # virtual time: the bus runs in this thread
        return await asyncio.to_thread(self._lss, op, args)

    def _lss(self, op: LssOp, args: tuple[int, ...]) -> tuple[int, ...]:
        from canola.lss import LssAddress, LssError  # noqa: PLC0415 -- loaded on first use

        lss = self.master.lss
        try:
            if op == "switch_global":
                lss.switch_global("configuration" if args[0] else "waiting")
            elif op == "select":
                try:
                    lss.select(LssAddress(*args[:4]))
                except LssError:
                    raise
                except Error as exc:  # no device with that address answered
                    raise GatewayFailure(GatewayError.TIMEOUT, str(exc)) from None
            elif op == "set_node":
                lss.configure_node_id(args[0])
            elif op == "store":
                lss.store()
            elif op == "inquire":
                return (lss.inquire_value(_INQUIRE[args[0]]),)
            elif op == "fastscan":
                before = lss.timeout_ms
                lss.timeout_ms = args[0]
                try:
                    found = lss.fastscan_one()
                finally:
                    lss.timeout_ms = before
                if found is None:
                    return ()
                return (found.vendor, found.product, found.revision, found.serial)
            else:
                raise GatewayFailure(GatewayError.REQUEST_NOT_SUPPORTED, f"LSS {op}")
        except LssError as exc:
            raise GatewayFailure(_lss_error(op, exc.status, exc.error), str(exc)) from None
        return ()

    # ---- events

    def subscribe(self, listener: Listener) -> Callable[[], None]:
        return self._listeners.subscribe(listener)

    def _emit(self, event: Event) -> None:
        self._listeners.emit(event)

    def _bootup(self, node: int) -> None:
        self._emit(BootUp(node))

    def _frame(self, frame: Frame) -> None:
        if 0x701 <= frame.can_id <= 0x77F and len(frame.data) == 1 and frame.data[0] \
                and not frame.rtr:
            self._emit(Heartbeat(frame.can_id - 0x700, frame.data[0] & 0x7F))

    def _emcy(self, event: EmcyEvent) -> None:
        self._emit(Emcy(event.node, event.code, event.register, event.manufacturer))

    def _heartbeat(self, event: HeartbeatEvent) -> None:
        if event.kind == "lost":
            self._emit(HeartbeatLost(event.node))

    def _rpdo(self, rpdo: int) -> None:  # 0-based
        try:
            values = mapped_values(self.local_read, 0x1600 + rpdo)
        except SdoAbort:
            return
        self._emit(Rpdo(rpdo + 1, tuple(values)))

    # ---- simulated bus, life cycle

    async def run(self, tick_s: float = 0.005, speed: float = 1.0) -> None:
        """On a simulated bus: keep virtual time moving with wall time (until cancelled).
        On python-can the master's own thread does that; this returns at once."""
        bus = self.master.bus
        if not isinstance(bus, SimBus):
            return
        loop = asyncio.get_running_loop()
        last = loop.time()
        while True:
            await asyncio.sleep(tick_s)
            now = loop.time()
            bus.run_for(max(1, int((now - last) * 1e6 * speed)))
            last = now

    def close(self) -> None:
        self.master.stop()
        if self._on_close is not None:
            self._on_close()


def open_master(args: argparse.Namespace) -> MasterBackend:
    """The gateway's master on ``--iface`` / ``--bus`` (``--node-id``, ``--eds``)."""
    from canola.bus.open import open_bus  # noqa: PLC0415 -- python-can only when used

    bus = open_bus(iface=args.iface, url=args.bus)
    try:
        master = Master(bus, node_id=args.node_id or 127, eds_file=args.eds,
                        sdo_timeout_ms=getattr(args, "sdo_timeout", 1000))
        master.start()
    except BaseException:
        bus.shutdown()
        raise
    return MasterBackend(master, on_close=bus.shutdown)
