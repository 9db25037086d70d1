#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""canola.Master against python-canopen's RemoteNode where users are: the master's frames
cross a python-can bus object to a device that another bus object (or process) serves.
Prints one line of key=value pairs (bench/run turns them into rows).

usage: bench_master.py SETUP ROUND_TRIPS RUNS PDOS [--node CANOLA_NODE]
    SETUP is where the device is:
      virtual  two python-can virtual bus objects of one channel in one process: the master
               on one, the device on the other (canola.Device for canola, LocalNode for
               python-canopen), each bus object with its own receive thread. The process's
               CPU is the master's and the device's.
      hub      the socketcand hub (``canola bus serve``, a process) and canola-node (C, a
               process) on its channel; each master on canola's socketcand client.
      vcan     vcan0 (SocketCAN) and canola-node on it; each master on python-can's
               socketcan interface.
    A third contender, ``floor``, is python-can alone: the calling thread sends the request
    and receives the answer (on the virtual bus a second bus object's thread answers it), no
    CANopen stack at all: what any Python stack pays for python-can's bus objects (and, on
    the virtual bus, the two thread hand-offs).
    Per contender, each run in a fresh process of its own (only the measured master
    exists; runs interleaved), idle and then beside 4 CPU-bound processes:
      rate     expedited SDO uploads of 0x1018 sub 1 per second, back to back (best run);
      cpu_us   CPU time of the master's process per round trip (that run);
      pdo      of PDOS frames sent on 0x185 at 2,000 per second by another bus object (or
               process), how many reached the master's callback (canola: Master.on_frame
               with the COB-ID; python-canopen: Network.subscribe, the level its RPDOs use).
internal: bench_master.py child CONTENDER SETUP URL ROUND_TRIPS PDOS
          bench_master.py send URL PDOS
"""
from __future__ import annotations

import os
import socket
import subprocess
import sys
import threading
import time
from collections.abc import Callable
from typing import Any

import can

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
SERVER_ID = 5
INDEX, SUB = 0x1018, 1
PDO_ID = 0x185
PDO_RATE = 2000  # frames per second
LOADS = 4  # CPU-bound processes of the loaded runs
CONTENDERS = {"virtual": ("canola", "pycanopen", "floor"),
              "hub": ("canola", "pycanopen", "floor"), "vcan": ("canola", "pycanopen", "floor")}


def eds_of(setup: str) -> str:
    if setup == "virtual":
        return os.path.join(HERE, "ds301_objects.eds")
    return os.path.join(ROOT, "examples", "example_od.eds")  # canola-node's dictionary


def open_bus(url: str) -> can.BusABC:
    """virtual://CHANNEL, socketcan://IFACE or socketcand://HOST:PORT/CHANNEL."""
    if url.startswith("virtual://"):
        return can.Bus(interface="virtual", channel=url[10:], receive_own_messages=False)
    if url.startswith("socketcan://"):
        return can.Bus(interface="socketcan", channel=url[12:])
    from canola.bus.open import open_bus as canola_open  # noqa: PLC0415 -- the socketcand client

    return canola_open(url=url)


# ---- a contender in its own process

def canola_master(setup: str, url: str) -> tuple[Callable[[], bytes], Any, list[Any]]:
    import canola  # noqa: PLC0415

    bus = open_bus(url)
    closing: list[Any] = []
    if setup == "virtual":
        device = canola.Device(eds_of(setup), SERVER_ID, open_bus(url))
        device.start()
        closing.append(device)
    master = canola.Master(bus, announce=False)
    master.start()
    closing.insert(0, master)
    client = master.sdo(SERVER_ID)

    def subscribe(fn: Callable[[], None]) -> None:
        master.on_frame(lambda frame: fn(), PDO_ID)
    return (lambda: client.upload(INDEX, SUB)), subscribe, closing


def pycanopen_master(setup: str, url: str) -> tuple[Callable[[], bytes], Any, list[Any]]:
    import canopen  # noqa: PLC0415

    net = canopen.Network(open_bus(url)).connect()
    closing: list[Any] = [net]
    if setup == "virtual":
        device_net = canopen.Network(open_bus(url)).connect()
        device_net.create_node(SERVER_ID, eds_of(setup))  # the LocalNode answers
        closing.append(device_net)
    remote = net.add_node(SERVER_ID, eds_of(setup))
    remote.sdo.RESPONSE_TIMEOUT = 10.0  # a starved machine: no time-outs (not the speed)

    def subscribe(fn: Callable[[], None]) -> None:
        net.subscribe(PDO_ID, lambda can_id, data, timestamp: fn())
    return (lambda: remote.sdo.upload(INDEX, SUB)), subscribe, closing


