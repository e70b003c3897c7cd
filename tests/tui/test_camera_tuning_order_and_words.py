"""Camera (F2), a new user on the twin (80 x 24): ``+`` x80 took body_threshold 14 -> 174
past contact_threshold 30 and up to contact_level 180, then ``hands 0`` for good with
no hint why. The thresholds now keep their order (a step past it is refused, saying why
and that ``R`` puts every setting back as the profile has it), and with no hand seen the
live numbers name the settings changed from the profile's. ``W`` said ``(the saved ones
replaced)`` with none saved; a calibration's ``S: save`` broke over two lines (a key and
its word now stay together wherever text wraps, ``console.tui.glue``)."""

from __future__ import annotations

import asyncio

import pytest

from console.cli.main import Context
from console.tui.app import HapTableApp
from console.tui.glue import stays_together, wrap

from .conftest import wait_for
from .test_camera_layout import _first_frame, screen_lines, text_in
from .test_camera_stale import _Fit

SIZES = pytest.mark.parametrize("size", [(80, 24), (120, 40)], ids=["80x24", "120x40"])


def _app(plugins) -> HapTableApp:
    return HapTableApp(Context("sim", plugins), fast=True, initial="camera")


def _status(app) -> str:
    return text_in(app, app.query_one("#camera-status"))


@SIZES
def test_plus_keeps_the_thresholds_order_and_r_puts_them_back(plugins, size):
    async def scenario():
        app = _app(plugins)
        async with app.run_test(size=size) as pilot:
            await _first_frame(app, pilot)
            svc = app.session.camera_started
            start = dict(svc.params())
            assert app.pane("camera").chosen_key() == "body_threshold"
            for _ in range(12):
                await pilot.press("plus")
            p = svc.params()
            assert p["body_threshold"] < p["contact_threshold"] < p["contact_level"], p
            said = _status(app)
            assert "body_threshold stays" in said and "contact_threshold 30" in said, said
            assert "R: the profile's settings" in said, said
            # a setting that hides the hand (as an overrides file may hold): the panel
            # says which, and how to get back
            svc.classifier.set_tunable("min_hand_area_px", 300000)
            info = app.query_one("#camera-info")
            await wait_for(pilot, lambda: "min_hand_area_px" in text_in(app, info), 30, "hint")
            hint = text_in(app, info)
            assert "hands 0" in hint and "may hide a hand" in hint and "R:" in hint, hint
            # the refusal keeps its rows whole while the live block grows by the hint
            assert "R: the profile's settings" in _status(app), _status(app)
            await pilot.press("R")
            assert svc.params() == start
            await wait_for(pilot, lambda: "hands 1" in text_in(app, info), 30, "the hand again")
            assert "min_hand_area_px" not in text_in(app, info)

    asyncio.run(scenario())


def test_a_key_stays_with_its_word():
    assert stays_together("S:", "save") and stays_together("b:", "capture")
    assert not stays_together("targets:", "rms")
    text = "12 targets: rms 1.2 mm, max 2.0 mm, outliers none. S: save"
    for width in range(20, 40):
        rows = wrap(text, width)
        assert not any(r.endswith("S:") for r in rows), (width, rows)


@SIZES
def test_w_says_replaced_only_when_saved_and_s_save_stays_whole(plugins, size):
    async def scenario():
        app = _app(plugins)
        async with app.run_test(size=size) as pilot:
            await _first_frame(app, pilot)
            await pilot.press("W")
            await wait_for(pilot, lambda: "W again" in _status(app), 30, "W asks")
            assert "replaced" not in _status(app), _status(app)  # none saved yet
            await pilot.press("W")
            await wait_for(pilot, lambda: "kept in" in _status(app), 30, "kept")
            await pilot.press("W")
            await wait_for(pilot, lambda: "W again" in _status(app), 30, "W asks again")
            assert "the saved ones replaced" in _status(app), _status(app)
            # a finished calibration: its key and word on one row, whatever the width
            block = app.query_one("#camera-wizard")
            wizard = app.session.calibration
            wizard.result, wizard.report_text = _Fit(), "12 targets"
            width = app.pane("camera").side_width("camera-wizard")
            wizard.message = "x" * (width - 3) + " S: save"  # S: ends a row unless kept
            await wait_for(pilot, lambda: "save" in text_in(app, block), 30, "the result")
            rows = [r.rstrip() for r in screen_lines(app)]
            assert not any(r.endswith("S:") for r in rows), rows
            assert any("S: save" in r for r in rows), rows

    asyncio.run(scenario())
