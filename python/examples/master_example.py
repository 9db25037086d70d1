# SPDX-License-Identifier: Apache-2.0
"""A CANopen master in a few lines: canola.Master with two canola.Devices.

    python master_example.py          # everything on canola's simulated bus, virtual time

On the simulated bus time only moves when the program says so, so this runs in an instant
and prints the same every time. To drive real devices instead, give the Master a
python-can bus (``can.Bus(interface="socketcan", channel="can0")``): the calls are the same.
"""

from __future__ import annotations

from pathlib import Path

import canola
from canola.core import SimBus

EDS = Path(__file__).resolve().parent.parent / "tests" / "data" / "interop.eds"


def main() -> None:
    bus = SimBus(bitrate=500_000)  # with a timing model of a 500 kbit/s bus
    master = canola.Master(bus, node_id=1)
    devices = [canola.Device(EDS, n, bus) for n in (5, 6)]
    master.on_bootup(lambda node: print(f"boot-up of node {node}"))
    master.on_heartbeat(lambda e: print(f"heartbeat: node {e.node} {e.kind} {e.state}"))
    master.on_emcy(lambda e: print(f"EMCY from node {e.node}: 0x{e.code:04X} "
                                   f"register 0x{e.register:02X}"))
    tpdos: list[canola.master.Frame] = []
    master.on_frame(tpdos.append, cob_id=0x285)  # TPDO2 of node 5
    master.start()
    for dev in devices:
        dev.start()
        master.monitor(dev.node_id, 250)
    master.wait(0.2)

    for node in (5, 6):  # configure by SDO
        sdo = master.sdo(node)
        name, vendor = sdo.read(0x1008, 0, "vs"), sdo.read(0x1018, 1, "u32")
        print(f"node {node}: {name!r}, vendor 0x{vendor:X}")
        sdo.write(0x1800 + 1, 5, "u16", 50)  # TPDO2 event timer 50 ms
    master.nmt(0, "start")
    devices[0].od[0x2006][0] = 0x1234  # the application of node 5 changes a mapped value
    master.wait(0.12)

    master.sdo(5).download(0x200F, 0, bytes(range(100)) * 10, block=True)  # 1000 bytes
    print("block download of 1000 bytes done; read back:",
          len(master.sdo(5).upload(0x200F, 0, block=True)), "bytes")
    devices[1].emcy_raise(0x4210)
    devices[1].od[0x1017][0] = 0  # node 6 falls silent
    master.wait(0.5)
    try:
        master.sdo(5).upload(0x5555, 0)
    except canola.SdoAbort as exc:
        print(f"abort 0x{exc.code:08X}: {exc.text}")
    print(f"{len(tpdos)} TPDO2 frames of node 5, the last {tpdos[-1].data.hex()}")
    print(f"bus load {bus.load:.1%}, {len(bus.trace)} frames in {bus.now_us / 1e6:.2f} s")


if __name__ == "__main__":
    main()
