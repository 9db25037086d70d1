# SPDX-License-Identifier: Apache-2.0
"""Which client gives up its slot when a new one comes and every slot is taken.

Pure: :func:`victim` looks at what each client did and when, nothing else. The first
rule that matches a client picks it; within a rule, the one that has been so longest:

1. silent: never sent a complete line (nor, where a token is asked for, proved it): it
   has had its chance; the one connected longest first;
2. stuck: a reply or event has waited ``quiet_s`` or more to be written (the client does
   not read);
3. quiet: neither a line from it nor a reply written to it for ``quiet_s`` or more, and
   not waiting for events;
4. quiet and waiting for events.

Never picked: a client with a request running, or traffic (a line from it, a reply
written to it) within the last ``quiet_s``. When every client is such a one, nobody is
picked and the newcomer is refused instead. So a flood of new connections, silent or
churning, only ever replaces itself, and a client in use keeps its slot.
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import Protocol, TypeVar

__all__ = ["QUIET_S", "Activity", "victim"]

#: Seconds without traffic after which a client counts as quiet (its slot may go).
QUIET_S = 10.0


class Activity(Protocol):
    """What the rules read of a client (times on one monotonic clock, in seconds)."""

    @property
    def connected_at(self) -> float: ...

    @property
    def last_line_at(self) -> float | None:
        """Its last complete line (None: none yet)."""
        ...

    @property
    def last_reply_at(self) -> float | None:
        """The last reply or event written to it (None: none yet)."""
        ...

    @property
    def unwritten_since(self) -> float | None:
        """Since when a reply or event has waited to be written (None: nothing waits)."""
        ...

    @property
    def running(self) -> bool: ...

    @property
    def listening(self) -> bool: ...


A = TypeVar("A", bound=Activity)


def victim(clients: Iterable[A], now: float, quiet_s: float = QUIET_S) -> tuple[A, str] | None:
    """The client whose slot goes to a newcomer, and why (for the log); None when every
    client is running a request or had traffic within ``quiet_s``."""
    best: tuple[tuple[int, float], A, str] | None = None
    for client in clients:
        ranked = _rank(client, now, quiet_s)
        if ranked is not None and (best is None or ranked[0] < best[0]):
            best = (ranked[0], client, ranked[1])
    return None if best is None else (best[1], best[2])


def _rank(c: Activity, now: float, quiet_s: float) -> tuple[tuple[int, float], str] | None:
    """(rule, minus how long) and the reason; None for a client that keeps its slot."""
    if c.running:
        return None
    if c.last_line_at is None:
        age = now - c.connected_at
        return (1, -age), f"silent since it connected {age:.1f} s ago"
    if c.unwritten_since is not None and now - c.unwritten_since >= quiet_s:
        waited = now - c.unwritten_since
        return (2, -waited), f"its replies unread for {waited:.1f} s"
    quiet = now - max(c.last_line_at, c.last_reply_at or c.last_line_at)
    if quiet < quiet_s:
        return None
    rule = 4 if c.listening else 3
    return (rule, -quiet), f"quiet for {quiet:.1f} s"
