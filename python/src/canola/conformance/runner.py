# SPDX-License-Identifier: Apache-2.0
"""Running the checks against one node: a tester (a :class:`canola.Master`) on the bus, the
node's NMT state learnt first and restored at the end, each check started in
PRE-OPERATIONAL and followed by its undo actions. Ctrl-C ends the run with
:class:`~canola.conformance.results.Interrupted`, which carries the report of what ran."""

from __future__ import annotations

import logging
import os
import time
from collections.abc import Callable, Iterable
from typing import Any

from canola import Master, SdoAbort
from canola.conformance.context import STATES, CheckEnded, Context, Skipped, outcome
from canola.conformance.link import Link
from canola.conformance.options import Options
from canola.conformance.rawsdo import NoAnswerError, SdoProtocolError
from canola.conformance.registry import Check, select
from canola.conformance.results import Interrupted, Report, Result, Status
from canola.core import SimBus
from canola.errors import Error
from canola.formats import eds

__all__ = ["Progress", "run"]

log = logging.getLogger("canola.conformance")

#: ``progress(done, total, check, result)``: before a check (result None) and after it.
Progress = Callable[[int, int, Check, Result | None], None]

_PROBE_HEARTBEAT_MS = 100
_RESTORE_COMMAND = {0x04: "stop", 0x05: "start", 0x7F: "preop"}


def run(bus: Any, node_id: int, eds_file: str | os.PathLike[str] | eds.ObjectDictionary, *,
        only: Iterable[str] = (), options: Options | None = None, master_id: int | None = None,
        progress: Progress | None = None) -> Report:
    """Run the checks (all, or the groups/checks in ``only``) against node ``node_id`` of
    ``bus`` (a :class:`canola.core.SimBus` or a python-can bus), described by ``eds_file``.
    The tester is a :class:`canola.Master` at ``master_id`` (default 127, or 126 when the
    node is 127). Raises :class:`canola.Error` for a bad argument or EDS, and on Ctrl-C
    :class:`~canola.conformance.Interrupted` (a KeyboardInterrupt) with the report of the
    checks that ran (the interrupted one's changes put back, the NMT state restored)."""
    if not isinstance(node_id, int) or not 1 <= node_id <= 127:
        raise Error(f"node-ID {node_id!r} is outside 1..127")
    opts = options or Options()
    checks = select(only)
    od = eds_file if isinstance(eds_file, eds.ObjectDictionary) else eds.parse(
        eds_file, node_id=node_id)
    if od.node_id != node_id:
        od = eds.parse(eds.write(od, dcf=True), node_id=node_id, filename=od.file)
    tester_id = master_id if master_id is not None else (126 if node_id == 127 else 127)
    if tester_id == node_id:
        raise Error(f"the tester's node-ID {tester_id} is the node's")
    sim = isinstance(bus, SimBus)
    timing = ("virtual time (simulated bus)" if sim else
              f"wall clock: answers within {opts.timeout:g} s, periods within "
              f"±{opts.tolerance * 100:g} %")
    report = Report(node_id, od.file, _bus_name(bus), timing)
    # announced (its boot-up; no heartbeat, 0x1017 is 0): a quiet master could not send
    # the heartbeats of its node-ID that the EMCY checks make the node consume
    master = Master(bus, tester_id, sdo_timeout_ms=round(opts.timeout * 1000), announce=True)
    master.start()
    runner = _Run(master, node_id, od, opts, report)
    try:
        runner.go(checks, progress)
    except KeyboardInterrupt:
        report.interrupted = runner.current or "the start"
        report.notes.append(f"interrupted (Ctrl-C) during {report.interrupted}: "
                            f"{len(report.results)} of {len(checks)} checks ran")
        raise Interrupted(report) from None
    finally:
        master.stop()
    return report


def _bus_name(bus: Any) -> str:
    if isinstance(bus, SimBus):
        return "simulated bus (canola.core.SimBus)"
    return f"python-can {type(bus).__name__} {getattr(bus, 'channel_info', '')}".strip()


