"""The console does nothing while nothing changes: an idle screen is not redrawn, a
hidden screen does no per-tick work, and a change (an e-stop, a relay switched here or
elsewhere) still shows. Behaviour only: the CPU and the delays are measured by
``haptable bench console-idle``."""

from __future__ import annotations

import asyncio
import collections
import re
import threading
from types import SimpleNamespace

import numpy as np
import pytest
from textual.app import App
from textual.widget import Widget
from textual.widgets import Switch

from console.cli.main import Context
from console.tui.app import HapTableApp
from console.tui.halfblock_view import HalfBlockView
from console.tui.live import status_key
from console.tui.plots import HalfBlockImage
from console.tui.safety_bar import SafetyBar

from .conftest import app_processed, wait_for

SIZES = [(80, 24), (120, 40)]
#: the screens with nothing live on them (Camera and Latency show the camera loop,
#: Signals' expression line blinks its cursor)
STILL = ["devices", "vibration", "relays", "electrostatic", "scenes", "scope", "studies"]


def _bar(app) -> str:
    return str(app.query_one("#safety", SafetyBar).render())


def _bar_idle(app) -> bool:
    """The bar says the outputs are open and idle (at any width)."""
    return "outputs idle" in _bar(app) or "| idle |" in _bar(app)


class RefreshCounter:
    """``Widget.refresh`` calls per widget while installed (``monkeypatch``)."""

    def __init__(self, monkeypatch) -> None:
        self.calls: collections.Counter = collections.Counter()
        original = Widget.refresh

        def counting(widget, *args, **kw):
            self.calls[widget] += 1
            return original(widget, *args, **kw)

        monkeypatch.setattr(Widget, "refresh", counting)

    def within(self, root: Widget) -> dict[str, int]:
        """The calls on ``root`` and the widgets inside it, by widget."""
        return {
            f"{type(w).__name__}#{w.id}": n
            for w, n in self.calls.items()
            if w is root or root in w.ancestors
        }


async def _idle(app, pilot) -> None:
    """Outputs open, the bar drawn with them, the first draw of the screen over."""
    await wait_for(pilot, lambda: app.session.outputs is not None, 30, "outputs open")
    await wait_for(pilot, lambda: _bar_idle(app), 10, "the bar: outputs idle")
    await pilot.pause(0.5)


@pytest.mark.parametrize("tab", STILL)
def test_an_idle_screen_is_not_redrawn(plugins, monkeypatch, tab):
    """At each of the sizes: the first as the console starts, the next after the terminal
    is resized to it (one console start per screen)."""

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial=tab)
        async with app.run_test(size=SIZES[0]) as pilot:
            await _idle(app, pilot)
            pane = app.pane(tab)
            await wait_for(pilot, lambda: pane.is_mounted, 10, "pane mounted")
            for size in SIZES:
                if tuple(app.size) != size:
                    await pilot.resize_terminal(*size)
                    await wait_for(pilot, lambda s=size: tuple(app.size) == s, 10, f"{size}")
                await pilot.pause(1.0)  # a screen's first work (a doctor run, a listing) ends
                shown = collections.Counter()
                if hasattr(pane, "show_state"):
                    original = pane.show_state

                    def counting(status, log, _shown=shown, _original=original):
                        _shown["show_state"] += 1
                        _original(status, log)

                    monkeypatch.setattr(pane, "show_state", counting)
                bar = app.query_one("#safety", SafetyBar)
                draws = bar.draws
                refreshes = RefreshCounter(monkeypatch)
                polls, changes = app.live.watch.polls, app.live.watch.changes
                await pilot.pause(1.2)
                assert app.live.watch.polls > polls, size  # the outputs were read meanwhile;
                # a screen hears only of changes (none, unless an underrun on a loaded machine)
                assert shown["show_state"] <= app.live.watch.changes - changes, size
                assert bar.draws == draws, size  # the bar's text stayed the same: not redrawn
                assert refreshes.within(pane) == {}, size
                assert refreshes.within(bar) == {}, size

    asyncio.run(scenario())


