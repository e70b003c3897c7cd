"""The independent phalanx renderer: format, optics, clipping, seeding, every gesture."""

from __future__ import annotations

import argparse
import json

import cv2
import numpy as np
import pytest

from plugins.gestures.dataset import GESTURES, load_dataset
from plugins.gestures.dataset_commands import COMMANDS
from plugins.gestures.phalanx_gestures import static_pose
from plugins.gestures.phalanx_renderer import (
    Pose,
    Subject,
    draw_optics,
    hand_parts,
    radiance,
    render,
    touch_mask,
)
from plugins.gestures.phalanx_synth import optics_of, render_sample, subject_of, synth_phalanx

SUBJECT = Subject("s1", "right", reflectance=0.95)
J0 = (0.0,) * 8


def _pose(gesture: str, subject: Subject = SUBJECT) -> Pose:
    palm, fingers = static_pose(gesture, subject, J0)
    return Pose((300.0, 260.0), -90.0, palm, fingers)


def test_dataset_loads_with_meta(tmp_path):
    info = synth_phalanx(
        tmp_path / "set", 1, 1, gestures=("one_finger", "zoom"), workers=1, light_scale=0.7
    )
    samples = load_dataset(tmp_path / "set", check_images=True)
    assert [s.gesture for s in samples] == ["one_finger", "zoom"]
    for s in samples:
        assert s.frames().shape == (6, 480, 640)
        assert s.background() is not None and s.fps == 60
        assert s.meta["renderer"] == "phalanx" and s.meta["light_scale"] == 0.7
        assert s.truth()["renderer"] == "phalanx"
    assert info["samples"] == 2


def test_touching_tips_brightest_hover_dimmer():
    pose = _pose("two_finger")
    rad = radiance(hand_parts(pose, SUBJECT), SUBJECT.reflectance)
    touch = touch_mask(pose, SUBJECT)
    near = cv2.dilate(touch.astype(np.uint8), np.ones((9, 9), np.uint8)).astype(bool)
    hover = (rad > 2.0) & ~near
    assert touch.sum() > 50 and hover.sum() > 2000
    tips = rad[cv2.erode(touch.astype(np.uint8), np.ones((3, 3), np.uint8)).astype(bool)]
    assert tips.mean() > 2.5 * rad[hover].mean()
    assert tips.mean() > np.percentile(rad[hover], 99.5)
    assert rad.max() == pytest.approx(tips.max())


def test_bright_light_clips_touching_skin_dim_light_does_not():
    pose = _pose("closed_hand")
    touch = touch_mask(pose, SUBJECT)
    optics = draw_optics(np.random.default_rng(3))
    shares = {}
    for scale in (0.7, 1.3):
        img = render([pose], SUBJECT, optics, scale, np.random.default_rng(0))[0]
        shares[scale] = float((img[touch] == 255).mean())
    assert shares[0.7] == 0.0
    assert shares[1.3] > 0.05


def test_same_seed_same_frames_light_keeps_the_performance():
    s, o = subject_of(5, 0, "left"), optics_of(5, 0)
    a = render_sample("rotate", s, o, np.random.default_rng(11), n_frames=4)
    b = render_sample("rotate", s, o, np.random.default_rng(11), n_frames=4)
    c = render_sample("rotate", s, o, np.random.default_rng(12), n_frames=4)
    assert np.array_equal(a[0], b[0]) and np.array_equal(a[1], b[1])
    assert not np.array_equal(a[0], c[0])
    bright = render_sample("rotate", s, o, np.random.default_rng(11), n_frames=4, light_scale=1.3)
    assert bright[2]["centre_px"] == a[2]["centre_px"]
    assert bright[0].astype(float).mean() > a[0].astype(float).mean()


@pytest.mark.parametrize("hand", ["right", "left"])
def test_every_gesture_renders(hand):
    s, o = subject_of(1, 0, hand), optics_of(1, 0)
    for gi, g in enumerate(GESTURES):
        frames, bg, truth = render_sample(g, s, o, np.random.default_rng(gi), n_frames=2)
        assert frames.shape == (2, 480, 640) and frames.dtype == np.uint8
        assert truth["touch_px"] > 40, g
        assert (frames[0].astype(int) - bg).max() > 60, g


def test_left_hand_is_the_mirror_image():
    lefty = Subject("s2", "left", reflectance=0.95)
    right = touch_mask(_pose("l_shape"), SUBJECT)
    left = touch_mask(_pose("l_shape", lefty), lefty)
    assert not np.array_equal(right, left)
    assert abs(int(right.sum()) - int(left.sum())) < 0.05 * right.sum()


def test_cli_renderer_switch(tmp_path, capsys):
    conf, run, _ = COMMANDS["synth"]
    parser = argparse.ArgumentParser()
    conf(parser)
    out = tmp_path / "ph"
    argv = ["--out", str(out), "--renderer", "phalanx", "--subjects", "1", "--reps", "1"]
    args = parser.parse_args([*argv, "--gestures", "drag", "--workers", "1", "--json"])
    assert run(args) == 0
    info = json.loads(capsys.readouterr().out)
    assert info["renderer"] == "phalanx" and info["samples"] == 1
    assert load_dataset(out)[0].meta["renderer"] == "phalanx"
    assert parser.parse_args(argv[:2]).renderer == "twin"
