"""The IR camera twin: frames, ground truth, gestures, hard cases, mapping, streaming."""

from __future__ import annotations

import time
from dataclasses import replace
from types import SimpleNamespace

import cv2
import numpy as np
import pytest

from plugins.twin.camera.camera import IdleScript, TouchScript, TwinCamera
from plugins.twin.camera.geometry import TableMapping
from plugins.twin.camera.gestures import DYNAMIC, GESTURES, STATIC, plan_take, take_pose
from plugins.twin.camera.hand import hand_pieces, make_subject
from plugins.twin.camera.render import Rig, hand_layer
from plugins.twin.camera.sample import render_background, render_frame, render_sample

QUIET = Rig(noise_sigma=0.0, shot_gain=0.0)


def _render(gesture, seed=0, **kw):
    return render_sample(gesture, "s1", 0, np.random.default_rng(seed), **kw)


@pytest.fixture(scope="module")
def all_samples():
    return {g: _render(g, seed=i) for i, g in enumerate(GESTURES)}


def _local(img, p, r=1):
    x, y = int(round(p[0])), int(round(p[1]))
    return float(img[max(y - r, 0) : y + r + 1, max(x - r, 0) : x + r + 1].mean())


def test_frames_are_640x480_uint8_with_the_documented_frame_counts(all_samples):
    for g, (frames, truth) in all_samples.items():
        assert frames.dtype == np.uint8
        assert frames.shape[1:] == (480, 640)
        assert len(frames) == (6 if g in STATIC else 8)
        assert len(truth["frames"]) == len(frames)
        assert truth["gesture"] == g and truth["kind"] == ("static" if g in STATIC else "dynamic")


def test_ground_truth_contacts_land_on_bright_sharp_blobs(all_samples):
    for g, (frames, truth) in all_samples.items():
        bg = render_background(Rig(), truth["t0_s"], np.random.default_rng(0)).astype(float)
        for img, ft in zip(frames, truth["frames"], strict=True):
            assert ft["contacts_px"], f"{g}: no contact in a frame"
            diff = img.astype(float) - bg
            highpass = diff - cv2.GaussianBlur(diff, (0, 0), 6)
            for p in ft["contacts_px"]:
                assert _local(diff, p) > 110, f"{g}: contact {p} not bright"
                assert _local(highpass, p, 0) > -5, f"{g}: contact {p} in a blurred region"


def test_contacts_are_brighter_than_hovering_parts():
    s = make_subject("s1")
    rng = np.random.default_rng(0)
    frames, truth = render_sample("one_finger", s, 0, rng, rig=QUIET, t0_s=0.0)
    img = frames[0].astype(float)
    bg = render_background(QUIET, 0.0, rng).astype(float)
    tip = truth["frames"][0]["contacts_px"][0]
    palm = truth["frames"][0]["hands"][0]["center_px"]
    assert _local(img - bg, tip) > 2 * _local(img - bg, palm) > 0
    # the same finger lifted 15 mm: its tip is dimmer and blurrier
    take = plan_take("one_finger", s, np.random.default_rng(1), QUIET.mapping.table_mm)
    pose = take_pose(take, 0.0)
    lifted = replace(
        pose,
        fingers=(
            pose.fingers[0],
            replace(pose.fingers[1], contact=False, lift_mm=15.0),
            *pose.fingers[2:],
        ),
    )
    a, ta = render_frame([(s, pose)], QUIET, 0.0, rng)
    b, _ = render_frame([(s, lifted)], QUIET, 0.0, rng)
    p = ta["contacts_px"][0]
    assert _local(a.astype(float) - bg, p) > 1.5 * _local(b.astype(float) - bg, p)


def test_height_dims_and_blurs_skin():
    s = make_subject("s2")
    rng = np.random.default_rng(0)
    take = plan_take("closed_hand", s, rng, QUIET.mapping.table_mm, angle_deg=90.0)
    base = take_pose(take, 0.0)
    geo0 = hand_pieces(s, base)
    peaks, edges = [], []
    for lift in (0.0, 10.0, 30.0):
        pieces = [type(p)(p.poly_mm, p.h_mm + lift, p.refl) for p in geo0.pieces]
        layer = hand_layer(pieces, QUIET.mapping)
        peaks.append(float(layer.max()))
        gy, gx = np.gradient(layer)
        edges.append(float(np.hypot(gx, gy).max()))
    assert peaks[0] > peaks[1] > peaks[2]
    assert edges[0] > edges[1] > edges[2]


