"""The Gestures panel, driven as an operator would: opened from the command palette,
a tiny twin dataset synthesized (its size and time first, then confirmed) with a
progress bar and a summary, training cancelled
(no model file appears), training run to the end (accuracy per fold), bad input."""

from __future__ import annotations

import asyncio
from pathlib import Path

from textual.widgets import Input

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import wait_for


def _set(panel, name: str, value: str) -> None:
    panel.query_one(f"#gp-{name}", Input).value = value


def test_gestures_panel_synth_train_cancel_and_bad_input(plugins, tmp_path, one_model_setting):
    ds, model = tmp_path / "set", tmp_path / "gestures.skops"

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="devices")
        async with app.run_test(size=(80, 24)) as pilot:
            await wait_for(pilot, lambda: app.session.outputs is not None, what="outputs open")
            await pilot.press("ctrl+p")
            await pilot.press(*"Panel: gestures")
            await pilot.press("enter")
            await wait_for(pilot, lambda: type(app.screen).__name__ == "GesturesPanel")
            panel = app.screen
            work = panel.work
            _set(panel, "dataset", str(ds))
            _set(panel, "model", str(model))
            _set(panel, "subjects", "1")

            # bad input: one red line naming the field, nothing started or written
            _set(panel, "reps", "0")
            await pilot.press("s")
            assert "reps '0'" in work.text and "\n" not in work.text
            assert work.query_one("Label").has_class("error")
            assert not work.busy and not ds.exists()

            # a tiny dataset (4 repetitions: the harmonics and frames are chosen inside
            # each training half): its size and time first, then s again starts it; the
            # bar shows while it runs, a summary when done
            _set(panel, "reps", "4")
            await pilot.press("s")
            await wait_for(pilot, lambda: work.outcome is not None, 60, "estimate")
            assert "s again within" in work.text and not ds.exists()
            await pilot.press("s")
            assert work.busy and work.progress is not None
            seen = set()

            def done() -> bool:
                if work.progress is not None:
                    seen.add(round(work.progress, 2))
                return work.outcome is not None

            await wait_for(pilot, done, 180, "synthesis done")
            assert work.outcome == "done", work.text
            assert "synthesized 40 samples (1 x 10 x 4)" in work.text
            assert len(seen) >= 3  # the bar moved through the work
            files = panel.query_one("#gp-files")
            await wait_for(pilot, lambda: "40 samples" in str(files.render()), 10, "files")
            assert "4 reps" in str(files.render())
            assert sorted(p.name for p in tmp_path.iterdir()) == ["set"]

            # t first says the training's size and its time (issue 27: it started at once,
            # 20 s for 60 samples unsaid): no training of this model timed yet
            await pilot.press("t")
            assert not work.busy, work.text
            assert "t again within 20 s to train: 2fold on 40 samples" in work.text, work.text
            assert "its time said as it runs" in work.text, work.text
            # training cancelled: says so, no model file, no temporary left behind
            await pilot.press("t", "x")
            await wait_for(pilot, lambda: work.outcome is not None, 180, "training stopped")
            assert work.outcome == "cancelled" and "training cancelled" in work.text
            assert "training cancelled: no model was written" in work.text  # said once
            assert sorted(p.name for p in tmp_path.iterdir()) == ["set"]

            # training to the end: accuracy per fold, the model in the files block
            await pilot.press("t", "t")
            await wait_for(pilot, lambda: work.outcome is not None, 300, "training done")
            assert work.outcome == "done", work.text
            res = panel.query_one("#gp-result")
            await wait_for(pilot, lambda: "fold 2" in str(res.render()), 10, "result")
            result = str(res.render())
            assert "fold 1" in result and "fold 2" in result and "2fold" in result
            assert model.is_file()
            # the model in the files block; its evaluation said once, in the result
            await wait_for(pilot, lambda: "result below" in str(files.render()), 10, "files")
            assert "fold 1" not in str(files.render()) and "below" in work.text
            assert sorted(p.name for p in tmp_path.iterdir()) == ["gestures.skops", "set"]
            # the next t says its time at the pace this training took
            await pilot.press("t")
            assert "on 40 samples" in work.text and "the last training's pace" in work.text
            assert " s a sample)" in work.text and not work.busy, work.text

            # the e-stop works here too, and the panel's safety bar shows it
            await pilot.press("ctrl+e")
            await wait_for(pilot, lambda: app.session.outputs.estopped, what="e-stop")
            bar = panel.query_one("#safety")
            await wait_for(pilot, lambda: str(bar.render()).startswith(" E-STOP"), what="bar")

            await pilot.press("escape")
            await wait_for(pilot, lambda: type(app.screen).__name__ != "GesturesPanel")

    asyncio.run(scenario())


def test_gestures_panel_at_80x24(snap_compare, monkeypatch):
    """The panel at the smallest supported terminal, after a bad repetition count (stable
    plugins and relative paths, so the picture does not depend on the machine: the
    project's profile reads ``~/profiles/sim.toml``, its folder the home)."""
    from console.config.plugins import load_plugins

    monkeypatch.setenv("HOME", str(Path(__file__).resolve().parents[2]))

    names = ("twin", "twin.camera", "twin.plate", "gestures")
    plugins = load_plugins(builtins={n: f"plugins.{n}" for n in names})
    app = HapTableApp(Context("sim", plugins), fast=True, initial="devices")

    async def run_before(pilot):
        await wait_for(pilot, lambda: app.session.outputs is not None, what="outputs open")
        app.push_screen(plugins.of("panel")["gestures"].factory(app))
        await wait_for(pilot, lambda: type(app.screen).__name__ == "GesturesPanel")
        panel = app.screen
        await wait_for(pilot, lambda: bool(panel.query("#gp-files")), what="panel composed")
        _set(panel, "dataset", "no-such-set")
        _set(panel, "model", "no-such-model.skops")
        _set(panel, "reps", "0")
        panel.action_refresh()
        files = panel.query_one("#gp-files")
        await wait_for(pilot, lambda: "no-such-model" in str(files.render()), 10, "files")
        await pilot.press("s")
        await pilot.pause(0.3)
        await pilot.wait_for_scheduled_animations()

    assert snap_compare(app, terminal_size=(80, 24), run_before=run_before)
