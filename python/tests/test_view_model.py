# SPDX-License-Identifier: Apache-2.0
"""What ``canola view`` makes of the frames (canola.view.model), in virtual time: the time of
each frame is given, no bus, no server."""

from __future__ import annotations

from pathlib import Path

from canola.decode import Decoder
from canola.nodedicts import NodeDictionaries
from canola.pdomap import Mapped, Pdo
from canola.view.model import LIMITS, BusModel, Cursor
from canola.view.ring import Ring
from canola.view.signals import SignalStore

DEMO = Path(__file__).resolve().parents[1] / "src" / "canola" / "data" / "demo"
T0 = 1_700_000_000.0


def _events(model: BusModel, cursor: Cursor, t: float) -> list[list[object]]:
    return list(model.update(cursor, t)["events"])


def test_node_table_states_bootups_and_heartbeat_loss() -> None:
    model = BusModel()
    cursor = Cursor()
    model.feed(T0, 0x705, b"\x00")  # boot-up
    model.feed(T0 + 0.01, 0x000, b"\x80\x00")  # NMT preop all
    for i in range(5):  # heartbeats every 100 ms
        model.feed(T0 + 0.1 * (i + 1), 0x705, b"\x7f")
    update = model.update(cursor, T0 + 0.55)
    [row] = update["nodes"]
    assert row["node"] == 5 and row["state"] == "PRE-OPERATIONAL" and row["bootups"] == 1
    assert row["period_ms"] == 100.0 and not row["lost"]
    texts = [e[3] for e in update["events"]]
    assert texts == ["node 5 boot-up (#1)", "node 5 is PRE-OPERATIONAL", "NMT preop all"]
    model.check(T0 + 0.5 + 0.9)  # silent 0.9 s: under the 1 s floor
    assert not model.update(cursor, T0 + 1.4)["nodes"][0]["lost"]
    model.check(T0 + 0.5 + 1.1)
    update = model.update(cursor, T0 + 1.6)
    assert update["nodes"][0]["lost"]
    [lost] = update["events"]
    assert lost[1] == "heartbeat" and "node 5 heartbeat lost" in str(lost[3])
    model.check(T0 + 3)  # marked once
    assert _events(model, cursor, T0 + 3) == []
    model.feed(T0 + 3.1, 0x705, b"\x05")
    texts = [e[3] for e in _events(model, cursor, T0 + 3.2)]
    assert texts == ["node 5 PRE-OPERATIONAL -> OPERATIONAL", "node 5 heard again (OPERATIONAL)"]


def test_a_node_without_heartbeat_is_where_nmt_put_it() -> None:
    model = BusModel()
    cursor = Cursor()
    model.feed(T0, 0x706, b"\x00")  # boot-up, no heartbeat after
    model.feed(T0 + 0.1, 0x000, b"\x01\x06")  # start node 6
    model.feed(T0 + 0.2, 0x000, b"\x02\x07")  # stop node 7: not node 6
    [row] = model.update(cursor, T0 + 0.3)["nodes"]
    assert (row["state"], row["state_by"]) == ("OPERATIONAL", "NMT")
    model.feed(T0 + 0.4, 0x000, b"\x81\x00")  # reset node, all: unknown until its boot-up
    model.feed(T0 + 0.5, 0x706, b"\x00")
    texts = [e[3] for e in model.update(cursor, T0 + 0.6)["events"]]
    assert texts[-3:] == ["node 6 OPERATIONAL -> ? (NMT command; it sends no heartbeat)",
                          "node 6 boot-up (#2)", "node 6 is PRE-OPERATIONAL"]


def test_identity_name_and_configured_heartbeat_from_sdo_traffic() -> None:
    model = BusModel()
    model.feed(T0, 0x605, bytes.fromhex("4018100100000000"))
    model.feed(T0, 0x585, bytes.fromhex("43181001A00C0000"))  # vendor 0x0CA0
    model.feed(T0, 0x585, bytes.fromhex("4F081000414243"))  # 0x1008 "ABC", 7 bytes: bad
    model.feed(T0, 0x585, bytes.fromhex("4F08100041424300"))  # "ABC" expedited, 1 byte
    model.feed(T0, 0x605, bytes.fromhex("2B17100064000000"))  # 0x1017 = 100 ms
    [row] = model.update(Cursor(), T0)["nodes"]
    assert row["identity"] == {"vendor": 0x0CA0}
    assert row["name"] == "A" and row["configured_ms"] == 100


