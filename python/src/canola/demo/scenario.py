# SPDX-License-Identifier: Apache-2.0
"""The flow of the demo (seed 001, "Logic Summary"), step by step, each step checked.

A master (node 0x3F = 63, :class:`canola.Master`) and the three devices of
:mod:`canola.demo.devices` (:class:`canola.Device` each, with its application):

1. the master powers on and broadcasts its online status: its boot-up on 0x73F
   (0x700 + 0x3F), as the node that runs the network announces itself;
2. the devices power on; the master sees their boot-ups (0x700 + node, data 00);
3. the master sends NMT "enter pre-operational" to all;
4. the CANopen manager (CiA 302-2, :meth:`canola.Master.boot`) boots the network from its
   description: for each device it reads 0x1000 and 0x1018 (the identity its EDS gives),
   downloads its concise DCF (0x1017 = 100 ms, then the first TPDO (synchronous) and
   RPDO with the CiA 301 procedure: PDO off, mapping count 0, entries, count,
   transmission type, PDO on), watches its heartbeat (time-out 250 ms); once every device
   booted it starts the network (0x1F80: NMT start all). The step passes on the
   manager's verdict: every node booted, the network started;
5. the heartbeats: 0x1017 reads back 100 ms on each device, its heartbeats come every
   100 ms, the master watches them;
6. the PDO mappings read back from each device;
7. every heartbeat says OPERATIONAL after the manager's NMT start;
8. SYNC every 10 ms: every device answers each SYNC with its TPDO;
9. the master sends RPDOs (drive: controlword, target velocity; I/O module: outputs): the
   devices apply them and the new values come back in their TPDOs;
10. the drive raises an EMCY (0x4310, excess temperature); the master reports it;
11. the sensor falls silent; the master reports the heartbeat loss.

A step passes on what the master observes (and, for RPDOs, on the device's dictionary).
A failing step does not stop the demo: the next steps run and say what they see.
:class:`Faults` breaks a step on purpose (``canola demo --fault``), to see the checks work.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from canola.boot_plan import Network as NetworkDescription
from canola.boot_plan import SlaveSpec
from canola.decode import emcy_text
from canola.demo.devices import (
    DEVICES,
    DRIVE,
    IO,
    RPDO_TRANSMISSION,
    SENSOR,
    TPDO_TRANSMISSION,
    Mapped,
    attach_application,
    configuration,
    eds_path,
    identity,
)
from canola.demo.network import Network
from canola.demo.observer import Observer
from canola.demo.report import STEPS, Step
from canola.demo.trace import Trace
from canola.device import Device
from canola.errors import Error
from canola.formats import concise
from canola.manager import NetworkManager
from canola.master import EmcyEvent, HeartbeatEvent, Master

__all__ = ["FAULTS", "Faults", "Scenario"]

MASTER_ID = 0x3F  # its online status (boot-up) is 0x73F
HEARTBEAT_MS = 100
CONSUMER_MS = 250
#: Step 5 averages the period over this many heartbeats of each node, waiting for them up to
#: HEARTBEAT_WAIT_PERIODS periods; on a real bus a period up to REAL_PERIOD_MARGIN times the
#: configured one passes (a shared, loaded machine: one measured 3.05x in an emulated VM).
HEARTBEATS_SEEN = 4
HEARTBEAT_WAIT_PERIODS = 12
REAL_PERIOD_MARGIN = 4.0
SYNC_US = 10_000
SYNCS = 5  # SYNC cycles of the TPDO step
TARGET_RPM = 1500
EMCY_CODE = 0x4310  # CiA 402: excess temperature, drive
# How long (times the time scale) a step waits for the network's answer to what it did:
# long enough for a process starved by a loaded machine; the waits end on the answer.
REACTION_S = 1.0


@dataclass(frozen=True)
class Faults:
    """Faults to inject: devices that never power on, devices that answer another
    vendor-ID than their EDS gives (the manager refuses them), the drive's EMCY switched
    off, the sensor that keeps beating instead of falling silent."""

    never_boots: frozenset[int] = frozenset()
    wrong_vendor: frozenset[int] = frozenset()
    emcy_off: bool = False
    keeps_beating: bool = False


#: ``canola demo --fault NAME``.
FAULTS: dict[str, Faults] = {
    "sensor-never-boots": Faults(never_boots=frozenset({SENSOR})),
    "drive-emcy-off": Faults(emcy_off=True),
    "drive-wrong-vendor": Faults(wrong_vendor=frozenset({DRIVE})),
    "sensor-keeps-beating": Faults(keeps_beating=True),
}

#: What a device answers as its vendor-ID with the fault ``drive-wrong-vendor``.
WRONG_VENDOR = 0x00000BAD


def _read_int(master: Master, node: int, index: int, sub: int, data_type: str) -> int:
    value = master.sdo(node).read(index, sub, data_type)
    if not isinstance(value, int):
        raise Error(f"0x{index:04X}:{sub:02X} of node {node} is not a number")
    return value


def _nodes(ids: list[int] | set[int]) -> str:
    ids = sorted(ids)
    if not ids:
        return "no node"
    return ("node " if len(ids) == 1 else "nodes ") + ", ".join(map(str, ids))


class Scenario:
    """The network on ``net``, telling its story on ``trace``."""

    def __init__(self, net: Network, trace: Trace, faults: Faults | None = None, *,
                 time_scale: int = 1) -> None:
        if not 1 <= time_scale <= 100:
            raise Error(f"time scale {time_scale} is outside 1..100")
        self.net = net
        self.scale = time_scale
        self.heartbeat_ms = HEARTBEAT_MS * time_scale
        self.consumer_ms = CONSUMER_MS * time_scale
        self.sync_us = SYNC_US * time_scale
        self.trace = trace
        self.faults = faults or Faults()
        self.specs = {spec.node_id: spec for spec in DEVICES}
        self.obs = Observer(net, trace)
        # a node that does not answer costs little virtual time, but real buses may be slow
        self.sdo_timeout_ms = 300 if net.virtual else 1000
        self.master = Master(net.node_bus(), MASTER_ID,
                             sdo_timeout_ms=min(0xFFFF, self.sdo_timeout_ms * time_scale))
        self.manager: NetworkManager | None = None
        self.devices: dict[int, Device] = {}
        for spec in DEVICES:
            dev = Device(eds_path(spec), spec.node_id, net.node_bus())
            attach_application(spec, dev)
            self.obs.watch_device(spec, dev)
            self.devices[spec.node_id] = dev
        self.obs.watch_master(self.master)
        trace.master_id = MASTER_ID

    def wait(self, seconds: float) -> None:
        self.net.wait(seconds, self.obs.tick)

    def wait_until(self, done: Callable[[], bool], at_most: float) -> bool:
        """Let time pass in 10 ms steps until ``done()`` or ``at_most`` seconds (times the
        time scale) passed."""
        end = self.net.now() + at_most * self.scale
        while not done():
            if self.net.now() >= end:
                return False
            self.wait(0.01)
        return True

    # ---- the flow

    def run(self, *, keep_running: bool = False) -> list[Step]:
        r"""Every step, then the nodes stopped (unless ``keep_running``: the caller
        :meth:`close`\ s them)."""
        steps = [Step(key, title) for key, title in STEPS]
        actions: dict[str, Callable[[], tuple[bool, str]]] = {
            "master-online": self.online, "boot-up": self.boot, "pre-operational": self.preop,
            "manager": self.manage, "heartbeat": self.heartbeat, "pdo-mapping": self.pdo_mapping,
            "start": self.start, "sync-tpdo": self.sync_tpdo, "rpdo": self.rpdo,
            "emcy": self.emcy, "heartbeat-loss": self.heartbeat_loss,
        }
        try:
            for n, step in enumerate(steps, 1):
                self.trace.heading(f"{n}. {step.title}")
                try:
                    step.ok, step.detail = actions[step.key]()
                except Error as exc:
                    step.ok, step.detail = False, str(exc)
                self.obs.tick()
            self.master.stop_sync()
            self.wait(0.02)
        finally:
            if not keep_running:
                self.close()
        return steps

    def close(self) -> None:
        for node in (self.master, *self.devices.values()):
            node.stop()

    def online(self) -> tuple[bool, str]:
        self.master.start()
        cob = 0x700 + MASTER_ID

        def announced() -> bool:
            return any(frame.can_id == cob and frame.data == b"\x00" and not frame.rtr
                       for frame, _ in self.trace.events)

        self.wait_until(announced, 0.5)
        if not announced():
            return False, f"no boot-up {cob:03X}#00 from the master"
        return True, f"{cob:03X}#00: the master, node {MASTER_ID} (0x{MASTER_ID:02X}), is online"

    def boot(self) -> tuple[bool, str]:
        for node, dev in self.devices.items():
            if node not in self.faults.never_boots:
                dev.start()
            if node in self.faults.wrong_vendor:  # after its reset, which loads the EDS's
                dev.od[0x1018, 1] = WRONG_VENDOR
        def all_booted() -> bool:
            return self.obs.bootups() >= set(self.devices)

        self.wait_until(all_booted, 0.5)
        booted = self.obs.bootups()
        missing = set(self.devices) - booted
        if missing:
            return False, f"no boot-up from {_nodes(missing)}"
        return True, f"{_nodes(booted)} booted"

    def preop(self) -> tuple[bool, str]:
        sent = self._nmt_seen("preop")
        self.master.nmt(0, "preop")
        self.wait_until(lambda: self._nmt_seen("preop") > sent and all(
            d.nmt_state == "PRE-OPERATIONAL" for d in self.devices.values()), REACTION_S)
        if self._nmt_seen("preop") == sent:
            return False, "the NMT command did not reach the bus"
        wrong = {n: d.nmt_state for n, d in self.devices.items()
                 if d.nmt_state != "PRE-OPERATIONAL"}
        if wrong:
            return False, "; ".join(f"node {n} is {s}" for n, s in sorted(wrong.items()))
        return True, f"{_nodes(list(self.devices))} pre-operational"

    def _each(self, fn: Callable[[int], None]) -> dict[int, str]:
        """Run ``fn`` for every device; the errors by node (SDO aborts, time-outs)."""
        errors = {}
        for node in self.devices:
            try:
                fn(node)
            except Error as exc:
                errors[node] = str(exc)
        return errors

    @staticmethod
    def _failed(errors: dict[int, str]) -> str:
        return "; ".join(f"node {n}: {e}" for n, e in sorted(errors.items()))

    def network(self) -> NetworkDescription:
        """The network description the manager boots: every device mandatory, expected to
        be what its EDS says (0x1000, 0x1018), configured by its concise DCF, its
        heartbeat watched; the network started with one NMT command (0x1F80 bit 1)."""
        return NetworkDescription(tuple(
            SlaveSpec(node_id=spec.node_id, mandatory=True, identity=identity(spec),
                      config=concise.build(configuration(spec, self.heartbeat_ms)),
                      heartbeat_ms=self.consumer_ms)
            for spec in DEVICES), start="all", source="canola demo")

    def manage(self) -> tuple[bool, str]:
        network = self.network()
        mgr = self.manager = self.master.boot(network, on_event=self.obs.manager_event,
                                              wait=False)
        # each boot ends within an SDO time-out and a heartbeat time-out
        self.wait_until(mgr.settled, len(network.slaves)
                        * (self.sdo_timeout_ms + CONSUMER_MS) / 1000 + 0.5)
        self.wait(0.01)  # the manager's reports and the NMT start reach the trace
        self.obs.mapped = True
        statuses = mgr.slaves()
        booted = {e.node for e in mgr.events if e.kind == "booted"}
        problems = [f"{self.obs.name(s.node)} {str(s).split(': ', 1)[1]}"
                    for s in statuses if not s.ok or s.node not in booted]
        if not mgr.settled():
            problems.append("the boot did not settle")
        if not mgr.started:
            problems.append("the network was not started")
        if problems:
            return False, "; ".join(problems)
        entries = sum(len(concise.parse(s.config or b"\0\0\0\0")) for s in network.slaves)
        return True, (f"{_nodes(booted)} booted (identity checked, {entries} entries "
                      "downloaded), network started")

    def _heartbeat_times(self, node: int, since: float) -> list[float]:
        return [frame.t for frame, ev in self.trace.events
                if ev.kind == "heartbeat" and ev.node == node and frame.t >= since]

    def heartbeat(self) -> tuple[bool, str]:
        since = self.net.now()

        def configured(node: int) -> None:
            back = _read_int(self.master, node, 0x1017, 0, "u16")
            if back != self.heartbeat_ms:
                raise Error(f"0x1017 reads back {back}")

        errors = self._each(configured)
        # four heartbeats of each node; a starved machine may take longer than 3.5 periods
        self.wait_until(lambda: all(len(self._heartbeat_times(n, since)) >= HEARTBEATS_SEEN
                                    for n in self.devices),
                        HEARTBEAT_WAIT_PERIODS * HEARTBEAT_MS / 1000)
        self.obs.tick()
        # Virtual time: the producer's period to the bit. Real time: the devices share the
        # CPU with this process, so a starved machine sends late; never early, though.
        low, high = (0.99, 1.01) if self.net.virtual else (0.5, REAL_PERIOD_MARGIN)
        periods = {}
        for node in self.devices:
            times = self._heartbeat_times(node, since)
            if len(times) < 2:
                errors.setdefault(node, f"{len(times)} heartbeat(s) in "
                                        f"{self.net.now() - since:.3f} s")
                continue
            period_ms = (times[-1] - times[0]) / (len(times) - 1) * 1000
            periods[node] = period_ms
            if not low * self.heartbeat_ms <= period_ms <= high * self.heartbeat_ms:
                errors.setdefault(node, f"heartbeats every {period_ms:.0f} ms")
            elif self.master.heartbeat_state(node) is None:
                errors.setdefault(node, "the master does not watch its heartbeat")
        if errors:
            return False, self._failed(errors)
        heard = sorted({round(p) for p in periods.values()})
        return True, (f"0x1017 = {self.heartbeat_ms} ms on {_nodes(list(self.devices))} "
                      f"(read back), heard every {'/'.join(map(str, heard))} ms, watched "
                      f"by the master (time-out {self.consumer_ms} ms)")

    def _check_pdo(self, node: int, comm: int, *, mapping: tuple[Mapped, ...],
                   transmission: int) -> None:
        mapping_index, cob_id = comm + 0x200, (0x180 if comm >= 0x1800 else 0x200) + node
        got_cob = _read_int(self.master, node, comm, 1, "u32")
        if got_cob != cob_id:
            raise Error(f"0x{comm:04X}:01 reads back 0x{got_cob:08X}")
        got_type = _read_int(self.master, node, comm, 2, "u8")
        if got_type != transmission:
            raise Error(f"0x{comm:04X}:02 reads back {got_type}")
        count = _read_int(self.master, node, mapping_index, 0, "u8")
        back = [_read_int(self.master, node, mapping_index, i, "u32")
                for i in range(1, count + 1)]
        if back != [m.entry for m in mapping]:
            raise Error(f"0x{mapping_index:04X} reads back "
                        + (", ".join(f"0x{v:08X}" for v in back) or "no entry"))

    def pdo_mapping(self) -> tuple[bool, str]:
        def check(node: int) -> None:
            spec = self.specs[node]
            self._check_pdo(node, 0x1800, mapping=spec.tpdo, transmission=TPDO_TRANSMISSION)
            if spec.rpdo:
                self._check_pdo(node, 0x1400, mapping=spec.rpdo,
                                transmission=RPDO_TRANSMISSION)

        errors = self._each(check)
        if errors:
            return False, self._failed(errors)
        rx = [n for n, s in self.specs.items() if s.rpdo]
        return True, (f"TPDO1 on every SYNC for {_nodes(list(self.devices))}, RPDO1 for "
                      f"{_nodes(rx)}, read back")

    def start(self) -> tuple[bool, str]:
        starts = [ev.fields.get("target") for _, ev in self.trace.events
                  if ev.kind == "nmt" and ev.fields.get("command") == "start"]
        if not starts:
            return False, "the manager sent no NMT start"
        self.wait_until(lambda: all(self.master.heartbeat_state(n) == "OPERATIONAL"
                                    for n in self.devices), 2.5 * HEARTBEAT_MS / 1000)
        wrong = {n: self.master.heartbeat_state(n) for n in self.devices}
        wrong = {n: s for n, s in wrong.items() if s != "OPERATIONAL"}
        if wrong:
            return False, "; ".join(f"node {n} heartbeat says {s or 'nothing'}"
                                    for n, s in sorted(wrong.items()))
        how = ("NMT start all" if 0 in starts
               else "NMT start " + ", ".join(str(t) for t in starts))
        return True, f"{_nodes(list(self.devices))} heard OPERATIONAL ({how} by the manager)"

    def _nmt_seen(self, command: str) -> int:
        """How many NMT ``command`` frames to all nodes the trace has seen."""
        return sum(1 for _, ev in self.trace.events if ev.kind == "nmt"
                   and ev.fields.get("command") == command and ev.fields.get("target") == 0)

    def _syncs(self) -> int:
        return sum(1 for _, ev in self.trace.events if ev.kind == "sync")

    def sync_tpdo(self) -> tuple[bool, str]:
        syncs0, tpdos0 = self._syncs(), self.obs.tpdo_counts()
        began = self.net.now()
        self.master.start_sync(self.sync_us)
        # five SYNCs; a real-time master on a starved machine may be late (one SYNC in
        # 600 ms was seen at a load of 20 on 2 cores): the wait ends on the fifth SYNC
        self.wait_until(lambda: self._syncs() - syncs0 >= SYNCS,
                        max(4 * SYNCS * SYNC_US / 1e6, 5 * REACTION_S))
        syncs, took_ms = self._syncs() - syncs0, (self.net.now() - began) * 1000

        def answered() -> dict[int, int]:
            return {n: c - tpdos0[n] for n, c in self.obs.tpdo_counts().items()}

        # the TPDOs of the last SYNC may still be on their way (real buses, a starved
        # process: these waits end as soon as what they wait for is there)
        self.wait_until(lambda: min(answered().values()) >= syncs, REACTION_S)
        tpdos = answered()
        short = {n: c for n, c in tpdos.items() if c < syncs}
        if syncs < SYNCS:
            return False, f"{syncs} SYNCs in {took_ms:.0f} ms (period {self.sync_us} us)"
        if short:
            return False, "; ".join(f"node {n}: {c} TPDOs for {syncs} SYNCs"
                                    for n, c in sorted(short.items()))
        return True, (f"{syncs} SYNCs in {took_ms:.0f} ms (period {self.sync_us // 1000} ms), "
                      "TPDOs " + ", ".join(f"node {n} {c}" for n, c in sorted(tpdos.items())))

    def rpdo(self) -> tuple[bool, str]:
        outputs = 0
        for cycle in range(25):
            control = (0x0006, 0x0007)[cycle] if cycle < 2 else 0x000F
            target = TARGET_RPM if cycle >= 2 else 0
            self.master.send_pdo(0x200 + DRIVE, control.to_bytes(2, "little")
                                 + target.to_bytes(4, "little", signed=True))
            outputs = 1 << (cycle // 5)
            self.master.send_pdo(0x200 + IO, bytes([outputs]))
            self.wait(self.sync_us / 1e6)
        drive, io = self.devices[DRIVE], self.devices[IO]
        self.wait_until(lambda: self.obs.last_tpdo(IO).get("inputs") == outputs
                        and self.obs.last_tpdo(DRIVE).get("velocity") == TARGET_RPM, REACTION_S)
        problems = []
        if drive.od[0x60FF, 0] != TARGET_RPM or drive.od[0x6040, 0] != 0x000F:
            problems.append(f"drive holds target velocity {drive.od[0x60FF, 0]}, "
                            f"controlword 0x{drive.od[0x6040, 0]:04X}")
        if io.od[0x6200, 1] != outputs:
            problems.append(f"I/O module holds outputs 0x{io.od[0x6200, 1]:02X}, "
                            f"0x{outputs:02X} sent")
        fed = self.obs.last_tpdo(DRIVE)
        if fed.get("velocity") != TARGET_RPM or fed.get("statusword") != 0x0237:
            problems.append(f"drive TPDO says {fed or 'nothing'}")
        if self.obs.last_tpdo(IO).get("inputs") != outputs:
            problems.append(f"I/O module TPDO says {self.obs.last_tpdo(IO) or 'nothing'}")
        if problems:
            return False, "; ".join(problems)
        return True, (f"drive enabled (statusword 0x0237), velocity 0 -> {TARGET_RPM} rpm; "
                      f"I/O outputs 0x{outputs:02X} back as inputs")

    def emcy(self) -> tuple[bool, str]:
        drive = self.devices[DRIVE]
        if self.faults.emcy_off:
            drive.od[0x1014, 0] = 0x80000000 | (0x80 + DRIVE)
        before = len(self.obs.emcys())
        self.obs.say(self.obs.name(DRIVE), "over-temperature: raises EMCY 0x4310")
        drive.emcy_raise(EMCY_CODE, b"\x5a")

        def arrived() -> list[EmcyEvent]:
            return [e for e in self.obs.emcys(before) if e.node == DRIVE]

        self.wait_until(lambda: bool(arrived()), REACTION_S)
        got = arrived()
        if not any(e.code == EMCY_CODE for e in got):
            return False, f"no EMCY 0x{EMCY_CODE:04X} from node {DRIVE} reached the master"
        reg = next(e.register for e in got if e.code == EMCY_CODE)
        return True, (f"node {DRIVE}: 0x{EMCY_CODE:04X} {emcy_text(EMCY_CODE)}, "
                      f"error register 0x{reg:02X}")

    def heartbeat_loss(self) -> tuple[bool, str]:
        sensor = self.devices[SENSOR]
        before = len(self.obs.heartbeat_events())
        if not self.faults.keeps_beating:
            self.obs.say(self.obs.name(SENSOR), "falls silent (no heartbeat, no PDO)")
            sensor.od[0x1017, 0] = 0
            if sensor.nmt_state != "INITIALISING":  # else it never spoke at all
                sensor.nmt_apply("stop")
        def losses() -> list[HeartbeatEvent]:
            return [e for e in self.obs.heartbeat_events(before)
                    if e.node == SENSOR and e.kind == "lost"]

        self.wait_until(lambda: bool(losses()), 2 * CONSUMER_MS / 1000 + 0.1)
        lost = losses()
        if not lost:
            return False, f"the master reported no heartbeat loss of node {SENSOR}"
        return True, (f"node {SENSOR} lost after {self.consumer_ms} ms, "
                      f"last state {lost[0].state}")
