# SPDX-License-Identifier: Apache-2.0
"""``python -m canola.gateway``: the same as ``canola gateway``."""

import sys

from canola.gateway.cli import main

sys.exit(main())
