"""TUIO 1.1 received by an independent OSC server (python-osc dispatcher + threading UDP)."""

from __future__ import annotations

import threading
import time

import numpy as np
import pytest
from pythonosc import osc_packet
from pythonosc.dispatcher import Dispatcher
from pythonosc.osc_server import ThreadingOSCUDPServer

from console.core.types import Contact, Gesture, Hand, HandShape

TABLE = (743.46, 447.29)


class BundleDispatcher(Dispatcher):
    """Keeps every packet's messages together (one TUIO bundle = one list)."""

    def __init__(self) -> None:
        super().__init__()
        self.lock = threading.Lock()
        self.bundles: list[list[tuple[str, tuple]]] = []
        self.set_default_handler(lambda *a: None)

    def call_handlers_for_packet(self, data, client_address):
        msgs = [
            (m.message.address, tuple(m.message.params))
            for m in osc_packet.OscPacket(data).messages
        ]
        with self.lock:
            self.bundles.append(msgs)
        return super().call_handlers_for_packet(data, client_address)


@pytest.fixture
def server():
    disp = BundleDispatcher()
    got: list = []
    disp.map("/haptable/gesture", lambda addr, *args: got.append(args))
    srv = ThreadingOSCUDPServer(("127.0.0.1", 0), disp)
    th = threading.Thread(target=srv.serve_forever, daemon=True)
    th.start()
    srv.gestures = got
    yield srv
    srv.shutdown()
    srv.server_close()


def wait_for(fn, timeout_s=5.0):
    t0 = time.monotonic()
    while time.monotonic() - t0 < timeout_s:
        if fn():
            return True
        time.sleep(0.01)
    return False


def by_profile(bundles, profile):
    return [b for b in bundles if b and b[0][0] == profile]


def check_structure(b, profile):
    """source, alive, set per alive id, fseq: the TUIO 1.1 bundle layout."""
    addrs = {a for a, _ in b}
    assert addrs == {profile}
    cmds = [p[0] for _, p in b]
    assert cmds[0] == "source" and cmds[1] == "alive" and cmds[-1] == "fseq"
    assert set(cmds[2:-1]) <= {"set"}
    alive = list(b[1][1][1:])
    sets = [p for _, p in b[2:-1]]
    ids = [p[1] for p in sets]
    assert len(set(ids)) == len(ids) and set(ids) <= set(alive)  # a coasting id: no set
    return alive, sets, b[-1][1][1]


def hand(center_mm, angle_deg=30.0, contacts=()):
    c = np.array([[100, 100], [160, 100], [160, 180], [100, 180]], float)
    return Hand(
        c,
        (130.0, 140.0),
        30.0,
        angle_deg,
        HandShape.of(np.zeros(4), len(contacts)),
        tuple(contacts),
        center_mm,
    )


def test_contacts_hands_and_a_gesture_arrive_normalised(server):
    from plugins.tuio.sender import TuioSender

    port = server.server_address[1]
    tx = TuioSender("127.0.0.1", port, table_mm=TABLE)
    c1 = Contact(0, (10.0, 20.0), (371.73, 223.645))
    c2 = Contact(1, (30.0, 20.0), (74.346, 44.729))
    h = hand((400.0, 200.0), contacts=(c1,))
    tx.send(0.0, [c1, c2], [h])
    tx.send(0.1, [c1], [h], Gesture("static_hand", "static", 0.9, 0.1, h))
    tx.close()
    assert wait_for(lambda: len(server.dispatcher.bundles) >= 7)
    bundles = server.dispatcher.bundles
    cur = by_profile(bundles, "/tuio/2Dcur")
    blb = by_profile(bundles, "/tuio/2Dblb")
    assert len(cur) == 3 and len(blb) == 3
    fseqs = []
    for b in sorted(cur, key=lambda b: b[-1][1][1]):
        alive, sets, fseq = check_structure(b, "/tuio/2Dcur")
        fseqs.append(fseq)
        for s in sets:
            assert len(s) == 7  # set s x y X Y m
    assert fseqs == sorted(set(fseqs)) and len(fseqs) == 3
    first = min(cur, key=lambda b: b[-1][1][1])
    _, sets, _ = check_structure(first, "/tuio/2Dcur")
    pos = sorted((s[2], s[3]) for s in sets)
    assert pos[0] == pytest.approx((0.1, 0.1), abs=1e-6)
    assert pos[1] == pytest.approx((0.5, 0.5), abs=1e-6)
    # the contact that stays keeps its session id; the one that lifted gets no set (it
    # coasts in alive for the grace frames: a blob missed once keeps its id)
    second = sorted(cur, key=lambda b: b[-1][1][1])[1]
    alive1 = {s[1] for s in sets if s[2] == pytest.approx(0.5)}
    alive2, sets2, _ = check_structure(second, "/tuio/2Dcur")
    assert {s[1] for s in sets2} == alive1 and set(alive2) == {s[1] for s in sets}
    # the last frame (close) has nothing alive
    last = max(cur, key=lambda b: b[-1][1][1])
    assert check_structure(last, "/tuio/2Dcur")[0] == []
    b0 = min(blb, key=lambda b: b[-1][1][1])
    _, bsets, _ = check_structure(b0, "/tuio/2Dblb")
    (s,) = bsets
    assert len(s) == 13  # set s x y a w h f X Y A m r
    assert (s[2], s[3]) == pytest.approx((400 / TABLE[0], 200 / TABLE[1]), abs=1e-6)
    assert s[4] == pytest.approx(np.radians(30.0), abs=1e-5)
    assert s[5] == pytest.approx(60 / 640) and s[6] == pytest.approx(80 / 480)
    assert s[7] == pytest.approx(60 * 80 / (640 * 480))
    assert wait_for(lambda: len(server.gestures) == 1)
    name, kind, conf, gx, gy, sid, fseq = server.gestures[0]
    assert (name, kind) == ("static_hand", "static")
    assert conf == pytest.approx(0.9)
    assert (gx, gy) == pytest.approx((400 / TABLE[0], 200 / TABLE[1]), abs=1e-6)
    assert sid == s[1]


def test_a_gesture_is_sent_once_while_it_lasts(server):
    from plugins.tuio.sender import TuioSender

    tx = TuioSender("127.0.0.1", server.server_address[1], table_mm=TABLE)
    h = hand((300.0, 100.0))
    g = Gesture("two_finger", "static", 1.0, 0.0, h)
    # frames of (hands, gesture): recognition drops it for a frame, then for ten, while
    # the hand stays: one gesture; the hand lifts (its id ends) and comes back: again
    frames = [([h], g)] * 5 + [([h], None)] + [([h], g)] * 3 + [([h], None)] * 10
    frames += [([], None)] * 8 + [([h], g)] * 3
    for k, (hands, gk) in enumerate(frames):
        tx.send(k / 60, [], hands, gk)
    assert wait_for(lambda: len(server.dispatcher.bundles) >= 2 * len(frames) + 2)
    time.sleep(0.05)
    assert len(server.gestures) == 2
    assert [a[0] for a in server.gestures] == ["two_finger"] * 2
    assert [a[-1] for a in server.gestures] == [1, len(frames) - 2]  # fseq of each start
    assert server.gestures[0][5] != server.gestures[1][5]  # on the hand's new id
