# SPDX-License-Identifier: Apache-2.0
"""How starved the tester's host was: of the tester's own process (the link notes each wait
that overran) and of the whole host (Linux's pressure stall information, PSI: how long the
host's tasks waited for a CPU). A node late on the bus while the host was starved may be a
node sharing that host (canola device, an emulated board, the bridge to it) or a
late-stamped frame: the checks then measure again rather than judge (see timing.py).

On a simulated bus (virtual time) the host never counts; without PSI (not Linux, or a
kernel without it) only the tester's own stalls do."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

__all__ = ["PSI_CPU", "Starvation", "host_cpu_wait"]

#: Linux's CPU pressure file: "some avg10=.. avg60=.. avg300=.. total=MICROSECONDS".
PSI_CPU = Path("/proc/pressure/cpu")


def host_cpu_wait() -> float | None:
    """Seconds the host's tasks have waited for a CPU since boot (PSI "some": at least one
    runnable task waiting); None where the host does not tell."""
    try:
        first = PSI_CPU.read_text(encoding="ascii").splitlines()[0].split()
    except (OSError, IndexError, UnicodeDecodeError):
        return None
    if not first or first[0] != "some":
        return None
    for field in first[1:]:
        name, _, value = field.partition("=")
        if name == "total" and value.isdigit():
            return int(value) / 1e6
    return None


@dataclass(frozen=True, slots=True)
class Starvation:
    """Over some time: the tester's longest stall and how long the host's tasks waited for
    a CPU (seconds)."""

    stall: float = 0.0
    cpu_wait: float = 0.0

    @property
    def worst(self) -> float:
        return max(self.stall, self.cpu_wait)

    def __str__(self) -> str:
        parts = []  # what rounds to 0 ms is left out
        if round(self.stall * 1000):
            parts.append(f"the tester itself for {self.stall * 1000:.0f} ms")
        if round(self.cpu_wait * 1000):
            parts.append(f"its tasks waited for a CPU {self.cpu_wait * 1000:.0f} ms")
        return ", ".join(parts) or "not starved"
