"""The touch-calibration wizard driven from the console session, without Textual: frames
feed it through the camera service's hook, the twin is aimed at each target, the
observers get calibration events, and the fit is saved."""

from __future__ import annotations

import json
import threading
from types import SimpleNamespace

import pytest

from console.core.types import Contact


def _px(pos_mm) -> tuple[float, float]:
    """The fake camera's view of the table: 0.5 px per mm, offset (10, 20) px."""
    return (10.0 + 0.5 * pos_mm[0], 20.0 + 0.5 * pos_mm[1])


class FakeCamera:
    """A camera the operator's finger is aimed at (a ``TouchableCamera``, like the twin);
    it knows where a table point shows once it is given a ``px_of`` mapping."""

    def __init__(self) -> None:
        self.target = None
        self.aimed: list = []
        self.px_of = None

    def read(self, timeout_s: float = 0.1):
        return None

    def close(self) -> None:
        pass

    def status(self) -> dict:
        return {"fps": 0.0, "dropped": 0}

    def set_target(self, pos_mm) -> None:
        self.target = pos_mm
        self.aimed.append(pos_mm)

    def mm_to_px(self, pos_mm):
        return None if self.px_of is None else self.px_of(pos_mm)


class Classifier:
    def touch_calibration(self, profile):
        from plugins.gestures.calibration import CalibrationSession, target_grid

        return CalibrationSession(
            target_grid((800.0, 500.0), columns=3, rows=2), hold_frames=2, lift_frames=1
        )


def _session(profile, classifier):
    from console.session import ConsoleSession

    cam = FakeCamera()
    service = SimpleNamespace(classifier=classifier, camera=cam, error="", frame_hooks=[])
    session = ConsoleSession(
        SimpleNamespace(profile=profile, pm=None), camera_factory=lambda p, pl: service
    )
    events: list = []
    session.subscribe(events.append)
    return session, cam, events


def _frames(session, cam, n: int) -> None:
    """``n`` frames: the finger on the aimed target (if any), else no contact."""
    for _ in range(n):
        contacts = () if cam.target is None else (Contact(1, _px(cam.target)),)
        for hook in list(session.camera.frame_hooks):
            hook(None, {"contacts": contacts})


def test_wizard_runs_from_the_session_and_saves(profile, tmp_path):
    from console.session.events import Progress, Snapshot, Started, Stopped

    session, cam, events = _session(profile, Classifier())
    wizard = session.calibration
    sent: list = []
    done = threading.Event()

    class Projector:
        def start_scene(self, name, events):
            sent.append(("start", name, len(events[0]["targets_mm"])))

        def update(self, event):
            sent.append(("update", event["type"]))

        def stop_scene(self):
            sent.append(("stop",))
            done.set()

    wizard.projector = Projector
    assert wizard.start()
    assert wizard.message == "touch target 1 of 6"
    assert cam.target == tuple(wizard.active.targets_mm[0])  # the twin touches target 1
    _frames(session, cam, 60)
    assert wizard.active is None and wizard.result is not None
    r = wizard.result.report()
    assert r["pairs"] == 6 and r["rms_mm"] < 1e-6  # an exact affine view
    assert "on a new touch (leave-one-out" in wizard.message and "trust this" in wizard.message
    assert "fit residual 0.00 mm rms" in wizard.message  # said as the fit's, not the error
    assert session.camera.frame_hooks == []  # unhooked
    assert cam.target is None

    kinds = [type(e) for e in events if e.topic == "calibration"]
    assert kinds[0] is Started and kinds[-2:] == [Snapshot, Stopped]
    fractions = [e.fraction for e in events if isinstance(e, Progress)]
    assert fractions == sorted(fractions) and fractions[-1] == 1.0
    assert done.wait(5)
    assert sent[0] == ("start", "touch_calibration", 6) and sent[-1] == ("stop",)
    assert sent.count(("update", "touch")) == 6  # in order, from the projector's thread

    assert wizard.message.endswith("S: save")  # the key the result asks for
    path = wizard.save(tmp_path / "cal.json")
    assert json.loads(path.read_text())["format"].startswith("haptable-touch-calibration")
    assert isinstance(events[-1], Stopped) and events[-1].reason == f"saved: {path}"
    # saved: the line says so (issue 27), no longer asking for S as if unsaved
    assert "S: save" not in wizard.message and wizard.message.endswith(f"saved to {path}")
    assert "fit residual" in wizard.message
    wizard.save(tmp_path / "cal.json")  # again: one "saved to", the newest
    assert wizard.message.count("saved to") == 1


def test_skip_cancel_and_a_classifier_without_calibration(profile):
    from console.core.errors import UserError
    from console.session.events import Failed, Stopped

    session, cam, events = _session(profile, Classifier())
    wizard = session.calibration
    assert wizard.start()
    wizard.skip()
    assert wizard.active.index == 1 and wizard.message == "touch target 2 of 6"
    assert cam.target == tuple(wizard.active.targets_mm[1])
    assert wizard.cancel() and wizard.active is None
    assert wizard.message == "calibration cancelled" and cam.target is None
    assert isinstance(events[-1], Stopped) and events[-1].reason == "cancelled"
    assert not wizard.cancel()
    with pytest.raises(UserError, match="run it first"):
        wizard.save()

    # skipping every target: too few touches is said in one line, nothing kept
    assert wizard.start()
    for _ in range(6):
        wizard.skip()
    assert wizard.active is None and wizard.result is None and wizard.failed
    assert "at least 4" in wizard.message
    assert any(isinstance(e, Failed) and e.topic == "calibration" for e in events)

    session.camera.classifier = SimpleNamespace(params=None)
    assert not wizard.start()
    assert "offers none" in wizard.message and "[gestures] classifier" in wizard.message
    assert isinstance(events[-1], Failed) and events[-1].severity == "warning"
    session.camera.classifier = None
    assert not wizard.start() and "not running yet" in wizard.message


def test_target_in_the_camera_image_when_the_camera_knows_its_mapping(profile):
    session, cam, _ = _session(profile, Classifier())
    wizard = session.calibration
    assert wizard.target_px() is None  # not running
    wizard.start()
    assert wizard.target_px() is None  # this camera knows no mapping
    cam.px_of = _px
    assert wizard.target_px() == pytest.approx(_px(wizard.target_mm()))


def test_the_result_says_which_number_to_trust():
    """A second new operator's try: `0.00 mm rms, 0.00 mm max (leave-one-out 3.55 mm)`
    read as a contradiction. The leave-one-out error comes first as what a new touch
    may expect, the fit's residual after it named as such."""
    from console.session.calibration import report_words  # lazy: beside the wizard's

    said = report_words(
        {"pairs": 12, "rms_mm": 0.0, "max_mm": 0.0, "loo_rms_mm": 3.55, "outliers": []}
    )
    assert said.startswith("12 targets: expect 3.55 mm rms on a new touch"), said
    assert "trust this" in said and "reprojection error" not in said, said
    assert said.index("3.55") < said.index("fit residual 0.00 mm rms, 0.00 mm max"), said
