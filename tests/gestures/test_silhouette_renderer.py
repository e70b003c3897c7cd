"""The silhouette renderer: deterministic, rear-DI looking (touching skin bright and sharp,
hovering skin dim and soft, clipping only under strong light), hands that hold still or
move as told, fingertip contacts of human size measured on the image, shot noise with
Poisson statistics."""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest

from console.plugin_api import UserError
from plugins.gestures.dataset import load_dataset
from plugins.gestures.silhouette_gestures import make_subject, patch_geometry
from plugins.gestures.silhouette_renderer import (
    E_PER_DN,
    PX_PER_MM,
    _sensor,
    mm_to_px,
    render_sample,
    synth_silhouette,
    table,
)


def test_same_seed_same_sample_and_light_leaves_the_hand_alone():
    f1, b1, m1 = render_sample("drag", 1, 2, seed=5)
    f2, b2, m2 = render_sample("drag", 1, 2, seed=5)
    assert all(np.array_equal(a, b) for a, b in zip(f1, f2, strict=True))
    assert np.array_equal(b1, b2) and m1 == m2
    f3, _, _ = render_sample("drag", 1, 3, seed=5)
    assert not np.array_equal(f1[0], f3[0])
    _, _, dim = render_sample("drag", 1, 2, light_scale=0.7, seed=5)
    assert dim["truth"] == m1["truth"] and dim["hand"] == m1["hand"]
    assert len(f1) == 6 and f1[0].shape == (480, 640) and f1[0].dtype == np.uint8


def _edge_px(img: np.ndarray, start_px, direction, length_px: int = 40) -> tuple[float, float]:
    """(20-80 % rise distance in px, plateau level) along a line leaving a bright region."""
    sm = cv2.blur(img.astype(np.float32), (3, 3))
    d = np.asarray(direction, float) / np.hypot(*direction)
    n = np.array([-d[1], d[0]])
    s = np.arange(0, length_px, 0.25)
    prof = np.zeros_like(s)
    for off in (-1, 0, 1):
        xs = start_px[0] + s * d[0] + off * n[0]
        ys = start_px[1] + s * d[1] + off * n[1]
        prof += cv2.remap(
            sm, xs.astype(np.float32)[None], ys.astype(np.float32)[None], cv2.INTER_LINEAR
        )[0]
    prof /= 3
    hi, lo = prof[:8].mean(), prof[-8:].mean()
    x80 = s[np.argmax(prof < lo + 0.8 * (hi - lo))]
    x20 = s[np.argmax(prof < lo + 0.2 * (hi - lo))]
    return x20 - x80, hi


def test_touching_fingertip_is_brighter_and_sharper_than_the_hovering_palm():
    frames, bg, meta = render_sample("one_finger", 0, 0, seed=0)
    tab, truth = table(0), meta["truth"]
    tip = np.array(mm_to_px(tab, *truth["contacts_mm"][0]["index"]))
    palm = np.array(mm_to_px(tab, *truth["palm_centre_mm"][0]))
    out = tip - palm
    tip_w, tip_level = _edge_px(frames[0], tip - 2 * out / np.hypot(*out), out)
    # the palm's edge on the little-finger side (no finger beyond it)
    ang = truth["angle_rad"][0]
    side = 1.0 if meta["hand"] == "right" else -1.0
    u_dir = side * np.array([math.sin(ang), -math.cos(ang)])
    palm_w, palm_level = _edge_px(frames[0], palm, u_dir, 70)
    assert tip_level > 1.8 * palm_level
    assert tip_w < 0.4 * palm_w, (tip_w, palm_w)


def test_strong_light_clips_touching_skin_and_weak_light_does_not():
    strong, _, _ = render_sample("closed_hand", 0, 0, light_scale=1.3, seed=0)
    weak, wbg, _ = render_sample("closed_hand", 0, 0, light_scale=0.7, seed=0)
    clipped = strong[0] == 255
    assert clipped.sum() > 50
    # what clips is touching skin: bright under weak light too, far above the empty table
    assert (weak[0][clipped].astype(int) - wbg[clipped] > 90).mean() > 0.95
    assert max(int(f.max()) for f in weak) < 255


