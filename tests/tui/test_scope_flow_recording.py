"""Scope (F9) draws a study's flow recording: each trial's plan re-rendered from its
recorded parameters through the registered flow effect, as the flow demo and Scenes
render flows, on the map the trial was recorded with (``recording/map.npz``), each
patch's drive drawn. It said "no renderer here for a plan of kind flow" and drew
nothing (only the flow under a hand had a renderer)."""

from __future__ import annotations

import asyncio

import pytest

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import wait_for, words_on
from .test_recording_view import _type_path


@pytest.fixture
def flow_trial(tmp_path, plugins, profile, map_file):
    """A study trial file whose plan is a flow between two grid points, played at
    another level than the effect's (a participant's), recorded with its map."""
    from console.plugin_api import UserError, load_map
    from plugins.studies.sensation import apply_level
    from plugins.studies.stimuli import EffectPlayer
    from plugins.studies.trial_recording import TrialRecorder

    vmap = load_map(map_file, require_all=False)
    player = EffectPlayer(plugins, profile, vmap, lambda plan: True)
    for a, b in ((int(vmap.points[0]), int(vmap.points[-1])), (1, 12), (5, 30)):
        trial = {"index": 0, "phase": "main", "stimulus": {"effect": "flow"}}
        trial["stimulus"].update(from_point=a, to_point=b)
        try:
            plan = player.prepare(trial)
            break
        except UserError:
            continue
    level = {"level": "test", "parts": [{"amplitude_v": 0.5 * float(p["amplitude_v"])}
                                        for p in plan.meta["parts"]]}  # fmt: skip
    plan = apply_level(plan, level)
    (tmp_path / "plan.json").write_text("{}")
    rec = TrialRecorder(
        tmp_path, {"experiment": "exp1", "trials": [trial]}, profile=None, vmap=vmap
    )
    play = rec.noted_play(lambda p: None)
    rec.begin(0)
    play(plan)
    path = rec.finish({"trial": 0, "participant": "P01", "event": "done", "response": "left"})
    return path, sorted({p for s in plan.segments for p in s.patches})


@pytest.mark.parametrize("size", [(80, 24), (120, 40)], ids=["80x24", "120x40"])
def test_scope_draws_a_study_flow_recording(plugins, flow_trial, size):
    path, patches = flow_trial

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="scope")
        async with app.run_test(size=size) as pilot:
            scope = app.pane("scope")
            await wait_for(pilot, lambda: app.focused is scope, 20, "scope focused")
            await _type_path(app, pilot, "#scope-recording", str(path))
            chart = app.query_one("#scope-chart")
            info = lambda: words_on(app, "#scope-info")  # noqa: E731
            drawn = lambda: words_on(app, "#scope-chart")  # noqa: E731
            await wait_for(pilot, lambda: "re-rendered" in info() or "renderer" in drawn(), 60)
            assert "no renderer" not in drawn(), drawn()
            assert "bit for bit" in info(), info()
            # each patch the flow drove is drawn, named in the legend on screen
            assert [s.label for s in chart.series] == patches, chart.series
            assert all(abs(s.y).max() > 0 for s in chart.series), "a channel drawn flat"
            shown = words_on(app, "#scope-chart")
            for name in patches:
                assert name in shown, shown

    asyncio.run(scenario())


def test_a_demos_two_point_flow_is_rendered_again_as_the_demo_rendered_it(
    plugins, profile, map_file
):
    """The flow demo's flow between two resting fingers (kind ``two_point``, points in
    mm between the grid's) re-renders through the same effect, bit for bit."""
    from types import SimpleNamespace

    from console.core.plan_watch import plan_record
    from console.plugin_api import FlowEffect, load_map
    from console.tui.scope_recording import rerender
    from plugins.demos.adapters import TwoPointFlows

    vmap = load_map(map_file, require_all=False)
    effect = plugins.provider("effect", FlowEffect, profile, plugin_hint="vibrotactile")
    (x0, y0), (x1, y1) = vmap.points_mm[0], vmap.points_mm[-1]
    a_mm, b_mm = (x0 + 13.3, y0 + 7.1), (x1 - 11.2, y1 - 5.4)
    line = plan_record(TwoPointFlows(effect, map_file).plan(a_mm, b_mm))
    assert line["meta"]["kind"] == "two_point"
    run = SimpleNamespace(vibration_map=lambda: vmap)
    session = SimpleNamespace(
        profile=profile, plugins=plugins, vibration=SimpleNamespace(current=None)
    )
    plan, said = rerender(session, line, run)
    assert plan is not None and "bit for bit" in said, said
