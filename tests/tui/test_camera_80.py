"""The Camera screen (F2) at 80 x 24 as a new user meets it (issue 27): a demo holding the
camera leaves the side panel readable and the keys that need the camera refuse on the
status line, naming who holds it (and the line goes when the camera is back); the
screen's own outcomes (``b``, a bad ``U`` target) are said on its status line, not in
toasts; every key the screen needs shows, in the footer or on the keys line."""

from __future__ import annotations

import asyncio

import numpy as np
from textual.widgets import Input

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import wait_for
from .test_camera_layout import _first_frame, screen_lines, text_in

SIZE = (80, 24)


def _app(plugins) -> HapTableApp:
    return HapTableApp(Context("sim", plugins), fast=True, initial="camera")


def _status(app) -> str:
    return text_in(app, app.query_one("#camera-status"))


def _toasts(app) -> list[str]:
    return [str(n.message) for n in app._notifications]


def test_a_demo_holding_the_camera_leaves_the_panel_readable_and_b_k_refuse(plugins):
    async def scenario():
        app = _app(plugins)
        async with app.run_test(size=SIZE) as pilot:
            await _first_frame(app, pilot)
            svc = app.session.camera_started
            await asyncio.to_thread(svc.release, "demo knob")  # as a demo takes it
            background = np.array(svc.classifier.background.image, copy=True)
            view = app.query_one("#camera-view")
            await wait_for(pilot, lambda: "demo knob" in text_in(app, view), 30, "borrowed")
            await pilot.pause(0.3)
            side = app.query_one("#camera-side")
            assert side.region.width >= 30, side.region
            assert "body_threshold" in text_in(app, app.query_one("#camera-settings"))
            await pilot.press("b")
            await wait_for(pilot, lambda: "demo knob" in _status(app), 30, "b refused")
            said = _status(app)
            assert "b refused" in said and "F6" in said, said
            assert np.array_equal(background, svc.classifier.background.image)
            await pilot.press("k")
            await wait_for(pilot, lambda: "k refused" in _status(app), 30, "k refused")
            assert app.session.calibration.active is None
            assert not any("demo knob" in t for t in _toasts(app)), _toasts(app)
            # the demo gives the camera back: the refusal is no longer true, it goes
            await asyncio.to_thread(svc.give_back)
            app.pane("camera").set_visible(True)
            await wait_for(pilot, lambda: "demo knob" not in _status(app), 30, "line gone")

    asyncio.run(scenario())


def test_b_and_a_bad_tuio_target_are_said_on_the_status_line(plugins):
    async def scenario():
        app = _app(plugins)
        async with app.run_test(size=SIZE) as pilot:
            await _first_frame(app, pilot)
            await pilot.press("b")  # the twin's hand in view: b asks first
            await wait_for(pilot, lambda: "background" in _status(app), 30, "b")
            await pilot.press("U")
            await wait_for(pilot, lambda: isinstance(app.focused, Input), 30, "the field")
            app.focused.value = "nowhere"
            await pilot.press("enter")
            await wait_for(pilot, lambda: "host:port" in _status(app), 30, "bad target")
            assert "correct it, Enter" in _status(app), _status(app)  # its field open
            assert not any("background" in t or "host:port" in t for t in _toasts(app)), _toasts(
                app
            )

    asyncio.run(scenario())


def test_every_key_the_camera_screen_needs_shows_at_80_columns(plugins):
    async def scenario():
        app = _app(plugins)
        async with app.run_test(size=SIZE) as pilot:
            await _first_frame(app, pilot)
            await pilot.pause(0.5)  # the footer laid out at this width
            footer, shown = screen_lines(app)[-1], "\n".join(screen_lines(app))
            for key in ("- + change", "[ ] setting", "v view", "k calibrate"):
                assert key in footer, (key, footer)
            for key in ("g gestures", "u U TUIO", "b background", "W keep"):
                assert key in shown, (key, shown)

    asyncio.run(scenario())
