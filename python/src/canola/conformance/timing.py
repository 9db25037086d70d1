# SPDX-License-Identifier: Apache-2.0
"""Timing checks on a shared host: a period measured from the bus's timestamps, judged only
when the tester itself ran on time.

A node that is late and a host too busy to run the node (or the bridge to it, or the tester)
on time look the same in the frames. So a measurement that shows a problem while the
tester's own process was starved for more than the tolerance of a period is measured again;
when every one of :data:`ATTEMPTS` was starved, the check is SKIPPED as inconclusive, with
the reason. A tester that ran on time judges: a late node fails on a quiet host."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from itertools import pairwise

from canola.conformance.context import Context
from canola.conformance.link import Seen

__all__ = ["ATTEMPTS", "Measured", "judged"]

#: Measurements of a period while the tester itself was starved, at most.
ATTEMPTS = 3


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


def judged(ctx: Context, period_s: float, late: str, measure: Callable[[], Measured], *,
           clause: str = "") -> Measured:
    """The first measurement that shows no problem or ran while the tester was starved for
    at most the tolerance of ``period_s``; each problem is then a finding (of ``clause``
    when narrower than the check's). ``late`` says what the problems mean in the
    inconclusive verdict ("heartbeats came late")."""
    for attempt in range(1, ATTEMPTS + 1):
        began = ctx.link.now()
        measured = measure()
        starved = max(ctx.link.stalled(began), measured.behind)
        problems = measured.problems
        if not problems or starved <= ctx.options.tolerance * period_s:
            for what, expected, got in problems:
                ctx.finding(what, expected, got, clause=clause)
            return measured
        ctx.note(f"attempt {attempt}: {problems[0][0]} {problems[0][2]}, while the tester "
                 f"itself was starved for {starved * 1000:.0f} ms: measured again")
    ctx.skip(f"inconclusive: the tester itself was starved (up to {starved * 1000:.0f} ms) "
             f"in each of {ATTEMPTS} measurements, and {late} (the last: {problems[0][0]} "
             f"{problems[0][2]}): a late node cannot be told from a starved host; measure on "
             "a quieter host")
