"""A study run plays on the console's vibration map: while it runs, the Vibration
screen's ``m`` (and a typed ``measure``, ``load`` or ``import``) is refused on the key,
naming the run as a refused Enter does, and the map stays the run's; once the run
ends the line says the map is free again."""

from __future__ import annotations

import asyncio

import pytest

from console.tui.command_line import CommandLine

from .studies_pilot import exp1_trial_done, studies_app, studies_pane, wait_for

REFUSED = (
    "measure refused: P01's study run (Studies screen) plays on this map (stop it there first)"
)


def _status(app) -> str:
    return " ".join(str(app.query_one("#vib-status").render()).split())


async def _type(app, pilot, text: str) -> None:
    await pilot.press("colon")
    await wait_for(pilot, lambda: isinstance(app.focused, CommandLine), 10, "the line")
    app.focused.value = text
    await pilot.press("enter")


@pytest.mark.parametrize("size", [(80, 24), (120, 40)])
def test_m_is_refused_while_a_study_plays_on_the_map(double_plugins, map_file, tmp_path, size):
    async def scenario():
        app = studies_app(double_plugins)
        async with app.run_test(size=size) as pilot:
            pane = await studies_pane(pilot, app, map_file)
            vib = app.session.vibration
            measured: list[int] = []
            real = vib.measure
            vib.measure = lambda *a, **kw: measured.append(1) or real(*a, **kw)
            await exp1_trial_done(pilot, pane, tmp_path)
            used = vib.current
            await pilot.press("f3")
            await wait_for(pilot, lambda: app.pane("vibration") is not None, what="Vibration")
            await wait_for(pilot, lambda: app.query("#vib-status"), what="its status")
            await pilot.pause(0.5)
            for _ in range(2):  # no question first: refused at once, again
                await pilot.press("m")
                await wait_for(pilot, lambda: "refused" in _status(app), 10, "the refusal")
                assert _status(app) == REFUSED
            await _type(app, pilot, "load elsewhere.npz")
            await wait_for(pilot, lambda: _status(app).startswith("load refused"), 10, "load")
            assert app.query_one("#vib-cmd", CommandLine).value == "load elsewhere.npz"
            assert measured == [] and vib.current is used and pane.running == "P01"
            await pilot.press("escape", "f10")
            pane.focus()
            await pilot.press("a", "a")
            await wait_for(pilot, lambda: pane.running is None, what="the run stopped")
            await pilot.press("f3")
            await wait_for(pilot, lambda: "has ended" in _status(app), 10, "the map free")
            assert "m measures" in _status(app)

    asyncio.run(scenario())


def test_the_service_refuses_to_replace_a_map_in_use(map_file, plugins):
    """The check is the service's (``console.session.vibration``): a screen that skips
    its own is refused too; the run itself may replace it."""
    from types import SimpleNamespace

    from console.core.errors import UserError
    from console.session.vibration import VibrationService

    events: list = []
    from console.config.profile import load_profile

    profile = load_profile("sim", plugins)  # its map's hold is across processes too
    svc = VibrationService(SimpleNamespace(profile=profile, plugins=None, emit=events.append))
    with svc.in_use("P01's study run (Studies screen)") as who:
        with pytest.raises(UserError, match="load refused: P01's study run"):
            svc.load(map_file)
        with pytest.raises(UserError, match="measure refused"):
            svc.measure()
        with pytest.raises(UserError, match="import refused"):
            svc.import_uff(["PA=a.uff"])
        assert svc.load(map_file, by=who) is svc.current  # the run's own
    assert svc.used_by is None
    assert svc.load(map_file) is svc.current
