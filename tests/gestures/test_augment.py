"""Domain randomisation (``synth(vary="wide")``, ``augment``): the drawn conditions stay in
their declared ranges and are seeded, the same seed renders the same frames, and bright
light clips touching skin at 255 while dim light does not."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from plugins.gestures.augment import (
    WIDE_RANGES,
    augment_sample,
    in_ranges,
    light_field,
    twin_profile,
    wide_condition,
)
from plugins.gestures.synth import _twin_camera, synth


def test_wide_conditions_stay_in_ranges_and_are_seeded():
    conds = [wide_condition(3, s, g, r) for s in range(3) for g in range(10) for r in range(5)]
    assert all(in_ranges(c) == [] for c in conds)
    assert {c["augment"]["finger_px"] for c in conds} == {-1, 0, 1}
    assert any(c["exposure_ms"] == 0.0 for c in conds) and any(c["exposure_ms"] > 0 for c in conds)
    lights = [c["illumination"] for c in conds]
    lo, hi = WIDE_RANGES["illumination"]
    assert min(lights) < lo + 0.2 and max(lights) > hi - 0.2  # the range is used
    assert wide_condition(3, 1, 2, 3) == wide_condition(3, 1, 2, 3)
    assert wide_condition(3, 1, 2, 3) != wide_condition(4, 1, 2, 3)
    assert in_ranges({**conds[0], "gamma": 2.0}) == [] and in_ranges(
        {**conds[0], "illumination": 2.0}
    ) == ["illumination"]


def _pngs(root: Path) -> dict[str, bytes]:
    return {str(p.relative_to(root)): p.read_bytes() for p in sorted(root.rglob("*.png"))}


def test_same_seed_same_frames(tmp_path):
    kw = dict(subjects=1, reps=1, gestures=("l_shape",), static_frames=2, workers=1, vary="wide")
    a = synth(tmp_path / "a", seed=5, **kw)
    synth(tmp_path / "b", seed=5, **kw)
    synth(tmp_path / "c", seed=6, **kw)
    assert a["samples"] == 1 and a["condition_ranges"] == WIDE_RANGES
    pa, pb, pc = (_pngs(tmp_path / k) for k in "abc")
    assert len(pa) == 4  # dataset background, sample background, 2 frames
    assert pa == pb
    assert [pa[k] for k in pa if "l_shape" in k] != [pc[k] for k in pc if "l_shape" in k]


def _render(light: float) -> np.ndarray:
    """Frames of a flat hand at ``light`` under a wide condition's other settings."""
    cond = wide_condition(0, 0, 3, 0)
    cond.update(illumination=light, exposure_ms=0.0)
    factory, prof = _twin_camera(0, False, 0.0)
    camera = factory({**prof, **twin_profile(cond)})
    rng = np.random.default_rng(0)
    frames, _ = camera.render_sample("closed_hand", "s1", 0, rng, n_frames=2, t0_s=1.0)
    bg = camera.render_background(0.5, rng)
    aug = {**cond["augment"], "gamma": 1.0, "lobe_gain": 0.0, "blur_px": 0.0}
    return augment_sample(frames, bg, aug, rng)[0]


def test_bright_light_clips_at_255_and_dim_light_does_not():
    bright, dim = _render(1.6), _render(0.5)
    assert bright.dtype == np.uint8
    assert (bright == 255).sum() > 200  # touching skin saturates
    assert (dim == 255).sum() == 0


def test_augment_keeps_glass_and_clips_the_bright_end():
    rng = np.random.default_rng(1)
    bg = np.full((48, 64), 40, np.uint8)
    frame = bg.copy()
    frame[5:43, 5:59] = 250
    aug = {
        "glow_scale": 1.0,
        "finger_px": 1,
        "lobe_gain": 0.3,
        "field_seed": 1,
        "blur_px": 0.0,
        "gamma": 1.0,
        "post_noise": 0.0,
    }
    out, out_bg = augment_sample(frame[None], bg, aug, rng)
    field = light_field(bg.shape, 0.3, 1)
    over = (frame >= 250) & (field * 250 > 256)
    assert over.sum() > 50 and (out[0][over] == 255).all()  # the bright end clips
    assert (out[0, 4:44, 4:60] > 100).all()  # grown by a pixel
    glass = np.ones_like(bg, bool)
    glass[2:46, 2:62] = False
    assert np.abs(out[0][glass].astype(int) - out_bg[glass]).max() <= 1
