# SPDX-License-Identifier: Apache-2.0
"""canola.Master: an NMT master and SDO client run by the C core, on a python-can bus or a
SimBus.

    master = canola.Master(bus, node_id=127)
    master.start()
    master.nmt(5, "start")                      # node 0 = all nodes
    name = master.sdo(5).upload(0x1008, 0)      # bytes; SdoAbort on an abort code
    master.sdo(5).download(0x6000, 1, b"\\x2a")
    value = await master.sdo(5).aupload(0x1018, 1)   # asyncio
    master.monitor(5, 1500)                      # heartbeat consumer
    master.on_heartbeat(print); master.on_emcy(print)
    master.start_sync(10_000)                    # SYNC every 10 ms
    master.send_pdo(0x205, b"\\x01\\x02")
    mgr = master.boot("plant.yaml")              # CiA 302-2 manager: canola.manager
    ids = master.lss.fastscan()                  # CiA 305: canola.lss
    master.flash(5, image, progress=print)       # CiA 302-3: canola.flash

The master's own dictionary comes from ``canola/data/master.eds`` (shipped in the
package): 16 SDO client channels (0x1280..0x128F), a heartbeat consumer for every node-ID
(0x1016 sub N watches node N once :meth:`Master.monitor` writes it), an EMCY consumer for
every node-ID (0x1028), and the SYNC/TIME producer objects. An EDS rather than entries
built in code, so the dictionary is inspectable with the same tools as any device's
(``canola odgen``, a CANopen tool's EDS view) and a user can pass an edited copy.

Like any node, the master takes NMT commands from the bus: a reset communication (or
reset node) to its node-ID or to all brings its communication objects back to their
power-on values, the SDO client channels and the heartbeat watches among them. It serves
every node again afterwards (the channel of a node is looked up in the core, never
remembered blindly); a running CANopen manager boots the network again (CiA 302-2); what
:meth:`Master.monitor`, :meth:`Master.start_sync` and :meth:`Master.start_time` set up is
set again by the reset itself, before the master's boot-up: the heartbeat watches, the
SYNC period and counter (the first SYNC one period after the reset, counting from 1) and
the TIME production at its period. So is what they set up before :meth:`Master.start`
(whose power-on is such a reset). Entries written otherwise (``master.od``, SDO from
another tool) take their power-on values, as CiA 301 says.
"""

from __future__ import annotations

import datetime as dt
import os
import time
from collections.abc import Callable, Sequence
from importlib import resources
from typing import TYPE_CHECKING, Any, TypeVar

from canola._c import check, ffi, lib
from canola._channels import SdoChannels
from canola._engine import Bus, Frame, _Timer
from canola._nodebase import (
    STATE_NAMES,
    EmcyEvent,
    HeartbeatEvent,
    NodeBase,
    load_od,
    nmt_command,
)
from canola.core import SimBus
from canola.errors import Error, SdoTimeout
from canola.formats import eds, values
from canola.formats.odgen import GenerateOptions

if TYPE_CHECKING:  # loaded on first use (the command line starts faster without them)
    from canola.boot_plan import Network
    from canola.flash import FlashResult
    from canola.lss import Lss
    from canola.manager import BootEvent, NetworkManager

__all__ = ["MASTER_EDS", "EmcyEvent", "Frame", "HeartbeatEvent", "Master", "SdoClient",
           "SdoTimeout"]

#: Path of the master's default EDS inside the package.
MASTER_EDS = str(resources.files("canola") / "data" / "master.eds")

_EPOCH = dt.datetime(1984, 1, 1, tzinfo=dt.UTC)

F = TypeVar("F", bound=Callable[..., Any])


