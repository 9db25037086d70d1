# SPDX-License-Identifier: Apache-2.0
"""The canola C core, from Python: object dictionaries, nodes and the simulated bus.

Built on the cffi extension ``canola._core`` (through ``canola._c``). Everything runs on
a :class:`SimBus` with a virtual clock; nothing depends on wall time.

- :meth:`Od.from_eds` turns a parsed EDS/DCF (:func:`canola.formats.eds.parse`) into an entry
  table in C memory, with the type / access / power-on value mapping of
  :mod:`canola.formats.odgen`.
- :class:`SimBus` is the simulated bus; ``trace`` collects every delivered frame as a
  candump line (``(0.001000) sim0 701#00``).
- the nodes on it: :class:`canola.Device`, :class:`canola.Master` and the bare
  :class:`canola.simnode.Node`.
"""

from __future__ import annotations

import math
import sys
from dataclasses import dataclass
from typing import Any

from canola._c import check as _check
from canola._c import ffi, lib
from canola.errors import Error
from canola.formats import eds
from canola.formats.datatypes import DATA_TYPES
from canola.formats.odgen import (
    _BOOL,
    _DOMAIN,
    _OSTRING,
    _RAW,
    _REAL,
    _SIGNED,
    _TABLE_OBJECTS,
    _UNSIGNED,
    _USTRING,
    _VSTRING,
    GenerateOptions,
    _Gen,
    check_usable,
)

__all__ = ["NMT_CMDS", "NMT_STATES", "Od", "SimBus"]

#: NMT command names -> command specifier.
NMT_CMDS: dict[str, int] = {
    "start": int(lib.CO_NMT_CMD_START),
    "stop": int(lib.CO_NMT_CMD_STOP),
    "pre-operational": int(lib.CO_NMT_CMD_ENTER_PRE_OPERATIONAL),
    "reset-node": int(lib.CO_NMT_CMD_RESET_NODE),
    "reset-communication": int(lib.CO_NMT_CMD_RESET_COMMUNICATION),
}

#: NMT state values (as heartbeats carry them) -> names.
NMT_STATES: dict[int, str] = {
    int(v): ffi.string(lib.co_nmt_state_name(v)).decode()
    for v in (lib.CO_NMT_INITIALISING, lib.CO_NMT_STOPPED, lib.CO_NMT_OPERATIONAL,
              lib.CO_NMT_PRE_OPERATIONAL)
}

# ---------------------------------------------------------------------------------------
# object dictionary


@dataclass(frozen=True)
class _EntryInfo:
    index: int
    sub: int
    type: int
    size: int


class Od:
    """An entry table (``co_od_entry_t[]``) and its values, in memory owned by this object.

    Keep the object alive as long as a node uses it (:class:`Node` does).
    """

    def __init__(self, entries: Any, count: int, keep: list[Any], infos: list[_EntryInfo],
                 node_id: int | None) -> None:
        self._entries = entries
        self.count = count
        self._keep = keep
        self.infos = infos
        self.node_id = node_id

    @property
    def entries(self) -> Any:
        """The ``co_od_entry_t`` array (cffi cdata)."""
        return self._entries

    @classmethod
    def from_eds(cls, model: eds.ObjectDictionary, node_id: int | None = None,
                 options: GenerateOptions | None = None) -> Od:
        """Build the table of ``model`` as :func:`canola.formats.odgen.generate` would in C.

        ``node_id`` is the node-ID the dictionary is meant for (default: the DCF's); the
        ``$NODEID`` part of power-on values is added by the core at reset, from the node's
        own ID. ``options`` as for odgen (``min_string_size``, ``domain_size``). Raises
        :class:`~canola.errors.EdsError` for what the core cannot hold.
        """
        opts = options or GenerateOptions()
        check_usable(model, opts)
        gen = _Gen(model, opts)
        built: list[tuple[eds.Variable, int, int, Any, Any, Any]] = []
        keep: list[Any] = []
        for index in sorted(model.objects):
            obj = model.objects[index]
            if obj.object_type not in _TABLE_OBJECTS or not obj.subs:
                continue
            for sub in sorted(obj.subs):
                var = obj.subs[sub]
                e = gen.entry(var, f"sub{sub}")
                if e is None:  # DOMAIN without storage (domain_size 0)
                    continue
                attr = 0
                for name in e.attr.split("|"):
                    attr |= int(getattr(lib, name.strip()))
                size = e.size
                if e.kind == _OSTRING:  # an OCTET_STRING keeps the length of its default
                    init = gen.octets(var, *gen.value_text(var))
                    size = len(init) or size
                value, dflt = _storage(gen, var, e.kind, e.ctype, size, keep=keep)
                limits = _limits(gen, var, e.kind) if e.limits is not None else ffi.NULL
                built.append((var, attr, size, value, dflt, limits))
        count = len(built)
        entries = ffi.new("co_od_entry_t[]", max(count, 1))
        infos = []
        for i, (var, attr, size, value, dflt, limits) in enumerate(built):
            assert var.data_type is not None
            ent = entries[i]
            ent.index = var.index
            ent.sub = var.subindex
            ent.type = var.data_type
            ent.attr = attr
            ent.size = size
            ent.value = value
            ent.dflt = dflt
            ent.limits = limits
            keep.append(limits)
            infos.append(_EntryInfo(var.index, var.subindex, var.data_type, size))
        od = ffi.new("co_od_t *")
        od.entries = entries
        od.count = count
        bad = ffi.new("uint32_t *")
        if lib.co_od_validate(od, bad) != lib.CO_OK:
            pos = int(bad[0])
            where = f" at 0x{infos[pos].index:04X} sub {infos[pos].sub}" if pos < count else ""
            raise Error(f"the core rejects the object dictionary{where}")
        return cls(entries, count, keep, infos,
                   node_id if node_id is not None else model.node_id)


