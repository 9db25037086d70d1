# SPDX-License-Identifier: Apache-2.0
"""What the gateway needs from a CANopen master: a small interface, and the events.

:class:`Backend` is the whole contract between the executor and the master it drives;
:mod:`canola.gateway.masterbackend` implements it (canola.Master, on python-can or a
simulated bus). Tests use a fake too.

SDO failures are :class:`canola.errors.SdoAbort` (an SDO time-out is abort 0x05040000);
cancelling an SDO coroutine must abort the transfer on the bus before it returns.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Literal, Protocol

from canola.gateway.requests import NmtCommand

__all__ = ["Backend", "BootUp", "Emcy", "Event", "Heartbeat", "HeartbeatLost", "Listener",
           "Listeners", "LssOp", "Rpdo"]


@dataclass(frozen=True)
class BootUp:
    node: int


@dataclass(frozen=True)
class Heartbeat:
    node: int
    state: int


@dataclass(frozen=True)
class HeartbeatLost:
    node: int


@dataclass(frozen=True)
class Emcy:
    node: int
    code: int
    register: int
    data: bytes  # the 5 manufacturer-specific bytes


@dataclass(frozen=True)
class Rpdo:
    """The gateway's own RPDO ``num`` (1-based) received: its mapped values."""

    num: int
    values: tuple[int, ...]


Event = BootUp | Heartbeat | HeartbeatLost | Emcy | Rpdo
Listener = Callable[[Event], None]

#: One LSS master request (CiA 305), see :meth:`Backend.lss`.
LssOp = Literal["switch_global", "select", "set_node", "store", "inquire", "fastscan"]


class Listeners:
    """The listeners a backend reports its events to (what :meth:`Backend.subscribe` needs)."""

    def __init__(self) -> None:
        self._listeners: list[Listener] = []

    def subscribe(self, listener: Listener) -> Callable[[], None]:
        """Add ``listener``; returns the function that removes it (a second call: nothing)."""
        self._listeners.append(listener)

        def unsubscribe() -> None:
            if listener in self._listeners:
                self._listeners.remove(listener)

        return unsubscribe

    def emit(self, event: Event) -> None:
        """Call every listener with ``event`` (one that unsubscribes meanwhile: still this
        time)."""
        for listener in list(self._listeners):
            listener(event)


class Backend(Protocol):
    """A master node on one CAN network."""

    @property
    def node_id(self) -> int:
        """The master's own node-ID."""
        ...

    @property
    def nmt_state(self) -> str:
        """The master's own NMT state: INITIALISING, PRE-OPERATIONAL, OPERATIONAL or
        STOPPED (:mod:`canola.gateway.ownnode` says what it gates)."""
        ...

    @property
    def sdo_closings(self) -> int:
        """How often the master's node entered a state without SDO (STOPPED, or
        INITIALISING in a reset): a transfer during which it grew was cut off by that."""
        ...

    @property
    def has_lss(self) -> bool:
        """Whether :meth:`lss` works (without, every lss_* command answers ERROR:100)."""
        ...

    async def sdo_upload(self, node: int, index: int, sub: int, *, block: bool,
                         timeout_ms: int) -> bytes:
        """Read (index, sub) of ``node`` over SDO (``block``: block transfer; ``timeout_ms``:
        the client's ``set sdo_timeout``, 0 for the backend's own)."""
        ...

    async def sdo_download(self, node: int, index: int, sub: int, data: bytes, *,
                           block: bool, timeout_ms: int) -> None:
        """Write ``data`` to (index, sub) of ``node`` over SDO."""
        ...

    def local_read(self, index: int, sub: int) -> bytes:
        """Read the master's own dictionary as an SDO client would (raises SdoAbort)."""
        ...

    def local_write(self, index: int, sub: int, data: bytes) -> None:
        """Write the master's own dictionary as an SDO client would (raises SdoAbort)."""
        ...

    async def nmt(self, node: int, command: NmtCommand) -> None:
        """Send an NMT command to ``node`` (0: all nodes) on the bus; the master itself
        does not follow it here (the executor applies it with :meth:`local_nmt`)."""
        ...

    async def local_nmt(self, command: NmtCommand) -> None:
        """Apply an NMT command to the master itself (nothing on the bus but its
        boot-up after a reset)."""
        ...

    def subscribe(self, listener: Listener) -> Callable[[], None]:
        """Call ``listener`` with every network event; returns the unsubscribe function."""
        ...

    async def lss(self, op: LssOp, args: tuple[int, ...] = ()) -> tuple[int, ...]:
        """One LSS master request: ``switch_global`` (1: configuration, 0: waiting),
        ``select`` (vendor, product, revision, serial), ``set_node`` (node-ID), ``store``,
        ``inquire`` (0..3: vendor, product, revision, serial; 4: node-ID) -> (value,),
        ``fastscan`` (time-out ms) -> the address found (that device is in configuration)
        or () when none answered. Fails with GatewayFailure (100 when the master has no
        LSS, 103 on no answer, 501/502/504 when the device refused)."""
        ...
