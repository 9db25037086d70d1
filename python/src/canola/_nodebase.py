# SPDX-License-Identifier: Apache-2.0
"""What :class:`canola.Device` and :class:`canola.Master` share: an engine, the NMT
state, start/stop, callbacks, and typed local access to the node's own dictionary."""

from __future__ import annotations

import contextlib
import logging
import os
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from typing import Any, TypeVar

from canola._c import CData, ffi, lib
from canola._engine import Bus, Engine, Frame, _Timer
from canola.core import NMT_CMDS, Od
from canola.errors import Error, SdoAbort
from canola.formats import eds, values
from canola.formats.odgen import GenerateOptions

__all__ = ["STATE_NAMES", "EmcyEvent", "Frame", "HeartbeatEvent", "LocalOd", "NodeBase",
           "StoreRejectedEvent"]

log = logging.getLogger("canola.node")

#: NMT state value -> the name :attr:`NodeBase.nmt_state` gives.
STATE_NAMES: dict[int, str] = {
    0x00: "INITIALISING",
    0x04: "STOPPED",
    0x05: "OPERATIONAL",
    0x7F: "PRE-OPERATIONAL",
}

#: NMT command names accepted by Master.nmt and Device.nmt_apply (with aliases).
NMT_NAMES: dict[str, int] = {
    **NMT_CMDS,
    "preop": NMT_CMDS["pre-operational"],
    "pre-op": NMT_CMDS["pre-operational"],
    "reset": NMT_CMDS["reset-node"],
    "reset-comm": NMT_CMDS["reset-communication"],
}

_EC_KINDS = {
    int(lib.CO_EC_BOOT): "boot",
    int(lib.CO_EC_REMOTE_RESET): "reset",
    int(lib.CO_EC_STARTED): "started",
    int(lib.CO_EC_STATE_CHANGED): "state",
    int(lib.CO_EC_HB_TIMEOUT): "lost",
    int(lib.CO_EC_HB_RESUMED): "resumed",
    int(lib.CO_EC_NOT_BOOTED): "not-booted",
    int(lib.CO_EC_GUARD_TIMEOUT): "guard-lost",
    int(lib.CO_EC_GUARD_TOGGLE): "guard-toggle",
    int(lib.CO_EC_GUARD_RESUMED): "guard-resumed",
    int(lib.CO_EC_LIFE_GUARD): "life-guard",
    int(lib.CO_EC_LIFE_GUARD_RESUMED): "life-guard-resumed",
}


def nmt_command(command: str | int) -> int:
    """The NMT command specifier of a name (start, stop, pre-operational/preop,
    reset-node, reset-communication) or a specifier."""
    if isinstance(command, int) and not isinstance(command, bool):
        if command not in NMT_CMDS.values():
            raise Error(f"unknown NMT command specifier 0x{command:02X}")
        return command
    if isinstance(command, str) and command.strip().lower() in NMT_NAMES:
        return NMT_NAMES[command.strip().lower()]
    raise Error(f"unknown NMT command {command!r} (one of {', '.join(NMT_NAMES)})")


@dataclass(frozen=True)
class HeartbeatEvent:
    """A heartbeat consumer event: ``kind`` is boot, reset, started, state, lost, resumed,
    not-booted (or a guarding kind); ``state``/``previous`` are state names."""

    node: int
    kind: str
    state: str
    previous: str


@dataclass(frozen=True)
class EmcyEvent:
    """An EMCY received: sender ``node``, error ``code``, error ``register`` and the five
    ``manufacturer`` bytes. ``code`` 0 is "error reset / no error"."""

    node: int
    code: int
    register: int
    manufacturer: bytes
    cob_id: int


@dataclass(frozen=True)
class StoreRejectedEvent:
    """Stored parameters refused at a reset: the file of ``group`` ("communication",
    comm.params, or "application", app.params) failed a check (``reason``) and was ignored
    as a whole. The group runs on its defaults; the node raised EMCY ``code`` (0xFF11 or
    0xFF12), which stays active until a save or restore of the group succeeds."""

    group: str
    file: str
    reason: str
    code: int


