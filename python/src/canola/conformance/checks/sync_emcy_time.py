# SPDX-License-Identifier: Apache-2.0
"""Groups ``sync``, ``emcy`` and ``time``: the SYNC counter (0x1019) as consumer and
producer, a TPDO's SYNC start value; EMCY on a heartbeat consumer time-out (0x1014 COB-ID,
0x1001, 0x1003 and its clearing); the TIME consumer setting (0x1012)."""

from __future__ import annotations

import statistics
from functools import partial

from canola.conformance import pdo_tools as pt
from canola.conformance import timing
from canola.conformance.context import Context, outcome
from canola.conformance.entries import writable
from canola.conformance.link import Seen
from canola.conformance.registry import check

__all__ = ["heartbeat_loss"]

_SYNC_US = 100_000
_SYNC_US_LEAST = 10_000
_SYNC_FRAMES = 7
_CONSUMER_MS = 200
#: 0x1012 bit 31: the node consumes TIME.
_CONSUMER = 0x80000000


def _writable_entry(ctx: Context, index: int, why: str) -> None:
    var = ctx.need(index, why=why)
    if not writable(var):
        ctx.skip(f"0x{index:04X} is not writable in the EDS ({why})")


def _keep_counter(ctx: Context) -> None:
    """Keep 0x1019 and 0x1006 for the check, 0x1006 at 0 now (0x1019 changes only then),
    and write them back in that order too: 0x1006 to 0, 0x1019, 0x1006."""
    period = ctx.var(0x1006, 0)
    stoppable = period is not None and writable(period)
    if stoppable:
        ctx.keep(0x1006, 0)
    ctx.keep(0x1019, 0)
    if stoppable:
        ctx.on_undo("write 0 to 0x1006:0 (0x1019 changes only then)",
                    partial(ctx.sdo.download, 0x1006, 0, bytes(4)))
        ctx.write(0x1006, 0, bytes(4))


def _period_us(ctx: Context) -> int:
    """The SYNC period for the producer check: 100 ms, or 0x1006's HighLimit when lower
    (SKIPPED below 10 ms)."""
    high = ctx.need(0x1006, why="communication cycle period").high
    period = min(_SYNC_US, high) if isinstance(high, int) else _SYNC_US
    if period < _SYNC_US_LEAST:
        ctx.skip(f"0x1006's HighLimit {period} µs is below the {_SYNC_US_LEAST} µs the check "
                 "can time")
    return period


@check("sync.counter_overflow", clause="CiA 301 §7.2.5, §7.5.2.22",
       title="0x1019 takes 0 and 2..240 and refuses 1 and 241 (0x06090030)")
def counter_overflow(ctx: Context) -> None:
    _writable_entry(ctx, 0x1019, "SYNC counter overflow")
    _keep_counter(ctx)
    for value in (1, 241):
        ctx.expect_abort(f"write {value} to 0x1019", (0x06090030,),
                         partial(ctx.sdo.download, 0x1019, 0, bytes([value])))
    for value in (2, 240, 0):
        ctx.write(0x1019, 0, bytes([value]))
        if ctx.read_uint(0x1019) != value:
            ctx.finding(f"read back 0x1019 after writing {value}", f"{value}",
                        f"{ctx.read_uint(0x1019)}")


@check("sync.producer", clause="CiA 301 §7.2.5, §7.5.2.5, §7.5.2.6, §7.5.2.22",
       title="as SYNC producer (0x1005 bit 30, 0x1006 100 ms or its HighLimit if lower) the "
             "node sends SYNC at the period, its counter running 1..0x1019")