def test_left_hand_is_the_mirror_image_of_the_right():
    s = make_subject("s3")
    for g in ("open_hand", "l_shape", "two_finger"):
        take = plan_take(
            g,
            s,
            np.random.default_rng(2),
            (743.46, 447.29),
            wrist_mm=(300.0, 100.0),
            angle_deg=90.0,
            tremor=False,
        )
        right = take_pose(take, 0.0)
        left = replace(right, side="left")
        gr, gl = hand_pieces(s, right), hand_pieces(s, left)
        cr = {c["finger"]: np.array(c["pos_mm"]) for c in gr.contacts}
        cl = {c["finger"]: np.array(c["pos_mm"]) for c in gl.contacts}
        assert cr.keys() == cl.keys()
        for f in cr:  # mirror about the line x = 300 (the hand's axis, pointing +y)
            assert cl[f] == pytest.approx([600.0 - cr[f][0], cr[f][1]], abs=1e-6)
        if "thumb" in cr:  # a right hand, palm down, seen from above: thumb on the left
            assert cr["thumb"][0] < 300.0 < cl["thumb"][0]
    # and in the image: the left hand's layer is the right one's mirror (axis at x=300 mm)
    m = TableMapping(corners_px=((620.0, 420.0), (20.0, 420.0), (20.0, 60.0), (620.0, 60.0)))
    take = plan_take(
        "open_hand",
        s,
        np.random.default_rng(2),
        m.table_mm,
        wrist_mm=(371.73, 120.0),
        angle_deg=90.0,
        tremor=False,
    )
    pr = take_pose(take, 0.0)
    lr = hand_layer(hand_pieces(s, pr).pieces, m)
    ll = hand_layer(hand_pieces(s, replace(pr, side="left")).pieces, m)
    mirrored = np.abs(ll[:, 1:] - lr[:, ::-1][:, :-1]).mean()
    assert mirrored < 0.05 * np.abs(ll - lr).mean()


def test_same_seed_same_frames_other_seed_other_frames():
    a, ta = _render("rotate", seed=7)
    b, tb = _render("rotate", seed=7)
    c, tc = _render("rotate", seed=8)
    assert np.array_equal(a, b) and ta == tb
    assert not np.array_equal(a, c)


def test_subjects_differ_and_keep_their_hands():
    s1, s2 = make_subject("s1"), make_subject("s2")
    assert s1 == make_subject("s1")
    assert s1.length_mm != s2.length_mm and s1.finger_len_mm != s2.finger_len_mm
    lengths = [make_subject(f"s{i}").length_mm for i in range(1, 30)]
    assert 5 < np.std(lengths) < 15 and 175 < np.mean(lengths) < 195
    widths = [make_subject(f"s{i}").width_mm for i in range(1, 30)]
    assert 80 < np.mean(widths) < 90  # paper: 84.8 +- 5.2 mm
    # the same pose of two subjects puts the fingertips in different places
    ta = _render("open_hand", seed=3, wrist_mm=(300.0, 100.0), angle_deg=90.0)[1]
    tb = render_sample(
        "open_hand", "s2", 0, np.random.default_rng(3), wrist_mm=(300.0, 100.0), angle_deg=90.0
    )[1]
    pa, pb = np.array(ta["frames"][0]["contacts_mm"]), np.array(tb["frames"][0]["contacts_mm"])
    assert np.abs(pa - pb).max() > 3.0


def _contacts(truth, k):
    hand = truth["frames"][k]["hands"][0]
    return {c["finger"]: np.array(c["pos_mm"]) for c in hand["contacts"] if c["kind"] == "tip"}


