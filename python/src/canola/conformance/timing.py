# SPDX-License-Identifier: Apache-2.0
"""Timing checks on a shared host: a period measured from the bus's timestamps, judged only
when the host ran the tester (and whatever shares the host with it) on time.

A node that is late and a host too busy to run the node (or the bridge to it, or the tester)
on time look the same in the frames. So a measurement that shows a problem while the host
was starved (starvation.py: the tester's own stalls, the host's tasks waiting for a CPU)
for more than the tolerance of a period is measured again; when every one of
:data:`ATTEMPTS` was starved, the check is SKIPPED as inconclusive, with the reason. On a
quiet host the measurement judges: a late node fails."""

from __future__ import annotations

import statistics
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from itertools import pairwise

from canola.conformance.context import Context
from canola.conformance.link import Match, Seen
from canola.conformance.starvation import Starvation

__all__ = ["ATTEMPTS", "Measured", "judged", "periodic"]

#: Measurements of a period while the tester itself was starved, at most.
ATTEMPTS = 3


def periodic(ctx: Context, match: Match, frames: int, period_s: float,
             since: int | None = None) -> list[Seen]:
    """The next ``frames`` frames ``match`` takes after ``since`` (default: now), fewer when
    they did not come while ``frames`` periods, the tolerance twice over and the answer
    time-out went by."""
    limit = frames * period_s * (1 + 2 * ctx.options.tolerance) + ctx.options.timeout
    start = ctx.link.mark() if since is None else since
    return ctx.link.wait_count(match, frames, limit, start)[:frames]


@dataclass
class Measured:
    """The frames of one measurement (in bus order) and what is wrong with their timing,
    each problem as (what, expected, got)."""

    seen: Sequence[Seen]
    problems: list[tuple[str, str, str]] = field(default_factory=list)

    @property
    def gaps(self) -> list[float]:
        """The intervals between the frames by the bus's timestamps, in seconds."""
        return [b.frame.timestamp - a.frame.timestamp for a, b in pairwise(self.seen)]

    @property
    def behind(self) -> float:
        """How much later than the bus the tester read some frames than others (seconds):
        its own lag, which the bus's timestamps leave out."""
        lags = [s.t - s.frame.timestamp for s in self.seen]
        return max(lags) - min(lags) if lags else 0.0

    def median_near(self, what: str, period_s: float, tolerance: float) -> None:
        """A problem ``what`` when the median interval is off ``period_s`` by more than
        ``tolerance`` (a fraction): a stall of the node or the tester moves it least."""
        middle = statistics.median(self.gaps)
        if abs(middle - period_s) > tolerance * period_s:
            self.problems.append((what, f"{period_s * 1000:g} ms ± {tolerance * 100:g} %",
                                  f"{middle * 1000:.1f} ms"))


def judged(ctx: Context, period_s: float, late: str, measure: Callable[[], Measured], *,
           clause: str = "") -> Measured:
    """The first measurement that shows no problem or ran while the host was starved for at
    most the tolerance of ``period_s``; each problem is then a finding (of ``clause`` when
    narrower than the check's). ``late`` says what the problems mean in the inconclusive
    verdict ("heartbeats came late")."""
    for attempt in range(1, ATTEMPTS + 1):
        since = ctx.link.since()
        measured = measure()
        host = ctx.link.starved(since)
        starved = Starvation(max(host.stall, measured.behind), host.cpu_wait)
        problems = measured.problems
        if not problems or starved.worst <= ctx.options.tolerance * period_s:
            for what, expected, got in problems:
                ctx.finding(what, expected, got, clause=clause)
            return measured
        ctx.note(f"attempt {attempt}: {problems[0][0]} {problems[0][2]}, while the host was "
                 f"starved ({starved}): measured again")
    ctx.skip(f"inconclusive: the host was starved in each of {ATTEMPTS} measurements (the "
             f"last: {starved}), and {late} (the last: {problems[0][0]} {problems[0][2]}): a "
             "late node cannot be told from a starved host; measure on a quieter host")
