# SPDX-License-Identifier: Apache-2.0
"""Group ``nmt``: boot-up after the resets, the state machine seen in heartbeats, SDO
gating, what the resets do to the values, the heartbeat period, node guarding, and (with
``--destructive``) storing and restoring parameters."""

from __future__ import annotations

import statistics
from collections.abc import Callable
from contextlib import suppress
from functools import partial
from itertools import pairwise

from canola import SdoAbort
from canola.conformance import pdo_tools as pt
from canola.conformance import timing
from canola.conformance.context import (
    APPLICATION_REFUSALS,
    STATES,
    Context,
    abort_text,
    outcome,
)
from canola.conformance.entries import (
    ACTING,
    another_number,
    describe,
    integer_range,
    variables,
    writable,
)
from canola.conformance.rawsdo import NoAnswerError, SdoProtocolError
from canola.conformance.registry import check
from canola.formats import eds, values

__all__ = ["heartbeat", "reset"]

_HEARTBEAT_MS = 100
_INTERVALS = 10
_TRANSITIONS = (("start", 0x05), ("stop", 0x04), ("preop", 0x7F), ("stop", 0x04),
                ("start", 0x05), ("preop", 0x7F))
#: Communication entries a reset check may change (their change has no side effect).
_COMM_CANDIDATES = (0x1017, 0x100C, 0x1015, 0x1007)
#: Between two guarding requests while the node takes an NMT command.
_GUARD_RETRY_S = 0.02
_SAVE = int.from_bytes(b"save", "little")
_LOAD = int.from_bytes(b"load", "little")


def reset(ctx: Context, command: str) -> float:
    """Send reset-node or reset-comm and wait for exactly one boot-up frame; the seconds it
    took. No boot-up ends the check."""
    cob = ctx.heartbeat_cob()
    mark = ctx.link.mark()
    began = ctx.link.now()
    ctx.nmt(command)
    seen = ctx.link.wait_frame(lambda f: f.can_id == cob and f.data == b"\0" and not f.rtr,
                               ctx.options.boot_timeout, mark)
    if seen is None:
        ctx.fail(f"NMT {command}", f"a boot-up frame {cob:03X} [00] within "
                 f"{ctx.options.boot_timeout:g} s", "none")
    took = ctx.link.now() - began
    _after_bootup(ctx, seen.pos + 1)
    boots = ctx.link.frames_since(mark, lambda f: f.can_id == cob and f.data == b"\0")
    if len(boots) != 1:
        ctx.finding(f"NMT {command}", "one boot-up frame", f"{len(boots)}")
    return took


def _after_bootup(ctx: Context, since: int) -> None:
    """Wait until the node's next error control frame after its boot-up tells whether the
    boot-up came once: with a heartbeat producer (0x1017 after the reset) until its first
    heartbeat (up to 1 + 2 x tolerance periods and the answer time-out: a starved node's
    heartbeat comes late, never not), else for ``quiet`` seconds."""
    period = 0
    # the check reads 0x1000 next and says so when SDO does not answer
    with suppress(SdoAbort, NoAnswerError, SdoProtocolError):
        if ctx.var(0x1017, 0) is not None:
            period = int.from_bytes(ctx.sdo.upload(0x1017, 0), "little")
    if not period:
        ctx.link.wait(ctx.options.quiet)
        return
    limit = period / 1000 * (1 + 2 * ctx.options.tolerance) + ctx.options.timeout
    cob = ctx.heartbeat_cob()
    ctx.link.wait_frame(lambda f: f.can_id == cob and not f.rtr, limit, since)


def heartbeat(ctx: Context) -> int:
    """Make the node produce heartbeats (0x1017 set to 100 ms for the check when it can be
    written, else its own period); the period in ms. SKIPPED without a producer."""
    var = ctx.need(0x1017, why="no heartbeat producer")
    if writable(var):
        ctx.write_temp(0x1017, 0, _HEARTBEAT_MS.to_bytes(2, "little"))
        return _HEARTBEAT_MS
    period = ctx.read_uint(0x1017)
    if not period:
        ctx.skip("0x1017 is 0 and read-only: the heartbeat producer is off")
    return period