def _storage(gen: _Gen, var: eds.Variable, kind: int, ctype: str, size: int, *,
             keep: list[Any]) -> tuple[Any, Any]:
    """Native storage and power-on value of one entry, as cdata (void * compatible)."""
    text, key = gen.value_text(var)
    if kind in (_BOOL, _SIGNED, _UNSIGNED, _REAL):
        number, _ = gen.number(var, text, key, kind, kind != _REAL)
        value = ffi.new(f"{ctype} *")
        dflt = ffi.new(f"{ctype} *", number)
    elif kind == _DOMAIN:
        data = ffi.new("uint8_t[]", size)
        value = ffi.new("co_od_domain_t *", {"data": data, "len": 0})
        keep.append(data)
        dflt = ffi.NULL
    else:
        if kind == _RAW:
            raw, _ = gen.number_raw(var, text, key)
            init = raw.to_bytes(6, "little")
        elif kind == _VSTRING:
            init = gen.encode(var, text, key)
        elif kind == _OSTRING:
            init = gen.octets(var, text, key)
        else:
            assert kind == _USTRING
            init = text.encode("utf-16-le")
        value = ffi.new("uint8_t[]", size)
        dflt = ffi.new("uint8_t[]", init.ljust(size, b"\0")[:size])
    keep.append(value)
    keep.append(dflt)
    return value, dflt


def _limits(gen: _Gen, var: eds.Variable, kind: int) -> Any:
    assert var.data_type is not None
    info = DATA_TYPES[var.data_type]
    lim = ffi.new("co_od_limits_t *")
    real_max = 3.4028234663852886e38 if var.data_type == 0x08 else sys.float_info.max
    for side, text, key in (("low", var.low_limit, "LowLimit"), ("high", var.high_limit,
                                                                  "HighLimit")):
        num = getattr(lim, side)
        given = text is not None and bool(text.strip())
        if kind == _REAL:
            value = gen.number(var, text or "", key, kind, True)[0] if given else (
                -real_max if side == "low" else real_max)
            num.f = float(value) if math.isfinite(float(value)) else real_max
        else:
            bound = info.min if side == "low" else info.max
            value = gen.number(var, text or "", key, kind, True)[0] if given else bound
            if kind == _SIGNED:
                num.i = int(value)
            else:
                num.u = int(value)
    return lim


# ---------------------------------------------------------------------------------------
# bus


@ffi.def_extern()
def canola_py_trace(ctx: Any, line: Any) -> None:
    trace: list[str] = ffi.from_handle(ctx)
    trace.append(ffi.string(line).decode("ascii", "replace"))


class SimBus:
    """A simulated CAN bus with a virtual clock (``port/sim``).

    ``bitrate`` 0 delivers every frame at the instant it is sent; 10000..1000000 models
    arbitration and frame lengths. ``trace`` holds every delivered frame as a candump line.
    """

    def __init__(self, bitrate: int = 0) -> None:
        bus = lib.canola_py_bus_new(bitrate)
        if bus == ffi.NULL:
            raise Error(f"cannot create a simulated bus at {bitrate} bit/s")
        self._bus = ffi.gc(bus, lib.canola_py_bus_free)
        self.trace: list[str] = []
        self._trace_handle = ffi.new_handle(self.trace)
        lib.co_sim_set_trace(self._bus, lib.canola_py_trace, self._trace_handle)
        # nodes live as long as the bus: their ports stay attached to it
        self._nodes: list[tuple[Any, Any]] = []
        # canola.Device / canola.Master engines: their callbacks run after each run
        self._engines: list[Any] = []

    @property
    def now_us(self) -> int:
        """Virtual time in microseconds."""
        return int(lib.canola_py_bus_now(self._bus))

    @property
    def load(self) -> float:
        """Bus load since time 0 (timing model only), 0..1."""
        return float(lib.co_sim_load(self._bus))

    def run_until(self, until_us: int) -> None:
        """Advance virtual time to ``until_us``, delivering frames and polling nodes."""
        if until_us < self.now_us:
            raise Error(f"cannot run back in time (now {self.now_us} us, asked {until_us} us)")
        while True:  # step to the timers of the Python side (canola.Master's TIME)
            step = until_us
            for engine in self._engines:
                due = engine.next_timer_us()
                if due is not None and due < step:
                    step = max(due, self.now_us)
            _check(lib.co_sim_run_until(self._bus, step), "co_sim_run_until")
            for engine in self._engines:
                engine.run_timers(self.now_us)
            for engine in self._engines:
                engine.dispatch()
            if self.now_us >= until_us:
                break

    def run_for(self, us: int) -> None:
        """Advance virtual time by ``us``."""
        self.run_until(self.now_us + us)
