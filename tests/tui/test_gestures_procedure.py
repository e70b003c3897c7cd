"""The Gestures panel's train + evaluate and `haptable gestures eval` run one procedure:
on the same small synthetic dataset they name the same procedure and give the same
accuracies (issue 27: the panel said 90.0 % / 87.5 %, the CLI 97.5 % / 95.0 %)."""

from __future__ import annotations

import asyncio
import json

import numpy as np
import pytest
from textual.widgets import Input

from console.cli.main import Context, main
from console.tui.app import HapTableApp
from plugins.gestures import sketch
from plugins.gestures.dataset import write_background, write_sample

from .conftest import wait_for


@pytest.fixture
def dataset(tmp_path):
    """2 subjects x 10 gestures x 2 repetitions of sketched hands (seconds to analyse)."""
    root = tmp_path / "set"
    bg = sketch.background()
    write_background(root, bg)
    rng = np.random.default_rng(3)
    for subject, size in (("s1", 0.95), ("s2", 1.08)):
        for g in sketch.STATIC + sketch.DYNAMIC:
            for rep in range(2):
                poses = sketch.gesture_poses(
                    g,
                    4 if g in sketch.STATIC else 5,
                    pos_px=(rng.uniform(220, 420), rng.uniform(180, 280)),
                    theta_deg=rng.uniform(-180, 180),
                    left=bool(rep % 2),
                    size=size * rng.uniform(0.95, 1.05),
                    speed=rng.uniform(0.8, 1.2),
                )
                frames = [sketch.draw([p], bg, rng=rng) for p in poses]
                write_sample(
                    root, g, f"{subject}_{rep:03d}", frames, subject=subject,
                    hand="left" if rep % 2 else "right", fps=60,
                )  # fmt: skip
    return root


def test_panel_and_cli_evaluate_alike(plugins, dataset, tmp_path, capsys, one_model_setting):
    from console.config.profile import save_overrides

    model = tmp_path / "gestures.skops"

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="devices")
        async with app.run_test(size=(80, 24)) as pilot:
            await wait_for(pilot, lambda: app.session.outputs is not None, what="outputs open")
            # a vision setting kept after the console started (the Camera screen's W):
            # the CLI started now reads it, and so does the panel
            save_overrides(app.ctx.profile, {"vision.body_threshold": 30.0}, plugins)
            app.push_screen(plugins.of("panel")["gestures"].factory(app))
            await wait_for(pilot, lambda: type(app.screen).__name__ == "GesturesPanel")
            panel = app.screen
            await wait_for(pilot, lambda: bool(panel.query("#gp-files")), what="panel composed")
            panel.query_one("#gp-dataset", Input).value = str(dataset)
            panel.query_one("#gp-model", Input).value = str(model)
            panel.query_one("#gp-cv", Input).value = "2fold"
            await pilot.press("t", "t")  # the second starts what the first said
            work = panel.work
            await wait_for(pilot, lambda: work.outcome is not None, 300, "training done")
            assert work.outcome == "done", work.text
            res = panel.query_one("#gp-result")
            await wait_for(pilot, lambda: "fold 2" in str(res.render()), 10, "result")
            return work.result, " ".join(str(res.render()).split())

    got, shown = asyncio.run(scenario())
    capsys.readouterr()
    assert main(["gestures", "eval", str(dataset), "--cv", "2fold", "--no-cache", "--json"]) == 0
    cli = json.loads(capsys.readouterr().out)

    # one procedure, named in both outputs
    assert cli["procedure"] == got["procedure"]
    assert cli["procedure"].startswith("2-fold CV")
    assert "seed 0" in cli["procedure"] and "harmonics" in cli["procedure"]
    assert cli["procedure"] in shown
    # the same numbers, fold by fold
    assert cli["static_accuracy"] == got["static_accuracy"]
    assert cli["dynamic_accuracy"] == got["dynamic_accuracy"]
    assert [f["accuracy"] for f in cli["folds"]] == [f["accuracy"] for f in got["folds"]]


def test_cli_eval_names_its_procedure_in_text(dataset, capsys):
    args = ["gestures", "eval", str(dataset), "--cv", "2fold", "--harmonics", "2", "--frames", "4"]
    assert main(args) == 0
    out = capsys.readouterr().out
    line = next(s for s in out.splitlines() if s.startswith("procedure:"))
    assert "2-fold CV" in line and "harmonics 2" in line and "frames 4" in line
    assert "seed 0" in line
