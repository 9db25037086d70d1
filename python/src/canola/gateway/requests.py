# SPDX-License-Identifier: Apache-2.0
"""The typed requests of the CiA 309-3 ASCII gateway, as the line parser produces them.

Every request carries the client's sequence number (``seq``) and the network / node the
line named (``None``: the session's default, set with ``set network`` / ``set node``).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Literal

__all__ = [
    "Auth",
    "BootUpIndication",
    "DisableGuarding",
    "DisableHeartbeat",
    "EnableGuarding",
    "EnableHeartbeat",
    "Help",
    "InfoVersion",
    "Init",
    "Lss",
    "Nmt",
    "NmtCommand",
    "PdoRead",
    "PdoWrite",
    "Request",
    "SdoRead",
    "SdoWrite",
    "Set",
    "SetRpdo",
    "SetTpdo",
]

NmtCommand = Literal["start", "stop", "preop", "reset_node", "reset_comm"]


@dataclass(frozen=True)
class Request:
    seq: int
    net: int | None = None
    node: int | None = None


@dataclass(frozen=True)
class SdoRead(Request):
    """``r[ead] <index> <sub> [<type>]``: SDO upload; no type shows raw ``hex``."""

    index: int = 0
    sub: int = 0
    type: str | None = None


@dataclass(frozen=True)
class SdoWrite(Request):
    """``w[rite] <index> <sub> <type> <value>``: SDO download of ``data``."""

    index: int = 0
    sub: int = 0
    type: str = "hex"
    data: bytes = b""


@dataclass(frozen=True)
class Nmt(Request):
    """``start``, ``stop``, ``preop[erational]``, ``reset node``, ``reset comm[unication]``."""

    command: NmtCommand = "start"


@dataclass(frozen=True)
class Set(Request):
    """``set network|node|sdo_timeout|sdo_block|heartbeat|id|command_timeout|command_size|
    events <value>``."""

    what: str = ""
    value: int = 0


@dataclass(frozen=True)
class SetRpdo(Request):
    """``set rpdo <num> <cob-id> <trans> <n> [<index> <sub>] <type> ...``."""

    num: int = 1
    cob_id: int = 0
    transmission: int = 0xFF
    mapping: tuple[int, ...] = field(default=())


@dataclass(frozen=True)
class SetTpdo(Request):
    """``set tpdo[x] <num> <cob-id> <trans> [<inhibit>] [<event>|<sync>] <n> <map>...``."""

    num: int = 1
    cob_id: int = 0
    transmission: int = 0xFF
    inhibit: int = 0
    event: int = 0
    sync: int = 0
    mapping: tuple[int, ...] = field(default=())


@dataclass(frozen=True)
class PdoRead(Request):
    """``r[ead] p[do] <num>``: the values mapped to the gateway's RPDO ``num``."""

    num: int = 1


@dataclass(frozen=True)
class PdoWrite(Request):
    """``w[rite] p[do] <num> <n> <value>...``: set the values mapped to TPDO ``num``."""

    num: int = 1
    values: tuple[int, ...] = field(default=())


@dataclass(frozen=True)
class EnableHeartbeat(Request):
    """``enable heartbeat <ms>``: watch the node's heartbeat (consumer time ``ms``)."""

    ms: int = 0


@dataclass(frozen=True)
class DisableHeartbeat(Request):
    """``disable heartbeat``."""


@dataclass(frozen=True)
class EnableGuarding(Request):
    """``enable guarding <guard time ms> <life time factor>``."""

    guard_ms: int = 0
    factor: int = 0


@dataclass(frozen=True)
class DisableGuarding(Request):
    """``disable guarding``."""


@dataclass(frozen=True)
class Init(Request):
    """``init <bit timing index 0..9>``."""

    bit_timing: int = 0


@dataclass(frozen=True)
class BootUpIndication(Request):
    """``boot_up_indication Enable|Disable``: boot-up events to this client."""

    enable: bool = True


@dataclass(frozen=True)
class Auth(Request):
    """``auth <token>``: the client proves it may use the gateway (canola's, not CiA
    309-3: docs/security.md); answered by the connection, never executed."""

    token: str = field(default="", repr=False)


@dataclass(frozen=True)
class InfoVersion(Request):
    """``info version``."""


@dataclass(frozen=True)
class Help(Request):
    """``help [datatype|lss]``."""

    topic: str = ""


@dataclass(frozen=True)
class Lss(Request):
    """One of the ``lss_*`` commands (and ``_lss_fastscan``) with its raw arguments."""

    command: str = ""
    args: tuple[int, ...] = field(default=())
