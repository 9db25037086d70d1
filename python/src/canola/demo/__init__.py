# SPDX-License-Identifier: Apache-2.0
"""``canola demo``: a master and three devices walking through the life of a CANopen network
(boot-up, NMT, the CiA 302-2 manager's configuration and start, SYNC and PDOs, EMCY,
heartbeat loss), every frame decoded and every step checked.

- :mod:`canola.demo.devices`: the devices (EDS files in ``canola/data/demo``) and their
  applications;
- :mod:`canola.demo.network`: the simulated bus in virtual time, or python-can buses;
- :mod:`canola.demo.trace`: the decoded trace;
- :mod:`canola.demo.scenario`: the flow and its checks;
- :mod:`canola.demo.report`: the summary table and JSON.
"""
