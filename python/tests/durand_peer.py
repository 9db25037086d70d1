# SPDX-License-Identifier: Apache-2.0
"""durand (a CANopen responder library from PyPI, independent of canola) as a device on
canola's simulated bus, in virtual time: its network interface over a raw port (a quiet
canola.Master that only moves frames), its scheduler advanced with the bus's clock."""

from __future__ import annotations

from collections import deque
from collections.abc import Callable, Iterator
from contextlib import contextmanager

import durand
from durand.scheduler import VirtualScheduler, get_scheduler, set_scheduler

from canola import Error, Master
from canola.core import SimBus
from canola.master import Frame

#: How often durand's clock is advanced (virtual us): its timers are this exact.
TICK_US = 1000


class SimBusNetwork:
    """durand's NetworkABC on a SimBus: frames it subscribed to reach its callbacks, what
    it sends goes on the bus from a quiet canola node (``port_id``)."""

    def __init__(self, bus: SimBus, port_id: int) -> None:
        self.subscriptions: dict[int, Callable[[int, bytes], None]] = {}
        self.port = Master(bus, node_id=port_id, announce=False)
        self.port.on_frame(self._rx)
        self.port.start()
        self._backlog: deque[tuple[int, bytes]] = deque()  # more than the port's queue holds

    def add_subscription(self, cob_id: int, callback: Callable[[int, bytes], None]) -> None:
        self.subscriptions[cob_id] = callback

    def remove_subscription(self, cob_id: int) -> None:
        self.subscriptions.pop(cob_id, None)

    def send(self, cob_id: int, msg: bytes) -> None:
        self._backlog.append((cob_id, bytes(msg)))
        self.flush()

    def flush(self) -> None:
        """Hand the port what its transmit queue takes (durand sends a block's sub-block
        at once); the rest at the next tick."""
        while self._backlog:
            frame = self._backlog.popleft()  # first: sending runs the bus, which may flush
            try:
                self.port.send(*frame)
            except Error as exc:
                if "no room" not in str(exc):
                    raise
                self._backlog.appendleft(frame)
                return

    def _rx(self, frame: Frame) -> None:
        callback = self.subscriptions.get(frame.can_id)
        if callback is not None and not frame.rtr and not frame.extended:
            callback(frame.can_id, frame.data)


@contextmanager
def virtual_time(bus: SimBus, network: SimBusNetwork) -> Iterator[VirtualScheduler]:
    """durand's global scheduler as virtual time that follows ``bus`` (restored after)."""
    before = get_scheduler()
    scheduler = VirtualScheduler()
    set_scheduler(scheduler)
    def tick() -> None:
        scheduler.run(TICK_US / 1e6)
        network.flush()

    timer = network.port._engine.add_timer(TICK_US, tick)
    try:
        yield scheduler
    finally:
        network.port._engine.remove_timer(timer)
        set_scheduler(before)


def device(network: SimBusNetwork, node_id: int) -> durand.Node:
    """A durand node with a few objects of every kind the tests use."""
    node = durand.Node(network, node_id)  # type: ignore[arg-type]
    od = node.object_dictionary
    dt = durand.DatatypeEnum
    od[0x2000] = durand.Variable(dt.UNSIGNED16, "rw", value=10, name="u16")
    od[0x2001] = durand.Variable(dt.INTEGER32, "rw", value=-7, name="i32")
    od[0x2002] = durand.Variable(dt.REAL32, "rw", value=1.5, name="r32")
    od[0x2003] = durand.Variable(dt.VISIBLE_STRING, "rw", value=b"durand peer", name="vs")
    od[0x2004] = durand.Variable(dt.DOMAIN, "rw", value=b"", name="domain")
    od[0x2005] = durand.Variable(dt.UNSIGNED32, "ro", value=0x11223344, name="ro u32")
    od[0x2006] = durand.Variable(dt.UNSIGNED8, "rw", value=3, minimum=1, maximum=9,
                                 name="limited u8")
    return node
