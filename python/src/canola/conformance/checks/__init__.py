# SPDX-License-Identifier: Apache-2.0
"""The check modules, one per group (SYNC, EMCY and TIME share one): importing this
package registers every check (:mod:`canola.conformance.registry`), in the order they run
within their group."""

from canola.conformance.checks import dictionary, nmt, pdo, sdo, sync_emcy_time

__all__ = ["dictionary", "nmt", "pdo", "sdo", "sync_emcy_time"]
