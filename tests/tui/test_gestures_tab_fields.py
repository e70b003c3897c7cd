"""The Gestures panel (Camera F2, ``g``) at 80 x 24: `Tab` edits the fields, `Enter`
returns to the buttons (README, the panel's help). New operator's try: the first Tab went
through the panel's three buttons, the first field was the third or fourth Tab. Now the
buttons are one stop of the Tab order (Left/Right move between them): the first Tab from
them lands on the dataset field, the next ones on each field in turn, then back."""

from __future__ import annotations

import asyncio

from textual.widgets import Input

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import wait_for
from .test_camera_layout import screen_lines
from .test_gestures_work_kept import _panel_from_camera

SIZE = (80, 24)
FIELDS = ["gp-dataset", "gp-subjects", "gp-reps", "gp-cv", "gp-model"]


def _focused(app) -> str | None:
    return getattr(app.focused, "id", None)


def test_the_first_tab_from_the_buttons_edits_the_first_field(plugins):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="camera")
        async with app.run_test(size=SIZE) as pilot:
            panel = await _panel_from_camera(app, pilot)
            assert _focused(app) == "gp-synth"
            dataset = panel.query_one("#gp-dataset", Input)
            before = dataset.value
            await pilot.press("tab")
            assert _focused(app) == "gp-dataset"
            await pilot.press("Q")  # what the operator types goes into the field
            assert dataset.value != before and "Q" in dataset.value, dataset.value
            for name in FIELDS[1:]:  # each field in turn, then back to the buttons
                await pilot.press("tab")
                assert _focused(app) == name
            await pilot.press("tab")
            assert _focused(app) == "gp-synth"
            # Enter in a field returns to the buttons; the next Tab edits again
            await pilot.press("tab", "tab")
            assert _focused(app) == "gp-subjects"
            await pilot.press("enter")
            assert _focused(app) == "gp-synth"
            await pilot.press("tab")
            assert _focused(app) == "gp-dataset"
            # Left/Right move between the buttons; Tab from any edits the first field,
            # shift+Tab from it goes back to that button
            await pilot.press("shift+tab")
            assert _focused(app) == "gp-synth"
            await pilot.press("right")
            assert _focused(app) == "gp-train"
            await pilot.press("right")
            assert _focused(app) == "gp-cancel"
            await pilot.press("tab")
            assert _focused(app) == "gp-dataset"
            await pilot.press("shift+tab")
            assert _focused(app) == "gp-cancel"
            await pilot.press("left", "left")
            assert _focused(app) == "gp-synth"
            # the help (?) says the same, on the screen
            await pilot.press("question_mark")

            def shown() -> str:
                return " ".join(ln.strip(" █▀▄") for ln in screen_lines(app))

            await wait_for(pilot, lambda: "This screen: Gestures" in shown(), 10, "help")
            words = " ".join(shown().split())
            assert "tab: edit the fields (enter returns here)" in words, words
            assert "left/right: between the buttons" in words, words

    asyncio.run(scenario())
