"""Issue 27, what a new operator found at 80 x 24: one error in one place (a screen's own
outcome on its status line, no toast beside it) and every failure in the log (ctrl+l);
texts whole at 80 columns (Devices' result, Vibration's ``d`` reason, Relays' row after a
reset, Scenes' descriptions); one label per key (Scenes' ``s``); the projector line says
who holds it; the same footer rule on every screen (``f1-f10 screens``); a saved signal's
key says ``saved``; the piezo range as the gate holds it, with where it comes from."""

from __future__ import annotations

import asyncio
import logging
import re

from textual.widgets import DataTable, Input, Static

from console.cli.main import Context
from console.tui.app import HapTableApp
from console.tui.logs import LogScreen, ViewHandler

from .conftest import wait_for
from .test_camera_layout import text_in
from .test_screens import _load_map, _ready


def _flat(text: str) -> str:
    return re.sub(r"\s+", " ", str(text)).strip()


def _toasts(app) -> list[str]:
    return [str(n.message) for n in app._notifications]


def _screen(app) -> list[str]:
    return [strip.text for strip in app.screen._compositor.render_strips()]


def _footer(app) -> str:
    return _screen(app)[-1]


def assert_whole(app, widget, text: str) -> None:
    """``text`` shows whole inside ``widget``'s visible part of the screen (wrapped
    anywhere: a long path breaks inside a word)."""
    shown = text_in(app, widget)
    assert re.sub(r"\s+", "", str(text)) in re.sub(r"\s+", "", shown), (
        f"{text!r}\nnot whole in\n{shown!r}\n" + "\n".join(_screen(app))
    )


# ---------------------------------------------------------------- one error, one place
def test_a_refused_play_is_said_once_on_its_screen_and_is_in_the_log(plugins):
    """Signals during an e-stop: the refusal on the status line, no toast; the log view
    (ctrl+l) has it, and the toasts of the e-stop key too."""

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="signals")
        handler = ViewHandler(app)
        logging.getLogger().addHandler(handler)
        try:
            async with app.run_test(size=(80, 24)) as pilot:
                await _ready(app, pilot)
                status = app.query_one("#sig-status", Static)
                await pilot.press("ctrl+e")
                await wait_for(pilot, lambda: app.session.outputs.estopped, what="e-stopped")
                await pilot.press("ctrl+o")
                await wait_for(pilot, lambda: "e-stop" in str(status.render()), 20, "refused")
                said = _flat(status.render())
                await pilot.pause(0.5)
                assert not any(said[:30] in _flat(t) for t in _toasts(app)), _toasts(app)
                assert_whole(app, status, said)
                await pilot.press("ctrl+l")
                await wait_for(pilot, lambda: isinstance(app.screen, LogScreen), 5, "log")
                log = "\n".join(s.text for s in app.screen.query_one("RichLog").lines)
                assert said[:40] in _flat(log), log  # the status line's error
                assert "E-STOP: outputs silenced" in _flat(log)  # and the e-stop's toast (wrapped)
        finally:
            logging.getLogger().removeHandler(handler)

    asyncio.run(scenario())


def test_signals_says_the_estop_refusal_in_the_console_s_words_and_drops_it_at_the_reset(plugins):
    """The refusal reads as on every screen (``refused: e-stop active, ctrl+r resets``);
    after the operator's reset the line no longer says the e-stop refused anything."""

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="signals")
        async with app.run_test(size=(80, 24)) as pilot:
            await _ready(app, pilot)
            status = app.query_one("#sig-status", Static)
            await pilot.press("ctrl+e")
            await wait_for(pilot, lambda: app.session.outputs.estopped, what="e-stopped")
            await pilot.press("ctrl+o")
            await wait_for(pilot, lambda: "e-stop" in str(status.render()), 20, "refused")
            assert "refused: e-stop active, ctrl+r resets" in _flat(status.render())
            await pilot.press("ctrl+r")
            await wait_for(pilot, lambda: not app.session.outputs.estopped, what="reset")
            await wait_for(pilot, lambda: "refused" not in str(status.render()), 10, "cleared")
            assert "e-stop reset" in _flat(status.render())

    asyncio.run(scenario())


