"""The roving measurement's line, from the plugin's steps (no app): which point is next and
where, the progress, and the last point's coherence with its verdict computed by hand."""

from __future__ import annotations

import numpy as np
import pytest

from console.tui.roving_view import (
    ADD_ACCELEROMETER,
    RovingProgress,
    add_accelerometer_text,
    has_accelerometer,
    roving_map_path,
)
from plugins.vibrotactile.roving_console import PASS_FRACTION, coherence_step


def test_coherence_step_matches_numbers_worked_by_hand():
    # 2 excitations x 5 bins: 6 of 10 bins >= 0.9; sorted: .1 .3 .5 .6 .91 | .92 .95 .97 .99 1
    coh = np.array([[0.1, 0.95, 1.0, 0.92, 0.5], [0.3, 0.99, 0.91, 0.6, 0.97]])
    got = coherence_step(coh, 0.9)
    assert got["coherence_min"] == pytest.approx(0.1)
    assert got["coherence_median"] == pytest.approx((0.91 + 0.92) / 2)
    assert got["good_fraction"] == pytest.approx(0.6)
    assert PASS_FRACTION > 0.6 and got["passes"] is False
    assert coherence_step(np.full((5, 4), 0.95), 0.9)["passes"] is True


def test_the_line_names_the_next_point_progress_and_the_last_verdict():
    p = RovingProgress()
    p.apply({"event": "next", "point": 12, "x_mm": 701.7, "y_mm": 43.6, "done": 11})
    p.apply({"total": 84})
    assert p.line() == (
        "roving sensor: 11/84 points · next: point 12 at (702, 44) mm (the twin moves the "
        "sensor there) · last point: none measured yet"
    )
    assert p.fraction == pytest.approx(11 / 84)
    step = coherence_step(np.array([[0.1, 0.95, 1.0, 0.92, 0.5]]), 0.9)
    p.apply({"event": "measured", "point": 12, "done": 12, "total": 84, **step})
    assert "next" not in p.line() and "12/84 points" in p.line()
    assert p.last_text() == (
        "last: point 12 coherence min 0.10, median 0.92; >= 0.9 over 60% of the band "
        "(needs 80%): FAILS"
    )
    # on a table the operator places the sensor and presses m
    p.apply({"event": "next", "point": 13, "x_mm": 41.7, "y_mm": 103.6, "simulated": False})
    assert p.waiting and "glue the sensor on point 13 at (42, 104) mm, then press m" in p.line()


class _Prof:
    path = "t.toml"
    name = "t"

    def __init__(self, inputs):
        self.inputs = inputs

    def items(self, section):
        return self.inputs


def test_only_an_accelerometer_input_starts_the_roving_run(tmp_path):
    accel = {"channel": 1, "kind": "accelerometer", "sensitivity": 10.2}
    loop = {"channel": 2, "kind": "loopback", "sensitivity": 1.0}
    assert has_accelerometer(_Prof({"accel": accel, "loop": loop}))
    assert not has_accelerometer(_Prof({"loop": loop}))
    assert not has_accelerometer(_Prof({}))
    # without one, m measures as before and the screen says how to add one, and where
    text = add_accelerometer_text(_Prof({}))  # one line of words; ? says it whole
    assert text == "measuring with the vibrometer; ? says how to add an accelerometer input"
    assert len(text) < 78 and "accelerometer: ?" not in text  # a second operator's try
    assert "add [audio_inputs.accel] channel = 1, kind = 'accelerometer'" in ADD_ACCELEROMETER
    assert "overrides.toml" in ADD_ACCELEROMETER  # the operator's file, not the shipped one
    kept = tmp_path / "measured-map-0123.npz"
    assert roving_map_path(kept) == tmp_path / "roving-map-0123.npz"


