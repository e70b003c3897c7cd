"""Issue 27, the last new-user try, Camera (F2) at 80 x 24: a finished calibration's
``S`` is in the footer and the saved path breaks only after a ``/``; the exposure
assistant's status line and the live block give touching skin's level from the same
measurement; ``b`` with a hand held on the glass says a hand is in view and keeps the
background as it was until ``b`` is pressed again."""

from __future__ import annotations

import asyncio
import re

import numpy as np

from console.cli.main import Context
from console.files import paths
from console.session.background_check import bright_blobs
from console.tui import camera_wizard
from console.tui.app import HapTableApp
from console.tui.wrap_paths import break_paths

from .conftest import wait_for, words_on
from .test_camera_layout import _first_frame, screen_lines, text_in
from .test_camera_stale import _Fit


def _status(app) -> str:
    return text_in(app, app.query_one("#camera-status"))


def _skin(text: str) -> float | None:
    found = re.search(r"touching skin at (\d+) of 255", text)
    return None if found is None else float(found.group(1))


def test_break_paths_cuts_a_path_only_after_a_slash():
    text = "saved to ~/.local/state/haptable/sim/touch_calibration.json, kept"
    shown = break_paths(text, 20)
    assert shown.replace("\n", "") == text  # nothing lost, nothing added
    assert shown.count("\n") == 2 and all(p.endswith("/") for p in shown.split("\n")[:-1])
    assert all(len(p.split(" ")[-1]) <= 20 for p in shown.split("\n")), shown
    assert break_paths("a short/path stays whole", 20) == "a short/path stays whole"


def test_bright_blobs_find_a_hand_not_the_empty_table():
    """A dim vignetted table with noise has none; a hand-sized bright disc on it is found
    where it was drawn, with its drawn area (the reference)."""
    rng = np.random.default_rng(1)
    yy, xx = np.mgrid[0:480, 0:640]
    table = 40 - 25 * ((xx - 320) ** 2 + (yy - 240) ** 2) / (400**2) + rng.normal(0, 3, (480, 640))
    assert bright_blobs(table) == []
    disc = (xx - 400) ** 2 + (yy - 200) ** 2 < 60**2
    blobs = bright_blobs(np.where(disc, 210.0, table))
    assert len(blobs) == 1 and abs(blobs[0].area_px - disc.sum()) < 0.02 * disc.sum(), blobs
    assert np.allclose(blobs[0].center_px, (400, 200), atol=1.0), blobs


def test_camera_save_key_path_exposure_and_background(plugins, monkeypatch):
    monkeypatch.setenv("HOME", str(paths.profile_state_dir("sim", "x").parent.parent))
    monkeypatch.setattr(camera_wizard, "BACKGROUND_AGAIN_S", 60.0)  # a loaded machine

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="camera")
        async with app.run_test(size=(80, 24)) as pilot:
            await _first_frame(app, pilot)
            wizard = app.session.calibration
            wizard.result, wizard.report_text = _Fit(), "12 targets"  # a finished fit
            wizard.message = "12 targets: outliers none. S: save"
            await wait_for(pilot, lambda: "S save" in screen_lines(app)[-1], 10, "S in footer")
            await pilot.press("S")
            block = app.query_one("#camera-wizard")
            await wait_for(pilot, lambda: "saved to" in text_in(app, block), 30, "saved")
            # the reply to S keeps its rows first: its path whole on the screen (a row
            # laid out after the text changed: waited for, bounded)
            await wait_for(
                pilot,
                lambda: any("touch_calibration.json" in r for r in screen_lines(app)),
                10,
                "the saved path whole on screen",
            )
            await wait_for(pilot, lambda: "S save" not in screen_lines(app)[-1], 10, "S gone")
            # the twin holds a flat hand still: the live block and e agree on its level
            svc = app.session.camera_started
            await pilot.press("P")
            panel = "#camera-measures"  # pinned under the live numbers (finding 2)
            await wait_for(pilot, lambda: _skin(words_on(app, panel)), 30, "skin on panel")
            await pilot.press("e")
            await wait_for(pilot, lambda: "of 255" in _status(app), 60, "e measured")
            said = _skin(_status(app))
            await pilot.pause(0.6)  # the live block's next numbers
            shown = _skin(words_on(app, panel))
            assert said is not None and shown is not None and abs(said - shown) <= 3, (
                _status(app),
                words_on(app, panel),
            )
            # b with the hand held still: named, and the background stays as it was
            # (once the recent frames b takes the median of all hold the hand: a loaded
            # machine may still hold frames from before P)
            held = lambda: bright_blobs(svc.median_background()) != []  # noqa: E731
            await wait_for(pilot, held, 30, "the held hand in the recent frames")
            await pilot.press("b")
            await wait_for(pilot, lambda: "b again" in _status(app), 30, "b warns")
            assert "a hand is in view" in _status(app), _status(app)
            assert bright_blobs(svc.classifier.background.image) == []  # as it was
            await pilot.press("b")  # again: kept as asked
            await wait_for(pilot, lambda: "background captured" in _status(app), 30, "kept")
            assert bright_blobs(svc.classifier.background.image) != []  # as asked
            await pilot.press("P")

    asyncio.run(scenario())
