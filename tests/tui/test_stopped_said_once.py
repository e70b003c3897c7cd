"""A play stopped by an e-stop from a shell is said once, as an e-stop: Devices (F1) `t`
then `haptable estop` said "sweep on 'twin': stopped by stopped: haptable estop ...".
Electrostatic (F5): a knob condition started with Enter, then ctrl+e, names the key
that plays it again (it said "then p plays", and `p` plays the Vpp/Hz setting)."""

from __future__ import annotations

import asyncio

import pytest
from textual.widgets import OptionList

from console.cli.main import Context
from console.kernel.line_server import request
from console.session.events import PlayOutcome
from console.tui.app import HapTableApp

from .conftest import wait_for, words_on
from .test_screens import _ready

SIZES = pytest.mark.parametrize("size", [(80, 24), (120, 40)], ids=["80x24", "120x40"])


def test_a_reason_is_said_with_one_stopped():
    said = PlayOutcome("x", started=True, stopped="stopped: haptable estop (pid 1)")
    assert said.how_it_stopped == "stopped: haptable estop (pid 1)"
    assert PlayOutcome("x", stopped="the e-stop (a)").how_it_stopped == "stopped by the e-stop (a)"
    assert PlayOutcome("x", stopped="stopped").how_it_stopped == "stopped"


@SIZES
def test_a_sweep_stopped_from_a_shell_says_the_estop_once(plugins, size):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=False, initial="devices")
        async with app.run_test(size=size) as pilot:
            await wait_for(pilot, lambda: app.session.outputs is not None, 30, "outputs")
            pane = app.pane("devices")
            await pilot.press("t")
            await wait_for(pilot, lambda: "playing" in pane.result, 30, "playing")
            sock = app.session.outputs.table.control_sock
            await asyncio.to_thread(request, sock, "estop haptable estop (a shell)", timeout_s=5)
            await wait_for(pilot, lambda: "stopped" in pane.result, 30, "stopped")
            line = " ".join(pane.result.split())
            assert "stopped by stopped" not in line and "stopped: stopped" not in line, line
            assert "stopped by the e-stop (" in line and "haptable estop" in line, line
            assert "ctrl+r resets" in line, line

    asyncio.run(scenario())


@SIZES
def test_a_knob_condition_stopped_names_enter_to_play_it_again(plugins, size):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=False, initial="electrostatic")
        async with app.run_test(size=size) as pilot:
            await _ready(app, pilot)
            pane = app.pane("electrostatic")
            ol = app.query_one("#es-list", OptionList)
            ids = [ol.get_option_at_index(i).id for i in range(ol.option_count)]
            cond = next(i for i in ids if i.startswith("cond:") and i != "cond:V")
            ol.focus()
            ol.highlighted = ids.index(cond)
            await pilot.press("enter")
            await wait_for(pilot, lambda: "playing knob" in pane.status_text, 20, "playing")
            await pilot.press("ctrl+e")
            await wait_for(pilot, lambda: "stopped by" in pane.status_text, 20, "stopped")
            line = words_on(app, "#es-status")
            assert "p plays" not in line, line
            assert f"enter plays knob {cond.split(':', 1)[1]} again" in line, line

    asyncio.run(scenario())