def floor_pair(setup: str, url: str) -> tuple[Callable[[], bytes], Any, list[Any]]:
    """python-can alone: the request sent and the answer received by the calling thread,
    no CANopen stack; on the virtual bus a second bus object's thread answers it."""
    bus = open_bus(url)
    stop = threading.Event()
    closing: list[Any] = []
    if setup == "virtual":
        other = open_bus(url)

        def serve() -> None:
            while not stop.is_set():
                msg = other.recv(0.05)
                if msg is not None and msg.arbitration_id == 0x600 + SERVER_ID:
                    other.send(can.Message(arbitration_id=0x580 + SERVER_ID,
                                           data=b"\x43\x18\x10\x01\0\0\0\0",
                                           is_extended_id=False))
        thread = threading.Thread(target=serve, daemon=True)
        thread.start()
        closing.append(_Closer(lambda: (stop.set(), thread.join(2.0), other.shutdown())))
    closing.append(_Closer(bus.shutdown))
    request = can.Message(arbitration_id=0x600 + SERVER_ID, data=b"\x40\x18\x10\x01\0\0\0\0",
                          is_extended_id=False)

    def upload() -> bytes:
        bus.send(request)
        while True:
            msg = bus.recv(10.0)
            if msg is None:
                raise SystemExit("bench_master: floor: no answer")
            if msg.arbitration_id == 0x580 + SERVER_ID:
                return bytes(msg.data[4:])
    return upload, None, closing


class _Closer:
    def __init__(self, fn: Callable[[], object]) -> None:
        self.fn = fn

    def disconnect(self) -> None:
        self.fn()


MAKERS = {"canola": canola_master, "pycanopen": pycanopen_master, "floor": floor_pair}


def close_all(objs: list[Any]) -> None:
    for obj in objs:
        for name in ("stop", "disconnect"):
            if hasattr(obj, name):
                getattr(obj, name)()
                break
        bus = getattr(obj, "bus", None)
        if isinstance(bus, can.BusABC):
            bus.shutdown()


def send_pdos(url: str, count: int) -> None:
    """``count`` frames on PDO_ID at PDO_RATE per second, in bursts every 10 ms."""
    bus = open_bus(url)
    try:
        per_tick = PDO_RATE // 100
        t0 = time.monotonic()
        for i in range(count):
            if i % per_tick == 0:
                delay = t0 + i / PDO_RATE - time.monotonic()
                if delay > 0:
                    time.sleep(delay)
            bus.send(can.Message(arbitration_id=PDO_ID, data=i.to_bytes(4, "little"),
                                 is_extended_id=False))
    finally:
        bus.shutdown()


