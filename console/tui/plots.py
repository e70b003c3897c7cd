"""Text plots for the console: pure functions of arrays returning Rich renderables.

- ``frf_plot``: |H| (dB re 1 um/V) of several excitations against frequency, one
  character per column, with one frequency marked.
- ``sparkline``: values as ``▁▂▃▄▅▆▇█``.
- ``HalfBlockImage``: a grey image as half-block characters (two pixels per cell),
  with coloured overlay pixels.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from rich.color import Color
from rich.segment import Segment
from rich.style import Style
from rich.text import Text

SERIES_COLOURS = ("cyan", "magenta", "green", "yellow", "bright_white")
BARS = "▁▂▃▄▅▆▇█"


def frf_plot(
    freq_hz: np.ndarray,
    mags: np.ndarray,
    names: Sequence[str],
    *,
    width: int = 60,
    height: int = 10,
    mark_hz: float | None = None,
    band_hz: float | None = None,
    masked: np.ndarray | None = None,
    floor_db: float = -60.0,
) -> Text:
    """|H| of ``mags`` (S, F) in um/V on a dB axis; columns hold the max over their bins.

    Masked bins never draw. ``mark_hz`` draws a vertical marker and its value per series.
    """
    f = np.asarray(freq_hz, float)
    m = np.abs(np.asarray(mags))
    keep = np.ones(f.shape, bool) if masked is None else ~np.asarray(masked, bool)
    if band_hz is not None:
        keep &= f <= band_hz
    width, height = max(10, int(width)), max(3, int(height))
    text = Text()
    if not keep.any() or m.size == 0:
        return Text("no usable bins to plot")
    fmax = float(f[keep].max())
    fmin = float(f[keep].min())
    col = np.clip(
        ((f - fmin) / max(fmax - fmin, 1e-12) * (width - 1)).round().astype(int), 0, width - 1
    )
    with np.errstate(divide="ignore"):
        db = 20 * np.log10(np.maximum(m, 1e-12))
    db[:, ~keep] = -np.inf
    top = float(np.nanmax(db[np.isfinite(db)])) if np.isfinite(db).any() else 0.0
    top = float(np.ceil(top / 10) * 10) + 0.0  # never "-0"
    bottom = max(floor_db, top - 60.0)
    grid = [[(" ", "") for _ in range(width)] for _ in range(height)]
    for s in range(m.shape[0]):
        colmax = np.full(width, -np.inf)
        np.maximum.at(colmax, col[keep], db[s, keep])
        for c in range(width):
            if not np.isfinite(colmax[c]) or colmax[c] < bottom:
                continue
            r = int(round((top - colmax[c]) / (top - bottom) * (height - 1)))
            grid[min(max(r, 0), height - 1)][c] = ("•", SERIES_COLOURS[s % len(SERIES_COLOURS)])
    mark_col = None
    if mark_hz is not None and fmin <= mark_hz <= fmax:
        mark_col = int(round((mark_hz - fmin) / max(fmax - fmin, 1e-12) * (width - 1)))
    for r in range(height):
        label = f"{top - r * (top - bottom) / (height - 1):5.0f} " if r % 3 == 0 else "      "
        text.append(label, style="dim")
        for c, (ch, style) in enumerate(grid[r]):
            if c == mark_col and ch == " ":
                text.append("│", style="bold red")
            else:
                text.append(ch, style=style)
        text.append("\n")
    axis = f"      {fmin:<8.0f}{'Hz  dB re 1 um/V':^{max(width - 16, 1)}}{fmax:>8.0f}"
    text.append(axis + "\n", style="dim")
    for s, name in enumerate(names):
        text.append(f" {name}", style=SERIES_COLOURS[s % len(SERIES_COLOURS)])
        if mark_hz is not None:
            k = int(np.argmin(np.abs(f - mark_hz)))
            text.append(f" {m[s, k]:.3g}", style="dim")
    if mark_hz is not None:
        text.append(f"   │ {mark_hz:g} Hz", style="bold red")
    return text


def sparkline(values: Sequence[float], width: int = 20) -> str:
    """The last ``width`` values as bar characters scaled to their own max (``''`` if none)."""
    v = np.asarray(list(values)[-width:], float)
    v = v[np.isfinite(v)]
    if v.size == 0:
        return ""
    hi = float(v.max())
    if hi <= 0:
        return BARS[0] * v.size
    idx = np.clip((v / hi * (len(BARS) - 1)).round().astype(int), 0, len(BARS) - 1)
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
    replace the grey value. Grey is quantised to 32 levels (style cache)."""

    def __init__(self, grey: np.ndarray, overlay: np.ndarray | None = None) -> None:
        g = (np.clip(grey, 0, 255).astype(np.uint8) // 8) * 8 + 4
        rgb = np.repeat(g[..., None], 3, axis=2)
        if overlay is not None:
            on = overlay.any(axis=2)
            rgb[on] = overlay[on]
        self.rgb = rgb

    def __rich_measure__(self, console, options):
        from rich.measure import Measurement

        return Measurement(self.rgb.shape[1], self.rgb.shape[1])

    def __rich_console__(self, console, options):
        rgb = self.rgb
        for r in range(0, rgb.shape[0] - 1, 2):
            top, bot = rgb[r], rgb[r + 1]
            for c in range(rgb.shape[1]):
                yield Segment(
                    "▀", _style(tuple(int(v) for v in top[c]), tuple(int(v) for v in bot[c]))
                )
            yield Segment.line()
