"""One measured-map provider: the console's Vibration screen and the demos' flow read the
same cached measurement of the plate; it is measured once."""

from __future__ import annotations

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
    path = flow_map_path(fv.profile, None, fv.pm)  # the demo asks first: measured now
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
    assert flow_map_path(fv.profile, None, fv.pm) == path and fv.calls == [1]

    # measuring again (m on the Vibration screen) replaces the kept map, with progress
    session.vibration.measure()
    assert fv.calls == [1, 1]
    assert any(isinstance(e, Progress) and e.name == "measure" for e in events)
    assert flow_map_path(fv.profile, None, fv.pm) == path and fv.calls == [1, 1]


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
    from console.errors import UserError
    from console.session import ConsoleSession

    monkeypatch.setenv("HAPTABLE_CACHE_DIR", str(tmp_path))
    fv = fake_vibrometer
    session = ConsoleSession(SimpleNamespace(profile=fv.profile, pm=fv.pm))
    assert session.vibration.load_cached() is None
    with pytest.raises(UserError, match="no vibration map yet"):
        session.vibration.current_map()
    assert fv.calls == []  # asking never measures
