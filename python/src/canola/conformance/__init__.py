# SPDX-License-Identifier: Apache-2.0
"""canola.conformance: a CiA 301 test suite for any CANopen node, from its EDS.

    import canola.conformance
    report = canola.conformance.run(bus, 5, "drive.eds")   # SimBus or python-can bus
    assert report.passed, canola.conformance.markdown(report)

The same from the command line: ``canola conformance --node-id 5 --eds drive.eds --iface
can0 [--junit FILE] [--markdown FILE] [--only GROUP...] [--list] [--destructive]``.

The checks (``--list``) come in groups: ``dictionary`` (the node's object dictionary
against its EDS), ``sdo`` (the protocol, frame by frame), ``nmt`` (state machine, boot-up,
heartbeat, node guarding), ``pdo`` (mapping procedure, transmission types), ``sync``,
``emcy``, ``time``. Each names the CiA 301 / CiA 306 clause it tests; a failure keeps
what was expected, what the node did, and the frames around it. A check the EDS says
the node cannot support is SKIPPED with the reason, never passed.

Non-destructive by default: every value a check changes is written back, stored
parameters are never saved, the NMT state is restored at the end (``--destructive`` runs
the checks of 0x1010/0x1011 too). What it does send: NMT commands to this node only
(reset node and reset communication among them: unsaved values return to their power-on
values, as at a power cycle), writes of values and PDO parameters that are restored,
RPDOs, SYNC and TIME frames, heartbeats as the tester's node-ID. See docs/conformance.md.
"""

import importlib
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from canola.conformance.options import Options
    from canola.conformance.registry import CHECKS, GROUPS, Check, select
    from canola.conformance.reporters import LiveProgress, check_list, junit, markdown, verdict
    from canola.conformance.results import Finding, Interrupted, Report, Result, Status
    from canola.conformance.runner import run

__all__ = ["CHECKS", "GROUPS", "Check", "Finding", "Interrupted", "LiveProgress", "Options",
           "Report", "Result", "Status", "check_list", "junit", "markdown", "run", "select",
           "verdict"]

_MODULES = {
    "Options": "options", "CHECKS": "registry", "GROUPS": "registry", "Check": "registry",
    "select": "registry", "LiveProgress": "reporters", "check_list": "reporters",
    "junit": "reporters", "markdown": "reporters", "verdict": "reporters",
    "Finding": "results", "Interrupted": "results", "Report": "results", "Result": "results",
    "Status": "results", "run": "runner",
}


def __getattr__(name: str) -> Any:
    # Loaded on first use: the command line reads GROUPS and Options without the suite.
    module = _MODULES.get(name)
    if module is None:
        raise AttributeError(f"module 'canola.conformance' has no attribute {name!r}")
    importlib.import_module("canola.conformance.checks")  # registers every check
    return getattr(importlib.import_module(f"canola.conformance.{module}"), name)
