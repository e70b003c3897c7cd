"""Recording conditions of the camera twin: IR light level, LED layout, hand size and
hover height, and `gestures synth --vary` drawing them per subject and session."""

from __future__ import annotations

import json
from dataclasses import replace

import numpy as np
import pytest

from plugins.twin.camera.camera import TwinCamera
from plugins.twin.camera.gestures import plan_take, take_pose
from plugins.twin.camera.hand import make_subject, scaled_subject
from plugins.twin.camera.render import Rig, drift, hand_layer
from plugins.twin.camera.sample import frame_truth, render_frame


def test_illumination_scales_the_light_not_the_ambient_offset():
    rig = Rig()
    t = 12.0
    _, o = drift(rig, t)
    rng = np.random.default_rng(0)
    base = render_frame([], rig, t, rng, noise=False)[0].astype(float) - o
    brighter = render_frame([], replace(rig, illumination=1.3), t, rng, noise=False)[0] - o
    lit = base > 20
    ratio = np.median(brighter[lit] / base[lit])
    assert abs(ratio - 1.3) < 0.02
    # another LED layout moves the hot spots
    other = render_frame([], replace(rig, seed=99), t, rng, noise=False)[0].astype(float) - o
    assert np.mean(np.abs(other - base)) > 1.0


def test_hand_scale_and_hover_scale():
    subj = make_subject("s1")
    big = scaled_subject(subj, size=1.1, hover=1.5)
    assert big.length_mm == pytest.approx(1.1 * subj.length_mm)
    assert big.lift_mm == pytest.approx(1.5 * subj.lift_mm)
    assert scaled_subject(subj) is subj
    mapping = Rig().mapping
    take = plan_take("closed_hand", subj, np.random.default_rng(1), mapping.table_mm, side="right")
    pose = take_pose(take, 0.0)
    area = []
    for s in (subj, scaled_subject(subj, 1.1)):
        layer = hand_layer(frame_truth([(s, pose)], mapping, "", 0.0)[0], mapping)
        area.append(np.count_nonzero(layer > 20))
    assert 1.1 < area[1] / area[0] < 1.35  # ~1.21 = 1.1 ** 2 of the skin seen
    # through the camera: a larger hand on the same performance
    frames = [
        TwinCamera(hand_scale=k, realtime=False).render_sample(
            "open_hand", "s1", 0, np.random.default_rng(4), n_frames=1
        )[0][0]
        for k in (1.0, 1.1)
    ]
    assert np.count_nonzero(frames[1] > 120) > 1.1 * np.count_nonzero(frames[0] > 120)


def test_synth_vary_draws_conditions_per_subject_and_session(tmp_path):
    from plugins.gestures.synth import CONDITION_RANGES, synth

    kw = dict(subjects=2, reps=4, seed=5, workers=1, gestures=("one_finger", "drag"))
    info = synth(tmp_path / "a", vary=True, sessions=2, **kw)
    assert info["vary"] and info["sessions"] == 2
    metas = [json.loads(p.read_text()) for p in sorted((tmp_path / "a").glob("*/*/sample.json"))]
    assert len(metas) == 16
    conds = {m["session"]: m["condition"] for m in metas}
    assert sorted(conds) == ["s1/0", "s1/1", "s2/0", "s2/1"]
    for c in conds.values():
        lo, hi = CONDITION_RANGES["illumination"]
        assert lo <= c["illumination"] <= hi
        lo, hi = CONDITION_RANGES["noise_sigma"]
        assert lo <= c["noise_sigma"] <= hi
    assert len({c["illumination"] for c in conds.values()}) == 4
    assert len({c["led_seed"] for c in conds.values()}) == 4
    # the condition is rendered: a sample's own background is as bright as its light says
    bgs = {}
    from plugins.gestures.dataset import load_dataset

    for s in load_dataset(tmp_path / "a"):
        bgs.setdefault(s.meta["session"], []).append(float(np.mean(s.background())))
    lights = {k: conds[k]["illumination"] for k in conds}
    lo, hi = min(lights, key=lights.get), max(lights, key=lights.get)
    assert np.mean(bgs[hi]) > np.mean(bgs[lo]) * (1 + 0.5 * (lights[hi] / lights[lo] - 1))
    # same seed, same conditions; without --vary none are written
    b = synth(tmp_path / "b", vary=True, sessions=2, **kw)
    assert b["condition_ranges"] == info["condition_ranges"]
    again = json.loads(next((tmp_path / "b").glob("drag/s2_003/sample.json")).read_text())
    first = json.loads(next((tmp_path / "a").glob("drag/s2_003/sample.json")).read_text())
    assert again["condition"] == first["condition"]
    synth(tmp_path / "c", **{**kw, "reps": 1})
    plain = json.loads(next((tmp_path / "c").glob("drag/*/sample.json")).read_text())
    assert "condition" not in plain