def test_static_poses_touch_with_the_right_fingers(all_samples):
    want = {
        "one_finger": {"index"},
        "two_finger": {"index", "middle"},
        "l_shape": {"thumb", "index"},
        "closed_hand": {"thumb", "index", "middle", "ring", "little"},
        "open_hand": {"thumb", "index", "middle", "ring", "little"},
    }
    for g, fingers in want.items():
        t = all_samples[g][1]
        assert set(_contacts(t, 0)) == fingers, g
        palm = t["frames"][0]["hands"][0]["palm_contact"]
        assert palm == (g in ("closed_hand", "open_hand")), g
        moved = max(np.linalg.norm(_contacts(t, -1)[f] - _contacts(t, 0)[f]) for f in fingers)
        assert moved < 3.0, f"{g} is static but moved {moved:.1f} mm"
    a = _contacts(all_samples["open_hand"][1], 0)
    b = _contacts(all_samples["closed_hand"][1], 0)
    assert np.linalg.norm(a["little"] - a["index"]) > np.linalg.norm(b["little"] - b["index"])


def test_dynamic_gestures_move_as_scripted():
    for seed in range(4):
        _, t = _render("drag", seed=seed)
        assert np.linalg.norm(_contacts(t, -1)["index"] - _contacts(t, 0)["index"]) > 10

        _, t = _render("rotate", seed=seed)
        c0, c1 = _contacts(t, 0), _contacts(t, -1)
        assert np.linalg.norm(c1["thumb"] - c0["thumb"]) < 2.5  # the pivot
        r0 = np.linalg.norm(c0["index"] - c0["thumb"])
        r1 = np.linalg.norm(c1["index"] - c1["thumb"])
        assert abs(r1 - r0) < 3.0 and np.linalg.norm(c1["index"] - c0["index"]) > 10  # arc
        turn = t["frames"][-1]["hands"][0]["angle_deg"] - t["frames"][0]["hands"][0]["angle_deg"]
        assert abs((turn + 180) % 360 - 180) > 10

        _, t = _render("zoom", seed=seed)
        d0 = np.linalg.norm(_contacts(t, 0)["index"] - _contacts(t, 0)["thumb"])
        d1 = np.linalg.norm(_contacts(t, -1)["index"] - _contacts(t, -1)["thumb"])
        assert (d1 - d0 > 8) if t["variant"] == "in" else (d0 - d1 > 8)

        _, t = _render("spread_pile", seed=seed)

        def spread(k, t=t):
            p = np.array(list(_contacts(t, k).values()))
            return np.linalg.norm(p - p.mean(0), axis=1).mean()

        assert len(_contacts(t, 0)) == 5
        assert (
            (spread(-1) - spread(0) > 2.5)
            if t["variant"] == "spread"
            else (spread(0) - spread(-1) > 2.5)
        )

        _, t = _render("wipe", seed=seed)
        h0, h1 = t["frames"][0]["hands"][0], t["frames"][-1]["hands"][0]
        assert h0["palm_contact"]
        d = np.array(h1["center_mm"]) - np.array(h0["center_mm"])
        a = np.radians(h0["angle_deg"])
        assert abs(d @ [-np.sin(a), np.cos(a)]) > 15  # sideways to the hand


def test_hard_case_empty_frame_is_the_background():
    frames, t = _render("drag", hard=("empty",), rig=QUIET, t0_s=5.0)
    bg = render_background(QUIET, 5.0, np.random.default_rng(0))
    assert all(not f["hands"] for f in t["frames"])
    assert np.abs(frames[0].astype(int) - bg).max() <= 1


def test_hard_case_hand_cut_by_the_image_border():
    frames, t = _render("open_hand", hard=("border_cut",))
    contacts = t["frames"][0]["hands"][0]["contacts"]
    assert any(not c["in_image"] for c in contacts) and any(c["in_image"] for c in contacts)
    assert frames[0][:, :3].max() > 120  # bright skin reaches the image edge


def test_hard_case_two_hands():
    _, t = _render("one_finger", hard=("two_hands",))
    hands = t["frames"][0]["hands"]
    assert len(hands) == 2 and {h["side"] for h in hands} == {"left", "right"}
    p = np.array(t["frames"][0]["contacts_mm"])
    assert len(p) == 2 and np.linalg.norm(p[0] - p[1]) > 60


def test_hard_case_fingertip_only_is_a_small_blob():
    frames, t = _render("one_finger", hard=("fingertip_only",), rig=QUIET, t0_s=0.0)
    bg = render_background(QUIET, 0.0, np.random.default_rng(0)).astype(float)
    diff = frames[0].astype(float) - bg
    blob = diff > 100
    n, labels = cv2.connectedComponents(blob.astype(np.uint8))
    assert n == 2  # background + one blob
    assert 3 <= blob.sum() <= 60
    x, y = t["frames"][0]["contacts_px"][0]
    assert labels[int(round(y)), int(round(x))] == 1


