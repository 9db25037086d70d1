# SPDX-License-Identifier: Apache-2.0
"""Group ``sdo``: the SDO server frame by frame -- expedited, segmented and block transfer
both ways at sizes around the frame boundaries, wrong toggle bit, unknown command
specifier, client abort, block CRC and block size, the server's own time-out."""

from __future__ import annotations

from collections.abc import Callable
from functools import partial
from typing import TypeVar

from canola import SdoAbort
from canola.conformance.context import Context, abort_text, outcome
from canola.conformance.entries import (
    VARIABLE_TYPES,
    describe,
    fixed_size,
    plain_rw,
    readable,
    variables,
)
from canola.conformance.rawsdo import NoAnswerError, SdoProtocolError
from canola.conformance.registry import check
from canola.formats import eds

#: Value lengths around the frame boundaries: expedited (4), one segment (7), two (14).
SIZES = (1, 4, 5, 7, 8, 14, 15, 21, 22)
#: For block transfer also around a sub-block of 127 segments (889 bytes), where the
#: entry takes them.
BLOCK_SIZES = (*SIZES, 889, 890)
T = TypeVar("T")
_PATTERN = b"canola conformance SDO probe: 0123456789 abcdefghijklmnopqrstuvwxyz"


def _probe(size: int) -> bytes:
    return (_PATTERN * (size // len(_PATTERN) + 1))[:size]


def _rw(ctx: Context) -> list[eds.Variable]:
    return [v for v in variables(ctx.od) if plain_rw(v)]


#: Preference among the entries of variable length: DOMAIN, then the strings (an
#: OCTET_STRING is often of fixed length).
_VARIABLE_ORDER = (0x000F, 0x0009, 0x000B, 0x000A)


def variable_entry(ctx: Context) -> eds.Variable | None:
    """A readable, writable DOMAIN or string (its length is the value's) that reads now
    (what a check writes to it is written back)."""
    found = [v for v in _rw(ctx) if v.data_type in VARIABLE_TYPES]
    found.sort(key=lambda v: _VARIABLE_ORDER.index(v.data_type or 0x000F))
    for var in found:
        try:
            ctx.sdo.upload(var.index, var.subindex)
        except (SdoAbort, NoAnswerError, SdoProtocolError):
            continue
        return var
    return None


def long_entry(ctx: Context) -> eds.Variable | None:
    """A readable, writable entry of fixed size above 4 bytes (segmented by nature)."""
    return next((v for v in _rw(ctx) if (fixed_size(v) or 0) > 4), None)


def short_entry(ctx: Context) -> eds.Variable | None:
    """A readable, writable entry of 1..4 bytes (0x1017 first: present nearly everywhere)."""
    found = [v for v in _rw(ctx) if 1 <= (fixed_size(v) or 0) <= 4]
    found.sort(key=lambda v: (v.index, v.subindex) != (0x1017, 0))
    return found[0] if found else None


def _long_candidates(ctx: Context) -> list[eds.Variable]:
    """Readable entries that may read more than 4 bytes."""
    return [v for v in variables(ctx.od)
            if readable(v) and (fixed_size(v) is None or (fixed_size(v) or 0) > 4)]


def long_readable(ctx: Context) -> tuple[eds.Variable, bytes] | None:
    """An entry that reads more than 4 bytes (segmented), and its value."""
    for var in _long_candidates(ctx):
        try:
            data = ctx.sdo.upload(var.index, var.subindex)
        except (SdoAbort, NoAnswerError, SdoProtocolError):
            continue
        if len(data) > 4:
            return var, data
    return None


def _same(var: eds.Variable, wrote: bytes, got: bytes) -> bool:
    if var.data_type != 0x000F:  # strings may come back with their padding
        return got.rstrip(b"\0") == wrote.rstrip(b"\0")
    return got == wrote


def _sized_series(ctx: Context, var: eds.Variable, write: str, read: str,
                  sizes: tuple[int, ...] = SIZES) -> None:
    """Write (``write``: segmented or block) then read back (``read``: segmented or
    block) values of each of ``sizes`` bytes; the sizes that went through make the note. A
    value too long for the entry (0x06070012) ends the series once more than a segment
    went."""
    ctx.keep(var.index, var.subindex)
    done: list[int] = []
    for size in sizes:
        data = _probe(size)
        try:
            if write == "block":
                ctx.sdo.block_download(var.index, var.subindex, data)
            else:
                ctx.sdo.download(var.index, var.subindex, data, segmented=size > 4)
        except SdoAbort as exc:
            if exc.code == 0x06070012 and done and done[-1] >= 8:
                break  # the entry is full: it took more than one segment's worth
            ctx.finding(f"{write} download of {size} bytes to {describe(var)}", "success",
                        outcome(exc))
            continue
        except (NoAnswerError, SdoProtocolError) as exc:
            ctx.finding(f"{write} download of {size} bytes to {describe(var)}", "success",
                        outcome(exc))
            continue
        try:
            got = (ctx.sdo.block_upload(var.index, var.subindex)[0] if read == "block"
                   else ctx.sdo.upload(var.index, var.subindex))
        except (SdoAbort, NoAnswerError, SdoProtocolError) as exc:
            ctx.finding(f"{read} upload of {size} bytes from {describe(var)}", "success",
                        outcome(exc))
            continue
        if not _same(var, data, got):
            ctx.finding(f"read back {size} bytes from {describe(var)}",
                        f"[{data.hex(' ').upper()}]", f"[{got.hex(' ').upper()}]")
            continue
        done.append(size)
    ctx.note(f"{describe(var)}: {', '.join(map(str, done))} bytes")


def _own_value(ctx: Context, var: eds.Variable, how: str,
               download: Callable[[bytes], T]) -> tuple[bytes, T]:
    """Write the entry's own value back to it by ``download`` (nothing changes); the value
    and what ``download`` gave. A failure ends the check."""
    data = ctx.read(var.index, var.subindex)
    try:
        return data, download(data)
    except (SdoAbort, NoAnswerError, SdoProtocolError) as exc:
        ctx.fail(f"{how} download of its own value to {describe(var)}", "success",
                 outcome(exc))


@check("sdo.expedited_upload", clause="CiA 301 §7.2.4.3.6",
       title="an expedited upload answer has scs 2, e = 1, the right n and the multiplexer")
def expedited_upload(ctx: Context) -> None:
    tested = [(index, size) for index, size in ((0x1000, 4), (0x1001, 1))
              if ctx.var(index, 0) is not None]
    if not tested:
        ctx.skip("the EDS has neither 0x1000 nor 0x1001")
    for index, size in tested:
        what = f"upload 0x{index:04X}:0 ({size} bytes)"
        try:
            data = ctx.sdo.initiate(bytes([0x40, index & 0xFF, index >> 8, 0]), index, 0, what,
                                    2)
        except (SdoAbort, NoAnswerError, SdoProtocolError) as exc:
            ctx.fail(what, "a value", outcome(exc))
        expected = 0x43 | (4 - size) << 2
        if data[0] not in (expected, 0x42):
            ctx.finding(f"command byte of the answer to an {what}",
                        f"{expected:02X} (or 42: size not indicated)", f"{data[0]:02X}")


@check("sdo.expedited_download", clause="CiA 301 §7.2.4.3.3",
       title="an expedited download is answered 0x60 with the multiplexer, the value stored")
def expedited_download(ctx: Context) -> None:
    var = short_entry(ctx)
    if var is None:
        ctx.skip("the EDS has no readable and writable entry of 1..4 bytes")
    data = ctx.read(var.index, var.subindex)  # its own value: nothing changes
    mux = bytes([var.index & 0xFF, var.index >> 8, var.subindex])
    what = f"expedited download of {describe(var)}"
    try:
        answer = ctx.sdo.initiate(bytes([0x23 | (4 - len(data)) << 2]) + mux + data,
                                  var.index, var.subindex, what, 3)
    except (SdoAbort, NoAnswerError, SdoProtocolError) as exc:
        ctx.fail(what, "answer 60 with the multiplexer", outcome(exc))
    if answer[0] != 0x60:
        ctx.finding(f"command byte of the answer to an {what}", "60", f"{answer[0]:02X}")
    if ctx.read(var.index, var.subindex) != data:
        ctx.finding(f"read back {describe(var)}", data.hex(" ").upper(), "another value")
    ctx.note(describe(var))


@check("sdo.segmented_download", clause="CiA 301 §7.2.4.3.3, §7.2.4.3.4",
       title="segmented downloads of 5..22 bytes (1..4 segments) are stored as sent")
def segmented_download(ctx: Context) -> None:
    var = variable_entry(ctx)
    if var is not None:
        _sized_series(ctx, var, "segmented", "segmented")
        return
    var = long_entry(ctx)
    if var is None:
        ctx.skip("the EDS has no readable and writable entry longer than 4 bytes")
    data, _ = _own_value(ctx, var, "segmented", partial(ctx.sdo.download, var.index,
                                                        var.subindex, segmented=True))
    ctx.note(f"{describe(var)}: its own {len(data)} bytes")


@check("sdo.segmented_upload", clause="CiA 301 §7.2.4.3.6, §7.2.4.3.7",
       title="an upload of more than 4 bytes is segmented, toggle bits alternate, sizes add up")
def segmented_upload(ctx: Context) -> None:
    var = variable_entry(ctx)
    if var is not None:
        ctx.write_temp(var.index, var.subindex, _probe(SIZES[-1]))
    for cand in ([var] if var is not None else []) + _long_candidates(ctx):
        try:
            data = ctx.sdo.upload(cand.index, cand.subindex)
        except SdoAbort:
            continue  # an empty DOMAIN, say: dictionary.entries judges that
        except (NoAnswerError, SdoProtocolError) as exc:
            ctx.fail(f"upload {describe(cand)}", "a segmented upload", outcome(exc))
        if len(data) > 4:
            ctx.note(f"{describe(cand)}: {len(data)} bytes")
            return
    ctx.skip("the EDS has no entry that reads more than 4 bytes")


def _segmented_start(ctx: Context) -> tuple[eds.Variable, bool]:
    """An entry for a half-done segmented transfer: (entry, upload?). An upload needs no
    write; a download goes to an entry of the sizes' choice or longer than 4 bytes."""
    found = long_readable(ctx)
    if found is not None:
        return found[0], True
    var = variable_entry(ctx) or long_entry(ctx)
    if var is None:
        ctx.skip("the EDS has no entry for a segmented transfer")
    ctx.keep(var.index, var.subindex)
    return var, False


def _download_size(var: eds.Variable) -> int:
    """The size a segmented download to ``var`` announces: its type's, else 14 bytes."""
    return fixed_size(var) or 14


def _initiate(ctx: Context, var: eds.Variable, upload: bool) -> None:
    mux = bytes([var.index & 0xFF, var.index >> 8, var.subindex])
    if upload:
        answer = ctx.sdo.request(bytes([0x40]) + mux, f"upload {describe(var)}")
        ok = answer[0] & 0xE2 == 0x40  # scs 2, not expedited
    else:
        size = _download_size(var).to_bytes(4, "little")
        answer = ctx.sdo.request(bytes([0x21]) + mux + size, f"download {describe(var)}")
        ok = answer[0] == 0x60
    if not ok:
        ctx.fail(f"initiate a segmented {'upload' if upload else 'download'} of "
                 f"{describe(var)}", "a segmented transfer", answer.hex(" ").upper())


def _served_again(ctx: Context, after: str) -> None:
    ctx.served(f"after {after}")


@check("sdo.toggle_download", clause="CiA 301 §7.2.4.3.4, §7.2.4.3.17",
       title="a download segment with the wrong toggle bit is aborted with 0x05030000")
def toggle_download(ctx: Context) -> None:
    var = variable_entry(ctx) or long_entry(ctx)
    if var is None:
        ctx.skip("the EDS has no readable and writable entry for a segmented download")
    ctx.keep(var.index, var.subindex)
    _initiate(ctx, var, upload=False)
    piece = _probe(min(7, _download_size(var)))
    last = int(len(piece) == _download_size(var))
    answer = ctx.sdo.request(bytes([0x10 | (7 - len(piece)) << 1 | last]) + piece,
                             "a first segment with toggle 1")
    _expect_toggle_abort(ctx, var, answer, "download segment 1 with toggle bit 1")
    _served_again(ctx, "the wrong toggle bit")


@check("sdo.toggle_upload", clause="CiA 301 §7.2.4.3.7, §7.2.4.3.17",
       title="an upload segment request with the wrong toggle bit is aborted with 0x05030000")
def toggle_upload(ctx: Context) -> None:
    found = long_readable(ctx)
    if found is None:
        ctx.skip("the EDS has no entry that reads more than 4 bytes")
    var = found[0]
    _initiate(ctx, var, upload=True)
    answer = ctx.sdo.request(bytes([0x70]), "a first upload segment request with toggle 1")
    _expect_toggle_abort(ctx, var, answer, "upload segment request 1 with toggle bit 1")
    _served_again(ctx, "the wrong toggle bit")


def _expect_toggle_abort(ctx: Context, var: eds.Variable, answer: bytes, what: str) -> None:
    code = int.from_bytes(answer[4:8], "little") if answer[0] == 0x80 else None
    if code != 0x05030000:
        ctx.finding(what, abort_text(0x05030000),
                    abort_text(code) if code is not None else f"[{answer.hex(' ').upper()}]")
        if code is None:
            ctx.sdo.abort(var.index, var.subindex)


@check("sdo.unknown_command", clause="CiA 301 §7.2.4.3.17",
       title="a request with an unknown command specifier (7) is aborted with 0x05040001")
def unknown_command(ctx: Context) -> None:
    answer = ctx.sdo.request(bytes([0xE0, 0x00, 0x10, 0x00]), "command specifier 7")
    code = int.from_bytes(answer[4:8], "little") if answer[0] == 0x80 else None
    if code != 0x05040001:
        ctx.finding("request E0 00 10 00 ...", abort_text(0x05040001),
                    abort_text(code) if code is not None else f"[{answer.hex(' ').upper()}]")
    _served_again(ctx, "an unknown command specifier")


@check("sdo.client_abort", clause="CiA 301 §7.2.4.3.17",
       title="a transfer the client aborts ends silently, and the server serves again")
def client_abort(ctx: Context) -> None:
    var, upload = _segmented_start(ctx)
    _initiate(ctx, var, upload)
    mark = ctx.sdo.send(bytes([0x80, var.index & 0xFF, var.index >> 8, var.subindex])
                        + (0x08000000).to_bytes(4, "little"))
    ctx.link.wait(ctx.options.quiet)
    answers = ctx.link.frames_since(mark, lambda f: f.can_id == ctx.sdo.tx)
    if answers:
        ctx.finding("abort from the client", "no answer",
                    f"[{answers[0].frame.data.hex(' ').upper()}]")
    _served_again(ctx, "the client's abort")


@check("sdo.server_timeout", clause="CiA 301 §7.2.4.3.17 (0x05040000)",
       title="the server aborts a half-done transfer with 0x05040000 and serves again")
def server_timeout(ctx: Context) -> None:
    var, upload = _segmented_start(ctx)
    began = ctx.link.now()
    _initiate(ctx, var, upload)
    mark = ctx.link.mark()
    limit = ctx.options.server_timeout
    seen = ctx.link.wait_frame(lambda f: f.can_id == ctx.sdo.tx, limit, mark)
    if seen is None:
        ctx.finding(f"a half-done {'upload' if upload else 'download'} of {describe(var)}",
                    f"{abort_text(0x05040000)} within {limit:g} s", "no abort")
        ctx.sdo.abort(var.index, var.subindex)
    else:
        data = seen.frame.data
        code = int.from_bytes(data[4:8], "little") if data[0] == 0x80 else None
        if code != 0x05040000:
            ctx.finding("the server's answer to silence", abort_text(0x05040000),
                        abort_text(code) if code is not None else f"[{data.hex(' ').upper()}]")
        else:
            ctx.note(f"aborted after {ctx.link.now() - began:.2f} s")
    _served_again(ctx, "the time-out")


def _block_target(ctx: Context) -> eds.Variable:
    var = variable_entry(ctx)
    if var is None:
        var = long_entry(ctx) or short_entry(ctx)
    if var is None:
        ctx.skip("the EDS has no readable and writable entry")
    return var


@check("sdo.block_download", clause="CiA 301 §7.2.4.3.9-11, §7.2.4.3.16",
       title="block downloads (1..22 bytes, 889/890 where the entry takes them; CRC) are "
             "acknowledged per sub-block and stored")
def block_download(ctx: Context) -> None:
    var = _block_target(ctx)
    if var.data_type in VARIABLE_TYPES:
        _sized_series(ctx, var, "block", "segmented", BLOCK_SIZES)
        return
    data, blksize = _own_value(ctx, var, "block",
                               partial(ctx.sdo.block_download, var.index, var.subindex))
    ctx.note(f"{describe(var)}: its own {len(data)} bytes, block size {blksize}")


@check("sdo.block_upload", clause="CiA 301 §7.2.4.3.13-15, §7.2.4.3.16",
       title="block uploads (protocol switch threshold 0) give the value with a right CRC")
def block_upload(ctx: Context) -> None:
    var = variable_entry(ctx)
    if var is not None:
        _sized_series(ctx, var, "segmented", "block", BLOCK_SIZES)
        return
    found = long_readable(ctx)
    target, data = found if found is not None else (ctx.need(0x1000, why="device type"),
                                                    ctx.read(0x1000, 0))
    try:
        got, _ = ctx.sdo.block_upload(target.index, target.subindex)
    except (SdoAbort, NoAnswerError, SdoProtocolError) as exc:
        ctx.fail(f"block upload of {describe(target)}", "its value", outcome(exc))
    if got != data:
        ctx.finding(f"block upload of {describe(target)}", f"[{data.hex(' ').upper()}]",
                    f"[{got.hex(' ').upper()}]")
    ctx.note(f"{describe(target)}: {len(data)} bytes")


@check("sdo.block_crc", clause="CiA 301 §7.2.4.3.11, §7.2.4.3.16",
       title="a block download with a wrong CRC is aborted with 0x05040004")
def block_crc(ctx: Context) -> None:
    var = _block_target(ctx)
    original = ctx.keep(var.index, var.subindex)
    data = _probe(15) if var.data_type in VARIABLE_TYPES else original
    try:
        ctx.sdo.block_download(var.index, var.subindex, data, bad_crc=True)
    except SdoAbort as exc:
        if exc.code != 0x05040004:
            ctx.finding(f"block download to {describe(var)} with a wrong CRC",
                        abort_text(0x05040004), outcome(exc))
        return
    except (NoAnswerError, SdoProtocolError) as exc:
        ctx.fail(f"block download to {describe(var)} with a wrong CRC",
                 abort_text(0x05040004), outcome(exc))
    ctx.finding(f"block download to {describe(var)} with a wrong CRC",
                abort_text(0x05040004), "success")


@check("sdo.block_size", clause="CiA 301 §7.2.4.3.13-14, §7.2.4.3.17",
       title="block size 0 is aborted with 0x05040002; the server keeps to the client's "
             "block size in every sub-block")
def block_size(ctx: Context) -> None:
    target = variable_entry(ctx)
    if target is not None:
        ctx.write_temp(target.index, target.subindex, _probe(SIZES[-1]))
    else:
        found = long_readable(ctx)
        target = found[0] if found is not None else ctx.need(0x1000, why="device type")
    ctx.expect_abort(f"block upload of {describe(target)} with block size 0", (0x05040002,),
                     lambda: ctx.sdo.block_upload(target.index, target.subindex, blksize=0))
    try:
        _, blocks = ctx.sdo.block_upload(target.index, target.subindex, blksize=1,
                                         next_blksize=2)
    except (SdoAbort, NoAnswerError, SdoProtocolError) as exc:
        ctx.fail(f"block upload of {describe(target)}, block size 1 then 2", "its value",
                 outcome(exc))
    if blocks[0] != 1 or any(n > 2 for n in blocks[1:]):
        ctx.finding(f"sub-blocks of a block upload of {describe(target)}",
                    "1 segment, then at most 2 per sub-block", f"{blocks}")
    ctx.note(f"{describe(target)}: sub-blocks {blocks}")
