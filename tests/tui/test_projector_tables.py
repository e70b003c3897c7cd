"""A projected scene's ``tables`` need, prepared by the console through the registered
``flow`` effect: the grid scene started from the console is prepared (or says why not),
and becomes prepared once a vibration map is loaded. No projector process: the service
is driven as the console drives it (states are queued for a projector that is absent)."""

from __future__ import annotations

import asyncio

import pytest

from console.core.errors import UserError
from console.runtime.projector.client import ProjectorLink
from console.runtime.projector.service import ProjectorService, effect_providers
from plugins.demos.panel import status_text

from .conftest import command, wait_for
from .test_screens import _app, _ready


def _service(plugins, profile, tmp_path, current_map) -> ProjectorService:
    return ProjectorService(
        socket_path=tmp_path / "p.sock",
        command=None,
        scenes={n: r.factory for n, r in plugins.of("scene").items()},
        profile=profile,
        providers=effect_providers(profile, plugins, current_map),
    )


def test_grid_scene_gets_the_flow_effects_tables(plugins, profile, tmp_path, map_file):
    svc = _service(plugins, profile, tmp_path, lambda: map_file)
    try:
        svc.start_scene("grid")
        st = svc.status()
        assert st["unprepared_needs"] == [] and "not prepared" not in status_text(st)
        got = svc.prepared["tables"]
        assert got["points"] == list(range(1, 85))
        # the very tables the flow effect answers a pair with
        flow = plugins.get("effect", "flow").factory(profile)
        entry = flow.query(51, 52, vmap=map_file)
        t = got["tables"]
        i, j = t.vmap.point_index(51), t.vmap.point_index(52)
        assert t.freq_hz[i, j] == entry["frequency_hz"]
        assert t.excitations[t.actuator[i, j]] == entry["actuator"]
        svc.start_scene("flow_two_point")  # pairs of points: the same need
        assert svc.status()["unprepared_needs"] == []
    finally:
        svc.link.close()


def test_without_a_map_the_scene_says_why_and_is_prepared_later(
    plugins, profile, tmp_path, map_file
):
    have: list = []

    def current_map():
        if not have:
            raise UserError("no vibration map yet: load one")
        return have[0]

    svc = _service(plugins, profile, tmp_path, current_map)
    try:
        svc.start_scene("grid")  # the scene still shows
        st = svc.status()
        assert st["scene"] == "grid" and st["unprepared_needs"] == ["tables"]
        assert "not prepared: tables (no vibration map yet: load one)" in status_text(st)
        have.append(map_file)
        assert svc.prepare_again() == []
        assert "not prepared" not in status_text(svc.status())
    finally:
        svc.link.close()


def test_without_vibrotactile_the_status_names_the_plugin(tmp_path, map_file):
    from console.config.plugins import BUILTIN_PLUGINS, load_plugins
    from console.config.profile import load_profile

    pm = load_plugins(builtins={k: v for k, v in BUILTIN_PLUGINS.items() if k != "vibrotactile"})
    svc = _service(pm, load_profile("sim", pm), tmp_path, lambda: map_file)
    try:
        svc.start_scene("grid")
        assert "install/enable vibrotactile" in status_text(svc.status())
    finally:
        svc.link.close()


@pytest.fixture
def no_projector_process(monkeypatch):
    """The scenes screen's service without spawning the projector (it is absent)."""
    monkeypatch.setattr(ProjectorService, "start", lambda self: None)
    monkeypatch.setattr(ProjectorLink, "wait_connected", lambda self, timeout_s=10.0: True)


def test_grid_scene_from_the_console_is_prepared_once_a_map_is_loaded(
    plugins, map_file, no_projector_process
):
    async def scenario():
        app = _app(plugins, "scenes")
        async with app.run_test(size=(100, 30)) as pilot:
            await _ready(app, pilot)
            table = app.query_one("#scene-table")
            names = [str(table.get_row_at(i)[0]) for i in range(table.row_count)]
            table.move_cursor(row=names.index("grid"))
            await pilot.press("enter")
            await wait_for(
                pilot,
                lambda: (
                    app.session.projector is not None and app.session.projector.scene_name == "grid"
                ),
                30,
                "grid started",
            )
            svc = app.session.projector
            assert svc.unprepared == ["tables"]
            assert "no vibration map yet" in status_text(svc.status())
            # load a map on the Vibration screen: its tables reach the projected scene
            await pilot.press("f3")
            await wait_for(pilot, lambda: app.pane("vibration") is not None)
            vib = app.pane("vibration")
            await wait_for(pilot, lambda: app.focused is vib.focus_target, 10, "grid focused")
            await command(app, pilot, f"load {map_file}")
            await wait_for(pilot, lambda: svc.unprepared == [], 30, "tables prepared")
            assert svc.prepared["tables"]["tables"].vmap.points.size == 84
            assert "not prepared" not in status_text(svc.status())
            # a scene started now is prepared from the loaded map at once
            await pilot.press("f6")
            await wait_for(pilot, lambda: app.focused is table, 10, "scene list focused")
            table.move_cursor(row=names.index("flow_two_point"))
            await pilot.press("enter")
            await wait_for(pilot, lambda: svc.scene_name == "flow_two_point", 30)
            assert svc.unprepared == []

    asyncio.run(scenario())
