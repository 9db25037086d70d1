# SPDX-License-Identifier: Apache-2.0
"""The three devices of the demo network: their EDS files, node-IDs, the PDO mappings the
master gives them, and the small application each one runs.

- node 2, an I/O module (CiA 401, ``io_module.eds``): its eight outputs are wired back to
  its eight inputs, so what the master writes by RPDO comes back in the TPDO.
- node 3, a drive (CiA 402, ``drive.eds``): a velocity-mode drive; controlword 0x06, 0x07,
  0x0F walk it to "operation enabled" (statusword), then its actual velocity ramps towards
  the target velocity by at most 500 rpm per SYNC.
- node 4, a sensor (CiA 404, ``sensor.eds``): a temperature in 0.01 degC that rises by
  0.25 degC every 100 ms.

:func:`configuration` is what the CANopen manager downloads to a device (its concise DCF):
the heartbeat producer time and the PDO mappings in the CiA 301 order; :func:`identity` is
what the manager expects it to answer (0x1000 and 0x1018 of its EDS).
"""

from __future__ import annotations

from dataclasses import dataclass
from importlib import resources
from pathlib import Path

from canola.boot_plan import Identity, identity_of
from canola.device import Device
from canola.formats import eds
from canola.formats.concise import Record, pdo_order

__all__ = ["DEVICES", "DeviceSpec", "Mapped", "attach_application", "configuration",
           "eds_path", "identity"]


@dataclass(frozen=True)
class Mapped:
    """One object mapped into a PDO: index, sub-index, length in bits, a short name and
    whether the value is signed."""

    index: int
    sub: int
    bits: int
    name: str
    signed: bool = False

    @property
    def entry(self) -> int:
        """The mapping entry (0xIIIISSLL) written to 0x16xx / 0x1Axx."""
        return self.index << 16 | self.sub << 8 | self.bits


@dataclass(frozen=True)
class DeviceSpec:
    """A device of the demo: ``role`` names it, ``tpdo``/``rpdo`` are the mappings of its
    first TPDO and RPDO as the master configures them (empty: no such PDO)."""

    role: str
    node_id: int
    eds: str
    profile: str
    tpdo: tuple[Mapped, ...]
    rpdo: tuple[Mapped, ...] = ()


IO, DRIVE, SENSOR = 2, 3, 4

DEVICES: tuple[DeviceSpec, ...] = (
    DeviceSpec("I/O module", IO, "io_module.eds", "CiA 401",
               tpdo=(Mapped(0x6000, 1, 8, "inputs"),),
               rpdo=(Mapped(0x6200, 1, 8, "outputs"),)),
    DeviceSpec("drive", DRIVE, "drive.eds", "CiA 402",
               tpdo=(Mapped(0x6041, 0, 16, "statusword"),
                     Mapped(0x606C, 0, 32, "velocity", signed=True)),
               rpdo=(Mapped(0x6040, 0, 16, "controlword"),
                     Mapped(0x60FF, 0, 32, "target velocity", signed=True))),
    DeviceSpec("sensor", SENSOR, "sensor.eds", "CiA 404",
               tpdo=(Mapped(0x9130, 1, 32, "temperature", signed=True),)),
)


def eds_path(spec: DeviceSpec) -> Path:
    """The EDS file of ``spec`` inside the package (``canola/data/demo``)."""
    return Path(str(resources.files("canola") / "data" / "demo" / spec.eds))


def identity(spec: DeviceSpec) -> Identity:
    """What ``spec``'s device answers if it is the one its EDS describes: 0x1000 and 0x1018
    sub1..4 (DefaultValue)."""
    return identity_of(eds.parse(eds_path(spec)))


#: Transmission types: TPDO1 on every SYNC, RPDO1 applied at once.
TPDO_TRANSMISSION, RPDO_TRANSMISSION = 1, 255


