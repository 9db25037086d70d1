# SPDX-License-Identifier: Apache-2.0
"""PDOs from the checks' side: which PDOs the EDS has, their configuration read from the
node, and the CiA 301 re-mapping procedure (§7.5.2.36/38) to change and restore them:
invalidate (COB-ID bit 31), mapping count 0, entries, count, parameters, COB-ID valid."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from functools import partial

from canola import SdoAbort
from canola.conformance.context import Context
from canola.conformance.entries import (
    another_value,
    describe,
    fixed_size,
    mappable,
    readable,
    variables,
    writable,
)
from canola.conformance.rawsdo import NoAnswerError, SdoProtocolError
from canola.formats import eds

__all__ = [
    "INVALID",
    "PRODUCER",
    "Mapped",
    "Pdo",
    "PdoConfig",
    "SyncSource",
    "all_pdos",
    "check_values",
    "configurable",
    "configure",
    "dynamic",
    "entry_of",
    "keep",
    "mapped",
    "pdos",
    "read_config",
    "remap",
    "remappable",
    "restorable",
    "rpdo_payload",
    "sync_source",
    "tpdo_frames",
    "try_mapping",
    "usable_pdo",
    "write_config",
]

INVALID = 0x80000000
#: 0x1005 bit 30: the node produces SYNC.
PRODUCER = 0x40000000
#: Parameter sub-indices of a communication record besides the COB-ID (1).
PARAMS = (2, 3, 5, 6)


@dataclass(frozen=True)
class Pdo:
    """PDO ``n`` (0-based) of one direction: its communication and mapping indices."""

    tpdo: bool
    n: int

    @property
    def comm(self) -> int:
        return (0x1800 if self.tpdo else 0x1400) + self.n

    @property
    def mapping(self) -> int:
        return self.comm + 0x200

    @property
    def name(self) -> str:
        return f"{'TPDO' if self.tpdo else 'RPDO'}{self.n + 1}"


@dataclass
class PdoConfig:
    """A PDO's configuration as the node has it: COB-ID, parameters (sub-index -> value,
    those the EDS has), mapping count and every mapping entry the EDS has (1-based)."""

    cob: int
    params: dict[int, int] = field(default_factory=dict)
    count: int = 0
    entries: dict[int, int] = field(default_factory=dict)

    @property
    def valid(self) -> bool:
        return not self.cob & INVALID

    @property
    def mapped(self) -> list[int]:
        return [self.entries[i] for i in range(1, self.count + 1) if i in self.entries]


def pdos(ctx: Context, *, tpdo: bool) -> list[Pdo]:
    """The PDOs of a direction whose communication and mapping records the EDS has."""
    found = []
    for n in range(512):
        pdo = Pdo(tpdo, n)
        if ctx.var(pdo.comm, 1) is not None and ctx.var(pdo.mapping, 0) is not None:
            found.append(pdo)
    return found


def all_pdos(ctx: Context) -> list[Pdo]:
    """Every PDO the EDS has (:func:`pdos`): the TPDOs, then the RPDOs."""
    return pdos(ctx, tpdo=True) + pdos(ctx, tpdo=False)


def configurable(ctx: Context, pdo: Pdo) -> bool:
    """The EDS lets the COB-ID be written (every change of a PDO's configuration begins by
    making it not valid)."""
    var = ctx.var(pdo.comm, 1)
    return var is not None and writable(var)


def dynamic(ctx: Context, pdo: Pdo) -> bool:
    """The EDS lets the mapping be written (and the COB-ID: the procedure needs it)."""
    var = ctx.var(pdo.mapping, 0)
    return (var is not None and writable(var) and ctx.var(pdo.mapping, 1) is not None
            and configurable(ctx, pdo))


def _size(ctx: Context, index: int, sub: int) -> int:
    var = ctx.var(index, sub)
    return (fixed_size(var) or 4) if var is not None else 4


def read_config(ctx: Context, pdo: Pdo) -> PdoConfig:
    cfg = PdoConfig(ctx.read_uint(pdo.comm, 1))
    for sub in PARAMS:
        if ctx.var(pdo.comm, sub) is not None:
            cfg.params[sub] = ctx.read_uint(pdo.comm, sub)
    cfg.count = ctx.read_uint(pdo.mapping, 0)
    obj = ctx.od.objects[pdo.mapping]
    for sub in sorted(obj.subs):
        if sub:
            cfg.entries[sub] = ctx.read_uint(pdo.mapping, sub)
    return cfg


def default_cob(ctx: Context, pdo: Pdo, cfg: PdoConfig) -> int:
    """A valid COB-ID for the PDO: its own without bit 31, else the pre-defined one."""
    cob = cfg.cob & ~INVALID
    if cob & 0x7FF:
        return cob
    if pdo.n < 4:
        return (0x180 if pdo.tpdo else 0x200) + 0x100 * pdo.n + ctx.node_id
    ctx.skip(f"{pdo.name} has no COB-ID and none pre-defined")


def write_config(ctx: Context, pdo: Pdo, cfg: PdoConfig, *, touch_mapping: bool) -> None:
    """Write ``cfg`` by the re-mapping procedure (each step must succeed, or the check
    ends). ``touch_mapping``: write the mapping (count 0, entries, count)."""
    ctx.write_uint(pdo.comm, 1, read_cob(ctx, pdo) | INVALID, 4)
    if touch_mapping:
        ctx.write_uint(pdo.mapping, 0, 0, 1)
        for sub, entry in cfg.entries.items():
            if sub <= cfg.count:
                ctx.write_uint(pdo.mapping, sub, entry, 4)
            else:  # unused: its value back where it takes it (a node may refuse stale ones)
                ctx.try_write(pdo.mapping, sub, entry.to_bytes(4, "little"))
        ctx.write_uint(pdo.mapping, 0, cfg.count, 1)
    for sub, value in cfg.params.items():
        var = ctx.var(pdo.comm, sub)
        if var is not None and writable(var):  # a read-only one is as it was
            ctx.write_uint(pdo.comm, sub, value, _size(ctx, pdo.comm, sub))
    ctx.write_uint(pdo.comm, 1, cfg.cob, 4)


def restorable(ctx: Context, pdo: Pdo, cfg: PdoConfig) -> bool:
    """The PDO's mapping ``cfg`` is one the EDS allows (and so can be written back): its
    count within the EDS's limits and sub-indices, only entries the EDS marks PDO-mappable
    in the PDO's direction (or dummy entries, below 0x1000)."""
    count = ctx.var(pdo.mapping, 0)
    if (count is None or not _within(count, cfg.count)
            or cfg.count > max(ctx.od.objects[pdo.mapping].subs)):
        return False
    for entry in cfg.mapped:
        index, sub = entry >> 16, (entry >> 8) & 0xFF
        var = ctx.var(index, sub)
        if index >= 0x1000 and (var is None or not mappable(var, tpdo=pdo.tpdo)):
            return False
    return True


