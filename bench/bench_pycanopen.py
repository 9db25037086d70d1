#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""python-canopen's master (RemoteNode) and device (LocalNode) in one process on
python-can's virtual bus: expedited SDO uploads of 0x1000 sub 0 (a u32), back to back.
The anchor of canola's round-trip row (bench/bench_sdo_net.c expedited_rtt does the same
with two canola nodes). Prints one line of key=value pairs; wall-clock time, best of RUNS.

usage: bench_pycanopen.py [ROUND_TRIPS [RUNS]]
"""
import sys
import time

import can
import canopen
from canopen.objectdictionary import UNSIGNED32, ODVariable

DEVICE_TYPE = 0x00020192
SERVER_ID = 5


def dictionary() -> canopen.ObjectDictionary:
    od = canopen.ObjectDictionary()
    var = ODVariable("Device type", 0x1000, 0)
    var.data_type = UNSIGNED32
    var.access_type = "ro"
    var.default = DEVICE_TYPE
    od.add_object(var)
    return od


def main() -> int:
    round_trips = int(sys.argv[1]) if len(sys.argv) > 1 else 2000
    runs = int(sys.argv[2]) if len(sys.argv) > 2 else 3
    channel = "canola-bench"
    master_net = canopen.Network()
    device_net = canopen.Network()
    master_net.connect(interface="virtual", channel=channel, receive_own_messages=False)
    device_net.connect(interface="virtual", channel=channel, receive_own_messages=False)
    try:
        device_net.create_node(SERVER_ID, dictionary())  # the LocalNode answers
        remote = master_net.add_node(SERVER_ID, dictionary())
        best = None
        for _ in range(runs):
            t0 = time.perf_counter()
            for _ in range(round_trips):
                data = remote.sdo.upload(0x1000, 0)
                if int.from_bytes(data, "little") != DEVICE_TYPE:
                    print("bench_pycanopen: wrong value uploaded: no figure", file=sys.stderr)
                    return 1
            s = time.perf_counter() - t0
            best = s if best is None or s < best else best
    finally:
        master_net.disconnect()
        device_net.disconnect()
    print(f"round_trips={round_trips} runs={runs} best_ns={best * 1e9:.0f} "
          f"rate={round_trips / best:.1f} canopen={canopen.__version__} can={can.__version__}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
