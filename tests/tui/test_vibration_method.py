"""The Vibration screen says how a flow is rendered: the effect's method and the
contrast its map predicts (read from the plan, never from the effect's name)."""

from __future__ import annotations

import asyncio

from .conftest import command, wait_for
from .test_screens import _app, _load_map, _ready


def test_flow_method_and_predicted_contrast_shown(plugins, map_file):
    async def scenario():
        app = _app(plugins, "vibration")
        async with app.run_test(size=(110, 32)) as pilot:
            await _ready(app, pilot)
            pane = await _load_map(app, pilot, map_file)
            await command(app, pilot, "51 52")
            await wait_for(pilot, lambda: len(app.session.played) == 1, 30, "flow played")
            plan = app.session.played[0]
            want = f"method paper, predicted contrast {plan.meta['predicted_contrast_db']:.1f} dB"
            info = app.query_one("#vib-info")
            await wait_for(pilot, lambda: "flow 51 -> 52" in str(info.render()), 30, "info")
            assert want in str(info.render())
            assert want in str(app.query_one("#vib-status").render())
            parts = plan.meta["parts"]
            assert plan.meta["predicted_contrast_db"] == min(p["contrast_db"] for p in parts)
            assert pane.selected == [51, 52]

    asyncio.run(scenario())