def _within(var: eds.Variable, value: int) -> bool:
    low, high = var.low, var.high
    return not ((isinstance(low, int) and value < low) or (isinstance(high, int) and value > high))


def remappable(ctx: Context, pdo: Pdo) -> bool:
    """The mapping can be changed and its own written back (:func:`dynamic`,
    :func:`restorable`)."""
    return dynamic(ctx, pdo) and restorable(ctx, pdo, read_config(ctx, pdo))


def read_cob(ctx: Context, pdo: Pdo) -> int:
    return ctx.read_uint(pdo.comm, 1)


def keep(ctx: Context, pdo: Pdo, original: PdoConfig | None = None) -> PdoConfig:
    """The PDO's configuration (``original``, else read now), written back after the
    check."""
    if original is None:
        original = read_config(ctx, pdo)
    touch = dynamic(ctx, pdo)
    ctx.on_undo(f"restore {pdo.name}",
                lambda: write_config(ctx, pdo, original, touch_mapping=touch))
    return original


def configure(ctx: Context, pdo: Pdo, *, entries: Sequence[int] | None = None,
              **params: int) -> PdoConfig:
    """Give the PDO ``entries`` (None, or its own: its mapping is not written) and
    parameters by name (``type``, ``inhibit``, ``event``, ``sync_start``), valid; restored
    after the check."""
    if not configurable(ctx, pdo):
        ctx.skip(f"the EDS has {pdo.name}'s COB-ID (0x{pdo.comm:04X}:1) read-only: its "
                 "configuration cannot be changed")
    original = read_config(ctx, pdo)
    subs = {"type": 2, "inhibit": 3, "event": 5, "sync_start": 6}
    for name, value in params.items():
        var = ctx.var(pdo.comm, subs[name])
        where = f"{pdo.name} {name} (0x{pdo.comm:04X}:{subs[name]})"
        if var is None:
            ctx.skip(f"the EDS has no {where}")
        if not writable(var) and original.params.get(subs[name]) != value:
            ctx.skip(f"the EDS has {where} read-only ({original.params.get(subs[name])}); "
                     f"the check needs {value}")
    keep(ctx, pdo, original)
    cfg = PdoConfig(default_cob(ctx, pdo, original), dict(original.params), original.count,
                    dict(original.entries))
    for name, value in params.items():
        cfg.params[subs[name]] = value
    remap = entries is not None and list(entries) != original.mapped
    if entries is not None:
        cfg.count = len(entries)
        cfg.entries.update(dict(enumerate(entries, start=1)))
    write_config(ctx, pdo, cfg, touch_mapping=remap)
    ctx.link.cobs.add(cfg.cob & 0x7FF)  # its frames are the node's
    return cfg


