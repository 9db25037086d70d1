# SPDX-License-Identifier: Apache-2.0
"""How a run behaves: :class:`Options` (light: the command line reads its defaults without
loading the suite)."""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["Options"]


@dataclass(frozen=True)
class Options:
    """How a run behaves. Times in seconds (virtual on a SimBus).

    ``timeout``: how long an answer may take (SDO, a heartbeat, a PDO after its SYNC).
    ``boot_timeout``: how long a reset may take until the boot-up frame.
    ``server_timeout``: how long the server may keep a half-done SDO transfer open before
    its own time-out aborts it. ``quiet``: how long "no frame comes" is watched.
    ``tolerance``: the share a measured period may differ from the configured one.
    ``destructive``: run the checks that save or restore stored parameters.
    ``transfer_timeout``: how long one SDO transfer of the tester may take in all (a
    server that keeps it going longer is stopped).
    """

    timeout: float = 2.0
    boot_timeout: float = 5.0
    server_timeout: float = 5.0
    quiet: float = 0.5
    tolerance: float = 0.25
    destructive: bool = False
    transfer_timeout: float = 60.0
