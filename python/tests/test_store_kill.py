# SPDX-License-Identifier: Apache-2.0
"""Parameter storage survives SIGKILL during a save.

A device (canola.Device with a store folder, on a hub) gets new parameter values over SDO,
then the "save" signature on 0x1010:1; it is killed with SIGKILL at a random moment around
the save. Afterwards a fresh device loads the folder: both files must load and hold either
the previous generation of values or the new one, the same in both (a save of both groups is
one step), never defaults, a mix inside one file or between the two, or an error.
CANOLA_STORE_LOOPS sets the number of rounds (default 200).

To keep a round cheap the devices are forked from a driver process that has canola
imported already (a fork takes milliseconds, a fresh interpreter about a second). The driver
runs in a process group of its own: the test ends it and every device it forked, pass or
fail.

The master sends "save" and does not wait for the answer; a device killed after answering
may have that answer still on its way through the hub when the next round's device is
asked. So the rounds alternate between node-IDs 5 and 6 (a late answer belongs to the
other node's SDO channel), and each round waits until the hub has let the killed device go
(so its last frames were passed on before the round after next).
"""

from __future__ import annotations

import contextlib
import os
import random
import signal
import subprocess
import sys
import textwrap
import time
from collections.abc import Callable, Iterator
from pathlib import Path

import can
import pytest
from bounded import Lines

from canola.bus.hub import HubThread
from canola.core import SimBus
from canola.device import Device
from canola.formats import eds
from canola.master import Master

pytestmark = [pytest.mark.slow, pytest.mark.realtime]

EDS = Path(__file__).parent / "data" / "cli_device.eds"
LOOPS = int(os.environ.get("CANOLA_STORE_LOOPS", "200"))

DRIVER = textwrap.dedent("""
    import os, sys, time
    from canola.formats import eds
    from canola.bus.open import open_bus
    from canola.device import Device
    model = eds.parse(sys.argv[1])
    for line in sys.stdin:
        url, store, node_id = line.split()
        pid = os.fork()
        if pid == 0:
            bus = open_bus(url=url)
            dev = Device(model, int(node_id), bus, store_dir=store)
            dev.start()
            print(f"ready {os.getpid()}", flush=True)
            while True:
                time.sleep(10)
        while True:  # reap the children killed so far
            try:
                done, _ = os.waitpid(-1, os.WNOHANG)
            except ChildProcessError:
                break
            if done == 0:
                break
""")

SAVE = bytes([0x23, 0x10, 0x10, 0x01]) + b"save"
NODES = (5, 6)  # the rounds' devices, in turn


def _values(gen: int) -> tuple[int, int, int]:
    """Generation ``gen``'s values: (0x2000 u32, 0x2001 i16) in the application file and
    0x1017 (u16) in the communication file; never the EDS defaults."""
    return 0x5A000000 + gen, -1000 - gen, 2000 + gen


def _loaded(model: eds.ObjectDictionary, store: Path) -> tuple[int, int, int]:
    bus = SimBus()
    dev = Device(model, 5, bus, store_dir=store)
    dev.start()
    bus.run_for(1000)
    got = (dev.od.get(0x2000, 0), dev.od.get(0x2001, 0), dev.od.get(0x1017, 0))
    assert all(isinstance(v, int) for v in got)
    return got  # type: ignore[return-value]


@pytest.fixture
def driver() -> Iterator[subprocess.Popen[str]]:
    proc = subprocess.Popen([sys.executable, "-c", DRIVER, str(EDS)], stdin=subprocess.PIPE,
                            stdout=subprocess.PIPE, text=True, start_new_session=True)
    try:
        yield proc
    finally:
        with contextlib.suppress(ProcessLookupError):
            os.killpg(proc.pid, signal.SIGKILL)  # the driver and any device it forked
        proc.wait(10)
        for pipe in (proc.stdin, proc.stdout):
            if pipe is not None:
                pipe.close()


def _wait(check: Callable[[], bool], what: str, timeout: float = 30.0) -> None:
    end = time.monotonic() + timeout
    while not check():
        assert time.monotonic() < end, f"{what}: not within {timeout} s"
        time.sleep(0.005)


def test_sigkill_during_save_keeps_old_or_new(tmp_path: Path,
                                              driver: subprocess.Popen[str]) -> None:
    model = eds.parse(EDS)
    store = tmp_path / "store"
    store.mkdir()
    rng = random.Random(2026)
    outcomes = {"old": 0, "new": 0, "mid-save": 0}
    assert driver.stdin is not None and driver.stdout is not None
    lines = Lines(driver.stdout, "the forked device")
    with HubThread() as hub:
        url = f"socketcand://127.0.0.1:{hub.port}/store"
        bus = can.Bus(interface="socketcand", host="127.0.0.1", port=hub.port, channel="store")
        master = Master(bus, 127, sdo_timeout_ms=10000)  # a starved device answers late
        master.start()
        try:
            saved_gen = 0

            def spawn(node_id: int) -> int:
                driver.stdin.write(f"{url} {store} {node_id}\n")  # type: ignore[union-attr]
                driver.stdin.flush()  # type: ignore[union-attr]
                line = lines.line(60)  # a device that died says nothing: a failed test
                assert line.startswith("ready "), line
                return int(line.split()[1])

            def kill(pid: int) -> None:
                """SIGKILL, then wait until the hub has let the device go."""
                os.kill(pid, signal.SIGKILL)
                _wait(lambda: len(hub.hub.clients()) == 1, "the hub drops the killed device")

            def write(gen: int, node_id: int) -> None:
                u32, i16, hb = _values(gen)
                sdo = master.sdo(node_id)
                sdo.write(0x2000, 0, "u32", u32)
                sdo.write(0x2001, 0, "i16", i16)
                sdo.write(0x1017, 0, "u16", hb)

            # generation 0 saved properly; and how long a save takes, to aim the kills
            pid = spawn(NODES[0])
            write(0, NODES[0])
            start = time.monotonic()
            master.sdo(NODES[0]).download(0x1010, 1, b"save")
            save_s = time.monotonic() - start
            kill(pid)
            assert _loaded(model, store) == _values(0)
            started = time.monotonic()
            for gen in range(1, LOOPS + 1):
                for leftover in store.glob("*.tmp"):  # so that a .tmp below is this round's
                    leftover.unlink()
                node_id = NODES[gen % 2]
                pid = spawn(node_id)
                write(gen, node_id)
                master.send(0x600 + node_id, SAVE)  # no waiting for the answer
                time.sleep(rng.uniform(0, 2 * save_s))
                kill(pid)  # the kernel has finished the process too
                if any(store.glob("*.tmp")):  # killed between writing and renaming
                    outcomes["mid-save"] += 1
                got = _loaded(model, store)
                old, new = _values(saved_gen), _values(gen)
                assert got in (old, new), (gen, got, old, new)
                if got == new:
                    saved_gen = gen
                outcomes["new" if got == new else "old"] += 1
            elapsed = time.monotonic() - started
        finally:
            master.stop()
            bus.shutdown()
    print(f"\n{LOOPS} kills in {elapsed:.1f} s (save took {save_s * 1000:.1f} ms): {outcomes}")
    assert outcomes["old"] + outcomes["new"] == LOOPS
    if LOOPS >= 50:  # the kills really land inside saves, and on both sides of them
        assert outcomes["mid-save"] > 0 and outcomes["old"] > 0 and outcomes["new"] > 0
