"""The frame's light fit (``background.illumination``) stops refitting when a refit
would use the pixels of the fit before (issue 28's cost): the same gain, offset and
noise, bit for bit, as the three fits always made; the empty table (often nothing to
drop out) takes fewer fits."""

from __future__ import annotations

import numpy as np
import pytest

import plugins.gestures.background as background
from plugins.gestures.background import _median, _median_of_scratch, brightness_gain
from plugins.twin.camera.camera import IdleScript, TwinCamera
from plugins.twin.camera.render import Rig


def plain_illumination(frame, bg, step=12):
    """``illumination`` as first written: always three fits."""
    f = frame[::step, ::step].astype(np.float32).ravel()
    b = bg[::step, ::step].astype(np.float32).ravel()
    fk, bk = f, b
    gain, offset, mad = 1.0, 0.0, 0.0
    for it in range(3):
        n = len(fk)
        if n < 10:
            break
        mb, mf = float(np.add.reduce(bk) / n), float(np.add.reduce(fk) / n)
        db = bk - mb
        var = float(np.dot(db, db)) / n
        if var < 4.0:
            gain, offset = 1.0, _median_of_scratch(fk - bk)
        else:
            gain = float(np.dot(db, fk - mf)) / n / var
            offset = mf - gain * mb
        res = f - (gain * b + offset)
        med = _median(res)
        mad = _median_of_scratch(np.abs(res - med))
        if it < 2:
            keep = res <= med + 2.0 * mad + 1.0
            fk, bk = f[keep], b[keep]
    noise = 1.4826 * mad
    if not (0.2 < gain < 5.0):
        return brightness_gain(frame, bg, step), 0.0, noise
    return gain, offset, noise


@pytest.fixture(scope="module")
def filmed():
    """The twin (seeded, drifting light): frames of a resting hand, then of the empty
    table, with the empty table the background model starts from."""
    cam = TwinCamera(rig=Rig(drift_gain=0.1, drift_offset=8.0, drift_period_s=2.0), seed=5)
    cam.realtime = False
    bg = cam.background()
    cam.place("open_hand", (370.0, 220.0))
    hand = [cam.read().image for _ in range(20)]
    cam.set_script(IdleScript())
    empty = [cam.read().image for _ in range(20)]
    cam.close()
    return bg, hand, empty


def test_the_fit_is_the_three_fits_bit_for_bit_and_the_empty_table_takes_fewer(filmed, monkeypatch):
    bg, hand, empty = filmed
    bgs = (bg, np.clip(bg.astype(np.float32) * 1.2 + 9.0, 0, 255).astype(np.uint8))
    for b in bgs:
        for img in hand + empty:
            assert background.illumination(img, b) == plain_illumination(img, b)
    fits = []
    median = background._median
    monkeypatch.setattr(background, "_median", lambda a: fits.append(1) or median(a))
    for img in empty:
        background.illumination(img, bg)
    assert len(fits) < 3 * len(empty)  # three fits a frame before
