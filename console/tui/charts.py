"""Line charts for the console on textual-plotext: series with axis labels and units, a
legend, an optional log-frequency axis and a dB axis, drawn to the size the layout gives.

``Chart`` is the widget; the data it draws is a tuple of ``Series`` (plain arrays). Long
series are reduced to a min/max pair per output column before plotext sees them
(``envelope``): a 1 s waveform at 48 kHz draws as fast as 200 points and no peak is lost.
On a log-x axis (a spectrum) the columns are log-spaced and keep their maximum
(``log_peaks``), so low frequencies get as many columns as high ones.
``Chart.summary()`` is the plain-text view of what the chart shows (title, axes with their
units and ranges, one line per series): tests and screen readers read it.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from rich.text import Text
from textual_plotext import PlotextPlot

#: Colours of successive series (plotext names); the legend shows them in this order.
SERIES_COLOURS = ("cyan", "magenta", "green", "orange", "white")


@dataclass(frozen=True)
class Series:
    """One line of a chart: ``y`` against ``x`` (same length), named in the legend."""

    label: str
    x: np.ndarray
    y: np.ndarray


def envelope(x: np.ndarray, y: np.ndarray, columns: int) -> tuple[np.ndarray, np.ndarray]:
    """At most ``2 * columns`` points of (x, y) keeping each column's min and max (in
    order of x), so a reduced waveform still reaches every peak the full one reaches."""
    x, y = np.asarray(x, float), np.asarray(y, float)
    columns = max(1, int(columns))
    if x.size <= 2 * columns:
        return x, y
    edges = np.linspace(0, x.size, columns + 1).astype(int)
    xs, ys = [], []
    for a, b in zip(edges[:-1], edges[1:], strict=True):
        if b <= a:
            continue
        seg = y[a:b]
        i, j = int(np.argmin(seg)), int(np.argmax(seg))
        for k in sorted({i, j}):
            xs.append(x[a + k])
            ys.append(seg[k])
    return np.asarray(xs), np.asarray(ys)


def log_peaks(x: np.ndarray, y: np.ndarray, columns: int) -> tuple[np.ndarray, np.ndarray]:
    """At most ``columns`` points of (x, y) (x > 0, ascending) on a log-x axis: x cut into
    ``columns`` log-spaced columns, each kept as its largest y (at its x). A spectrum
    reduced this way keeps its low frequencies (one column per few bins there, many
    bins per column at the top) and its peaks; columns with no point are left out."""
    x, y = np.asarray(x, float), np.asarray(y, float)
    columns = max(1, int(columns))
    if x.size <= columns:
        return x, y
    edges = np.geomspace(x[0], x[-1], columns + 1)
    starts = np.searchsorted(x, edges[:-1], side="left")
    ends = np.append(starts[1:], x.size)
    xs, ys = [], []
    for a, b in zip(starts, ends, strict=True):
        if b <= a:
            continue
        k = a + int(np.argmax(y[a:b]))
        xs.append(x[k])
        ys.append(y[k])
    return np.asarray(xs), np.asarray(ys)


def to_db(y: np.ndarray, ref: float = 1.0, floor_db: float = -120.0) -> np.ndarray:
    """``20 log10(|y| / ref)``, never below ``floor_db`` (zeros included)."""
    with np.errstate(divide="ignore"):
        db = 20.0 * np.log10(np.abs(np.asarray(y, float)) / ref)
    return np.maximum(np.nan_to_num(db, nan=floor_db, neginf=floor_db), floor_db)


#: the mark a series' legend entry shows (its line is drawn in braille)
BRAILLE = "⣿"
#: plotext colour names Rich spells otherwise
RICH_COLOURS = {"orange": "dark_orange", "gray": "grey50"}


def legend_rows(
    legend: Sequence[tuple[str, str, str]], width: int, most: int = 1 << 20
) -> list[Text]:
    """Rows ``⣿ label  ⣿ label ...`` in the series' colours, each within ``width``: an
    entry that does not fit a row starts the next one (every entry whole, at 80 columns
    too), at most ``most`` rows (the last one then ends in "…")."""
    rows: list[Text] = []
    for label, colour, marker in legend:
        entry = Text(marker, style=RICH_COLOURS.get(colour, colour))
        entry.append(f" {label}")
        if rows and rows[-1].cell_len + 2 + entry.cell_len <= width:
            rows[-1].append("  ")
        elif len(rows) < most:
            rows.append(Text(" "))
        else:  # no row left: the last one says there is more
            rows[-1].append("  ")
        rows[-1].append_text(entry)
    for row in rows:
        row.truncate(width, overflow="ellipsis")
    return rows


def _axis(label: str, unit: str) -> str:
    return f"{label} ({unit})" if unit else label


class Chart(PlotextPlot):
    """A line chart. ``x_unit``/``y_unit`` show in the axis labels; ``log_x`` draws x on a
    log axis (non-positive x left out); ``db_y`` draws ``20 log10(|y| / db_ref)`` and puts
    ``dB re <db_ref> <y_unit>`` on the y axis. ``set_series`` replaces what it draws."""

    DEFAULT_CSS = """
    Chart {
        width: 1fr;
        height: 1fr;
        min-height: 6;
    }
    """

    def __init__(
        self,
        *,
        title: str = "",
        x_label: str = "",
        x_unit: str = "",
        y_label: str = "",
        y_unit: str = "",
        log_x: bool = False,
        db_y: bool = False,
        db_ref: float = 1.0,
        db_floor: float = -120.0,
        zero_y: bool = False,
        name: str | None = None,
        id: str | None = None,  # noqa: A002 - Textual's name
        classes: str | None = None,
    ) -> None:
        super().__init__(name=name, id=id, classes=classes)
        self.title = title
        self.x_label, self.x_unit = x_label, x_unit
        self.y_label, self.y_unit = y_label, y_unit
        self.log_x, self.db_y, self.db_ref, self.db_floor = log_x, db_y, db_ref, db_floor
        self.zero_y = zero_y  # y symmetric about 0, its zero labelled (a voltage)
        self.series: tuple[Series, ...] = ()
        self.empty_text = "nothing to plot"

    # ------------------------------------------------------------------ data
    def set_series(self, series: Sequence[Series], *, title: str | None = None) -> None:
        """Draw ``series`` (each ``x`` and ``y`` of one length) from the next refresh."""
        for s in series:
            if np.shape(s.x) != np.shape(s.y):
                raise ValueError(f"series {s.label!r}: x and y differ in length")
        self.series = tuple(series)
        if title is not None:
            self.title = title
        self.refresh()

    def clear(self, empty_text: str = "nothing to plot") -> None:
        """Draw nothing but ``empty_text``."""
        self.series = ()
        self.empty_text = empty_text
        self.refresh()

    @property
    def y_axis_label(self) -> str:
        if self.db_y:
            ref = f"{self.db_ref:g} {self.y_unit}".strip()
            return f"{self.y_label} (dB re {ref})" if self.y_label else f"dB re {ref}"
        return _axis(self.y_label, self.y_unit)

    @property
    def x_axis_label(self) -> str:
        return _axis(self.x_label, self.x_unit)

    def drawn(self, columns: int | None = None) -> list[tuple[str, np.ndarray, np.ndarray]]:
        """(label, x, y) as drawn: log-x drops x <= 0, dB-y converts, long series reduced
        to ``columns`` min/max pairs (the widget's width by default; on a log-x axis the
        largest y of each of ``columns`` log-spaced columns: ``log_peaks``)."""
        cols = columns if columns is not None else max(10, self.size.width or 80)
        out = []
        for s in self.series:
            x, y = np.asarray(s.x, float), np.asarray(s.y, float)
            keep = np.isfinite(x) & np.isfinite(y)
            if self.log_x:
                keep &= x > 0
            x, y = x[keep], y[keep]
            if self.db_y:
                y = to_db(y, self.db_ref, self.db_floor)
            if self.log_x:  # columns of equal width on the log axis: max per column
                order = np.argsort(x, kind="stable")
                x, y = log_peaks(x[order], y[order], cols)
            else:
                x, y = envelope(x, y, cols)
            out.append((s.label, x, y))
        return out

    def summary(self) -> str:
        """What the chart shows, as plain lines: title, axes, one line per series."""
        lines = [self.title] if self.title else []
        if not self.series:
            return "\n".join([*lines, self.empty_text])
        log = " (log axis)" if self.log_x else ""
        lines.append(f"x: {self.x_axis_label}{log}; y: {self.y_axis_label}")
        for label, x, y in self.drawn(columns=1 << 20):
            if x.size:
                lines.append(
                    f"{label}: x {x.min():.4g}..{x.max():.4g}, y {y.min():.4g}..{y.max():.4g}"
                )
            else:
                lines.append(f"{label}: no points to draw")
        return "\n".join(lines)

    # ------------------------------------------------------------------ drawing
    def render(self):  # noqa: ANN201 - Textual's RenderResult
        plt = self.plt
        plt.clear_figure()
        plt.title(self.title)
        if not self.series:
            return Text(f"{self.title}\n{self.empty_text}" if self.title else self.empty_text)
        plt.xlabel(self.x_axis_label)
        plt.ylabel(self.y_axis_label)
        if self.log_x:
            plt.xscale("log")
        drawn, legend = self.drawn(), []
        for (label, x, y), colour in zip(
            drawn, SERIES_COLOURS * (1 + len(self.series)), strict=False
        ):
            if x.size:  # no plotext label: its legend would sit on the curve
                plt.plot(x.tolist(), y.tolist(), color=colour, marker="braille")
                legend.append((label, colour, BRAILLE))
        if self.zero_y:
            self._zero_centred(plt, drawn)
        return self.figure_and_legend(legend)

    def figure_and_legend(self, legend: Sequence[tuple[str, str, str]]) -> Text:
        """The figure set up on ``plt`` above the rows naming its series, each as
        (label, plotext colour, marker): plotext draws its own legend inside the plot's
        top left corner, over the curve. No row for it on a chart of under two rows."""
        width, height = self.size.width, self.size.height
        if not legend or height < 2:
            return super().render()
        # the legend's rows below the figure (it keeps at least half of the height)
        rows = legend_rows(legend, width, max(1, height // 2 - 1))
        plt = self.plt
        plt.plotsize(width, height - len(rows))
        plt._set_size(width, height - len(rows))  # as textual-plotext's own render does
        plt.theme(self._get_plotext_theme_name(self.app.theme))
        text = Text.from_ansi(plt.build().removesuffix("\n"))
        for row in rows:
            text.append("\n")
            text.append_text(row)
        return text

    def _zero_centred(self, plt, drawn: list[tuple[str, np.ndarray, np.ndarray]]) -> None:
        """y from -top to top with 0 a labelled tick (``zero_y``); fewer ticks on a short
        chart, so no label lands on 0's row."""
        top = max((float(np.max(np.abs(y))) for _l, _x, y in drawn if y.size), default=0.0)
        top = top or 1.0
        rows = self.size.height - 6  # title, the x axis, its ticks and label, legend, margin
        half = 3 if rows >= 9 else 2 if rows >= 5 else 1
        plt.ylim(-top, top)
        plt.yticks([top * k / half for k in range(-half, half + 1)])
