# SPDX-License-Identifier: Apache-2.0
"""canola sync and canola time in virtual time: the CLI's master produces the frames with
the core's SYNC producer and the master's TIME production, on a simulated bus the
commands open (exact stamps, counters and counts). Over python-can: test_cli_eds.py."""

from __future__ import annotations

import json

import pytest
from cli_helpers import cli, cli_on_sim_bus

from canola import Master
from canola.core import SimBus


@pytest.fixture
def sim(monkeypatch: pytest.MonkeyPatch) -> tuple[list[str], SimBus]:
    return cli_on_sim_bus(monkeypatch, bitrate=0)  # frames at the instant they are sent


def _frames(bus: SimBus, since_us: int) -> list[tuple[int, str, str]]:
    """(us after ``since_us``, COB-ID, data) of every frame on the bus."""
    out = []
    for line in bus.trace:
        stamp, _, frame = line.split()
        can_id, data = frame.split("#")
        out.append((round(float(stamp.strip("()")) * 1e6) - since_us, can_id, data))
    return out


def test_sync_count_with_counter(capsys: pytest.CaptureFixture[str],
                                 sim: tuple[list[str], SimBus]) -> None:
    opts, bus = sim
    begin = bus.now_us
    assert cli(capsys, "sync", "10", "--counter", "3", "--count", "5", *opts, "--json") == (
        0, '{"frames": 5, "service": "sync"}\n', "")
    bus.run_for(1_000_000)  # stopped: nothing more, not even from the silent master
    assert _frames(bus, begin) == [(k * 10_000, "080", f"{(k - 1) % 3 + 1:02X}")
                                   for k in range(1, 6)]


def test_sync_duration_without_counter(capsys: pytest.CaptureFixture[str],
                                       sim: tuple[list[str], SimBus]) -> None:
    opts, bus = sim
    begin = bus.now_us
    code, out, _ = cli(capsys, "sync", "20", "--duration", "0.25", *opts, "--json")
    assert (code, json.loads(out)) == (0, {"frames": 12, "service": "sync"})
    bus.run_for(1_000_000)
    assert _frames(bus, begin) == [(k * 20_000, "080", "") for k in range(1, 13)]


def test_sync_once_per_period_of_a_long_period(capsys: pytest.CaptureFixture[str],
                                               sim: tuple[list[str], SimBus]) -> None:
    opts, bus = sim
    begin = bus.now_us
    assert cli(capsys, "sync", "1500", "--count", "2", *opts) == (0, "", "")
    assert [t for t, _, _ in _frames(bus, begin)] == [1_500_000, 3_000_000]


def test_time_periodic_and_once(capsys: pytest.CaptureFixture[str],
                                sim: tuple[list[str], SimBus]) -> None:
    opts, bus = sim
    begin = bus.now_us
    assert cli(capsys, "time", "--period", "100", "--count", "4", *opts, "--json") == (
        0, '{"frames": 4, "service": "time"}\n', "")
    bus.run_for(1_000_000)
    frames = _frames(bus, begin)
    assert [(t, can_id, len(data)) for t, can_id, data in frames] == [
        (k * 100_000, "100", 12) for k in range(4)]  # the first at once
    begin = bus.now_us
    assert cli(capsys, "time", *opts, "--json") == (0, '{"frames": 1, "service": "time"}\n',
                                                    "")
    bus.run_for(1_000_000)
    assert [(t, can_id) for t, can_id, _ in _frames(bus, begin)][4:] == [(0, "100")]


def test_sync_count_counts_only_its_own(capsys: pytest.CaptureFixture[str],
                                        sim: tuple[list[str], SimBus]) -> None:
    # another SYNC producer on the same COB-ID (every 7 ms: never at the same instant in
    # the first 70 ms): --count N stops after N SYNCs of the command's own
    opts, bus = sim
    other = Master(bus, 90)
    other.start()
    other.start_sync(7000)
    begin = bus.now_us
    assert cli(capsys, "sync", "10", "--count", "5", *opts, "--json") == (
        0, '{"frames": 5, "service": "sync"}\n', "")
    bus.run_for(15_000)  # up to 65 ms: a sixth SYNC of its own would come at 60 ms
    other.stop_sync()
    own = [t for t, can_id, _ in _frames(bus, begin) if can_id == "080" and t % 10_000 == 0]
    assert own == [k * 10_000 for k in range(1, 6)]
