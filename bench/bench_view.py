#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""The CPU that ``canola view`` takes at a given frame rate. Prints one line of key=value
pairs (bench/run turns it into a row).

usage: bench_view.py FRAMES_PER_S SECONDS PAGES

A socketcand hub (canola.bus.hub, in this process) carries the traffic of a busy network:
every 10 ms a SYNC, the TPDO1 of nodes 1..18 and one heartbeat (nodes in turn), so 20
frames per 10 ms at 2,000 frames/s. ``canola view`` runs as its own process on the hub with
the demo drive's EDS for every node (each TPDO decoded into its signals), and PAGES pages
are open (WebSocket clients in this process, taking every update). Measured over SECONDS
after a warm-up: the view process's CPU time (user + system, from /proc) per second of wall
time and per frame, the frames the view counted against the frames sent (it kept up when
they are equal), and what the pages were sent.
"""
from __future__ import annotations

import asyncio
import json
import os
import queue
import subprocess
import sys
import threading
import time
from pathlib import Path

import can

from canola.bus.hub import HubThread
from canola.bus.socketcand_bus import SocketcandBus

ROOT = Path(__file__).resolve().parents[1]
EDS = ROOT / "python" / "src" / "canola" / "data" / "demo" / "drive.eds"
CYCLE_S = 0.01
NODES = range(1, 19)
WARM_UP_S = 2.0
#: Frames the hub holds for a client that reads late: a process starved by a loaded machine
#: catches up afterwards (the view counts every frame), rather than losing them at the hub.
QUEUE = 100_000


def cpu_seconds(pid: int) -> float:
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")  # utime + stime


def cycle_frames(n: int) -> list[can.Message]:
    """The frames of cycle ``n``: SYNC, the TPDO1s, one heartbeat."""
    frames = [can.Message(arbitration_id=0x080, data=b"", is_extended_id=False)]
    for node in NODES:
        data = (0x237).to_bytes(2, "little") + (n % 3000).to_bytes(4, "little", signed=True)
        frames.append(can.Message(arbitration_id=0x180 + node, data=data,
                                  is_extended_id=False))
    node = NODES[n % len(NODES)]
    frames.append(can.Message(arbitration_id=0x700 + node, data=b"\x05",
                              is_extended_id=False))
    return frames


def start_view(port: int) -> tuple[subprocess.Popen[str], int]:
    proc = subprocess.Popen(
        [sys.executable, "-m", "canola.cli", "view", "--bus",
         f"socketcand://127.0.0.1:{port}/can0", "--eds", str(EDS), "--listen", "127.0.0.1:0"],
        stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
    stdout = proc.stdout
    assert stdout is not None
    lines: queue.Queue[str] = queue.Queue()
    threading.Thread(target=lambda: [lines.put(line) for line in stdout], daemon=True).start()
    end = time.monotonic() + 120
    while (left := end - time.monotonic()) > 0:
        try:
            line = lines.get(timeout=min(left, 1.0))  # the view prints its URL at once
        except queue.Empty:
            if proc.poll() is not None:
                break  # it exited instead
            continue
        if line.startswith("canola view: http://"):
            return proc, int(line.split(":")[3].split("/")[0])
    proc.kill()
    proc.wait(10)
    raise SystemExit("bench_view: canola view did not start")


class Pages:
    """``count`` pages: each takes every update; the last frame total the view reported."""

    def __init__(self) -> None:
        self.updates = 0
        self.bytes = 0
        self.total = 0

    async def run(self, port: int, count: int, stop: asyncio.Event) -> None:
        import aiohttp  # noqa: PLC0415

        async with aiohttp.ClientSession() as session:
            sockets = [await session.ws_connect(f"http://127.0.0.1:{port}/ws",
                                                origin=f"http://127.0.0.1:{port}",
                                                max_msg_size=0) for _ in range(count)]

            async def take(ws: aiohttp.ClientWebSocketResponse) -> None:
                while not stop.is_set():
                    try:
                        msg = await asyncio.wait_for(ws.receive(), 1.0)
                    except TimeoutError:
                        continue
                    if msg.type != aiohttp.WSMsgType.TEXT:
                        return
                    data = json.loads(msg.data)
                    if data["type"] == "update":
                        self.updates += 1
                        self.bytes += len(msg.data)
                        self.total = max(self.total, data["traffic"]["total"])

            await asyncio.gather(*(take(ws) for ws in sockets))
            for ws in sockets:
                await ws.close()


async def measure(rate: float, seconds: float, pages_open: int) -> dict[str, float]:
    per_cycle = 20
    cycle_s = per_cycle / rate
    with HubThread(queue_limit=QUEUE) as hub:
        sender = SocketcandBus("127.0.0.1", hub.port, "can0", 5.0)
        view, web_port = start_view(hub.port)
        try:
            time.sleep(1.0)  # the view's bus connection is open
            pages = Pages()
            stop = asyncio.Event()
            clients = asyncio.create_task(pages.run(web_port, pages_open, stop))
            sent = 0
            began = due = time.perf_counter()
            cpu0 = wall0 = None
            n = 0
            while True:
                now = time.perf_counter()
                if cpu0 is None and now - began >= WARM_UP_S:
                    cpu0, wall0, sent0 = cpu_seconds(view.pid), now, sent
                if wall0 is not None and now - wall0 >= seconds:
                    break
                for msg in cycle_frames(n):
                    sender.send(msg)
                sent += per_cycle
                n += 1
                # the next cycle on time; a sender that fell behind does not burst to catch up
                due = max(due + cycle_s, time.perf_counter() - 2 * cycle_s)
                await asyncio.sleep(max(0.0, due - time.perf_counter()))
            cpu = cpu_seconds(view.pid) - cpu0
            wall = time.perf_counter() - wall0
            # the last update tells what the view counted: every frame, if it kept up
            end = time.monotonic() + 10
            while pages.total < sent and time.monotonic() < end:
                await asyncio.sleep(0.1)
            stop.set()
            await asyncio.wait_for(clients, 10)
        finally:
            view.terminate()
            view.wait(10)
            sender.shutdown()
    frames = sent - sent0
    return {"fps": frames / wall, "cpu_pct": 100 * cpu / wall, "cpu_us_per_frame": 1e6 * cpu /
            frames, "sent": sent, "seen": pages.total, "updates_per_s": pages.updates / (
                wall + WARM_UP_S), "page_kb_per_s": pages.bytes / 1e3 / (wall + WARM_UP_S) /
            pages_open, "pages": pages_open, "seconds": wall}


def main() -> None:
    rate, seconds, pages = float(sys.argv[1]), float(sys.argv[2]), int(sys.argv[3])
    figures = asyncio.run(measure(rate, seconds, pages))
    print(" ".join(f"{k}={v:.3f}" if isinstance(v, float) else f"{k}={v}"
                   for k, v in figures.items()))


if __name__ == "__main__":
    main()
