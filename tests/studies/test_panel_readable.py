"""The Studies screen as a new experimenter first sees it, at 80 x 24 and 120 x 40: the
screen's keys in the footer at once, every field labelled and shown whole, and a status
that names the participant after a run stopped and says a refusal once."""

from __future__ import annotations

import asyncio

import pytest
from textual.widgets import Button, Static

from .studies_pilot import studies_app, studies_pane, wait_for


def screen_text(app) -> str:
    return "\n".join(strip.text for strip in app.screen._compositor.render_strips())


async def _studies(app, pilot):
    return await studies_pane(pilot, app)


@pytest.mark.parametrize("size", [(80, 24), (120, 40)])
def test_keys_in_the_footer_and_fields_readable_on_show(double_plugins, size):
    async def scenario():
        app = studies_app(double_plugins)
        async with app.run_test(size=size) as pilot:
            pane = await _studies(app, pilot)
            await wait_for(
                pilot,
                lambda: app.focused is not None and pane in app.focused.ancestors_with_self,
                what="the screen focused",
            )
            assert isinstance(app.focused, Button) and app.focused.id == "start"
            await pilot.pause(0.2)
            text = screen_text(app)
            footer = text.splitlines()[-1]
            for key in ("s start", "p pause", "a abort", "n analyse", "t view"):
                assert key in footer, footer
            assert "^e E-STOP" in footer and "? help" in footer, footer  # at 80 columns too
            for label in (
                "protocol",
                "participant",
                "simulated",
                "projector",
                "age",
                "sex",
                "handedness",
                "hand width cm",
                "hand length cm",
                "consent noted",
            ):
                assert label in text, label
            assert "folder " in text
            # a filled field keeps its label and shows its value whole (the folder as a
            # user's default data folder reads)
            pane.query_one("#out").value = "/root/.local/share/haptable/studies"
            pane.query_one("#handedness").value = "ambidextrous"
            pane.query_one("#hand_length_cm").value = "18.15"
            await pilot.pause(0.2)
            text = screen_text(app)
            assert "folder /root/.local/share/haptable/studies" in text
            assert "handedness ambidextrous" in text and "hand length cm 18.15" in text
            # s on the screen as it shows starts a run (a person without details: refused)
            pane.query_one("#protocol").value = "exp2"
            pane.query_one("#simulate").value = False
            await pilot.press("s")
            await wait_for(pilot, lambda: pane.last.get("stopped"), what="refused")

    asyncio.run(scenario())


def test_status_names_the_participant_and_says_a_refusal_once(double_plugins, map_file, tmp_path):
    async def scenario():
        app = studies_app(double_plugins)
        async with app.run_test(size=(80, 24)) as pilot:
            pane = await _studies(app, pilot)
            await asyncio.to_thread(app.session.vibration.load, map_file)
            status = pane.query_one("#study-status", Static)
            pane.query_one("#protocol").value = "exp2"
            pane.query_one("#out").value = str(tmp_path)
            pane.query_one("#participant").value = "P07"
            # a person without details: refused, the reason said once
            pane.query_one("#simulate").value = False
            await pilot.click("#start")
            await wait_for(pilot, lambda: pane.last.get("stopped"), what="refused")
            await pilot.pause(0.2)
            shown = str(status.render())
            assert shown.startswith("P07: ")
            assert shown.count("hand length cm missing") == 1, shown
            # a simulated run, aborted: the status still names the participant
            pane.query_one("#simulate").value = True
            await pilot.click("#start")
            bar = pane.query_one("#study-progress")
            await wait_for(pilot, lambda: (bar.progress or 0) >= 2, what="two trials done")
            # pressed, not clicked: a toast in the corner may cover the button at 80 x 24
            abort = pane.query_one("#abort", Button)
            abort.press()  # asks first
            await pilot.pause(0.1)
            abort.press()
            await wait_for(pilot, lambda: pane.running is None, what="the run stopped")
            await pilot.pause(0.2)
            shown = str(status.render())
            done = int(bar.progress)
            assert shown.startswith(f"P07: {done}/200 trials done"), shown
            assert "aborted" in shown and shown.count(f"{done}/200") <= 2

    asyncio.run(scenario())


def test_the_help_has_a_line_per_key(double_plugins):
    async def scenario():
        app = studies_app(double_plugins)
        async with app.run_test(size=(80, 24)) as pilot:
            pane = await _studies(app, pilot)
            await wait_for(pilot, lambda: app.focused is pane.focus_target, what="focus")
            await pilot.press("question_mark")
            await pilot.pause(0.3)
            help_text = str(app.screen.query_one("#help-text", Static).render())
            raw = help_text.splitlines()
            lines = [" ".join(ln.split()) for ln in raw]  # (the key column's own spaces)
            assert "t show the trials / the analysis" in lines
            assert any(ln.startswith("arrows answer up/down/left/right") for ln in lines)
            # the descriptions start in one column
            at = {
                ln.index(w) for ln in raw for w in ("show the trials", "answer up/down") if w in ln
            }
            assert len(at) == 1, raw
            assert max(len(ln) for ln in pane.HELP_TEXT.splitlines()) <= 76  # no wrapping

    asyncio.run(scenario())


def test_start_during_an_e_stop_is_refused_on_the_key_and_writes_nothing(
    double_plugins, map_file, tmp_path
):
    """ctrl+e, then s (twice): one line saying how to go on, no run folder, no trial
    line. Before s the status says the flow study needs a vibration map, until one is
    loaded."""

    async def scenario():
        app = studies_app(double_plugins)
        async with app.run_test(size=(80, 24)) as pilot:
            pane = await _studies(app, pilot)
            status = pane.query_one("#study-status", Static)
            pane.query_one("#protocol").value = "exp1"
            pane.query_one("#out").value = str(tmp_path)
            await wait_for(pilot, lambda: app.focused is pane.focus_target, what="focus")
            await pilot.pause(0.2)
            assert "exp1 needs a vibration map: none yet, s measures the twin's grid first" in (
                str(status.render())
            )
            pane.query_one("#protocol").value = "knob"  # no map needed
            await pilot.pause(0.2)
            assert "vibration map" not in str(status.render())
            pane.query_one("#protocol").value = "exp1"
            await asyncio.to_thread(app.session.vibration.load, map_file)
            await wait_for(pilot, lambda: "vibration map" not in str(status.render()), 10)
            await pilot.press("ctrl+e")
            await wait_for(pilot, lambda: app.session.outputs.estopped, what="e-stop")
            for _ in range(2):
                await pilot.press("s")
                await pilot.pause(0.3)
                # the screen's own key: the last line of its status (console.tui.said)
                said = str(status.render()).splitlines()[-1]
                assert said == "refused: e-stop active, ctrl+r resets"  # as every screen says it
                assert pane.running is None
            assert not (tmp_path / "P01").exists()
            await pilot.press("ctrl+r")
            await wait_for(pilot, lambda: not app.session.outputs.estopped, what="reset")
            # the reset: the line no longer says the e-stop refused anything
            await wait_for(pilot, lambda: "e-stop active" not in str(status.render()), 10)
            await pilot.press("s")  # now it runs
            await wait_for(pilot, lambda: (tmp_path / "P01" / "trials.jsonl").exists(), 60)
            await pilot.press("a", "a")  # the second confirms
            await wait_for(pilot, lambda: pane.running is None, what="stopped")

    asyncio.run(scenario())
