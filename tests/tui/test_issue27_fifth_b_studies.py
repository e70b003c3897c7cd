"""Issue 27 (fifth, b): the Studies screen at 80 x 24 as a new operator met it: the
trials table follows the newest trial unless the operator moved the cursor, ``r`` while
paused says why nothing happens, and ``o`` visibly switches the analysis's notes
between all of them and one line (with an ANOVA table or without)."""

from __future__ import annotations

import asyncio

from textual.widgets import DataTable, ProgressBar

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import wait_for, words_on
from .test_camera_layout import text_in


def _newest_shown(app, table: DataTable) -> bool:
    """The newest trial's row is on the screen (its number in the table's visible rows)."""
    last = str(table.get_row_at(table.row_count - 1)[0])
    rows = text_in(app, table).split()
    return last in rows


def test_trials_follow_replay_paused_and_notes_toggle(plugins, map_file, tmp_path):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="studies")
        async with app.run_test(size=(80, 24)) as pilot:
            await wait_for(pilot, lambda: app.session.outputs is not None, 30, "outputs")
            await wait_for(pilot, lambda: app.pane("studies") is not None, 30, "studies")
            await asyncio.to_thread(app.session.vibration.load, map_file)
            pane = app.pane("studies")
            pane.query_one("#protocol").value = "exp2"
            pane.query_one("#out").value = str(tmp_path)
            pane.focus()
            await pilot.press("s", "s")  # exp2's 200 trials (about 10 min) ask first
            bar = pane.query_one("#study-progress", ProgressBar)
            table = pane.query_one("#study-trials", DataTable)
            await wait_for(pilot, lambda: (bar.progress or 0) >= 12, 60, "twelve trials")
            await pilot.press("p")  # paused after this trial: the table settles
            await wait_for(pilot, lambda: "paused" in words_on(app, "#study-status"), 30, "p")
            await pilot.pause(0.3)
            assert _newest_shown(app, table), text_in(app, table)
            await pilot.press("r")  # paused: says why nothing happens, in one line
            status = str(pane.query_one("#study-status").render()).splitlines()
            said = [line for line in status if line.startswith("r:")]
            assert said and "paused" in said[0], status
            await pilot.pause(0.3)  # the status took a line: the table is shorter
            assert _newest_shown(app, table), text_in(app, table)
            pane.control.abort("test over")
            await wait_for(pilot, lambda: pane.running is None, 30, "the run stopped")
            await pilot.press("n")
            notes = pane.query_one("#analysis-notes")
            await wait_for(pilot, lambda: pane.notes and notes.render(), 60, "analysis notes")
            assert pane.query_one("#study-anova", DataTable).row_count == 0  # one run

            def box() -> str:
                return text_in(app, pane.query_one("#analysis-notes-box"))

            # with no ANOVA table the notes show whole in its place (drawn after the title)
            await wait_for(pilot, lambda: "no ANOVA table" in box(), 30, "the notes drawn")
            # the stop's analysis and n's: o acts on the view once neither is under way
            await wait_for(pilot, lambda: not pane._busy, 60, "the analysis done")
            await wait_for(pilot, lambda: "o: one line" in box(), 30, "all the notes shown")
            await pilot.press("o")
            await wait_for(pilot, lambda: "(o shows all)" in box(), 30, "o: one line")
            assert "o: one line" not in box(), box()
            await pilot.press("o")
            await wait_for(pilot, lambda: "o: one line" in box(), 30, "o: all of them again")
            assert "(o shows all)" not in box(), box()

    asyncio.run(scenario())
