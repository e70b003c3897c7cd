"""TUIO 2.0 out, read back by a decoder written here from the TUIO 2.0 specification
(www.tuio.org/?tuio20) on python-osc's parsing: message types and argument counts,
frm first and alv last, session ids, outlines against their analytic shape and the
vision's outline, the datagram limit, WebSocket, and the ``[tuio]`` keys."""

from __future__ import annotations

import contextlib
import dataclasses
import socket
import threading
import time

import cv2
import numpy as np
import pytest
from pythonosc.osc_bundle import OscBundle
from pythonosc.osc_message import OscMessage
from pythonosc.parsing import osc_types

from console.core.errors import UserError
from console.core.types import Contact, Hand, HandShape

TABLE = (743.46, 447.29)
IMAGE = (640, 480)

# ---------------------------------------------------------------- the spec's decoder
#: address -> (type tags always there, optional tail), from the specification's table
REQUIRED = {
    "/tuio2/frm": ("itis", ""),  # f_id time dim source
    "/tuio2/ptr": ("iiiffffff", "fffff"),  # s_id tu_id c_id x y a shear radius press [...]
    "/tuio2/bnd": ("iffffff", "fffff"),  # s_id x y angle width height area [...]
}


@dataclasses.dataclass
class Frame2:
    """One decoded bundle: its frm, its components by session id, its alv."""

    f_id: int
    time: tuple
    dim: tuple[int, int]
    source: str
    bnd: dict[int, tuple]
    ocg: dict[int, np.ndarray]
    ptr: dict[int, dict]
    alive: list[int]
    size: int


def tags_of(m: OscMessage) -> str:
    """The message's type tags, read from its datagram (OSC 1.0: address, then tags)."""
    _, i = osc_types.get_string(m.dgram, 0)
    return osc_types.get_string(m.dgram, i)[0].lstrip(",")


def decode(dgram: bytes) -> Frame2:
    """A TUIO 2.0 bundle checked against the specification, decoded."""
    assert OscBundle.dgram_is_bundle(dgram)
    msgs = list(OscBundle(dgram))
    assert all(isinstance(m, OscMessage) for m in msgs)  # no nested bundles
    addrs = [m.address for m in msgs]
    assert addrs[0] == "/tuio2/frm" and addrs[-1] == "/tuio2/alv"
    assert "/tuio2/frm" not in addrs[1:] and "/tuio2/alv" not in addrs[:-1]
    out = Frame2(0, (), (0, 0), "", {}, {}, {}, [], len(dgram))
    for m in msgs:
        tags, p = tags_of(m), list(m.params)
        if m.address in REQUIRED:
            need, opt = REQUIRED[m.address]
            assert tags in (need, need + opt), (m.address, tags)
        if m.address == "/tuio2/frm":
            out.f_id, out.time, out.source = p[0], p[1], p[3]
            assert isinstance(p[1], tuple)  # an OSC time tag: (utc datetime, fraction)
            dim = p[2] & 0xFFFFFFFF
            out.dim = (dim >> 16, dim & 0xFFFF)  # width in the upper 16 bits
        elif m.address == "/tuio2/bnd":
            assert p[0] not in out.bnd
            out.bnd[p[0]] = tuple(p[1:])
        elif m.address == "/tuio2/ocg":
            assert tags[0] == "i" and set(tags[1:]) == {"f"} and len(tags[1:]) % 2 == 0
            out.ocg[p[0]] = np.array(p[1:], float).reshape(-1, 2)
        elif m.address == "/tuio2/ptr":
            s_id, tu_id, c_id = p[:3]
            out.ptr[s_id] = {
                "type": tu_id & 0xFFFF,  # tu_id = user << 16 | type (the spec's example)
                "user": (tu_id >> 16) & 0xFFFF,
                "c_id": c_id,
                "xy": (p[3], p[4]),
            }
        elif m.address == "/tuio2/alv":
            assert set(tags) <= {"i"}
            out.alive = list(p)
        else:
            raise AssertionError(f"unexpected {m.address}")
    comps = set(out.bnd) | set(out.ocg) | set(out.ptr)
    assert comps <= set(out.alive)  # every component sent is alive
    return out


