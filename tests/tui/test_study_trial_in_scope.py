"""A study's trial file (``record trials``) opens in the console's recording view, as
``haptable replay`` reads it: on Scope (F9) ``o`` shows its plan, where the console used
to refuse it as "an HDF5 file but not a HapTable recording" (the field's hint names it)."""

from __future__ import annotations

import asyncio

import numpy as np
import pytest

from console.cli.main import Context
from console.core.types import OutputPlan, Segment
from console.tui.app import HapTableApp
from console.tui.recording_view import open_run

from .conftest import wait_for, words_on
from .test_recording_view import _type_path


@pytest.fixture
def trial_file(tmp_path):
    from plugins.studies.trial_recording import TrialRecorder

    (tmp_path / "plan.json").write_text("{}")
    trials = [{"index": 0, "phase": "main", "stimulus": {"effect": "sine"}}]
    rec = TrialRecorder(tmp_path, {"experiment": "exp1", "trials": trials}, profile=None)
    plan = OutputPlan(
        48000,
        (Segment(np.sin(np.arange(480) / 10.0) * 20, np.zeros(480), frozenset({"PB"})),),
        "trial pulse",
        meta={"kind": "test"},
    )
    play = rec.noted_play(lambda p: None)
    rec.begin(0)
    play(plan)
    return rec.finish({"trial": 0, "participant": "P03", "event": "done", "response": "yes"})


def test_open_run_reads_a_study_trial(plugins, trial_file):
    run = open_run(plugins, str(trial_file))
    try:
        assert run.n_frames == 0 and [p["name"] for p in run.plans()] == ["trial pulse"]
        assert run.gate_events() == []
    finally:
        run.close()


@pytest.mark.parametrize("size", [(80, 24), (120, 40)])
def test_scope_shows_a_study_trials_plan(plugins, trial_file, size):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="scope")
        async with app.run_test(size=size) as pilot:
            await wait_for(pilot, lambda: app.pane("scope") is not None, 30, "scope")
            scope = app.pane("scope")
            await wait_for(pilot, lambda: app.focused is scope, 20, "scope focused")
            await _type_path(app, pilot, "#scope-recording", str(trial_file))
            await wait_for(
                pilot, lambda: "plan 1/1" in words_on(app, "#scope-head"), 30, "the trial's plan"
            )
            await wait_for(
                pilot, lambda: "trial pulse" in words_on(app, "#scope-info"), 30, "its summary"
            )
            assert "not a HapTable recording" not in words_on(app, "#scope-head")

    asyncio.run(scenario())


def test_camera_sends_a_trial_without_frames_to_scope(plugins, trial_file):
    """A simulated study's trial saw no camera: Camera says where its plan shows."""

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="camera")
        async with app.run_test(size=(80, 24)) as pilot:
            pane = app.pane("camera")
            await wait_for(pilot, lambda: app.focused is pane, 30, "camera focused")
            await _type_path(app, pilot, "#camera-recording", str(trial_file))
            await wait_for(
                pilot, lambda: "no frames" in words_on(app, "#camera-status"), 30, "said"
            )
            said = words_on(app, "#camera-status")
            assert "not a HapTable recording" not in said and "Scope" in said, said

    asyncio.run(scenario())
