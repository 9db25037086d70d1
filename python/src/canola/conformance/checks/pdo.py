# SPDX-License-Identifier: Apache-2.0
"""Group ``pdo``: the mapping procedure (a valid PDO is locked, the procedure works for
every mappable entry, wrong mappings are refused), TPDO transmission types (SYNC cyclic and
acyclic, event timer, inhibit time), RPDOs applied at once or at the SYNC, an RPDO that is
too short."""

from __future__ import annotations

import statistics
from functools import partial

from canola import SdoAbort
from canola.conformance import pdo_tools as pt
from canola.conformance import timing
from canola.conformance.context import Context, abort_text, outcome
from canola.conformance.entries import (
    another_value,
    describe,
    fixed_size,
    mappable,
    readable,
    variables,
)
from canola.conformance.link import Seen
from canola.conformance.registry import check

_EVENT_MS = 100
_INHIBIT_MS = 200
_FRAMES = 8
_SYNCS = 6


def _usable(ctx: Context, *, tpdo: bool, need_writable: bool = False
            ) -> tuple[pt.Pdo, list[int]]:
    found = pt.usable_pdo(ctx, tpdo=tpdo, need_writable=need_writable)
    if found is None:
        kind = "TPDO" if tpdo else "RPDO"
        ctx.skip(f"no {kind} in the EDS maps (or can map) entries SDO can read back"
                 + (" and write" if need_writable else ""))
    return found


@check("pdo.valid_locked", clause="CiA 301 §7.5.2.35-38",
       title="a valid PDO's mapping and its COB-ID (to another valid one) cannot be changed")
def valid_locked(ctx: Context) -> None:
    tested = 0
    for pdo in pt.all_pdos(ctx):
        cfg = pt.read_config(ctx, pdo)
        if not cfg.valid:
            continue
        tested += 1
        if pt.dynamic(ctx, pdo):
            ctx.expect_abort(f"write {pdo.name} mapping count {cfg.count} while valid",
                             None, partial(ctx.sdo.download, pdo.mapping, 0, bytes([cfg.count])),
                             restore=partial(pt.write_config, ctx, pdo, cfg, touch_mapping=True))
        other = cfg.cob ^ 0x1
        ctx.expect_abort(f"change {pdo.name} COB-ID 0x{cfg.cob:X} to 0x{other:X} while valid",
                         None, partial(ctx.sdo.download, pdo.comm, 1, other.to_bytes(4, "little")),
                         restore=partial(ctx.sdo.download, pdo.comm, 1,
                                         cfg.cob.to_bytes(4, "little")))
    if not tested:
        ctx.skip("no PDO is valid")
    ctx.note(f"{tested} valid PDOs")


@check("pdo.own_mappings", clause="CiA 301 §7.5.2.36, §7.5.2.38; CiA 306 §4.5.2 (PDOMapping)",
       title="every PDO's mapping as the node has it is one its EDS allows: count within "
             "the sub-indices and limits, entries PDO-mappable in the PDO's direction")
def own_mappings(ctx: Context) -> None:
    every = pt.all_pdos(ctx)
    if not every:
        ctx.skip("the EDS has no PDO")
    for pdo in every:
        cfg = pt.read_config(ctx, pdo)
        if not pt.restorable(ctx, pdo, cfg):
            ctx.finding(f"{pdo.name}'s mapping (0x{pdo.mapping:04X})",
                        f"one the EDS allows for a {pdo.name[:4]}",
                        f"count {cfg.count}, {_hex(cfg.mapped)}")
    ctx.note(f"{len(every)} PDOs")


@check("pdo.remap", clause="CiA 301 §7.5.2.36, §7.5.2.38 (mapping procedure)",
       title="invalidate, count 0, entries, count, validate works on every PDO with a "
             "writable mapping, and the mapping reads back")
def remap(ctx: Context) -> None:
    tested = []
    for pdo in pt.all_pdos(ctx):
        if not pt.dynamic(ctx, pdo):
            continue
        cfg = pt.read_config(ctx, pdo)
        if not pt.restorable(ctx, pdo, cfg):
            continue  # it could not be written back (pdo.own_mappings reports it)
        entries = cfg.mapped
        if not entries:
            var = next((v for v in variables(ctx.od) if mappable(v, tpdo=pdo.tpdo)), None)
            if var is None:
                continue
            entries = [pt.entry_of(var)]
        got = pt.remap(ctx, pdo, entries)
        again = pt.read_config(ctx, pdo)
        if again.mapped != entries or again.cob != got.cob:
            ctx.finding(f"{pdo.name} after the procedure",
                        f"count {len(entries)}, {_hex(entries)}, COB-ID 0x{got.cob:X}",
                        f"count {again.count}, {_hex(again.mapped)}, COB-ID 0x{again.cob:X}")
        tested.append(pdo.name)
    if not tested:
        ctx.skip("no PDO has a writable mapping and a mappable entry")
    ctx.note(", ".join(tested))