def remap(ctx: Context, pdo: Pdo, entries: Sequence[int]) -> PdoConfig:
    """Map ``entries`` by the whole procedure (even when they are the PDO's own), valid;
    restored after the check."""
    original = keep(ctx, pdo)
    cfg = PdoConfig(default_cob(ctx, pdo, original), dict(original.params), len(entries),
                    {**original.entries, **dict(enumerate(entries, start=1))})
    write_config(ctx, pdo, cfg, touch_mapping=True)
    return cfg


def entry_of(var: eds.Variable) -> int:
    """The mapping entry of an entry: index << 16 | sub << 8 | length in bits."""
    return var.index << 16 | var.subindex << 8 | 8 * (fixed_size(var) or 0)


@dataclass(frozen=True)
class Mapped:
    """One mapped entry of a PDO: the EDS entry (None: a dummy or unknown entry) and its
    place in the frame."""

    var: eds.Variable | None
    offset: int
    size: int


def mapped(ctx: Context, entries: Sequence[int]) -> list[Mapped]:
    """The mapped entries of a mapping, byte-aligned (bit lengths that are not whole bytes
    give None entries)."""
    out, offset = [], 0
    for entry in entries:
        bits = entry & 0xFF
        size = bits // 8
        out.append(Mapped(ctx.var(entry >> 16, (entry >> 8) & 0xFF) if bits % 8 == 0 else None,
                          offset, size))
        offset += size
    return out


def usable_pdo(ctx: Context, *, tpdo: bool, need_writable: bool = False
               ) -> tuple[Pdo, list[int]] | None:
    """A PDO of the direction and a mapping for it whose entries the EDS knows (and that
    SDO can read back, and for ``need_writable`` write): the node's own mapping when it
    fits, else the first mappable entry, where the mapping can be written. Only PDOs whose
    COB-ID can be written and whose own mapping is one the EDS allows."""
    def fits(var: eds.Variable | None) -> bool:
        return var is not None and readable(var) and (writable(var) or not need_writable) \
            and fixed_size(var) is not None

    for pdo in filter(partial(configurable, ctx), pdos(ctx, tpdo=tpdo)):
        cfg = read_config(ctx, pdo)
        entries = cfg.mapped
        if not restorable(ctx, pdo, cfg):
            continue  # a mapping unlike its EDS: pdo.remap reports it
        if entries and all(fits(m.var) for m in mapped(ctx, entries)):
            return pdo, entries
        if dynamic(ctx, pdo):
            var = next((v for v in variables(ctx.od) if mappable(v, tpdo=tpdo) and fits(v)),
                       None)
            if var is not None:
                return pdo, [entry_of(var)]
    return None


def try_mapping(ctx: Context, pdo: Pdo, entries: Sequence[int]) -> BaseException | None:
    """Invalidate the PDO and map ``entries`` (count 0, entries, count): what the first
    refused step raised, or None."""
    steps = [(pdo.comm, 1, (read_cob(ctx, pdo) | INVALID).to_bytes(4, "little")),
             (pdo.mapping, 0, b"\0"),
             *((pdo.mapping, sub, entry.to_bytes(4, "little"))
               for sub, entry in enumerate(entries, start=1)),
             (pdo.mapping, 0, bytes([len(entries)]))]
    for index, sub, data in steps:
        try:
            ctx.sdo.download(index, sub, data)
        except (SdoAbort, NoAnswerError, SdoProtocolError) as exc:
            return exc
    return None


def rpdo_payload(ctx: Context, entries: Sequence[int]
                 ) -> tuple[bytes, list[tuple[eds.Variable, bytes]]]:
    """An RPDO frame for ``entries`` whose values differ from the node's (each entry's
    :func:`~canola.conformance.entries.another_value`), and what each entry should read
    back."""
    frame = bytearray()
    expected: list[tuple[eds.Variable, bytes]] = []
    for m in mapped(ctx, entries):
        if m.var is None or m.var.data_type is None:
            frame += bytes(m.size)
            continue
        data = another_value(m.var, ctx.read(m.var.index, m.var.subindex))
        frame += data
        expected.append((m.var, data))
    return bytes(frame), expected