def _bootup(command: str, when: str) -> Callable[[Context], None]:
    def bootup(ctx: Context) -> None:
        took = reset(ctx, command)
        ctx.served(f"after {when}")
        ctx.note(f"boot-up after {took:.3f} s")

    return bootup


for _command, _when in (("reset-node", "reset node"), ("reset-comm", "reset communication")):
    check(f"nmt.bootup_{_command.replace('-', '_')}", clause="CiA 301 §7.2.8.3.1, §7.2.8.3.3",
          title=f"after {_when}: one boot-up frame, then SDO in PRE-OPERATIONAL")(
        _bootup(_command, _when))


@check("nmt.states", clause="CiA 301 §7.2.8.3.1, §7.3.2",
       title="start, stop and enter pre-operational reach their states, seen in heartbeats "
             "(in every state)")
def states(ctx: Context) -> None:
    period = heartbeat(ctx)
    wait = 2 * period / 1000 + ctx.options.timeout
    for command, state in _TRANSITIONS:
        mark = ctx.link.mark()
        ctx.nmt(command)
        if ctx.wait_error_control(mark, wait, (state,)) is None:
            seen = [STATES.get(s.frame.data[0] & 0x7F, hex(s.frame.data[0])) for s in
                    ctx.link.frames_since(mark, lambda f: f.can_id == ctx.heartbeat_cob())]
            ctx.fail(f"NMT {command}", f"a heartbeat {STATES[state]} within {wait:g} s",
                     ", ".join(seen) or "no heartbeat")
    ctx.note(" -> ".join(STATES[s] for _, s in _TRANSITIONS))


@check("nmt.sdo_gating", clause="CiA 301 §7.3.2 (services per state)",
       title="no SDO answer in STOPPED; SDO in PRE-OPERATIONAL and OPERATIONAL")
def sdo_gating(ctx: Context) -> None:
    ctx.enter("stop")
    mark = ctx.sdo.send(bytes([0x40, 0x00, 0x10, 0x00]))
    ctx.link.wait(ctx.options.quiet)
    answers = ctx.link.frames_since(mark, lambda f: f.can_id == ctx.sdo.tx)
    if answers:
        ctx.finding("SDO upload 0x1000:0 in STOPPED", f"no answer within "
                    f"{ctx.options.quiet:g} s", f"[{answers[0].frame.data.hex(' ').upper()}]")
    ctx.enter("start")
    ctx.served("in OPERATIONAL")
    ctx.enter("preop")
    ctx.served("in PRE-OPERATIONAL")


@check("nmt.heartbeat_period", clause="CiA 301 §7.2.8.3.2.2, §7.5.2.20",
       title="heartbeats come at the 0x1017 period (median within the tolerance, no gap over "
             "1 + 2 x tolerance periods) and stop at 0")
def heartbeat_period(ctx: Context) -> None:
    period = heartbeat(ctx)
    p = period / 1000
    ctx.link.wait(p)  # the period set takes effect
    measured = timing.judged(ctx, p, "heartbeats came late", partial(_heartbeats, ctx, period),
                             clause="CiA 301 §7.2.8.3.2.2 (heartbeat producer time, 0x1017)")
    gaps = measured.gaps
    ctx.note(f"{period} ms: {len(gaps)} intervals, median {statistics.median(gaps) * 1000:.1f}"
             f" ms, {min(gaps) * 1000:.1f}..{max(gaps) * 1000:.1f} ms")
    if measured.behind > p:
        ctx.note(f"the tester saw heartbeats up to {measured.behind:.2f} s late (its own "
                 "stall, not the node's: the bus's timestamps are judged)")
    var = ctx.var(0x1017, 0)
    if var is not None and writable(var):
        ctx.write(0x1017, 0, b"\0\0")
        ctx.link.wait(p)
        mark = ctx.link.mark()
        ctx.link.wait(3 * p)
        cob = ctx.heartbeat_cob()
        beats = ctx.link.frames_since(
            mark, lambda f: f.can_id == cob and len(f.data) == 1 and not f.rtr)
        if beats:
            ctx.finding("heartbeats after 0x1017 = 0", f"none in {3 * period} ms",
                        f"{len(beats)}", clause="CiA 301 §7.5.2.20 (0: not used)")


