#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""canola from Python against python-canopen, like for like: both stacks in one process on
python-can's virtual bus with the same EDS (bench/ds301_objects.eds). Prints one line of
key=value pairs (bench/run turns them into rows). Wall-clock figures are the best of RUNS;
the contenders' runs are interleaved so that a busy machine hurts them alike.

usage: bench_python.py same_bus ROUND_TRIPS RUNS
    Expedited SDO uploads of 0x1018 sub 1, back to back, from a master to a device:
    canola.Master + canola.Device on one python-can bus object (``canola_*``), the same two
    on two bus objects of one channel (``canola2_*``), python-canopen's RemoteNode +
    LocalNode on two Networks of one channel (``pycanopen_*``, its way of joining them).
    Per contender: round trips/s, CPU time per round trip (the process's, all threads),
    the threads the nodes add, and the lock acquisitions per round trip that Python's
    profiler sees (counted by their releases, those inside threading.Event and queue.Queue
    included, every thread; in a separate, untimed run).
usage: bench_python.py block BYTES RUNS
    An SDO block upload and a block download of BYTES between canola.Master and
    canola.Device on one python-can bus object: bytes per second of each, best of RUNS.
usage: bench_python.py segments SEGMENTS RUNS
    How fast a canola.Device answers each segment of a segmented SDO upload (a DOMAIN of
    7 x SEGMENTS bytes) to a plain python-can client on another bus object of the channel,
    idle and beside 4 CPU-bound processes: median, 99th percentile and longest time from a
    segment request sent to its answer received, over RUNS uploads.
usage: bench_python.py device_frames FRAMES RUNS
    A canola.Device on a python-can virtual bus receives FRAMES RPDOs sent by a plain
    python-can bus object of the same channel, as fast as they come, each applied to its
    dictionary: frames per second from the first send until the device applied the last.
"""
from __future__ import annotations

import os
import sys
import tempfile
import threading
import time
from collections.abc import Callable
from typing import Any

import can

EDS = os.path.join(os.path.dirname(os.path.abspath(__file__)), "ds301_objects.eds")
SERVER_ID = 5
INDEX, SUB = 0x1018, 1
EXPECTED = 0  # 0x1018 sub 1's default in EDS


def virtual(channel: str) -> can.BusABC:
    return can.Bus(interface="virtual", channel=channel, receive_own_messages=False)


class Contender:
    """Nodes set up once; ``upload()`` does one round trip; ``close()`` ends them."""

    def __init__(self, name: str, make: Callable[[], tuple[Callable[[], int], Callable[[], None]]]):
        self.name = name
        before = threading.active_count()
        self.upload, self.close = make()
        self.threads = threading.active_count() - before
        self.best: float | None = None
        self.cpu: float | None = None

    def run(self, round_trips: int) -> None:
        upload = self.upload
        c0, t0 = time.process_time(), time.perf_counter()
        for _ in range(round_trips):
            if upload() != EXPECTED:
                raise SystemExit(f"bench_python: {self.name} uploaded a wrong value")
        wall, cpu = time.perf_counter() - t0, time.process_time() - c0
        if self.best is None or wall < self.best:
            self.best, self.cpu = wall, cpu


def canola_pair(shared: bool, channel: str) -> tuple[Callable[[], int], Callable[[], None]]:
    import canola  # noqa: PLC0415

    buses = [virtual(channel)] if shared else [virtual(channel), virtual(channel)]
    device = canola.Device(EDS, SERVER_ID, buses[-1])
    master = canola.Master(buses[0], announce=False)
    device.start()
    master.start()
    client = master.sdo(SERVER_ID)

    def upload() -> int:
        return int.from_bytes(client.upload(INDEX, SUB), "little")

    def close() -> None:
        master.stop()
        device.stop()
        for bus in buses:
            bus.shutdown()
    return upload, close


def pycanopen_pair(channel: str) -> tuple[Callable[[], int], Callable[[], None]]:
    import canopen  # noqa: PLC0415

    master_net, device_net = canopen.Network(), canopen.Network()
    master_net.connect(interface="virtual", channel=channel, receive_own_messages=False)
    device_net.connect(interface="virtual", channel=channel, receive_own_messages=False)
    device_net.create_node(SERVER_ID, EDS)  # the LocalNode answers
    remote = master_net.add_node(SERVER_ID, EDS)
    remote.sdo.RESPONSE_TIMEOUT = 10.0  # a starved machine: no time-outs (not the speed)

    def upload() -> int:
        return int.from_bytes(remote.sdo.upload(INDEX, SUB), "little")

    def close() -> None:
        master_net.disconnect()
        device_net.disconnect()
    return upload, close


MAKERS: dict[str, Callable[[], tuple[Callable[[], int], Callable[[], None]]]] = {
    "canola": lambda: canola_pair(True, "bench-canola"),
    "canola2": lambda: canola_pair(False, "bench-canola2"),
    "pycanopen": lambda: pycanopen_pair("bench-pycanopen"),
}


def count_locks(make: Callable[[], tuple[Callable[[], int], Callable[[], None]]],
                round_trips: int) -> float:
    """Lock acquisitions per round trip as the profiler sees them, in every thread: their
    releases (lock.release, lock.__exit__), as a ``with`` block's acquisition is not a
    call the profiler reports but its release is."""
    counts = [0]
    names = {"release", "__exit__"}

    def prof(frame: Any, event: str, arg: Any) -> None:
        if event == "c_call" and getattr(arg, "__name__", "") in names and \
                type(getattr(arg, "__self__", None)).__name__ in ("lock", "RLock"):
            counts[0] += 1

    threading.setprofile(prof)  # threads the nodes start from here on
    try:
        upload, close = make()
        upload()  # first use: channel set-up, imports
        sys.setprofile(prof)
        start = counts[0]
        for _ in range(round_trips):
            upload()
        sys.setprofile(None)
        n = counts[0] - start
        close()
    finally:
        threading.setprofile(None)  # type: ignore[arg-type]
        sys.setprofile(None)
    return n / round_trips


def same_bus(round_trips: int, runs: int) -> None:
    contenders = [Contender(name, make) for name, make in MAKERS.items()]
    failed = []
    try:
        for c in list(contenders):
            try:
                c.run(max(1, round_trips // 10))  # warm up: not a figure
                c.best = c.cpu = None
            except Exception as exc:  # a contender that cannot do it gets no figures
                print(f"bench_python: {c.name} fails: {exc}", file=sys.stderr)
                contenders.remove(c)
                failed.append(c)
        for _ in range(runs):
            for c in contenders:
                c.run(round_trips)
    finally:
        for c in contenders + failed:
            c.close()
    locks = {c.name: count_locks(MAKERS[c.name], min(round_trips, 500)) for c in contenders}
    out = [f"round_trips={round_trips}", f"runs={runs}"]
    out += [f"{c.name}_rate=fails" for c in failed]
    for c in contenders:
        assert c.best is not None and c.cpu is not None
        out += [f"{c.name}_rate={round_trips / c.best:.1f}",
                f"{c.name}_cpu_us={c.cpu / round_trips * 1e6:.1f}",
                f"{c.name}_threads={c.threads}", f"{c.name}_locks={locks[c.name]:.1f}"]
    import canopen  # noqa: PLC0415
    out += [f"canopen={canopen.__version__}", f"can={can.__version__}"]
    print(" ".join(out))


# Two objects of the bench's own beside the EDS's: a DOMAIN to move blocks through and a
# u32 an RPDO maps.
EXTRA_OBJECTS = """
[2000]
ParameterName=Block data
ObjectType=0x7
DataType=0x000F
AccessType=rw
PDOMapping=0

[2001]
ParameterName=Process value
ObjectType=0x7
DataType=0x0007
AccessType=rw
DefaultValue=0
PDOMapping=1
"""


def bench_eds(folder: str) -> str:
    """bench/ds301_objects.eds with EXTRA_OBJECTS, written into ``folder``."""
    with open(EDS) as f:
        text = f.read()
    text = text.replace("[ManufacturerObjects]\nSupportedObjects=0",
                        "[ManufacturerObjects]\nSupportedObjects=2\n1=0x2000\n2=0x2001")
    path = os.path.join(folder, "bench.eds")
    with open(path, "w") as f:
        f.write(text + EXTRA_OBJECTS)
    return path


def block(size: int, runs: int) -> None:
    import canola  # noqa: PLC0415

    data = bytes(i * 7 % 251 for i in range(size))
    best = {"down": float("inf"), "up": float("inf")}
    with tempfile.TemporaryDirectory() as tmp:
        bus = virtual("bench-block")
        device = canola.Device(bench_eds(tmp), SERVER_ID, bus, domain_size=size)
        master = canola.Master(bus, announce=False)
        device.start()
        master.start()
        client = master.sdo(SERVER_ID)
        try:
            for _ in range(runs):
                t0 = time.perf_counter()
                client.download(0x2000, 0, data, block=True, timeout=600)
                best["down"] = min(best["down"], time.perf_counter() - t0)
                t0 = time.perf_counter()
                back = client.upload(0x2000, 0, block=True, max_size=size, timeout=600)
                best["up"] = min(best["up"], time.perf_counter() - t0)
                if back != data:
                    raise SystemExit("bench_python: the block upload differs from the download")
        finally:
            master.stop()
            device.stop()
            bus.shutdown()
    print(f"bytes={size} runs={runs} download_Bps={size / best['down']:.0f} "
          f"upload_Bps={size / best['up']:.0f}")


def _segment_times(client: can.BusABC, segments: int) -> list[float]:
    """One segmented upload of 0x2000 by hand: the time each segment took to answer."""
    def answer() -> bytes:
        end = time.monotonic() + 30.0
        while time.monotonic() < end:
            msg = client.recv(1.0)
            if msg is not None and msg.arbitration_id == 0x580 + SERVER_ID:
                return bytes(msg.data)
        raise SystemExit("bench_python: the device did not answer within 30 s")

    request = can.Message(arbitration_id=0x600 + SERVER_ID, is_extended_id=False,
                          data=bytes([0x40, 0x00, 0x20, 0, 0, 0, 0, 0]))
    client.send(request)
    if answer()[0] & 0xE0 != 0x40:
        raise SystemExit("bench_python: the upload did not start")
    times = []
    for i in range(segments):
        t0 = time.perf_counter()
        client.send(can.Message(arbitration_id=0x600 + SERVER_ID, is_extended_id=False,
                                data=bytes([0x60 | (i & 1) << 4]) + bytes(7)))
        if answer()[0] & 0xE0:
            raise SystemExit("bench_python: a segment was refused")
        times.append(time.perf_counter() - t0)
    return times


def segments(count: int, runs: int) -> None:
    import subprocess  # noqa: PLC0415

    import canola  # noqa: PLC0415

    out = [f"segments={count}", f"runs={runs}"]
    with tempfile.TemporaryDirectory() as tmp:
        bus, client = virtual("bench-segments"), virtual("bench-segments")
        device = canola.Device(bench_eds(tmp), SERVER_ID, bus, domain_size=7 * count)
        device.start()
        device.od.write(0x2000, 0, bytes(7 * count))
        try:
            for load in ("idle", "load"):
                burners = [subprocess.Popen([sys.executable, "-c", "while True: pass"])
                           for _ in range(4 if load == "load" else 0)]
                try:
                    times = sorted(t for _ in range(runs) for t in _segment_times(client, count))
                finally:
                    for p in burners:
                        p.kill()
                        p.wait(10)
                out += [f"{load}_median_us={times[len(times) // 2] * 1e6:.0f}",
                        f"{load}_p99_us={times[int(len(times) * 0.99)] * 1e6:.0f}",
                        f"{load}_max_us={times[-1] * 1e6:.0f}"]
        finally:
            device.stop()
            bus.shutdown()
            client.shutdown()
    print(" ".join(out))


def device_frames(frames: int, runs: int) -> None:
    import canola  # noqa: PLC0415

    best = float("inf")
    with tempfile.TemporaryDirectory() as tmp:
        bus, sender = virtual("bench-frames"), virtual("bench-frames")
        device = canola.Device(bench_eds(tmp), SERVER_ID, bus)
        applied = [0]
        done = threading.Event()

        @device.on_rpdo
        def count(rpdo: int) -> None:
            applied[0] += 1
            if applied[0] == frames:
                done.set()

        device.start()
        device.od[0x1600, 1] = 0x20010020  # RPDO 1: the u32, on 0x200 + node-ID
        device.od[0x1600, 0] = 1
        device.od[0x1400, 1] = 0x200 + SERVER_ID
        sender.send(can.Message(arbitration_id=0, data=bytes([1, SERVER_ID]),
                                is_extended_id=False))
        while device.nmt_state != "OPERATIONAL":
            time.sleep(0.001)
        messages = [can.Message(arbitration_id=0x200 + SERVER_ID, is_extended_id=False,
                                data=i.to_bytes(4, "little")) for i in range(frames)]
        try:
            for _ in range(runs):
                applied[0] = 0
                done.clear()
                t0 = time.perf_counter()
                for msg in messages:
                    sender.send(msg)
                if not done.wait(600):
                    raise SystemExit(f"bench_python: the device applied {applied[0]} of "
                                     f"{frames} RPDOs")
                best = min(best, time.perf_counter() - t0)
            if device.od[0x2001, 0] != frames - 1:
                raise SystemExit("bench_python: the last RPDO's value is not in the dictionary")
        finally:
            device.stop()
            bus.shutdown()
            sender.shutdown()
    print(f"frames={frames} runs={runs} fps={frames / best:.0f}")


def main() -> int:
    if len(sys.argv) != 4 or sys.argv[1] not in ("same_bus", "block", "segments",
                                                  "device_frames"):
        print(__doc__, file=sys.stderr)
        return 2
    what, n, runs = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
    {"same_bus": same_bus, "block": block, "segments": segments,
     "device_frames": device_frames}[what](n, runs)
    return 0


if __name__ == "__main__":
    sys.exit(main())
