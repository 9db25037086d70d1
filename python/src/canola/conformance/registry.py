# SPDX-License-Identifier: Apache-2.0
"""The checks of the suite: what each is called, its group, the clause it tests, and the
function that runs it. Check modules register with :func:`check` when
:mod:`canola.conformance.checks` is imported (:func:`select` and ``canola.conformance.CHECKS``
do that); the runner and ``--list`` read :data:`CHECKS` (grouped by :data:`GROUPS`)."""

from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import dataclass
from typing import TYPE_CHECKING

from canola.errors import Error

if TYPE_CHECKING:
    from canola.conformance.context import Context

__all__ = ["CHECKS", "GROUPS", "Check", "check", "select"]

#: The groups, in the order they run, with what they cover.
GROUPS: dict[str, str] = {
    "dictionary": "the node's object dictionary against its EDS",
    "sdo": "SDO protocol: expedited, segmented and block transfer, protocol errors",
    "nmt": "NMT state machine and error control (boot-up, heartbeat, node guarding)",
    "pdo": "PDO mapping procedure, transmission types, RPDO processing",
    "sync": "SYNC consumer and producer, counter overflow",
    "emcy": "EMCY producer, error register, pre-defined error field",
    "time": "TIME consumer configuration",
}


@dataclass(frozen=True)
class Check:
    """One check: ``name`` (``group.what``), ``clause`` (the CiA 301/306 clauses it tests),
    ``title`` (what passes), ``destructive`` (needs ``--destructive``), ``run``."""

    name: str
    group: str
    clause: str
    title: str
    run: Callable[[Context], None]
    destructive: bool = False


CHECKS: list[Check] = []


def check(name: str, *, clause: str, title: str,
          destructive: bool = False) -> Callable[[Callable[[Context], None]],
                                                 Callable[[Context], None]]:
    """Register the decorated function as the check ``name`` (its group is the part before
    the first dot)."""
    group = name.split(".", 1)[0]
    if group not in GROUPS:
        raise Error(f"check {name}: unknown group {group!r}")
    if any(c.name == name for c in CHECKS):
        raise Error(f"check {name} is registered twice")

    def register(fn: Callable[[Context], None]) -> Callable[[Context], None]:
        CHECKS.append(Check(name, group, clause, title, fn, destructive))
        return fn

    return register


def select(only: Iterable[str] = ()) -> list[Check]:
    """The checks to run, grouped in :data:`GROUPS` order: all of them, or those whose
    group or name is in ``only``. Raises Error naming an unknown group or check."""
    from canola.conformance import checks  # noqa: F401, PLC0415 -- registers them

    wanted = list(only)
    names = {c.name for c in CHECKS}
    for item in wanted:
        if item not in GROUPS and item not in names:
            raise Error(f"unknown group or check {item!r} (groups: {', '.join(GROUPS)}; "
                        "--list shows the checks)")
    chosen = [c for c in CHECKS if not wanted or c.group in wanted or c.name in wanted]
    order = list(GROUPS)
    return sorted(chosen, key=lambda c: order.index(c.group))