def test_hard_case_rotated_exactly_180_degrees():
    a, ta = _render("l_shape", hard=("rotated_180",))
    assert ta["frames"][0]["hands"][0]["angle_deg"] == 270.0
    b, tb = _render(
        "l_shape", angle_deg=90.0, wrist_mm=tuple(ta["frames"][0]["hands"][0]["wrist_mm"])
    )
    assert tb["frames"][0]["hands"][0]["angle_deg"] == 90.0
    # no tremor: the exact pose holds in every frame
    assert ta["frames"][0]["hands"][0]["wrist_mm"] == ta["frames"][-1]["hands"][0]["wrist_mm"]


def test_hard_case_sudden_illumination_change():
    frames, t = _render("drag", hard=("illumination_step",))
    steps = [f["illumination_step"] for f in t["frames"]]
    k = steps.index(True)
    assert not any(steps[:k]) and all(steps[k:])
    assert frames[k].mean() - frames[k - 1].mean() > 10


def test_unknown_gesture_or_hard_case_is_refused():
    with pytest.raises(ValueError, match="unknown gesture"):
        _render("wave")
    with pytest.raises(ValueError, match="hard case"):
        _render("drag", hard=("fog",))


def test_mapping_round_trip_and_corners_with_and_without_distortion():
    pts = np.random.default_rng(0).uniform([0, 0], [743.46, 447.29], (200, 2))
    for m in (TableMapping(), TableMapping(k1=-0.18, k2=0.03)):
        assert np.abs(m.px_to_mm(m.mm_to_px(pts)) - pts).max() < 1e-6
    m = TableMapping()
    corners = m.mm_to_px([[0, 0], [743.46, 0], [743.46, 447.29], [0, 447.29]])
    assert corners == pytest.approx(np.array(m.corners_px), abs=1e-6)
    # second method: OpenCV's perspectiveTransform with the same homography
    ref = cv2.perspectiveTransform(pts.reshape(-1, 1, 2), m.homography).reshape(-1, 2)
    assert np.abs(ref - m.mm_to_px(pts)).max() < 1e-6
    # barrel distortion pulls the corners towards the image centre, the centre stays
    d = TableMapping(k1=-0.18, k2=0.03)
    c = np.array([319.5, 239.5])
    dc = d.mm_to_px([[0, 0]])[0]
    assert np.linalg.norm(dc - c) < np.linalg.norm(corners[0] - c) - 10
    # the forward distortion agrees with OpenCV's projectPoints model
    und = m.mm_to_px(pts)
    k = d.camera_matrix
    obj = np.c_[(und - k[:2, 2]) / d.focal_px, np.ones(len(und))]
    ref, _ = cv2.projectPoints(obj, np.zeros(3), np.zeros(3), k, d.dist_coeffs)
    assert np.abs(ref.reshape(-1, 2) - d.mm_to_px(pts)).max() < 1e-6


def test_truth_pixels_and_millimetres_agree_under_distortion():
    rig = Rig(mapping=TableMapping(k1=-0.18, k2=0.03))
    _, t = render_sample("open_hand", "s1", 0, np.random.default_rng(1), rig=rig)
    for c in t["frames"][0]["hands"][0]["contacts"]:
        assert rig.mapping.px_to_mm([c["pos_px"]])[0] == pytest.approx(c["pos_mm"], abs=0.01)


def test_camera_streams_frames_with_status():
    cam = TwinCamera(script=IdleScript(), realtime=False)
    frames = [cam.read() for _ in range(5)]
    assert [f.seq for f in frames] == [0, 1, 2, 3, 4]
    assert frames[0].image.shape == (480, 640) and frames[0].image.dtype == np.uint8
    st = cam.status()
    assert {"fps", "dropped", "nominal_fps", "frames"} <= st.keys() and st["frames"] == 5
    cam.close()
    assert cam.read() is None


