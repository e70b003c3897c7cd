"""Issue 27 (ui c), a new operator at 80 x 24 on Devices, Vibration, Relays and
Electrostatic: a focused list's Enter first in the footer (on a row where Enter acts), a
status line that says what is true now (a lapsed question leaves it; a refusal because a
run holds the outputs leaves it when the run ends), a key and its word or a number and its
unit never split across lines, the doctor's checks all on Devices with nothing cut, the
self-test's time said before it starts and its progress while it runs, and one name per
test stimulus."""

from __future__ import annotations

import asyncio
import threading
from pathlib import Path

import numpy as np
from textual.widgets import DataTable, Footer

from console.cli.main import Context
from console.tui.app import HapTableApp
from console.tui.kept_text import wrap_kept

from .conftest import wait_for
from .test_camera_layout import screen_lines, text_in

HINT = (
    "enter: audition the highlighted item   + -: amplitude   [ ]: frequency   "
    "t: waveform   p: play the setting"
)


def test_wrapped_lines_keep_a_key_with_its_word_and_a_number_with_its_unit():
    for width in range(24, 60):
        lines = wrap_kept(HINT, width).plain.split("\n")
        assert all(len(line) <= width for line in lines), (width, lines)
        assert not any(line.rstrip().endswith(("t:", "+ -:", "[ ]:", "p:")) for line in lines)
        assert " ".join(" ".join(lines).split()) == " ".join(HINT.split())  # nothing lost
    said = "sine-PA played on 'twin' through the gate: piezo 20.0 V peak, screen 0.0 V peak"
    for width in range(30, 80):
        lines = wrap_kept(said, width).plain.split("\n")
        assert "screen 0.0 V peak" in lines[-1] or "screen 0.0 V peak" in lines[-2], lines
        assert not any(line.split()[-1] in ("V", "0.0", "screen") for line in lines), lines


def test_one_name_per_test_stimulus_and_old_names_still_play():
    from console.config.signal_library import BUILTIN
    from console.signals.stimuli import STIMULI, make_stimulus

    screen = [name for name in STIMULI if name.startswith("screen")]
    assert screen == ["screen-180"] and "screen-180" in BUILTIN
    plan = make_stimulus("screen-180hz", 8000)  # a saved script's old name
    assert plan.name == "screen-180" and plan.duration_s == 1.0


def test_selftest_estimate_is_the_chirps_it_plays(profile):
    from plugins.vibrotactile.selftest import FULL, QUICK, planned_s

    # independent: each path plays sweep_s + tail_s once (repeats 1), PALL only in full
    assert planned_s(profile) == (5 * (FULL.sweep_s + FULL.tail_s) * FULL.repeats, 5)
    assert planned_s(profile, quick=True)[1] == 4 and not QUICK.pall


def test_frf_legend_names_its_unit():
    from console.tui.plots import frf_series

    f = np.linspace(0.0, 600.0, 61)
    series = frf_series(f, np.ones((2, 61)) * 0.104, ["PA", "PB"], mark_hz=250.0)
    assert series[0].label == "PA 0.104 µm/V", series[0].label


def _footer(app) -> str:
    return text_in(app, app.screen.query_one(Footer))


def test_new_operator_at_80x24(plugins, monkeypatch):
    import console.tui.panes.devices_selftest as devices_mod
    import console.tui.panes.vibration as vibration_mod
    import console.tui.panes.vibration_measure as vibration_measure_mod

    gate = threading.Event()

    def slow_selftest(profile, pm):  # the real run plays 5 s of chirps: the UI's part only
        gate.wait(10)
        return True, "self-test: all paths healthy (2 s)"

    monkeypatch.setattr(devices_mod, "run_selftest", slow_selftest)
    monkeypatch.setattr(vibration_measure_mod, "MEASURE_AGAIN_S", 0.6)

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="devices")
        async with app.run_test(size=(80, 24)) as pilot:
            pane = app.pane("devices")
            cards = pane.query_one("#audio-table", DataTable)
            await wait_for(pilot, lambda: app.focused is cards and cards.row_count >= 2, 30)
            await wait_for(pilot, lambda: _footer(app).startswith("⏎ use"), 10, "enter shown")
            # the cursor starts on the card in use, where Enter acts
            key = cards.coordinate_to_cell_key(cards.cursor_coordinate).row_key.value
            assert pane.audio_rows[key][0] == "twin", key
            for key in ("d doctor", "t test", "s self-test", "^e E-STOP"):
                assert key in _footer(app), (key, _footer(app))
            # the doctor's checks, as `haptable doctor`, nothing cut
            doc = pane.query_one("#device-table", DataTable)
            await wait_for(pilot, lambda: doc.row_count >= 7, 20, "doctor rows")
            rows = range(doc.row_count)
            names = [" ".join(str(c) for c in doc.get_row_at(i)[:2]) for i in rows]
            # (the self-test's row as doctor says its quick part: skipped, no baseline yet)
            for name in ("realtime memory", "realtime scheduling", "selftest quick"):
                assert name in names, names
            doc.focus()
            await pilot.pause(0.1)
            shown = text_in(app, doc)
            assert "…" not in shown and "piezo, screen" in shown, shown
            await wait_for(pilot, lambda: _footer(app).startswith("⏎ whole row"), 10, "its enter")
            # the self-test says how long before it starts, then how far it is
            await pilot.press("s", "s")  # the first asks
            await wait_for(pilot, lambda: " left" in pane.result, 10, "progress")
            assert "self-test: measuring the twin's vibration map first" in pane.result
            gate.set()
            await wait_for(pilot, lambda: "healthy" in pane.result, 10, "the result")
            # a refusal because a run holds the outputs leaves when the run ends
            with app.session.hold_outputs("P01's study run (Studies screen)"):
                await pilot.press("t")
                await wait_for(pilot, lambda: "holds the outputs" in pane.result, 20)
                await pilot.pause(0.7)
                assert "holds the outputs" in pane.result  # still true: still said
            await wait_for(pilot, lambda: "has ended" in pane.result, 5, "refusal lapsed")

            # Electrostatic: the list's Enter first, its hint never splits "t: waveform"
            await pilot.press("f5")
            es = app.pane("electrostatic")
            await wait_for(pilot, lambda: es and app.focused is es.focus_target, 30)
            await wait_for(pilot, lambda: _footer(app).startswith("⏎ audition"), 10)
            for key in ("p play", "t sine/square", "+ - Vpp", "[ ] Hz"):
                assert key in _footer(app), (key, _footer(app))
            # the pane's hint is drawn at the screen's next refresh after the focus moved
            await wait_for(
                pilot,
                lambda: any("t: waveform" in line for line in screen_lines(app)),
                10,
                "the Electrostatic hint",
            )

            # Relays: the focused switch's Enter
            await pilot.press("f4")
            await wait_for(pilot, lambda: _footer(app).startswith("⏎ toggle"), 20)

            # Vibration: "x: cancel" on one line; a lapsed question leaves the line
            await pilot.press("f3")
            vib = app.pane("vibration")
            await wait_for(pilot, lambda: vib and app.focused is vib.focus_target, 30)
            await wait_for(pilot, lambda: any("x: cancel" in s for s in screen_lines(app)), 10)
            kept = Path(vibration_mod.__file__)  # a file there: m asks before replacing it
            monkeypatch.setattr(type(vib.service), "cached_map_path", lambda self: kept)
            await pilot.press("m")
            assert vib.status_text.startswith("m again within"), vib.status_text
            await wait_for(pilot, lambda: "m again" not in vib.status_text, 5, "question gone")

    asyncio.run(scenario())