def check_stream(frames: list[Frame2], limit: int = 4096) -> None:
    """Frame ids and times never go back (the parts of one split frame share theirs),
    each bundle within the datagram limit."""
    ids = [f.f_id for f in frames]
    assert ids == sorted(ids) and ids[0] >= 1
    times = [f.time for f in frames]
    assert times == sorted(times)
    assert max(f.size for f in frames) <= limit


def dist_px(points_px: np.ndarray, polygon_px: np.ndarray) -> np.ndarray:
    """Distance of each point to the closed polygon's edges (OpenCV's point test)."""
    poly = np.asarray(polygon_px, np.float32).reshape(-1, 1, 2)
    return np.array(
        [abs(cv2.pointPolygonTest(poly, (float(x), float(y)), True)) for x, y in points_px]
    )


# ---------------------------------------------------------------- synthetic frames
def circle(center_px, r_px, n=720, jitter_px=0.0, seed=0):
    a = np.linspace(0, 2 * np.pi, n, endpoint=False)
    r = r_px + np.random.default_rng(seed).uniform(-jitter_px, jitter_px, n)
    return np.column_stack([center_px[0] + r * np.cos(a), center_px[1] + r * np.sin(a)])


def hand(contour, contacts=()):
    c = contour.mean(0)
    return Hand(
        contour,
        (float(c[0]), float(c[1])),
        40.0,
        0.0,
        HandShape.of(np.zeros(4), len(contacts)),
        tuple(contacts),
    )


class Catcher:
    """Bundles 'sent' by the sender (its UDP client replaced)."""

    def __init__(self) -> None:
        self.dgrams: list[bytes] = []

    def send(self, content) -> None:
        self.dgrams.append(content.dgram)


def test_two_hands_and_their_fingers_keep_their_sessions_and_outlines():
    from plugins.tuio.sender2 import Tuio2Sender

    out = Catcher()
    tx = Tuio2Sender(table_mm=TABLE, image_px=IMAGE, client=out, source="t7")
    a_px, b_px = circle((200, 240), 90), circle((470, 250), 70)
    for k in range(10):  # both hands rest, moving a little: A with two fingers, B with one
        d = np.array([k * 0.5, 0.0])
        fa = (Contact(0, (170 + d[0], 180.0), area_px=50.0), Contact(1, (230 + d[0], 180.0)))
        fb = (Contact(2, (470 + d[0], 200.0)),)
        tx.send(k / 60, [*fa, *fb], [hand(a_px + d, fa), hand(b_px + d, fb)])
    for k in range(10, 20):  # A lifts, B stays
        fb = (Contact(2, (475.0, 200.0)),)
        tx.send(k / 60, list(fb), [hand(b_px + [5.0, 0.0], fb)])
    tx.close()
    frames = [decode(d) for d in out.dgrams]
    assert len(frames) == 21  # one bundle per frame: they fit
    check_stream(frames)
    assert [f.f_id for f in frames] == list(range(1, 22))
    assert frames[0].dim == IMAGE and frames[0].source.startswith("t7@")
    first = frames[:10]
    hand_ids = {tuple(sorted(f.bnd)) for f in first}
    assert len(hand_ids) == 1 and len(next(iter(hand_ids))) == 2  # two hands, stable ids
    (ids,) = hand_ids
    assert all(set(f.ocg) == set(ids) for f in first)  # each hand's outline, same session
    sid_a = min(ids, key=lambda s: first[0].bnd[s][0])  # A is the left one
    sid_b = max(ids, key=lambda s: first[0].bnd[s][0])
    fingers = {tuple(sorted(f.ptr)) for f in first}
    assert len(fingers) == 1 and len(next(iter(fingers))) == 3  # three fingers, stable
    for f in first:
        assert set(f.alive) == set(f.bnd) | set(f.ptr)
        for p in f.ptr.values():
            owner = sid_a if p["xy"][0] < 0.5 else sid_b
            assert p["c_id"] == owner and p["user"] == 1 + owner % 0xFFFF and p["type"] == 0
    # the outline: its points on the analytic circle, the circle within a pixel of it
    f0 = frames[0]
    for sid, ref in ((sid_a, a_px), (sid_b, b_px)):
        got = f0.ocg[sid] * IMAGE
        r = np.hypot(*(got - ref.mean(0)).T)
        assert np.allclose(r, np.hypot(*(ref - ref.mean(0)).T)[0], atol=0.01)
        assert dist_px(circle(ref.mean(0), r[0], n=3600), got).max() <= 1.0
        x, y, _a, w, h, area = f0.bnd[sid][:6]
        assert (x, y) == pytest.approx(tuple(ref.mean(0) / IMAGE), abs=1e-3)
        assert w == pytest.approx(2 * r[0] / IMAGE[0], rel=0.01)
        assert area == pytest.approx(np.pi * r[0] ** 2 / (IMAGE[0] * IMAGE[1]), rel=0.01)
    later = frames[10:20]
    assert all(set(f.bnd) == {sid_b} for f in later)  # B keeps its session
    assert sid_a in later[0].alive and sid_a not in later[-1].alive  # A ends after grace
    assert frames[-1].alive == [] and not frames[-1].bnd  # close: nothing alive


