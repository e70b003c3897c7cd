"""The Devices screen: pick a sound card and a relay board (saved to the profile's override
file, the outputs reopened with them), play a named test signal through the gate."""

from __future__ import annotations

import asyncio

import numpy as np
from textual.widgets import DataTable, Static

from console.cli.main import main
from console.config.plugins import load_plugins
from console.config.profile import load_profile, overrides_path
from console.runtime.context import Context
from console.tui.app import HapTableApp

from .conftest import wait_for


def _module(name: str):
    """A test plugin module of ``card_plugins`` (the table's outputs process loads it
    from its file too)."""
    import importlib.util
    from pathlib import Path

    file = Path(__file__).parent / "card_plugins" / f"{name}.py"
    spec = importlib.util.spec_from_file_location(f"haptable_test_{name}", file)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def _bench_card_plugin():
    return _module("bench_card")


def _row_of(table: DataTable, text: str) -> int | None:
    for i in range(table.row_count):
        if any(text in str(c) for c in table.get_row_at(i)):
            return i
    return None


async def _select(pilot, app, table_id: str, text: str) -> DataTable:
    table = app.query_one(table_id, DataTable)
    await wait_for(pilot, lambda: _row_of(table, text) is not None, 20, f"{text} listed")
    table.focus()
    table.move_cursor(row=_row_of(table, text))
    await pilot.press("enter", "enter")  # the first asks, the second uses it
    return table


def _result(app) -> str:
    return str(app.query_one("#devices-result", Static).content)


def test_pick_a_sound_card_and_a_relay_board_the_next_load_has_them():
    plugins = load_plugins(extra={"bench_card": _bench_card_plugin()})

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="devices")
        async with app.run_test(size=(120, 40)) as pilot:
            await wait_for(pilot, lambda: app.session.outputs is not None, what="outputs")
            table = await _select(pilot, app, "#audio-table", "Bench Card B (JACK)")
            await wait_for(pilot, lambda: "in use" in _result(app), 20, "card in use")
            assert "Bench Card B (JACK)" in _result(app)
            assert str(overrides_path("sim").name) in _result(app)
            session = app.session
            assert session.outputs is not None
            assert session.outputs_profile.get("audio.device") == "Bench Card B (JACK)"
            # the table marks the card in use, and lists host API, channels, latencies
            await wait_for(
                pilot,
                lambda: str(table.get_row_at(_row_of(table, "Card B"))[0]) == "●",
                10,
                "card B marked",
            )
            row = [str(c) for c in table.get_row_at(_row_of(table, "Card B"))]
            assert row[3:6] == ["JACK", "8", "3.0/10.0"]
            audio_drivers = [str(c) for c in table.get_column_at(1)]
            assert {"twin", "sounddevice"} <= set(audio_drivers)  # every driver, the twin too
            mic = [str(c) for c in table.get_row_at(_row_of(table, "Bench mic"))]
            assert mic[-1] == "1 output"
            # the relay board: every registered driver with what its probe finds
            await _select(pilot, app, "#relay-table", "twin")
            await wait_for(pilot, lambda: "relay board 'twin' in use already" in _result(app), 20)
            relays = app.query_one("#relay-table", DataTable)
            drivers = [str(c) for c in relays.get_column_at(1)]
            assert {"twin", "yoctopuce", "hid"} <= set(drivers)
            # a named test signal, through the session and the gate, on the new card
            await pilot.press("t")
            await wait_for(pilot, lambda: "played" in _result(app), 30, "test played")
            assert "piezo 20.0 V peak" in _result(app) and "screen 0.0 V peak" in _result(app)
            rec = session.outputs.recording()  # what the card's amplifiers received
            assert abs(np.max(np.abs(rec[:, 0])) - 20.0) < 1e-3

    asyncio.run(scenario())
    again = load_profile("sim", plugins)
    assert again.get("audio.driver") == "bench-card"
    assert again.get("audio.device") == "Bench Card B (JACK)"
    assert again.get("relays.driver") == "twin"
    assert again.overrides == overrides_path("sim")


