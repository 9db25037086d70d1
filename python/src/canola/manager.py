# SPDX-License-Identifier: Apache-2.0
"""The CANopen manager (CiA 302-2) from Python: boot a network from its description.

    net = canola.boot_plan.load("plant.yaml")          # or network.from_dcfs([...])
    mgr = master.boot(net, on_event=print)           # blocks until the boot settled
    if mgr.started: ...
    for status in mgr.slaves(): print(status)        # node, state, CiA 302 reason

The C core does the work (``co_manager_*``): for every slave in turn it checks the device
type and identity, downloads the concise DCF, sets up the heartbeat watch, then starts the
network once every mandatory slave booted. Failures carry the CiA 302 letter and text
(``"D: vendor-ID does not match"``), the SDO abort code and the entry. The manager keeps
running after :meth:`Master.boot` returns: a slave that was missing or failed and sends a
boot-up later is booted then (``boot_on_bootup``), and joins the running network.

Events (:class:`BootEvent`) reach ``on_event`` callbacks outside the node's lock, in order,
like every canola callback. Do not use SDO to a slave while the manager boots it (both
would talk to its one SDO server).
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, TypeVar

from canola._c import check as _check
from canola._c import ffi, lib
from canola._channels import SdoChannels, unset
from canola._waiting import Waiter
from canola.boot_plan import Network
from canola.errors import ABORT_TEXT, Error

__all__ = ["BootEvent", "NetworkManager", "SlaveStatus", "boot"]

_KINDS = {
    int(lib.CO_MGR_BOOTED): "booted",
    int(lib.CO_MGR_STARTED): "started",
    int(lib.CO_MGR_FAILED): "failed",
    int(lib.CO_MGR_LOST): "lost",
    int(lib.CO_MGR_NETWORK_STARTED): "network-started",
    int(lib.CO_MGR_NETWORK_HALTED): "network-halted",
}
_STATES = {
    int(lib.CO_MGR_UNLISTED): "unlisted",
    int(lib.CO_MGR_WAITING): "waiting",
    int(lib.CO_MGR_BOOTING): "booting",
    int(lib.CO_MGR_CONFIGURED): "configured",
    int(lib.CO_MGR_RUNNING): "running",
    int(lib.CO_MGR_FAILED_STATE): "failed",
    int(lib.CO_MGR_MISSING): "missing",
}
_START = {"all": int(lib.CO_MGR_START_ALL), "each": 0, "none": int(lib.CO_MGR_NO_SLAVE_START)}

F = TypeVar("F", bound=Callable[..., Any])


def reason_text(reason: int) -> str:
    """The CiA 302 text of a reason letter's code ("" for none)."""
    return ffi.string(lib.co_boot_reason_text(reason)).decode() if reason else ""


@dataclass(frozen=True)
class BootEvent:
    """What the manager reports. ``kind``: booted, started, failed, lost, network-started,
    network-halted; ``node`` 0 for network-started. For failed/lost/network-halted,
    ``reason`` is the CiA 302 letter and ``text`` its meaning; ``abort`` the SDO abort code
    (B, J), ``index``/``sub`` the entry read or written, ``value`` what the slave
    reported (C, D, M, N, O)."""

    node: int
    kind: str
    reason: str = ""
    text: str = ""
    abort: int = 0
    index: int = 0
    sub: int = 0
    value: int = 0

    def __str__(self) -> str:
        if self.kind == "network-started":
            return "network started"
        if self.kind == "network-halted":
            return f"network halted: mandatory node {self.node} failed ({self.text})"
        line = f"node {self.node}: {self.kind}"
        if self.reason:
            line += f": {self.text}"
            line += _details(self.reason, self.abort, self.index, self.sub, self.value)
        return line

    def as_dict(self) -> dict[str, object]:
        return {"node": self.node, "kind": self.kind, "reason": self.reason,
                "text": self.text, "abort": self.abort, "index": self.index, "sub": self.sub,
                "value": self.value}


def _details(reason: str, abort: int, index: int, sub: int, value: int) -> str:
    parts = []
    if reason in "CDMNO" and reason:
        parts.append(f"0x{index:04X}:{sub:02X} is 0x{value:08X}")
    if reason == "J" and index:
        parts.append(f"entry 0x{index:04X}:{sub:02X}")
    if abort:
        parts.append(f"SDO abort 0x{abort:08X} ({ABORT_TEXT.get(abort, 'unknown abort code')})")
    return f" ({'; '.join(parts)})" if parts else ""