class SdoClient:
    """SDO client of one remote node (one client channel of the master).

    ``upload``/``download`` block until the transfer ends; ``aupload``/``adownload`` are
    their asyncio forms. ``block=True`` uses block transfer; ``timeout`` (seconds) bounds
    the whole transfer; ``answer_timeout`` (seconds, up to 65.535) is how long each answer
    may take in this transfer (default: ``timeout_ms``, the master's ``sdo_timeout_ms``). An
    abort raises :class:`~canola.errors.SdoAbort` with its ``code``, who sent it
    (``by_server``) and after how long (``after_s``); no answer in time raises
    :class:`SdoTimeout` (code 0x05040000, sent by the master). One transfer at a time per
    node: a second one waits for the first. On a SimBus every form runs the simulated bus
    until the transfer ends (the asyncio forms too: virtual time has no other driver).
    """

    def __init__(self, channels: SdoChannels, node: int, timeout_ms: int) -> None:
        self._channels = channels
        self.node = node
        self.timeout_ms = timeout_ms

    # ---- blocking

    def upload(self, index: int, sub: int, *, block: bool = False,
               timeout: float | None = None, max_size: int = 65536,
               answer_timeout: float | None = None) -> bytes:
        """Read (index, sub) of the node: its wire bytes."""
        return self._channels.upload(self.node, index, sub, block=block, max_size=max_size,
                                     timeout=timeout, answer_ms=_answer_ms(answer_timeout),
                                     default_ms=self.timeout_ms)

    def download(self, index: int, sub: int, data: bytes, *, block: bool = False,
                 timeout: float | None = None, answer_timeout: float | None = None) -> None:
        """Write ``data`` (wire bytes) to (index, sub): expedited up to 4 bytes, else
        segmented (or block with ``block=True``)."""
        self._channels.download(self.node, index, sub, bytes(data), block=block,
                                timeout=timeout, answer_ms=_answer_ms(answer_timeout),
                                default_ms=self.timeout_ms)

    def read(self, index: int, sub: int, data_type: str | int, **kw: Any) -> values.Value:
        """upload + :func:`canola.formats.values.decode` as ``data_type`` (e.g. "u16", "vs")."""
        return values.decode(data_type, self.upload(index, sub, **kw))

    def write(self, index: int, sub: int, data_type: str | int, value: values.Value,
              **kw: Any) -> None:
        """:func:`canola.formats.values.encode` as ``data_type`` + download."""
        self.download(index, sub, values.encode(data_type, value), **kw)

    # ---- asyncio

    async def aupload(self, index: int, sub: int, *, block: bool = False,
                      timeout: float | None = None, max_size: int = 65536,
                      answer_timeout: float | None = None) -> bytes:
        """:meth:`upload` as a coroutine (the thread that receives completes it)."""
        return await self._channels.aupload(self.node, index, sub, block=block,
                                            max_size=max_size, timeout=timeout,
                                            answer_ms=_answer_ms(answer_timeout),
                                            default_ms=self.timeout_ms)

    async def adownload(self, index: int, sub: int, data: bytes, *, block: bool = False,
                        timeout: float | None = None,
                        answer_timeout: float | None = None) -> None:
        """:meth:`download` as a coroutine."""
        await self._channels.adownload(self.node, index, sub, bytes(data), block=block,
                                       timeout=timeout, answer_ms=_answer_ms(answer_timeout),
                                       default_ms=self.timeout_ms)


def _answer_ms(answer_timeout: float | None) -> int:
    """``answer_timeout`` in ms for co_sdo_client_set_timeout (0: the master's)."""
    if answer_timeout is None:
        return 0
    ms = round(answer_timeout * 1000)
    if not 1 <= ms <= 0xFFFF:
        raise Error(f"answer_timeout must be 0.001..65.535 s, got {answer_timeout}")
    return ms


#: 0x1012 of a TIME producer on COB-ID 0x100 (bit 30).
_TIME_PRODUCER = 0x40000100


def _sync_writes(period_us: int, overflow: int) -> list[tuple[int, int]]:
    """(index, value) writes at sub 0 that make a SYNC producer of ``period_us`` with
    counter ``overflow``: the period goes to 0 first (0x1019 may change only then)."""
    return [(0x1006, 0), (0x1019, overflow), (0x1005, 0x40000080), (0x1006, period_us)]


