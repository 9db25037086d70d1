# SPDX-License-Identifier: Apache-2.0
"""The entries the SDO checks move values through, and what they write there.

A check writes only what the EDS guarantees an entry takes, or the entry's own value: the
strings first (their type says what they take: characters), the longest value first (the
entry holds at least that much), DOMAINs last (what a DOMAIN takes is its application's
choice: CANopenDemo's 0x2122 takes only its own byte sequence). An application's refusal
of a probe (:data:`~canola.conformance.context.APPLICATION_REFUSALS`: a value or a length
the EDS does not guarantee) is no deviation: the size is "not applicable", with the
reason, and the series goes on with the next entry; a check with no size left falls back
on the entry's own value.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from canola import SdoAbort
from canola.conformance.context import APPLICATION_REFUSALS, Context, abort_text, outcome
from canola.conformance.entries import (
    VARIABLE_TYPES,
    describe,
    fixed_size,
    plain_rw,
    readable,
    variables,
)
from canola.conformance.rawsdo import NoAnswerError, SdoProtocolError, TransferLimitError
from canola.formats import eds

__all__ = ["BLOCK_SIZES", "SIZES", "Candidate", "announced_size", "long_entry",
           "long_readable", "long_value", "probe", "same", "short_entry", "sized_series",
           "variable_entries"]

#: Value lengths around the frame boundaries: expedited (4), one segment (7), two (14).
SIZES = (1, 4, 5, 7, 8, 14, 15, 21, 22)
#: For block transfer also around a sub-block of 127 segments (889 bytes), where an entry
#: takes them.
BLOCK_SIZES = (*SIZES, 889, 890)
_PATTERN = b"canola conformance SDO probe: 0123456789 abcdefghijklmnopqrstuvwxyz"
_TOO_LONG = 0x06070012
_STRINGS = (0x0009, 0x000A, 0x000B)


def probe(size: int) -> bytes:
    """``size`` bytes of visible characters."""
    return (_PATTERN * (size // len(_PATTERN) + 1))[:size]


@dataclass
class Candidate:
    """An entry of variable length and the value it read (``value``); what the series
    learnt of it: the first length it refused as too long, whether it takes probes at all,
    the sizes it took."""

    var: eds.Variable
    value: bytes
    too_long: int | None = None
    refuses_probes: bool = False
    kept: bool = False
    took: list[int] = field(default_factory=list)


def _rw(ctx: Context) -> list[eds.Variable]:
    return [v for v in variables(ctx.od) if plain_rw(v)]


def variable_entries(ctx: Context) -> list[Candidate]:
    """The readable, writable strings and DOMAINs that read now, with their values: the
    strings first, the longest value first; the DOMAINs after them."""
    found = []
    for var in (v for v in _rw(ctx) if v.data_type in VARIABLE_TYPES):
        try:
            found.append(Candidate(var, ctx.sdo.upload(var.index, var.subindex)))
        except (SdoAbort, NoAnswerError, SdoProtocolError):
            continue  # dictionary.entries judges the read
    found.sort(key=lambda c: (c.var.data_type not in _STRINGS, -len(c.value)))
    return found


def announced_size(cand: Candidate) -> int:
    """What a segmented download to the entry announces: its type's size, else its own
    value's length (what it holds now; 1 byte at least)."""
    return fixed_size(cand.var) or max(1, len(cand.value))


def long_entry(ctx: Context) -> eds.Variable | None:
    """A readable, writable entry of fixed size above 4 bytes (segmented by nature)."""
    return next((v for v in _rw(ctx) if (fixed_size(v) or 0) > 4), None)


def short_entry(ctx: Context) -> eds.Variable | None:
    """A readable, writable entry of 1..4 bytes (0x1017 first: present nearly everywhere)."""
    found = [v for v in _rw(ctx) if 1 <= (fixed_size(v) or 0) <= 4]
    found.sort(key=lambda v: (v.index, v.subindex) != (0x1017, 0))
    return found[0] if found else None


def long_readable(ctx: Context, more_than: int = 4) -> tuple[eds.Variable, bytes] | None:
    """An entry that reads more than ``more_than`` bytes, and its value."""
    for var in variables(ctx.od):
        if not readable(var) or (fixed_size(var) or more_than + 1) <= more_than:
            continue
        try:
            data = ctx.sdo.upload(var.index, var.subindex)
        except (SdoAbort, NoAnswerError, SdoProtocolError):
            continue
        if len(data) > more_than:
            return var, data
    return None


def long_value(ctx: Context, more_than: int) -> tuple[eds.Variable, bytes] | None:
    """An entry whose value is longer than ``more_than`` bytes, and the value: a string or
    DOMAIN as it is, else one that takes a probe of 22 bytes (written back after the
    check), else any readable entry."""
    cands = variable_entries(ctx)
    for cand in cands:
        if len(cand.value) > more_than:
            return cand.var, cand.value
    data = probe(SIZES[-1])
    for cand in cands:
        _keep(ctx, cand)
        try:
            ctx.sdo.download(cand.var.index, cand.var.subindex, data)
        except SdoAbort as exc:
            if exc.code in APPLICATION_REFUSALS:
                continue
            ctx.fail(f"write {len(data)} bytes to {describe(cand.var)}", "success",
                     outcome(exc))
        except (NoAnswerError, SdoProtocolError) as exc:
            ctx.fail(f"write {len(data)} bytes to {describe(cand.var)}", "success",
                     outcome(exc))
        return cand.var, data
    return long_readable(ctx, more_than)


