# SPDX-License-Identifier: Apache-2.0
"""A CANopen device in a few lines: canola.Device on a python-can bus.

    python device_example.py                              # python-can virtual bus
    python device_example.py --interface socketcan --channel vcan0 --node 5

The device uses the interop EDS of the tests (every data type, 4 RPDOs, 4 TPDOs). It
counts in 0x2006 (UNSIGNED16, mapped into TPDO2) every 100 ms up to ``--count`` (30: about
3 s), reports what the network writes and its NMT state changes, and raises an EMCY when
the counter reaches 20. Any CANopen master can talk to it (candump shows its heartbeat
every 100 ms).
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import can

import canola

EDS = Path(__file__).resolve().parent.parent / "tests" / "data" / "interop.eds"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--interface", default="virtual")
    parser.add_argument("--channel", default="canola-example")
    parser.add_argument("--node", type=int, default=5)
    parser.add_argument("--count", type=int, default=30, help="count this far, 100 ms apart")
    args = parser.parse_args()

    with can.Bus(interface=args.interface, channel=args.channel) as bus, \
            canola.Device(EDS, args.node, bus) as dev:
        dev.on_state(lambda state: print(f"NMT state: {state}"))
        dev.on_write(lambda index, sub, value: print(f"written 0x{index:04X}:{sub} = {value!r}"))
        print(f"device {args.node} on {args.interface}:{args.channel}, "
              f"{dev.od[0x1008][0]!r}, state {dev.nmt_state}")
        dev.nmt_apply("start")  # a device on its own: start by itself
        for count in range(1, args.count + 1):  # by counts: a busy machine only slows it
            dev.od[0x2006][0] = count  # mapped into TPDO2: sent on change (operational)
            if count == 20:
                dev.emcy_raise(0xFF00, b"demo")
                print("EMCY 0xFF00 raised, error register", dev.od[0x1001][0])
            time.sleep(0.1)
        print(f"counted to {args.count}")


if __name__ == "__main__":
    main()