@dataclass(frozen=True)
class SlaveStatus:
    """Where one slave stands: ``state`` waiting, booting, configured, running, failed or
    missing; for failed/missing the last failure's reason (letter, text, abort code,
    entry, value)."""

    node: int
    state: str
    mandatory: bool
    reason: str = ""
    text: str = ""
    abort: int = 0
    index: int = 0
    sub: int = 0
    value: int = 0

    @property
    def ok(self) -> bool:
        return self.state in ("configured", "running")

    def __str__(self) -> str:
        kind = "mandatory" if self.mandatory else "optional"
        line = f"node {self.node} ({kind}): {self.state}"
        if not self.ok and self.reason:
            line += f": {self.text}"
            line += _details(self.reason, self.abort, self.index, self.sub, self.value)
        return line

    def as_dict(self) -> dict[str, object]:
        return {"node": self.node, "state": self.state, "mandatory": self.mandatory,
                "reason": self.reason, "text": self.text, "abort": self.abort,
                "index": self.index, "sub": self.sub, "value": self.value}


@ffi.def_extern()
def canola_py_mgr_event(ctx: Any, event: Any) -> None:
    manager: NetworkManager = ffi.from_handle(ctx)
    reason = int(event.reason)
    manager._event(BootEvent(
        node=int(event.node_id), kind=_KINDS.get(int(event.kind), str(int(event.kind))),
        reason=chr(reason) if reason else "", text=reason_text(reason),
        abort=int(event.abort), index=int(event.index), sub=int(event.sub),
        value=int(event.value)))


