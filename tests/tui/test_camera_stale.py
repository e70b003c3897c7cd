"""The Camera screen (F2) at 80 x 24, third new-user try (issue 27): the status line
does not outlive the state it spoke of (a save, TUIO switched, before a calibration that
was then cancelled with x or Esc); a refused TUIO target comes back as typed and the
footer promises no key while the field takes them; a demo holding the camera refuses
every key that would change the camera or its settings and the live numbers say whose
they are."""

from __future__ import annotations

import asyncio

from textual.widgets import Input

from console.cli.main import Context
from console.files import paths
from console.tui.app import HapTableApp

from .conftest import wait_for, words_on
from .test_camera_layout import _first_frame, screen_lines, text_in

SIZE = (80, 24)


def _app(plugins) -> HapTableApp:
    return HapTableApp(Context("sim", plugins), fast=True, initial="camera")


def _status(app) -> str:
    return text_in(app, app.query_one("#camera-status"))


def _wizard(app) -> str:
    return " ".join(str(app.query_one("#camera-wizard").render()).split())


class _Fit:
    """A finished touch calibration (the twin's takes half a minute to touch)."""

    def save(self, path) -> None:
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text("{}")


async def _calibrating(app, pilot) -> None:
    await pilot.press("k")
    await wait_for(pilot, lambda: app.session.calibration.active is not None, 30, "running")


def test_a_save_or_tuio_said_before_a_cancelled_calibration_goes(plugins, monkeypatch):
    # the state folder under the home folder, as on an operator's machine: shown with ~
    monkeypatch.setenv("HOME", str(paths.profile_state_dir("sim", "x").parent.parent))

    async def scenario():
        app = _app(plugins)
        async with app.run_test(size=SIZE) as pilot:
            await _first_frame(app, pilot)
            wizard = app.session.calibration
            wizard.result, wizard.report_text = _Fit(), "12 targets"  # a finished fit
            await pilot.press("S")
            # the wizard's block says where, with ~ (no status line repeating it)
            await wait_for(pilot, lambda: "saved to" in _wizard(app), 30, "wizard saved")
            shown = _wizard(app).split("saved to ", 1)[1]
            assert shown.startswith("~/"), shown
            assert "saved" not in words_on(app, "#camera-status")
            await _calibrating(app, pilot)
            await pilot.press("x")
            await wait_for(pilot, lambda: "cancelled" in _wizard(app), 30, "cancelled")
            await pilot.pause(0.5)
            assert "saved" not in _status(app), _status(app)
            await pilot.press("u")
            await wait_for(pilot, lambda: "tuio on" in _status(app), 30, "tuio on")
            await _calibrating(app, pilot)
            await pilot.press("escape")  # Esc leaves the wizard as x does
            await wait_for(pilot, lambda: wizard.active is None, 30, "cancelled by Esc")
            await wait_for(pilot, lambda: "tuio" not in _status(app), 30, "tuio line gone")
            await pilot.press("u")  # the profile's TUIO back off

    asyncio.run(scenario())


def test_a_refused_tuio_target_comes_back_as_typed_and_the_footer_promises_no_key(plugins):
    async def scenario():
        app = _app(plugins)
        async with app.run_test(size=SIZE) as pilot:
            await _first_frame(app, pilot)
            # the footer draws after the first frame on a loaded machine
            await wait_for(pilot, lambda: "- +" in screen_lines(app)[-1], 30, "footer keys")
            await pilot.press("U")
            await wait_for(pilot, lambda: isinstance(app.focused, Input), 30, "the field")
            await wait_for(pilot, lambda: "- +" not in screen_lines(app)[-1], 30, "footer")
            footer = screen_lines(app)[-1]
            assert "[ ]" not in footer and "calibrate" not in footer, footer
            app.focused.value = "nowhere"
            await pilot.press("enter")
            await wait_for(pilot, lambda: "correct it, Enter" in _status(app), 30, "refused")
            # the field stays open as typed (``checked_field``); the footer still
            # promises none of the screen's keys
            assert isinstance(app.focused, Input) and app.focused.value == "nowhere"
            assert "- +" not in screen_lines(app)[-1], screen_lines(app)[-1]

    asyncio.run(scenario())


def test_a_demo_holding_the_camera_refuses_every_key_that_changes_it(plugins):
    async def scenario():
        app = _app(plugins)
        async with app.run_test(size=SIZE) as pilot:
            await _first_frame(app, pilot)
            svc = app.session.camera_started
            before = dict(svc.params())
            await asyncio.to_thread(svc.release, "demo knob")  # as a demo takes it
            info = app.query_one("#camera-info")
            await wait_for(pilot, lambda: "demo knob" in text_in(app, info), 30, "numbers")
            assert "fps" not in text_in(app, info), text_in(app, info)
            for key in ("n", "S", "x", "T", "plus", "W", "u", "U", "e"):
                await pilot.press(key)
                await wait_for(pilot, lambda: "demo knob" in _status(app), 30, key)
                assert "refused" in _status(app) and "F6" in _status(app), (key, _status(app))
                app.pane("camera").say("")
            # every vision setting as it was (the camera's own exposure and gain are not
            # listed while the demo holds the camera)
            after = svc.params()
            assert {k: after[k] for k in before if k in after} == {
                k: v for k, v in before.items() if k in after
            }
            assert not isinstance(app.focused, Input)
            await asyncio.to_thread(svc.give_back)

    asyncio.run(scenario())
