# SPDX-License-Identifier: Apache-2.0
"""The bytes the gateway holds for its clients: request lines being read, accepted and not
yet run, replies not yet written. Bounded per client (:class:`Share`) and over all clients
(:class:`Budget`).

A request line is accepted only when it fits both bounds; one that does not is answered
``ERROR:600`` (out of memory) and dropped, and what was accepted before it is untouched.
(The connection does not even collect a line longer than the room left: it skips the
rest of it, so a refused line costs no memory either.)
A reply cannot be refused (its request ran): it is held even past the bounds, and the
client's next request does not run while its replies waiting to be written reach its
bound (a client that does not read stalls itself, nobody else). So the bytes held are at
most the total bound plus one reply per client (a reply is at most about 4/3 of the
largest SDO upload, base64).
"""

from __future__ import annotations

import asyncio

__all__ = ["MAX_QUEUED", "MAX_QUEUED_TOTAL", "Budget", "Share"]

MAX_QUEUED = 8 * 1024 * 1024  # per client: two of the longest lines
MAX_QUEUED_TOTAL = 32 * 1024 * 1024  # over all clients


class Budget:
    """Bytes held over all clients, at most ``limit`` for new request lines."""

    def __init__(self, limit: int = MAX_QUEUED_TOTAL) -> None:
        self.limit = limit
        self.used = 0
        self.peak = 0

    def fits(self, n: int) -> bool:
        return self.used + n <= self.limit

    def take(self, n: int) -> None:
        self.used += n
        self.peak = max(self.peak, self.used)

    def give(self, n: int) -> None:
        self.used -= n


class Share:
    """One client's part of ``budget``: at most ``limit`` bytes of request lines and
    replies held for it."""

    def __init__(self, budget: Budget, limit: int = MAX_QUEUED) -> None:
        self.budget = budget
        self.limit = limit
        self.used = 0
        self.replies = 0  # of which replies not yet written
        self.partial = 0  # of which the part of a line still coming
        self._room = asyncio.Event()
        self._room.set()

    def room(self) -> int:
        """The longest request line this share and the budget could hold now."""
        return max(0, min(self.limit - self.used, self.budget.limit - self.budget.used))

    def hold_partial(self, n: int) -> None:
        """Hold ``n`` bytes for the part of a line read so far (instead of the last
        count): a line on its way takes room as it grows, so the bounds hold for lines
        being read too."""
        self._take(n - self.partial)
        self.partial = n

    def accept(self, n: int) -> bool:
        """Hold a request line of ``n`` bytes, if it fits this share and the budget."""
        if self.used + n > self.limit or not self.budget.fits(n):
            return False
        self._take(n)
        return True

    def ran(self, n: int) -> None:
        """The request of ``n`` bytes ran: no longer held."""
        self._give(n)

    def reply(self, n: int) -> None:
        """Hold a reply of ``n`` bytes until :meth:`written` (whatever the bounds)."""
        self._take(n)
        self.replies += n
        if self.replies >= self.limit:
            self._room.clear()

    def written(self, n: int) -> None:
        self._give(n)
        self.replies -= n
        if self.replies < self.limit:
            self._room.set()

    async def room_for_replies(self) -> None:
        """Wait until the replies waiting to be written are below the bound."""
        await self._room.wait()

    def release(self) -> None:
        """The client is gone: everything held for it goes back to the budget."""
        self.budget.give(self.used)
        self.used = self.replies = self.partial = 0
        self._room.set()

    def _take(self, n: int) -> None:
        self.used += n
        self.budget.take(n)

    def _give(self, n: int) -> None:
        self.used -= n
        self.budget.give(n)
