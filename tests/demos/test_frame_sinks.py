"""The demo runner meets TUIO and the camera twin only through registrations and
console types: frame sinks it opens by the profile, a GestureScript the twin acts out."""

from __future__ import annotations

import time

import pytest

from console.core.errors import UserError
from console.core.hookspecs import hookimpl


class Recorder:
    """A frame sink that keeps what it was fed."""

    def __init__(self) -> None:
        self.frames: list[int] = []
        self.closed = False

    def __call__(self, frame, work) -> None:
        self.frames.append(frame.seq)

    def close(self) -> None:
        self.closed = True


class SinkPlugin:
    def __init__(self, enabled: bool) -> None:
        self.enabled = enabled
        self.made: list[Recorder] = []

    @hookimpl
    def haptable_register_frame_sinks(self, register):
        def factory(profile, *, force=False):
            if not (force or self.enabled):
                return None
            self.made.append(Recorder())
            return self.made[-1]

        register("recorder", factory, description="keeps frame numbers")


def load(**extra):
    """The built-in plugins (demos and tuio among them) and ``extra`` ones by name."""
    from console.config.plugins import load_plugins

    return load_plugins(extra=extra)


def test_sinks_follow_the_profile_and_the_force_switch(profile):
    from plugins.demos.run import open_frame_sinks
    from plugins.tuio.sender import TuioSender

    pm = load(rec=SinkPlugin(enabled=True))
    assert {"tuio", "recorder"} <= set(pm.of("frame_sink"))
    assert not profile.get("tuio.enabled")  # the sim profile: TUIO off
    kinds = [type(s).__name__ for s in open_frame_sinks(profile, pm)]
    assert kinds == ["Recorder"]
    sinks = open_frame_sinks(profile, pm, force={"tuio": True})
    assert sorted(type(s).__name__ for s in sinks) == ["Recorder", "TuioSender"]
    for s in sinks:
        s.close()
    assert not open_frame_sinks(profile, pm, force={"recorder": False})
    (only,) = open_frame_sinks(profile, pm, force={"tuio": True, "recorder": False})
    assert isinstance(only, TuioSender)
    only.close()


def test_forcing_a_sink_nobody_registers_is_a_one_line_error(profile, monkeypatch):
    from plugins.demos.run import open_frame_sinks

    monkeypatch.setenv("HAPTABLE_BLOCK_PLUGINS", "tuio")
    pm = load()
    assert "tuio" not in pm.of("frame_sink")
    with pytest.raises(UserError, match="frame sink 'tuio': no plugin registers it"):
        open_frame_sinks(profile, pm, force={"tuio": True})


def test_a_running_demo_feeds_every_enabled_sink_and_closes_it(profile, outputs):
    from plugins.demos.run import start_demo

    rec = SinkPlugin(enabled=True)
    pm = load(rec=rec)
    run = start_demo("knob", profile, pm, outputs, watchdog_ms=5000, tuio=False)
    try:
        t0 = time.monotonic()
        while len(rec.made[0].frames) < 5 and time.monotonic() - t0 < 20:
            time.sleep(0.05)
    finally:
        run.stop()
    sink = rec.made[0]
    assert len(rec.made) == 1 and len(sink.frames) >= 5
    assert sink.frames == sorted(sink.frames)  # in camera order
    assert sink.closed


def test_the_twin_acts_out_the_demo_script(profile, plugins):
    from plugins.demos.run import script_twin

    gap = int(0.5 * float(profile.get("camera.fps")))
    camera = plugins.get("camera", "twin").factory(profile)
    camera.realtime = False
    try:
        assert script_twin(camera, "knob", profile, hold_frames=20)
        labels = []
        for _ in range(2 * gap + 40):
            camera.read(0.1)
            labels.append(camera.truth["gesture"])
    finally:
        camera.close()
    # empty table for the gap, the rotation for 20 frames, again: looping
    assert labels[:gap] == ["idle"] * gap
    assert labels[gap : gap + 20] == ["rotate"] * 20
    assert labels[gap + 20 : 2 * gap + 20] == ["idle"] * gap
    assert labels[2 * gap + 20 : 2 * gap + 40] == ["rotate"] * 20


def test_a_real_camera_is_left_alone(profile):
    from plugins.demos.run import script_twin

    class Plain:
        def read(self, timeout_s=0.1):
            return None

    assert not script_twin(Plain(), "flow", profile)
