"""The Vibration screen's status line is the one place for what happened (issue 27):

- a request says it is asking; "playing" comes from the outputs' report, and a refusal
  before the start (the e-stop) says so with the fix, never "stopped by the e-stop";
- a message names the fix where the operator is (no command-line switch), and the grid
  marks where a flow under a hand is possible;
- an error replaces the line (no toast beside it) and a refused command changes nothing;
- the flow's method and the lookup tables' rule are named once, with the contrasts
  they show."""

from __future__ import annotations

import asyncio

from textual.widgets import DataTable

from console.cli.main import Context
from console.tui.app import HapTableApp
from console.tui.command_line import CommandLine

from .conftest import command, wait_for
from .test_screens import _load_map, _ready


def _status(app) -> str:
    return str(app.query_one("#vib-status").render())


def _info(app) -> str:
    return str(app.query_one("#vib-info").render())


def test_enter_during_an_estop_is_refused_before_it_starts(plugins, map_file):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="vibration")
        async with app.run_test(size=(80, 24)) as pilot:
            await _ready(app, pilot)
            pane = await _load_map(app, pilot, map_file)
            await wait_for(pilot, lambda: app.focused is pane.focus_target, what="grid")
            seen: list[str] = []
            real = pane.status

            def spy(text, *a, **kw):
                seen.append(text)
                return real(text, *a, **kw)

            pane.status = spy
            await pilot.press("ctrl+e")
            await wait_for(pilot, lambda: app.session.outputs.estopped, what="e-stopped")
            pane.move_cursor(1)
            await pilot.press("enter")
            await wait_for(pilot, lambda: "refused" in _status(app), 20, "refusal shown")
            assert "point 1 refused: e-stop active, ctrl+r resets" in _status(app)
            assert not any("stopped by the e-stop" in t for t in seen), seen
            assert not any(t.startswith("playing") for t in seen), seen
            assert app.session.played == []
            # the reset clears the refusal the e-stop caused
            await pilot.press("ctrl+r")
            await wait_for(pilot, lambda: not app.session.outputs.estopped, what="reset")
            await wait_for(pilot, lambda: "refused" not in _status(app), 10, "refusal cleared")

    asyncio.run(scenario())


def test_a_play_says_asking_then_playing_from_the_outputs_report(plugins, map_file):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=False, initial="vibration")
        async with app.run_test(size=(80, 24)) as pilot:
            await _ready(app, pilot)
            pane = await _load_map(app, pilot, map_file)
            seen: list[str] = []
            real = pane.status

            def spy(text, *a, **kw):
                seen.append(text)
                return real(text, *a, **kw)

            pane.status = spy
            await command(app, pilot, "14")
            await wait_for(pilot, lambda: "played point 14" in _status(app), 30, "played")
            asks = [i for i, t in enumerate(seen) if t.startswith("asking to play point 14")]
            plays = [i for i, t in enumerate(seen) if t.startswith("playing point 14")]
            assert asks and plays and asks[0] < plays[0], seen

    asyncio.run(scenario())


def test_a_hand_flow_off_the_grid_names_the_fix_on_the_screen(plugins, map_file):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="vibration")
        async with app.run_test(size=(120, 40)) as pilot:
            await _ready(app, pilot)
            pane = await _load_map(app, pilot, map_file)
            await command(app, pilot, "hand 84 left")
            await wait_for(
                pilot,
                lambda: "hand" in _status(app) and not _status(app).endswith("..."),
                30,
                "hand refused",
            )
            text = _status(app)
            assert "--" not in text and "extrapolat" not in text, text
            assert "point 84" in text and "·" in text, text
            assert app.session.played == []
            # the grid marks the points where a hand flow fits (the sim's 120 mm hand:
            # rows 2-6, columns 2-11), and says what the mark means
            grid = app.query_one("#grid", DataTable)
            row2 = [str(c) for c in grid.get_row_at(1)]
            assert "·" not in row2[0] and "·" in row2[1] and "·" in row2[10]
            assert "·" not in row2[11]
            assert all("·" not in str(c) for c in grid.get_row_at(0))
            assert all("·" not in str(c) for c in grid.get_row_at(6))
            assert "·" in _info(app) or "·" in str(app.query_one("#vib-legend").render())
            # the refused command keeps the keys on its line: escape gives them back to
            # the grid, where w on a marked point plays
            assert isinstance(app.focused, CommandLine)
            await pilot.press("escape")
            pane.move_cursor(51)
            await pilot.press("w")
            await wait_for(pilot, lambda: len(app.session.played) == 1, 60, "hand flow played")

    asyncio.run(scenario())


