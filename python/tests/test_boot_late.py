# SPDX-License-Identifier: Apache-2.0
"""canola boot --timeout S and a slave that comes late (in virtual time, on the simulated
bus): the command waits for it as canola.Master.boot(wait=False) does, booting it at its
boot-up (CiA 302-2), mandatory or optional; without --timeout it ends once the boot
settled, as before. It gave up after ~3 s with reason B."""

from __future__ import annotations

from pathlib import Path

import pytest
from cli_helpers import SharedSimBus, cli
from managed import model, write_dcf

import canola.cli.common
from canola import Device

Capsys = pytest.CaptureFixture[str]
LATE_S = 20  # virtual seconds until the late slave is powered on


class LateSlaveBus(SharedSimBus):
    """A simulated bus on which a device (node ``node``) is powered on at ``at_s``."""

    def __init__(self, node: int, at_s: float) -> None:
        super().__init__(500_000)
        self.node, self.at_us = node, round(at_s * 1e6)
        self.device: Device | None = None

    def run_until(self, until_us: int) -> None:
        if self.device is None and until_us > self.at_us:
            super().run_until(self.at_us)
            self.device = Device(model(serial=self.node), self.node, self)
            self.device.start()
        super().run_until(until_us)


@pytest.fixture
def late_bus(monkeypatch: pytest.MonkeyPatch) -> LateSlaveBus:
    bus = LateSlaveBus(4, LATE_S)
    monkeypatch.setattr(canola.cli.common, "open_bus",
                        lambda *, iface=None, url=None, timeout=3.0: bus)
    return bus


def _network(tmp_path: Path, optional: bool) -> Path:
    write_dcf(tmp_path / "node2.dcf", 2, {(0x1017, 0): "100"}, serial=2)
    write_dcf(tmp_path / "node4.dcf", 4, {(0x2000, 0): "300"}, serial=4)
    path = tmp_path / "net.yaml"
    path.write_text("nodes:\n  - {id: 2, dcf: node2.dcf}\n"
                    f"  - {{id: 4, dcf: node4.dcf, optional: {str(optional).lower()}}}\n")
    return path


@pytest.mark.parametrize("optional", [False, True], ids=["mandatory", "optional"])
def test_boot_waits_for_a_late_slave_until_its_timeout(capsys: Capsys, tmp_path: Path,
                                                       late_bus: LateSlaveBus,
                                                       optional: bool) -> None:
    two = Device(model(serial=2), 2, late_bus)
    two.start()
    late_bus.run_for(10_000)
    code, out, err = cli(capsys, "boot", str(_network(tmp_path, optional)), "--bus",
                         "virtual://simulated", "--timeout", "90")
    assert (code, err) == (0, "")
    kind = "optional" if optional else "mandatory"
    assert out.splitlines() == ["node 2 (mandatory): running", f"node 4 ({kind}): running",
                                "network started"]
    assert late_bus.now_us < (LATE_S + 10) * 1_000_000  # ended once it booted, not at 90 s
    assert late_bus.device is not None and late_bus.device.od[0x2000, 0] == 300


def test_boot_without_timeout_ends_when_the_boot_settled(capsys: Capsys, tmp_path: Path,
                                                         late_bus: LateSlaveBus) -> None:
    two = Device(model(serial=2), 2, late_bus)
    two.start()
    late_bus.run_for(10_000)
    code, out, _ = cli(capsys, "boot", str(_network(tmp_path, True)), "--bus",
                       "virtual://simulated")
    assert code == 0 and out.splitlines()[1].startswith("node 4 (optional): failed: B: ")
    assert late_bus.device is None  # it ended before the slave came