def test_a_frame_too_big_for_a_datagram_is_simplified_then_split_whole():
    from console.runtime.tracking import Tracking
    from plugins.tuio.tuio2 import EPS_PX, Tuio2Encoder

    enc = Tuio2Encoder(table_mm=TABLE, image_px=IMAGE)
    tracking = Tracking()
    one = [circle((320, 240), 150, n=1400)]  # a long smooth outline: simplified, fits
    rough = [circle((110 + 210 * i, 240), 90, n=900, jitter_px=12.0, seed=i) for i in range(3)]
    results = []
    for contours in (one, rough):
        hands = [hand(c) for c in contours]
        tr = tracking.update(0.0, hands, [])
        results.append((contours, tr, enc.bundles(tr), enc.eps_px))
    (c1, tr1, b1, eps1), (c3, tr3, b3, eps3) = results
    assert len(b1) == 1 and 0 < eps1 <= 1.0  # simplified within a pixel, one bundle
    (f1,) = [decode(b) for b in b1]
    assert dist_px(c1[0], f1.ocg[tr1.hand_tracks[0].id] * IMAGE).max() <= eps1 + 1e-3
    assert len(b3) > 1 and eps3 >= EPS_PX[-1]  # too rough for one datagram: split
    parts = [decode(b) for b in b3]
    check_stream(parts)
    assert {p.f_id for p in parts} == {2}  # one frame, every part its frm
    live = sorted(t.id for t in tr3.live_hands)
    assert all(sorted(p.alive) == live for p in parts)  # the whole alv in each part
    sent = [sid for p in parts for sid in p.bnd]
    assert sorted(sent) == live  # each hand once, with its outline in the same part
    for c, t in zip(c3, tr3.hand_tracks, strict=True):
        (p,) = [p for p in parts if t.id in p.bnd]
        assert dist_px(c, p.ocg[t.id] * IMAGE).max() <= eps3 + 1e-3  # whole, not cut


# ---------------------------------------------------------------- the flow pipeline
@pytest.fixture
def udp_inbox():
    """A UDP socket on localhost collecting datagrams in a thread."""
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    sock.bind(("127.0.0.1", 0))
    sock.settimeout(0.2)
    got: list[bytes] = []
    stop = threading.Event()

    def run():
        while not stop.is_set():
            with contextlib.suppress(TimeoutError):
                got.append(sock.recv(65536))

    th = threading.Thread(target=run, daemon=True)
    th.start()
    yield sock.getsockname()[1], got
    stop.set()
    th.join(2)
    sock.close()