def same(var: eds.Variable, wrote: bytes, got: bytes) -> bool:
    """Is ``got`` what was written? Strings may come back with their padding."""
    if var.data_type != 0x000F:
        return got.rstrip(b"\0") == wrote.rstrip(b"\0")
    return got == wrote


def _keep(ctx: Context, cand: Candidate) -> None:
    """Write the entry's value back after the check (once)."""
    if not cand.kept:
        cand.kept = True
        var, value = cand.var, cand.value
        ctx.on_undo(f"write back {describe(var)}",
                    lambda: ctx.sdo.download(var.index, var.subindex, value))


def _through(ctx: Context, cand: Candidate, data: bytes, write: str, read: str) -> int | None:
    """Write ``data`` to the entry (``write``: "segmented" or "block") and read it back
    (``read``); 0 when it went through, the abort code of an application's refusal, None
    after a finding."""
    var = cand.var
    _keep(ctx, cand)
    try:
        if write == "block":
            ctx.sdo.block_download(var.index, var.subindex, data)
        else:
            ctx.sdo.download(var.index, var.subindex, data, segmented=len(data) > 4)
    except SdoAbort as exc:
        if exc.code in APPLICATION_REFUSALS:
            return exc.code
        ctx.finding(f"{write} download of {len(data)} bytes to {describe(var)}", "success",
                    outcome(exc))
        return None
    except TransferLimitError:
        raise  # a server past the tester's bounds: the check ends with it
    except (NoAnswerError, SdoProtocolError) as exc:
        ctx.finding(f"{write} download of {len(data)} bytes to {describe(var)}", "success",
                    outcome(exc))
        return None
    try:
        got = (ctx.sdo.block_upload(var.index, var.subindex)[0] if read == "block"
               else ctx.sdo.upload(var.index, var.subindex))
    except TransferLimitError:
        raise
    except (SdoAbort, NoAnswerError, SdoProtocolError) as exc:
        ctx.finding(f"{read} upload of {len(data)} bytes from {describe(var)}", "success",
                    outcome(exc))
        return None
    if not same(var, data, got):
        ctx.finding(f"read back {len(data)} bytes from {describe(var)}",
                    f"[{data.hex(' ').upper()}]", f"[{got.hex(' ').upper()}]")
        return None
    return 0


def sized_series(ctx: Context, cands: list[Candidate], write: str, read: str,
                 sizes: tuple[int, ...] = SIZES) -> None:
    """Write (``write``: segmented or block) then read back (``read``) a probe of each of
    ``sizes`` bytes, each through the first entry of ``cands`` that takes it. A size no
    entry takes (an application's refusal) is not applicable, with the reason; when none
    is taken the entry's own value goes through instead, and when that is refused too the
    check does not apply (SKIPPED)."""
    refusals: list[str] = []
    left_out: list[int] = []
    for size in sizes:
        data = probe(size)
        judged = False
        for cand in cands:
            if cand.refuses_probes or (cand.too_long is not None and size >= cand.too_long):
                continue
            code = _through(ctx, cand, data, write, read)
            if code is None or code == 0:
                judged = True
                if code == 0:
                    cand.took.append(size)
                break
            refusals.append(f"{size} bytes to {describe(cand.var)}: {abort_text(code)}")
            if code == _TOO_LONG:
                cand.too_long = size  # longer ones will not fit either
            elif code not in (0x06070010, 0x06070013):
                cand.refuses_probes = True  # the application wants other content
        if not judged:
            left_out.append(size)
    took = [c for c in cands if c.took]
    if not took and left_out:
        _own_value_through(ctx, cands, write, read, refusals)
        return
    for cand in took:
        ctx.note(f"{describe(cand.var)}: {', '.join(map(str, cand.took))} bytes")
    if left_out:
        ctx.note(f"not applicable: {', '.join(map(str, left_out))} bytes, refused by the "
                 f"application ({'; '.join(refusals[:3])})")


def _own_value_through(ctx: Context, cands: list[Candidate], write: str, read: str,
                       refusals: list[str]) -> None:
    """No probe went through: the entries' own values instead (the first taken makes the
    note); SKIPPED as not applicable when every one is refused."""
    for cand in cands:
        code = _through(ctx, cand, cand.value, write, read)
        if code is None:
            return
        if code == 0:
            ctx.note(f"{describe(cand.var)}: its own {len(cand.value)} bytes (the probes "
                     f"were refused: {'; '.join(refusals[:3])})")
            return
        refusals.append(f"its own {len(cand.value)} bytes to {describe(cand.var)}: "
                        f"{abort_text(code)}")
    ctx.skip("not applicable: the application refuses every value the tester writes "
             f"({'; '.join(refusals[:3])})")