def test_errors_go_to_the_status_line_only_and_a_refused_command_changes_nothing(plugins, map_file):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="vibration")
        async with app.run_test(size=(80, 24), notifications=True) as pilot:
            await _ready(app, pilot)
            pane = await _load_map(app, pilot, map_file)
            await command(app, pilot, "51 52")
            await wait_for(pilot, lambda: len(app.session.played) == 1, 30, "flow played")
            before = len(app._notifications)
            await command(app, pilot, "import PA")
            await wait_for(pilot, lambda: "EXC=FILE" in _status(app), 10, "first error")
            await command(app, pilot, "99")
            await wait_for(pilot, lambda: "99" in _status(app), 10, "99 on the line")
            assert "EXC=FILE" not in _status(app)
            await command(app, pilot, "0")
            await wait_for(pilot, lambda: "point 0" in _status(app), 10, "0 on the line")
            await pilot.pause(0.2)
            assert len(app._notifications) == before, [n.message for n in app._notifications]
            assert pane.selected == [51, 52]
            await command(app, pilot, "51 51")
            await wait_for(pilot, lambda: "51 -> 51" in _status(app), 10, "51 51 refused")
            assert pane.selected == [51, 52]
            await pilot.pause(0.3)
            assert "the same point" not in _info(app)
            await command(app, pilot, "51 99")
            await wait_for(pilot, lambda: "99" in _status(app), 10, "51 99 refused")
            assert pane.selected == [51, 52] and len(app.session.played) == 1
            assert len(app._notifications) == before

    asyncio.run(scenario())


def test_the_flow_names_its_method_and_the_tables_rule_with_their_contrasts(plugins, map_file):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="vibration")
        async with app.run_test(size=(120, 40)) as pilot:
            await _ready(app, pilot)
            pane = await _load_map(app, pilot, map_file)
            await wait_for(pilot, lambda: pane.session.tables_ready, 120, "tables built")
            await command(app, pilot, "51 52")
            await wait_for(pilot, lambda: "played flow" in _status(app), 30, "played")
            await wait_for(pilot, lambda: "flow 51 -> 52" in _info(app), 30, "info")
            s = pane.session
            fwd, back = s.lookup(51, 52), s.lookup(52, 51)
            info = _info(app)
            # each table entry with its contrast, under the tables' rule
            assert "rule perceptual" in info
            assert f"contrast {fwd['contrast_db']:.1f} dB" in info
            assert f"contrast {back['contrast_db']:.1f} dB" in info
            # the flow says which number it shows: the weaker of its two parts
            weaker = min(fwd["contrast_db"], back["contrast_db"])
            assert f"predicted contrast {weaker:.1f} dB (the weaker part)" in info
            assert "rule perceptual" in _status(app)

    asyncio.run(scenario())


def test_a_play_while_the_map_is_measured_is_refused(plugins, map_file):
    """Enter and f during a measurement (the new operator's m m, then f): refused in one
    line that names how to stop the measurement; nothing plays beside its sweeps."""

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="vibration")
        async with app.run_test(size=(80, 24)) as pilot:
            await _ready(app, pilot)
            pane = await _load_map(app, pilot, map_file)
            await wait_for(pilot, lambda: app.focused is pane.focus_target, what="grid")
            pane.move_cursor(51)
            await pilot.press("enter")
            await wait_for(pilot, lambda: "played point 51" in _status(app), 20, "51 played")
            pane.move_cursor(52)
            await pilot.press("enter")
            await wait_for(pilot, lambda: "played point 52" in _status(app), 20, "52 played")
            played = list(app.session.played)
            import time

            from console.session.vibration import Cancelled

            def held(progress, cancelled):  # a measurement that lasts until x (the
                while not cancelled():  # fast twin's would end before the keys)
                    time.sleep(0.02)
                raise Cancelled

            pane.service.measure = held
            pane.action_measure("measure")  # as `:measure` (no kept map: no question)
            await wait_for(pilot, lambda: pane._measuring is not None, 10, "measuring")
            for key in ("f", "enter"):
                await pilot.press(key)
                await wait_for(pilot, lambda: "refused" in _status(app), 10, f"{key} refused")
                assert "the map is being measured (x stops the measurement)" in _status(app)
            assert app.session.played == played, "a stimulus played beside the sweeps"
            await pilot.press("x")
            await wait_for(pilot, lambda: pane._measuring is None, 20, "measurement stopped")

    asyncio.run(scenario())