#: co_node_error_t of a refused group -> (group, file, CO_PARAMS_*).
_STORE_ERRORS: dict[int, tuple[str, str, int]] = {
    int(lib.CO_NODE_ERR_STORED_COMM): ("communication", "comm.params",
                                       int(lib.CO_PARAMS_COMMUNICATION)),
    int(lib.CO_NODE_ERR_STORED_APP): ("application", "app.params",
                                      int(lib.CO_PARAMS_APPLICATION)),
}

#: co_store_fault_t -> what the check found.
_STORE_FAULTS: dict[int, str] = {
    int(lib.CO_STORE_BAD_HEADER): "bad header (magic, format version or group)",
    int(lib.CO_STORE_BAD_LENGTH): "length mismatch (truncated, or bytes after the records)",
    int(lib.CO_STORE_BAD_CRC): "CRC mismatch",
    int(lib.CO_STORE_BAD_RECORDS): "records do not end at the stated length",
    int(lib.CO_STORE_READ_ERROR): "read error (or not a regular file)",
}


F = TypeVar("F", bound=Callable[..., Any])
P = TypeVar("P")


def load_od(source: str | os.PathLike[str] | eds.ObjectDictionary, node_id: int,
            options: GenerateOptions) -> Od:
    model = source if isinstance(source, eds.ObjectDictionary) else eds.parse(source)
    return Od.from_eds(model, node_id, options)


