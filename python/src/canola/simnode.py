# SPDX-License-Identifier: Apache-2.0
"""A bare node on a :class:`canola.core.SimBus`, for tests and tools that work in virtual
time: the node's own entries as the network would access them (access rights apply), NMT
master commands, and an SDO client (channel 0) that runs the bus until the transfer is
done. One of the node classes of :class:`canola._nodebase.NodeBase` (with
:class:`canola.Device` and :class:`canola.Master`): its callbacks are theirs.
"""

from __future__ import annotations

from typing import Literal

from canola._c import CData, check, ffi, lib
from canola._channels import Transfer
from canola._nodebase import NodeBase
from canola.core import NMT_CMDS, NMT_STATES, Od, SimBus
from canola.errors import Error, SdoAbort

__all__ = ["Node", "SdoMode"]

SdoMode = Literal["auto", "expedited", "segmented", "block"]

_MODES: dict[str, int] = {
    "auto": lib.CO_SDO_AUTO,
    "expedited": lib.CO_SDO_EXPEDITED,
    "segmented": lib.CO_SDO_SEGMENTED,
    "block": lib.CO_SDO_BLOCK,
}


class Node(NodeBase):
    """A canola node on ``bus`` with dictionary ``od`` (kept alive with the bus).

    ``node_id`` defaults to the dictionary's (a DCF's NodeID). Call :meth:`start` to power
    it on (boot-up frame, pre-operational).
    """

    _kind = "node"

    def __init__(self, bus: SimBus, od: Od, node_id: int | None = None) -> None:
        nid = node_id if node_id is not None else od.node_id
        if nid is None:
            raise Error("no node-ID: pass node_id")
        if not isinstance(bus, SimBus):
            raise Error(f"a canola.core.Node runs on a SimBus, not {type(bus).__name__}")
        super().__init__(bus, od, nid, sdo_timeout_ms=1000, store_dir=None, raw_frames=False)
        self.sim_bus = bus
        self._server: int | None = None

    @property
    def _node(self) -> CData:
        return self._c_node

    def _on_state(self, state: int) -> None:
        self.node_id = int(lib.co_node_id(self._node))  # an LSS master may have set it
        super()._on_state(state)

    @property
    def state(self) -> int:
        """The NMT state (0 initialising, 4 stopped, 5 operational, 0x7F pre-operational)."""
        return int(lib.co_nmt_state(self._node))

    @property
    def state_name(self) -> str:
        return NMT_STATES.get(self.state, "unknown")

    # ---- local access, as the network would do it

    def read(self, index: int, sub: int, cap: int = 4096) -> bytes:
        """Read an entry's wire value (access rights apply). Raises SdoAbort."""
        buf = ffi.new("uint8_t[]", cap)
        n = ffi.new("uint32_t *")
        with self.locked() as node:
            code = int(lib.co_node_read_net(node, index, sub, buf, cap, n))
        if code:
            raise SdoAbort(code)
        return bytes(ffi.buffer(buf, int(n[0])))

    def write(self, index: int, sub: int, data: bytes) -> None:
        """Write an entry's wire value (access rights, length, limits). Raises SdoAbort."""
        with self.locked() as node:
            code = int(lib.co_node_write_net(node, index, sub, data, len(data)))
        if code:
            raise SdoAbort(code)

    def get_uint(self, index: int, sub: int) -> int:
        """The native value of an integer entry (application access)."""
        out = ffi.new("uint64_t *")
        check(lib.co_node_get_uint(self._node, index, sub, out), "co_node_get_uint")
        return int(out[0])

    def set_uint(self, index: int, sub: int, value: int) -> None:
        """Application write of an integer entry (no access rights). Raises SdoAbort."""
        with self.locked() as node:
            code = int(lib.co_node_set_uint(node, index, sub, value))
        if code:
            raise SdoAbort(code)

    # ---- NMT master

    def nmt(self, cmd: str | int, target: int = 0) -> None:
        """Send an NMT command (``"start"``, ``"stop"``, ``"pre-operational"``,
        ``"reset-node"``, ``"reset-communication"`` or the specifier) to ``target``
        (0: all nodes) and let the bus deliver it."""
        spec = NMT_CMDS[cmd] if isinstance(cmd, str) else cmd
        with self.locked() as node:
            check(lib.co_nmt_send(node, spec, target), "co_nmt_send")

    # ---- SDO client (channel 0)

    def _setup(self, server_id: int) -> None:
        if self._server != server_id:
            check(lib.co_sdo_client_setup(self._node, 0, server_id), "co_sdo_client_setup")
            self._server = server_id

    def _wait(self, t: Transfer, timeout_us: int, what: str) -> None:
        bus = self.sim_bus
        deadline = bus.now_us + timeout_us
        while not t.done and bus.now_us < deadline:
            bus.run_until(min(bus.now_us + 1000, deadline))
        if not t.done:
            lib.co_sdo_client_abort(self._node, 0, 0x05040000)
            raise Error(f"{what}: no completion within {timeout_us} us of simulated time")
        if t.abort:
            raise SdoAbort(t.abort)

    def sdo_upload(self, server_id: int, index: int, sub: int, mode: SdoMode = "auto", *,
                   cap: int = 4096, timeout_us: int = 10_000_000) -> bytes:
        """Read (index, sub) of node ``server_id`` over SDO; runs the bus until done.

        Raises SdoAbort on an abort, Error when the transfer does not end within
        ``timeout_us`` of simulated time.
        """
        self._setup(server_id)
        buf = ffi.new("uint8_t[]", cap)
        t = Transfer()
        handle = ffi.new_handle(t)
        with self.locked() as node:
            err = lib.co_sdo_upload(node, 0, index, sub, _MODES[mode], buf, cap,
                                    lib.canola_py_sdo_done, handle)
        check(err, "co_sdo_upload")
        self._wait(t, timeout_us, f"SDO upload 0x{index:04X} sub {sub} of node {server_id}")
        return bytes(ffi.buffer(buf, t.length))

    def sdo_download(self, server_id: int, index: int, sub: int, data: bytes,
                     mode: SdoMode = "auto", *, timeout_us: int = 10_000_000) -> None:
        """Write ``data`` to (index, sub) of node ``server_id`` over SDO; runs the bus
        until done. Raises as :meth:`sdo_upload`."""
        self._setup(server_id)
        src = ffi.new("uint8_t[]", data)
        t = Transfer()
        handle = ffi.new_handle(t)
        with self.locked() as node:
            err = lib.co_sdo_download(node, 0, index, sub, _MODES[mode], src, len(data),
                                      lib.canola_py_sdo_done, handle)
        check(err, "co_sdo_download")
        self._wait(t, timeout_us, f"SDO download 0x{index:04X} sub {sub} of node {server_id}")
