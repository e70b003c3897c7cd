"""Issue 27, finding 12: "end to end" times only the frames whose decision scheduled an
output sample. A loop without an output stage (the console's camera loop: vision and
classify) keeps none; a stage that scheduled nothing this frame (the knob demo's
``scheduled`` without a crossing) is not stamped, and the frame goes on."""

from __future__ import annotations

import numpy as np

from console.core.types import Frame
from console.runtime.latency import ARRIVAL, LatencyMonitor
from console.runtime.loop import PASSED, FrameLoop
from plugins.demos.knob import KnobDemo


class ListCamera:
    def __init__(self, n: int) -> None:
        self.seq = 0

    def read(self) -> Frame:
        self.seq += 1
        return Frame(np.zeros((4, 4), np.uint8), self.seq, self.seq / 60)


def test_a_loop_without_an_output_stage_times_no_end_to_end():
    m = LatencyMonitor(["vision", "classify"])
    assert m.end_stage is None
    f = Frame(np.zeros((4, 4), np.uint8), 1, 0.0)
    for name, t in ((ARRIVAL, 0.0), ("dequeued", 0.001), ("vision", 0.004), ("classify", 0.005)):
        f.stamp(name, t)
    m.record(f)
    snap = m.snapshot()
    assert snap["frames"] == 1 and snap["end_stage"] is None
    assert snap["end_to_end"]["n"] == 0  # nothing scheduled, nothing timed
    assert LatencyMonitor(["vision", "scheduled", "scene"]).end_stage == "scheduled"


def test_a_passed_output_stage_is_not_stamped_and_the_frame_goes_on():
    scene: list[int] = []

    def scheduled(f, work):
        return None if f.seq % 3 == 0 else PASSED

    loop = FrameLoop(
        ListCamera(9),
        [
            ("vision", lambda f, w: None),
            ("scheduled", scheduled),
            ("scene", lambda f, w: scene.append(f.seq)),
        ],
    )
    for _ in range(9):
        f = loop.camera.read()
        f.stamp(ARRIVAL, 0.0)
        loop.process(f)
        assert ("scheduled" in f.stamps_s) == (f.seq % 3 == 0)
    assert scene == list(range(1, 10))  # every frame reached the scene
    snap = loop.monitor.snapshot()
    assert snap["frames"] == 9 and snap["end_to_end"]["n"] == 3


def test_the_knob_schedules_output_only_on_a_crossing():
    assert KnobDemo.scheduled_stage(None, None, {"knob": {"crossings": 0}}) is PASSED
    work = {"knob": {"crossings": 1}}
    assert KnobDemo.scheduled_stage(None, None, work) is None and "scheduled_s" in work
