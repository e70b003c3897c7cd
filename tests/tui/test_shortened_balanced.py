"""A line shortened for its width is cut after a whole word and never inside a bracket
whose end it drops: Scenes' last-run line once read ``knob loop stopped 4 s  …  limit
250 ms) - ctrl+r resets`` (a field dropped from inside the bracket). The one mechanism
(``console.tui.shorten``) serves the Scenes status, the toasts, the safety bar, table
cells and the Studies trials' column; checked at every width from 20 to 120 columns and on the screen at 80 x 24 and
120 x 40."""

from __future__ import annotations

import asyncio

import pytest
from textual.content import Content

from console.cli.main import Context
from console.tui.app import HapTableApp
from console.tui.safety_bar import _fit
from console.tui.shorten import balanced
from console.tui.table_fit import clip
from console.tui.toasts import fit_words
from plugins.demos.panel import fit_fields
from plugins.demos.status import status_lines
from plugins.studies.panel_text import clip as study_clip

from .conftest import wait_for
from .test_camera_layout import SIZES, screen_lines

#: a knob run the e-stop stopped, as its last report says it
SNAP = {
    "demo": "knob",
    "running": False,
    "uptime_s": 21.0,
    "estop": "the camera loop stalled (no frame for 310 ms, limit 250 ms) - ctrl+r resets",
    "camera": {"rate_fps": 60.0},
    "latency": {"fps": 59.0, "dropped_camera": 0, "dropped_queue": 0},
}
LINE = "\n".join(status_lines(SNAP)).split("\n")[0]
PLAIN = (
    "knob loop stopped 21 s  e-stop: the camera loop stalled (no frame for 310 ms, limit 250 ms)"
)


@pytest.mark.parametrize("width", range(20, 121))
def test_every_shortening_keeps_its_brackets_whole(width):
    for line in fit_fields(LINE, width).plain.split("\n"):
        assert balanced(line) and len(line) <= width, (width, line)
    toast = fit_words(Content(PLAIN), width).plain
    assert balanced(toast) and len(toast) <= width, (width, toast)
    cell = clip(PLAIN, width)
    assert balanced(cell) and len(cell) <= width, (width, cell)
    bar = _fit([PLAIN], width)
    assert balanced(bar) and len(bar) <= width, (width, bar)
    trial = study_clip("exp2 training left to right (right hand)", width // 3)
    assert balanced(trial) and len(trial) <= max(width // 3, 1), (width, trial)


@pytest.mark.parametrize("size", SIZES, ids=["80x24", "120x40"])
def test_the_last_run_line_on_scenes_is_balanced(plugins, size):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="scenes")
        async with app.run_test(size=size) as pilot:
            await wait_for(pilot, lambda: app.pane("scenes") is not None, 30, "scenes")
            pane = app.pane("scenes")
            pane._show_last_run("last run (e-stopped):\n" + "\n".join(status_lines(SNAP)))
            await pilot.pause(0.2)
            shown = screen_lines(app)
            at = next(i for i, x in enumerate(shown) if x.startswith("last run"))
            first = shown[at + 1].rstrip()
            assert first.startswith("knob loop stopped 21 s"), "\n".join(shown)
            assert balanced(first), first

    asyncio.run(scenario())