class NodeBase:
    """Engine, NMT state, start/stop, callbacks."""

    _kind = "node"
    _source = "its dictionary"  # what warnings name: the EDS/DCF file where known

    def __init__(self, bus: Bus, od: Od, node_id: int, *, sdo_timeout_ms: int,
                 store_dir: str | os.PathLike[str] | None, raw_frames: bool,
                 quiet: bool = False) -> None:
        if not 1 <= sdo_timeout_ms <= 0xFFFF:
            raise Error(f"sdo_timeout_ms {sdo_timeout_ms} is outside 1..65535")
        self.sdo_timeout_ms = sdo_timeout_ms
        store = os.fspath(store_dir) if store_dir is not None else None
        if store is not None and not os.path.isdir(store):
            raise Error(f"store_dir {store!r} is not a folder")
        self._types = {(i.index, i.sub): (i.type, i.size) for i in od.infos}
        self._engine = Engine(bus, od, node_id, self, sdo_timeout_ms=sdo_timeout_ms,
                              store_dir=store, raw_frames=raw_frames,
                              name=f"canola-{self._kind}-{node_id}", quiet=quiet)
        self.node_id = node_id
        self.od = LocalOd(self._engine, self._types)
        self._state_cbs: list[Callable[[str], None]] = []
        self._write_cbs: list[Callable[[int, int, values.Value], None]] = []
        self._sync_cbs: list[Callable[[int], None]] = []
        self._time_cbs: list[Callable[[values.TimeOfDay], None]] = []
        self._rpdo_cbs: list[Callable[[int], None]] = []
        self._hb_cbs: list[Callable[[HeartbeatEvent], None]] = []
        self._emcy_cbs: list[Callable[[EmcyEvent], None]] = []
        self._store_cbs: list[Callable[[StoreRejectedEvent], None]] = []

    @property
    def bus(self) -> Bus:
        return self._engine.bus

    @contextlib.contextmanager
    def locked(self) -> Iterator[CData]:
        """The C node (``co_node_t *``) under the node's lock, its clock brought to now: for
        a short call into the C core (what the parts built on a node do: a gateway's
        backend, a domain, a program). Frames sent inside go out when it ends; callbacks
        run after the lock. Never wait inside it: the node cannot receive meanwhile."""
        with self._engine.locked() as node:
            yield node

    def hook_entries(self, make: Callable[[CData, int], CData], keep: object) -> CData:
        """``make(entries, count)`` under the lock: C hooks attached to entries of the
        node's dictionary (their result); ``keep`` lives as long as the dictionary does
        (the entries point to it) unless the result is NULL."""
        od = self._engine.od
        with self._engine.locked():
            raw = make(od.entries, od.count)
        if raw != ffi.NULL:
            od._keep.append(keep)
        return raw

    # ---- what the facades built on a node hand to their parts

    @property
    def _c_node(self) -> CData:
        """The C node, for a caller that holds the lock already (a C callback) or runs the
        SimBus itself."""
        return self._engine.node

    def _add_timer(self, period_us: int, fn: Callable[[], None]) -> _Timer:
        return self._engine.add_timer(period_us, fn)

    def _remove_timer(self, timer: _Timer) -> None:
        self._engine.remove_timer(timer)

    def _add_frame_listener(self, fn: Callable[[Frame], None]) -> None:
        self._engine.add_frame_listener(fn)

    def _build(self, part: Callable[[Engine], P]) -> P:
        """``part(engine)``: a part of the node, handed the engine (it never reaches back
        into the node)."""
        return part(self._engine)

    # ---- life cycle

    def start(self) -> None:
        """Power the node on (boot-up, pre-operational) and, on python-can, start the bus
        thread. Calling it after :meth:`stop` resumes the thread."""
        self._engine.start()

    def stop(self) -> None:
        """Stop the bus thread (python-can; waits up to 2 s). The node keeps its state."""
        self._engine.stop()

    def __enter__(self) -> NodeBase:
        self.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self.stop()

    @property
    def nmt_state(self) -> str:
        """INITIALISING, PRE-OPERATIONAL, OPERATIONAL or STOPPED."""
        with self._engine.locked() as node:
            state = int(lib.co_nmt_state(node))
        return STATE_NAMES.get(state, f"0x{state:02X}")

    # ---- callbacks (each returns its function, so they work as decorators)

    def on_state(self, fn: F) -> F:
        """``fn(state_name)`` after this node's NMT state changed."""
        self._state_cbs.append(fn)
        return fn

    def on_write(self, fn: F) -> F:
        """``fn(index, sub, value)`` after the network (SDO, RPDO) wrote an entry."""
        self._write_cbs.append(fn)
        return fn

    def on_sync(self, fn: F) -> F:
        """``fn(counter)`` on every SYNC (0 when SYNCs carry no counter)."""
        self._sync_cbs.append(fn)
        return fn

    def on_time(self, fn: F) -> F:
        """``fn(TimeOfDay)`` on every TIME consumed (0x1012 bit 31)."""
        self._time_cbs.append(fn)
        return fn

    def on_rpdo(self, fn: F) -> F:
        """``fn(rpdo)`` (0-based) after an RPDO was applied."""
        self._rpdo_cbs.append(fn)
        return fn

    def on_heartbeat(self, fn: F) -> F:
        """``fn(HeartbeatEvent)`` for heartbeat consumer (0x1016) events."""
        self._hb_cbs.append(fn)
        return fn

    def on_emcy(self, fn: F) -> F:
        """``fn(EmcyEvent)`` for every EMCY the consumer (0x1028) receives."""
        self._emcy_cbs.append(fn)
        return fn

    def on_frame_sent(self, fn: F) -> F:
        """``fn(Frame)`` for every frame this node puts on the bus, in the order sent: its
        own frames, which python-can does not hand back to the bus object that sent them
        (e.g. to report this node's EMCYs, on the COB-ID its 0x1014 holds). Like every
        callback it runs outside the lock, after the call that made the node send."""
        self._engine.add_sent_listener(fn)
        return fn

    def on_store_rejected(self, fn: F) -> F:
        """``fn(StoreRejectedEvent)`` when, at a reset (:meth:`start` included), a stored
        parameter file of ``store_dir`` failed its checks and was ignored: the node runs on
        defaults. Without any such callback the event is logged as a warning."""
        self._store_cbs.append(fn)
        return fn

    # ---- C callbacks (under the lock): queue the work for after

    def _fire(self, cbs: list[Callable[..., None]], *args: Any) -> None:
        for fn in list(cbs):
            self._engine.later(lambda fn=fn: fn(*args))  # type: ignore[misc]

    def _on_state(self, state: int) -> None:
        self._fire(self._state_cbs, STATE_NAMES.get(state, f"0x{state:02X}"))

    def _on_reset(self, what: int) -> None:
        """The core reset the communication objects (``what``: CO_RESET_*), before its
        boot-up: what a facade set up there is set again here."""

    def _on_written(self, index: int, sub: int, by_app: bool) -> None:
        if by_app or not self._write_cbs:  # on_write: what the network wrote
            return
        try:
            value = self.od._read_locked(index, sub)
        except Error:
            return
        self._fire(self._write_cbs, index, sub, value)

    def _on_sync(self, counter: int) -> None:
        self._fire(self._sync_cbs, counter)

    def _on_time(self, ms: int, days: int) -> None:
        self._fire(self._time_cbs, values.TimeOfDay(ms, days))

    def _on_rpdo(self, rpdo: int) -> None:
        self._fire(self._rpdo_cbs, rpdo)

    def _on_errctl(self, kind: int, node_id: int, state: int, previous: int) -> None:
        def name(s: int) -> str:
            return STATE_NAMES.get(s, "unknown")
        self._fire(self._hb_cbs, HeartbeatEvent(node_id, _EC_KINDS.get(kind, str(kind)),
                                                name(state), name(previous)))

    def _on_emcy(self, cob_id: int, code: int, reg: int, manufacturer: bytes) -> None:
        self._fire(self._emcy_cbs, EmcyEvent(cob_id & 0x7F, code, reg, manufacturer, cob_id))

    def _on_error(self, error: int) -> None:
        if error == lib.CO_NODE_ERR_SDO_COB_FIXED:
            log.warning("%s %d: %s: [1200] sub1/sub2 are not 0x%03X/0x%03X, the COB-IDs CiA "
                        "301 fixes for the default SDO server: served on those regardless",
                        self._kind, self.node_id, self._source, 0x600 + self.node_id,
                        0x580 + self.node_id)
            return
        if error == lib.CO_NODE_ERR_STORE_FAILED:
            log.warning("%s %d: storing parameters failed (full disk, read-only or broken "
                        "storage): the files stored before stay (EMCY 0x%04X)", self._kind,
                        self.node_id, int(lib.CO_EMCY_STORE_FAILED))
            return
        refused = _STORE_ERRORS.get(error)
        if refused is None:
            return  # transmit losses: counted by the core (co_node_stats)
        group, file, param_group = refused
        fault = int(lib.co_storage_verify(self._engine.node, param_group))
        event = StoreRejectedEvent(group, file, _STORE_FAULTS.get(fault, f"fault {fault}"),
                                   int(lib.CO_EMCY_STORE_REJECTED) + param_group)
        if not self._store_cbs:
            log.warning("%s %d: stored %s parameters (%s) refused: %s; defaults in use "
                        "(EMCY 0x%04X)", self._kind, self.node_id, group, file, event.reason,
                        event.code)
        self._fire(self._store_cbs, event)


