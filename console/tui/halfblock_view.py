"""A Static that shows a text or a ``HalfBlockImage`` drawn line by line.

A new picture of the size of the last one rebuilds and repaints only the cell rows that
changed (``HalfBlockImage.changed_rows``): a live camera view in which a hand moves
costs the rows it crosses, and a still one nothing. Text (``update``) shows as a
Static's.
"""

from __future__ import annotations

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
