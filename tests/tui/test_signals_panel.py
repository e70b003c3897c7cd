"""The Signals screen as an operator uses it: type an expression, see its waveform and
spectrum, save it, play it on PA and on the screen (the twin's amplifiers got the samples
the gate passed), and a bad expression as one line."""

from __future__ import annotations

import asyncio
import tomllib

import numpy as np
import pytest
from textual.widgets import Input, OptionList, Static

from console.cli.main import Context
from console.config.signal_library import add_signal, library_path
from console.signals.design import render
from console.signals.expr import parse
from console.tui.app import HapTableApp
from console.tui.charts import Chart

from .conftest import wait_for

TYPED = "sine(200 Hz, 30 V, 0.3 s)*ramp(10 ms)"


def _status(app) -> str:
    return str(app.query_one("#sig-status", Static).render())


async def _type(pilot, text: str) -> None:
    for ch in text:
        await pilot.press(
            {
                " ": "space",
                "(": "left_parenthesis",
                ")": "right_parenthesis",
                ",": "comma",
                "*": "asterisk",
                ".": "full_stop",
            }.get(ch, ch)
        )


def test_design_save_and_play_on_a_patch_and_the_screen(plugins):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="signals")
        async with app.run_test(size=(80, 24)) as pilot:
            await wait_for(pilot, lambda: app.session.outputs is not None, 20, "outputs open")
            expr = app.query_one("#sig-expr", Input)
            await wait_for(pilot, lambda: app.focused is expr, 10, "expression focused")
            expr.value = ""
            await _type(pilot, TYPED)
            assert expr.value == TYPED
            await pilot.press("enter")
            wave = app.query_one("#sig-wave", Chart)
            spec = app.query_one("#sig-spectrum", Chart)
            await wait_for(pilot, lambda: "200.0 Hz" in _status(app), 10, "preview")
            assert "0.300 s, peak 30.00 V" in _status(app)
            assert (
                "waveform on PA" in wave.summary() and "x: time (s); y: piezo (V)" in wave.summary()
            )
            shown = wave.render().plain
            assert "time (s)" in shown and "30" in shown  # drawn, with its axis
            ((label, f, db),) = spec.drawn(columns=10_000)
            assert abs(f[np.argmax(db)] - 200.0) < 5  # the spectrum peaks at the tone
            assert not app.session.played  # nothing played yet: the plots come first

            app.query_one("#sig-name", Input).value = "probe-tone"
            await pilot.press("ctrl+s")
            await wait_for(pilot, lambda: "saved probe-tone" in _status(app), 5, "saved")
            saved = tomllib.loads(library_path("sim").read_text())["signals"]
            assert saved["probe-tone"]["expr"] == TYPED
            names = [o.id for o in app.query_one("#sig-library", OptionList).options]
            assert "probe-tone" in names and "sweep" in names

            await pilot.press("ctrl+o")
            await wait_for(pilot, lambda: "played probe-tone on PA" in _status(app), 20, "PA")
            want = render(parse(TYPED), 48_000)
            rec = app.session.outputs.recording()
            piezo = rec[:, 0]
            k = int(np.flatnonzero(piezo)[0]) - int(np.flatnonzero(want)[0])
            np.testing.assert_allclose(piezo[k : k + want.size], want, atol=1e-9)
            assert not rec[:, 1].any()

            n = rec.shape[0]
            app.query_one("#sig-target", Input).value = "screen"
            await pilot.press("ctrl+o")
            await wait_for(
                pilot,
                lambda: "on screen" in _status(app) and "played" in _status(app),
                20,
                "screen",
            )
            screen = app.session.outputs.recording()[n:, 1]
            assert abs(np.max(np.abs(screen)) - 30.0) < 0.01
            assert "waveform on screen" in wave.summary()

            played = len(app.session.played)
            expr.value = "sine(200, 30 V, 1 s)"
            await pilot.press("ctrl+o")
            await wait_for(pilot, lambda: "needs a unit" in _status(app), 5, "error line")
            assert "\n" not in _status(app) and "write 200 Hz" in _status(app)
            assert len(app.session.played) == played  # refused: nothing played
            assert "no signal" in wave.render().plain

    asyncio.run(scenario())


