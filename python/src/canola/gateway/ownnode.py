# SPDX-License-Identifier: Apache-2.0
"""The gateway's own node in the network: what its NMT state means for its clients.

The gateway is a node (its master's node-ID) and follows NMT like any node: a command to
its node-ID or to all (node-ID 0) applies to it, whether a client of the gateway or
another node on the bus sent it (CiA 301 §7.2.8.3.1). As the network's NMT master it
switches itself into OPERATIONAL after every boot-up (power-on, reset node, reset
communication) unless bit 2 of its 0x1F80 (NMT start-up, CiA 302-2) is set; its
dictionary without 0x1F80 (the built-in one) counts as bit 2 clear, as CANopenNode's
canopend does.

What its state gates (CiA 301 §7.3.2.2, the NMT states and the communication objects
each allows): SDO runs in PRE-OPERATIONAL and OPERATIONAL only, for every device involved
in the transfer, its client as much as its server. So while the gateway's node is STOPPED
(or initialising during a reset) its SDO client sends nothing: the executor answers SDO
requests to other nodes ``ERROR:204`` (wrong NMT state, naming the state) and a transfer
that the node's stop or reset cut off likewise, never an abort code that would blame the
device. Everything else goes on: NMT commands (the way to start the gateway again), LSS,
heartbeat and EMCY events, and its own dictionary (no frame on the bus).

:class:`OwnNode` watches the state (the master's state callbacks, which run after the
change, outside the master's lock) and counts how often SDO was closed, so a transfer that
ended with abort 0x08000022 can tell the gateway's stop from the device's refusal.
"""

from __future__ import annotations

import logging
from collections.abc import Callable

from canola.errors import Error
from canola.master import Master

__all__ = ["NO_SELF_START", "SDO_STATES", "OwnNode"]

#: 0x1F80 bit 2: the NMT master does not enter OPERATIONAL by itself (CiA 302-2).
NO_SELF_START = 0x04
#: The NMT states in which a node may take part in SDO transfers (CiA 301).
SDO_STATES = frozenset({"PRE-OPERATIONAL", "OPERATIONAL"})

log = logging.getLogger("canola.gateway")


def self_starts(master: Master) -> bool:
    """Whether ``master`` enters OPERATIONAL by itself after its boot-up: bit 2 of its
    0x1F80 clear, or no 0x1F80 at all."""
    try:
        startup = master.od.get(0x1F80, 0)
    except Error:
        return True
    return not (isinstance(startup, int) and startup & NO_SELF_START)


class OwnNode:
    """The state of the gateway's node. ``start`` applies NMT start to it (under its lock);
    ``self_start`` None reads 0x1F80 (:func:`self_starts`)."""

    def __init__(self, master: Master, start: Callable[[], None], *,
                 self_start: bool | None = None) -> None:
        self._master = master
        self._start = start
        self.self_start = self_starts(master) if self_start is None else self_start
        #: How often the node entered a state without SDO (STOPPED, or INITIALISING).
        self.sdo_closings = 0
        self._last = master.nmt_state
        master.on_state(self._changed)
        if self.self_start and self._last == "PRE-OPERATIONAL":
            self._start()  # its power-on boot-up came before the gateway was there

    @property
    def state(self) -> str:
        """INITIALISING, PRE-OPERATIONAL, OPERATIONAL or STOPPED, now."""
        return self._master.nmt_state

    def _changed(self, state: str) -> None:
        last, self._last = self._last, state
        if state not in SDO_STATES:
            self.sdo_closings += 1
        if state != last:
            log.info("the gateway's node (%d) is %s", self._master.node_id, state)
        if state == "PRE-OPERATIONAL" and last == "INITIALISING" and self.self_start \
                and self.state == "PRE-OPERATIONAL":  # not moved on meanwhile
            self._start()