@pytest.mark.parametrize("size", SIZES)
def test_an_estop_reaches_the_bar_by_its_event_alone(plugins, size):
    """The periodic read is put off for an hour: the e-stop's session event (from
    another thread, as `haptable estop` in a shell or a demo's watchdog) is what brings
    the bar up to date; the reset too."""

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="relays")
        async with app.run_test(size=size) as pilot:
            await _idle(app, pilot)
            app.live.watch.poll_s = 3600.0
            app.live.watch.poke()  # the watch now sleeps for the hour
            await pilot.pause(0.2)
            polls = app.live.watch.polls
            threading.Thread(target=app.session.estop, args=("from a shell",)).start()
            await wait_for(pilot, lambda: "E-STOP: from a shell" in _bar(app), 10, "e-stop")
            assert app.live.watch.polls <= polls + 2  # read on the event, not a timer
            assert "ctrl+r" in _bar(app)
            assert "open - e-stop active" in str(app.query_one("#interlock-1").render())
            await pilot.press("ctrl+r")
            await wait_for(pilot, lambda: _bar_idle(app), 10, "reset")
            assert "ready" in str(app.query_one("#interlock-1").render())

    asyncio.run(scenario())


@pytest.mark.parametrize("size", SIZES)
def test_a_relay_switch_shows_here_and_from_elsewhere(plugins, size):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="relays")
        async with app.run_test(size=size) as pilot:
            await _idle(app, pilot)
            switch1 = app.query_one("#relay-1", Switch)
            await pilot.press("1")  # the operator's key
            await wait_for(pilot, lambda: "relays closed: 1" in _bar(app), 10, "bar")
            await wait_for(pilot, lambda: switch1.value, 10, "switch 1 on")
            log = app.query_one("#relaylog")
            await wait_for(pilot, lambda: log.row_count == 1, 10, "logged")
            # another client of the table (a demo, a script) switches relay 2
            out = app.session.outputs
            threading.Thread(target=out.set_relays, args=({1, 2},)).start()
            switch2 = app.query_one("#relay-2", Switch)
            await wait_for(pilot, lambda: switch2.value, 10, "switch 2 on")
            await wait_for(pilot, lambda: "relays closed: 1,2" in _bar(app), 10, "bar")
            await wait_for(pilot, lambda: log.row_count == 2, 10, "logged")

    asyncio.run(scenario())


def test_a_hidden_screen_does_no_per_tick_work(plugins, monkeypatch):
    """Camera, Latency, Scope and Relays opened and left: no timer of theirs runs, no
    draw; the relays switched meanwhile show at once when Relays opens again."""

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="devices")
        async with app.run_test(size=(120, 40)) as pilot:
            await _idle(app, pilot)
            for key, tab in (
                ("f2", "camera"),
                ("f7", "latency"),
                ("f9", "scope"),
                ("f4", "relays"),
            ):
                await pilot.press(key)
                await wait_for(pilot, lambda t=tab: app.pane(t) is not None, 10, tab)
                await wait_for(pilot, lambda t=tab: app.pane(t).is_mounted, 10, tab)
                await pilot.pause(0.5)
            await pilot.press("f1")
            await wait_for(pilot, lambda: app.active_tab == "devices", 10, "devices")
            await pilot.pause(0.3)
            camera, latency, scope, relays = (
                app.pane(t) for t in ("camera", "latency", "scope", "relays")
            )
            assert camera._timer is None and latency._timer is None and scope._timer is None
            ticks = collections.Counter()
            for pane, name in (
                (camera, "redraw"),
                (latency, "show_loop"),
                (scope, "tick"),
                (relays, "show_state"),
            ):
                original = getattr(pane, name)

                def counting(*args, _name=name, _original=original):
                    ticks[_name] += 1
                    return _original(*args)

                monkeypatch.setattr(pane, name, counting)
            refreshes = RefreshCounter(monkeypatch)
            # the outputs change (another client switches a relay) while Relays is hidden
            threading.Thread(target=app.session.outputs.set_relays, args=({3},)).start()
            await wait_for(pilot, lambda: "relays closed: 3" in _bar(app), 10, "bar")
            await pilot.pause(1.0)
            assert ticks == {}
            for pane in (camera, latency, scope, relays):
                assert refreshes.within(pane) == {}, pane
            assert not app.session.camera.watched  # no loop runs for a hidden screen
            await pilot.press("f4")
            await wait_for(pilot, lambda: app.query_one("#relay-3", Switch).value, 10, "shown")
            assert ticks["show_state"] >= 1

    asyncio.run(scenario())


