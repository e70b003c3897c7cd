"""The camera's and the vision's frame rates counted over one and the same time window
(the Camera and Latency screens): each rate is a counter's growth over the window, so two
rates shown side by side are of the same seconds and the vision never reads faster than
the camera that feeds it (but for the frames in flight at the window's edges)."""

from __future__ import annotations

from collections import deque

#: the seconds the rates are counted over
WINDOW_S = 3.0
#: the counters: frames the camera delivered, frames the vision processed
CAMERA, VISION = "camera", "vision"


def frame_counts(st: dict) -> dict[str, int] | None:
    """The counters of a camera service's ``status()`` (or a demo's snapshot): the
    frames the camera delivered (its driver's count, else the frames the loop took from
    it) and the frames the vision processed; None while no loop counts."""
    cam, lat = st.get("camera") or {}, st.get("latency") or None
    if lat is None:
        return None
    taken = int(lat.get("frames", 0)) + int(lat.get("dropped_queue", 0))
    delivered = cam.get("frames")
    return {
        CAMERA: int(delivered) if isinstance(delivered, int | float) else taken,
        VISION: int(lat.get("frames", 0)),
    }


class SameWindow:
    """Rates of several counters over the same last ``window_s`` seconds."""

    def __init__(self, window_s: float = WINDOW_S) -> None:
        self.window_s = float(window_s)
        self._samples: deque[tuple[float, dict[str, int]]] = deque()

    def add(self, t_s: float, counts: dict[str, int] | None) -> dict[str, float] | None:
        """Count ``counts`` at ``t_s`` (monotonic s); the rates per second of each over
        the window ending now (None until two readings lie ``window_s / 3`` apart, after
        a counter went back: a new loop, or with ``counts`` None)."""
        if counts is None:
            self._samples.clear()
            return None
        if self._samples:
            last = self._samples[-1][1]
            if set(last) != set(counts) or any(counts[k] < last[k] for k in counts):
                self._samples.clear()  # another loop's counters
        self._samples.append((t_s, dict(counts)))
        while len(self._samples) > 2 and self._samples[1][0] <= t_s - self.window_s:
            self._samples.popleft()  # the oldest kept reading starts the window
        t0, first = self._samples[0]
        if t_s - t0 < self.window_s / 3:
            return None
        return {k: (counts[k] - first[k]) / (t_s - t0) for k in counts}

    def span_s(self) -> float:
        """The seconds the last rates were counted over."""
        return self._samples[-1][0] - self._samples[0][0] if self._samples else 0.0
