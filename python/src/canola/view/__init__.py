# SPDX-License-Identifier: Apache-2.0
"""``canola view``: a live picture of a CANopen network in the browser.

- :mod:`canola.view.model`: every frame decoded into the node table
  (:mod:`~canola.view.nodes`), the event log, the PDO signals (:mod:`~canola.view.signals`)
  and the traffic figures (:mod:`~canola.view.traffic`); what each page has been sent;
- :mod:`canola.view.actions`: the page's SDO reads and writes, NMT commands, PDO mappings;
- :mod:`canola.view.server`: the web server (aiohttp): the page, its WebSocket, its
  requests, and who may write;
- :mod:`canola.view.runner` and :mod:`canola.view.launch`: the threads, and starting it;
- ``static/``: the page (no CDN: every file ships in the package; uPlot draws the plots).
"""
