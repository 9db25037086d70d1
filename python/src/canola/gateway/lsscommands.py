# SPDX-License-Identifier: Apache-2.0
"""The gateway's ``lss_*`` commands (CiA 309-3 over CiA 305) on its backend's LSS master.

Arguments and error codes follow CANopenNode's gateway, which ``cocomm`` scripts know:

- 101: wrong arguments (count or range: ``lss_set_node`` takes 0..127 or 255,
  ``lss_switch_glob`` 0|1, ``lss_inquire_addr`` 0..3, scan types 0..2, time-outs
  0..65535 ms where 0 is the default 100 ms);
- 102: the LSS master is not in the state for the command: like CANopenNode's, this one
  remembers what it switched to configuration (nothing, one device selected, or all);
  ``lss_set_node``, ``lss_store`` and the inquiries need a device in configuration
  (``lss_set_node`` in global configuration only 255), a scan needs all devices waiting;
  ``lss_set_node 0`` too;
- 103: no answer; 501: refused with a manufacturer-specific error (0xFF);
  502: node-ID refused; 504: store refused (the backend maps its master's answers);
- 100: what this gateway does not do (bit timing, identify, slowscan, scan types 1 and 2).

Requests run one at a time (one LSS master). A reply may have several lines
(``lss_allnodes``), joined with LF.
"""

from __future__ import annotations

import asyncio
from typing import Literal

from canola.gateway.backend import Backend, LssOp
from canola.gateway.codes import GatewayError, GatewayFailure
from canola.gateway.requests import Lss

__all__ = ["LSS_SCAN_TIMEOUT_MS", "LssCommands"]

#: Time-out (ms) per LSS answer of ``_lss_fastscan`` and ``lss_allnodes`` given as 0 or
#: not given.
LSS_SCAN_TIMEOUT_MS = 100

Mode = Literal["waiting", "selective", "global"]
_NOT_SUPPORTED = frozenset({"lss_identity", "lss_ident_nonconf", "_lss_slowscan"})


def _syntax(detail: str) -> GatewayFailure:
    return GatewayFailure(GatewayError.SYNTAX, detail)


def _state(detail: str) -> GatewayFailure:
    return GatewayFailure(GatewayError.INTERNAL_STATE, detail)


def _address(values: tuple[int, ...]) -> str:
    return " ".join(f"0x{v:08X}" for v in values)


def _scan_timeout(args: tuple[int, ...]) -> int:
    timeout = args[0] if args else 0
    if timeout > 0xFFFF:
        raise _syntax(f"LSS time-out {timeout} ms")
    return timeout or LSS_SCAN_TIMEOUT_MS


