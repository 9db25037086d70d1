# SPDX-License-Identifier: Apache-2.0
"""canola.Device: a CANopen device run by the C core, on a python-can bus or a SimBus.

    import can, canola
    bus = can.Bus(interface="socketcan", channel="can0")
    with canola.Device("drive.eds", 5, bus, store_dir="/var/lib/drive") as dev:
        dev.od[0x6000][1] = 42            # typed per the EDS; mapped -> event-driven TPDO
        dev.on_write(lambda index, sub, value: print(hex(index), sub, value))
        dev.emcy_raise(0x4210, b"\\x01")   # temperature

On a python-can bus a background thread receives frames and runs the node's timers (see
:mod:`canola._engine` for threading); on a :class:`canola.core.SimBus` the simulated bus
runs it in virtual time, deterministically: advance it with ``bus.run_for(us)``.
"""

from __future__ import annotations

import logging
import os

from canola._c import check, ffi, lib
from canola._engine import Bus
from canola._nodebase import NodeBase, StoreRejectedEvent, load_od, nmt_command
from canola.errors import Error
from canola.formats import eds
from canola.formats.odgen import GenerateOptions

__all__ = ["Device", "StoreRejectedEvent"]

log = logging.getLogger("canola.device")


def _stored_node_id(store_dir: str, node_id: int) -> int:
    """The node-ID an LSS store configuration left in ``store_dir``, else ``node_id``; a
    damaged lss.params is said (and ``node_id`` used)."""
    stored = ffi.new("uint8_t *")
    err = int(lib.canola_py_stored_node_id(store_dir.encode(), stored))
    path = os.path.join(store_dir, "lss.params")
    if err == lib.CO_OK:
        if stored[0] != node_id:
            log.warning("device: node-ID %d, stored by LSS in %s (not %d)", stored[0], path,
                        node_id)
        return int(stored[0])
    if err == lib.CO_ERR_STATE:
        log.warning("device: %s: damaged (not a line of canola-lss 1): ignored, node-ID %d",
                    path, node_id)
    return node_id


class Device(NodeBase):
    """A device with the dictionary of ``eds_or_dcf`` (a path or a parsed
    :class:`canola.formats.eds.ObjectDictionary`) as node ``node_id`` on ``bus``.

    ``store_dir``: a folder where 0x1010 "save" stores parameters (files comm.params and
    app.params, written atomically); they are loaded at every reset. An LSS store
    configuration (CiA 305) keeps the node-ID the LSS master configured there too
    (lss.params): it wins over ``node_id`` from then on, at every reset node and start.
    ``string_size`` is the room of each VISIBLE/OCTET/UNICODE_STRING entry (at least its
    default's length) and ``domain_size`` that of each DOMAIN: the largest value an SDO
    download (expedited, segmented or block) writes into it, whatever the SDO server's
    buffer (4 KiB here).
    ``sdo_timeout_ms``: the SDO server's time-out.
    Call :meth:`start` (or use ``with``) to power it on.
    """

    _kind = "device"

    def __init__(self, eds_or_dcf: str | os.PathLike[str] | eds.ObjectDictionary,
                 node_id: int, bus: Bus, *, store_dir: str | os.PathLike[str] | None = None,
                 string_size: int = 256, domain_size: int = 4096,
                 sdo_timeout_ms: int = 1000) -> None:
        if not isinstance(node_id, int) or not (1 <= node_id <= 127 or node_id == 0xFF):
            raise Error(f"node-ID {node_id!r} is outside 1..127 (or 0xFF: none, for LSS)")
        if not isinstance(eds_or_dcf, eds.ObjectDictionary):
            self._source = os.fspath(eds_or_dcf)
        if store_dir is not None:
            node_id = _stored_node_id(os.fspath(store_dir), node_id)
        od = load_od(eds_or_dcf, node_id, GenerateOptions(domain_size=domain_size,
                                                          min_string_size=string_size))
        super().__init__(bus, od, node_id, sdo_timeout_ms=sdo_timeout_ms,
                         store_dir=store_dir, raw_frames=False)

    def __enter__(self) -> Device:
        self.start()
        return self

    def _on_state(self, state: int) -> None:
        # an LSS master may have given the node its (new) node-ID at this reset
        self.node_id = int(lib.co_node_id(self._c_node))
        super()._on_state(state)

    def emcy_raise(self, code: int, manufacturer: bytes = b"") -> None:
        """Raise error ``code`` (1..0xFFFF): EMCY frame, 0x1001 and 0x1003 updated.
        ``manufacturer``: up to 5 bytes (zero-padded)."""
        if not isinstance(code, int) or not 1 <= code <= 0xFFFF:
            raise Error(f"EMCY error code {code!r} is outside 0x0001..0xFFFF")
        if len(manufacturer) > 5:
            raise Error(f"EMCY manufacturer data has at most 5 bytes, got {len(manufacturer)}")
        data = bytes(manufacturer).ljust(5, b"\0")
        with self.locked() as node:
            err = int(lib.co_emcy_raise(node, code, data))
        if err not in (lib.CO_OK, lib.CO_ERR_FULL):
            check(err, "co_emcy_raise")

    def emcy_clear(self, code: int) -> None:
        """Clear error ``code``; the last one clearing sends the error-reset EMCY (0x0000).
        Raises Error when the code was not active."""
        with self.locked() as node:
            err = int(lib.co_emcy_clear(node, code))
        if err == lib.CO_ERR_NOT_FOUND:
            raise Error(f"EMCY error code 0x{code:04X} is not active")
        check(err, "co_emcy_clear")

    def emcy_active(self, code: int) -> bool:
        with self.locked() as node:
            return bool(lib.co_emcy_active(node, code))

    def nmt_apply(self, command: str | int) -> None:
        """Apply an NMT command to this device itself (as if received)."""
        spec = nmt_command(command)
        with self.locked() as node:
            check(int(lib.co_nmt_apply(node, spec)), "co_nmt_apply")

    def tpdo_request(self, n: int) -> None:
        """Send TPDO ``n`` (0-based) now if it is event-driven (or at the next SYNC if
        acyclic). Raises Error when the PDO does not exist, is not valid or the device is
        not operational."""
        with self.locked() as node:
            check(int(lib.co_tpdo_request(node, n)), f"TPDO {n + 1}")
