# SPDX-License-Identifier: Apache-2.0
"""What a check works with: the node (raw frames, a raw SDO client, NMT), its EDS, the
run's options, and the bookkeeping of the check (findings, notes, what to restore).

A check passes when it ends without a finding. :meth:`Context.finding` records one (with
the frames around it) and goes on; :meth:`Context.fail` records one and ends the check;
:meth:`Context.skip` ends it as SKIPPED (the EDS says the node cannot support it), and
:meth:`Context.not_applicable` too, when the node's application refuses a probe value its
EDS does not guarantee (:data:`APPLICATION_REFUSALS`): that is no deviation. Every
value a check changes is put back by :meth:`Context.write_temp`'s undo, which the runner
runs after the check, in reverse order, with the node in PRE-OPERATIONAL.
"""

from __future__ import annotations

from collections.abc import Callable, Collection
from dataclasses import dataclass, field
from typing import NoReturn

from canola import SdoAbort
from canola.conformance.entries import describe, writable
from canola.conformance.link import Link
from canola.conformance.options import Options
from canola.conformance.rawsdo import NoAnswerError, RawSdo, SdoProtocolError
from canola.conformance.results import Finding
from canola.errors import ABORT_TEXT, Error
from canola.formats import eds

__all__ = ["APPLICATION_REFUSALS", "NMT_CS", "STATES", "CheckEnded", "Context", "Options",
           "Skipped", "abort_text", "outcome"]

#: NMT command specifiers.
NMT_CS = {"start": 0x01, "stop": 0x02, "preop": 0x80, "reset-node": 0x81,
          "reset-comm": 0x82}
#: NMT states as error control frames carry them.
STATES = {0x00: "BOOT-UP", 0x04: "STOPPED", 0x05: "OPERATIONAL", 0x7F: "PRE-OPERATIONAL"}
#: The state each NMT command leads to.
ENTERS = {"start": 0x05, "stop": 0x04, "preop": 0x7F}
#: Abort codes by which an application refuses a value or a length it does not take
#: (CiA 301 §7.2.4.3.17): for a probe value the EDS does not guarantee, the check does not
#: apply; they are no deviation from the protocol.
APPLICATION_REFUSALS = frozenset({
    0x06070010, 0x06070012, 0x06070013,  # the length
    0x06090030, 0x06090031, 0x06090032, 0x06090036,  # the value
    0x08000020, 0x08000021, 0x08000022,  # the application, its local control, its state
})
#: The heartbeat period a check switches on to see the node's state (ms).
_STATE_HEARTBEAT_MS = 100

_TRACE_PER_FINDING = 20


class Skipped(Exception):  # noqa: N818 -- an outcome, not an error
    """The check does not apply to this node (``reason`` says why)."""


class CheckEnded(Exception):  # noqa: N818 -- an outcome, not an error
    """The check cannot go on (its finding is recorded)."""


def abort_text(code: int) -> str:
    return f"abort 0x{code:08X} ({ABORT_TEXT.get(code, 'unknown abort code')})"


def outcome(exc: BaseException | None) -> str:
    """What a transfer ended with, as a finding's ``got``."""
    if exc is None:
        return "success"
    if isinstance(exc, SdoAbort):
        return abort_text(exc.code)
    return str(exc)