def _heartbeats(ctx: Context, period: int) -> timing.Measured:
    """Measure the next heartbeat intervals by the bus's timestamps (a node late shows in
    them, the tester's own stall does not: the frames reach it late, in a burst). No
    heartbeats end the check."""
    p = period / 1000
    tol = ctx.options.tolerance
    cob = ctx.heartbeat_cob()
    seen = timing.periodic(ctx, lambda f: f.can_id == cob and len(f.data) == 1 and not f.rtr,
                           _INTERVALS + 1, p)
    if len(seen) <= _INTERVALS:
        ctx.fail(f"heartbeats at {period} ms", f"{_INTERVALS + 1} heartbeats", f"{len(seen)}",
                 clause="CiA 301 §7.2.8.3.2.2")
    measured = timing.Measured(seen)
    gaps = measured.gaps
    measured.median_near(f"median heartbeat interval (0x1017 = {period} ms)", p, tol)
    if max(gaps) > p * (1 + 2 * tol):
        measured.problems.append((f"longest heartbeat interval (0x1017 = {period} ms)",
                                  f"at most {period * (1 + 2 * tol):g} ms",
                                  f"{max(gaps) * 1000:.1f} ms"))
    return measured


def _comm_entry(ctx: Context) -> eds.Variable:
    for index in _COMM_CANDIDATES:
        var = ctx.var(index, 0)
        if var is not None and var.access_type == "rw" and integer_range(var) is not None:
            return var
    ctx.skip("the EDS has none of 0x1017, 0x100C, 0x1015, 0x1007 as a writable entry")


def _app_entry(ctx: Context) -> eds.Variable | None:
    """A plain read-write integer entry of the application (0x2000.., manufacturer area
    first), or None."""
    found = [v for v in variables(ctx.od) if v.index >= 0x2000 and v.access_type == "rw"
             and integer_range(v) is not None and v.index not in ACTING]
    found.sort(key=lambda v: not 0x2000 <= v.index <= 0x5FFF)
    return found[0] if found else None


def _number(ctx: Context, var: eds.Variable) -> int:
    assert var.data_type is not None
    value = values.decode(var.data_type, ctx.read(var.index, var.subindex))
    assert isinstance(value, int)
    return int(value)


def _put(ctx: Context, var: eds.Variable, value: int) -> None:
    assert var.data_type is not None
    ctx.write(var.index, var.subindex, values.encode(var.data_type, value))


def _put_probe(ctx: Context, var: eds.Variable, value: int) -> None:
    """Write ``value`` to an application entry: its application may refuse it (the check
    does not apply then); any other failure ends the check."""
    assert var.data_type is not None
    error = ctx.try_write(var.index, var.subindex, values.encode(var.data_type, value))
    if isinstance(error, SdoAbort) and error.code in APPLICATION_REFUSALS:
        ctx.not_applicable(f"the value {value} for {describe(var)}", error)
    if error is not None:
        ctx.fail(f"write {value} to {describe(var)}", "success", outcome(error))


def _expect_value(ctx: Context, var: eds.Variable, expected: int, after: str,
                  clause: str) -> None:
    got = _number(ctx, var)
    if got != expected:
        ctx.finding(f"{describe(var)} after {after}", f"{expected}", f"{got}", clause=clause)


def _reset_values(ctx: Context, command: str, app_restored: bool) -> None:
    comm = _comm_entry(ctx)
    app = _app_entry(ctx)
    for var in (comm, app):
        if var is not None:
            ctx.keep(var.index, var.subindex)
    reset(ctx, command)  # the power-on values (defaults, or stored ones)
    comm0 = _number(ctx, comm)
    app0 = _number(ctx, app) if app is not None else 0
    _put(ctx, comm, another_number(comm, comm0))
    if app is not None:
        _put_probe(ctx, app, another_number(app, app0))
    reset(ctx, command)
    area = "communication and application" if app_restored else "communication"
    power_on = (f"CiA 301 §7.3.2.2.1: NMT {command} sets the {area} parameters to their "
                "power-on values (defaults, or stored ones)")
    _expect_value(ctx, comm, comm0, f"NMT {command}", power_on)
    if app is not None:
        _expect_value(ctx, app, app0 if app_restored else another_number(app, app0),
                      f"NMT {command}", power_on if app_restored else
                      "CiA 301 §7.3.2.2.1: reset communication leaves the application "
                      "parameters")
    ctx.note(f"{describe(comm)}" + (f", {describe(app)}" if app is not None else
                                    " (the EDS has no plain writable application integer)"))


