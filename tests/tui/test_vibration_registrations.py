"""The Vibration screen works through registrations: the lookup-table build is a worker
with progress that x cancels and b restarts; without the vibrotactile plugin the screen
says which plugin to enable instead of playing anything."""

from __future__ import annotations

import asyncio
import time

import numpy as np

from console.cli.main import Context
from console.config.plugins import BUILTIN_PLUGINS, load_plugins
from console.tui.app import HapTableApp

from .conftest import command, wait_for
from .test_screens import _app, _load_map, _ready


def _status(app) -> str:
    return str(app.query_one("#vib-status").render())


def test_table_build_shows_progress_cancels_and_rebuilds(plugins, map_file, monkeypatch, tmp_path):
    from plugins.vibrotactile import registered

    # a cold cache of its own: the session's may hold these tables from another test
    monkeypatch.setenv("HAPTABLE_CACHE_DIR", str(tmp_path / "cache"))

    real = registered.build_tables
    fractions: list[float] = []

    def slow_build(m, band_hz, progress=None, **kw):
        def slow(frac: float, msg: str) -> None:
            fractions.append(frac)
            time.sleep(0.25)  # a large map: each step takes a while
            progress(frac, msg)

        return real(m, band_hz, slow, **kw)

    monkeypatch.setattr(registered, "build_tables", slow_build)

    async def scenario():
        app = _app(plugins, "vibration")
        async with app.run_test(size=(80, 24)) as pilot:
            await _ready(app, pilot)
            pane = await _load_map(app, pilot, map_file)
            bar = app.query_one("#vib-progress")
            await wait_for(pilot, lambda: "lookup tables: pairs" in _status(app), 10, "progress")
            assert bar.display
            await pilot.press("x")
            await wait_for(pilot, lambda: "build cancelled" in _status(app), 20, "cancelled")
            assert not bar.display and not pane.session.tables_ready
            assert fractions and max(fractions) < 1.0  # stopped part way
            # the map stays usable: a point plays without tables
            await command(app, pilot, "51")
            await wait_for(pilot, lambda: len(app.session.played) == 1)
            await wait_for(pilot, lambda: "played point 51" in _status(app), 10, "point played")
            # b builds them again, to the end
            fractions.clear()
            await pilot.press("b")
            await wait_for(pilot, lambda: _status(app).endswith("; ready"), 30, "rebuilt")
            assert pane.session.tables_ready and fractions[-1] == 1.0
            await command(app, pilot, "51 52")
            await wait_for(pilot, lambda: len(app.session.played) == 2)
            assert app.session.played[1].name == "flow 51->52"

    asyncio.run(scenario())


def test_without_vibrotactile_the_screen_names_the_plugin(map_file):
    pm = load_plugins(builtins={k: v for k, v in BUILTIN_PLUGINS.items() if k != "vibrotactile"})

    async def scenario():
        app = HapTableApp(Context("sim", pm), fast=True, initial="vibration")
        async with app.run_test(size=(80, 24)) as pilot:
            await _ready(app, pilot)
            await _load_map(app, pilot, map_file)  # maps are the console's: they load
            await wait_for(pilot, lambda: "without lookup tables" in _status(app), 10)
            assert "install/enable vibrotactile" in _status(app)
            await command(app, pilot, "51")
            await wait_for(
                pilot, lambda: "localized point stimulus" in _status(app), 10, "point refused"
            )
            assert "install/enable vibrotactile" in _status(app)
            await command(app, pilot, "import PA=a.uff")  # typed once the line has focus
            # the refusal is shown and notified; a later status (the point's FRF, shown by
            # its own worker) may replace the status line under load: read the notices too
            await wait_for(
                pilot,
                lambda: (
                    "imports UFF" in _status(app)
                    or any("imports UFF" in n.message for n in app._notifications)
                ),
                20,
                "import refused",
            )
            assert app.session.played == []

    asyncio.run(scenario())


def test_uff_import_through_the_flow_effect(plugins, tmp_path, map_file):
    from console.config.profile import load_profile
    from console.files.vibration_map import load_map, make_map
    from plugins.vibrotactile.uff_export import export_uff

    full = load_map(map_file)
    row = make_map(
        full.frf_um_per_v[:, 48:60],  # grid row 5: points 49..60
        full.freq_hz,
        full.points[48:60],
        full.points_mm[48:60],
        full.excitations,
        full.masked,
    )
    gain = float(load_profile("sim", plugins).get("amplifiers.piezo_gain"))
    paths = export_uff(row, tmp_path / "uff", gain=gain)
    specs = [f"{p.stem}={p}" for p in paths]

    async def scenario():
        app = _app(plugins, "vibration")
        async with app.run_test(size=(80, 24)) as pilot:
            await _ready(app, pilot)
            pane = app.pane("vibration")
            await command(app, pilot, "import " + " ".join(specs))
            await wait_for(pilot, lambda: pane.session is not None, 30, "imported")
            await wait_for(pilot, lambda: _status(app).endswith("; ready"), 30, "tables")
            assert _status(app).startswith("map: UFF import: 5 excitations, 12 points")
            m = pane.session.vmap
            assert m.points.tolist() == list(range(49, 61))
            np.testing.assert_allclose(m.frf_um_per_v, row.frf_um_per_v, rtol=1e-9, atol=1e-12)
            await command(app, pilot, "51 52")
            await wait_for(pilot, lambda: len(app.session.played) == 1)
            entry = pane.session.lookup(51, 52)
            assert app.session.played[0].meta["parts"][0]["frequency_hz"] == entry["frequency_hz"]

    asyncio.run(scenario())


def test_measurement_uses_the_vibrometer_the_profile_names():
    from types import SimpleNamespace

    import pytest

    from console.core.errors import UserError
    from console.session import vibration as vs

    def measured(name: str, progress) -> dict:
        used.append(name)
        progress(1, 1)
        return {
            "frf_um_per_v": np.ones((5, 1, 3)),
            "freq_hz": np.array([10.0, 20.0, 30.0]),
            "points": np.array([1]),
            "points_mm": np.zeros((1, 2)),
            "excitations": ("PA", "PB", "PC", "PD", "PALL"),
            "meta": {"source": name},
        }

    def reg(name):
        def factory(profile):
            return SimpleNamespace(measure=lambda progress=None: measured(name, progress))

        return SimpleNamespace(factory=factory)

    def plugins(*names):
        return SimpleNamespace(of=lambda kind: {n: reg(n) for n in names})

    def profile(driver):
        return SimpleNamespace(get=lambda key, default=None: driver)

    used: list[str] = []
    run = [lambda f, m: None, lambda: False]
    with pytest.raises(UserError, match="driver = 'ldv': no such vibrometer; available: twin"):
        vs.measure_map(profile("ldv"), plugins("twin"), *run)  # never the twin instead
    with pytest.raises(UserError, match="not set; set it to one of a, b"):
        vs.measure_map(profile(None), plugins("a", "b"), *run)
    with pytest.raises(UserError, match="install/enable twin.plate"):
        vs.measure_map(profile("twin"), plugins(), *run)
    m = vs.measure_map(profile(None), plugins("twin"), *run)  # the only one
    assert used == ["twin"] and m.points.tolist() == [1]
    with pytest.raises(vs.Cancelled):  # cancel reaches the device through its progress
        vs.measure_map(profile("b"), plugins("a", "b"), run[0], iter([False, True]).__next__)
    assert used == ["twin", "b"]
