"""A knob session: tracker -> knob -> stream for one grip, fed frame by frame.

The live loop and the twin use the same object: ``feed(t_s, contacts)`` per camera
frame, ``render_until(t_s)`` pulls audio blocks (offline) up to a time.

``record=True`` (offline runs) keeps everything: every state, item, crossing and the
rendered audio. A live session (``record=False``) runs for as long as the operator
likes, so it keeps only the last ``LIVE_LOG`` frames' items and crossings (bounded
memory); ``crossings_total`` counts them all.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from .knob import Crossing, Knob
from .rotation import RotationState, RotationTracker
from .synth import KnobStream

#: Entries a live session keeps per log (items per frame; crossings; item changes; the
#: stream's per-block trace and detents): ~70 s of steady turning, 8 s of frames. A
#: live trial needs a few dozen; 4096 kept ~4 MB and took a 10-minute soak to fill.
LIVE_LOG = 512


def _log(record: bool) -> list | deque:
    return [] if record else deque(maxlen=LIVE_LOG)


class KnobSession:
    def __init__(
        self,
        condition: str,
        *,
        sectors: int,
        settings: Mapping[str, Any],
        limits: Mapping[str, float] | None = None,
        sample_rate_hz: int = 48000,
        block: int = 64,
        start_item: int = 0,
        n_items: int | None = None,
        record: bool = True,
    ) -> None:
        s = dict(settings)
        self.knob = Knob(sectors, s["hysteresis_deg"], start_item=start_item, n_items=n_items)
        self.tracker = RotationTracker(
            s["filter_alpha"],
            s["filter_beta"],
            s["max_hold_frames"],
            start_angle_deg=self.knob.center_deg(start_item),
            max_pivot_hold_frames=s["max_pivot_hold_frames"],
        )
        self.stream = KnobStream(condition, sample_rate_hz, s, limits, sectors=sectors)
        if not record:  # live: the stream's per-block trace and detent log stay short too
            self.stream.trace = deque(maxlen=LIVE_LOG)
            self.stream.detent_log = deque(maxlen=LIVE_LOG)
        self.fs, self.block, self.record = int(sample_rate_hz), int(block), record
        self.start_item = int(start_item)
        self.states: list[RotationState] = []
        self.crossings: list[Crossing] | deque[Crossing] = _log(record)
        self.crossing_ids: list[int] | deque[int] = _log(record)
        self.crossings_total = 0
        self.items: list[int] | deque[int] = _log(record)
        #: (t_s, item) at the start and after every crossing (append-only, any thread reads;
        #: live: the last ``LIVE_LOG``)
        self.item_log: list[tuple[float, int]] | deque[tuple[float, int]] = _log(record)
        self._piezo: list[np.ndarray] = []
        self._screen: list[np.ndarray] = []

    @property
    def t_audio_s(self) -> float:
        return self.stream.samples_out / self.fs

    def feed(self, t_s: float, contacts: Sequence[Any]) -> list[Crossing]:
        st = self.tracker.update(t_s, contacts)
        cr = self.knob.update(t_s, st.angle_deg) if st.touching else []
        ids = self.stream.post(len(cr), st.angle_deg, st.velocity_deg_s, st.touching)
        if self.record:
            self.states.append(st)
        self.crossings += cr
        self.crossing_ids += ids
        self.crossings_total += len(cr)
        if cr:
            self.item_log.append((float(t_s), self.knob.item))
        self.items.append(self.knob.item)
        return cr

    def scene_event(self) -> dict[str, Any]:
        """The knob state for a projected scene (JSON): ``angle_deg`` from the start
        item's lower boundary (so ``floor(angle / width)`` counts items from the start),
        ``item_offset`` = the selection with hysteresis (what the detents follow)."""
        return {
            "type": "knob",
            "angle_deg": self.tracker.angle_deg - self.start_item * self.knob.width_deg,
            "item_offset": self.knob.item - self.start_item,
            "velocity_deg_s": self.tracker.velocity_deg_s,
            "touching": self.tracker.touching,
        }

    def render_block(self) -> bool:
        b = self.stream.next_block(self.block)
        if b is None:
            return False
        if self.record:
            self._piezo.append(b[0])
            self._screen.append(b[1])
        return True

    def render_until(self, t_s: float) -> None:
        """Render every block that starts before ``t_s``."""
        while self.t_audio_s < t_s and self.render_block():
            pass

    def finish(self) -> None:
        self.stream.request_stop()
        while self.render_block():
            pass

    def output(self) -> tuple[np.ndarray, np.ndarray]:
        cat = lambda xs: np.concatenate(xs) if xs else np.zeros(0)  # noqa: E731
        return cat(self._piezo), cat(self._screen)

    def latency_samples(self) -> np.ndarray:
        start = dict(self.stream.detent_log)
        return np.array(
            [
                start[i] - c.t_s * self.fs
                for c, i in zip(self.crossings, self.crossing_ids, strict=True)
                if i in start
            ]
        )
