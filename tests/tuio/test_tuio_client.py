"""The twin's resting hand streamed as TUIO 1.1 to an independent client (python-tuio)."""

from __future__ import annotations

import threading
import time

import numpy as np
import pytest

pytest.importorskip("pythontuio")
from pythontuio.dispatcher import TuioDispatcher, TuioListener  # noqa: E402

GESTURE = "/haptable/gesture"


class Events(TuioListener):
    """What a TUIO application sees: objects added, removed, and blob positions."""

    def __init__(self) -> None:
        self.lock = threading.Lock()
        self.added = {"blob": [], "cursor": []}
        self.removed = {"blob": [], "cursor": []}
        self.blob_pos: list[tuple[int, float, float]] = []

    def add_tuio_blob(self, blob):
        with self.lock:
            self.added["blob"].append(blob.session_id)

    def remove_tuio_blob(self, blob):
        with self.lock:
            self.removed["blob"].append(blob.session_id)

    def update_tuio_blob(self, blob):
        with self.lock:
            self.blob_pos.append((blob.session_id, *blob.position))

    def add_tuio_cursor(self, cur):
        with self.lock:
            self.added["cursor"].append(cur.session_id)

    def remove_tuio_cursor(self, cur):
        with self.lock:
            self.removed["cursor"].append(cur.session_id)


@pytest.fixture
def client():
    from pythonosc.osc_server import BlockingOSCUDPServer

    disp = TuioDispatcher()
    ev = Events()
    disp.add_listener(ev)
    gestures: list[tuple] = []
    disp.map(GESTURE, lambda addr, *args: gestures.append(args))
    srv = BlockingOSCUDPServer(("127.0.0.1", 0), disp)  # one packet at a time, in order
    th = threading.Thread(target=srv.serve_forever, daemon=True)
    th.start()
    srv.events, srv.gestures, srv.disp = ev, gestures, disp
    yield srv
    srv.shutdown()
    srv.server_close()


def test_a_resting_hand_is_one_blob_and_its_fingers_keep_their_ids(client, profile, plugins):
    from console.core.types import GestureScript, GestureStep
    from console.runtime.stages import base_stages, learn_background, open_classifier
    from plugins.tuio.sender import TuioSender

    # 5 s of a resting open hand, lifted, then placed again with two fingers down (60 fps)
    gap, n_open, n_two = 30, 300, 150
    n = gap + n_open + gap + n_two
    table = (float(profile.get("table.width_mm")), float(profile.get("table.height_mm")))
    camera = plugins.build("camera", "twin", profile)
    camera.realtime = False
    camera.set_script(
        GestureScript(
            (GestureStep("open_hand", frames=n_open), GestureStep("two_finger", frames=n_two)),
            gap_frames=gap,
            loop=False,
        )
    )
    tx = TuioSender("127.0.0.1", client.server_address[1], table_mm=table, source="table7")
    try:
        clf = open_classifier(profile, plugins)
        learn_background(camera, clf)
        stages = base_stages(clf)
        for _ in range(n):
            f = camera.read(1.0)
            work: dict = {}
            for _, stage in stages:
                stage(f, work)
            tx(f, work)
        tx.close()
    finally:
        camera.close()
    ev = client.events
    t0 = time.monotonic()
    while len(ev.removed["blob"]) < len(ev.added["blob"]) and time.monotonic() - t0 < 5:
        time.sleep(0.02)
    time.sleep(0.1)
    assert tx.source.startswith("table7@")
    assert len(ev.added["blob"]) == 2  # one blob session per placement of the hand
    assert ev.removed["blob"] == ev.added["blob"]  # each ended when the hand left
    sid_open = ev.added["blob"][0]
    assert sum(s == sid_open for s, _, _ in ev.blob_pos) >= 0.95 * n_open  # all 5 s
    assert len(ev.added["cursor"]) == 2  # the two fingertips, each one id throughout
    assert sorted(ev.removed["cursor"]) == sorted(ev.added["cursor"])
    pos = np.array([(x * table[0], y * table[1]) for _, x, y in ev.blob_pos])
    ids = np.array([s for s, _, _ in ev.blob_pos])
    assert len(pos) >= 0.95 * (n_open + n_two)
    step = np.concatenate([np.hypot(*np.diff(pos[ids == s], axis=0).T) for s in ev.added["blob"]])
    print(f"blob centre step mm: p50 {np.median(step):.2f} p99 {np.percentile(step, 99):.2f}")
    assert np.percentile(step, 99) < 3.0  # mm between frames (the palm centre jumped ~38)
    said = [(g[0], g[5]) for g in client.gestures]
    print("gestures:", said)
    assert len(said) == len(set(said))  # each gesture once per placement, not per frame
    sid_two = ev.added["blob"][1]
    assert ("two_finger", sid_two) in said and ("static_hand", sid_open) in said
