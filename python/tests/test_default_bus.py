# SPDX-License-Identifier: Apache-2.0
"""A default bus: ``CANOLA_BUS`` and python-can's own configuration name the bus of every
command; ``--iface``/``--bus`` override them; a bus without a channel, or none at all, is
a one-line error."""

from __future__ import annotations

import itertools
import json
import time
from collections.abc import Iterator
from pathlib import Path

import can
import pytest
from cli_helpers import cli, one_line_error

from canola.bus.hub import HubThread

_channels = itertools.count()


@pytest.fixture
def home(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """A home folder without python-can configuration files (~/.canrc, ...)."""
    monkeypatch.setenv("HOME", str(tmp_path))
    return tmp_path


@pytest.fixture
def peer() -> Iterator[tuple[str, can.BusABC]]:
    """A python-can virtual channel of this test and a bus on it that listens."""
    channel = f"default-bus-{next(_channels)}"
    bus = can.Bus(interface="virtual", channel=channel)
    yield channel, bus
    bus.shutdown()


def _nmt_start_seen(capsys: pytest.CaptureFixture[str], bus: can.BusABC,
                    *options: str) -> bool:
    """``canola nmt start 5 OPTIONS`` went out on ``bus``."""
    code, _, err = cli(capsys, "nmt", "start", "5", *options)
    assert (code, err) == (0, "")
    msg = bus.recv(2)
    return msg is not None and (msg.arbitration_id, bytes(msg.data)) == (0, b"\x01\x05")


def test_canola_bus_names_the_bus(capsys: pytest.CaptureFixture[str], home: Path,
                                  monkeypatch: pytest.MonkeyPatch,
                                  peer: tuple[str, can.BusABC]) -> None:
    channel, bus = peer
    monkeypatch.setenv("CANOLA_BUS", f"virtual://{channel}")
    assert _nmt_start_seen(capsys, bus)


def test_bus_options_override_canola_bus(capsys: pytest.CaptureFixture[str], home: Path,
                                         monkeypatch: pytest.MonkeyPatch,
                                         peer: tuple[str, can.BusABC]) -> None:
    channel, bus = peer
    monkeypatch.setenv("CANOLA_BUS", "socketcand://127.0.0.1:1/nothing-listens-here")
    assert _nmt_start_seen(capsys, bus, "--bus", f"virtual://{channel}")
    code, _, err = cli(capsys, "nmt", "start", "5", "--iface", "nosuchcan7")
    assert code == 1 and "nosuchcan7" in err  # --iface, not CANOLA_BUS, was tried
    one_line_error(err)


@pytest.mark.parametrize("how", ["variables", "CAN_CONFIG", "file"])
def test_python_can_configuration(capsys: pytest.CaptureFixture[str], home: Path,
                                  monkeypatch: pytest.MonkeyPatch,
                                  peer: tuple[str, can.BusABC], how: str) -> None:
    channel, bus = peer
    if how == "variables":
        monkeypatch.setenv("CAN_INTERFACE", "virtual")
        monkeypatch.setenv("CAN_CHANNEL", channel)
    elif how == "CAN_CONFIG":
        monkeypatch.setenv("CAN_CONFIG", f'{{"interface": "virtual", "channel": "{channel}"}}')
    else:
        (home / ".canrc").write_text(f"[default]\ninterface = virtual\nchannel = {channel}\n")
    assert _nmt_start_seen(capsys, bus)


def test_canola_bus_comes_before_python_can(capsys: pytest.CaptureFixture[str], home: Path,
                                            monkeypatch: pytest.MonkeyPatch,
                                            peer: tuple[str, can.BusABC]) -> None:
    channel, bus = peer
    monkeypatch.setenv("CAN_INTERFACE", "socketcan")
    monkeypatch.setenv("CAN_CHANNEL", "nosuchcan7")
    monkeypatch.setenv("CANOLA_BUS", f"virtual://{channel}")
    assert _nmt_start_seen(capsys, bus)


@pytest.mark.parametrize(("env", "code", "message"), [
    ({}, 2, "no bus: give --iface IFACE or --bus URL, or set CANOLA_BUS=URL"),
    ({"CANOLA_BUS": "socketcand://127.0.0.1:29536"}, 1, "CANOLA_BUS: no channel in"),
    ({"CANOLA_BUS": "socketcand://127.0.0.1:29536/"}, 1, "CANOLA_BUS: no channel in"),
    ({"CANOLA_BUS": "socketcan://"}, 1, "CANOLA_BUS: no channel in"),
    ({"CANOLA_BUS": "can0"}, 1, "CANOLA_BUS: unknown bus URL"),
    ({"CAN_INTERFACE": "virtual"}, 1, "names interface 'virtual' but no channel"),
    ({"CAN_CONFIG": "{not json"}, 1, "python-can's configuration:"),
    ({"CAN_INTERFACE": "nosuchinterface", "CAN_CHANNEL": "x"}, 1, "Unknown interface type"),
    ({"CAN_INTERFACE": "socketcan", "CAN_CHANNEL": "nosuchcan7"}, 1, "cannot open"),
])
@pytest.mark.usefixtures("home")
def test_no_usable_default_bus(capsys: pytest.CaptureFixture[str],
                               monkeypatch: pytest.MonkeyPatch, env: dict[str, str],
                               code: int, message: str) -> None:
    for name, value in env.items():
        monkeypatch.setenv(name, value)
    for command in (["nmt", "start", "5"], ["scan"], ["sdo", "read", "5", "0x1000"],
                    ["monitor", "--once"], ["dump"]):
        got, out, err = cli(capsys, *command)
        assert (got, out) == (code, ""), (command, err)
        one_line_error(err)
        assert message in err, (command, err)


def test_bus_url_without_channel_is_refused(capsys: pytest.CaptureFixture[str]) -> None:
    code, _, err = cli(capsys, "nmt", "start", "5", "--bus", "socketcand://127.0.0.1:29536")
    assert code == 1 and "no channel in 'socketcand://127.0.0.1:29536'" in err
    one_line_error(err)


def test_dump_of_a_file_needs_no_bus(capsys: pytest.CaptureFixture[str], home: Path,
                                     tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    log = tmp_path / "x.log"
    log.write_text("(1.0) can0 705#05\n")
    monkeypatch.setenv("CANOLA_BUS", "socketcand://127.0.0.1:1/nothing-listens-here")
    code, out, _ = cli(capsys, "dump", str(log))
    assert code == 0 and "node 5 heartbeat OPERATIONAL" in out


@pytest.mark.realtime
def test_python_can_socketcand_configuration(capsys: pytest.CaptureFixture[str], home: Path,
                                             monkeypatch: pytest.MonkeyPatch) -> None:
    """A socketcand bus from python-can's configuration opens as --bus socketcand://..."""
    with HubThread() as hub:
        peer = can.Bus(interface="socketcand", host="127.0.0.1", port=hub.port,
                       channel="cfg")
        try:
            monkeypatch.setenv("CAN_CONFIG", json.dumps(
                {"interface": "socketcand", "host": "127.0.0.1", "port": hub.port,
                 "channel": "cfg"}))
            deadline = time.monotonic() + 30
            seen = False
            while not seen and time.monotonic() < deadline:  # the peer's join is async
                seen = _nmt_start_seen(capsys, peer)
            assert seen
        finally:
            peer.shutdown()