def test_camera_sudden_lights_change():
    cam = TwinCamera(script=IdleScript(), realtime=False)
    before = cam.read().image.mean()
    cam.lights_changed = True
    after = cam.read()
    assert after.image.mean() - before > 10 and cam.truth["illumination_step"]
    assert abs(cam.background().mean() - after.image.mean()) < 2


def test_a_reader_a_few_frames_late_gets_every_frame_in_order(monkeypatch):
    """As from a camera driver's buffer queue: late by up to ``CATCH_UP_FRAMES`` frames,
    the reader gets them all, each with its capture time; later, the ones beyond are
    dropped (a fake clock: the test does not depend on the machine's load)."""
    from plugins.twin.camera import camera as cam_mod

    clock = SimpleNamespace(now=100.0)
    fake = SimpleNamespace(
        monotonic=lambda: clock.now,
        sleep=lambda s: setattr(clock, "now", clock.now + max(0.0, s)),
    )
    monkeypatch.setattr(cam_mod, "time", fake)
    cam = TwinCamera(script=IdleScript(), fps=60.0, realtime=True)
    first = cam.read(0.5)
    clock.now += 2.5 / 60  # a stall of 2.5 frames
    got = [cam.read(0.5) for _ in range(4)]
    assert [f.seq for f in got] == [first.seq + i for i in range(1, 5)]
    assert [round((f.t_capture_s - first.t_capture_s) * 60) for f in got] == [1, 2, 3, 4]
    assert cam.status()["dropped"] == 0
    clock.now += 10.5 / 60  # 9.5 frames late: the newest 3 (and this one) kept, 6 lost
    late = cam.read(0.5)
    assert cam.status()["dropped"] == 9 - cam_mod.CATCH_UP_FRAMES == 6
    assert late.seq == got[-1].seq + 1 + 6
    assert [cam.read(0.5).seq for _ in range(3)] == [late.seq + 1, late.seq + 2, late.seq + 3]


def test_camera_performs_a_gesture_for_recording():
    cam = TwinCamera(realtime=False)
    first = cam.perform("zoom", "s2", "left", 12)
    labels = []
    for _ in range(first + 12):
        cam.read()
        labels.append(cam.truth["gesture"])
    assert labels[first:] == ["zoom"] * 12
    assert cam.truth["hands"][0]["side"] == "left" and cam.truth["hands"][0]["subject"] == "s2"


def test_touch_script_touches_each_point_with_realistic_error():
    pts = [(100.0, 100.0), (400.0, 250.0), (650.0, 380.0)]
    exact = TouchScript(pts, table_mm=(743.46, 447.29), error_mm=0.0, bias_mm=0.0, loop=False)
    cam = TwinCamera(script=exact, realtime=False)
    seen = {}
    for _ in range(exact.period * 3):
        cam.read()
        t = cam.truth
        if t.get("touching"):
            seen.setdefault(t["target_index"], []).append(t["contacts_mm"][0])
    assert sorted(seen) == [0, 1, 2]
    for i, p in enumerate(pts):
        assert np.linalg.norm(np.mean(seen[i], axis=0) - p) < 0.6
    noisy = TouchScript(pts * 10, table_mm=(743.46, 447.29), error_mm=1.5, bias_mm=2.0)
    err = np.array(noisy.hits) - np.array(pts * 10)
    assert 1.0 < np.linalg.norm(err, axis=1).mean() < 6.0


def test_set_target_makes_the_operator_touch_it():
    cam = TwinCamera(realtime=False, touch_error_mm=0.0, touch_bias_mm=0.0)
    cam.set_target((300.0, 200.0))
    for _ in range(30):
        cam.read()
    t = cam.truth
    assert t["touching"] and t["target_mm"] == [300.0, 200.0]
    assert np.linalg.norm(np.array(t["contacts_mm"][0]) - [300.0, 200.0]) < 1.0
    x, y = t["contacts_px"][0]
    assert cam.read().image[int(round(y)), int(round(x))] > 120
    cam.set_target(None)
    cam.read()
    assert cam.truth["hands"] == []


def test_plugin_registers_the_twin_camera_and_its_profile_section(plugins, profile):
    assert "twin" in plugins.of("camera")
    assert "twin_camera" in plugins.sections
    cam = plugins.get("camera", "twin").factory(profile)
    cam.realtime = False
    f = cam.read()
    assert f.image.shape == (profile.get("camera.height_px"), profile.get("camera.width_px"))
    assert cam.status()["driver"] == "twin"
    cam.close()


