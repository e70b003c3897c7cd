"""A new-user trial (twin profile ``sim``): ``haptable study run --simulate`` from a shell
held the vibration map but not the table: the console's Vibration screen refused ``m``
naming the run, yet Enter played point 51. As the README says, the run holds the table's
outputs: every console action that plays (Vibration's Enter, Devices' ``t``, a demo's
start, a relay's toggle) is refused while it runs, naming it (its command and pid), one check for all."""

from __future__ import annotations

import asyncio
import signal

import pytest

from console.cli.main import Context
from console.config.profile import load_profile
from console.core.errors import UserError
from console.runtime.measured_map import measured_map
from console.tui.app import HapTableApp

from .studies_pilot import wait_for
from .test_cli_map_held import _held, _shell_run, _status


@pytest.mark.parametrize("size", [(80, 24), (120, 40)])
def test_a_shell_s_study_run_holds_the_console_s_plays(plugins, tmp_path, size):
    profile = load_profile("sim", plugins)
    measured_map(profile, plugins)  # the twin's map kept: the console opens with it
    proc = None

    async def scenario():
        nonlocal proc
        app = HapTableApp(Context("sim", plugins), fast=True, initial="vibration")
        async with app.run_test(size=size) as pilot:
            await wait_for(pilot, lambda: "kept measurement" in _status(app), 30, "the map")
            proc = _shell_run(tmp_path / "a")  # then the run starts in a shell
            who = await asyncio.to_thread(_held, profile, proc)
            assert "haptable study run --simulate, pid " in who, who
            played = len(app.session.played)
            await pilot.press("enter")
            await wait_for(pilot, lambda: "refused" in _status(app), 10, "the refusal")
            said = _status(app)
            assert who in said and "holds the outputs" in said, said
            assert "stop it there first" in said, said
            assert len(app.session.played) == played  # nothing reached the outputs
            with pytest.raises(UserError, match="holds the outputs"):
                app.session.demos.check_start("flow")
            await pilot.press("f1")
            await wait_for(pilot, lambda: app.pane("devices") is not None, 20, "devices")
            devices = app.pane("devices")
            await wait_for(pilot, lambda: app.focused is not None, 10, "focus")
            await pilot.press("t")
            await wait_for(pilot, lambda: "refused" in devices.result, 20, "t refused")
            assert who in " ".join(devices.result.split()), devices.result
            assert len(app.session.played) == played
            await pilot.press("f4")  # a relay setting is refused too, naming the run
            await wait_for(pilot, lambda: app.pane("relays") is not None, 20, "relays")
            await pilot.pause(0.3)
            await pilot.press("2")
            row = app.query_one("#interlock-2")
            await wait_for(pilot, lambda: "refused" in str(row.render()), 10, "2 refused")
            assert who in " ".join(str(row.render()).split())
            assert 2 not in app.session.outputs.operator_relays()

    try:
        asyncio.run(scenario())
    finally:
        if proc is not None:
            proc.send_signal(signal.SIGINT)  # Ctrl-C: the run stops, its hold with it
            proc.wait(30)