def test_a_relay_refused_during_an_estop_is_said_on_its_row_not_as_a_toast(plugins):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="relays")
        async with app.run_test(size=(80, 24)) as pilot:
            await wait_for(pilot, lambda: app.session.outputs is not None, what="outputs")
            pane = app.pane("relays")
            await pilot.press("ctrl+e")
            await wait_for(pilot, lambda: app.session.outputs.estopped, what="e-stopped")
            await pilot.press("1")
            await wait_for(pilot, lambda: 1 in pane.refused, 10, "refused")
            await pilot.pause(0.3)
            row = app.query_one("#interlock-1", Static)
            assert "refused: e-stop active" in text_in(app, row)
            assert not any("relay 1" in t for t in _toasts(app)), _toasts(app)
            # after the reset the row says the relay's state now, whole at 80 columns
            await pilot.press("ctrl+r")
            await wait_for(pilot, lambda: not app.session.outputs.estopped, what="reset")
            await wait_for(pilot, lambda: "refused" not in str(row.render()), 10, "cleared")
            await pilot.pause(0.2)
            assert_whole(app, row, "open - ready (switches only in silence)")

    asyncio.run(scenario())


# ---------------------------------------------------------------- whole at 80 x 24
def test_the_result_of_a_pick_shows_where_the_pick_is(plugins):
    """Devices: the relay board's row is below the fold at 80 x 24; what its pick did
    shows whole while that row is in view."""

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="devices")
        async with app.run_test(size=(80, 24)) as pilot:
            await wait_for(pilot, lambda: app.session.outputs is not None, what="outputs")
            relays = app.query_one("#relay-table", DataTable)
            await wait_for(pilot, lambda: relays.row_count > 0, 20, "relay boards listed")
            relays.focus()
            twin = next(
                i for i in range(relays.row_count) if "twin" in str(relays.get_row_at(i)[1])
            )
            relays.move_cursor(row=twin)
            await pilot.pause(0.2)
            await pilot.press("enter")
            result = app.query_one("#devices-result", Static)
            await wait_for(pilot, lambda: "in use" in str(result.render()), 20, "picked")
            await pilot.pause(0.3)
            assert_whole(app, result, str(result.render()))
            screen = app.screen.region
            assert screen.contains_region(relays.region.intersection(screen))
            assert relays.region.intersection(app.pane("devices").region).area > 0

    asyncio.run(scenario())


def test_the_reason_of_d_shows_whole(plugins, map_file):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="vibration")
        async with app.run_test(size=(80, 24)) as pilot:
            await _ready(app, pilot)
            pane = await _load_map(app, pilot, map_file)
            await wait_for(pilot, lambda: app.focused is pane.focus_target, what="grid")
            pane.move_cursor(1)  # a corner: no hand fits there
            await pilot.press("d")
            label = app.query_one("#vib-status")
            await wait_for(pilot, lambda: "hand" in pane.status_text, 20, "the reason")
            await pilot.pause(0.3)
            assert "point 1" in pane.status_text
            assert_whole(app, label, pane.status_text)

    asyncio.run(scenario())


def test_scenes_descriptions_show_whole_and_s_has_one_label(plugins):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="scenes")
        async with app.run_test(size=(80, 24)) as pilot:
            await wait_for(pilot, lambda: app.pane("scenes") is not None, what="scenes")
            pane = app.pane("scenes")
            await wait_for(pilot, lambda: app.focused is pane.focus_target, what="focused")
            await pilot.pause(0.3)
            demos = app.query_one("#demo-table", DataTable)
            for reg in app.ctx.pm.of("demo").values():
                assert_whole(app, demos, reg.description)
            scenes = app.query_one("#scene-table", DataTable)
            for name, reg in sorted(app.ctx.pm.of("scene").items())[:3]:  # those in view
                assert_whole(app, scenes, f"{name} {reg.plugin} {reg.description}")
            # the s key: one label, the footer's, in both hints
            hints = [_flat(h.render()) for h in pane.query(".hint").results(Static)]
            assert all("s stop" in h for h in hints), hints
            assert not any("s:" in h or "black" in h for h in hints), hints
            assert " s stop " in f" {_footer(app)} "

    asyncio.run(scenario())


# ---------------------------------------------------------------- the projector's holder
class _Link:
    def wait_connected(self, timeout):
        return True


class _Projector:
    """A running projector service (what ``ProjectorService`` reports)."""

    def __init__(self):
        self.link, self.scene = _Link(), None

    def start_scene(self, name, events=None):
        self.scene = name

    def stop_scene(self):
        self.scene = "black"

    def status(self):
        return {"connected": True, "scene": self.scene, "pid": 4242}


