"""One measured-map provider: the console's Vibration screen and the demos' flow read the
same cached measurement of the plate; it is measured once."""

from __future__ import annotations

import json
from types import SimpleNamespace

import numpy as np
import pytest


def test_the_demo_and_the_console_share_one_measurement(fake_vibrometer, monkeypatch, tmp_path):
    from console.runtime.measured_map import measured_map, measured_map_path
    from console.session import ConsoleSession
    from console.session.events import Progress, Started
    from plugins.demos.run import flow_map_path

    monkeypatch.setenv("HAPTABLE_CACHE_DIR", str(tmp_path))
    fv = fake_vibrometer
    path = flow_map_path(fv.profile, fv.pm)  # the demo asks first: measured now
    assert fv.calls == [1]
    assert path == measured_map_path(fv.profile) and path.is_relative_to(tmp_path)

    session = ConsoleSession(SimpleNamespace(profile=fv.profile, pm=fv.pm))
    events: list = []
    session.subscribe(events.append)
    vs = session.vibration.load_cached()  # the console's screen finds it
    assert vs is not None and fv.calls == [1]
    assert np.array_equal(vs.vmap.frf_um_per_v, fv.map.frf_um_per_v)
    assert session.vibration.current is vs and session.vibration.current_map() is vs.vmap
    assert any(isinstance(e, Started) and e.topic == "vibration" for e in events)
    assert measured_map(fv.profile, fv.pm).points.size == fv.map.points.size
    assert flow_map_path(fv.profile, fv.pm) == path and fv.calls == [1]

    # measuring again (m on the Vibration screen) replaces the kept map, with progress
    session.vibration.measure()
    assert fv.calls == [1, 1]
    assert any(isinstance(e, Progress) and e.name == "measure" for e in events)
    assert flow_map_path(fv.profile, fv.pm) == path and fv.calls == [1, 1]


def test_another_plate_is_another_map(fake_vibrometer, monkeypatch, tmp_path):
    from console.runtime.measured_map import measured_map_file, measured_map_path

    monkeypatch.setenv("HAPTABLE_CACHE_DIR", str(tmp_path))
    fv = fake_vibrometer
    first = measured_map_file(fv.profile, fv.pm)
    fv.profile.plate = {"thickness_mm": 99.0}
    assert measured_map_path(fv.profile) != first
    measured_map_file(fv.profile, fv.pm)
    assert fv.calls == [1, 1]


def test_no_map_yet_is_one_line(fake_vibrometer, monkeypatch, tmp_path):
    from console.core.errors import UserError
    from console.session import ConsoleSession

    monkeypatch.setenv("HAPTABLE_CACHE_DIR", str(tmp_path))
    fv = fake_vibrometer
    session = ConsoleSession(SimpleNamespace(profile=fv.profile, pm=fv.pm))
    assert session.vibration.load_cached() is None
    with pytest.raises(UserError, match="no vibration map yet"):
        session.vibration.current_map()
    assert fv.calls == []  # asking never measures


def _cli(configure, runner, argv, fv) -> int:
    import argparse

    parser = argparse.ArgumentParser()
    configure(parser)
    return runner(parser.parse_args(argv), SimpleNamespace(profile=fv.profile, pm=fv.pm))


@pytest.mark.slow
def test_the_commands_use_the_same_measured_map(fake_vibrometer, tmp_path, capsys):
    """`haptable tables build measured` reuses the map the flow demo measured; the console
    then finds it too; `frf measure` measures again into the same file, and the demo
    reuses that one."""
    from console.files.vibration_map import load_map
    from console.runtime.measured_map import measured_map_path
    from console.session import ConsoleSession
    from plugins.demos.run import flow_map_path
    from plugins.vibrotactile.cli import frf as frf_cli
    from plugins.vibrotactile.cli import tables as tables_cli
    from plugins.vibrotactile.tables import load_tables

    fv = fake_vibrometer
    path = flow_map_path(fv.profile, fv.pm)  # the flow demo first: measured now
    assert fv.calls == [1] and path == measured_map_path(fv.profile)
    out = tmp_path / "tables.npz"
    argv = ["build", "measured", "--out", str(out), "--rule", "paper"]
    assert _cli(tables_cli.configure_tables, tables_cli.run_tables, argv, fv) == 0
    assert fv.calls == [1]  # the command reused the demo's file
    assert load_tables(out).vmap.content_hash() == load_map(path).content_hash()
    session = ConsoleSession(SimpleNamespace(profile=fv.profile, pm=fv.pm))
    assert session.vibration.load_cached() is not None and fv.calls == [1]

    argv = ["query", "measured", "--active", "51", "--passive", "52", "--json"]
    capsys.readouterr()
    assert (
        _cli(tables_cli.configure_tables, tables_cli.run_tables, [*argv, "--rule", "paper"], fv)
        == 0
    )
    assert "actuator" in capsys.readouterr().out and fv.calls == [1]

    # measuring on purpose replaces the one file; every user then reads the new one
    copy = tmp_path / "copy.npz"
    assert _cli(frf_cli.configure_frf, frf_cli.run_frf, ["measure", "--out", str(copy)], fv) == 0
    assert fv.calls == [1, 1]
    assert str(path) in capsys.readouterr().out
    assert load_map(copy).content_hash() == load_map(path).content_hash()
    assert flow_map_path(fv.profile, fv.pm) == path and fv.calls == [1, 1]


def test_a_command_measures_first_and_the_demo_reuses_it(fake_vibrometer, capsys):
    from console.runtime.measured_map import measured_map_path
    from plugins.demos.run import flow_map_path
    from plugins.vibrotactile.cli import frf as frf_cli

    fv = fake_vibrometer
    assert not measured_map_path(fv.profile).exists()
    assert _cli(frf_cli.configure_frf, frf_cli.run_frf, ["info", "measured", "--json"], fv) == 0
    assert fv.calls == [1]  # nothing kept yet: measured once, for the command
    assert json.loads(capsys.readouterr().out)["points"] == fv.map.points.size
    assert flow_map_path(fv.profile, fv.pm) == measured_map_path(fv.profile)
    assert fv.calls == [1]


def test_a_file_named_measured_is_a_file(fake_vibrometer, tmp_path, monkeypatch):
    from console.files.vibration_map import save_map
    from plugins.vibrotactile.cli.common import map_source

    fv = fake_vibrometer
    monkeypatch.chdir(tmp_path)
    save_map(tmp_path / "measured", fv.map)
    ctx = SimpleNamespace(profile=fv.profile, pm=fv.pm)
    assert map_source("measured", ctx) == "measured" and fv.calls == []
    assert map_source("other.npz", ctx) == "other.npz"
