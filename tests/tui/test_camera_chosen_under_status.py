"""The Camera screen (F2) keeps the chosen vision setting's row (``▸``) in view at 80 x 24
and 120 x 40 whatever the status lines above it hold: after a calibration's result with
its saved path and a refused TUIO switch, every ``]`` / ``[`` shows the chosen row, and
every ``-`` / ``+`` shows it with its new value (the README and ``?`` promise so: ``+``
never changes a value the operator cannot see)."""

from __future__ import annotations

import asyncio

import pytest

from console.cli.main import Context
from console.core.errors import UserError
from console.tui.app import HapTableApp

from .conftest import wait_for, words_on
from .test_camera_field_in_view import SAVED
from .test_camera_layout import SIZES, _first_frame, screen_lines


def _row(app, key: str) -> str | None:
    """The screen's row showing ``▸ key``, None when it is not on the screen."""
    return next((ln for ln in screen_lines(app) if f"▸ {key} " in ln), None)


async def _refused_target(app, pilot) -> None:
    """``u`` refused with a long TUIO error on the status line, the keys still the
    screen's (a refused ``U`` target keeps its field open instead: ``checked_field``)."""
    svc = app.session.camera_started

    def refuse(name, on, target=None):
        raise UserError(
            "tuio target '256.1.1.1:99999': 256 is not 0-255 in an IPv4 address; "
            "port 99999 is not 1-65535"
        )

    svc.set_sink = refuse
    await pilot.press("u")
    said = lambda: words_on(app, "#camera-status")  # noqa: E731
    await wait_for(pilot, lambda: "port 99999" in said(), 10, "the refusal")
    await wait_for(pilot, lambda: app.focused is app.pane("camera"), 10, "the keys back")


@pytest.mark.parametrize("size", SIZES, ids=["80x24", "120x40"])
def test_the_chosen_row_shows_under_a_result_and_a_tuio_error(plugins, size):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="camera")
        async with app.run_test(size=size) as pilot:
            await _first_frame(app, pilot)
            pane = app.pane("camera")
            svc = app.session.camera_started
            wiz = app.session.calibration
            wiz.result, wiz.message, wiz.failed = object(), SAVED, False
            await wait_for(
                pilot, lambda: "saved to" in words_on(app, "#camera-wizard"), 10, "result"
            )
            await _refused_target(app, pilot)
            said = lambda: words_on(app, "#camera-status")  # noqa: E731
            controls = svc.control_values()
            keys = list(svc.params())
            for i in range(len(keys) + 1):
                await pilot.press("right_square_bracket")
                key = pane.chosen_key()
                await wait_for(
                    pilot, lambda k=key: _row(app, k) is not None, 5, f"▸ {key} after {i + 1} x ]"
                )
                if key in controls:
                    continue
                before = svc.params()[key]
                await pilot.press("plus")
                after = svc.params()[key]
                if after == before:  # at its top already
                    continue
                await wait_for(
                    pilot,
                    lambda k=key, v=after: f"▸ {k} {v:g}" in (_row(app, k) or ""),
                    5,
                    f"▸ {key} {after:g} after +",
                )
            # the status lines still say what they said
            assert "port 99999" in said()

    asyncio.run(scenario())


#: a finished calibration's numbers, as the twin's run reports them
REPORT = (
    "12 targets: reprojection error 0.61 mm rms, 1.32 mm max (leave-one-out 2.72 mm); "
    "outliers none."
)


@pytest.mark.parametrize("size", SIZES, ids=["80x24", "120x40"])
def test_a_saved_calibration_result_shows_whole(plugins, size, monkeypatch):
    """k's result, saved with S: the wizard's block (the numbers and where they were
    saved) shows whole under the live numbers, no status line repeating it; the chosen
    setting's row still shows."""
    from console.files import paths

    from .test_camera_layout import text_in
    from .test_camera_stale import _Fit

    # the state folder under the home folder, as on an operator's machine: shown with ~
    monkeypatch.setenv("HOME", str(paths.profile_state_dir("sim", "x").parent.parent))

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="camera")
        async with app.run_test(size=size) as pilot:
            await _first_frame(app, pilot)
            pane = app.pane("camera")
            wiz = app.session.calibration
            wiz.result, wiz.report_text = _Fit(), REPORT
            wiz.message = f"{REPORT} S: save"
            await pilot.press("S")
            block = app.query_one("#camera-wizard")
            whole = lambda: " ".join(str(block.render()).split())  # noqa: E731
            await wait_for(pilot, lambda: "saved to" in whole(), 10, "saved")
            await wait_for(pilot, lambda: "touch_calibration.json" in whole(), 10, "its path")
            await pilot.pause(0.6)  # the live numbers' next write
            await wait_for(pilot, lambda: text_in(app, block) == whole(), 5, "the block whole")
            assert whole().endswith("touch_calibration.json"), whole()
            assert "leave-one-out 2.72 mm" in text_in(app, block)
            assert "saved to" not in words_on(app, "#camera-status")  # said once, above
            key = pane.chosen_key()
            assert _row(app, key) is not None, key

    asyncio.run(scenario())