def test_a_broken_override_file_gets_one_line(capsys):
    path = overrides_path("sim")
    path.parent.mkdir(parents=True)
    path.write_text('[audio]\nblock_size = "large"\n')
    assert main(["--profile", "sim", "doctor"]) != 0
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1, err
    assert str(path) in err and "block_size" in err and "expected" in err
    assert "Traceback" not in err


def test_a_pick_refused_by_a_broken_override_file_says_so_and_keeps_the_outputs():
    plugins = load_plugins(extra={"bench_card": _bench_card_plugin()})

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="devices")
        async with app.run_test(size=(120, 40)) as pilot:
            await wait_for(pilot, lambda: app.session.outputs is not None, what="outputs")
            before = app.session.outputs
            path = overrides_path("sim")
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_text('[audio]\nsample_rate_hz = "fast"\n')  # broken by hand meanwhile
            await _select(pilot, app, "#audio-table", "Bench Card A (ALSA)")
            await wait_for(pilot, lambda: "not saved" in _result(app), 20, "refusal shown")
            msg = _result(app)
            assert str(path) in msg and "sample_rate_hz" in msg and "\n" not in msg
            assert app.session.outputs is before  # still the ones that were open
            assert path.read_text() == '[audio]\nsample_rate_hz = "fast"\n'  # untouched

    asyncio.run(scenario())


def test_a_pick_during_an_estop_is_saved_but_the_estopped_outputs_stay():
    plugins = load_plugins(extra={"bench_card": _bench_card_plugin()})

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="devices")
        async with app.run_test(size=(120, 40)) as pilot:
            await wait_for(pilot, lambda: app.session.outputs is not None, what="outputs")
            before = app.session.outputs
            await pilot.press("ctrl+e")
            assert before.wait_safe(5)
            await _select(pilot, app, "#audio-table", "Bench Card A (ALSA)")
            await wait_for(pilot, lambda: "stay as they are" in _result(app), 20, "refusal")
            assert "e-stop is active" in _result(app)
            assert app.session.outputs is before and before.estopped  # never reopened
            assert load_profile("sim", plugins).get("audio.device") == "Bench Card A (ALSA)"

    asyncio.run(scenario())


def _failing_card_plugin():
    return _module("dead_card")


def test_a_row_with_no_device_cannot_be_picked_and_the_outputs_stay():
    plugins = load_plugins(extra={"dead_card": _failing_card_plugin()})

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="devices")
        async with app.run_test(size=(120, 40)) as pilot:
            await wait_for(pilot, lambda: app.session.outputs is not None, what="outputs")
            before = app.session.outputs
            await _select(pilot, app, "#audio-table", "none: no output")
            await wait_for(pilot, lambda: "no device on this row" in _result(app), 10)
            assert "empty-card" in _result(app) and "\n" not in _result(app)
            await pilot.pause(0.3)
            assert app.session.outputs is before and not before.estopped
            assert not overrides_path("sim").exists()  # nothing saved

    asyncio.run(scenario())


def test_a_pick_that_fails_to_open_brings_back_the_outputs_and_the_overrides():
    plugins = load_plugins(extra={"dead_card": _failing_card_plugin()})
    path = overrides_path("sim")
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text('# my settings\n[audio]\ndevice = ""\n')

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="devices")
        async with app.run_test(size=(120, 40)) as pilot:
            await wait_for(pilot, lambda: app.session.outputs is not None, what="outputs")
            await _select(pilot, app, "#audio-table", "Dead Card")
            await wait_for(pilot, lambda: "did not open" in _result(app), 20, "failure")
            msg = _result(app)
            assert "device unavailable" in msg and "previous outputs are back" in msg
            assert "\n" not in msg
            out = app.session.outputs
            assert out is not None and not out.estopped
            assert (app.session.outputs_profile or app.ctx.profile).get("audio.driver") == "twin"
            await pilot.press("t")  # the twin plays again
            await wait_for(pilot, lambda: "through the gate" in _result(app), 30, "played")

    asyncio.run(scenario())
    assert path.read_text() == '# my settings\n[audio]\ndevice = ""\n'
    assert load_profile("sim", plugins).get("audio.driver") == "twin"