def child(contender: str, setup: str, url: str, round_trips: int, pdos: int) -> None:
    upload, subscribe, closing = MAKERS[contender](setup, url)
    try:
        expected = upload()  # first use: set-up, imports
        for _ in range(max(1, round_trips // 10)):
            upload()  # warm-up: not a figure
        c0, t0 = time.process_time(), time.perf_counter()
        for _ in range(round_trips):
            if upload() != expected:
                raise SystemExit(f"bench_master: {contender} uploaded another value")
        wall, cpu = time.perf_counter() - t0, time.process_time() - c0
        got = -1
        if subscribe is not None and pdos:
            seen = [0]

            def count() -> None:
                seen[0] += 1
            subscribe(count)
            if setup == "virtual":
                sender = threading.Thread(target=send_pdos, args=(url, pdos), daemon=True)
                sender.start()
                sender.join(pdos / PDO_RATE * 20 + 30)
            else:
                subprocess.run([sys.executable, __file__, "send", url, str(pdos)], check=True,
                               timeout=pdos / PDO_RATE * 20 + 600)  # an emulated VM's start
            end = time.monotonic() + 5.0
            while seen[0] < pdos and time.monotonic() < end:
                time.sleep(0.05)
            got = seen[0]
        print(f"rate={round_trips / wall:.1f} cpu_us={cpu / round_trips * 1e6:.1f} pdo={got}")
    finally:
        close_all(closing)


# ---- the parent: the device, the runs, the load

def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def wait_port(port: int, limit_s: float) -> None:
    end = time.monotonic() + limit_s
    while time.monotonic() < end:
        try:
            socket.create_connection(("127.0.0.1", port), timeout=1.0).close()
            return
        except OSError:
            time.sleep(0.1)
    raise SystemExit(f"bench_master: the hub did not listen on {port} within {limit_s} s")


def start_device(setup: str, node: str) -> tuple[str, list[subprocess.Popen[bytes]]]:
    """The bus URL of SETUP and the processes that serve it."""
    if setup == "virtual":
        return f"virtual://bench-master-{os.getpid()}", []
    procs: list[subprocess.Popen[bytes]] = []
    if setup == "hub":
        port = free_port()
        canola = os.path.join(os.path.dirname(sys.executable), "canola")
        procs.append(subprocess.Popen([canola, "bus", "serve", "--port", str(port)],
                                      stdout=subprocess.DEVNULL))
        wait_port(port, 60.0)
        url = f"socketcand://127.0.0.1:{port}/can0"
        bus_arg = ["--bus", url]
    else:
        url, bus_arg = "socketcan://vcan0", ["--iface", "vcan0"]
    procs.append(subprocess.Popen([node, *bus_arg, "--node-id", str(SERVER_ID),
                                   "--heartbeat", "0"], stdout=subprocess.DEVNULL))
    time.sleep(1.0)
    return url, procs


def run_child(contender: str, setup: str, url: str, round_trips: int,
              pdos: int) -> dict[str, float]:
    cmd = [sys.executable, __file__, "child", contender, setup, url, str(round_trips), str(pdos)]
    r = subprocess.run(cmd, capture_output=True, text=True, timeout=1800, check=False)
    if r.returncode != 0:
        raise SystemExit(f"bench_master: {contender} on {setup} failed:\n{r.stderr}")
    return {k: float(v) for k, v in (f.split("=") for f in r.stdout.split())}


def burners(n: int) -> list[subprocess.Popen[bytes]]:
    return [subprocess.Popen([sys.executable, "-c", "while True: pass"]) for _ in range(n)]


def parent(setup: str, round_trips: int, runs: int, pdos: int, node: str) -> None:
    url, procs = start_device(setup, node)
    out = [f"setup={setup}", f"round_trips={round_trips}", f"runs={runs}", f"pdos={pdos}"]
    try:
        for load in ("idle", "load"):
            load_procs = burners(LOADS) if load == "load" else []
            try:
                best: dict[str, dict[str, float]] = {}
                for _ in range(runs):
                    for contender in CONTENDERS[setup]:
                        f = run_child(contender, setup, url, round_trips,
                                      0 if contender == "floor" else pdos)
                        b = best.setdefault(contender, f)
                        if f["rate"] > b["rate"]:
                            b["rate"], b["cpu_us"] = f["rate"], f["cpu_us"]
                        b["pdo"] = min(b["pdo"], f["pdo"])
            finally:
                for p in load_procs:
                    p.kill()
                    p.wait(10)
            for contender, b in best.items():
                out += [f"{load}_{contender}_{k}={v:g}" for k, v in b.items()]
    finally:
        for p in procs:
            p.terminate()
            try:
                p.wait(10)
            except subprocess.TimeoutExpired:
                p.kill()
                p.wait(10)
    import canopen  # noqa: PLC0415
    out += [f"canopen={canopen.__version__}", f"can={can.__version__}"]
    print(" ".join(out))


def main() -> int:
    args = sys.argv[1:]
    if args[:1] == ["child"] and len(args) == 6:
        child(args[1], args[2], args[3], int(args[4]), int(args[5]))
        return 0
    if args[:1] == ["send"] and len(args) == 3:
        send_pdos(args[1], int(args[2]))
        return 0
    node = os.path.join(ROOT, "build", "canola-node")
    if len(args) == 6 and args[4] == "--node":
        node = args.pop(5)
        args.pop(4)
    if len(args) != 4 or args[0] not in CONTENDERS:
        print(__doc__, file=sys.stderr)
        return 2
    if args[0] != "virtual" and not os.access(node, os.X_OK):
        print(f"bench_master: no canola-node at {node} (--node PATH)", file=sys.stderr)
        return 2
    parent(args[0], int(args[1]), int(args[2]), int(args[3]), node)
    return 0


if __name__ == "__main__":
    sys.exit(main())