@check("nmt.reset_comm_values", clause="CiA 301 §7.3.2.2.1 (reset communication)",
       title="reset communication restores a communication entry's power-on value and "
             "keeps an application value")
def reset_comm_values(ctx: Context) -> None:
    _reset_values(ctx, "reset-comm", app_restored=False)


@check("nmt.reset_node_values", clause="CiA 301 §7.3.2.2.1 (reset application)",
       title="reset node restores the power-on values of a communication and an "
             "application entry")
def reset_node_values(ctx: Context) -> None:
    _reset_values(ctx, "reset-node", app_restored=True)


@check("nmt.node_guarding", clause="CiA 301 §7.2.8.3.2.1",
       title="guarding requests are answered with the state and an alternating toggle bit, "
             "in PRE-OPERATIONAL and STOPPED")
def node_guarding(ctx: Context) -> None:
    ctx.need(0x100C, why="no node guarding")
    ctx.need(0x100D, why="no node guarding")
    if not ctx.link.remote_frames:
        ctx.skip("this bus cannot send the guarding request (a remote frame): python-can's "
                 "socketcand client sends every frame as data")
    hb = ctx.var(0x1017, 0)
    if hb is not None and ctx.read_uint(0x1017):
        if not writable(hb):
            ctx.skip("the heartbeat producer is on (0x1017 read-only): no guarding")
        ctx.write_temp(0x1017, 0, b"\0\0")
    toggles: list[int] = []
    before = 0x7F
    for command, state in ((None, 0x7F), (None, 0x7F), (None, 0x7F), ("stop", 0x04),
                           ("preop", 0x7F)):
        if command is not None:
            ctx.nmt(command)
        until = ctx.link.now() + (ctx.options.timeout if command is not None else 0.0)
        answer = _guard(ctx, state)
        toggles.append(answer >> 7)
        # a node may take the command in a while: meanwhile it answers with the state before
        while answer & 0x7F == before != state and ctx.link.now() < until:
            ctx.link.wait(_GUARD_RETRY_S)
            answer = _guard(ctx, state)
            toggles.append(answer >> 7)
        if answer & 0x7F != state:
            ctx.fail(f"guarding answer in {STATES[state]}", f"1 byte, state 0x{state:02X}",
                     f"[{answer:02X}]")
        before = state
    if any(a == b for a, b in pairwise(toggles)):
        ctx.finding("toggle bits of consecutive guarding answers", "alternating",
                    " ".join(map(str, toggles)))
    ctx.note(f"toggles {' '.join(map(str, toggles))}")


def _guard(ctx: Context, state: int) -> int:
    """Send a guarding request (RTR) and return the answer's byte; no answer, or one not
    of 1 byte, ends the check (``state``: the one expected, for the message)."""
    cob = ctx.heartbeat_cob()
    mark = ctx.link.mark()
    ctx.link.send(cob, rtr=True)
    seen = ctx.link.wait_frame(lambda f: f.can_id == cob and not f.rtr, ctx.options.timeout,
                               mark)
    if seen is None:
        ctx.fail(f"guarding request in {STATES[state]}", "an answer", "none")
    data = seen.frame.data
    if len(data) != 1:
        ctx.fail(f"guarding answer in {STATES[state]}", f"1 byte, state 0x{state:02X}",
                 f"[{data.hex(' ').upper()}]")
    return data[0]


@check("nmt.store_restore", clause="CiA 301 §7.5.2.13, §7.5.2.14", destructive=True,
       title="0x1010 'save' keeps a value over reset communication, a wrong signature is "
             "refused (0x08000020), 0x1011 'load' brings the default back")
