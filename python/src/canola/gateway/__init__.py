# SPDX-License-Identifier: Apache-2.0
"""The CiA 309-3 ASCII gateway: a master node exposed as text lines (``canola gateway``).

- :mod:`~canola.gateway.parser`: one line -> one typed request (pure, linear; fuzzed)
- :mod:`~canola.gateway.formats`: values <-> text per CiA 309-3 data type
- :mod:`~canola.gateway.executor`: requests -> replies against a master;
  :mod:`~canola.gateway.lsscommands`: the lss_* commands; :mod:`~canola.gateway.helptext`
- :mod:`~canola.gateway.events`: boot-up, heartbeat and EMCY events to clients
- :mod:`~canola.gateway.server`: TCP, Unix socket and stdio clients, their slots and idle
  time-out; :mod:`~canola.gateway.connection`: one client's reader, worker and writer;
  :mod:`~canola.gateway.listen`: where to listen
- :mod:`~canola.gateway.backend`: what the gateway needs from a master;
  :mod:`~canola.gateway.masterbackend`: canola.Master (python-can or simulated bus)
"""

from canola.gateway.codes import GatewayError
from canola.gateway.executor import Executor, Session
from canola.gateway.parser import ParseError, parse_line
from canola.gateway.server import GatewayServer, parse_listen

__all__ = ["Executor", "GatewayError", "GatewayServer", "ParseError", "Session", "parse_line",
           "parse_listen"]
