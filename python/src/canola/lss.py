# SPDX-License-Identifier: Apache-2.0
"""Layer setting services (CiA 305) from a :class:`canola.Master`: find devices without a
node-ID and give them one.

    ids = master.lss.fastscan()                  # [LssAddress(vendor, product, ...), ...]
    master.lss.set_node_id(ids[0], 5)            # that device boots as node 5
    master.lss.inquire(ids[0])                   # {"vendor": ..., "node_id": 5, ...}
    master.lss.assign([20, 21, 22])              # fastscan + next ID, until none is left

A :class:`canola.Device` created with node-ID 0xFF (:data:`UNCONFIGURED`) has none: it
answers LSS only and boots as soon as a master gives it one.

A fastscan finds one device and costs 134 LSS time-outs (``timeout_ms``, default 100 ms:
about 13 s in real time; on a SimBus that is virtual time); one above a device found, from
7 to about 270. Every request raises :class:`LssError` when it fails (no answer, refused).

:meth:`Lss.fastscan` lists them all: devices are found lowest address first, and each scan
after the first looks for the lowest address above the last one found (from 7 time-outs
when only the serial numbers differ). A device found stays in LSS configuration, where
CiA 305 has it ignore fastscan. Some slaves take part in fastscan there all the same:
CANopenNode's answer every request, which would confirm every bit of the next scan (the
scan tells, ``keeps_answering``, and such a slave is switched back to waiting), durand's
match them as in waiting. Either way they are below the addresses asked for next.
"""

from __future__ import annotations

import re
import threading
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from canola._c import check as _check
from canola._c import ffi, lib
from canola._waiting import Waiter
from canola.errors import Error

if TYPE_CHECKING:
    from canola._engine import Engine

__all__ = ["UNCONFIGURED", "FastscanTimeLimitError", "Lss", "LssAddress", "LssError"]

#: The node-ID of a device that has none yet (LSS gives it one).
UNCONFIGURED = 0xFF

_INQUIRE = {
    "vendor": int(lib.CO_LSS_CS_INQUIRE_VENDOR),
    "product": int(lib.CO_LSS_CS_INQUIRE_PRODUCT),
    "revision": int(lib.CO_LSS_CS_INQUIRE_REVISION),
    "serial": int(lib.CO_LSS_CS_INQUIRE_SERIAL),
    "node_id": int(lib.CO_LSS_CS_INQUIRE_NODE_ID),
}
_PART = re.compile(r"^(0x)?[0-9a-f]{1,8}$", re.IGNORECASE)


@dataclass(frozen=True, order=True)
class LssAddress:
    """A device's LSS address: its identity object 0x1018 sub1..4. Written (and parsed)
    as ``vendor:product:revision:serial`` in hex."""

    vendor: int
    product: int
    revision: int
    serial: int

    def __str__(self) -> str:
        return (f"{self.vendor:08X}:{self.product:08X}:{self.revision:08X}:"
                f"{self.serial:08X}")

    @classmethod
    def parse(cls, text: str) -> LssAddress:
        """From ``vendor:product:revision:serial`` (hex, 0x optional). Raises Error."""
        parts = text.strip().split(":")
        if len(parts) != 4 or not all(_PART.match(p) for p in parts):
            raise Error(f"bad LSS address {text!r}: vendor:product:revision:serial in hex, "
                        "e.g. CA0:1:10000:2A")
        vendor, product, revision, serial = (int(p, 16) for p in parts)
        return cls(vendor, product, revision, serial)

    def as_dict(self) -> dict[str, int]:
        return {"vendor": self.vendor, "product": self.product, "revision": self.revision,
                "serial": self.serial}


class LssError(Error):
    """An LSS request that failed: ``status`` is ok, time-out, refused, scan failed or
    cancelled; ``error``/``spec_error`` the device's answer to a refused request."""

    def __init__(self, what: str, status: int, error: int = 0, spec_error: int = 0) -> None:
        self.status = ffi.string(lib.co_lss_status_name(status)).decode()
        self.error = error
        self.spec_error = spec_error
        detail = {
            int(lib.CO_LSS_TIMEOUT): "no answer",
            int(lib.CO_LSS_REFUSED): f"refused with error {error} (specific {spec_error})",
            int(lib.CO_LSS_SCAN_FAILED): "the answers stopped half-way (devices left the bus, "
                                         "or answer later than the LSS time-out?)",
        }.get(status, self.status)
        super().__init__(f"LSS {what}: {detail}")


class FastscanTimeLimitError(Error):
    """:meth:`Lss.fastscan` reached its ``time_limit``; ``found``: the devices found so
    far."""

    def __init__(self, time_limit: float, found: list[LssAddress]) -> None:
        self.time_limit = time_limit
        self.found = list(found)
        listed = ", ".join(map(str, found)) or "none"
        super().__init__(f"LSS fastscan: not done within {time_limit:g} s (found so far: "
                         f"{listed})")


