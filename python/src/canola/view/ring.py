# SPDX-License-Identifier: Apache-2.0
"""A bounded log with sequence numbers: each reader keeps the number of the last item it
took, and :meth:`Ring.since` gives what came after it (the oldest left out once the ring
is full, and how many)."""

from __future__ import annotations

import itertools
from collections import deque
from typing import Generic, TypeVar

__all__ = ["Ring"]

T = TypeVar("T")


class Ring(Generic[T]):
    def __init__(self, size: int) -> None:
        self._items: deque[T] = deque(maxlen=size)
        self.last = 0  # the sequence number of the newest item (0: none yet)

    def __len__(self) -> int:
        return len(self._items)

    def add(self, item: T) -> None:
        self._items.append(item)
        self.last += 1

    def since(self, seq: int, limit: int) -> tuple[list[T], int, int]:
        """The items after number ``seq``, at most the newest ``limit``: (items, the number
        of the last one, how many newer than ``seq`` were left out)."""
        seq = min(max(seq, 0), self.last)
        new = min(self.last - seq, len(self._items))
        missed = self.last - seq - new  # gone from the ring before this reader came back
        take = min(new, limit)
        items = list(itertools.islice(reversed(self._items), take))[::-1]
        return items, self.last, missed + new - take