@dataclass
class Context:
    """One check's view of the node ``node_id`` described by ``od``."""

    link: Link
    node_id: int
    od: eds.ObjectDictionary
    options: Options
    findings: list[Finding] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)
    undo: list[tuple[str, Callable[[], None]]] = field(default_factory=list)

    def __post_init__(self) -> None:
        self.sdo = RawSdo(self.link, self.node_id, self.options.timeout,
                          self.options.transfer_timeout, note=self.note)
        self._heartbeat_ms: int | None = None  # how the node shows its state (enter)

    # ---- outcomes

    def finding(self, what: str, expected: str, got: str, *, clause: str = "") -> None:
        """Record a deviation (with the latest frames) and go on; ``clause``: the one it
        deviates from, when narrower than the check's."""
        self.findings.append(Finding(what, expected, got,
                                     tuple(self.link.trace(_TRACE_PER_FINDING)), clause))

    def fail(self, what: str, expected: str, got: str, *, clause: str = "") -> NoReturn:
        """Record a deviation and end the check."""
        self.finding(what, expected, got, clause=clause)
        raise CheckEnded(what)

    def skip(self, reason: str) -> NoReturn:
        raise Skipped(reason)

    def not_applicable(self, what: str, exc: SdoAbort) -> NoReturn:
        """End the check as SKIPPED: the application refused ``what`` (a value or length
        the EDS does not guarantee) with one of :data:`APPLICATION_REFUSALS`."""
        raise Skipped(f"not applicable: {what} refused with {abort_text(exc.code)}, the "
                      "application's choice (the EDS does not guarantee that value)")

    def note(self, text: str) -> None:
        """Something the report says about a passing check (what was covered, measured)."""
        self.notes.append(text)

    # ---- the EDS

    def var(self, index: int, sub: int = 0) -> eds.Variable | None:
        obj = self.od.objects.get(index)
        return None if obj is None else obj.subs.get(sub)

    def need(self, index: int, sub: int = 0, *, why: str) -> eds.Variable:
        """The entry, or SKIPPED: "the EDS has no 0x1017:0 (why)"."""
        var = self.var(index, sub)
        if var is None:
            self.skip(f"the EDS has no 0x{index:04X}:{sub} ({why})")
        return var

    # ---- SDO, failing the check on an unexpected outcome

    def read(self, index: int, sub: int = 0) -> bytes:
        """Upload (index, sub); an abort, no answer or a protocol error ends the check."""
        try:
            return self.sdo.upload(index, sub)
        except (SdoAbort, NoAnswerError, SdoProtocolError) as exc:
            self.fail(f"read 0x{index:04X}:{sub}", "its value", outcome(exc))

    def read_uint(self, index: int, sub: int = 0) -> int:
        return int.from_bytes(self.read(index, sub), "little")

    def served(self, when: str) -> bool:
        """Does the SDO server serve (``when``: "after reset node", say)? Any answer to a
        read of 0x1000:0 says so, an abort too (the EDS may lack 0x1000:
        dictionary.mandatory judges that); else a finding, and False."""
        try:
            self.sdo.upload(0x1000, 0)
        except SdoAbort:
            pass
        except (NoAnswerError, SdoProtocolError) as exc:
            self.finding(f"read 0x1000:0 {when}", "an answer (its value or an abort)",
                         outcome(exc))
            return False
        return True

    def write(self, index: int, sub: int, data: bytes) -> None:
        """Download (index, sub); any failure ends the check."""
        try:
            self.sdo.download(index, sub, data)
        except (SdoAbort, NoAnswerError, SdoProtocolError) as exc:
            self.fail(f"write [{data.hex(' ').upper()}] to 0x{index:04X}:{sub}", "success",
                      outcome(exc))

    def write_uint(self, index: int, sub: int, value: int, size: int) -> None:
        self.write(index, sub, value.to_bytes(size, "little"))

    def try_write(self, index: int, sub: int, data: bytes) -> BaseException | None:
        """Download and return what went wrong (None: success)."""
        try:
            self.sdo.download(index, sub, data)
        except (SdoAbort, NoAnswerError, SdoProtocolError) as exc:
            return exc
        return None

    def keep(self, index: int, sub: int = 0) -> bytes:
        """Read (index, sub) and have the runner write it back after the check."""
        original = self.read(index, sub)
        self.on_undo(f"write back 0x{index:04X}:{sub}",
                     lambda: self.sdo.download(index, sub, original))
        return original

    def write_temp(self, index: int, sub: int, data: bytes) -> None:
        """Write (index, sub), to be written back after the check."""
        self.keep(index, sub)
        self.write(index, sub, data)

    def on_undo(self, label: str, fn: Callable[[], None]) -> None:
        """Run ``fn`` after the check (last registered first)."""
        self.undo.append((label, fn))

    def expect_abort(self, what: str, codes: Collection[int] | None,
                     transfer: Callable[[], object], *,
                     restore: Callable[[], None] | None = None) -> bool:
        """Run ``transfer`` (an SDO access that must be refused): True when the server
        aborted it with one of ``codes`` (None: any), else a finding (and ``restore`` runs,
        to put back what a wrongly accepted write changed)."""
        try:
            transfer()
        except SdoAbort as exc:
            if codes is None or exc.code in codes:
                return True
            self.finding(what, _codes(codes), outcome(exc))
            return False
        except (NoAnswerError, SdoProtocolError) as exc:
            self.finding(what, _codes(codes), outcome(exc))
            return False
        self.finding(what, _codes(codes), "success")
        if restore is not None:
            try:
                restore()
            except Error as exc:
                self.finding(f"restore after: {what}", "success", outcome(exc))
        return False

    # ---- NMT and error control

    def nmt(self, command: str) -> None:
        """Send an NMT command to the node (never to all nodes)."""
        self.link.send(0x000, bytes([NMT_CS[command], self.node_id]))

    def enter(self, command: str) -> None:
        """Send NMT ``command`` (start, stop, preop) and wait until the node reports the
        state in its heartbeat (at 100 ms for the check where 0x1017 is writable): a node
        may take the command in a while (CANopenLinux in its next pass, RPDOs before it),
        and a check acts on the state. Without a heartbeat it waits ``quiet`` seconds. A
        node that does not report the state fails the check."""
        period = self._state_heartbeat()
        mark = self.link.mark()
        self.nmt(command)
        if not period:
            self.link.wait(self.options.quiet)
            return
        state = ENTERS[command]
        wait = 2 * period / 1000 + self.options.timeout
        if self.wait_error_control(mark, wait, (state,)) is None:
            self.fail(f"NMT {command}", f"a heartbeat {STATES[state]} within {wait:g} s",
                      "none", clause="CiA 301 §7.2.8.3.2.2, §7.3.2")

    def _state_heartbeat(self) -> int:
        """The node's heartbeat period (ms) for the check: 100 ms where 0x1017 is writable,
        else its own; 0 without heartbeat. Read once per check (before it stops the node)."""
        if self._heartbeat_ms is None:
            var = self.var(0x1017, 0)
            period = self.read_uint(0x1017) if var is not None else 0
            if period != _STATE_HEARTBEAT_MS and var is not None and writable(var):
                self.keep(0x1017, 0)
                if self.try_write(0x1017, 0, _STATE_HEARTBEAT_MS.to_bytes(2, "little")) is None:
                    period = _STATE_HEARTBEAT_MS
            self._heartbeat_ms = period
        return self._heartbeat_ms

    def heartbeat_cob(self) -> int:
        return 0x700 + self.node_id

    def wait_error_control(self, since: int, timeout: float,
                           states: Collection[int] | None = None) -> int | None:
        """The state in the first heartbeat (or boot-up) after ``since``, among ``states``
        if given; None when none came within ``timeout``."""
        cob = self.heartbeat_cob()
        seen = self.link.wait_frame(
            lambda f: f.can_id == cob and not f.rtr and len(f.data) == 1
            and (states is None or f.data[0] & 0x7F in states), timeout, since)
        return None if seen is None else seen.frame.data[0] & 0x7F

    def entry_name(self, index: int, sub: int) -> str:
        var = self.var(index, sub)
        return describe(var) if var is not None else f"0x{index:04X}:{sub}"


def _codes(codes: Collection[int] | None) -> str:
    if codes is None:
        return "an abort"
    return " or ".join(abort_text(c) for c in codes)
