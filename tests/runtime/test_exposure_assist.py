"""The exposure assistant (issue 28) against a fake camera whose touching skin clips
above some exposure: it converges below the sensor's maximum, says when it cannot, and
gives the camera its first values back when cancelled or failing."""

from __future__ import annotations

import numpy as np
import pytest

from console.core.types import TunableRange
from console.runtime.exposure_assist import TARGET_P99, Reading, assist, reading_of


class FakeCamera:
    """Touching skin shows ``k`` x exposure x gain grey levels (clipped at 255) over a
    background of 30; a driver's exposure and gain with its own ranges."""

    def __init__(self, exposure=200.0, gain=16.0, k=0.1, exposure_min=0.0) -> None:
        self.values = {"exposure": exposure, "gain": gain}
        self.ranges = {
            "exposure": TunableRange(exposure_min, 1000.0, 10.0),
            "gain": TunableRange(-1.0, 255.0, 4.0),
        }
        self.k = k
        self.log: list[tuple[str, float]] = []

    def controls(self):
        return dict(self.ranges)

    def control_values(self):
        return dict(self.values)

    def set_control(self, name, value):
        self.values[name] = self.ranges[name].clamp(value)
        self.log.append((name, self.values[name]))

    def skin(self) -> float:
        return self.k * self.values["exposure"] * max(self.values["gain"], 1.0)

    def measure(self) -> Reading | None:
        true = self.skin()
        level = min(true, 255.0) - 30.0
        return Reading(min(true, 255.0), 800 if true >= 255 else 0, level, level / 180.0, 2.0)


def test_it_steps_the_exposure_down_until_touching_skin_is_below_the_maximum():
    cam = FakeCamera(k=0.1)  # 320 grey levels: clips
    said: list[str] = []
    out = assist(cam, cam.measure, progress=said.append)
    assert out.ok, out.line
    assert cam.skin() <= TARGET_P99 and cam.measure().clipped_px == 0
    assert not cam.measure().too_dark()  # contacts stay well above the hover layer
    assert cam.values["gain"] == 16.0  # the exposure was enough
    assert out.line.startswith("e: set exposure") and f"{cam.values['exposure']:g}" in out.line
    assert said and all("x stops" in s for s in said)


def test_in_range_already_nothing_changes():
    cam = FakeCamera(k=0.05)  # 160
    out = assist(cam, cam.measure)
    assert out.ok and not cam.log and "kept exposure 200, gain 16" in out.line


def test_gain_follows_when_the_exposure_is_at_its_minimum():
    cam = FakeCamera(exposure=120.0, gain=16.0, k=0.2, exposure_min=100.0)  # 384
    out = assist(cam, cam.measure)
    assert out.ok, out.line
    assert cam.values["exposure"] == 100.0 and cam.values["gain"] < 16.0
    assert cam.skin() <= TARGET_P99


def test_at_the_drivers_minimum_and_still_clipping_it_says_lower_the_led_power():
    cam = FakeCamera(exposure=120.0, gain=-1.0, k=3.0, exposure_min=100.0)
    out = assist(cam, cam.measure)
    assert not out.ok and "lower the IR LED power" in out.line
    assert "exposure 100" in out.line and "px at 255" in out.line
    assert cam.values == {"exposure": 100.0, "gain": -1.0}  # less light than before


def test_it_never_makes_touching_skin_too_dark_to_find():
    cam = FakeCamera(k=0.1)

    def measure():  # clips until it goes dark at once (a sensor's nonlinearity)
        r = cam.measure()
        return r if cam.values["exposure"] > 150 else Reading(40.0, 0, 10.0, 0.06, 2.0)

    out = assist(cam, measure)
    assert not out.ok and "loses the contacts" in out.line and "LED power" in out.line
    assert cam.values["exposure"] == 160.0  # the last one that kept them


def test_no_hand_on_the_glass_changes_nothing():
    cam = FakeCamera()
    out = assist(cam, lambda: None)
    assert out.line == (
        "e: no hand held still in the frames measured: hold a flat hand on the glass, then e"
    )
    assert not cam.log


def test_cancel_and_failure_give_the_first_values_back():
    cam = FakeCamera(k=0.2)
    calls = []
    out = assist(cam, cam.measure, cancelled=lambda: calls.append(1) or len(calls) > 1)
    assert not out.ok and out.line == "e cancelled: exposure 200, gain 16 as before"
    assert cam.values == {"exposure": 200.0, "gain": 16.0} and len(cam.log) > 1

    cam = FakeCamera(k=0.2)
    seen = iter([cam.measure()])

    def broken():
        return next(seen)  # the second frame never comes

    out = assist(cam, broken)
    assert not out.ok and out.line.startswith("e failed") and "as before" in out.line
    assert cam.values == {"exposure": 200.0, "gain": 16.0}


def test_a_driver_without_exposure_or_gain_is_named_with_the_fix():
    class Plain:
        def controls(self):
            return {}

        def control_values(self):
            return {}

        def set_control(self, name, value):
            raise AssertionError

    out = assist(Plain(), lambda: None, driver="v4l2-raw")
    assert "v4l2-raw driver takes no exposure or gain" in out.line and "opencv" in out.line


def test_automatic_exposure_asks_for_a_manual_one():
    cam = FakeCamera(exposure=-1.0)
    out = assist(cam, cam.measure)
    assert not out.ok and "automatic (-1)" in out.line and not cam.log


def test_a_reading_on_the_twin_sees_clipping_skin_and_its_light():
    from plugins.gestures.vision import process_frame
    from plugins.twin.camera.camera import TwinCamera

    cam = TwinCamera(realtime=False)
    bg = cam.background()
    cam.place("open_hand", (370.0, 220.0))
    cam.read()
    img = cam.read().image
    r = reading_of(img, process_frame(img, bg))
    assert r is not None and r.p99 < TARGET_P99 and r.clipped_px == 0 and not r.too_dark()
    cam.set_control("gain", 1.75)  # more light before the 8-bit clip
    img = cam.read().image
    r = reading_of(img, process_frame(img, bg))
    assert r.p99 == 255 and r.clipped_px > 0 and r.clips()
    assert reading_of(img, process_frame(bg, bg)) is None  # no hand


def test_the_twins_default_frame_is_unchanged():
    from plugins.twin.camera.render import Rig
    from plugins.twin.camera.sample import render_frame

    a = render_frame([], Rig(), 1.0, np.random.default_rng(3))[0]
    b = render_frame([], Rig(), 1.0, np.random.default_rng(3), light=1.0)[0]
    c = render_frame([], Rig(), 1.0, np.random.default_rng(3), light=0.5)[0]
    assert np.array_equal(a, b) and c.mean() < 0.6 * a.mean()
    with pytest.raises(ValueError, match="use one of exposure, gain"):
        from plugins.twin.camera.camera import TwinCamera

        TwinCamera().set_control("focus", 1.0)