class _Run:
    def __init__(self, master: Master, node_id: int, od: eds.ObjectDictionary, options: Options,
                 report: Report) -> None:
        self.link = Link(master, node_id)
        self.node_id = node_id
        self.od = od
        self.options = options
        self.report = report
        self.current = ""  # the check running

    def context(self) -> Context:
        return Context(self.link, self.node_id, self.od, self.options)

    def go(self, checks: list[Check], progress: Progress | None) -> None:
        initial = self.start()
        try:
            for n, chk in enumerate(checks):
                self.current = chk.name
                if progress is not None:
                    progress(n, len(checks), chk, None)
                result = self.one(chk)
                self.report.results.append(result)
                if progress is not None:
                    progress(n + 1, len(checks), chk, result)
            self.current = "the restoring of the NMT state"
        finally:  # an interrupted run restores the state too
            self.finish(initial)

    # ---- the node's state before and after

    def start(self) -> int | None:
        """The node's NMT state (from its heartbeat, switched on for a moment if need be);
        a STOPPED node is put into PRE-OPERATIONAL so that it answers SDO. Raises Error
        when the node answers neither then nor before (no node to check)."""
        ctx = self.context()
        mark = self.link.mark()
        state = None
        try:
            period: int | None = int.from_bytes(ctx.sdo.upload(0x1017, 0), "little")
            answered = True
        except (SdoAbort, SdoProtocolError):
            period, answered = None, True
        except NoAnswerError:
            period, answered = None, False
        if period:
            state = ctx.wait_error_control(mark, period / 1000 * 1.5 + self.options.timeout)
        elif period == 0:
            try:
                ctx.sdo.download(0x1017, 0, _PROBE_HEARTBEAT_MS.to_bytes(2, "little"))
                state = ctx.wait_error_control(mark, _PROBE_HEARTBEAT_MS / 1000 * 1.5
                                               + self.options.timeout)
                ctx.sdo.download(0x1017, 0, b"\0\0")
            except (SdoAbort, NoAnswerError, SdoProtocolError):
                pass
        elif not answered:  # a stopped node says so in its heartbeat, if it has one
            state = ctx.wait_error_control(mark, self.options.timeout)
        ctx.nmt("preop")
        try:
            ctx.sdo.upload(0x1000, 0)
        except (SdoAbort, SdoProtocolError):
            pass  # it answers: the checks judge how
        except NoAnswerError as exc:
            raise Error(f"node {self.node_id} does not answer SDO ({exc}), not even after "
                        "'enter pre-operational': is the node-ID right, the bus the node's, "
                        "its bit rate the bus's?") from None
        if state is None and not answered:  # SDO only after 'enter pre-operational'
            state = 0x04
            self.report.notes.append("NMT state before the run: STOPPED (no heartbeat; SDO "
                                     "answered only after 'enter pre-operational')")
            return state
        name = STATES.get(state, "unknown") if state is not None else "unknown (no heartbeat)"
        self.report.notes.append(f"NMT state before the run: {name}")
        return state

    def finish(self, initial: int | None) -> None:
        ctx = self.context()
        command = _RESTORE_COMMAND.get(initial or 0x7F, "preop")
        ctx.nmt(command)
        self.link.wait(0.01)
        self.report.notes.append(f"NMT state restored with the command '{command}'"
                                 if initial in _RESTORE_COMMAND
                                 else "NMT state left PRE-OPERATIONAL")

    # ---- one check

    def one(self, chk: Check) -> Result:
        began = time.monotonic()
        if chk.destructive and not self.options.destructive:
            return Result(chk, Status.SKIPPED, "saves or restores stored parameters: run "
                                               "with --destructive")
        self.link.forget()
        ctx = self.context()
        ctx.nmt("preop")
        status, reason = Status.PASSED, ""
        try:
            if not ctx.served("before the check (is the node there?)"):
                raise CheckEnded("no node")
            chk.run(ctx)
        except KeyboardInterrupt:
            self.undo(ctx)  # what the interrupted check changed goes back first
            raise
        except Skipped as exc:
            status, reason = Status.SKIPPED, str(exc)
        except CheckEnded as exc:
            reason = str(exc)
        except (SdoAbort, NoAnswerError, SdoProtocolError) as exc:
            ctx.finding("an SDO transfer of the check", "success", outcome(exc))
        except Error as exc:
            ctx.finding("the check", "no error", f"error of the tester: {exc}")
        except Exception as exc:  # a bug of the tester: say so, keep going
            log.exception("check %s", chk.name)
            ctx.finding("the check", "no error", f"error of the tester: "
                        f"{type(exc).__name__}: {exc}")
        self.undo(ctx)
        if ctx.findings:
            status = Status.FAILED
        return Result(chk, status, reason, ctx.findings, ctx.notes, time.monotonic() - began)

    def undo(self, ctx: Context) -> None:
        """Put back what the check changed: PRE-OPERATIONAL first (PDO parameters take
        writes there), then the undo actions, last registered first."""
        ctx.nmt("preop")
        for label, fn in reversed(ctx.undo):
            try:
                fn()
            except CheckEnded:
                pass  # its finding is recorded; the other undo actions still run
            except (SdoAbort, NoAnswerError, SdoProtocolError) as exc:
                ctx.finding(label, "success", outcome(exc))
