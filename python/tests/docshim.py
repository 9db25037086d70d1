# SPDX-License-Identifier: Apache-2.0
"""Runs one python block of the manual as a program (``python docshim.py BLOCK.py``), as
docsession.py promises: a python-can bus the block opens on a real interface is
python-can's virtual bus of the same channel (in this process: the block's nodes on one
channel hear each other), so an example written for ``can0`` runs on any machine."""

from __future__ import annotations

import runpy
import sys
from typing import Any

import can

#: python-can interfaces that need hardware or a kernel this machine may lack.
REAL = {"socketcan", "pcan", "kvaser", "vector", "ixxat", "slcan", "gs_usb", "nican",
        "seeedstudio", "serial", "usb2can", "canalystii", "systec", "etas"}

_Bus = can.Bus


def _virtual_instead(*args: Any, **kwargs: Any) -> can.BusABC:
    if kwargs.get("interface") in REAL:
        kwargs["interface"] = "virtual"
    return _Bus(*args, **kwargs)


can.Bus = can.interface.Bus = _virtual_instead

if __name__ == "__main__":
    script = sys.argv[1]
    sys.argv = sys.argv[1:]
    runpy.run_path(script, run_name="__main__")