def _bright_centroids_mm(frames: list[np.ndarray], bg: np.ndarray) -> np.ndarray:
    """Table mm (through the camera's pixel-to-glass map) of the bright skin's centroid
    per frame: over 60 % of the first frame's brightest, weighted by the excess."""
    tab = table(0)
    diffs = [cv2.blur(f.astype(np.float32) - bg, (5, 5)) for f in frames]
    thr = 0.6 * diffs[0].max()
    out = []
    for d in diffs:
        ys, xs = np.nonzero(d > thr)
        w = d[ys, xs] - thr
        out.append(
            [np.average(tab.x_mm[ys, xs], weights=w), np.average(tab.y_mm[ys, xs], weights=w)]
        )
    return np.array(out)


@pytest.mark.parametrize("gesture", ["one_finger", "l_shape", "open_hand"])
def test_a_static_hand_holds_still(gesture):
    frames, bg, _ = render_sample(gesture, 1, 0, seed=0)
    c = _bright_centroids_mm(frames, bg)
    assert np.hypot(*(c - c[0]).T).max() < 2.0


def test_a_drag_moves_as_fast_as_its_truth_says():
    frames, bg, meta = render_sample("drag", 1, 0, seed=0)
    c = _bright_centroids_mm(frames, bg)
    moved = np.hypot(*(c[-1] - c[0]))
    want = meta["truth"]["speed_mm_s"] * 5 / 60
    assert moved > 10.0
    assert moved == pytest.approx(want, rel=0.15)


def _two_contacts_mm(frame: np.ndarray, bg: np.ndarray) -> np.ndarray:
    """Table mm of the two largest flat-topped bright blobs (the touching fingertips)."""
    tab = table(0)
    diff = cv2.blur(frame.astype(np.float32) - bg, (3, 3))
    n, lab, stats, _ = cv2.connectedComponentsWithStats((diff > 0.75 * diff.max()).astype(np.uint8))
    big = 1 + np.argsort(stats[1:, cv2.CC_STAT_AREA])[::-1][:2]
    return np.array([[tab.x_mm[lab == i].mean(), tab.y_mm[lab == i].mean()] for i in big])


@pytest.mark.parametrize("rep", [0, 1])
def test_zoom_and_rotate_move_the_two_fingertips_as_their_truth_says(rep):
    frames, bg, meta = render_sample("zoom", 2, rep, seed=0)
    a, b = _two_contacts_mm(frames[0], bg), _two_contacts_mm(frames[-1], bg)
    change = np.hypot(*(b[0] - b[1])) - np.hypot(*(a[0] - a[1]))
    want = meta["truth"]["spacing_rate_mm_s"] * 5 / 60
    assert abs(want) > 6 and abs(change - want) < 0.3 * abs(want), (change, want)
    frames, bg, meta = render_sample("rotate", 2, rep, seed=0)
    turns = []
    for f in (frames[0], frames[-1]):
        d = np.subtract(*_two_contacts_mm(f, bg))
        turns.append(math.degrees(math.atan2(d[1], d[0])))
    turned = (turns[1] - turns[0] + 90) % 180 - 90  # the line between the tips, either way
    want = meta["truth"]["omega_deg_s"] * 5 / 60
    assert abs(want) > 4 and abs(turned - want) < 2.0, (turned, want)


