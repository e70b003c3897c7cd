"""The Vibration screen is honest about what it can do: on the lab profile it says the
outputs are not open and never loads the twin's map as if it were the table's (it says
which map it shows and why); ``b`` is in the footer and says when the tables are built."""

from __future__ import annotations

import asyncio
import shutil

from console.cli.main import Context
from console.core.errors import UserError
from console.tui.app import HapTableApp

from .conftest import wait_for
from .test_literal_text import screen_text


def test_lab_profile_says_outputs_are_closed_and_keeps_the_twin_map_out(
    plugins, map_file, monkeypatch
):
    from console.kernel import client

    def no_card(profile, pm, **kw):
        raise UserError("[audio] device = 'Scarlett': no stereo output device matches")

    monkeypatch.setattr(client, "Outputs", no_card)

    async def scenario():
        app = HapTableApp(Context("haptable-lab", plugins), fast=True, initial="vibration")
        kept = app.session.vibration.cached_map_path()  # a map the twin measured earlier
        kept.parent.mkdir(parents=True, exist_ok=True)
        shutil.copy(map_file, kept)
        async with app.run_test(size=(120, 40)) as pilot:
            pane = app.pane("vibration")
            line = app.query_one("#vib-outputs")
            await wait_for(pilot, lambda: line.display, 20, "the outputs line")
            text = str(line.render())
            assert "outputs not open: [audio] device = 'Scarlett'" in text
            assert "nothing plays from this screen" in text
            await wait_for(pilot, lambda: "no vibration map" in pane.status_text, 20, "status")
            assert pane.session is None and app.session.vibration.current is None
            assert "only vibrometer is the plate twin" in pane.status_text
            assert f"load {kept} uses it anyway" in pane.status_text
            assert "plate twin" in screen_text(app)
            # what the scenes get is not the twin's map either
            try:
                app.session.vibration.current_map()
            except UserError as exc:
                assert "measured on the plate twin" in str(exc)
            else:
                raise AssertionError("the twin's map was handed to a scene")

    asyncio.run(scenario())


def test_sim_profile_names_the_map_it_loads_and_b_says_tables_are_built(plugins, map_file):
    async def scenario():
        from console.files.vibration_map import load_map
        from console.runtime.measured_map import keep_measured_map

        app = HapTableApp(Context("sim", plugins), fast=True, initial="vibration")
        vib = app.session.vibration
        keep_measured_map(vib.profile, load_map(map_file))  # as a measurement keeps it
        async with app.run_test(size=(120, 40)) as pilot:
            pane = app.pane("vibration")
            await wait_for(pilot, lambda: pane.session is not None, 30, "the kept map")
            assert "the kept measurement of" in pane.summary and "m measures again" in pane.summary
            assert not app.query_one("#vib-outputs").display  # the twin's outputs are open
            await wait_for(pilot, lambda: pane.status_text.endswith("ready"), 60, "tables")
            assert "b tables" in screen_text(app)  # the key is in the footer
            await wait_for(pilot, lambda: app.focused is pane.focus_target, 10, "grid focus")
            await pilot.press("b")
            assert "lookup tables already built for this map" in pane.status_text

    asyncio.run(scenario())
