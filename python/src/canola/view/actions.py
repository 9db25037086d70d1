# SPDX-License-Identifier: Apache-2.0
"""What the page of ``canola view`` can ask of the bus: the object tree of a node's EDS,
SDO reads and writes of an entry, NMT commands, a node's PDO mappings read by SDO.

They run through one :class:`canola.Master`, opened on the first request (a view that is
only looked at sends nothing); it stays silent on the bus but for its requests. Values go
both ways as text, typed by the node's EDS when it has the entry (else raw hex bytes). Every
failure is an :class:`ActionError` with a one-line message for the page.
"""

from __future__ import annotations

import asyncio
import threading
from collections.abc import Callable
from typing import Any

import can

from canola.errors import Error, SdoAbort
from canola.formats import values
from canola.formats.eds import ObjectDictionary, Variable
from canola.master import Master
from canola.nodedicts import NodeDictionaries
from canola.odnames import value_text
from canola.pdomap import read_pdos

__all__ = ["NMT_COMMANDS", "ActionError", "BusActions", "od_tree"]

NMT_COMMANDS = ("start", "stop", "preop", "reset-node", "reset-comm")


class ActionError(Error):
    """A request the page made that failed (one line for the page)."""


def _variable(od: ObjectDictionary | None, index: int, sub: int) -> Variable | None:
    obj = None if od is None else od.objects.get(index)
    return None if obj is None else obj.subs.get(sub)


def _type_name(code: int | None) -> str:
    try:
        return values.type_name(code) if code is not None else ""
    except values.ValueFormatError:
        return f"0x{code:04X}"


def od_tree(od: ObjectDictionary | None) -> list[dict[str, Any]]:
    """The objects of ``od`` with their entries (names, types, access), for the page."""
    if od is None:
        return []
    return [{"index": obj.index, "name": obj.name, "subs": [
        {"sub": var.subindex, "name": var.name, "type": _type_name(var.data_type),
         "access": var.access_type or "", "default": var.default_value or ""}
        for _, var in sorted(obj.subs.items())]}
        for _, obj in sorted(od.objects.items())]


class BusActions:
    """The requests, by a master that ``open_master`` makes (once, on first use)."""

    def __init__(self, open_master: Callable[[], Master],
                 dictionaries: NodeDictionaries) -> None:
        self._open = open_master
        self._dicts = dictionaries
        self._master: Master | None = None
        self._lock = threading.Lock()
        self._closed = False

    def master(self) -> Master:
        with self._lock:
            if self._closed:  # a request still running at Ctrl-C opens no master after it
                raise ActionError("the view is stopping")
            if self._master is None:
                try:
                    master = self._open()
                    master.start()
                except Error as exc:
                    raise ActionError(f"cannot reach the bus: {exc}") from None
                self._master = master
            return self._master

    def close(self) -> None:
        """Stop the master, and refuse requests from now on (they would open another)."""
        with self._lock:
            self._closed = True
            if self._master is not None:
                self._master.stop()
                bus = self._master.bus
                if isinstance(bus, can.BusABC):
                    bus.shutdown()
                self._master = None

    async def _call(self, fn: Callable[[], Any]) -> Any:
        """``fn`` in a worker thread (SDO transfers wait), its errors as ActionError."""
        try:
            return await asyncio.get_running_loop().run_in_executor(None, fn)
        except SdoAbort as exc:
            raise ActionError(str(exc)) from None
        except Error as exc:
            raise ActionError(str(exc)) from None

    async def read(self, node: int, index: int, sub: int) -> dict[str, Any]:
        """Upload an entry: its value as text (typed by the EDS), the raw bytes."""
        data: bytes = await self._call(lambda: self.master().sdo(node).upload(index, sub))
        var = _variable(self._dicts.get(node), index, sub)
        return {"value": value_text(var, data), "raw": data.hex(" ").upper(),
                "type": _type_name(None if var is None else var.data_type)}

    async def write(self, node: int, index: int, sub: int, text: str) -> dict[str, Any]:
        """Download ``text`` to an entry, as its EDS type says (hex bytes without one)."""
        var = _variable(self._dicts.get(node), index, sub)
        try:
            if var is not None and var.data_type is not None:
                data = values.encode(var.data_type, values.from_text(var.data_type, text))
            else:
                data = bytes.fromhex(text)
        except (values.ValueFormatError, ValueError) as exc:
            raise ActionError(f"bad value {text!r}: {exc}"
                              if var is not None else
                              f"bad value {text!r}: no EDS type for this entry, give hex "
                              "bytes (e.g. 0A 00)") from None
        if not data:
            raise ActionError("nothing to write")
        await self._call(lambda: self.master().sdo(node).download(index, sub, data))
        return {"written": data.hex(" ").upper()}

    async def nmt(self, node: int, command: str) -> None:
        if command not in NMT_COMMANDS:
            raise ActionError(f"unknown NMT command {command!r}: {', '.join(NMT_COMMANDS)}")
        await self._call(lambda: self.master().nmt(node, command))

    async def pdos(self, node: int) -> list[Any]:
        """Read ``node``'s PDO mappings by SDO."""
        od = self._dicts.get(node)
        return list(await self._call(lambda: read_pdos(self.master().sdo(node), od)))