def _patch_mm(img: np.ndarray, at_px) -> tuple[float, float]:
    """(width, length) in mm of the flat-topped bright patch at ``at_px``."""
    sm = cv2.blur(img.astype(np.float32), (3, 3))
    c, r = (int(round(v)) for v in at_px)
    win = sm[r - 20 : r + 21, c - 20 : c + 21]
    _, lab = cv2.connectedComponents((win >= 0.88 * np.percentile(win, 99)).astype(np.uint8))
    ys, xs = np.nonzero(lab == lab[20, 20])
    pts = np.c_[xs, ys].astype(float)
    pts -= pts.mean(0)
    _, vec = np.linalg.eigh(pts.T @ pts)
    w, length = (np.ptp(pts @ vec[:, i]) + 1 for i in (0, 1))
    return w / PX_PER_MM, length / PX_PER_MM


@pytest.mark.parametrize("gesture", ["one_finger", "two_finger", "l_shape"])
def test_fingertip_contacts_measured_on_the_image_have_human_size(gesture):
    tab = table(0)
    for s in range(2):
        frames, _, meta = render_sample(gesture, s, 0, seed=0)
        subject = make_subject(0, s)
        for finger, xy in meta["truth"]["contacts_mm"][0].items():
            _, w_model, l_model = patch_geometry(subject, finger)
            w, length = _patch_mm(frames[0], mm_to_px(tab, *xy))
            assert 9.0 <= w <= 15.0 and 12.0 <= length <= 20.0, (finger, w, length)
            assert abs(w - w_model) < 2.0 and abs(length - l_model) < 2.5


def test_shot_noise_has_poisson_variance():
    """Photon transfer: the variance of two frames' difference grows with the mean as a
    Poisson count of E_PER_DN electrons per grey level (plus the read noise)."""
    tab = table(0)
    rng = np.random.default_rng(3)
    for level in (40.0, 120.0):
        flat = np.full((480, 640), level, np.float32)
        a = _sensor(tab, flat, 1.0, rng).astype(np.float32)
        b = _sensor(tab, flat, 1.0, rng).astype(np.float32)
        d = (a - b)[100:380, 100:540]
        d -= d.mean(axis=1, keepdims=True)  # row noise
        var = d.var() / 2
        m = level ** (1 / tab.gamma) * 255 ** (1 - 1 / tab.gamma)  # local gain of the gamma
        slope = m / level / tab.gamma
        want = slope**2 * (level / E_PER_DN + tab.read_dn**2) + 1 / 12  # + rounding
        assert var == pytest.approx(want, rel=0.12), (level, var, want)


def test_writes_a_dataset_the_project_loads(tmp_path):
    assert synth_silhouette(tmp_path, 1, 1, light_scale=1.3, seed=2) == 10
    samples = load_dataset(tmp_path, check_images=True)
    assert len(samples) == 10 and {s.subject for s in samples} == {"s1"}
    assert all(s.meta["renderer"] == "silhouette" and s.n_frames == 6 for s in samples)
    assert samples[0].truth()["contacts_mm"]


def test_bad_input_gets_one_line():
    with pytest.raises(UserError, match="gesture 'fist'.*one_finger"):
        render_sample("fist", 0, 0)
    with pytest.raises(UserError, match="light_scale 9.*0.7"):
        render_sample("drag", 0, 0, light_scale=9)
    with pytest.raises(UserError, match="seed -1: must be a whole number"):
        render_sample("drag", 0, 0, seed=-1)


def test_synth_renderer_silhouette_writes_a_set_the_tools_read(tmp_path, capsys):
    """``haptable gestures synth --renderer silhouette`` writes every gesture; options
    it does not model are refused in one line."""
    from console.cli.main import main

    out = tmp_path / "sil"
    assert main(["gestures", "synth", "--renderer", "silhouette", "--subjects", "1",
                 "--reps", "1", "--out", str(out)]) == 0  # fmt: skip
    assert len(load_dataset(out, check_images=True)) == 10
    assert main(["gestures", "synth", "--renderer", "silhouette", "--vary",
                 "--out", str(tmp_path / "x")]) != 0  # fmt: skip
    err = capsys.readouterr().err.strip().splitlines()
    assert err[-1].startswith("haptable: error: --vary") and "silhouette" in err[-1]