class NetworkManager:
    """The manager for ``network`` on the master's node whose SDO client ``channels`` these
    are (:meth:`canola.Master.boot` makes one). It uses a channel of its own (reserved
    among ``channels``)."""

    def __init__(self, channels: SdoChannels, network: Network) -> None:
        if not isinstance(network, Network):
            raise Error(f"a canola.boot_plan.Network is needed, not {type(network).__name__}")
        own = network.slave(channels.node_id)
        if own is not None:
            raise Error(f"{network.source}: node {own.node_id} is the master itself")
        self.channels = channels
        self.network = network
        self.engine = channels.engine
        self._waiter = Waiter(self.engine)
        self._lock = threading.Lock()
        self.events: list[BootEvent] = []
        self._last_failure: dict[int, BootEvent] = {}
        self._callbacks: list[Callable[[BootEvent], None]] = []
        self._started = False
        self._channel = 0
        self._keep: list[Any] = []
        self._slaves = ffi.new("co_mgr_slave_t[127]")
        for spec in network.slaves:
            s = self._slaves[spec.node_id - 1]
            s.assignment = (lib.CO_MGR_SLAVE
                            | (lib.CO_MGR_MANDATORY if spec.mandatory else 0)
                            | (lib.CO_MGR_BOOT_ON_BOOTUP if spec.boot_on_bootup else 0)
                            | (lib.CO_MGR_KEEP_ALIVE if spec.keep_alive else 0))
            ident = spec.identity
            s.device_type = ident.device_type
            s.vendor = ident.vendor
            s.product = ident.product
            s.revision = ident.revision
            s.serial = ident.serial
            if spec.config is not None:
                buf = ffi.new("uint8_t[]", max(len(spec.config), 1))
                ffi.memmove(buf, spec.config, len(spec.config))
                self._keep.append(buf)
                s.dcf = buf
                s.dcf_len = len(spec.config)
            s.heartbeat_ms = spec.heartbeat_ms
        self._mgr = ffi.new("co_manager_t *")
        self._handle = ffi.new_handle(self)

    # ---- callbacks

    def on_event(self, fn: F) -> F:
        """``fn(BootEvent)`` for every report (after the node's lock is released)."""
        self._callbacks.append(fn)
        return fn

    def _event(self, event: BootEvent) -> None:  # under the node's lock
        self.events.append(event)
        if event.kind in ("failed", "lost"):
            self._last_failure[event.node] = event
        if event.kind in ("booted", "failed", "network-started", "network-halted"):
            self.engine.later(self._idle)
        for fn in list(self._callbacks):
            self.engine.later(lambda fn=fn: fn(event))  # type: ignore[misc]

    # ---- running

    def start(self) -> None:
        """Attach to the master's node and boot every slave (returns at once)."""
        if not self.engine.running:
            raise Error("the master is not started: call start() first")
        startup = lib.CO_MGR_NMT_MASTER | _START[self.network.start]
        if not self.network.master_start:
            startup |= lib.CO_MGR_NO_SELF_START
        with self.engine.locked() as node:
            self._release_clients(node)
            channel = self.channels.reserve()
            self._channel = channel
            config = ffi.new("co_manager_config_t *", {
                "nmt_startup": startup, "slaves": self._slaves, "sdo_channel": channel,
                "reset_slaves": self.network.reset_slaves,
                "on_event": lib.canola_py_mgr_event, "ctx": self._handle})
            _check(int(lib.co_manager_init(self._mgr, node, config)), "co_manager_init")
            _check(int(lib.co_manager_start(self._mgr)), "co_manager_start")
        self._started = True

    def _release_clients(self, node: Any) -> None:
        """Free the master's SDO client channels to the slaves (under the lock)."""
        self.channels.release(node, [spec.node_id for spec in self.network.slaves])

    def _idle(self) -> None:
        """After a boot settled: the manager's channel lets go of the last slave, so that
        master.sdo() may talk to it (the manager sets the channel up again for the next
        boot)."""
        with self.engine.locked() as node:
            if self._settled_locked() and not lib.co_sdo_client_busy(node, self._channel):
                unset(self.engine, self._channel)

    def _settled_locked(self) -> bool:
        states = [(spec, int(lib.co_manager_slave_state(self._mgr, spec.node_id)))
                  for spec in self.network.slaves]
        if any(s in (lib.CO_MGR_WAITING, lib.CO_MGR_BOOTING) for _, s in states):
            return False
        if lib.co_manager_network_started(self._mgr):
            return True
        # every mandatory one booted: the network starts at the next poll
        return not all(s in (lib.CO_MGR_CONFIGURED, lib.CO_MGR_RUNNING)
                       for spec, s in states if spec.mandatory)

    def settled(self) -> bool:
        """No slave waits for its boot or is booting, and the network started or cannot
        start (a mandatory slave failed)."""
        with self.engine.locked():
            return self._settled_locked()

    def wait(self, timeout: float | None = None) -> bool:
        """Block until :meth:`settled` (or ``timeout`` seconds, virtual on a SimBus);
        returns :attr:`started`. Every boot step ends with an SDO or heartbeat time-out,
        so the wait ends without a ``timeout`` too, unless slaves keep sending boot-ups
        (each one starts their boot again)."""
        if not self._started:
            raise Error("the manager is not started")
        self._waiter.check()
        self._waiter.wait(self.settled, timeout)
        return self.started

    def wait_until(self, condition: Callable[[], bool], timeout: float | None) -> bool:
        """Block until ``condition()`` (checked as the boot moves on) or ``timeout``
        seconds (virtual on a SimBus); whether it held. The manager keeps booting slaves
        that send their boot-up meanwhile."""
        if not self._started:
            raise Error("the manager is not started")
        self._waiter.check()
        return self._waiter.wait(condition, timeout)

    @property
    def started(self) -> bool:
        """True once the network was started (every mandatory slave booted)."""
        with self.engine.locked():
            return bool(lib.co_manager_network_started(self._mgr))

    def status(self, node: int) -> SlaveStatus:
        """Where slave ``node`` stands."""
        spec = self.network.slave(node)
        if spec is None:
            raise Error(f"node {node!r} is not in the network description")
        with self.engine.locked():
            state = _STATES.get(int(lib.co_manager_slave_state(self._mgr, node)), "unknown")
        last = self._last_failure.get(node)
        if state in ("failed", "missing") and last is not None:
            return SlaveStatus(node, state, spec.mandatory, last.reason, last.text,
                               last.abort, last.index, last.sub, last.value)
        return SlaveStatus(node, state, spec.mandatory)

    def slaves(self) -> list[SlaveStatus]:
        """:meth:`status` of every slave, by node-ID."""
        return [self.status(spec.node_id) for spec in self.network.slaves]


def boot(channels: SdoChannels, network: Network, previous: NetworkManager | None, *,
         on_event: Callable[[BootEvent], None] | None = None, wait: bool = True,
         timeout: float | None = None) -> NetworkManager:
    """Boot ``network`` on the node of ``channels`` (see :meth:`canola.Master.boot`), unless
    the ``previous`` boot is still in progress. The node points to the manager returned:
    keep it alive as long as the node."""
    if previous is not None and previous._started and not previous.settled():
        raise Error("a network boot is in progress")
    manager = NetworkManager(channels, network)
    if on_event is not None:
        manager.on_event(on_event)
    manager.start()
    if wait:
        manager.wait(timeout)
    return manager
