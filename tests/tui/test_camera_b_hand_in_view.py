"""Camera (F2), a new user's first minute on the twin (profile ``sim``, 80 x 24): ``b``
took the background at once with the twin's scripted hand moving in view (``hands 1
contacts 5``): only a hand held still stays in the frames' median. A hand the vision
counted in any of the recent frames, or a bright blob in their median or in the
brightest of each pixel over them, now makes ``b`` ask first, as with ``P``'s flat hand."""

from __future__ import annotations

import asyncio

import numpy as np
import pytest

from console.cli.main import Context
from console.session.background_check import in_view
from console.tui import camera_wizard
from console.tui.app import HapTableApp

from .conftest import wait_for
from .test_camera_layout import _first_frame, text_in

SIZES = pytest.mark.parametrize("size", [(80, 24), (120, 40)], ids=["80x24", "120x40"])


def _app(plugins) -> HapTableApp:
    return HapTableApp(Context("sim", plugins), fast=True, initial="camera")


def _status(app) -> str:
    return text_in(app, app.query_one("#camera-status"))


def test_a_hand_in_any_recent_frame_is_in_view():
    """The vision's count in any one frame, or a bright blob in the brightest of each
    pixel over the frames (a hand passing through: not in their median)."""
    yy, xx = np.mgrid[0:120, 0:160]
    table = np.full((120, 160), 30.0)
    frames = [table.copy() for _ in range(15)]
    assert not in_view(frames, [(0, 0)] * 15).any()
    seen = [(0, 0)] * 14 + [(1, 5)]
    found = in_view(frames, seen)
    assert found.any() and found.frames == 1 and (found.hands, found.contacts) == (1, 5)
    for i, f in enumerate(frames):  # a disc moving across: in every frame, one place each
        f[(xx - 20 - 8 * i) ** 2 + (yy - 60) ** 2 < 15**2] = 220.0
    assert in_view(frames, [None] * 15).blobs  # none counted by the vision, still seen


@SIZES
def test_b_asks_first_while_the_twins_moving_hand_is_in_view(plugins, size, monkeypatch):
    monkeypatch.setattr(camera_wizard, "BACKGROUND_AGAIN_S", 60.0)  # a loaded machine

    async def scenario():
        app = _app(plugins)
        async with app.run_test(size=size) as pilot:
            await _first_frame(app, pilot)
            svc = app.session.camera_started
            info = app.query_one("#camera-info")
            await wait_for(pilot, lambda: "hands 1" in text_in(app, info), 30, "the hand")
            before = np.array(svc.classifier.background.image, copy=True)
            await pilot.press("b")
            answered = lambda: "anyway" in _status(app) or "captured" in _status(app)  # noqa: E731
            await wait_for(pilot, answered, 30, "b answers")
            said = _status(app)
            assert "a hand is in view" in said and "b again within 60 s" in said, said
            assert "takes it anyway" in said, said
            # as it was (it adapts slowly, ``background_alpha``: no step to a new one)
            assert np.abs(before - svc.classifier.background.image).max() < 10
            await pilot.press("b")
            await wait_for(pilot, lambda: "background captured" in _status(app), 30, "taken")
            assert "as asked" in _status(app)

    asyncio.run(scenario())


def test_the_twins_empty_table_is_no_hand(plugins, profile):
    """The hard case the maximum adds: 15 noisy frames of the twin's empty table (its
    vignetting, sensor noise) hold no blob in their per-pixel maximum."""
    cam = plugins.build("camera", "twin", profile)
    try:
        rng = np.random.default_rng(0)
        frames = [cam.render_background(0.1 * i, rng) for i in range(15)]
    finally:
        cam.close()
    assert not in_view(frames, [(0, 0)] * 15).any()