def producer(ctx: Context) -> None:
    _writable_entry(ctx, 0x1005, "SYNC COB-ID")
    _writable_entry(ctx, 0x1006, "communication cycle period")
    period_us = _period_us(ctx)
    counter = ctx.var(0x1019, 0) is not None and writable(ctx.need(0x1019, why="counter"))
    if counter:
        _keep_counter(ctx)
        ctx.write(0x1019, 0, bytes([3]))
    else:
        ctx.keep(0x1006, 0)
    cob = ctx.keep(0x1005, 0)  # written back first: the producer stops
    sync = int.from_bytes(cob, "little") & 0x7FF
    ctx.link.cobs.add(sync)
    ctx.write_uint(0x1005, 0, sync, 4)  # the node's own producer off for a moment
    ctx.write_uint(0x1006, 0, period_us, 4)
    mark = ctx.link.mark()
    ctx.link.wait(ctx.options.quiet)  # SYNC while the node's producer is off: another's
    others = ctx.link.frames_since(mark, lambda f: f.can_id == sync)
    if others:
        ctx.skip(f"inconclusive: another node sends SYNC on 0x{sync:03X} ({len(others)} "
                 "frames before the node's producer was on): the node's SYNC frames cannot "
                 "be told from the other's; run with the node alone with the tester")
    mark = ctx.link.mark()
    error = ctx.try_write(0x1005, 0, (sync | pt.PRODUCER).to_bytes(4, "little"))
    if error is not None:
        ctx.skip(f"0x1005 refuses the producer bit ({outcome(error)}): not a SYNC producer")
    p = period_us / 1e6
    tol = ctx.options.tolerance
    marks = [mark]  # the first measurement from the producer's start, the others from now

    def measure() -> timing.Measured:
        since = marks.pop() if marks else ctx.link.mark()
        seen = timing.periodic(ctx, lambda f: f.can_id == sync, _SYNC_FRAMES, p, since)
        if len(seen) < _SYNC_FRAMES:
            ctx.fail(f"SYNC frames on 0x{sync:03X} (period {p * 1000:g} ms)",
                     f"{_SYNC_FRAMES}", f"{len(seen)}")
        measured = timing.Measured(seen)
        measured.median_near("median SYNC interval", p, tol)
        return measured

    measured = timing.judged(ctx, p, "SYNC came off its period", measure)
    if counter:
        counters = [s.frame.data[0] if len(s.frame.data) == 1 else -1 for s in measured.seen]
        start = counters[0]
        wanted = [(start - 1 + i) % 3 + 1 for i in range(len(counters))]
        if counters != wanted or start not in (1, 2, 3):
            ctx.finding("SYNC counters (0x1019 = 3)", "1 2 3 1 2 3 ...",
                        " ".join(map(str, counters)))
    gaps = measured.gaps
    ctx.note(f"median {statistics.median(gaps) * 1000:.1f} ms over {len(gaps)} intervals")


@check("sync.start_value", clause="CiA 301 §7.2.5, §7.5.2.37 (SYNC start value)",
       title="a TPDO of type 1 with SYNC start value 3 starts at the SYNC whose counter is 3")
def start_value(ctx: Context) -> None:
    _writable_entry(ctx, 0x1019, "SYNC counter overflow")
    pdo, entries = pt.usable_pdo(ctx, tpdo=True) or ctx.skip(
        "no TPDO in the EDS maps (or can map) entries")
    if ctx.var(pdo.comm, 6) is None:
        ctx.skip(f"the EDS has no SYNC start value for {pdo.name}")
    _keep_counter(ctx)
    ctx.write(0x1019, 0, bytes([5]))
    cob = pt.configure(ctx, pdo, entries=entries, type=1, sync_start=3).cob & 0x7FF
    sync = pt.sync_source(ctx)
    ctx.enter("start")
    counts = pt.tpdos_per_sync(ctx, cob, sync, (1, 2, 3, 4, 5, 1), lambda i, _: i >= 2)
    if counts != [0, 0, 1, 1, 1, 1]:
        ctx.finding(f"{pdo.name} after SYNCs with counters 1 2 3 4 5 1",
                    "0 0 1 1 1 1", " ".join(map(str, counts)))
    ctx.note(f"{pdo.name}: {' '.join(map(str, counts))}")