def _hex(entries: list[int]) -> str:
    return "[" + " ".join(f"{e:08X}" for e in entries) + "]"


@check("pdo.map_every_mappable", clause="CiA 301 §7.5.2.36, §7.5.2.38; CiA 306 §4.5.2 "
       "(PDOMapping)", title="every entry the EDS marks PDO-mappable can be mapped (a TPDO "
       "for readable entries, an RPDO for writable ones)")
def map_every_mappable(ctx: Context) -> None:
    tested = 0
    for tpdo in (True, False):
        pdo = next((p for p in pt.pdos(ctx, tpdo=tpdo) if pt.remappable(ctx, p)), None)
        candidates = [v for v in variables(ctx.od) if mappable(v, tpdo=tpdo)]
        if pdo is None or not candidates:
            continue
        pt.keep(ctx, pdo)
        for var in candidates:
            tested += 1
            exc = pt.try_mapping(ctx, pdo, [pt.entry_of(var)])
            if exc is not None:
                ctx.finding(f"map {describe(var)} into {pdo.name}", "success", outcome(exc))
    if not tested:
        ctx.skip("no PDO with a writable mapping, or no mappable entry")
    ctx.note(f"{tested} mappings")


@check("pdo.map_refused", clause="CiA 301 §7.5.2.36, §7.5.2.38",
       title="mapping a non-mappable entry is refused (0x06040041), more than 64 bits too "
             "(0x06040042)")
def map_refused(ctx: Context) -> None:
    pdo = next((p for p in pt.all_pdos(ctx) if pt.remappable(ctx, p)), None)
    if pdo is None:
        ctx.skip("no PDO has a writable mapping (and its own mapping of PDO-mappable "
                 "entries)")
    pt.keep(ctx, pdo)
    subs = max(ctx.od.objects[pdo.mapping].subs)
    plain = next((v for v in variables(ctx.od) if not v.pdo_mapping and fixed_size(v)
                  and readable(v) and 1 <= (fixed_size(v) or 0) <= 4), None)
    tested = []
    if plain is not None:
        tested.append(describe(plain))
        _refused(ctx, pdo, [pt.entry_of(plain)], 0x06040041,
                 f"map {describe(plain)} (PDOMapping=0) into {pdo.name}")
    big: list[int] = []
    for var in variables(ctx.od):
        if mappable(var, tpdo=pdo.tpdo) and sum((e & 0xFF) for e in big) <= 64:
            big.append(pt.entry_of(var))
    if sum(e & 0xFF for e in big) > 64 and len(big) <= subs:
        tested.append(f"{sum(e & 0xFF for e in big)} bits")
        _refused(ctx, pdo, big, 0x06040042,
                 f"map {sum(e & 0xFF for e in big)} bits {_hex(big)} into {pdo.name}")
    if not tested:
        ctx.skip("no non-mappable entry and not enough mappable ones to exceed 64 bits")
    ctx.note("; ".join(tested))


def _refused(ctx: Context, pdo: pt.Pdo, entries: list[int], code: int, what: str) -> None:
    exc = pt.try_mapping(ctx, pdo, entries)
    if not (isinstance(exc, SdoAbort) and exc.code == code):
        ctx.finding(what, abort_text(code), outcome(exc))


def _every_second(i: int, counts: list[int]) -> bool:
    """Type 2: a TPDO after every second SYNC. Whether after the first is the node's choice
    (the tester waits for it); then the others follow from it."""
    return i == 0 or (i % 2 == 0) == (counts[0] > 0)


@check("pdo.tpdo_sync_cyclic", clause="CiA 301 §7.2.2, §7.5.2.37 (transmission type 1..240)",
       title="a TPDO of type 2 comes after every second SYNC, only then, with its mapped "
             "length")
def tpdo_sync_cyclic(ctx: Context) -> None:
    pdo, entries = _usable(ctx, tpdo=True)
    cfg = pt.configure(ctx, pdo, entries=entries, type=2)
    cob = cfg.cob & 0x7FF
    sync = pt.sync_source(ctx)
    ctx.enter("start")
    mark = ctx.link.mark()
    counts = pt.tpdos_per_sync(ctx, cob, sync, [None] * _SYNCS, _every_second)
    if counts not in ([0, 1] * 3, [1, 0] * 3):
        ctx.finding(f"{pdo.name} (type 2) after each of {_SYNCS} SYNCs",
                    "1 every second SYNC: 0 1 0 1 0 1", " ".join(map(str, counts)))
    size = sum(e & 0xFF for e in entries) // 8
    for s in ctx.link.frames_since(mark, lambda f: f.can_id == cob):
        if len(s.frame.data) != size:
            ctx.finding(f"{pdo.name} frame", f"{size} bytes", f"{len(s.frame.data)} bytes")
            break
    ctx.note(f"{pdo.name} on 0x{cob:03X}: {' '.join(map(str, counts))}")


