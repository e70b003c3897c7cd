"""The camera service's start, the camera first: the Camera screen shows its frames
(``preview_loop``: no stages, nothing classified) while the classifier is built (its
libraries, a saved model and touch calibration: seconds on a loaded 2-core machine),
and the loop with the vision replaces it once the classifier is there. Built at the same
time, the two compete for the CPU and the first frame comes later. ``Starting`` says
what is being prepared and since when (the Camera screen shows it until the vision
runs)."""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any

from console.runtime.latency import LatencyMonitor
from console.runtime.loop import FrameLoop

#: what ``Starting.step`` says, in order
OPENING_CAMERA = "opening the camera"
LOADING_VISION = "loading the vision (gesture classifier)"


class Starting:
    """What the service prepares now (``step``, "" when nothing) and since when."""

    def __init__(self) -> None:
        self.step = ""
        self._since = time.monotonic()

    def set(self, step: str) -> None:
        self.step, self._since = step, time.monotonic()

    def line(self) -> str:
        """``step`` and the seconds it has taken so far ("" when nothing is prepared)."""
        if not self.step:
            return ""
        return f"{self.step} ... {time.monotonic() - self._since:.0f} s"


def preview_loop(camera: Any, sink: Callable[[Any, dict], None]) -> FrameLoop:
    """A started loop that only reads ``camera`` into ``sink`` (no stages): frames to
    show while the vision is prepared."""
    return FrameLoop(
        camera, [], monitor=LatencyMonitor([]), queue_size=2, sinks=[sink], name="preview"
    ).start()
