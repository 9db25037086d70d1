# SPDX-License-Identifier: Apache-2.0
"""``canola.values``, as docs/python.md names it: :mod:`canola.formats.values` (Python values <->
CANopen data types) under its first name. Nothing lives here."""

from canola.formats.values import *  # noqa: F403