def test_name_from_the_eds_until_0x1008_is_read() -> None:
    dicts = NodeDictionaries([f"3={DEMO / 'drive.eds'}"])
    model = BusModel(dictionaries=dicts)
    model.feed(T0, 0x703, b"\x05")
    [row] = model.update(Cursor(), T0)["nodes"]
    assert row["name"] == "canola SD-1" and row["name_from"] == "EDS"


def test_emcy_and_sdo_abort_in_words() -> None:
    model = BusModel()
    model.feed(T0, 0x083, bytes.fromhex("1043095A00000000"))
    model.feed(T0, 0x583, bytes.fromhex("8000600000000206"))
    events = _events(model, Cursor(), T0)
    assert [e[1] for e in events] == ["emcy", "sdo"]
    assert events[0][3] == ("EMCY node 3 0x4310 temperature, error register 0x09 (generic, "
                            "temperature), data 5A 00 00 00 00")
    assert "SDO abort 0x6000:00 0x06020000" in str(events[1][3])
    assert "Object does not exist in the object dictionary" in str(events[1][3])


def test_pdo_signals_decoded_by_the_mapping_with_the_eds_unit() -> None:
    dicts = NodeDictionaries([f"3={DEMO / 'drive.eds'}"])
    pdo = Pdo("TPDO", 1, 0x183, entries=[Mapped(0x6041, 0, 16, "statusword", 0x0006),
                                          Mapped(0x606C, 0, 32, "velocity", 0x0004)])
    model = BusModel(Decoder(dicts, {3: [pdo]}), dicts)
    cursor = Cursor()
    model.feed(T0, 0x183, bytes.fromhex("3702DC050000"))
    model.feed(T0 + 0.01, 0x183, (0x237).to_bytes(2, "little") + (-20).to_bytes(4, "little",
                                                                             signed=True))
    update = model.update(cursor, T0 + 0.02)
    assert {s["id"]: s["unit"] for s in update["signals"]} == {
        "3/TPDO1/statusword": "", "3/TPDO1/velocity": "rpm"}
    assert update["points"]["3/TPDO1/velocity"] == [[T0, T0 + 0.01], [1500, -20]]
    assert "signals" not in model.update(cursor, T0 + 0.03)  # sent once


def test_traffic_figures() -> None:
    model = BusModel(bitrate=125_000)
    for i in range(200):  # 100 frames/s of 8 bytes for 2 s, 100 SYNCs/s
        model.feed(T0 + i * 0.01, 0x181, bytes(8))
        model.feed(T0 + i * 0.01, 0x080, b"")
    traffic = model.update(Cursor(), T0 + 1.995)["traffic"]
    assert traffic["total"] == 400
    assert traffic["fps"] == {"PDO": 100.0, "SYNC": 100.0}
    # (47 + 64) + 47 bits per 10 ms = 15,800 bit/s of 125,000
    assert traffic["load_pct"] == 12.64


def test_a_page_gets_a_bounded_amount_and_is_told_what_was_left_out() -> None:
    model = BusModel()
    cursor = Cursor()
    frames = 3 * LIMITS["frames"]
    for i in range(frames):
        model.feed(T0 + i * 1e-4, 0x181, i.to_bytes(2, "little"))
    update = model.update(cursor, T0 + 1)
    assert len(update["frames"]) == LIMITS["frames"]
    assert update["left_out"]["frames"] == frames - LIMITS["frames"]
    assert update["frames"][-1][2] == (frames - 1).to_bytes(2, "little").hex().upper()
    again = model.update(cursor, T0 + 1)
    assert again["frames"] == [] and again["left_out"]["frames"] == 0


def test_ring_since() -> None:
    ring: Ring[int] = Ring(4)
    for i in range(1, 7):
        ring.add(i)
    assert ring.since(0, 10) == ([3, 4, 5, 6], 6, 2)  # 1 and 2 gone from the ring
    assert ring.since(4, 10) == ([5, 6], 6, 0)
    assert ring.since(4, 1) == ([6], 6, 1)
    assert ring.since(6, 10) == ([], 6, 0)
    assert ring.since(99, 10) == ([], 6, 0)


def test_thinned_points_keep_the_newest() -> None:
    store = SignalStore()
    pdo = Pdo("TPDO", 1, 0x181, entries=[Mapped(0x6000, 1, 8, "x", 0x0005)])
    for i in range(1000):
        store.feed(float(i), 1, pdo, {"x": i % 256}, None)
    seen: dict[str, int] = {}
    points, dropped = store.since(seen, 100)
    times, values = points["1/TPDO1/x"]
    assert len(times) <= 100 and dropped == 1000 - len(times)
    assert times[-1] == 999.0 and values[-1] == 999 % 256
    assert times == sorted(times)
    assert store.since(seen, 100) == ({}, 0)