class Master(NodeBase):
    """An NMT master / SDO client as node ``node_id`` on ``bus`` (python-can or SimBus).

    ``eds``: another dictionary for the master (default :data:`MASTER_EDS`).
    ``sdo_timeout_ms``: how long an SDO transfer waits for each answer.
    ``announce``: the master is a member of the network and says so, as every node does:
    its boot-up (0x700 + node-ID) at start and after a reset, then its heartbeat at the
    period of its 0x1017 (0, none, in :data:`MASTER_EDS`). A tool that only asks or
    commands passes ``announce=False``: none of these frames (nor answers to node
    guarding) go on the bus, so a CiA 302 manager sees no phantom node.
    Call :meth:`start` (or use ``with``).
    """

    _kind = "master"

    def __init__(self, bus: Bus, node_id: int = 127, *, sdo_timeout_ms: int = 1000,
                 eds_file: str | os.PathLike[str] | eds.ObjectDictionary | None = None,
                 announce: bool = True) -> None:
        if not isinstance(node_id, int) or not 1 <= node_id <= 127:
            raise Error(f"node-ID {node_id!r} is outside 1..127")
        od = load_od(eds_file if eds_file is not None else MASTER_EDS, node_id,
                     GenerateOptions(min_string_size=64))
        super().__init__(bus, od, node_id, sdo_timeout_ms=sdo_timeout_ms, store_dir=None,
                         raw_frames=True, quiet=not announce)
        self._clients: dict[int, SdoClient] = {}
        self._sdo = self._build(SdoChannels)
        self._frame_cbs: list[tuple[int | None, Callable[[Frame], None]]] = []
        self._bootup_cbs: list[Callable[[int], None]] = []
        self._time_timer: _Timer | None = None
        self._watches: dict[int, int] = {}  # node -> heartbeat time (ms), by monitor()
        self._sync: tuple[int, int] | None = None  # (period us, overflow), by start_sync()
        self._lss: Lss | None = None
        self._manager: NetworkManager | None = None
        self._managers: list[NetworkManager] = []  # the node points to them: kept alive

    def __enter__(self) -> Master:
        self.start()
        return self

    # ---- NMT

    def nmt(self, node: int, command: str | int) -> None:
        """Send an NMT command to ``node`` (1..127, 0 = all): start, stop,
        pre-operational (preop), reset-node, reset-communication. The master itself is not
        affected."""
        spec = nmt_command(command)
        if not isinstance(node, int) or not 0 <= node <= 127:
            raise Error(f"NMT target {node!r} is outside 0..127")
        self.send(0x000, bytes([spec, node]))

    # ---- SDO

    def sdo(self, node: int) -> SdoClient:
        """The SDO client of ``node`` (1..127)."""
        if not isinstance(node, int) or not 1 <= node <= 127:
            raise Error(f"SDO server node-ID {node!r} is outside 1..127")
        if node == self.node_id:
            raise Error(f"node {node} is the master itself")
        client = self._clients.get(node)
        if client is None:
            client = self._clients[node] = SdoClient(self._sdo, node, self.sdo_timeout_ms)
        return client

    # ---- heartbeat consumer, boot-up, EMCY consumer

    def monitor(self, node: int, heartbeat_ms: int) -> None:
        """Watch ``node``'s heartbeat: an event (:meth:`on_heartbeat`) when it is not heard
        for ``heartbeat_ms`` (0 stops watching). Monitoring starts with its first
        heartbeat."""
        if not isinstance(node, int) or not 1 <= node <= 127 or node == self.node_id:
            raise Error(f"cannot monitor node {node!r}")
        if not 0 <= heartbeat_ms <= 0xFFFF:
            raise Error(f"heartbeat time {heartbeat_ms} ms is outside 0..65535")
        self.od.set(0x1016, node, (node << 16 | heartbeat_ms) if heartbeat_ms else 0)
        if heartbeat_ms:
            self._watches[node] = heartbeat_ms
        else:
            self._watches.pop(node, None)

    def heartbeat_state(self, node: int) -> str | None:
        """The state ``node`` last reported to the heartbeat consumer, None if not heard."""
        with self.locked() as n:
            state = int(lib.co_hb_remote_state(n, node))
        return None if state == 0xFF else STATE_NAMES.get(state, f"0x{state:02X}")

    def on_bootup(self, fn: F) -> F:
        """``fn(node)`` for every boot-up frame (any node, monitored or not)."""
        self._listen()
        self._bootup_cbs.append(fn)
        return fn

    # ---- frames, PDOs

    def on_frame(self, fn: F, cob_id: int | None = None) -> F:
        """``fn(Frame)`` for every frame other nodes send (or only those on ``cob_id``):
        TPDOs of devices, for instance."""
        self._listen()
        self._frame_cbs.append((cob_id, fn))
        return fn

    def _listen(self) -> None:
        """Frames of other nodes come to :meth:`_frame` from the first callback on (a
        master nobody asks for them does not pay for them)."""
        if not self._bootup_cbs and not self._frame_cbs:
            self._add_frame_listener(self._frame)

    def _frame(self, frame: Frame) -> None:  # runs outside the lock, in order
        if 0x701 <= frame.can_id <= 0x77F and frame.data == b"\x00" and not frame.rtr:
            for fn in list(self._bootup_cbs):
                fn(frame.can_id - 0x700)
        for cob_id, cb in list(self._frame_cbs):
            if cob_id is None or cob_id == frame.can_id:
                cb(frame)

    def send(self, can_id: int, data: bytes = b"", *, rtr: bool = False) -> None:
        """Send a raw frame (11-bit ``can_id``, up to 8 bytes)."""
        if not isinstance(can_id, int) or not 0 <= can_id <= 0x7FF:
            raise Error(f"CAN-ID {can_id!r} is outside 0..0x7FF")
        if len(data) > 8:
            raise Error(f"a CAN frame holds at most 8 bytes, got {len(data)}")
        frame = ffi.new("co_frame_t *")
        frame.id = can_id
        frame.flags = lib.CO_FRAME_RTR if rtr else 0
        frame.len = len(data)
        ffi.memmove(frame.data, bytes(data), len(data))
        with self.locked() as node:
            err = int(lib.co_node_send(node, frame))
        check(err, "send")

    def send_pdo(self, cob_id: int, data: bytes) -> None:
        """Send process data on ``cob_id`` (an RPDO of a device, e.g. 0x200 + node)."""
        self.send(cob_id, data)

    # ---- SYNC, TIME

    def start_sync(self, period_us: int, overflow: int = 0) -> None:
        """Produce SYNC every ``period_us``; ``overflow`` 2..240 adds a counter 1..overflow
        (0 = no counter)."""
        if not 1 <= period_us <= 0xFFFFFFFF:
            raise Error(f"SYNC period {period_us} us is outside 1..2**32-1")
        if overflow and not 2 <= overflow <= 240:
            raise Error(f"SYNC counter overflow {overflow} is outside 2..240 (or 0)")
        for index, value in _sync_writes(period_us, overflow):
            self.od.set(index, 0, value)
        self._sync = (period_us, overflow)

    def stop_sync(self) -> None:
        """Stop producing SYNC."""
        self._sync = None
        self.od.set(0x1006, 0, 0)
        self.od.set(0x1005, 0, 0x80)

    def send_time(self, when: dt.datetime | None = None) -> None:
        """Send one TIME frame with ``when`` (default now, UTC; naive = UTC)."""
        moment = when or dt.datetime.now(dt.UTC)
        if moment.tzinfo is None:
            moment = moment.replace(tzinfo=dt.UTC)
        delta = moment - _EPOCH
        if delta.total_seconds() < 0:
            raise Error("TIME cannot express moments before 1984-01-01")
        us = (delta.days * 86400 + delta.seconds) * 1_000_000 + delta.microseconds
        if self.od.get(0x1012, 0) != _TIME_PRODUCER:
            self.od.set(0x1012, 0, _TIME_PRODUCER)
        tod = lib.co_time_from_us(us)
        with self.locked() as node:
            err = int(lib.co_time_send(node, ffi.new("co_time_of_day_t *", tod)))
        check(err, "co_time_send")

    def start_time(self, period_ms: int,
                   clock: Callable[[], dt.datetime] | None = None) -> None:
        """Produce TIME every ``period_ms``: ``clock()`` (default: now, UTC) each time.
        Replaces a running TIME production."""
        if not isinstance(period_ms, int) or not 1 <= period_ms <= 86_400_000:
            raise Error(f"TIME period {period_ms!r} ms is outside 1..86400000")
        self.stop_time()
        self._time_timer = self._add_timer(
            period_ms * 1000, lambda: self.send_time(clock() if clock else None))

    def stop_time(self) -> None:
        """Stop producing TIME periodically."""
        if self._time_timer is not None:
            self._remove_timer(self._time_timer)
            self._time_timer = None

    # ---- the master's own reset

    def _on_reset(self, what: int) -> None:
        """The core reset the communication objects (0x1000..0x1FFF) to their power-on
        values, before its boot-up: set what monitor(), start_sync() and start_time() set
        up again (a C callback: the lock is held)."""
        if what != lib.CO_RESET_COMMUNICATION:
            return
        od = self.od
        for node, heartbeat_ms in self._watches.items():
            od._set_locked(0x1016, node, node << 16 | heartbeat_ms)
        if self._sync is not None:
            for index, value in _sync_writes(*self._sync):
                od._set_locked(index, 0, value)
        if self._time_timer is not None:
            od._set_locked(0x1012, 0, _TIME_PRODUCER)

    # ---- CiA 302 manager, LSS, program download (canola.manager, .lss, .flash do the work)

    def boot(self, network: Network | str | os.PathLike[str] | Sequence[str | os.PathLike[str]],
             *, on_event: Callable[[BootEvent], None] | None = None, wait: bool = True,
             timeout: float | None = None) -> NetworkManager:
        """Boot the network (CiA 302-2) described by ``network``: a
        :class:`canola.boot_plan.Network`, a YAML file, or DCF files. Blocks until the boot
        settled (unless ``wait=False``) and returns the manager: ``started``, ``slaves()``,
        ``events``. ``on_event(BootEvent)`` for every report. See :mod:`canola.manager`."""
        from canola import boot_plan as net  # noqa: PLC0415
        from canola import manager  # noqa: PLC0415 -- on first use

        if not isinstance(network, net.Network):
            paths = [network] if isinstance(network, str | os.PathLike) else list(network)
            network = net.from_files(paths, node_id_of_master=self.node_id)
        mgr = manager.boot(self._sdo, network, self._manager, on_event=on_event, wait=wait,
                           timeout=timeout)
        if mgr is not self._manager:
            self._managers.append(mgr)
            self._manager = mgr
        return mgr

    @property
    def lss(self) -> Lss:
        """The LSS master (CiA 305): fastscan, set_node_id, inquire. See :mod:`canola.lss`."""
        from canola.lss import Lss  # noqa: PLC0415

        if self._lss is None:
            self._lss = self._build(Lss)
        return self._lss

    def flash(self, node: int, data: bytes, *, progress: Callable[[int, int], None] | None
              = None, program: int = 1, clear: bool = True, ident: int | None = None,
              timeout: float | None = None) -> FlashResult:
        """Download program ``data`` to ``node`` (CiA 302-3); ``progress(done, total)``.
        Raises :class:`canola.flash.FlashError` with the stage and abort code. See
        :mod:`canola.flash`."""
        from canola.flash import flash  # noqa: PLC0415

        return flash(self._sdo, node, data, progress=progress, program=program, clear=clear,
                     ident=ident, timeout=timeout)

    def wait(self, seconds: float) -> None:
        """Let ``seconds`` pass: virtual time on a SimBus, a sleep on python-can."""
        bus = self.bus
        if isinstance(bus, SimBus):
            bus.run_for(round(seconds * 1e6))
        else:
            time.sleep(seconds)

