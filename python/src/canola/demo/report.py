# SPDX-License-Identifier: Apache-2.0
"""The demo's verdict: one :class:`Step` per stage of the flow, printed as a table with
a check mark or a cross, or as JSON."""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Any

__all__ = ["STEPS", "Step", "failure_line", "summary_json", "summary_table"]

#: The steps of the flow, in order: (key, title).
STEPS: tuple[tuple[str, str], ...] = (
    ("master-online", "the master's online status (its boot-up, 0x73F)"),
    ("boot-up", "boot-ups seen by the master"),
    ("pre-operational", "NMT enter pre-operational"),
    ("manager", "the CANopen manager boots the network (CiA 302-2)"),
    ("heartbeat", "heartbeat producer configured by SDO and monitored"),
    ("pdo-mapping", "PDO mapping configured by SDO"),
    ("start", "NMT start: every node operational"),
    ("sync-tpdo", "SYNC drives the TPDOs"),
    ("rpdo", "RPDOs from the master applied by the devices"),
    ("emcy", "EMCY raised by a device, reported by the master"),
    ("heartbeat-loss", "a device falls silent, the master reports it"),
)


@dataclass
class Step:
    """The outcome of one step: ``ok`` and a line of ``detail`` (what was seen, or what
    was missing)."""

    key: str
    title: str
    ok: bool = False
    detail: str = "not reached"


def summary_table(steps: list[Step], *, unicode: bool = True) -> str:
    """The summary as text: a line per step with its mark, title and detail."""
    good, bad = ("\u2713", "\u2717") if unicode else ("ok", "FAIL")
    labels = [f"{n}. {s.title}" for n, s in enumerate(steps, 1)]
    width = max(map(len, labels))
    lines = ["== summary"]
    for label, s in zip(labels, steps, strict=True):
        lines.append(f" {good if s.ok else bad:>4} {label:<{width}}  {s.detail}")
    passed = sum(s.ok for s in steps)
    lines.append(f"{passed}/{len(steps)} steps passed")
    return "\n".join(lines)


def failure_line(steps: list[Step]) -> str | None:
    """One line naming the failed steps (None when every step passed)."""
    failed = [s for s in steps if not s.ok]
    if not failed:
        return None
    first = failed[0]
    more = f" (also failed: {', '.join(s.key for s in failed[1:])})" if failed[1:] else ""
    return f"canola demo: step '{first.key}' failed: {first.detail}{more}"


def summary_json(steps: list[Step], **extra: Any) -> dict[str, Any]:
    return {"ok": all(s.ok for s in steps), "steps": [asdict(s) for s in steps], **extra}
