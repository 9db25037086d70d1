"""A :class:`~canola.gateway.backend.Backend` over a canola.core node on a simulated bus.

The master is a :class:`canola.simnode.Node` on a :class:`canola.core.SimBus`; its SDO client
runs the bus (virtual time) until a transfer is done, so transfers take no wall time and
are never left half-way. :meth:`SimBackend.advance` moves virtual time on and reports the
frames seen since as events (boot-up, heartbeat, EMCY); :meth:`SimBackend.run` does that
continuously, at ``speed`` times wall-clock time, for a live simulated network.
"""

from __future__ import annotations

import asyncio
import contextlib
import time
from collections.abc import Callable, Iterator

from canola._c import ffi, lib
from canola._nodebase import nmt_command
from canola.core import SimBus
from canola.errors import Error, SdoAbort
from canola.gateway.backend import BootUp, Emcy, Event, Heartbeat, Listener, Listeners, LssOp
from canola.gateway.codes import GatewayError, GatewayFailure
from canola.gateway.requests import NmtCommand
from canola.simnode import Node

__all__ = ["NMT_NAMES", "SimBackend", "frame_event"]

#: Simulated time a transfer may take when the client set no time-out.
DEFAULT_LIMIT_US = 10_000_000


def _limit_us(timeout_ms: int) -> int:
    """A client's ``set sdo_timeout`` as the simulated transfer's bound (0: the default)."""
    return timeout_ms * 1000 if timeout_ms else DEFAULT_LIMIT_US

#: Gateway NMT command -> canola.core NMT command name.
NMT_NAMES: dict[str, str] = {
    "start": "start",
    "stop": "stop",
    "preop": "pre-operational",
    "reset_node": "reset-node",
    "reset_comm": "reset-communication",
}


def frame_event(can_id: int, data: bytes) -> Event | None:
    """The event a received frame is, if any (boot-up, heartbeat, EMCY)."""
    if 0x701 <= can_id <= 0x77F and len(data) == 1:
        node = can_id - 0x700
        return BootUp(node) if data[0] == 0 else Heartbeat(node, data[0] & 0x7F)
    if 0x81 <= can_id <= 0xFF and len(data) == 8:
        return Emcy(can_id - 0x80, int.from_bytes(data[:2], "little"), data[2], data[3:8])
    return None


class SimBackend:
    """The gateway's master: ``node`` on ``bus`` (both from canola.core)."""

    def __init__(self, bus: SimBus, node: Node, *, upload_cap: int = 2 * 1024 * 1024,
                 speed: float = 1.0) -> None:
        self.bus = bus
        self.node = node
        self.upload_cap = upload_cap
        self.speed = speed
        self._listeners = Listeners()
        self._seen = len(bus.trace)

    @property
    def node_id(self) -> int:
        return self.node.node_id

    @property
    def has_lss(self) -> bool:
        return False  # canola.core's Node has no LSS master binding

    # ---- SDO

    @contextlib.contextmanager
    def _sdo_transfer(self) -> Iterator[None]:
        """Around one SDO transfer: a failure that is not an abort is a time-out (abort
        0x05040000); the events of the transfer are reported after, whatever the outcome."""
        try:
            yield
        except SdoAbort:
            raise
        except Error:
            raise SdoAbort(0x05040000) from None
        finally:
            self._report()

    async def sdo_upload(self, node: int, index: int, sub: int, *, block: bool,
                         timeout_ms: int) -> bytes:
        with self._sdo_transfer():
            return self.node.sdo_upload(node, index, sub, "block" if block else "auto",
                                        cap=self.upload_cap, timeout_us=_limit_us(timeout_ms))

    async def sdo_download(self, node: int, index: int, sub: int, data: bytes, *,
                           block: bool, timeout_ms: int) -> None:
        with self._sdo_transfer():
            self.node.sdo_download(node, index, sub, data, "block" if block else "auto",
                                   timeout_us=_limit_us(timeout_ms))

    def local_read(self, index: int, sub: int) -> bytes:
        return self.node.read(index, sub, cap=self.upload_cap)

    def local_write(self, index: int, sub: int, data: bytes) -> None:
        self.node.write(index, sub, data)

    # ---- NMT

    async def nmt(self, node: int, command: NmtCommand) -> None:
        # the frame alone (Node.nmt would also apply a broadcast to the master itself)
        frame = ffi.new("co_frame_t *")
        frame.id, frame.flags, frame.len = 0x000, 0, 2
        frame.data[0:2] = [nmt_command(NMT_NAMES[command]), node]
        if int(lib.co_node_send(self.node._node, frame)):
            raise GatewayFailure(GatewayError.INTERNAL_STATE, "NMT frame not sent")
        self.bus.run_until(self.bus.now_us)
        self._report()

    async def local_nmt(self, command: NmtCommand) -> None:
        lib.co_nmt_apply(self.node._node, nmt_command(NMT_NAMES[command]))
        self.bus.run_until(self.bus.now_us)
        self._report()

    # ---- LSS

    async def lss(self, op: LssOp, args: tuple[int, ...] = ()) -> tuple[int, ...]:
        del args
        raise GatewayFailure(GatewayError.REQUEST_NOT_SUPPORTED, f"LSS {op}")

    # ---- events

    def subscribe(self, listener: Listener) -> Callable[[], None]:
        return self._listeners.subscribe(listener)

    def advance(self, us: int) -> None:
        """Run the simulated network for ``us`` of virtual time; report its events."""
        self.bus.run_for(us)
        self._report()

    async def run(self, tick_s: float = 0.005) -> None:
        """Keep virtual time moving with wall-clock time (times ``speed``); until cancelled."""
        last = time.monotonic()
        while True:
            await asyncio.sleep(tick_s)
            now = time.monotonic()
            self.advance(max(1, int((now - last) * 1e6 * self.speed)))
            last = now

    def _report(self) -> None:
        trace = self.bus.trace
        lines, self._seen = trace[self._seen:], len(trace)
        if len(trace) > 100_000:  # the trace is ours to trim: keep memory flat
            del trace[:]
            self._seen = 0
        for line in lines:
            frame = line.split()[-1]
            ident, _, data = frame.partition("#")
            try:
                event = frame_event(int(ident, 16), bytes.fromhex(data))
            except ValueError:
                continue
            if event is not None:
                self._listeners.emit(event)