@check("pdo.tpdo_sync_acyclic", clause="CiA 301 §7.2.2, §7.5.2.37 (transmission type 0)",
       title="a TPDO of type 0 whose data changed comes after the next SYNC, not before")
def tpdo_sync_acyclic(ctx: Context) -> None:
    pdo, entries = _usable(ctx, tpdo=True, need_writable=True)
    cfg = pt.configure(ctx, pdo, entries=entries, type=0)
    cob = cfg.cob & 0x7FF
    sync = pt.sync_source(ctx)
    var = pt.mapped(ctx, entries)[0].var
    assert var is not None
    original = ctx.keep(var.index, var.subindex)
    ctx.enter("start")
    sync.send()
    ctx.link.wait(ctx.options.quiet)
    changed = another_value(var, original)
    ctx.write(var.index, var.subindex, changed)
    # from the write's answer on: a TPDO of the SYNC before, however late, came before it
    mark = ctx.link.mark()
    ctx.link.wait(ctx.options.quiet)
    early = pt.tpdo_frames(ctx, cob, mark)
    sync.alone()
    if early:
        ctx.finding(f"{pdo.name} (type 0) after a change of {describe(var)}, before a SYNC",
                    "no frame until the SYNC", f"{len(early)} frames")
    mark = ctx.link.mark()
    sync.send()
    seen = ctx.link.wait_frame(lambda f: f.can_id == cob, ctx.options.timeout, mark)
    sync.alone()
    if seen is None and not early:
        ctx.skip(f"{pdo.name} of type 0 was not sent after {describe(var)} changed by SDO: "
                 "the node may need an application event the tester cannot cause")
    ctx.note(f"{pdo.name} on 0x{cob:03X} after the SYNC")


def _measure(ctx: Context, cob: int, count: int, period: float) -> list[Seen]:
    """The next ``count`` + 1 frames on ``cob`` (fewer when they did not come)."""
    return timing.periodic(ctx, lambda f: f.can_id == cob and not f.rtr, count + 1, period)


def _event_driven(ctx: Context, pdo: pt.Pdo, entries: list[int], **params: int) -> int:
    """Configure an event-driven TPDO (type 255); its COB-ID."""
    return pt.configure(ctx, pdo, entries=entries, type=255, **params).cob & 0x7FF


@check("pdo.tpdo_event_timer", clause="CiA 301 §7.2.2, §7.5.2.37 (type 255, event timer)",
       title="an event-driven TPDO with a 100 ms event timer comes every 100 ms (median within "
             "the tolerance) in OPERATIONAL")
def tpdo_event_timer(ctx: Context) -> None:
    pdo, entries = _usable(ctx, tpdo=True)
    cob = _event_driven(ctx, pdo, entries, event=_EVENT_MS, **_no_inhibit(ctx, pdo))
    ctx.enter("start")
    p = _EVENT_MS / 1000
    tol = ctx.options.tolerance

    def measure() -> timing.Measured:
        seen = _measure(ctx, cob, _FRAMES, p)
        if len(seen) <= _FRAMES:
            ctx.fail(f"{pdo.name} with event timer {_EVENT_MS} ms", f"{_FRAMES + 1} frames",
                     f"{len(seen)}")
        measured = timing.Measured(seen)
        measured.median_near(f"median interval of {pdo.name} (event timer {_EVENT_MS} ms)", p,
                             tol)
        return measured

    gaps = timing.judged(ctx, p, f"{pdo.name} came off its event timer", measure).gaps
    ctx.note(f"{pdo.name}: median {statistics.median(gaps) * 1000:.1f} ms over {len(gaps)} "
             "intervals")


def _no_inhibit(ctx: Context, pdo: pt.Pdo) -> dict[str, int]:
    return {"inhibit": 0} if ctx.var(pdo.comm, 3) is not None else {}


@check("pdo.tpdo_inhibit", clause="CiA 301 §7.2.2, §7.5.2.37 (inhibit time)",
       title="an event-driven TPDO keeps its inhibit time (200 ms) under a 50 ms event timer")
