# SPDX-License-Identifier: Apache-2.0
"""``canola demo --view``: the demo network on a bus that ``canola view`` watches.

The demo runs in real time on its bus (without ``--bus``/``--iface``: python-can's
in-process virtual bus, :func:`view_bus_url`), and the view reads that bus like any other:
its own bus object, its own master for the page's SDO requests. It knows the demo's
devices: their EDS files (names, the SDO browser's tree) and the PDO mappings the demo's
manager gives them, so the PDO signals are decoded from the first frame. After the story
the network keeps running (SYNC, PDOs; the sensor stays silent, marked lost) until Ctrl-C.
"""

from __future__ import annotations

import os
import threading
from collections.abc import Callable

import can

from canola.bus.open import open_bus
from canola.decode import Decoder
from canola.demo.devices import DEVICES, eds_path
from canola.demo.devices import Mapped as DemoMapped
from canola.demo.network import Network
from canola.demo.scenario import MASTER_ID, Scenario
from canola.formats.eds import ObjectDictionary
from canola.master import MASTER_EDS, Master
from canola.nodedicts import NodeDictionaries
from canola.pdomap import Mapped, Pdo
from canola.view.launch import start_view
from canola.view.runner import View

__all__ = ["keep_running", "start_demo_view", "view_bus_url"]

#: The view's own master (its SDO requests); the demo's master is node 0x3F.
VIEW_MASTER_ID = 127


def view_bus_url() -> str:
    """The in-process virtual bus of this run (python-can), by URL."""
    return f"virtual://canola-demo-{os.getpid()}"


def _dictionaries() -> NodeDictionaries:
    specs = [f"{spec.node_id}={eds_path(spec)}" for spec in DEVICES]
    return NodeDictionaries([*specs, f"{MASTER_ID}={MASTER_EDS}"])


def _pdo(od: ObjectDictionary | None, kind: str, cob_id: int,
         mapping: tuple[DemoMapped, ...]) -> Pdo:
    """One PDO of a demo device, its entries typed by the device's EDS."""
    entries = []
    for m in mapping:
        obj = None if od is None else od.objects.get(m.index)
        var = None if obj is None else obj.subs.get(m.sub)
        entries.append(Mapped(m.index, m.sub, m.bits, m.name,
                              None if var is None else var.data_type))
    return Pdo(kind, 1, cob_id, entries=entries)


def _pdos(dicts: NodeDictionaries) -> dict[int, list[Pdo]]:
    """The TPDO1 and RPDO1 of each device as the demo's manager maps them."""
    out: dict[int, list[Pdo]] = {}
    for spec in DEVICES:
        od = dicts.get(spec.node_id)
        out[spec.node_id] = [_pdo(od, "TPDO", 0x180 + spec.node_id, spec.tpdo)]
        if spec.rpdo:
            out[spec.node_id].append(_pdo(od, "RPDO", 0x200 + spec.node_id, spec.rpdo))
    return out


def start_demo_view(url: str | None, iface: str | None, *, listen: str,
                    allow_write: bool) -> View:
    """The view of the demo's bus (``url`` or ``iface``), started (it prints its URL)."""
    dicts = _dictionaries()

    def bus() -> can.BusABC:
        return open_bus(iface=iface, url=url)

    def master() -> Master:
        return Master(open_bus(iface=iface, url=url), VIEW_MASTER_ID, announce=False)

    return start_view(open_bus=bus, open_master=master,
                      dictionaries=dicts, decoder=Decoder(dicts, _pdos(dicts)),
                      listen=listen, allow_write=allow_write,
                      where=f"the demo network on {url or iface}")


def keep_running(scenario: Scenario, net: Network, stop: threading.Event,
                 say: Callable[[str], None]) -> None:
    """After the story: SYNC again, the frames drained (not kept), until ``stop`` is set."""
    scenario.master.start_sync(scenario.sync_us)
    say("canola demo: the network keeps running for the view (SYNC, PDOs; the sensor "
        "stays silent) until Ctrl-C")
    while not stop.wait(0.2):
        net.drain()
