"""Text plots for the console: pure functions of arrays returning Rich renderables.

- ``frf_series``: |H| (um/V) of several excitations against frequency as series of a
  ``console.tui.charts.Chart`` (dB axis), with one frequency marked.
- ``sparkline``: values as ``▁▂▃▄▅▆▇█`` over their own range, as many as the width allows.
- ``HalfBlockImage``: a grey image as half-block characters (two pixels per cell),
  with coloured overlay pixels.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from rich.color import Color
from rich.segment import Segment
from rich.style import Style

from console.tui.charts import Series

BARS = "▁▂▃▄▅▆▇█"


def frf_series(
    freq_hz: np.ndarray,
    mags: np.ndarray,
    names: Sequence[str],
    *,
    mark_hz: float | None = None,
    band_hz: float | None = None,
    masked: np.ndarray | None = None,
) -> list[Series]:
    """|H| of ``mags`` (S, F) in um/V against frequency, one chart series per excitation
    (for ``charts.Chart`` with a dB axis). Masked bins and bins above ``band_hz`` are left
    out (NaN, never drawn). With ``mark_hz`` each label carries its value at that
    frequency, in um/V, and a vertical line series ``plays at ... Hz`` marks it."""
    f = np.asarray(freq_hz, float)
    m = np.abs(np.asarray(mags, float))
    keep = np.ones(f.shape, bool) if masked is None else ~np.asarray(masked, bool)
    if band_hz is not None:
        keep &= f <= band_hz
    if not keep.any() or m.size == 0:
        return []
    k = None
    if mark_hz is not None:
        k = int(np.flatnonzero(keep)[np.argmin(np.abs(f[keep] - mark_hz))])
    series = []
    for s, name in enumerate(names):
        label = name if k is None else f"{name} {m[s, k]:.3g} µm/V"
        series.append(Series(label, f, np.where(keep, m[s], np.nan)))
    if mark_hz is not None:
        top = float(m[:, keep].max())
        if top > 0:  # a line over the 60 dB the axis shows below the highest peak
            series.append(
                Series(
                    f"plays at {mark_hz:g} Hz",
                    np.array([mark_hz, mark_hz]),
                    np.array([top * 1e-3, top]),
                )
            )
    return series


def sparkline(values: Sequence[float], width: int = 20, *, fill: bool = False) -> str:
    """The last ``width`` values as bar characters scaled to their own range, lowest to
    highest (``''`` if none): values that stay near one level show how they moved, not a
    solid block, and constant values are a flat low line. ``fill``: fewer values than
    ``width`` are stretched over it (each value as many bars, in turn), never a short line."""
    v = np.asarray(list(values)[-width:], float)
    v = v[np.isfinite(v)]
    if v.size == 0:
        return ""
    if fill and v.size < width:
        v = v[np.arange(width) * v.size // width]
    lo, span = float(v.min()), float(v.max() - v.min())
    if span <= 0:
        return BARS[0] * v.size
    idx = np.clip(((v - lo) / span * (len(BARS) - 1)).round().astype(int), 0, len(BARS) - 1)
    return "".join(BARS[i] for i in idx)


def downsample(image: np.ndarray, cols: int, rows: int) -> np.ndarray:
    """Area-average ``image`` (H, W) to (2*rows, cols) pixels for a half-block view."""
    img = np.asarray(image, float)
    h, w = img.shape[:2]
    ys = np.linspace(0, h, 2 * rows + 1).astype(int)
    xs = np.linspace(0, w, cols + 1).astype(int)
    rsum = np.add.reduceat(img, ys[:-1], axis=0)[: 2 * rows]
    csum = np.add.reduceat(rsum, xs[:-1], axis=1)[:, :cols]
    area = np.outer(np.diff(ys), np.diff(xs)).astype(float)
    return csum / np.maximum(area, 1)


_STYLES: dict[tuple, Style] = {}
_PACKED: dict[int, Style] = {}


_LABEL = Style(color="black", bgcolor="bright_white", bold=True)


_TOP_SHIFTS = np.array([40, 32, 24])
_BOTTOM_SHIFTS = np.array([16, 8, 0])


def _packed_style(key: int) -> Style:
    """The style of a cell whose two colours are packed in ``key`` (top RGB in bits
    40..63, bottom RGB in 0..23), made once per pair of colours."""
    s = _PACKED.get(key)
    if s is None:
        b = [(key >> k) & 0xFF for k in (40, 32, 24, 16, 8, 0)]
        s = _style((b[0], b[1], b[2]), (b[3], b[4], b[5]))
        if len(_PACKED) < 20000:
            _PACKED[key] = s
    return s


def _style(top: tuple, bottom: tuple) -> Style:
    key = (top, bottom)
    s = _STYLES.get(key)
    if s is None:
        s = Style(color=Color.from_rgb(*top), bgcolor=Color.from_rgb(*bottom))
        if len(_STYLES) < 20000:
            _STYLES[key] = s
    return s


class HalfBlockImage:
    """A (2*rows, cols) grey image plus overlay as ``▀`` cells (top pixel fg, bottom bg).

    ``overlay`` is an (2*rows, cols, 3) uint8 RGB array; pixels where it is non-zero
    replace the grey value. Grey is quantised to 32 levels (style cache). ``labels``
    ``{(row, col): text}`` write text over the cells from (row, col) on (clipped at the
    right edge), e.g. a blob's id next to it."""

    def __init__(
        self,
        grey: np.ndarray,
        overlay: np.ndarray | None = None,
        labels: dict[tuple[int, int], str] | None = None,
    ) -> None:
        g = (np.clip(grey, 0, 255).astype(np.uint8) // 8) * 8 + 4
        rgb = np.repeat(g[..., None], 3, axis=2)
        if overlay is not None:
            on = overlay.any(axis=2)
            rgb[on] = overlay[on]
        self.rgb = rgb
        self.text: dict[tuple[int, int], str] = {}  # (cell row, col) -> one character
        for (row, col), label in (labels or {}).items():
            for i, ch in enumerate(str(label)):
                if 0 <= row < rgb.shape[0] // 2 and 0 <= col + i < rgb.shape[1]:
                    self.text[(row, col + i)] = ch

    def __rich_measure__(self, console, options):
        from rich.measure import Measurement

        return Measurement(self.rgb.shape[1], self.rgb.shape[1])

    @property
    def size(self) -> tuple[int, int]:
        """(cols, rows) in character cells."""
        return self.rgb.shape[1], self.rgb.shape[0] // 2

    def changed_rows(self, other: HalfBlockImage | None) -> list[int]:
        """The cell rows that differ from ``other`` (all of them: a size apart, or None)."""
        cols, rows = self.size
        if other is None or other.size != (cols, rows):
            return list(range(rows))
        cells = (self.rgb[: 2 * rows] != other.rgb[: 2 * rows]).any(axis=2)
        changed = set(np.flatnonzero(cells.reshape(rows, 2, cols).any(axis=(1, 2))).tolist())
        changed.update(row for (row, _col), _ch in self.text.items() ^ other.text.items())
        return sorted(changed)

    def row_segments(self, row: int) -> list[Segment]:
        """Cell row ``row`` as segments: a run of equal cells is one segment."""
        rgb, text, cols = self.rgb, self.text, self.rgb.shape[1]
        top, bot = rgb[2 * row], rgb[2 * row + 1]
        # a cell's two colours as one number: where it changes, a new run starts
        cells = (top.astype(np.int64) << _TOP_SHIFTS).sum(axis=1) + (
            bot.astype(np.int64) << _BOTTOM_SHIFTS
        ).sum(axis=1)
        starts = np.flatnonzero(np.diff(cells)) + 1
        cuts = {0, cols, *starts.tolist()}
        for r, col in text:  # a label's cell is a run of its own
            if r == row:
                cuts.update((col, col + 1))
        edges = sorted(cuts)
        keys = cells.tolist()
        out = []
        for a, b in zip(edges[:-1], edges[1:], strict=True):
            ch = text.get((row, a))
            if ch is not None:
                out.append(Segment(ch, _LABEL))
            else:
                out.append(Segment("▀" * (b - a), _packed_style(keys[a])))
        return out

    def __rich_console__(self, console, options):
        for row in range(self.size[1]):
            yield from self.row_segments(row)
            yield Segment.line()