class LssCommands:
    """Runs :class:`~canola.gateway.requests.Lss` requests; remembers the master's mode."""

    def __init__(self, backend: Backend) -> None:
        self.backend = backend
        self.mode: Mode = "waiting"
        self._lock = asyncio.Lock()

    async def run(self, request: Lss) -> str:
        """The reply to ``request`` (raises GatewayFailure)."""
        if not self.backend.has_lss:
            raise GatewayFailure(GatewayError.REQUEST_NOT_SUPPORTED, "no LSS master")
        async with self._lock:
            return await self._run(request)

    def _need(self, *modes: Mode) -> None:
        if self.mode not in modes:
            raise _state(f"the LSS master is in {self.mode} (needs {' or '.join(modes)})")

    async def _op(self, op: LssOp, args: tuple[int, ...] = ()) -> tuple[int, ...]:
        return await self.backend.lss(op, args)

    async def _run(self, request: Lss) -> str:
        seq, args, command = request.seq, request.args, request.command
        ok = f"[{seq}] OK"

        def arity(*counts: int) -> None:
            if len(args) not in counts:
                raise _syntax(f"{command}: {len(args)} arguments")

        if command == "lss_switch_glob":
            arity(1)
            if args[0] > 1:
                raise _syntax("lss_switch_glob 0|1")
            self.mode = "waiting"  # what a failed switch leaves too
            await self._op("switch_global", args)
            self.mode = "global" if args[0] else "waiting"
            return ok
        if command == "lss_switch_sel":
            arity(4)
            self._need("waiting")
            await self._op("select", args)
            self.mode = "selective"
            return ok
        if command == "lss_set_node":
            arity(1)
            node = args[0]
            if 0x7F < node < 0xFF:
                raise _syntax(f"lss_set_node {node}: 0..127 or 255")
            if node == 0:
                raise _state("lss_set_node 0: no device takes node-ID 0")
            self._need("selective", *(("global",) if node == 0xFF else ()))
            await self._op("set_node", args)
            return ok
        if command == "lss_store":
            arity(0)
            self._need("selective")
            await self._op("store")
            return ok
        if command == "lss_inquire_addr":
            arity(0, 1)
            if args and args[0] > 3:
                raise _syntax("lss_inquire_addr 0..3")
            self._need("selective", "global")
            values = [(await self._op("inquire", (sub,)))[0] for sub in (args or (0, 1, 2, 3))]
            return f"[{seq}] {_address(tuple(values))}"
        if command == "lss_get_node":
            arity(0)
            self._need("selective", "global")
            (node,) = await self._op("inquire", (4,))
            return f"[{seq}] 0x{node & 0xFF:02X}"
        if command == "_lss_fastscan":
            arity(0, 1)
            timeout = _scan_timeout(args)
            self._need("waiting")
            found = await self._op("fastscan", (timeout,))
            if not found:
                raise GatewayFailure(GatewayError.TIMEOUT, "no device without node-ID")
            self.mode = "selective"
            return f"[{seq}] {_address(found)}"
        if command == "lss_allnodes":
            return await self._allnodes(request)
        if command == "lss_conf_bitrate":
            arity(2)
            if args[0] != 0 or args[1] > 9 or args[1] == 5:
                raise _syntax("lss_conf_bitrate 0 <0..4|6..9>")
        elif command == "lss_activate_bitrate":
            arity(1)
            if args[0] > 0xFFFF:
                raise _syntax("lss_activate_bitrate <0..65535 ms>")
        assert command in _NOT_SUPPORTED or command.endswith("bitrate"), command
        # bit timing: not exposed by the LSS master; identify and slowscan: not done here
        raise GatewayFailure(GatewayError.REQUEST_NOT_SUPPORTED, command)

    async def _allnodes(self, request: Lss) -> str:
        """Fastscan, configure the next node-ID (skipping the gateway's), store if asked,
        switch to waiting (the device boots); until no device without node-ID answers."""
        args = request.args
        if len(args) not in (0, 1, 3, 11):
            raise _syntax(f"lss_allnodes: {len(args)} arguments")
        timeout = _scan_timeout(args)
        node, store = (args[1], args[2]) if len(args) >= 3 else (1, 0)
        if not 1 <= node <= 127 or store > 1:
            raise _syntax("lss_allnodes: node 1..127, store 0|1")
        scan_types = args[3::2]
        if any(kind > 2 for kind in scan_types):
            raise _syntax("lss_allnodes: scan types 0..2")
        if any(scan_types):
            raise GatewayFailure(GatewayError.REQUEST_NOT_SUPPORTED, "scan types other than 0")
        self._need("waiting")
        lines: list[str] = []
        count = 0
        while True:
            if node == self.backend.node_id:
                node += 1
            if node > 127:
                lines.append("# Not all nodes scanned!")
                break
            found = await self._op("fastscan", (timeout,))
            if not found:
                lines.append(f"# Found {count} nodes, search finished.")
                break
            try:
                await self._op("set_node", (node,))
                if store:
                    await self._op("store")
            finally:
                self.mode = "waiting"
                await self._op("switch_global", (0,))
            lines.append(f"# Node-ID {node} assigned to: {_address(found)}")
            count += 1
            node += 1
        return "\n".join([*lines, f"[{request.seq}] OK"])