def heartbeat_loss(ctx: Context) -> tuple[int, Seen | None]:
    """Let the node consume the tester's heartbeat (0x1016:1, 200 ms), send one, then stop:
    the EMCY COB-ID and the EMCY 0x8130 the node sent (None: none within the time)."""
    var = ctx.need(0x1016, 1, why="no heartbeat consumer to cause an EMCY with")
    if not writable(var):
        ctx.skip("0x1016:1 is not writable: no heartbeat consumer to cause an EMCY with")
    ctx.need(0x1014, why="no EMCY producer")
    emcy = ctx.read_uint(0x1014)
    if emcy & pt.INVALID:
        ctx.skip(f"the EMCY producer is off (0x1014 = 0x{emcy:08X})")
    cob = emcy & 0x7FF
    ctx.link.cobs.add(cob)
    tester = ctx.link.master.node_id
    ctx.write_temp(0x1016, 1, (tester << 16 | _CONSUMER_MS).to_bytes(4, "little"))
    mark = ctx.link.mark()
    ctx.link.send(0x700 + tester, b"\x05")
    limit = _CONSUMER_MS / 1000 * (1 + 2 * ctx.options.tolerance) + ctx.options.timeout
    seen = ctx.link.wait_frame(lambda f: f.can_id == cob and f.data[:2] == b"\x30\x81", limit,
                               mark)
    return cob, seen


@check("emcy.heartbeat_loss", clause="CiA 301 §7.2.7, §7.2.8.3.2.2, §7.5.2.2, §7.5.2.17",
       title="a heartbeat consumer time-out gives EMCY 0x8130 on 0x1014's COB-ID, its error "
             "register byte that of 0x1001 with the generic bit")
def heartbeat_loss_emcy(ctx: Context) -> None:
    cob, seen = heartbeat_loss(ctx)
    if seen is None:
        ctx.fail(f"heartbeat of node {ctx.link.master.node_id} lost ({_CONSUMER_MS} ms)",
                 f"EMCY 0x8130 on 0x{cob:03X}", "none")
    data = seen.frame.data
    register = ctx.read_uint(0x1001)
    if len(data) != 8:
        ctx.finding("EMCY frame", "8 bytes", f"{len(data)} bytes")
    elif data[2] != register or not register & 1:
        ctx.finding("EMCY error register byte", f"0x1001 (now 0x{register:02X}), generic bit "
                    "set", f"0x{data[2]:02X}", clause="CiA 301 §7.5.2.2: bit 0 (generic "
                    "error) is set with any error; the EMCY carries 0x1001 (§7.2.7)")
    ctx.note(f"EMCY on 0x{cob:03X}, register 0x{data[2]:02X}")


@check("emcy.error_history", clause="CiA 301 §7.5.2.4",
       title="0x1003 records the error (sub 1 = 0x8130); writing 0 to sub 0 clears it, "
             "other values are refused (0x06090030)")
def error_history(ctx: Context) -> None:
    field = ctx.need(0x1003, 0, why="no pre-defined error field")
    ctx.need(0x1003, 1, why="no pre-defined error field")
    _, seen = heartbeat_loss(ctx)
    if seen is None:
        ctx.fail("heartbeat loss", "EMCY 0x8130 (the error to record)", "none")
    count = ctx.read_uint(0x1003, 0)
    newest = ctx.read_uint(0x1003, 1) if count else 0
    if count < 1 or newest & 0xFFFF != 0x8130:
        ctx.finding("0x1003 after EMCY 0x8130", "sub 0 >= 1, sub 1 & 0xFFFF = 0x8130",
                    f"sub 0 = {count}, sub 1 = 0x{newest:08X}")
    if not writable(field):  # CiA 301 §7.5.2.4: rw, writing 0 clears
        ctx.fail("0x1003:0 in the EDS", "rw (writing 0 clears the history)",
                 str(field.access_type))
    ctx.expect_abort("write 1 to 0x1003:0", (0x06090030,),
                     lambda: ctx.sdo.download(0x1003, 0, b"\x01"))
    ctx.write(0x1003, 0, b"\0")
    if ctx.read_uint(0x1003, 0) != 0:
        ctx.finding("0x1003:0 after writing 0", "0", f"{ctx.read_uint(0x1003, 0)}")
    ctx.note(f"{count} errors recorded, newest 0x{newest:08X}")


