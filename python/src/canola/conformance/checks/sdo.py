# SPDX-License-Identifier: Apache-2.0
"""Group ``sdo``: the SDO server frame by frame -- expedited, segmented and block transfer
both ways at sizes around the frame boundaries, wrong toggle bit, unknown command
specifier, client abort, block CRC and block size, the server's own time-out."""

from __future__ import annotations

from collections.abc import Callable
from functools import partial
from typing import TypeVar

from canola import SdoAbort
from canola.conformance import probes as pb
from canola.conformance.context import APPLICATION_REFUSALS, Context, abort_text, outcome
from canola.conformance.entries import describe
from canola.conformance.rawsdo import NoAnswerError, SdoProtocolError
from canola.conformance.registry import check
from canola.formats import eds

T = TypeVar("T")


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
    var = pb.short_entry(ctx)
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
    cands = pb.variable_entries(ctx)
    if cands:
        pb.sized_series(ctx, cands, "segmented", "segmented")
        return
    var = pb.long_entry(ctx)
    if var is None:
        ctx.skip("the EDS has no readable and writable entry longer than 4 bytes")
    data, _ = _own_value(ctx, var, "segmented", partial(ctx.sdo.download, var.index,
                                                        var.subindex, segmented=True))
    ctx.note(f"{describe(var)}: its own {len(data)} bytes")


@check("sdo.segmented_upload", clause="CiA 301 §7.2.4.3.6, §7.2.4.3.7",
       title="an upload of more than 4 bytes is segmented, toggle bits alternate, sizes add up")
def segmented_upload(ctx: Context) -> None:
    found = pb.long_value(ctx, 4)
    if found is None:
        ctx.skip("the EDS has no entry that reads more than 4 bytes")
    var, data = found
    try:
        got = ctx.sdo.upload(var.index, var.subindex)
    except (SdoAbort, NoAnswerError, SdoProtocolError) as exc:
        ctx.fail(f"upload {describe(var)}", "a segmented upload", outcome(exc))
    if not pb.same(var, data, got):
        ctx.finding(f"upload {describe(var)}", f"[{data.hex(' ').upper()}]",
                    f"[{got.hex(' ').upper()}]")
    ctx.note(f"{describe(var)}: {len(got)} bytes")


def _segmented_start(ctx: Context) -> tuple[pb.Candidate, bool]:
    """An entry for a half-done segmented transfer: (entry, upload?). An upload needs no
    write; a download goes to a string or DOMAIN, or an entry longer than 4 bytes."""
    found = pb.long_readable(ctx)
    if found is not None:
        return pb.Candidate(*found), True
    cand = _download_target(ctx)
    if cand is None:
        ctx.skip("the EDS has no entry for a segmented transfer")
    return cand, False


def _download_target(ctx: Context) -> pb.Candidate | None:
    """A string or DOMAIN, else an entry longer than 4 bytes, with its value (kept, to be
    written back after the check)."""
    cands = pb.variable_entries(ctx)
    if cands:
        cand = cands[0]
    else:
        var = pb.long_entry(ctx)
        if var is None:
            return None
        cand = pb.Candidate(var, ctx.read(var.index, var.subindex))
    ctx.keep(cand.var.index, cand.var.subindex)
    return cand


def _initiate(ctx: Context, cand: pb.Candidate, upload: bool) -> None:
    """Open a segmented transfer of the entry: a download announces what the entry holds
    (:func:`~canola.conformance.probes.announced_size`); its refusal by the application
    makes the check not applicable."""
    var = cand.var
    mux = bytes([var.index & 0xFF, var.index >> 8, var.subindex])
    if upload:
        answer = ctx.sdo.request(bytes([0x40]) + mux, f"upload {describe(var)}")
        ok = answer[0] & 0xE2 == 0x40  # scs 2, not expedited
    else:
        size = pb.announced_size(cand)
        answer = ctx.sdo.request(bytes([0x21]) + mux + size.to_bytes(4, "little"),
                                 f"download {describe(var)}")
        ok = answer[0] == 0x60
        code = int.from_bytes(answer[4:8], "little") if answer[0] == 0x80 else None
        if code in APPLICATION_REFUSALS:
            ctx.not_applicable(f"a segmented download of {size} bytes to {describe(var)}",
                               SdoAbort(code))
    if not ok:
        ctx.fail(f"initiate a segmented {'upload' if upload else 'download'} of "
                 f"{describe(var)}", "a segmented transfer", answer.hex(" ").upper())


def _served_again(ctx: Context, after: str) -> None:
    ctx.served(f"after {after}")


