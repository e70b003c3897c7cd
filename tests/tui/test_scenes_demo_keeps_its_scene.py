"""A demo showing its scene on the projector keeps it (a new operator's try at 80 x 24):
the knob running, F7 then F6 gave the focus to the scenes table and Enter replaced the
demo's projected scene with `flow_two_point`, no question asked. Back on F6 the demos
list has the focus (Enter stops the knob); Enter on a scene while the demo shows its own
is refused with one line naming the fix (s stops the demo first); after `s` it starts.
The projector line names the demo its scene is shown for."""

from __future__ import annotations

import asyncio

import pytest
from textual.widgets import DataTable

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import wait_for, words_on


def _shows(app, scene: str) -> bool:
    st = app.session.scenes.status() or {}
    return bool(st.get("connected")) and st.get("scene") == scene


async def _pick(pilot, table: DataTable, name: str) -> None:
    names = [str(table.get_row_at(i)[0]) for i in range(table.row_count)]
    table.move_cursor(row=names.index(name))
    await pilot.pause()


@pytest.mark.parametrize("size", [(80, 24), (120, 40)])
def test_enter_on_a_scene_never_replaces_the_demos_scene_unasked(plugins, size):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="scenes")
        async with app.run_test(size=size) as pilot:
            await wait_for(pilot, lambda: app.session.outputs is not None, 30, "outputs")
            pane = app.pane("scenes")
            scenes = app.query_one("#scene-table", DataTable)
            demos = app.query_one("#demo-table", DataTable)
            await wait_for(pilot, lambda: app.focused is scenes, 30, "the scenes table")
            await _pick(pilot, scenes, "knob")
            await pilot.press("enter")  # the projector first: the demo shows its scene there
            await wait_for(pilot, lambda: _shows(app, "knob"), 60, "the knob scene shown")
            await pilot.press("d")
            await wait_for(pilot, lambda: app.focused is demos, 10, "the demos list")
            await _pick(pilot, demos, "knob")
            await pilot.press("enter")
            await wait_for(pilot, lambda: pane.demo_state == "running", 60, "knob running")
            feed = app.session.demos.scene_feed
            await wait_for(pilot, lambda: (feed() or {}).get("sent"), 30, "its scene sent")
            # away and back: the demos list, as left
            await pilot.press("f7")
            await wait_for(pilot, lambda: app.active_tab == "latency", 20, "latency")
            await pilot.press("f6")
            await wait_for(pilot, lambda: app.active_tab == "scenes", 20, "scenes again")
            await wait_for(pilot, lambda: app.focused is demos, 20, "the demos list again")
            # Enter on another scene: refused, the demo's scene stays, the line says why
            scenes.focus()
            await wait_for(pilot, lambda: app.focused is scenes, 10, "the scenes table")
            await _pick(pilot, scenes, "flow_two_point")
            await pilot.press("enter")
            refused = "scene flow_two_point not started: the knob demo shows its scene"
            await wait_for(
                pilot, lambda: refused in words_on(app, "#projector-status"), 30, "refused"
            )
            line = words_on(app, "#projector-status")
            assert "s stops it first" in line and "scene: knob for the knob demo" in line
            await pilot.pause(0.5)
            assert _shows(app, "knob") and pane.demo_state == "running"
            # s stops the demo; Enter then shows the scene
            await pilot.press("s")
            await wait_for(pilot, lambda: pane.demo_name is None, 30, "knob stopped")
            assert refused not in words_on(app, "#projector-status")
            await pilot.press("enter")
            await wait_for(pilot, lambda: _shows(app, "flow_two_point"), 30, "the scene shown")

    asyncio.run(scenario())
