"""Scope (F9) on a recording: the plan's summary is said once (the info line: the chart
says only why it draws nothing), and the gate events list the relay switches by what
they switch, as the safety bar does (`1,5 (PA screen)`), never as a Python list
(`relays closed: [1]`: a new operator's try)."""

from __future__ import annotations

import asyncio

import pytest

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import wait_for, words_on
from .test_recording_view import _type_path
from .test_study_trial_in_scope import trial_file as trial_file  # the fixture


def _screen(app) -> str:
    return "\n".join(s.text for s in app.screen._compositor.render_strips())


@pytest.mark.parametrize("size", [(80, 24), (120, 40)], ids=["80x24", "120x40"])
def test_a_recordings_plan_is_summarised_once_and_relays_named(plugins, trial_file, size):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="scope")
        async with app.run_test(size=size) as pilot:
            scope = app.pane("scope")
            await wait_for(pilot, lambda: app.focused is scope, 20, "scope focused")
            await wait_for(pilot, lambda: app.session.outputs is not None, 30, "outputs")
            out = app.session.outputs
            out.set_relays({1, 5})  # through the gate: its switch events, as it words them
            out.set_relays(set())
            events = [
                {"t_s": e.t_s, "clock": e.clock, "kind": e.kind, "message": e.message}
                for e in out.events()
                if e.kind == "switch"
            ]
            await _type_path(app, pilot, "#scope-recording", str(trial_file))
            info = lambda: words_on(app, "#scope-info")  # noqa: E731
            await wait_for(pilot, lambda: "hash" in info() and ":" in info(), 30, "summary")
            await wait_for(pilot, lambda: "no renderer" in _screen(app), 30, "re-rendered")
            await pilot.pause(0.3)
            shown = " ".join(_screen(app).split())
            assert shown.count("trial pulse: 0.01 s on PB") == 1, shown
            assert shown.count("no renderer here") == 1, shown  # said once, not twice
            scope.replay.gate_events = lambda: events  # the recording's events
            await pilot.press("e")
            await wait_for(pilot, lambda: "relay switch" in info(), 10, "the gate events")
            said = info()
            assert "[" not in said and "]" not in said, said
            assert "relays closed: 1,5 (PA screen)" in said, said
            assert "relays closed: none" in said, said

    asyncio.run(scenario())