def test_the_flow_pipeline_streams_hands_and_fingers_over_udp(udp_inbox, profile, plugins):
    from console.core.types import GestureScript, GestureStep
    from console.runtime.stages import base_stages, learn_background, open_classifier
    from plugins.tuio.sender2 import Tuio2Sender

    port, got = udp_inbox
    gap, n_open, n_two = 20, 50, 60
    camera = plugins.build("camera", "twin", profile)
    camera.realtime = False
    camera.set_script(
        GestureScript(
            (GestureStep("open_hand", frames=n_open), GestureStep("two_finger", frames=n_two)),
            gap_frames=gap,
            loop=False,
        )
    )
    tx = Tuio2Sender("127.0.0.1", port, table_mm=TABLE, image_px=IMAGE)
    seen: dict[int, tuple] = {}  # f_id -> the vision's outlines by hand session, to_mm
    try:
        clf = open_classifier(profile, plugins)
        learn_background(camera, clf)
        stages = base_stages(clf)
        for _ in range(gap + n_open + gap + n_two):
            f = camera.read(1.0)
            work: dict = {}
            for _, stage in stages:
                stage(f, work)
            tx(f, work)
            tr = work["tracks"]
            outl = {t.id: h.contour_px for h, t in zip(tr.hands, tr.hand_tracks, strict=True)}
            seen[tx.fseq] = (outl, work["to_mm"])
        tx.close()
    finally:
        camera.close()
    t0 = time.monotonic()
    while len(got) < tx.sent and time.monotonic() - t0 < 5:
        time.sleep(0.02)
    frames = [decode(d) for d in list(got)]
    check_stream(frames)
    assert len(frames) >= 0.95 * tx.sent
    hands = sorted({s for f in frames for s in f.bnd})
    assert len(hands) == 2  # one bnd session per placement of the hand
    assert {s for f in frames for s in f.ocg} == set(hands)
    assert all(len(f.bnd) <= 1 for f in frames)
    on = [f for f in frames if f.bnd]
    assert len(on) >= 0.9 * (n_open + n_two)
    fingers = {s: p for f in frames for s, p in f.ptr.items()}
    assert len(fingers) == 2  # the two fingertips, one session each throughout
    assert {p["c_id"] for f in frames for p in f.ptr.values()} == {hands[1]}
    assert {p["user"] for f in frames for p in f.ptr.values()} == {1 + hands[1] % 0xFFFF}
    # the outline sent is the vision's, within a pixel, after the camera -> table mapping
    checked = 0
    for f in on[:: max(len(on) // 12, 1)]:
        outl, to_mm = seen[f.f_id]
        (sid,) = f.bnd
        grid = np.mgrid[0:640:40, 0:480:40].reshape(2, -1).T.astype(float)
        norm = to_mm(grid) / TABLE  # the mapping as the table sees it, inverted here
        back, _ = cv2.findHomography(norm.astype(np.float32), grid.astype(np.float32))
        px = cv2.perspectiveTransform(f.ocg[sid].reshape(-1, 1, 2), back).reshape(-1, 2)
        assert dist_px(outl[sid], px).max() <= 1.0 + 0.05
        checked += 1
    assert checked >= 8


# ---------------------------------------------------------------- WebSocket, settings
def test_websocket_clients_receive_each_bundle_whole():
    from websockets.exceptions import ConnectionClosed
    from websockets.sync.client import connect

    from plugins.tuio.sender2 import Tuio2Sender
    from plugins.tuio.websocket import WebSocketServer

    srv = WebSocketServer("127.0.0.1", 0)
    tx = Tuio2Sender(table_mm=TABLE, image_px=IMAGE, server=srv)
    tx.send(0.0, [], [])  # nobody connected: nothing waits
    got: list[bytes] = []
    with connect(f"ws://127.0.0.1:{srv.port}") as ws:
        t0 = time.monotonic()
        while srv.clients < 1 and time.monotonic() - t0 < 5:
            time.sleep(0.01)
        c = circle((320, 240), 120, n=1400)
        for k in range(5):
            tx.send(k / 60, [Contact(0, (320.0, 200.0))], [hand(c, (Contact(0, (320.0, 200.0)),))])
        tx.close()  # the empty frame, then the server ends
        try:
            while True:
                got.append(ws.recv(timeout=5))
        except (ConnectionClosed, TimeoutError):
            pass
    frames = [decode(d) for d in got]
    assert len(frames) == 6 and all(isinstance(d, bytes) for d in got)
    check_stream(frames, limit=65536)
    assert frames[0].size > 4096  # over WebSocket the outline needs no simplifying
    assert len(frames[0].ocg[next(iter(frames[0].bnd))]) == 1400
    assert frames[-1].alive == [] and srv.dropped == 0


def with_tuio(profile, **keys):
    return dataclasses.replace(
        profile, data={**profile.data, "tuio": {**profile.section("tuio"), **keys}}
    )


def test_version_1_1_stays_the_default_and_2_0_or_websocket_are_chosen(profile):
    from plugins.tuio.sender import TuioSender
    from plugins.tuio.sender2 import Tuio2Sender
    from plugins.tuio.sink import make_sender

    one = make_sender(profile, force=True)
    assert type(one) is TuioSender and profile.get("tuio.version") == "1.1"
    one.close()
    two = make_sender(with_tuio(profile, version="2.0"), force=True)
    assert isinstance(two, Tuio2Sender) and two.encoder.limit_bytes == 4096
    two.close()
    s = socket.socket()
    s.bind(("127.0.0.1", 0))
    free = s.getsockname()[1]
    s.close()
    ws = make_sender(
        with_tuio(profile, version="2.0", transport="websocket", ws_port=free), force=True
    )
    assert isinstance(ws, Tuio2Sender) and ws.port == free and ws.encoder.limit_bytes == 65536
    ws.close()
    with pytest.raises(UserError) as err:
        make_sender(with_tuio(profile, version="3"), force=True)
    assert str(err.value) == "[tuio] version = '3': give '1.1' or '2.0'"


def test_a_bad_version_in_a_profile_is_one_line_naming_the_key(plugins, tmp_path):
    from console.config.profile import find_profile, load_profile

    bad = tmp_path / "bad.toml"
    bad.write_text(find_profile("sim").read_text() + '\n[tuio]\nversion = "3"\n')
    with pytest.raises(UserError) as err:
        load_profile(bad, plugins)
    msg = str(err.value)
    assert "\n" not in msg and str(bad) in msg
    assert '[tuio] version = "3"' in msg and "'1.1', '2.0'" in msg


# ---------------------------------------------------------------- the flow demo, end to end
def test_the_flow_demos_tuio2_stream_names_each_hand_and_finger(
    udp_inbox, profile, plugins, outputs, tmp_path
):
    """``haptable demo flow --tuio`` with ``[tuio] version = "2.0"``: a right hand resting
    flat (the flow's) and a left hand in an L (thumb and index flat, the others' knuckles
    down), decoded by the spec's decoder."""
    from console.files.vibration_map import save_map
    from plugins.demos.run import start_demo
    from plugins.twin.camera.camera import Together
    from plugins.vibrotactile.analytic_plate import SSPlate, analytic_map

    port, got = udp_inbox
    save_map(tmp_path / "map.npz", analytic_map(SSPlate()))
    demos = {"flow_map": str(tmp_path / "map.npz"), "plan_process": False, "flow_atlas": False}
    data = {
        **profile.data,
        "tuio": {**profile.section("tuio"), "version": "2.0", "port": port},
        "demos": {**profile.section("demos"), **demos},
    }
    prof = dataclasses.replace(profile, data=data)
    cam = plugins.build("camera", "twin", prof)  # both hands posed before the first frame
    holds = []
    for gesture, centre_mm, side in (
        ("open_hand", (230, 230), "right"),
        ("l_shape", (520, 230), "left"),
    ):
        cam.place(gesture, centre_mm, subject="s1", side=side)
        holds.append(cam.script)
    cam.set_script(Together(holds))
    try:
        run = start_demo(
            "flow", prof, plugins, outputs, camera=cam, script=False, prepare=False, tuio=True,
            watchdog_ms=5000,
        )  # fmt: skip
    except BaseException:
        cam.close()
        raise
    try:
        t0 = time.monotonic()
        while time.monotonic() - t0 < 20 and sum(1 for d in list(got) if b"/tuio2/ptr" in d) < 40:
            time.sleep(0.05)
    finally:
        run.stop()
        cam.close()
    snap = run.snapshot()
    t0 = time.monotonic()
    while time.monotonic() - t0 < 2 and not (got and b"/tuio2/bnd" not in got[-1]):
        time.sleep(0.02)  # the sender's last, empty frame
    frames = [decode(d) for d in list(got)]  # frm first, alv last in each
    check_stream(frames)
    assert frames[-1].alive == []
    both = [f for f in frames if len(f.bnd) == 2]
    assert len(both) >= 30, "".join(str(len(f.bnd)) for f in frames) + str(snap["camera"])
    hands = sorted({s for f in frames for s in f.bnd})
    assert len(hands) == 2 and {s for f in frames for s in f.ocg} == set(hands)
    left = max(hands, key=lambda s: both[0].bnd[s][0])  # the L is the hand at larger x
    flat = min(hands, key=lambda s: both[0].bnd[s][0])
    ptrs = {}
    for f in both:
        for s, p in f.ptr.items():
            ptrs.setdefault(s, []).append(p)
    assert all(
        p["c_id"] == left and p["user"] == 1 + left % 0xFFFF for v in ptrs.values() for p in v
    )
    assert flat not in {p["c_id"] for v in ptrs.values() for p in v}  # a flat hand: no tips
    # one session per touching finger: the L's 4 or 5 contacts, each its own, each steady
    steady = {s: v for s, v in ptrs.items() if len(v) >= 0.8 * len(both)}
    assert 4 <= len(steady) <= 5 and len(ptrs) <= len(steady) + 2
    types = {s: {p["type"] for p in v[len(v) // 2 :]} for s, v in steady.items()}
    assert all(len(t) == 1 for t in types.values())  # a finger keeps its type
    named = sorted(t for (t,) in types.values() if t)
    assert len(named) >= 3 and set(named) <= set(range(6, 11))  # the left hand's ids
    assert len(set(named)) == len(named)  # never two sessions on one finger
    assert 10 in named and 6 in named  # the left thumb and index, flat on the glass


def test_close_lets_a_slow_client_receive_every_queued_bundle(monkeypatch):
    """``close`` ends the server only once each client's queue is written out: a client
    the machine serves slowly still gets every bundle sent before the close."""
    from websockets.exceptions import ConnectionClosed
    from websockets.sync.client import connect
    from websockets.sync.server import ServerConnection

    from plugins.tuio.websocket import WebSocketServer

    send = ServerConnection.send

    def slow(self, message, *a, **k):
        time.sleep(0.05)  # a loaded machine: each write comes late
        return send(self, message, *a, **k)

    monkeypatch.setattr(ServerConnection, "send", slow)
    srv = WebSocketServer("127.0.0.1", 0)
    got: list[bytes] = []
    with connect(f"ws://127.0.0.1:{srv.port}") as ws:
        t0 = time.monotonic()
        while srv.clients < 1 and time.monotonic() - t0 < 5:
            time.sleep(0.01)
        for k in range(8):
            srv.send(bytes([k]) * 32)
        srv.close()
        try:
            while True:
                got.append(ws.recv(timeout=5))
        except (ConnectionClosed, TimeoutError):
            pass
    assert got == [bytes([k]) * 32 for k in range(8)] and srv.dropped == 0
