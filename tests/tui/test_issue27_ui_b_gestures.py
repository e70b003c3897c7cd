"""Issue 27 (ui b): the Gestures panel's long work says its time left and moves through
the fit on every sample (a step with no report of its own); a training's result is
said once (the result block; the work line and the files block point to it); the size
and time of a synthesis leave the line when its fields change; a number is never cut
from its unit at 80 x 24. The time left itself checked against a constant pace."""

from __future__ import annotations

import asyncio
import re
import threading
import time

from textual.widgets import Input, Label, Static

from console.cli.main import Context
from console.tui.app import HapTableApp
from console.tui.time_left import Pace, left_words, seconds_left

from .conftest import wait_for
from .test_camera_layout import screen_lines
from .test_gestures_panel_80 import _panel


def test_time_left_at_a_constant_pace():
    # a quarter done in 10 s: the other three quarters take 30 s
    assert seconds_left(10.0, 0.25) == 30.0
    assert seconds_left(0.5, 0.5) is None and seconds_left(10.0, 0.0) is None
    assert left_words(30.0) == "about 30 s left"
    assert left_words(3 * 60 + 21) == "about 3 min 25 s left"  # up to 5 s past a minute
    assert left_words(120.0) == "about 2 min left" and left_words(None) == ""
    now = [100.0]
    pace = Pace(clock=lambda: now[0])
    assert pace.left(3, 50) is None  # the first count starts the pace
    now[0] += 8.0  # 2 trials in 8 s: 45 more take 180 s
    assert pace.left(5, 50) == 180.0


FOLDS = [
    {"accuracy": 0.9, "n_test": 20, "static_accuracy": 0.9, "dynamic_accuracy": 0.875},
    {"accuracy": 0.875, "n_test": 20, "static_accuracy": 0.9, "dynamic_accuracy": 0.85},
]
EVAL = {
    "cv": "2fold",
    "procedure": "2fold by subject halves",
    "n_samples": 40,
    "subjects": ["s1"],
    "static_accuracy": 0.9,
    "dynamic_accuracy": 0.8125,
    "folds": FOLDS,
}


def test_training_paced_said_once_and_estimate_lapses(plugins, tmp_path, monkeypatch):
    from plugins.gestures import panel as gp

    model = tmp_path / "m.skops"
    go = threading.Event()
    width = {"w": 78}

    def train(ds, model_out, *, profile, cv, progress, cancelled):
        progress(0.0, "features")
        for k in (1, 2):
            progress(0.45 * (k - 1), f"fold {k}/2: training")
            time.sleep(0.3)
            progress(0.45 * k, f"fold {k}/2: 90.0%")
        progress(0.9, "training on every sample")  # no report until it is done
        go.wait(30)
        progress(1.0, "saved")
        return {"model": str(model_out), "bytes": 1000, **EVAL}

    def files(ds, m):
        return {
            "dataset": {"path": str(ds), "exists": False},
            "model": {"path": str(model), "exists": True, "bytes": 1000, "n_samples": 40,
                      "evaluation": EVAL},
        }  # fmt: skip

    def estimate(subjects, reps, workers=1):
        # "about 45" ends the label's first line: a wrap at any space cuts "MB" off
        pad = width["w"] - len("s again within 20 s to start: ") - len("about 45")
        words = ("x" * 9 + " ") * (pad // 10) + "y" * (pad % 10)
        return {"text": f"{words.strip():<{pad}}about 45 MB and about 3 min"}

    monkeypatch.setattr(gp, "train_and_evaluate", train)
    monkeypatch.setattr(gp, "describe_files", files)
    monkeypatch.setattr(gp, "synth_estimate", estimate)

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="devices")
        async with app.run_test(size=(80, 24)) as pilot:
            panel = await _panel(app, pilot, plugins)
            work = panel.work
            panel.query_one("#gp-dataset", Input).value = str(tmp_path)
            panel.query_one("#gp-model", Input).value = str(model)
            width["w"] = work.query_one(Label).size.width
            # the estimate: "45 MB" on one line; a field changed: the line says so
            await pilot.press("s")
            await wait_for(pilot, lambda: "s again" in work.text, 30, "estimate")
            await pilot.pause(0.2)
            rows = " | ".join(screen_lines(app))
            assert "45 MB" in rows, rows
            panel.query_one("#gp-reps", Input).value = "41"
            await pilot.pause(0.1)
            assert "s again" not in work.text and "reps changed" in work.text, work.text
            # training: the final fit moves the bar past 90 % and says the time left
            await pilot.press("t", "t")  # the first says its size and time
            seen: list[str] = []

            def moved() -> bool:
                seen.append(work.text)
                return (work.progress or 0) > 0.9

            await wait_for(pilot, moved, 20, "the bar past 90 %")
            assert any(re.search(r"s left|s in this step", t) for t in seen), seen
            go.set()
            await wait_for(pilot, lambda: work.outcome == "done", 20, "trained")
            await pilot.pause(0.3)
            said = [
                work.text,
                str(panel.query_one("#gp-files", Static).render()),
                str(panel.query_one("#gp-result", Static).render()),
            ]
            # the result's numbers once: in the result block only
            assert sum(s.count("81.2 %") for s in said) == 1, said
            assert "81.2 %" in said[2] and "below" in said[0] and "below" in said[1], said

    asyncio.run(scenario())
