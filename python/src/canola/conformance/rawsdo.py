# SPDX-License-Identifier: Apache-2.0
"""An SDO client made of raw frames, for the checks: every request and answer is a frame
the tester sends or sees (so a failure can quote them), and every answer is checked
against CiA 301 §7.2.4.3 as it arrives.

- :meth:`RawSdo.upload` / :meth:`RawSdo.download`: expedited up to 4 bytes, else
  segmented (``segmented=True`` forces it);
- :meth:`RawSdo.block_download` / :meth:`RawSdo.block_upload`: block transfer with CRC;
- :meth:`RawSdo.request`: one request frame, its answer frame (protocol-level checks).

A server abort raises :class:`canola.SdoAbort`; no answer :class:`NoAnswerError`; an answer
that breaks the protocol :class:`SdoProtocolError`. After a failure in the middle of a
transfer the client aborts it (0x05040000 or 0x08000000), so the server is idle again.

Every transfer is bounded, so that a hostile server cannot keep the tester busy or make it
grow: at most :data:`MAX_VALUE_BYTES` bytes (announced or sent; abort 0x05040005), as many
segments as they fill, :data:`MAX_STALLED_ACKS` block acknowledgements in a row without
progress, and ``transfer_timeout`` seconds in all; past a bound :class:`TransferLimitError`.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TypeVar

from canola import SdoAbort
from canola.conformance.link import Link
from canola.errors import Error

__all__ = ["MAX_STALLED_ACKS", "MAX_VALUE_BYTES", "NoAnswerError", "RawSdo",
           "SdoProtocolError", "TransferLimitError", "ValueTooLargeError", "abort_frame",
           "crc16"]

ABORT_TIMEOUT = 0x05040000
ABORT_NO_MEMORY = 0x05040005
ABORT_GENERAL = 0x08000000
#: The most bytes one transfer moves (the tester's probes are 890 bytes at most).
MAX_VALUE_BYTES = 16 * 1024
#: Segments of an upload: as many as MAX_VALUE_BYTES fill, and a last one.
_MAX_SEGMENTS = MAX_VALUE_BYTES // 7 + 2
#: Block download acknowledgements in a row that take no segment (ackseq 0).
MAX_STALLED_ACKS = 4
#: A server time-out abort while the host was starved this long (s) is tried again...
STARVED_S = 0.1
#: ... this many times at most.
STARVED_RETRIES = 2
T = TypeVar("T")


class NoAnswerError(Error):
    """The server did not answer ``what`` within the time-out."""

    def __init__(self, what: str, timeout: float) -> None:
        super().__init__(f"no answer to {what} within {timeout:g} s")
        self.what = what


class SdoProtocolError(Error):
    """An answer that breaks the SDO protocol (the message says how)."""


class TransferLimitError(SdoProtocolError):
    """A transfer the tester stopped at one of its bounds (the message says which)."""


class ValueTooLargeError(TransferLimitError):
    """An upload of more than :data:`MAX_VALUE_BYTES` (announced or sent) the tester
    stopped: a large DOMAIN, or a server that does not stop."""


def crc16(data: bytes, crc: int = 0) -> int:
    """CRC-16-CCITT of the block transfer (CiA 301 §7.2.4.3.16): polynomial 0x1021,
    initial value 0, no reflection ("123456789" -> 0x31C3)."""
    for byte in data:
        crc ^= byte << 8
        for _ in range(8):
            crc = ((crc << 1) ^ 0x1021) if crc & 0x8000 else crc << 1
            crc &= 0xFFFF
    return crc


def _mux(index: int, sub: int) -> bytes:
    return index.to_bytes(2, "little") + bytes([sub])


def abort_frame(index: int, sub: int, code: int) -> bytes:
    """The 8 bytes of an SDO abort transfer."""
    return bytes([0x80]) + _mux(index, sub) + code.to_bytes(4, "little")


def _opens_transfer(data: bytes) -> bool:
    """A request that names its object: an initiate (ccs 1, 2; block ccs 5 and 6 with
    their initiate sub-commands) or an abort (ccs 4)."""
    ccs = data[0] >> 5
    return (ccs in (1, 2, 4) or (ccs == 5 and data[0] & 0x03 == 0)
            or (ccs == 6 and data[0] & 0x01 == 0))


def _continues_transfer(data: bytes) -> bool:
    """A request inside a transfer: a segment (ccs 0, 3) or a block sub-command."""
    return data[0] >> 5 in (0, 3, 5, 6) and not _opens_transfer(data)


class RawSdo:
    """SDO client of node ``node_id`` over ``link``; ``timeout``: seconds per answer.

    Each answer is attributed to the transfer in progress: an abort, or an answer to an
    initiate, that names another multiplexer (index, sub-index) than the transfer's cannot
    be its answer (it is a late one of an earlier exchange over a slow link, such as the
    abort of a request that reached the server after its own time-out) and is passed over.
    If no other answer comes within the time-out, the stray one is the answer, and wrong."""

    def __init__(self, link: Link, node_id: int, timeout: float,
                 transfer_timeout: float = 60.0,
                 note: Callable[[str], None] = lambda text: None) -> None:
        self.link = link
        self.note = note  # what the check's report says (a transfer tried again)
        self.node_id = node_id
        self.timeout = timeout
        self.transfer_timeout = transfer_timeout
        self._began = 0.0  # when the transfer in progress began (link time)
        self.rx = 0x600 + node_id  # the server's receive COB-ID
        self.tx = 0x580 + node_id  # the server's transmit COB-ID
        self._mux: bytes | None = None  # the transfer in progress's, once a request named it
        self._initiating = False  # the last request opened a transfer

    # ---- single frames

    def send(self, data: bytes) -> int:
        """Send one request frame (padded to 8 bytes); the mark before it."""
        frame = bytes(data).ljust(8, b"\0")
        if _opens_transfer(frame):
            self._mux = frame[1:4]
            self._began = self.link.now()
        elif not _continues_transfer(frame):
            self._mux = None  # no transfer (an unknown command): any answer is its answer
        self._initiating = _opens_transfer(frame)
        mark = self.link.mark()
        self.link.send(self.rx, frame)
        return mark

    def answer(self, since: int, what: str, timeout: float | None = None) -> bytes:
        """The next answer of the server after ``since``. Raises NoAnswerError."""
        return self.answer_at(since, what, timeout)[0]

    def answer_at(self, since: int, what: str,
                  timeout: float | None = None) -> tuple[bytes, int]:
        """The next answer after ``since`` that can belong to the transfer in progress, and
        the mark just after it. Raises NoAnswerError."""
        limit = self.timeout if timeout is None else timeout
        if self._mux is not None and not self._initiating:
            left = self._began + self.transfer_timeout - self.link.now()
            if left <= 0:
                raise TransferLimitError(f"{what}: the transfer has taken more than "
                                    f"{self.transfer_timeout:g} s")
            limit = min(limit, left)
        end = self.link.now() + limit
        stray: tuple[bytes, int] | None = None
        found: tuple[bytes, int] | None = None
        while found is None:
            left = max(0.0, end - self.link.now())
            seen = self.link.wait_frame(lambda f: f.can_id == self.tx and not f.rtr, left, since)
            if seen is None:
                if stray is None:
                    raise NoAnswerError(what, limit)
                found = stray
            elif self._foreign(seen.frame.data):
                since = seen.pos + 1
                stray = stray or (seen.frame.data, since)
            else:
                found = seen.frame.data, seen.pos + 1
        self._initiating = False  # answered: what follows belongs to the transfer
        return found

    def _foreign(self, answer: bytes) -> bool:
        """An answer that names another object than the transfer in progress."""
        if self._mux is None or len(answer) != 8:
            return False
        names_object = answer[0] == 0x80 or self._initiating
        return names_object and answer[1:4] != self._mux

    def request(self, data: bytes, what: str, timeout: float | None = None) -> bytes:
        """Send ``data`` and return the answer (any answer of its transfer, an abort too)."""
        return self.answer(self.send(data), what, timeout)

    def abort(self, index: int, sub: int, code: int = ABORT_GENERAL) -> None:
        """Abort the transfer in progress (no answer expected)."""
        self.send(abort_frame(index, sub, code))

    def initiate(self, data: bytes, index: int, sub: int, what: str, scs: int) -> bytes:
        """Send an initiate request and return its answer, checked (:meth:`_expect`)."""
        return self._expect(self.request(data, what), index, sub, what, scs)

    def _expect(self, data: bytes, index: int | None, sub: int, what: str,
                scs: int) -> bytes:
        """Check an answer: 8 bytes, not an abort, command specifier ``scs`` (bits 7..5),
        and, for initiate answers (``index`` given), the multiplexer echoed."""
        if len(data) != 8:
            raise SdoProtocolError(f"{what}: answer of {len(data)} bytes (SDO frames have 8)")
        if data[0] == 0x80:
            code = int.from_bytes(data[4:8], "little")
            raise SdoAbort(code)
        if data[0] >> 5 != scs:
            raise SdoProtocolError(f"{what}: command byte 0x{data[0]:02X} (server command "
                                    f"specifier {data[0] >> 5}, expected {scs})")
        if index is not None and data[1:4] != _mux(index, sub):
            got = int.from_bytes(data[1:3], "little")
            raise SdoProtocolError(f"{what}: answer names 0x{got:04X}:{data[3]} instead of "
                                    f"0x{index:04X}:{sub}")
        return data

    def _again_if_starved(self, transfer: Callable[[], T]) -> T:
        """Run ``transfer``; when the server aborts it with 0x05040000 (its time-out) while
        the host was starved (:data:`STARVED_S` or more: the tester's request may have
        reached the node late, through a bridge or an emulator on the same host), run it
        again, :data:`STARVED_RETRIES` times at most, each noted. On a quiet host the abort
        stands."""
        for _ in range(STARVED_RETRIES):
            since = self.link.since()
            try:
                return transfer()
            except SdoAbort as exc:
                starved = self.link.starved(since)
                if exc.code != ABORT_TIMEOUT or starved.worst < STARVED_S:
                    raise
                self.note(f"the server timed out a transfer (0x05040000) while the host was "
                          f"starved ({starved}): tried again")
        return transfer()

    # ---- expedited and segmented

    def upload(self, index: int, sub: int) -> bytes:
        """Read (index, sub): expedited or segmented, as the server chooses."""
        return self._again_if_starved(lambda: self._upload(index, sub))

    def _upload(self, index: int, sub: int) -> bytes:
        where = f"upload 0x{index:04X}:{sub}"
        first = self.initiate(bytes([0x40]) + _mux(index, sub), index, sub, where, 2)
        cmd = first[0]
        expedited, sized = bool(cmd & 0x02), bool(cmd & 0x01)
        if expedited:
            return first[4:8 - ((cmd >> 2) & 3)] if sized else first[4:8]
        size = int.from_bytes(first[4:8], "little") if sized else None
        try:
            self._bound(size, where)
            return self._upload_segments(index, sub, size, where)
        except TransferLimitError:
            self.abort(index, sub, ABORT_NO_MEMORY)
            raise
        except (NoAnswerError, SdoProtocolError):
            self.abort(index, sub, ABORT_GENERAL)
            raise

    @staticmethod
    def _bound(size: int | None, where: str) -> None:
        """TransferLimitError when a value of ``size`` bytes is more than the tester takes."""
        if size is not None and size > MAX_VALUE_BYTES:
            raise ValueTooLargeError(f"{where}: {size} bytes, more than the {MAX_VALUE_BYTES} "
                                "the tester takes")

    def _upload_segments(self, index: int, sub: int, size: int | None, where: str) -> bytes:
        data = bytearray()
        toggle = 0
        for segment in range(1, _MAX_SEGMENTS + 1):
            what = f"{where}, segment {segment}"
            seg = self._expect(self.request(bytes([0x60 | toggle << 4]), what), None, sub,
                               what, 0)
            if (seg[0] >> 4) & 1 != toggle:
                raise SdoProtocolError(f"{what}: toggle bit {(seg[0] >> 4) & 1}, expected "
                                        f"{toggle}")
            data += seg[1:8 - ((seg[0] >> 1) & 7)]
            if seg[0] & 1:
                break
            if size is not None and len(data) >= size:
                raise SdoProtocolError(f"{what}: {len(data)} of {size} bytes sent and "
                                        "still no last segment")
            self._bound(len(data), where)
            toggle ^= 1
        else:
            raise TransferLimitError(f"{where}: {_MAX_SEGMENTS} segments and no last one")
        if size is not None and len(data) != size:
            raise SdoProtocolError(f"{where}: {len(data)} bytes in the segments, "
                                    f"{size} announced")
        return bytes(data)

    def download(self, index: int, sub: int, data: bytes, *, segmented: bool = False) -> None:
        """Write ``data`` to (index, sub): expedited up to 4 bytes unless ``segmented``."""
        self._again_if_starved(lambda: self._download(index, sub, data, segmented))

    def _download(self, index: int, sub: int, data: bytes, segmented: bool) -> None:
        where = f"download 0x{index:04X}:{sub} ({len(data)} bytes)"
        if len(data) <= 4 and not segmented and data:
            cmd = 0x23 | (4 - len(data)) << 2
            self.initiate(bytes([cmd]) + _mux(index, sub) + data, index, sub, where, 3)
            return
        self.initiate(bytes([0x21]) + _mux(index, sub) + len(data).to_bytes(4, "little"),
                      index, sub, where, 3)
        try:
            self._download_segments(data, where)
        except (NoAnswerError, SdoProtocolError):
            self.abort(index, sub, ABORT_GENERAL)
            raise

    def _download_segments(self, data: bytes, where: str) -> None:
        toggle = 0
        for start in range(0, max(len(data), 1), 7):
            piece = data[start:start + 7]
            last = start + 7 >= len(data)
            cmd = toggle << 4 | (7 - len(piece)) << 1 | int(last)
            what = f"{where}, segment {start // 7 + 1}"
            ack = self._expect(self.request(bytes([cmd]) + piece, what), None, 0, what, 1)
            if (ack[0] >> 4) & 1 != toggle:
                raise SdoProtocolError(f"{what}: answer toggle bit {(ack[0] >> 4) & 1}, "
                                        f"expected {toggle}")
            toggle ^= 1

    # ---- block transfer

    def block_download(self, index: int, sub: int, data: bytes, *,
                       bad_crc: bool = False) -> int:
        """Write ``data`` by block transfer with CRC (a wrong CRC with ``bad_crc``); the
        block size the server asked for first."""
        return self._again_if_starved(lambda: self._block_download(index, sub, data, bad_crc))

    def _block_download(self, index: int, sub: int, data: bytes, bad_crc: bool) -> int:
        where = f"block download 0x{index:04X}:{sub} ({len(data)} bytes)"
        init = self.initiate(bytes([0xC6]) + _mux(index, sub) + len(data).to_bytes(4, "little"),
                             index, sub, where, 5)
        if init[0] & 0x03:
            raise SdoProtocolError(f"{where}: initiate answer 0x{init[0]:02X} (ss must be 0)")
        crc_on = bool(init[0] & 0x04)
        blksize = first_blksize = init[4]
        try:
            seq_data = [data[i:i + 7] for i in range(0, len(data), 7)] or [b""]
            sent = 0
            stalled = 0
            while sent < len(seq_data):
                if not 1 <= blksize <= 127:
                    raise SdoProtocolError(f"{where}: block size {blksize} (1..127)")
                chunk = seq_data[sent:sent + blksize]
                mark = self.link.mark()
                for n, piece in enumerate(chunk, start=1):
                    last = sent + n == len(seq_data)
                    self.link.send(self.rx, bytes([int(last) << 7 | n]) + piece.ljust(7, b"\0"))
                upto = min(len(data), (sent + len(chunk)) * 7)
                what = f"{where}, sub-block ending at byte {upto}"
                ack = self._expect(self.answer(mark, what), None, 0, what, 5)
                if ack[0] & 0x03 != 2:
                    raise SdoProtocolError(f"{what}: answer 0x{ack[0]:02X} (expected 0xA2)")
                if ack[1] > len(chunk):
                    raise SdoProtocolError(f"{what}: ackseq {ack[1]} of {len(chunk)} sent")
                sent += ack[1]  # the server asks again for what it did not take
                stalled = 0 if ack[1] else stalled + 1
                if stalled >= MAX_STALLED_ACKS:
                    raise TransferLimitError(f"{what}: {stalled} sub-blocks in a row acknowledged "
                                        "with ackseq 0 (no progress)")
                blksize = ack[2]
            n = (7 - len(data) % 7) % 7 if data else 7
            crc = crc16(data) ^ (0xFFFF if bad_crc else 0) if crc_on else 0
            what = f"{where}, end"
            end = self._expect(self.request(bytes([0xC1 | n << 2]) + crc.to_bytes(2, "little"),
                                            what), None, 0, what, 5)
            if end[0] & 0x03 != 1:
                raise SdoProtocolError(f"{what}: answer 0x{end[0]:02X} (expected 0xA1)")
        except (NoAnswerError, SdoProtocolError):
            self.abort(index, sub, ABORT_GENERAL)
            raise
        return first_blksize

    def block_upload(self, index: int, sub: int, *, blksize: int = 127,
                     next_blksize: int | None = None) -> tuple[bytes, list[int]]:
        """Read (index, sub) by block transfer with CRC (protocol switch threshold 0: the
        server must not fall back to a segmented upload); the client asks for ``blksize``
        segments per sub-block, then ``next_blksize``. The data and the number of segments
        in each sub-block."""
        return self._again_if_starved(
            lambda: self._block_upload(index, sub, blksize, next_blksize))

    def _block_upload(self, index: int, sub: int, blksize: int,
                      next_blksize: int | None) -> tuple[bytes, list[int]]:
        where = f"block upload 0x{index:04X}:{sub}"
        init = self.initiate(bytes([0xA4]) + _mux(index, sub) + bytes([blksize, 0, 0, 0]),
                             index, sub, where, 6)
        if init[0] & 0x01:
            raise SdoProtocolError(f"{where}: initiate answer 0x{init[0]:02X} (ss must be 0)")
        crc_on = bool(init[0] & 0x04)
        size = int.from_bytes(init[4:8], "little") if init[0] & 0x02 else None
        data = bytearray()
        blocks: list[int] = []
        try:
            self._bound(size, where)
            mark = self.send(bytes([0xA3]))
            asked = blksize
            while True:
                frames, last = self._sub_block(mark, asked, where)
                blocks.append(len(frames))
                for piece in frames:
                    data += piece
                self._bound(len(data) - 7, where)  # the last segment may hold less
                asked = next_blksize or blksize
                mark = self.send(bytes([0xA2, len(frames), asked]))
                if last:
                    break
            what = f"{where}, end"
            end = self._expect(self.answer(mark, what), None, 0, what, 6)
            if end[0] & 0x03 != 1:
                raise SdoProtocolError(f"{what}: frame 0x{end[0]:02X} (expected an end, "
                                        "0xC1 | n << 2)")
            unused = (end[0] >> 2) & 7
            if unused:
                del data[len(data) - unused:]
            if size is not None and len(data) != size:
                raise SdoProtocolError(f"{where}: {len(data)} bytes, {size} announced")
            if crc_on and int.from_bytes(end[1:3], "little") != crc16(bytes(data)):
                raise SdoProtocolError(f"{where}: CRC 0x{int.from_bytes(end[1:3], 'little'):04X}"
                                        f", computed 0x{crc16(bytes(data)):04X}")
            self.send(bytes([0xA1]))
        except TransferLimitError:
            self.abort(index, sub, ABORT_NO_MEMORY)
            raise
        except (NoAnswerError, SdoProtocolError):
            self.abort(index, sub, ABORT_GENERAL)
            raise
        return bytes(data), blocks

    def _sub_block(self, mark: int, blksize: int, where: str) -> tuple[list[bytes], bool]:
        """The segments of one sub-block sent after ``mark``: their data, and whether the
        last one carried the end flag."""
        frames: list[bytes] = []
        while True:
            what = f"{where}, segment {len(frames) + 1} of a sub-block of {blksize}"
            seg, mark = self.answer_at(mark, what)
            if len(seg) != 8:
                raise SdoProtocolError(f"{what}: {len(seg)} bytes (SDO frames have 8)")
            if seg[0] == 0x80 and not frames:
                raise SdoAbort(int.from_bytes(seg[4:8], "little"))
            seqno = seg[0] & 0x7F
            if seqno != len(frames) + 1:
                raise SdoProtocolError(f"{what}: sequence number {seqno}, expected "
                                        f"{len(frames) + 1}")
            frames.append(seg[1:8])
            if seg[0] & 0x80:
                return frames, True
            if len(frames) == blksize:
                return frames, False