@check("sdo.toggle_download", clause="CiA 301 §7.2.4.3.4, §7.2.4.3.17",
       title="a download segment with the wrong toggle bit is aborted with 0x05030000")
def toggle_download(ctx: Context) -> None:
    cand = _download_target(ctx)
    if cand is None:
        ctx.skip("the EDS has no readable and writable entry for a segmented download")
    _initiate(ctx, cand, upload=False)
    size = pb.announced_size(cand)
    piece = pb.probe(min(7, size))
    last = int(len(piece) == size)
    answer = ctx.sdo.request(bytes([0x10 | (7 - len(piece)) << 1 | last]) + piece,
                             "a first segment with toggle 1")
    _expect_toggle_abort(ctx, cand.var, answer, "download segment 1 with toggle bit 1")
    _served_again(ctx, "the wrong toggle bit")


@check("sdo.toggle_upload", clause="CiA 301 §7.2.4.3.7, §7.2.4.3.17",
       title="an upload segment request with the wrong toggle bit is aborted with 0x05030000")
def toggle_upload(ctx: Context) -> None:
    found = pb.long_readable(ctx)
    if found is None:
        ctx.skip("the EDS has no entry that reads more than 4 bytes")
    cand = pb.Candidate(*found)
    _initiate(ctx, cand, upload=True)
    answer = ctx.sdo.request(bytes([0x70]), "a first upload segment request with toggle 1")
    _expect_toggle_abort(ctx, cand.var, answer, "upload segment request 1 with toggle bit 1")
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
    cand, upload = _segmented_start(ctx)
    _initiate(ctx, cand, upload)
    var = cand.var
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
    cand, upload = _segmented_start(ctx)
    var = cand.var
    began = ctx.link.now()
    _initiate(ctx, cand, upload)
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


def _block_target(ctx: Context) -> pb.Candidate:
    """A string or DOMAIN, else an entry of fixed size, with its value (written back after
    the check)."""
    cands = pb.variable_entries(ctx)
    if cands:
        cand = cands[0]
    else:
        var = pb.long_entry(ctx) or pb.short_entry(ctx)
        if var is None:
            ctx.skip("the EDS has no readable and writable entry")
        cand = pb.Candidate(var, ctx.read(var.index, var.subindex))
    ctx.keep(cand.var.index, cand.var.subindex)
    return cand


@check("sdo.block_download", clause="CiA 301 §7.2.4.3.9-11, §7.2.4.3.16",
       title="block downloads (1..22 bytes, 889/890 where the entry takes them; CRC) are "
             "acknowledged per sub-block and stored")
def block_download(ctx: Context) -> None:
    cands = pb.variable_entries(ctx)
    if cands:
        pb.sized_series(ctx, cands, "block", "segmented", pb.BLOCK_SIZES)
        return
    var = _block_target(ctx).var
    data, blksize = _own_value(ctx, var, "block",
                               partial(ctx.sdo.block_download, var.index, var.subindex))
    ctx.note(f"{describe(var)}: its own {len(data)} bytes, block size {blksize}")


@check("sdo.block_upload", clause="CiA 301 §7.2.4.3.13-15, §7.2.4.3.16",
       title="block uploads (protocol switch threshold 0) give the value with a right CRC")
def block_upload(ctx: Context) -> None:
    cands = pb.variable_entries(ctx)
    if cands:
        pb.sized_series(ctx, cands, "segmented", "block", pb.BLOCK_SIZES)
        return
    found = pb.long_readable(ctx)
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
    cand = _block_target(ctx)  # its own value: what its application takes
    var = cand.var
    what = f"block download of its own {len(cand.value)} bytes to {describe(var)} with a " \
           "wrong CRC"
    try:
        ctx.sdo.block_download(var.index, var.subindex, cand.value, bad_crc=True)
    except SdoAbort as exc:
        if exc.code in APPLICATION_REFUSALS:
            ctx.not_applicable(f"a block download to {describe(var)}", exc)
        if exc.code != 0x05040004:
            ctx.finding(what, abort_text(0x05040004), outcome(exc))
        return
    except (NoAnswerError, SdoProtocolError) as exc:
        ctx.fail(what, abort_text(0x05040004), outcome(exc))
    ctx.finding(what, abort_text(0x05040004), "success")


@check("sdo.block_size", clause="CiA 301 §7.2.4.3.13-14, §7.2.4.3.17",
       title="block size 0 is aborted with 0x05040002; the server keeps to the client's "
             "block size in every sub-block")
def block_size(ctx: Context) -> None:
    found = pb.long_value(ctx, 7)  # two segments or more
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