@check("emcy.cob_id", clause="CiA 301 §7.5.2.17",
       title="0x1014 refuses another COB-ID while valid, takes it through bit 31, and the "
             "next EMCY uses it")
def cob_id(ctx: Context) -> None:
    _writable_entry(ctx, 0x1014, "COB-ID EMCY")
    original = ctx.read_uint(0x1014)
    if original & pt.INVALID:
        ctx.skip(f"the EMCY producer is off (0x1014 = 0x{original:08X})")

    def back() -> None:  # a valid COB-ID changes through "not valid"
        for value in (original | pt.INVALID, original):
            ctx.sdo.download(0x1014, 0, value.to_bytes(4, "little"))

    ctx.on_undo("write back 0x1014:0", back)
    other = 0x80 + (ctx.node_id % 127) + 1
    ctx.expect_abort(f"write 0x{other:X} to 0x1014 while 0x{original:X} is valid", None,
                     lambda: ctx.sdo.download(0x1014, 0, other.to_bytes(4, "little")),
                     restore=lambda: ctx.sdo.download(0x1014, 0, original.to_bytes(4, "little")))
    ctx.write_uint(0x1014, 0, original | pt.INVALID, 4)
    ctx.write_uint(0x1014, 0, other | pt.INVALID, 4)
    ctx.write_uint(0x1014, 0, other, 4)
    if ctx.var(0x1016, 1) is None:
        ctx.note("no heartbeat consumer to cause an EMCY with: the COB-ID change only")
        return
    cob, seen = heartbeat_loss(ctx)
    if seen is None:
        ctx.finding("EMCY after the change of 0x1014", f"EMCY 0x8130 on 0x{other:03X}",
                    "none")
    ctx.note(f"EMCY moved to 0x{cob:03X}")


@check("time.consumer", clause="CiA 301 §7.2.6, §7.5.2.15",
       title="0x1012 takes the consumer bit; TIME frames are taken without EMCY and the node "
             "keeps answering")
def time_consumer(ctx: Context) -> None:
    var = ctx.need(0x1012, why="no TIME object")
    value = ctx.read_uint(0x1012)
    if not value & _CONSUMER:
        if not writable(var):
            ctx.skip("0x1012 is read-only without the consumer bit: no TIME consumer")
        ctx.write_temp(0x1012, 0, ((value & 0x3FFFFFFF) | _CONSUMER).to_bytes(4, "little"))
        if not ctx.read_uint(0x1012) & _CONSUMER:
            ctx.finding("0x1012 after setting bit 31", "bit 31 set",
                        f"0x{ctx.read_uint(0x1012):08X}")
    cob = value & 0x7FF
    mark = ctx.link.mark()
    ctx.link.send(cob, bytes.fromhex("D00700000100"))
    ctx.link.wait(ctx.options.quiet)
    emcys = ctx.link.frames_since(mark, lambda f: 0x81 <= f.can_id <= 0xFF
                                  and f.can_id & 0x7F == ctx.node_id)
    if emcys:
        ctx.finding(f"TIME frame on 0x{cob:03X}", "no EMCY",
                    f"[{emcys[0].frame.data.hex(' ').upper()}]")
    ctx.served("after the TIME frame")
    ctx.note(f"TIME on 0x{cob:03X}: what the node does with it is not visible over CANopen")