class _Call:
    """One request in flight; the C completion fills it (under the node's lock)."""

    def __init__(self, waiter: Waiter) -> None:
        self.waiter = waiter
        self.done = False
        self.status = 0
        self.error = 0
        self.spec_error = 0
        self.value = 0
        self.answers = 0
        self.keeps_answering = False
        self.address = LssAddress(0, 0, 0, 0)


@ffi.def_extern()
def canola_py_lss_done(ctx: Any, result: Any) -> None:
    call: _Call = ffi.from_handle(ctx)
    call.status = int(result.status)
    call.error = int(result.error)
    call.spec_error = int(result.spec_error)
    call.value = int(result.value)
    call.answers = int(result.answers)
    call.keeps_answering = bool(result.keeps_answering)
    a = result.address
    call.address = LssAddress(int(a.vendor), int(a.product), int(a.revision), int(a.serial))
    call.done = True


def _node_id(node_id: int) -> int:
    if isinstance(node_id, bool) or not isinstance(node_id, int) or not 1 <= node_id <= 127:
        raise Error(f"node-ID {node_id!r} is outside 1..127")
    return node_id


class Lss:
    """The LSS master of ``master`` (``master.lss``). One request at a time; every method
    blocks until the devices answered or the time-out passed."""

    def __init__(self, engine: Engine, timeout_ms: int = 100) -> None:
        self.engine = engine
        self._waiter = Waiter(self.engine)
        self._lock = threading.Lock()
        self._timeout_ms = 0
        self.timeout_ms = timeout_ms

    @property
    def timeout_ms(self) -> int:
        """How long each request waits for answers (1..65535 ms)."""
        return self._timeout_ms

    @timeout_ms.setter
    def timeout_ms(self, value: int) -> None:
        if isinstance(value, bool) or not isinstance(value, int) or not 1 <= value <= 0xFFFF:
            raise Error(f"LSS time-out {value!r} ms is outside 1..65535")
        with self.engine.locked() as node:
            _check(int(lib.co_lss_master_set_timeout(node, value)), "LSS time-out")
        self._timeout_ms = value

    # ---- machinery

    def _run(self, what: str, start: Callable[[Any, Any], int], steps: int = 1,
             limit: float | None = None) -> _Call:
        """Start one request and wait for its completion (``steps`` time-outs at most, or
        ``limit`` seconds: then it is cancelled)."""
        self._waiter.check()
        with self._lock:
            call = _Call(self._waiter)
            handle = ffi.new_handle(call)
            with self.engine.locked() as node:
                err = int(start(node, handle))
            _check(err, f"LSS {what}")
            if limit is None:
                limit = steps * self._timeout_ms / 1000 * 1.5 + 2.0
            if not self._waiter.wait(lambda: call.done, limit):
                with self.engine.locked() as node:
                    lib.co_lss_master_cancel(node)  # completes it (cancelled)
                self._waiter.wait(lambda: call.done, 1.0)
            del handle
            return call

    def _expect_ok(self, what: str, call: _Call) -> None:
        if call.status != lib.CO_LSS_OK:
            raise LssError(what, call.status, call.error, call.spec_error)

    # ---- requests

    def switch_global(self, mode: str) -> None:
        """Switch every device to ``"waiting"`` or ``"configuration"``. Devices without
        node-ID that were given one boot when switched to waiting."""
        modes = {"waiting": lib.CO_LSS_WAITING, "configuration": lib.CO_LSS_CONFIGURATION}
        if mode not in modes:
            raise Error(f"LSS mode {mode!r}: waiting or configuration")
        with self.engine.locked() as node:
            _check(int(lib.co_lss_switch_global(node, modes[mode])), "LSS switch")

    def select(self, address: LssAddress) -> None:
        """Switch the device with ``address`` to configuration (switch state selective)."""
        if not isinstance(address, LssAddress):
            raise Error(f"an LssAddress is needed, not {address!r}")
        c_addr = ffi.new("co_lss_address_t *", address.as_dict())
        call = self._run(f"select {address}", lambda node, h: lib.co_lss_switch_selective(
            node, c_addr, lib.canola_py_lss_done, h))
        if call.status == lib.CO_LSS_TIMEOUT:
            raise Error(f"LSS: no device with address {address} answered")
        self._expect_ok(f"select {address}", call)

    def configure_node_id(self, node_id: int) -> None:
        """Give the device in configuration ``node_id`` (1..127, or 0xFF: none)."""
        if node_id != UNCONFIGURED:
            _node_id(node_id)
        call = self._run("configure node-ID", lambda node, h: lib.co_lss_configure_node_id(
            node, node_id, lib.canola_py_lss_done, h))
        self._expect_ok(f"configure node-ID {node_id}", call)

    def store(self) -> None:
        """Make the device in configuration store its node-ID (and bit timing)."""
        call = self._run("store", lambda node, h: lib.co_lss_store(
            node, lib.canola_py_lss_done, h))
        self._expect_ok("store configuration", call)

    def inquire_value(self, what: str) -> int:
        """One value of the device in configuration: vendor, product, revision, serial or
        node_id."""
        if what not in _INQUIRE:
            raise Error(f"cannot inquire {what!r}: one of {', '.join(_INQUIRE)}")
        call = self._run(f"inquire {what}", lambda node, h: lib.co_lss_inquire(
            node, _INQUIRE[what], lib.canola_py_lss_done, h))
        self._expect_ok(f"inquire {what}", call)
        return call.value & 0xFF if what == "node_id" else call.value

    def inquire(self, address: LssAddress | None = None) -> dict[str, int]:
        """Every value of one device: the one with ``address`` (selected, then back to
        waiting), or without address the one in configuration now."""
        try:  # a select whose answer was lost may have switched the device all the same
            if address is not None:
                self.select(address)
            return {what: self.inquire_value(what) for what in _INQUIRE}
        finally:
            if address is not None:
                self.switch_global("waiting")

    def count_unconfigured(self) -> int:
        """How many devices without node-ID answer (identify non-configured slave)."""
        call = self._run("identify non-configured", lambda node, h:
                         lib.co_lss_identify_non_configured(node, lib.canola_py_lss_done, h))
        if call.status == lib.CO_LSS_TIMEOUT:
            return 0
        self._expect_ok("identify non-configured", call)
        return call.answers

    def fastscan_one(self) -> LssAddress | None:
        """Find one device without node-ID: its address (it is now in configuration), or
        None when none answered."""
        call = self._scan(None)
        return None if call is None else call.address

    def _scan(self, limit: float | None, above: LssAddress | None = None) -> _Call | None:
        """One fastscan (cancelled after ``limit`` seconds), for the lowest address above
        ``above`` if given: the call, None when nobody answered; LssError when it failed
        or was cancelled."""
        scan = ffi.NULL
        if above is not None:
            scan = ffi.new("co_lss_fastscan_t *", {"address": above.as_dict(), "above": True})
        call = self._run("fastscan", lambda node, h: lib.co_lss_fastscan(
            node, scan, lib.canola_py_lss_done, h), steps=140 if above is None else 280,
            limit=limit)
        if call.status == lib.CO_LSS_TIMEOUT:
            return None
        self._expect_ok("fastscan", call)
        return call

    def fastscan(self, max_devices: int = 127, *,
                 time_limit: float | None = None) -> list[LssAddress]:
        """The addresses of every device without node-ID (lowest first, at most
        ``max_devices``); they are all back in waiting afterwards. Each scan after the
        first is for the lowest address above the last one found (see the module doc).
        ``time_limit`` (seconds; virtual time on a SimBus)
        bounds the whole scan: :class:`FastscanTimeLimitError` when it is reached, with the
        devices found so far."""
        if not 1 <= max_devices <= 127:
            raise Error(f"max_devices {max_devices!r} is outside 1..127")
        if time_limit is not None and not time_limit > 0:
            raise Error(f"time_limit must be positive, got {time_limit}")
        began = self.engine.now_us()
        found: list[LssAddress] = []
        try:
            while len(found) < max_devices:
                left = None
                if time_limit is not None:
                    left = time_limit - (self.engine.now_us() - began) / 1e6
                    if left <= 0:
                        raise FastscanTimeLimitError(time_limit, found)
                try:
                    call = self._scan(left, found[-1] if found else None)
                except LssError as exc:
                    if exc.status == "cancelled" and time_limit is not None:
                        raise FastscanTimeLimitError(time_limit, found) from None
                    raise
                if call is None or call.address in found:
                    break  # nobody left (a slave that matches anything: found again)
                found.append(call.address)
                if call.keeps_answering:  # it would confirm every bit of the next scan
                    self.switch_global("waiting")
        finally:
            if found:
                self.switch_global("waiting")
        return found

    def set_node_id(self, address: LssAddress, node_id: int, *, store: bool = False) -> None:
        """Give the device with ``address`` node-ID ``node_id`` (and make it store it).
        A device that had none boots with it at once; one that had one takes it at its
        next reset communication."""
        _node_id(node_id)
        try:  # a select whose answer was lost may have switched the device all the same
            self.select(address)
            self.configure_node_id(node_id)
            if store:
                self.store()
        finally:
            self.switch_global("waiting")

    def assign(self, node_ids: Iterable[int]) -> dict[LssAddress, int]:
        """Fastscan devices without node-ID one by one and give each the next of
        ``node_ids``; ends when the IDs or the devices run out. Returns who got which."""
        ids = [_node_id(n) for n in node_ids]
        given: dict[LssAddress, int] = {}
        for node_id in ids:
            address = self.fastscan_one()
            if address is None:
                break
            try:
                self.configure_node_id(node_id)
            finally:
                self.switch_global("waiting")  # the device boots with its new ID
            given[address] = node_id
        return given