class LocalOd:
    """The node's own dictionary from the application side: ``od[index][sub]`` and
    ``od[index, sub]`` read and write typed values (see :mod:`canola.formats.values`), without
    access rights (the application may set read-only entries) but with limits and the
    node's service rules; a write to a mapped object triggers event-driven TPDOs.
    Failures raise :class:`~canola.errors.SdoAbort` with the CiA code."""

    def __init__(self, engine: Engine, types: dict[tuple[int, int], tuple[int, int]]) -> None:
        self._engine = engine
        self._types = types  # (index, sub) -> (data type, size a read reserves)

    def _info(self, index: int, sub: int) -> tuple[int, int]:
        if not (isinstance(index, int) and isinstance(sub, int)):
            raise Error(f"index and sub-index are integers, not {index!r}, {sub!r}")
        info = self._types.get((index, sub))
        if info is None:
            known = any(i == index for i, _ in self._types)
            raise SdoAbort(0x06090011 if known else 0x06020000)
        return info

    def __contains__(self, key: object) -> bool:
        if isinstance(key, tuple):
            return key in self._types
        return any(i == key for i, _ in self._types)

    def __iter__(self) -> Iterator[tuple[int, int]]:
        return iter(sorted(self._types))

    def type_of(self, index: int, sub: int) -> int:
        """The CiA 301 data type code of an entry."""
        return self._info(index, sub)[0]

    def read(self, index: int, sub: int) -> bytes:
        """The wire bytes of an entry."""
        _, size = self._info(index, sub)
        with self._engine.locked() as node:
            return self._raw_read(node, index, sub, size)

    @staticmethod
    def _raw_read(node: Any, index: int, sub: int, size: int) -> bytes:
        cap = max(size, 8)
        buf = ffi.new("uint8_t[]", cap)
        n = ffi.new("uint32_t *")
        kind = ffi.new("uint8_t *")
        code = int(lib.canola_py_app_read(node, index, sub, buf, cap, n, kind))
        if code:
            raise SdoAbort(code)
        return bytes(ffi.buffer(buf, int(n[0])))

    def _read_locked(self, index: int, sub: int) -> values.Value:
        data_type, size = self._info(index, sub)
        data = self._raw_read(self._engine.node, index, sub, size)
        return values.decode(data_type, data)

    def write(self, index: int, sub: int, data: bytes) -> None:
        """Write wire bytes to an entry (application write)."""
        self._info(index, sub)
        engine = self._engine
        with engine.locked():
            code = int(lib.canola_py_dev_write(engine.dev, index, sub, bytes(data), len(data)))
        if code:
            raise SdoAbort(code)

    def _set_locked(self, index: int, sub: int, value: values.Value) -> None:
        """:meth:`set` from a C callback of the node (the lock is held already)."""
        data_type, _ = self._info(index, sub)
        data = values.encode(data_type, value)
        code = int(lib.canola_py_dev_write(self._engine.dev, index, sub, data, len(data)))
        if code:
            raise SdoAbort(code)

    def reserve(self, index: int, sub: int, size: int) -> None:
        """Reads of (index, sub) reserve ``size`` bytes from now on (an entry whose value
        the application sizes, e.g. a streamed DOMAIN)."""
        data_type, _ = self._info(index, sub)
        self._types[index, sub] = (data_type, size)

    def get(self, index: int, sub: int = 0) -> values.Value:
        data_type, _ = self._info(index, sub)
        return values.decode(data_type, self.read(index, sub))

    def set(self, index: int, sub: int, value: values.Value) -> None:
        data_type, _ = self._info(index, sub)
        self.write(index, sub, values.encode(data_type, value))

    def __getitem__(self, key: int | tuple[int, int]) -> Any:
        if isinstance(key, tuple):
            return self.get(*key)
        self._info(key, 0) if (key, 0) in self._types else self._info(key, 1)
        return _ObjectView(self, key)

    def __setitem__(self, key: tuple[int, int], value: values.Value) -> None:
        if not isinstance(key, tuple):
            raise Error("write an entry as od[index, sub] = value or od[index][sub] = value")
        self.set(key[0], key[1], value)


class _ObjectView:
    """``od[index]``: its sub-indices by ``[sub]``; ``.value`` is sub-index 0."""

    def __init__(self, od: LocalOd, index: int) -> None:
        self._od = od
        self.index = index

    def __getitem__(self, sub: int) -> values.Value:
        return self._od.get(self.index, sub)

    def __setitem__(self, sub: int, value: values.Value) -> None:
        self._od.set(self.index, sub, value)

    @property
    def value(self) -> values.Value:
        return self._od.get(self.index, 0)

    @value.setter
    def value(self, value: values.Value) -> None:
        self._od.set(self.index, 0, value)

