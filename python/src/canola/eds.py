# SPDX-License-Identifier: Apache-2.0
"""``canola.eds``, as docs/python.md names it: :mod:`canola.formats.eds` (EDS/DCF read, check,
write) under its first name. Nothing lives here."""

from canola.formats.eds import *  # noqa: F403