@dataclass
class SyncSource:
    """Sends SYNC on ``cob``: without data, or with the counter 1..``overflow`` (0x1019).
    The node takes every SYNC on ``cob``: :meth:`alone` tells whether another node sent
    one since ``since`` (a mark)."""

    ctx: Context
    cob: int
    overflow: int = 0
    counter: int = 0
    since: int = 0

    def send(self, counter: int | None = None) -> None:
        """The next SYNC (with ``counter``, when given, as its counter)."""
        if not self.overflow:
            self.ctx.link.send(self.cob)
            return
        self.counter = counter if counter is not None else self.counter % self.overflow + 1
        self.ctx.link.send(self.cob, bytes([self.counter]))

    def alone(self) -> None:
        """SKIPPED as inconclusive when another node sent SYNC on the COB-ID since the
        source began: the node under test takes every SYNC, so what it did after the
        tester's cannot be told from what it did after the other's."""
        others = self.ctx.link.frames_since(self.since, lambda f: f.can_id == self.cob)
        if others:
            self.ctx.skip(f"inconclusive: another node sends SYNC on 0x{self.cob:03X} "
                          f"({len(others)} frames during the check); the node takes them "
                          "too: run with the node alone with the tester")


def sync_source(ctx: Context) -> SyncSource:
    """The tester as the SYNC producer of the node (0x1005; SKIPPED without it: no SYNC
    consumer), with a counter when 0x1019 asks for one.
    For the check the tester is the only SYNC producer (the node's producer bit 30 off)
    and a synchronous window (0x1007) is off, where the EDS lets them be written: a node
    may drop the synchronous PDOs that come after the window (CiA 301 §7.2.5)."""
    var = ctx.need(0x1005, why="no SYNC consumer")
    cob = ctx.read_uint(0x1005, 0)
    if not cob & 0x7FF:
        ctx.skip(f"0x1005 = 0x{cob:08X}: SYNC on 0x000 (the NMT's COB-ID) cannot be sent")
    if cob & PRODUCER:
        if not writable(var):
            ctx.skip(f"the node produces SYNC itself (0x1005 = 0x{cob:08X}, read-only)")
        ctx.write_temp(0x1005, 0, (cob & ~PRODUCER).to_bytes(4, "little"))
    window = ctx.var(0x1007, 0)
    if window is not None and writable(window) and ctx.read_uint(0x1007, 0):
        ctx.write_temp(0x1007, 0, bytes(fixed_size(window) or 4))
    overflow = ctx.read_uint(0x1019, 0) if ctx.var(0x1019, 0) is not None else 0
    ctx.link.cobs.add(cob & 0x7FF)
    return SyncSource(ctx, cob & 0x7FF, overflow, since=ctx.link.mark())


def tpdos_per_sync(ctx: Context, cob: int, sync: SyncSource, counters: Sequence[int | None],
                   due: Callable[[int, list[int]], bool]) -> list[int]:
    """Send one SYNC per item of ``counters`` (its counter, or None for the next one): the
    number of TPDOs on ``cob`` after each, counted by the order of the frames on the bus
    (a TPDO belongs to the last SYNC before it), not by the time they took.
    ``due(i, counts)`` says, from the counts after the SYNCs before, whether a TPDO is due
    after SYNC ``i``: then the tester waits until it comes (up to the answer time-out), so
    that a slow node's TPDO is not taken for the next SYNC's. After each SYNC it then
    watches ``quiet`` seconds more for a TPDO too many."""
    marks: list[int] = []
    counts: list[int] = []
    for i, counter in enumerate(counters):
        if marks:
            counts.append(len(tpdo_frames(ctx, cob, marks[-1])))
        marks.append(ctx.link.mark())
        sync.send(counter)
        if due(i, counts):
            ctx.link.wait_frame(lambda f: f.can_id == cob and not f.rtr, ctx.options.timeout,
                                marks[-1])
        ctx.link.wait(ctx.options.quiet)
    sync.alone()
    ends = [*marks[1:], ctx.link.mark()]
    return [len(tpdo_frames(ctx, cob, a)) - len(tpdo_frames(ctx, cob, b))
            for a, b in zip(marks, ends, strict=True)]


def tpdo_frames(ctx: Context, cob: int, mark: int) -> list[float]:
    """The times of the TPDO frames on ``cob`` after ``mark``."""
    return [s.t for s in ctx.link.frames_since(mark, lambda f: f.can_id == cob and not f.rtr)]


def check_values(ctx: Context, expected: list[tuple[eds.Variable, bytes]], *, applied: bool,
                 when: str, judge: Callable[[], None] | None = None) -> None:
    """Read each entry back: a finding where it is (not) what the RPDO carried. ``judge``
    runs before a finding (it may end the check: SYNC from another node, say)."""
    for var, data in expected:
        got = ctx.read(var.index, var.subindex)
        if (got == data) != applied:
            if judge is not None:
                judge()
            ctx.finding(f"{describe(var)} {when}",
                        f"[{data.hex(' ').upper()}]" if applied else "its value before",
                        f"[{got.hex(' ').upper()}]")