def test_every_dynamic_gesture_keeps_its_contacts_on_the_glass(all_samples):
    for g in DYNAMIC:
        _, t = all_samples[g]
        for ft in t["frames"]:
            for p in ft["contacts_mm"]:
                assert 0 <= p[0] <= 743.46 and 0 <= p[1] <= 447.29, g


def test_two_index_fingers_touch_two_targets():
    cam = TwinCamera(realtime=False, touch_error_mm=0.0, touch_bias_mm=0.0)
    cam.set_targets([(200.0, 200.0), (500.0, 220.0)])
    for _ in range(25):
        cam.read()
    hands = {h["side"]: h for h in cam.truth["hands"]}
    assert set(hands) == {"left", "right"}
    assert hands["left"]["contacts"][0]["pos_mm"] == pytest.approx([200.0, 200.0], abs=1.0)
    assert hands["right"]["contacts"][0]["pos_mm"] == pytest.approx([500.0, 220.0], abs=1.0)
    with pytest.raises(ValueError, match="hand sides"):
        cam.set_targets([(1.0, 1.0)], sides=["left", "right"])


def test_place_holds_a_static_hand_where_asked():
    cam = TwinCamera(realtime=False)
    cam.place("open_hand", (370.0, 220.0), angle_deg=270.0, side="left")
    seen = []
    for _ in range(5):
        cam.read()
        seen.append(cam.truth["hands"][0]["center_mm"])
    assert cam.truth["gesture"] == "open_hand" and cam.truth["hands"][0]["side"] == "left"
    assert np.abs(np.array(seen) - [370.0, 220.0]).max() < 2.0
    assert cam.truth["hands"][0]["palm_contact"]


def test_motion_blur_smears_moving_hands_only():
    quiet_blur = replace(QUIET, exposure_s=0.012)
    sharp, ts = _render("wipe", seed=2, rig=QUIET, t0_s=0.0)
    blurred, tb = _render("wipe", seed=2, rig=quiet_blur, t0_s=0.0)
    assert ts == {**tb, "mapping": ts["mapping"]}  # same truth (mid-exposure)

    def edge(img):
        return float(np.percentile(np.abs(np.diff(img.astype(float), axis=1)), 99.9))

    assert edge(blurred[-1]) < 0.8 * edge(sharp[-1])
    still_a, _ = _render("open_hand", seed=2, rig=QUIET, t0_s=0.0)
    still_b, _ = _render("open_hand", seed=2, rig=quiet_blur, t0_s=0.0)
    assert np.array_equal(still_a, still_b)


def test_long_takes_sweep_back_and_forth_on_the_table():
    table = (743.46, 447.29)
    for g in ("rotate", "drag", "wipe", "zoom", "spread_pile"):
        for seed in range(2):
            take = plan_take(
                g, make_subject("s2"), np.random.default_rng(seed), table, duration_s=10.0
            )
            poses = [take_pose(take, k / 60.0) for k in range(0, 600, 23)]
            turn = np.array([p.angle_deg - take.angle_deg for p in poses])
            assert np.abs(turn).max() < (101.0 if g == "rotate" else 20.0), g
            for p in poses:
                geo = hand_pieces(make_subject("s2"), p)
                for c in geo.contacts:
                    assert -30 < c["pos_mm"][0] < table[0] + 30, g
                    assert -30 < c["pos_mm"][1] < table[1] + 30, g


def test_frames_that_passed_while_nobody_read_are_not_dropped():
    """The twin kept open while nobody reads (its screen hidden): on the next read the
    frames meanwhile are unread, not dropped, and the next frame is on time."""
    cam = TwinCamera(script=IdleScript(), fps=60.0, realtime=True)
    assert cam.read(0.5) is not None
    time.sleep(0.8)  # nobody reads (longer than READER_AWAY_S)
    t0 = time.monotonic()
    f = cam.read(0.5)
    assert f is not None and time.monotonic() - t0 < 0.1
    st = cam.status()
    assert st["dropped"] == 0 and 40 <= st["unread"] <= 60, st
    assert f.seq == st["unread"] + 1