class _Projector:
    """The projector service as the console sees it: the scene it shows, its events."""

    def __init__(self):
        from plugins.projector.scenes import BUILTIN_SCENES

        self.scenes, self.scene_name, self.scene = BUILTIN_SCENES, None, None

    def start_scene(self, name, events=()):
        self.scene_name, self.scene = name, self.scenes[name][0](None)
        for ev in events:
            self.scene.update(ev)

    def update(self, event):
        self.scene.update(event)


def test_each_next_point_moves_the_projected_marker():
    import threading
    from types import SimpleNamespace

    from console.tui.roving_view import SCENE, RovingView

    svc = _Projector()
    app = SimpleNamespace(
        session=SimpleNamespace(projector=svc), call_from_thread=lambda fn, *a, **k: None
    )
    view = RovingView(SimpleNamespace(app=app))
    stop = threading.Event()
    for n, (x, y) in ((1, (41.73, 43.645)), (14, (101.73, 103.645))):
        step = {"event": "next", "point": n, "x_mm": x, "y_mm": y, "done": n - 1, "total": 84}
        view._step(step, stop)
        state = svc.scene.state()
        assert svc.scene_name == SCENE and state["sensor"] == n
        assert state["points_mm"][n - 1] == pytest.approx([x, y])
        assert f"point {n} ({n - 1}/84 done)" in state["message"]


def test_a_dummy_pass_asks_for_the_dummy_and_the_next_move_without_it():
    p = RovingProgress()
    common = {"point": 13, "x_mm": 41.7, "y_mm": 103.6, "simulated": False, "total": 84}
    p.apply({"event": "next", "done": 12, **common, "dummy_mass_g": 14.0})
    assert "glue the sensor (without the dummy) on point 13 at (42, 104) mm, then press m" in (
        p.line()
    )
    p.waiting = False  # placed (m)
    p.apply({"event": "dummy", "on": True, "done": 12, **common, "dummy_mass_g": 14.0})
    assert p.waiting
    assert "clip the 14 g dummy on the sensor at point 13 at (42, 104) mm, then press m" in (
        p.line()
    )
    p.apply({"event": "dummy", "on": False, "done": 12, **common, "dummy_mass_g": 14.0})
    assert not p.waiting and "clip" not in p.line()
    twin = RovingProgress()
    twin.apply({"event": "dummy", "on": True, **common, "simulated": True, "dummy_mass_g": 14.0})
    assert not twin.waiting and "(the twin adds its mass)" in twin.line()


def test_a_dummy_without_the_sensor_s_mass_is_one_line_naming_the_keys():
    from console.plugin_api import UserError
    from plugins.vibrotactile.roving_console import RovingEffect

    eff = RovingEffect(_Prof({}))
    assert eff._dummy_mass_g({"name": "accel"}) is None
    assert eff._dummy_mass_g({"name": "accel", "mass_g": 7.0, "dummy_mass_g": 14.0}) == 14.0
    with pytest.raises(UserError) as e:
        eff._dummy_mass_g({"name": "accel", "dummy_mass_g": 14.0})
    msg = str(e.value)
    assert "\n" not in msg and "[audio_inputs.accel] dummy_mass_g = 14 needs mass_g" in msg


def test_the_measurement_says_a_time_left_from_its_first_step(monkeypatch):
    """A second new operator's try: the measurement's progress had no time left (the
    pace needs a second and a few percent); the expected seconds say it until then."""
    from console.tui.panes import vibration_words as W  # lazy: beside the roving tests

    now = [100.0]
    monkeypatch.setattr("console.core.time_left.time.monotonic", lambda: now[0])
    said: list[str] = []
    progress = W.with_time_left(lambda _f, msg: said.append(msg), expected_s=10.0)
    progress(0.0, "starting")
    now[0] += 3.0
    progress(0.01, "step 1/8")
    assert said == ["starting; about 10 s left", "step 1/8; about 7 s left"], said
    bare: list[str] = []
    W.with_time_left(lambda _f, msg: bare.append(msg))(0.0, "starting")
    assert bare == ["starting"]  # nothing expected: nothing guessed
