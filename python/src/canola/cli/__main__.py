# SPDX-License-Identifier: Apache-2.0
"""``python -m canola.cli``: the ``canola`` command."""

import sys

from canola.cli import main

sys.exit(main())