@pytest.mark.parametrize("size", SIZES)
def test_the_camera_view_converts_and_draws_only_what_changed(plugins, monkeypatch, size):
    """The same frame is not converted again; a new frame whose pixels moved by less
    than a grey step (sensor noise) draws nothing; a bright patch redraws only the
    rows it covers, and they show it."""

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="camera")
        async with app.run_test(size=size) as pilot:
            pane = app.pane("camera")
            await wait_for(pilot, lambda: pane.shown is not None, 30, "a picture")
            rng = np.random.default_rng(2)
            base = rng.uniform(60.0, 200.0, (480, 640))
            base[:, :40], base[:, -40:] = 0.0, 255.0  # black and white in view: a palm
            # does not move the grey levels shown (that would redraw the whole picture)
            now = {"frame": SimpleNamespace(image=base)}
            # the picture takes what the camera service shows (processed or a preview)
            for name in ("snapshot", "to_show"):
                monkeypatch.setattr(app.session.camera, name, lambda: (now["frame"], {}))
            # a fresh picture of these frames: grey levels set from them (they follow a
            # new scene over ~1 s of frames, and a palm drawn while they crawl up from
            # the twin's dark frames would be white on white), no cells kept from before
            pane._stretches.clear()
            pane._drawn = None
            view = app.query_one("#camera-view", HalfBlockView)
            await wait_for(pilot, lambda: view.picture is pane.shown, 10, "drawn")
            # the same frame: not converted again once the grey levels have settled on
            # it (on a loaded machine they may still follow it for a few redraws)
            for _ in range(20):
                await pilot.pause(0.3)
                draws, rows, shown = pane.draws, view.rows_drawn, pane.shown
                await pilot.pause(0.5)
                if pane.shown is shown and pane.draws == draws:
                    break
            assert pane.shown is shown and pane.draws == draws
            for _ in range(6):  # new frames, noise only
                now["frame"] = SimpleNamespace(image=base + rng.normal(0.0, 0.5, base.shape))
                await pilot.pause(0.12)
            assert pane.draws == draws and view.rows_drawn == rows
            bright = base.copy()
            bright[200:260, 100:300] = 255.0  # a hand's palm
            now["frame"] = SimpleNamespace(image=bright)
            before = [view.render_line(y).text for y in range(pane.shown.size[1])]
            styles = [list(view.render_line(y)) for y in range(pane.shown.size[1])]
            await wait_for(pilot, lambda: pane.draws > draws, 30, "the palm drawn")
            changed = view.rows_drawn - rows
            assert 0 < changed < pane.shown.size[1] // 2  # its rows, not the picture
            # the palm's rows (200-260 of 480) are painted anew, the rows far from it not
            cols, n = pane.shown.size
            palm = range(200 * n // 480, 260 * n // 480 + 1)
            now_lines = [list(view.render_line(y)) for y in range(n)]
            assert all(now_lines[y] != styles[y] for y in palm[1:-1])
            assert all(
                now_lines[y] == styles[y] for y in range(n) if abs(y - 230 * n // 480) > n // 4
            )
            assert [view.render_line(y).text for y in range(n)] == before  # ▀ cells alike

    asyncio.run(scenario())


# ---------------------------------------------------------------------- pieces
def _status(**gate) -> dict:
    base = {"estopped": False, "estop_reason": "", "clock": 0, "quiet_samples": 0}
    base |= {"level_v": [0.0, 0.0], "relays_closed": []}
    return {
        "gate": base | gate,
        "audio": {"underruns": 0, "blocks": 1, "fill_ms": {"p50_ms": 0.02}},
        "relays": {"switches": 0},
        "busy": False,
        "latency_samples": 3,
        "kernel": {"requests": {"status": {"n": 1}}, "clients": ["console"]},
    }


def test_the_status_key_changes_only_with_what_shows():
    key = status_key(_status())
    churn = _status(clock=48000, quiet_samples=48000)
    churn["audio"] |= {"blocks": 750, "fill_ms": {"p50_ms": 0.03}}
    churn["latency_samples"] = 99
    churn["kernel"]["requests"] = {"status": {"n": 40}}
    assert status_key(churn) == key
    assert status_key(_status(level_v=[0.04, -0.04])) == key  # shows as zero
    assert status_key(_status(level_v=[1.0, 0.0])) != key
    assert status_key(_status(estopped=True, estop_reason="x")) != key
    assert status_key(_status(relays_closed=[1])) != key
    more = _status()
    more["relays"]["switches"] = 1
    assert status_key(more) != key
    assert status_key(None, "starting") != status_key(None, "no sound card")


def test_a_halfblock_picture_redraws_only_the_rows_that_changed():
    rng = np.random.default_rng(1)
    grey = rng.uniform(0, 255, (12, 10))
    a = HalfBlockImage(grey, None, {(1, 2): "7"})
    assert a.changed_rows(HalfBlockImage(grey.copy(), None, {(1, 2): "7"})) == []
    moved = grey.copy()
    moved[9, 4] = 255 - moved[9, 4]
    assert a.changed_rows(HalfBlockImage(moved, None, {(1, 2): "7"})) == [4]
    assert a.changed_rows(HalfBlockImage(grey, None, {(2, 2): "7"})) == [1, 2]
    assert a.changed_rows(HalfBlockImage(grey[:10], None)) == list(range(6))  # resized

    async def scenario():
        class One(App):
            def compose(self):
                yield HalfBlockView("waiting", id="v")

        app = One()
        async with app.run_test(size=(40, 12)) as pilot:
            view = app.query_one(HalfBlockView)
            assert view.show_picture(a) == 6  # the first picture: every row
            await app_processed(app)
            refreshes = collections.Counter()
            original = view.refresh

            def counting(*regions, **kw):
                refreshes["rows"] += len(regions) or 99
                return original(*regions, **kw)

            view.refresh = counting
            assert view.show_picture(HalfBlockImage(grey.copy(), None, {(1, 2): "7"})) == 0
            assert refreshes["rows"] == 0
            assert view.show_picture(HalfBlockImage(moved, None, {(1, 2): "7"})) == 1
            assert refreshes["rows"] == 1  # one line repainted
            await pilot.pause(0.05)
            # the repainted line is the new picture's row
            new = HalfBlockImage(moved, None, {(1, 2): "7"}).row_segments(4)
            assert [(s.text, s.style) for s in view.render_line(4)] == [
                (s.text, s.style) for s in new
            ]
            view.update("camera stopped")
            await pilot.pause(0.05)
            assert "camera stopped" in view.render_line(0).text

    asyncio.run(scenario())


@pytest.mark.parametrize("size", SIZES)
def test_the_camera_s_live_numbers_change_without_laying_the_screen_out(plugins, monkeypatch, size):
    """The twin's hand comes and goes (its lines on the side panel with it) and the
    numbers change twice a second: the rows keep their place, so the screen is not laid
    out again for them (a layout costs more than the numbers' repaint)."""

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="camera")
        async with app.run_test(size=size) as pilot:
            pane = app.pane("camera")
            await wait_for(pilot, lambda: pane.shown is not None, 30, "a picture")
            info = app.query_one("#camera-info")
            rates = re.compile(r"camera \d+ fps.*?, vision \d+ fps", re.S)  # counted, vision on
            await wait_for(pilot, lambda: rates.search(str(info.render())), 30, "the rates")
            await pilot.pause(2.0)  # the hand seen once: its rows are kept from then on
            layouts = collections.Counter()
            laid: list = []  # the text each layout was for
            texts = set()
            original = Widget.refresh

            def counting(widget, *args, layout=False, **kw):
                if layout and widget is info:
                    layouts["info"] += 1
                    laid.append(pane._said.get("camera-info"))
                return original(widget, *args, layout=layout, **kw)

            monkeypatch.setattr(Widget, "refresh", counting)
            comings = 0  # the hand's lines came or went (each laid the screen out before)
            had = None
            for _ in range(50):
                text = str(info.render())
                texts.add(text)
                comings += had is not None and had != ("hand at" in text)
                had = "hand at" in text
                await pilot.pause(0.2)
            # the numbers changed meanwhile, in their rows: a row seen for the first time
            # (a loaded machine's "skipped" count) may lay it out a few times, not once
            # per change of the hand's lines
            assert len(texts) >= 5, texts
            assert layouts["info"] <= max(4, comings // 2), (comings, laid)

    asyncio.run(scenario())


@pytest.mark.parametrize("size", SIZES)
def test_the_camera_title_follows_the_grey_levels_without_laying_the_screen_out(
    plugins, monkeypatch, size
):
    """The view's title names the grey levels shown; as they follow the frames its text
    grows and shrinks (``grey 3 to 59`` -> ``grey 42 to 219``): each text shows whole,
    and the screen is not laid out again for it while it fits the picture's width (the
    title keeps that width: a longer one says the levels alone, cut to it, never
    widening the picture's column)."""

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="camera")
        async with app.run_test(size=size) as pilot:
            pane = app.pane("camera")
            await wait_for(pilot, lambda: pane.shown is not None, 30, "a picture")

            def ramp(lo: float, hi: float) -> np.ndarray:  # dark left, bright right
                return np.tile(np.linspace(lo, hi, 640), (480, 1))

            now = {"frame": SimpleNamespace(image=ramp(2.0, 60.0))}
            for name in ("snapshot", "to_show"):
                monkeypatch.setattr(app.session.camera, name, lambda: (now["frame"], {}))
            pane._stretches.clear()  # the levels set from these frames, not the twin's
            pane._drawn = None
            title = app.query_one("#camera-title")
            dark, bright = re.compile(r"grey \d to \d\d\b"), re.compile(r"grey \d\d to \d\d\d\b")
            await wait_for(pilot, lambda: dark.search(str(title.render())), 30, "dark levels")
            layouts = collections.Counter()  # the title's updates that lay the screen out
            update = title.update

            def counting(*args, layout: bool = True, **kw):
                layouts["title"] += layout
                return update(*args, layout=layout, **kw)

            monkeypatch.setattr(title, "update", counting)
            cols, text = pane.shown.size[0], pane._said["camera-title"].rstrip()
            seen = {text}  # the dark levels; a loaded machine may step to the bright at once
            needed = 0  # the title's length changed where it is longer than the picture
            for _ in range(200):  # brighter frames: the levels shown climb to 42 to 219
                now["frame"] = SimpleNamespace(image=ramp(40.0, 220.0))
                await pilot.pause(0.1)
                before, text = text, pane._said["camera-title"].rstrip()
                needed += len(before) != len(text) and max(len(before), len(text)) > cols
                assert text in str(title.render()), text  # the whole text shows
                assert title.size.width >= min(len(text), cols)
                seen.add(text)
                if bright.search(text):
                    break
            assert bright.search(text), seen
            assert len({len(t) for t in seen}) >= 2, seen  # the text's length changed
            assert layouts["title"] == needed, (cols, seen)

    asyncio.run(scenario())
