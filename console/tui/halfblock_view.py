"""A Static that shows a text or a ``HalfBlockImage`` drawn line by line.

A new picture of the size of the last one rebuilds and repaints only the cell rows that
changed (``HalfBlockImage.changed_rows``): a live camera view in which a hand moves
costs the rows it crosses, and a still one nothing. Text (``update``) shows as a
Static's.

``GreyStretch`` spreads a frame's grey levels over the display's range: an IR frame is
dark (the twin's background near 30 of 255), shown as it is it would be nearly black.
"""

from __future__ import annotations

import numpy as np
from textual.geometry import Region
from textual.strip import Strip
from textual.widgets import Static

from console.tui.plots import HalfBlockImage


class HalfBlockView(Static):
    """``show_picture`` draws a picture; ``update`` a text, as any Static."""

    def __init__(self, *args, **kw) -> None:
        super().__init__(*args, **kw)
        self.picture: HalfBlockImage | None = None
        self._strips: list[Strip] = []
        self.rows_drawn = 0  # cell rows rebuilt since mounted (tests count them)

    def show_picture(self, picture: HalfBlockImage) -> int:
        """Show ``picture``; the number of cell rows that changed (0: nothing drawn)."""
        old = self.picture
        cols, rows = picture.size
        resized = old is None or old.size != picture.size or len(self._strips) != rows
        changed = list(range(rows)) if resized else picture.changed_rows(old)
        self.picture = picture
        if not changed:
            return 0
        if resized:
            self._strips = [Strip.blank(cols)] * rows
        for r in changed:
            self._strips[r] = Strip(picture.row_segments(r), cols)
        self.rows_drawn += len(changed)
        if resized:
            self.refresh(layout=True)
        else:
            self.refresh(*(Region(0, r, cols, 1) for r in changed))
        return len(changed)

    def update(self, content="", *, layout: bool = True) -> None:
        """A text in place of the picture."""
        self.picture = None
        self._strips = []
        super().update(content, layout=layout)

    def render(self):
        return self.picture if self.picture is not None else super().render()

    def render_line(self, y: int) -> Strip:
        if self.picture is None:
            return super().render_line(y)
        if 0 <= y < len(self._strips):
            return self._strips[y]
        return Strip.blank(self.size.width)


class GreyStretch:
    """The grey levels a live view shows black and white (``lo``, ``hi``): a low and a
    high percentile of the frames, followed slowly (a fraction ``rate`` of the way per
    frame: ~1 s at 10 frames/s), so the picture does not flicker with each frame's
    noise or a hand passing; at least ``min_span`` levels apart, so a flat frame's
    noise is not blown up to the whole range. Calling it with a grey image (any shape)
    returns the image mapped to 0..255 (float)."""

    LOW_PCT = 1.0
    HIGH_PCT = 99.5

    #: the levels shown move only when the followed ones are this far from them: a
    #: picture is redrawn whole when they move, not on every frame of a slow follow
    HYSTERESIS = 4.0

    def __init__(self, rate: float = 0.1, min_span: float = 32.0) -> None:
        self.rate = rate
        self.min_span = min_span
        self.lo: float | None = None
        self.hi: float | None = None
        self._shown: tuple[float, float] | None = None

    def update(self, grey: np.ndarray) -> tuple[float, float]:
        """(lo, hi) after seeing ``grey``: the first frame sets them."""
        lo, hi = (float(v) for v in np.percentile(grey, [self.LOW_PCT, self.HIGH_PCT]))
        if self.lo is None or self.hi is None:
            self.lo, self.hi = lo, hi
        else:
            self.lo += self.rate * (lo - self.lo)
            self.hi += self.rate * (hi - self.hi)
        return self.levels()

    def levels(self) -> tuple[float, float]:
        """(black, white) as shown: ``lo``, ``hi`` at least ``min_span`` apart, changed
        only when they moved more than ``HYSTERESIS`` from what is shown."""
        lo, hi = self.lo or 0.0, self.hi if self.hi is not None else 255.0
        if hi - lo < self.min_span:
            mid = (lo + hi) / 2
            lo, hi = mid - self.min_span / 2, mid + self.min_span / 2
        shown = self._shown
        if shown is None or max(abs(lo - shown[0]), abs(hi - shown[1])) > self.HYSTERESIS:
            self._shown = (lo, hi)
        return self._shown

    def __call__(self, grey: np.ndarray) -> np.ndarray:
        lo, hi = self.update(grey)
        return stretch_grey(grey, lo, hi)


def stretch_grey(grey: np.ndarray, lo: float, hi: float) -> np.ndarray:
    """``grey`` with ``lo`` black and ``hi`` white, 0..255 (float)."""
    return np.clip((np.asarray(grey, float) - lo) * (255.0 / max(hi - lo, 1e-9)), 0, 255)