def test_the_scenes_screen_says_who_holds_the_projector(plugins):
    from plugins.demos.panel import status_text
    from plugins.studies.projected import ProjectedAnswers

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="scenes")
        async with app.run_test(size=(80, 24)) as pilot:
            await wait_for(pilot, lambda: app.pane("scenes") is not None, what="scenes")
            scenes = app.session.scenes
            line = app.query_one("#projector-status", Static)
            # starting for a study: not "not started"
            scenes.starting = ("exp2_hand", "P07's study run (Studies screen)")
            await wait_for(pilot, lambda: "starting" in str(line.render()), 5, "starting")
            assert "P07's study run" in str(line.render())
            scenes.starting = None
            scenes.service = _Projector()
            answers = ProjectedAnswers(app.session, None, "exp2_hand", by="P07's study run")
            await asyncio.to_thread(scenes.start, answers.scene, by=answers.by)
            await wait_for(pilot, lambda: "exp2_hand for" in str(line.render()), 5, "holder")
            assert "exp2_hand for P07's study run" in _flat(line.render())
            assert "not started" not in str(line.render())
            # black: nobody holds it; another scene (a demo's) is not the study's
            scenes.stop()
            assert "P07" not in status_text(scenes.status())
            scenes.service.scene = "knob"
            assert "P07" not in status_text(scenes.status())
            scenes.service = None

    asyncio.run(scenario())


# ---------------------------------------------------------------- footers, saved, range
def test_every_screen_s_footer_shows_the_screens_key(plugins):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="devices")
        async with app.run_test(size=(80, 24)) as pilot:
            await wait_for(pilot, lambda: app.session.outputs is not None, what="outputs")
            for tab, (_title, key, _reg) in app.tabs.items():
                await pilot.press(key)
                # (a loaded CI machine starting the camera's vision can hold a switch for
                # seconds: what is checked here is the footer, not the switch's time)
                await wait_for(pilot, lambda t=tab: app.active_tab == t, 30, tab)

                def complete() -> bool:  # the footer as drawn (it recomposes on a switch)
                    f = _footer(app)
                    return all(k in f for k in ("f1-f10 screens", "^e E-STOP", "? help"))

                await wait_for(pilot, complete, 10, f"{tab}'s footer: {_footer(app)!r}")

    asyncio.run(scenario())


def test_a_saved_signal_s_key_says_saved_until_it_changes(plugins):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="signals")
        async with app.run_test(size=(120, 40)) as pilot:
            await _ready(app, pilot)
            hint = app.query_one("#sig-hint", Static)
            name = app.query_one("#sig-name", Input)
            name.value = "mine"
            await pilot.pause(0.1)
            assert "^s save " in f"{_flat(hint.render())} " and "saved" not in _footer(app)
            await pilot.press("ctrl+s")
            await wait_for(pilot, lambda: "saved" in str(hint.render()), 10, "saved")
            await pilot.pause(0.2)
            assert "^s saved" in _footer(app) and "^s save " not in f"{_footer(app)} "
            expr = app.query_one("#sig-expr", Input)
            expr.value = expr.value + " * 50 %"
            await wait_for(pilot, lambda: "saved" not in str(hint.render()), 5, "changed")
            await pilot.pause(0.2)
            assert "^s save" in _footer(app) and "saved" not in _footer(app)

    asyncio.run(scenario())


def test_signals_says_the_piezo_range_the_gate_holds_and_where_it_comes_from(plugins):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="signals")
        async with app.run_test(size=(80, 24)) as pilot:
            await _ready(app, pilot)
            prof = app.ctx.profile
            lo, hi = float(prof.get("limits.piezo_min_v")), float(prof.get("limits.piezo_max_v"))
            card = float(prof.get("audio.full_scale_v")) * float(prof.get("amplifiers.piezo_gain"))
            app.query_one("#sig-expr", Input).value = "sine(250 Hz, 150 V, 1 s) * ramp(20 ms)"
            await pilot.press("ctrl+o")
            status = app.query_one("#sig-status", Static)
            await wait_for(pilot, lambda: "piezo range" in str(status.render()), 20, "refused")
            said = _flat(status.render())
            gate = f"{max(lo, -card):g}..{min(hi, card):+g} V"
            assert gate in said, said
            assert f"piezo_min_v..piezo_max_v = {lo:g}..{hi:+g} V" in said, said
            assert f"+-{card:g} V" in said and "full scale" in said, said
            await pilot.pause(0.2)
            assert_whole(app, status, said)

    asyncio.run(scenario())