def test_refusals_and_loading_from_the_library(plugins):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="signals")
        async with app.run_test(size=(80, 24)) as pilot:
            await wait_for(pilot, lambda: app.session.outputs is not None, 20, "outputs open")
            await wait_for(pilot, lambda: "dominant" in _status(app), 10, "first preview")
            expr = app.query_one("#sig-expr", Input)
            expr.value = "sine(250 Hz, 20 V, 0.5 s)"  # no ramp
            await pilot.press("ctrl+o")
            await wait_for(pilot, lambda: "ramp(5 ms)" in _status(app), 10, "ramp refusal")
            assert "ends at" in _status(app) and "ctrl+t adds it" in _status(app)
            assert "[limits] ramp_min_ms" in _status(app)  # brackets show literally
            assert not app.session.played
            await pilot.press("ctrl+t")  # the operator adds the ramp, visibly
            assert expr.value == "(sine(250 Hz, 20 V, 0.5 s)) * ramp(5 ms)"
            assert expr.cursor_position == len(expr.value)  # typing goes on at the end
            await pilot.press("ctrl+o")
            await wait_for(pilot, lambda: "played" in _status(app), 20, "played with its ramp")
            assert len(app.session.played) == 1
            lib = app.query_one("#sig-library", OptionList)
            lib.focus()
            await pilot.press("home", "down", "down", "enter")  # the third entry: sweep
            # over the typed expression (not in the library) enter asks first
            await wait_for(pilot, lambda: "enter again within" in _status(app), 5, "asked")
            await pilot.press("enter")
            await wait_for(pilot, lambda: expr.value.startswith("chirp("), 5, "loaded")
            assert app.query_one("#sig-name", Input).value == "sweep"
            pane = app.pane("signals")  # its preview's line first (it would overwrite the next)
            await wait_for(pilot, lambda: pane.preview and pane.preview.expr == expr.value, 10)
            await pilot.press("delete")
            await wait_for(pilot, lambda: "read-only" in _status(app), 5, "built-in kept")

            # saved from the command line while the console runs: there when shown again
            add_signal(library_path("sim"), "from-cli", "silence(1 s)")
            await pilot.press("f1")
            await wait_for(pilot, lambda: app.query_one("#tabs").active == "devices", 5, "f1")
            await pilot.press("f8")
            await wait_for(pilot, lambda: "from-cli" in [o.id for o in lib.options], 5, "reload")

    asyncio.run(scenario())


def test_estop_stops_an_audition(plugins):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=False, initial="signals")
        async with app.run_test(size=(80, 24)) as pilot:
            await wait_for(pilot, lambda: app.session.outputs is not None, 20, "outputs open")
            await wait_for(pilot, lambda: "dominant" in _status(app), 10, "first preview")
            app.query_one("#sig-expr", Input).value = "sine(250 Hz, 20 V, 20 s) * ramp(10 ms)"
            await pilot.press("ctrl+o")
            await wait_for(pilot, lambda: app.session.output_status()[0]["busy"], 10, "playing")
            await pilot.press("ctrl+e")
            await wait_for(pilot, lambda: "e-stop" in _status(app).lower(), 10, "e-stopped")
            out = app.session.outputs
            assert out.estopped
            await wait_for(pilot, lambda: not out.status()["busy"], 10, "silent")
            assert "played" not in _status(app)

    asyncio.run(scenario())


def test_a_chirp_draws_a_flat_band_on_the_log_frequency_axis(plugins):
    """A linear chirp spreads its energy evenly over its band: the spectrum as drawn (at
    80 columns, log-x) is flat across it, with points all along it, low end included; a
    sine draws one peak at its frequency, not a ramp up to it."""

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="signals")
        async with app.run_test(size=(80, 24)) as pilot:
            expr = app.query_one("#sig-expr", Input)
            await wait_for(pilot, lambda: app.focused is expr, 10, "expression focused")
            spec = app.query_one("#sig-spectrum", Chart)
            expr.value = "chirp(10 Hz, 625 Hz, 20 V, 1 s)"
            await pilot.press("enter")
            pane = app.pane("signals")  # the chirp's, not the first preview's (a race)
            drawn = lambda: pane.preview is not None and pane.preview.expr == expr.value  # noqa: E731
            await wait_for(pilot, lambda: drawn() and bool(spec.series), 10, "spectrum drawn")
            ((_label, f, db),) = spec.drawn()
            assert f.size <= max(10, spec.size.width)
            band = (f >= 10.0) & (f <= 625.0)
            assert np.count_nonzero(band) >= 10, f  # the band has columns, not one point
            # away from the chirp's ends (a Fresnel edge about sqrt(615 Hz/s) wide)
            inner = (f >= 50.0) & (f <= 575.0)
            assert np.count_nonzero(inner) >= 6
            assert np.ptp(db[inner]) < 3.0, (f[inner], db[inner])
            # the level by stationary phase: A / (T sqrt(rate)) as a sine's peak reads A
            level = 20 * np.log10(20.0 / (1.0 * np.sqrt(615.0)))
            assert abs(np.median(db[inner]) - level) < 0.5
            assert db[f > 1000.0].max() < level - 15  # nothing above the band
            expr.value = "sine(250 Hz, 20 V, 1 s)"
            await pilot.press("enter")
            await wait_for(
                pilot, lambda: abs(spec.drawn()[0][1][np.argmax(spec.drawn()[0][2])] - 250) < 1
            )
            ((_label, f, db),) = spec.drawn()
            assert db.max() == pytest.approx(20 * np.log10(20.0), abs=0.1)
            assert db[(f > 2.0) & (f < 150.0)].max() < db.max() - 60  # no ramp up to it

    asyncio.run(scenario())