def tpdo_inhibit(ctx: Context) -> None:
    pdo, entries = _usable(ctx, tpdo=True)
    cob = _event_driven(ctx, pdo, entries, event=_EVENT_MS // 2, inhibit=_INHIBIT_MS * 10)
    ctx.enter("start")
    p = _INHIBIT_MS / 1000
    floor = p * (1 - ctx.options.tolerance)

    def measure() -> timing.Measured:
        seen = _measure(ctx, cob, 4, p)
        if len(seen) <= 4:
            ctx.fail(f"{pdo.name} with event timer {_EVENT_MS // 2} ms, inhibit {_INHIBIT_MS}"
                     " ms", "5 frames", f"{len(seen)}")
        measured = timing.Measured(seen)
        # the median: two frames a stalled tester read at once look close, a node that
        # ignores its inhibit time sends every 50 ms
        middle = statistics.median(measured.gaps)
        if middle < floor:
            measured.problems.append((f"median interval of {pdo.name} (inhibit {_INHIBIT_MS}"
                                      " ms)", f"at least {floor * 1000:.0f} ms",
                                      f"{middle * 1000:.1f} ms"))
        return measured

    gaps = timing.judged(ctx, p, f"{pdo.name} came sooner than its inhibit time", measure).gaps
    ctx.note(f"{pdo.name}: {min(gaps) * 1000:.1f}..{max(gaps) * 1000:.1f} ms")


def _rpdo(ctx: Context, **params: int) -> tuple[pt.Pdo, int, list[int]]:
    pdo, entries = _usable(ctx, tpdo=False, need_writable=True)
    cfg = pt.configure(ctx, pdo, entries=entries, **params)
    for m in pt.mapped(ctx, entries):
        if m.var is not None:
            ctx.keep(m.var.index, m.var.subindex)
    return pdo, cfg.cob & 0x7FF, entries


@check("pdo.rpdo_applied", clause="CiA 301 §7.2.2, §7.5.2.35 (type 255)",
       title="an event-driven RPDO's data is applied at once (read back by SDO)")
def rpdo_applied(ctx: Context) -> None:
    pdo, cob, entries = _rpdo(ctx, type=255)
    ctx.enter("start")
    frame, expected = pt.rpdo_payload(ctx, entries)
    ctx.link.send(cob, frame)
    pt.check_values(ctx, expected, applied=True, when=f"after {pdo.name} [{frame.hex(' ')}]")
    ctx.note(f"{pdo.name} on 0x{cob:03X}: {', '.join(describe(v) for v, _ in expected)}")


@check("pdo.rpdo_sync", clause="CiA 301 §7.2.2, §7.5.2.35 (type 0..240)",
       title="a synchronous RPDO's data is applied at the next SYNC, not before")
def rpdo_sync(ctx: Context) -> None:
    pdo, cob, entries = _rpdo(ctx, type=1)
    sync = pt.sync_source(ctx)
    ctx.enter("start")
    frame, expected = pt.rpdo_payload(ctx, entries)
    ctx.link.send(cob, frame)
    pt.check_values(ctx, expected, applied=False, when=f"after {pdo.name} (type 1), before SYNC",
                    judge=sync.alone)
    sync.send()
    pt.check_values(ctx, expected, applied=True, when=f"after {pdo.name} (type 1) and a SYNC",
                    judge=sync.alone)
    ctx.note(f"{pdo.name} on 0x{cob:03X}")


@check("pdo.rpdo_length", clause="CiA 301 §7.2.2, §7.2.7 (EMCY 0x8210)",
       title="an RPDO shorter than its mapping is not applied and, where the node has "
             "EMCY, reported with EMCY 0x8210")
def rpdo_length(ctx: Context) -> None:
    pdo, cob, entries = _rpdo(ctx, type=255)
    ctx.enter("start")
    frame, expected = pt.rpdo_payload(ctx, entries)
    emcy = ctx.read_uint(0x1014, 0) if ctx.var(0x1014, 0) is not None else None
    mark = ctx.link.mark()
    ctx.link.send(cob, frame[:-1])
    pt.check_values(ctx, expected, applied=False,
                 when=f"after {pdo.name} of {len(frame) - 1} bytes (mapping: {len(frame)})")
    if emcy is None or emcy & pt.INVALID:
        ctx.note("no EMCY producer: EMCY not expected")
        return
    seen = ctx.link.wait_frame(lambda f: f.can_id == emcy & 0x7FF and f.data[:2] == b"\x10\x82",
                               ctx.options.timeout, mark)
    if seen is None:
        ctx.finding(f"EMCY after {pdo.name} of {len(frame) - 1} bytes",
                    f"EMCY 0x8210 on 0x{emcy & 0x7FF:03X}", "none")
    ctx.link.send(cob, frame)  # a right one: a node may clear the error with it
    ctx.note(f"{pdo.name} on 0x{cob:03X}")
