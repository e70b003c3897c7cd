"""The Vibration screen says how a flow is rendered: the effect's method and the
contrast its map predicts (read from the plan, never from the effect's name); on a
profile with a channel per patch the flow is the independent one, played per patch."""

from __future__ import annotations

import asyncio

import pytest

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import command, wait_for
from .test_screens import _load_map, _ready


@pytest.mark.parametrize(
    ("profile", "method"),
    [("sim", "method paper"), ("sim-4ch", "method independent (a drive per patch)")],
)
def test_flow_method_and_predicted_contrast_shown(plugins, map_file, profile, method):
    async def scenario():
        app = HapTableApp(Context(profile, plugins), fast=True, initial="vibration")
        async with app.run_test(size=(110, 32)) as pilot:
            await _ready(app, pilot)
            pane = await _load_map(app, pilot, map_file)
            await command(app, pilot, "51 52")
            await wait_for(pilot, lambda: len(app.session.played) == 1, 30, "flow played")
            plan = app.session.played[0]
            want = f"{method}, predicted contrast {plan.meta['predicted_contrast_db']:.1f} dB"
            info = app.query_one("#vib-info")
            await wait_for(pilot, lambda: "flow 51 -> 52" in str(info.render()), 30, "info")
            assert want in str(info.render())
            assert want in str(app.query_one("#vib-status").render())
            assert pane.selected == [51, 52]
            per_patch = all(s.independent for s in plan.segments)
            assert per_patch == (profile == "sim-4ch")

    asyncio.run(scenario())
