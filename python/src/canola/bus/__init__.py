# SPDX-License-Identifier: Apache-2.0
"""Buses and transports: how canola reaches a CAN bus, and the bus it can serve itself.

- :mod:`~canola.bus.open`: a python-can bus from ``--iface`` / ``--bus URL`` / the default
- :mod:`~canola.bus.socketcand`: the socketcand text protocol (pure functions);
  :mod:`~canola.bus.socketcand_bus`: canola's socketcand client, a python-can bus
- :mod:`~canola.bus.hub`: a software CAN bus serving socketcand (``canola bus serve``)
- :mod:`~canola.bus.candump`: candump logs and screens, read
"""