def _pdo(comm: int, node: int, mapping: tuple[Mapped, ...], transmission: int
         ) -> list[Record]:
    """The CiA 301 procedure for one PDO: off (COB-ID bit 31), mapping count 0, the
    entries, the count, the transmission type, on."""
    mapping_index = comm + 0x200
    cob_id = (0x180 if comm >= 0x1800 else 0x200) + node
    return pdo_order([(comm, 1, cob_id.to_bytes(4, "little")), (comm, 2, bytes([transmission])),
                      (mapping_index, 0, bytes([len(mapping)])),
                      *((mapping_index, i, m.entry.to_bytes(4, "little"))
                        for i, m in enumerate(mapping, 1))])


def configuration(spec: DeviceSpec, heartbeat_ms: int) -> list[Record]:
    """The entries the manager writes to ``spec``'s device, in order: 0x1017 (heartbeat
    producer time), TPDO1 and, when it has one, RPDO1."""
    records: list[Record] = [(0x1017, 0, heartbeat_ms.to_bytes(2, "little"))]
    records += _pdo(0x1800, spec.node_id, spec.tpdo, TPDO_TRANSMISSION)
    if spec.rpdo:
        records += _pdo(0x1400, spec.node_id, spec.rpdo, RPDO_TRANSMISSION)
    return records


def unpack(mapping: tuple[Mapped, ...], data: bytes) -> dict[str, int] | None:
    """The values of a PDO's payload by name, None when the length does not match."""
    if sum(m.bits for m in mapping) != 8 * len(data):
        return None
    out: dict[str, int] = {}
    pos = 0
    for m in mapping:
        chunk = data[pos:pos + m.bits // 8]
        out[m.name] = int.from_bytes(chunk, "little", signed=m.signed)
        pos += m.bits // 8
    return out


# ---- applications


_STATUS = {0x0006: 0x0231, 0x0007: 0x0233, 0x000F: 0x0237}  # CiA 402, simplified
_SWITCH_ON_DISABLED = 0x0250
_RAMP_RPM = 500


def _io_application(dev: Device) -> None:
    def written(index: int, sub: int, value: object) -> None:
        if (index, sub) == (0x6200, 1) and isinstance(value, int):
            dev.od[0x6000, 1] = value  # outputs wired to inputs

    dev.on_write(written)


def _drive_application(dev: Device) -> None:
    def written(index: int, sub: int, value: object) -> None:
        if (index, sub) == (0x6040, 0) and isinstance(value, int):
            dev.od[0x6041, 0] = _STATUS.get(value & 0x008F, _SWITCH_ON_DISABLED)

    def sync(_counter: int) -> None:
        enabled = dev.od[0x6041, 0] == _STATUS[0x000F]
        target = dev.od[0x60FF, 0] if enabled else 0
        actual = dev.od[0x606C, 0]
        assert isinstance(target, int) and isinstance(actual, int)
        step = max(-_RAMP_RPM, min(_RAMP_RPM, target - actual))
        if step:
            dev.od[0x606C, 0] = actual + step
        position = dev.od[0x6064, 0]
        assert isinstance(position, int)
        dev.od[0x6064, 0] = position + (actual + step) // 6  # increments per SYNC (10 ms)

    dev.on_write(written)
    dev.on_sync(sync)


def _sensor_application(dev: Device) -> None:
    count = [0]

    def sync(_counter: int) -> None:
        count[0] += 1
        if count[0] % 10 == 0:  # a new reading every 10 SYNCs (100 ms)
            value = dev.od[0x9130, 1]
            assert isinstance(value, int)
            dev.od[0x9130, 1] = value + 25

    dev.on_sync(sync)


def attach_application(spec: DeviceSpec, dev: Device) -> None:
    """Run ``spec``'s application on ``dev`` (callbacks on writes and SYNCs)."""
    {IO: _io_application, DRIVE: _drive_application,
     SENSOR: _sensor_application}[spec.node_id](dev)