def store_restore(ctx: Context) -> None:
    sub = 2 if ctx.var(0x1010, 2) is not None else 1
    ctx.need(0x1010, sub, why="no parameter storage")
    ctx.need(0x1011, sub, why="no restore of defaults")
    if not ctx.read_uint(0x1010, sub) & 1:
        ctx.skip(f"0x1010:{sub} says the node does not save on command")
    comm = _comm_entry(ctx)
    if comm.default is None or not isinstance(comm.default, int):
        ctx.skip(f"the EDS gives no default of {describe(comm)}")
    ctx.keep(comm.index, comm.subindex)
    for index in (0x1010, 0x1011):
        ctx.expect_abort(f"write a wrong signature to 0x{index:04X}:{sub}", (0x08000020,),
                         partial(ctx.sdo.download, index, sub, b"nope"))
    saved = another_number(comm, comm.default)
    _put(ctx, comm, saved)
    ctx.write_uint(0x1010, sub, _SAVE, 4)
    _put(ctx, comm, another_number(comm, saved))
    reset(ctx, "reset-comm")
    _expect_value(ctx, comm, saved, "save and reset communication",
                  "CiA 301 §7.5.2.13: the values saved are the power-on values of the next "
                  "reset communication")
    ctx.write_uint(0x1011, sub, _LOAD, 4)
    reset(ctx, "reset-comm")
    _expect_value(ctx, comm, comm.default, "load and reset communication",
                  "CiA 301 §7.5.2.14: after 'load' the next reset communication brings the "
                  "defaults")
    ctx.note(f"{describe(comm)}; wrong signatures: {abort_text(0x08000020)}")



@check("nmt.pdo_gating", clause="CiA 301 §7.3.2 (services per state)",
       title="RPDOs are applied and TPDOs sent in OPERATIONAL only (not in PRE-OPERATIONAL "
             "or STOPPED)")
def pdo_gating(ctx: Context) -> None:
    rpdo = pt.usable_pdo(ctx, tpdo=False, need_writable=True)
    tpdo = pt.usable_pdo(ctx, tpdo=True)
    if rpdo is None and tpdo is None:
        ctx.skip("no PDO in the EDS maps (or can map) entries SDO can read back")
    tested = []
    if tpdo is not None:
        tcob = pt.configure(ctx, tpdo[0], entries=tpdo[1], type=255,
                            event=_HEARTBEAT_MS).cob & 0x7FF
        tested.append(tpdo[0].name)
    if rpdo is not None:
        rcob = pt.configure(ctx, rpdo[0], entries=rpdo[1], type=255).cob & 0x7FF
        for m in pt.mapped(ctx, rpdo[1]):
            if m.var is not None:
                ctx.keep(m.var.index, m.var.subindex)
        # one payload for all states: where it must not be applied, the values stay
        frame, expected = pt.rpdo_payload(ctx, rpdo[1])
        tested.append(rpdo[0].name)
    for command, state in ((None, "PRE-OPERATIONAL"), ("stop", "STOPPED"),
                           ("start", "OPERATIONAL")):
        if command is not None:
            ctx.enter(command)  # the node takes the RPDO in the state it reports
        mark = ctx.link.mark()
        if rpdo is not None:
            ctx.link.send(rcob, frame)
        if tpdo is not None and state == "OPERATIONAL":  # a starved node's comes late
            ctx.link.wait_frame(lambda f: f.can_id == tcob and not f.rtr,
                                3 * _HEARTBEAT_MS / 1000 + ctx.options.timeout, mark)
        else:  # none may come: watch for three event timer periods
            ctx.link.wait(max(ctx.options.quiet, 3 * _HEARTBEAT_MS / 1000))
        if tpdo is not None:
            sent = pt.tpdo_frames(ctx, tcob, mark)
            if bool(sent) != (state == "OPERATIONAL"):
                ctx.finding(f"{tpdo[0].name} (event timer {_HEARTBEAT_MS} ms) in {state}",
                            "frames" if state == "OPERATIONAL" else "no frame",
                            f"{len(sent)} frames")
        if rpdo is not None:
            if command == "stop":
                ctx.enter("preop")  # SDO reads back what the RPDO in STOPPED did
            pt.check_values(ctx, expected, applied=state == "OPERATIONAL",
                            when=f"after {rpdo[0].name} in {state}")
    ctx.note(", ".join(tested))
