# SPDX-License-Identifier: Apache-2.0
"""``canola.eds``, as the README names it: :mod:`canola.formats.eds` (EDS/DCF read, check,
write) under its first name. Nothing lives here."""

from canola.formats.eds import *  # noqa: F403
